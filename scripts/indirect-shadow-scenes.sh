#!/usr/bin/env bash
# Indirect shadows on scenes nobody tuned on: the default method on the five visibility scenes
# (three tuned on, two held apart) and the bundled leak scene at 256x128 with a 64^2 RSM, without
# indirect shadows (off), with them marched against the depth maps (march: --shadow-grid 0) and
# with them walking the occupancy grid (on: the default). Per scene: the picture's mean FLIP to
# the ray-traced ground truth (exposure 1), the blockiness (steps and bends, with the grid's
# shadows; the bends without shadows too), the texels fetched a pixel (the machine's load does
# not change them) and the static frame's time: ROUNDS rounds that alternate off, march and on,
# FRAMES frames each, no ground truth; the time ratios are the medians of the rounds' ratios
# (min-max beside the grid's). Prints the Markdown table of BENCHMARKS.md ("Indirect shadows on
# scenes nobody tuned on"); keeps the ground-truth runs' stats files in the output folder, and
# the held-apart scenes' indirect light without shadows, with each kind and the truth at four
# times the exposure.
#
#   [ROUNDS=5] [FRAMES=10] scripts/indirect-shadow-scenes.sh [QUADRAY_BIN] [OUT_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-target/release/quadray}
out=${2:-bench/indirect/shadow-scenes}
rounds=${ROUNDS:-5}
frames=${FRAMES:-10}
mkdir -p "$out"
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
tuned=(visibility-door visibility-corridor visibility-gap)
held_apart=(visibility-shelf visibility-storeys visibility-pillars courtyard)
scenes=("${tuned[@]}" "${held_apart[@]}" leak)
run() { # scene, off|on, pictures' stem, stats file, flags...
    local scene=$1 shadows=$2 stem=$3 stats=$4
    shift 4
    local extra=()
    [ "$shadows" = on ] && extra=(--indirect-shadows)
    [ "$shadows" = march ] && extra=(--indirect-shadows --shadow-grid 0)
    "$bin" indirect --scene "assets/scenes/$scene.toml" "${extra[@]}" --size 256x128 \
        --rsm-size 64 --out "$stem.png" --stats "$stats" "$@" >/dev/null
}
for s in "${scenes[@]}"; do
    for shadows in off march on; do
        run "$s" $shadows "$scratch/$s-$shadows" "$out/$s-$shadows.json" --frames 0 --ground-truth
    done
    for ((r = 0; r < rounds; r++)); do
        for shadows in off march on; do
            stem=$scratch/$s-$shadows-$r
            run "$s" $shadows "$stem" "$stem.json" --frames "$frames"
        done
    done
done
for s in "${held_apart[@]}"; do
    for shadows in off march on; do
        stem=$scratch/$s-$shadows-bright
        run "$s" $shadows "$stem" "$stem.json" --frames 0 --ground-truth --exposure 4
        cp "$stem.indirect.png" "$out/$s-$shadows.png"
    done
    cp "$scratch/$s-on-bright.ground-truth.png" "$out/$s-truth.png"
done
python3 - "$out" "$scratch" "$rounds" "${#tuned[@]}" "${#held_apart[@]}" "${scenes[@]}" <<'PY'
import json, statistics, sys
out, scratch, rounds, tuned, held = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5])
scenes = sys.argv[6:]
load = lambda path: json.load(open(f"{path}.json"))
ms = lambda s, x, r: load(f"{scratch}/{s}-{x}-{r}")["gpu_time_ms_static"]["total_ms"]
print("| scene | set | FLIP off -> march -> grid | ratio: march | grid | blockiness (grid): steps | "
      "bends | bends off | fetches/px off -> grid | frame ms off -> grid | time ratio: march | grid (min-max) |")
print("|---" * 12 + "|")
for i, s in enumerate(scenes):
    kind = "tuned" if i < tuned else "held apart" if i < tuned + held else "bundled"
    off, march, on = (load(f"{out}/{s}-{x}") for x in ("off", "march", "on"))
    t_off, t_march, t_on = off["ground_truth"], march["ground_truth"], on["ground_truth"]
    fig = lambda v: "-" if v is None else f"{v:.2f}"
    times = [(ms(s, "off", r), ms(s, "march", r), ms(s, "on", r)) for r in range(rounds)]
    march_ratio = statistics.median(m / a for a, m, _ in times)
    ratios = [g / a for a, _, g in times]
    t0, t1 = (statistics.median(t[k] for t in times) for k in (0, 2))
    print(f"| {s} | {kind} | {t_off['flip']:.4f} -> {t_march['flip']:.4f} -> {t_on['flip']:.4f} | "
          f"{t_off['flip'] / t_march['flip']:.2f}x | {t_off['flip'] / t_on['flip']:.2f}x | "
          f"{fig(t_on['blockiness'])} | {fig(t_on['blockiness_bends'])} | {fig(t_off['blockiness_bends'])} | "
          f"{off['texel_fetches_per_pixel']:.0f} -> {on['texel_fetches_per_pixel']:.0f} | "
          f"{t0:.0f} -> {t1:.0f} | {march_ratio:.2f} | "
          f"{statistics.median(ratios):.2f} ({min(ratios):.2f}-{max(ratios):.2f}) |")
PY
