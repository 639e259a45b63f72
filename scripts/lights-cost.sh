#!/usr/bin/env bash
# The cost of each kind of light and of several lights in `quadray indirect` (BENCHMARKS.md,
# "Lights"): the Cornell box lit by a spot, the sun, a point light, then by 1, 2 and 4 spots; the
# default method, GPU medians of FRAMES frames with the lights rebuilt each frame, in ROUNDS
# rounds that run every scene once each (paired: a slow spell of the machine hits every scene
# alike), the median over the rounds. Prints a Markdown table: each pass's time, the GI passes'
# (pyramid, validity, indirect) over one spot's, and the frame with them over the frame without
# (G-buffer, RSMs, direct light).
# Usage: scripts/lights-cost.sh [QUADRAY] [SIZE] [RSM_SIZE] [FRAMES] [ROUNDS]
set -euo pipefail
cd "$(dirname "$0")/.."
quadray=${1:-target/release/quadray}
size=${2:-256}
rsm=${3:-128}
frames=${4:-10}
rounds=${5:-5}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
room=$(sed -n '/^\[\[mesh\]\]/,$p' assets/scenes/cornell.toml)
camera=$(sed -n '/^\[camera\]/,/^$/p' assets/scenes/cornell.toml)
spot() { printf '[[lights]]\nposition = [%s]\ndirection = [%s]\ncone_deg = 55.0\nfalloff_deg = 15.0\nintensity = [1.0, 1.0, 1.0]\n' "$1" "$2"; }
scene() { printf 'r_min = 0.05\n%s\n%s\n%s\n' "$camera" "$1" "$room" > "$out/$2.toml"; }
scene "$(spot '0.5, 0.97, 0.85' '-0.25, -1.0, -0.55')" spot
scene "$(printf '[[lights]]\ndirection = [-0.3, -0.6, -1.0]\nintensity = [1.5, 1.5, 1.5]\n')" sun
scene "$(printf '[[lights]]\nposition = [0.5, 0.8, 0.6]\nintensity = [0.5, 0.5, 0.5]\n')" point
scene "$(spot '0.5, 0.97, 0.85' '-0.25, -1.0, -0.55')" spots-1
scene "$(spot '0.5, 0.97, 0.85' '-0.25, -1.0, -0.55'; spot '0.2, 0.97, 0.3' '0.3, -1.0, 0.2')" spots-2
scene "$(spot '0.5, 0.97, 0.85' '-0.25, -1.0, -0.55'; spot '0.2, 0.97, 0.3' '0.3, -1.0, 0.2'; \
         spot '0.8, 0.97, 0.3' '-0.3, -1.0, 0.3'; spot '0.8, 0.97, 0.8' '-0.2, -1.0, -0.3')" spots-4
for round in $(seq "$rounds"); do
  for name in spot sun point spots-1 spots-2 spots-4; do
    "$quadray" indirect --scene "$out/$name.toml" --size "${size}x${size}" --rsm-size "$rsm" \
      --frames "$frames" --out "$out/$name.png" --stats "$out/$name-$round.json" > /dev/null
  done
done
python3 - "$out" "$rounds" <<'PY'
import json, statistics, sys
out, rounds = sys.argv[1], int(sys.argv[2])
views = {"spot": 1, "sun": 1, "point": 6, "spots-1": 1, "spots-2": 2, "spots-4": 4}
def median_passes(name):
    runs = [json.load(open(f"{out}/{name}-{r}.json"))["gpu_time_ms_moving"]["passes"]
            for r in range(1, rounds + 1)]
    return {k: statistics.median(run[k] for run in runs) for k in runs[0]}
passes = {name: median_passes(name) for name in views}
gi = {name: p["pyramid"] + p["validity"] + p["indirect"] for name, p in passes.items()}
print("| lights | views | rsm ms | pyramid + validity ms | indirect ms | direct ms | "
      "GI passes / one spot's | frame with GI / without |")
print("|---|---|---|---|---|---|---|---|")
for name, n in views.items():
    p = passes[name]
    without = p["gbuffer"] + p["rsm"] + p["direct"]
    print(f"| {name} | {n} | {p['rsm']:.2f} | {p['pyramid'] + p['validity']:.2f} | "
          f"{p['indirect']:.1f} | {p['direct']:.2f} | {gi[name] / gi['spot']:.2f} | "
          f"{(gi[name] + without) / without:.0f} |")
PY
