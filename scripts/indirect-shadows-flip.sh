#!/usr/bin/env bash
# Indirect shadows against the ray-traced ground truth on every bundled scene: the picture's mean
# FLIP and the indirect term's rel. L1 without and with `--indirect-shadows`, for the one cut and
# the per-tile cuts (estimate, far clusters shared at 2 tile extents), and their cost: fetches a
# pixel and, with ROUNDS=N (N > 0), the median static frame's time over N rounds that alternate
# off and on (5 frames each, no ground truth; their files are not kept). Prints a Markdown table
# (BENCHMARKS.md, "Indirect shadows against the ground truth") and keeps the ground-truth runs'
# stats files and pictures in the output folder.
#
#   [ROUNDS=N] scripts/indirect-shadows-flip.sh [QUADRAY_BIN] [OUT_DIR] [extra quadray indirect flags...]
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-target/release/quadray}
out=${2:-bench/indirect/shadows-flip}
rounds=${ROUNDS:-0}
shift $(($# < 2 ? $# : 2))
mkdir -p "$out"
rounds_dir=$(mktemp -d)
trap 'rm -rf "$rounds_dir"' EXIT
scenes=(leak cornell cornell_bunny cornell_buddha cornell_obj atrium cornell_spot)
run() { # scene file, method, off|on, output stem, flags...
    local file=$1 method=$2 shadows=$3 stem=$4
    shift 4
    local extra=()
    [ "$method" = quadtree-tiles ] && extra=(--tile-criterion estimate --tile-share 2)
    [ "$shadows" = on ] && extra+=(--indirect-shadows)
    "$bin" indirect --scene "$file" --method "$method" "${extra[@]}" --size 256x128 --rsm-size 64 \
        --out "$stem.png" --stats "$stem.json" "$@" >/dev/null
}
for s in "${scenes[@]}"; do
    file=assets/scenes/$s.toml
    [ -f "$file" ] || file=assets/scenes/$s.gltf
    for method in quadtree quadtree-tiles; do
        for shadows in off on; do
            run "$file" $method $shadows "$out/$s-$method-$shadows" --frames 1 --ground-truth "$@"
        done
        for ((r = 0; r < rounds; r++)); do
            for shadows in off on; do
                run "$file" $method $shadows "$rounds_dir/$s-$method-$shadows-$r" --frames 5 "$@"
            done
        done
    done
done
python3 - "$out" "$rounds_dir" "$rounds" "${scenes[@]}" <<'PY'
import json, statistics, sys
out, rounds_dir, rounds, scenes = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4:]
load = lambda path: json.load(open(f"{path}.json"))
head = "| scene | method | FLIP off -> on | ratio | rel L1 off -> on | ratio | fetches/px off -> on |"
print(head + (" frame ms off -> on | time ratio |" if rounds else ""))
print("|---" * (head.count("|") - 1 + (2 if rounds else 0)) + "|")
for s in scenes:
    for m in ("quadtree", "quadtree-tiles"):
        off, on = (load(f"{out}/{s}-{m}-{x}") for x in ("off", "on"))
        f0, f1 = off["ground_truth"]["flip"], on["ground_truth"]["flip"]
        l0, l1 = off["ground_truth"]["rel_l1"], on["ground_truth"]["rel_l1"]
        row = (f"| {s} | {m} | {f0:.4f} -> {f1:.4f} | {f0 / f1:.2f}x | {l0:.4f} -> {l1:.4f} | "
               f"{l0 / l1:.2f}x | {off['texel_fetches_per_pixel']:.0f} -> "
               f"{on['texel_fetches_per_pixel']:.0f} |")
        if rounds:
            ms = [statistics.median(load(f"{rounds_dir}/{s}-{m}-{x}-{r}")["gpu_time_ms_static"]["total_ms"]
                                    for r in range(rounds)) for x in ("off", "on")]
            row += f" {ms[0]:.0f} -> {ms[1]:.0f} | {ms[1] / ms[0]:.2f} |"
        print(row)
PY
