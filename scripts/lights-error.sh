#!/usr/bin/env bash
# The default method's error against the ray-traced ground truth for each kind of light
# (BENCHMARKS.md, "Lights"): the Cornell box's spot, the courtyard's sun, the lamplit room's three
# point lights and cornell_lights.gltf's sun, point light and spot, without and with indirect
# shadows. Prints a Markdown table of the FLIP and rel. L1 of the indirect light.
# Usage: scripts/lights-error.sh [QUADRAY] [WIDTH] [HEIGHT] [RSM_SIZE]
set -euo pipefail
cd "$(dirname "$0")/.."
quadray=${1:-target/release/quadray}
width=${2:-128}
height=${3:-96}
rsm=${4:-32}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
scenes=(cornell.toml courtyard.toml lamplit_room.toml cornell_lights.gltf)
for scene in "${scenes[@]}"; do
  for shadows in off on; do
    flag=()
    [ "$shadows" = on ] && flag=(--indirect-shadows)
    "$quadray" indirect --scene "assets/scenes/$scene" --size "${width}x${height}" \
      --rsm-size "$rsm" --frames 1 --ground-truth "${flag[@]}" --out "$out/$scene-$shadows.png" \
      --stats "$out/$scene-$shadows.json" > /dev/null
  done
done
python3 - "$out" "${scenes[@]}" <<'PY'
import json, sys
out, scenes = sys.argv[1], sys.argv[2:]
lights = {"cornell.toml": "a spot (1 view)", "courtyard.toml": "the sun (1 view)",
          "lamplit_room.toml": "3 point lights (18 views)",
          "cornell_lights.gltf": "sun, point, spot (8 views)"}
print("| scene | lights | FLIP without -> with indirect shadows | rel. L1 without -> with |")
print("|---|---|---|---|")
for scene in scenes:
    truth = [json.load(open(f"{out}/{scene}-{s}.json"))["ground_truth"] for s in ("off", "on")]
    print(f"| {scene} | {lights.get(scene, '')} | {truth[0]['flip']:.4f} -> {truth[1]['flip']:.4f} | "
          f"{truth[0]['rel_l1']:.3f} -> {truth[1]['rel_l1']:.3f} |")
PY
