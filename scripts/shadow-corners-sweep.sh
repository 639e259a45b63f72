#!/usr/bin/env bash
# The one cut's indirect shadows from corner receivers (--shadow-corners K) on the visibility
# scenes (three tuned on, four held apart) and the bundled leak scene and Cornell box, at 128x128
# with a 64^2 RSM: per scene and K the picture's mean FLIP to the ray-traced ground truth
# (exposure 1) and the frame's texel fetches over those of every pixel walking (K 0). Counts and
# errors are the same on any adapter. Prints the Markdown table of BENCHMARKS.md ("The one cut's
# indirect shadows from corners") and keeps the stats files in the output folder.
#
#   scripts/shadow-corners-sweep.sh [QUADRAY_BIN] [OUT_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-target/release/quadray}
out=${2:-bench/indirect/shadow-corners}
mkdir -p "$out"
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
scenes=(leak:bundled cornell:bundled visibility-corridor:tuned visibility-door:tuned
    visibility-gap:tuned visibility-storeys:"held apart" visibility-shelf:"held apart"
    visibility-pillars:"held apart" courtyard:"held apart")
spacings=(off 0 1 2 4 8)
echo "| scene | set | off | walks (K 0) | K 1 | K 2 | K 4 | K 8 |"
echo "|---|---|---|---|---|---|---|---|"
for entry in "${scenes[@]}"; do
    scene=${entry%%:*}
    row="| $scene | ${entry#*:} |"
    for k in "${spacings[@]}"; do
        flags=(--indirect-shadows --shadow-corners "$k")
        [ "$k" = off ] && flags=()
        "$bin" indirect --scene "assets/scenes/$scene.toml" --method quadtree "${flags[@]}" \
            --size 128x128 --rsm-size 64 --frames 0 --ground-truth --out "$scratch/p.png" \
            --stats "$out/$scene-$k.json" >/dev/null
        row+=$(python3 - "$out/$scene-$k.json" "$out/$scene-0.json" "$k" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
flip, fetches = s["ground_truth"]["flip"], s["work"]["texel_fetches"]
if sys.argv[3] in ("off", "0"):
    print(f" {flip:.4f} |", end="")
else:
    walks = json.load(open(sys.argv[2]))["work"]["texel_fetches"]
    print(f" {flip:.4f} ({fetches / walks:.2f}x) |", end="")
PY
)
    done
    echo "$row"
done
