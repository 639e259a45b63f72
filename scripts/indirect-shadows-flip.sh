#!/usr/bin/env bash
# Indirect shadows against the ray-traced ground truth on every bundled scene: the indirect
# term's mean FLIP and rel. L1 without and with `--indirect-shadows`, for the one cut and the
# per-tile cuts (estimate, far clusters shared at 2 tile extents). Prints a Markdown table
# (BENCHMARKS.md, "Indirect shadows against the ground truth") and keeps every stats file and
# picture in the output folder.
#
#   scripts/indirect-shadows-flip.sh [QUADRAY_BIN] [OUT_DIR] [extra quadray indirect flags...]
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-target/release/quadray}
out=${2:-bench/indirect/shadows-flip}
shift $(($# < 2 ? $# : 2))
mkdir -p "$out"
scenes=(leak cornell cornell_bunny cornell_buddha cornell_obj atrium cornell_spot)
for s in "${scenes[@]}"; do
    file=assets/scenes/$s.toml
    [ -f "$file" ] || file=assets/scenes/$s.gltf
    for method in quadtree quadtree-tiles; do
        extra=()
        [ $method = quadtree-tiles ] && extra=(--tile-criterion estimate --tile-share 2)
        for shadows in off on; do
            flag=()
            [ $shadows = on ] && flag=(--indirect-shadows)
            "$bin" indirect --scene "$file" --method $method "${extra[@]}" "${flag[@]}" "$@" \
                --size 256x128 --rsm-size 64 --frames 1 --ground-truth \
                --out "$out/$s-$method-$shadows.png" --stats "$out/$s-$method-$shadows.json" >/dev/null
        done
    done
done
python3 - "$out" "${scenes[@]}" <<'PY'
import json, sys
out, scenes = sys.argv[1], sys.argv[2:]
print("| scene | method | FLIP off -> on | ratio | rel L1 off -> on | fetches/px off -> on |")
print("|---|---|---|---|---|---|")
for s in scenes:
    for m in ("quadtree", "quadtree-tiles"):
        off, on = (json.load(open(f"{out}/{s}-{m}-{x}.json")) for x in ("off", "on"))
        f0, f1 = off["ground_truth"]["flip"], on["ground_truth"]["flip"]
        l0, l1 = off["ground_truth"]["rel_l1"], on["ground_truth"]["rel_l1"]
        print(f"| {s} | {m} | {f0:.4f} -> {f1:.4f} | {f0 / f1:.2f}x | {l0:.4f} -> {l1:.4f} | "
              f"{off['texel_fetches_per_pixel']:.0f} -> {on['texel_fetches_per_pixel']:.0f} |")
PY
