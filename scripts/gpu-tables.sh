#!/usr/bin/env bash
# Refreshes the GPU figures of BENCHMARKS.md on this machine's adapter, in one run of about 10
# minutes. First the smoke stage: every GPU pass of every technique alone at 16x16 (`quadray
# smoke`), each case in its own process under its own timeout, with the Khronos validation layer
# and its synchronization validation where the machine has the layer (crates/quadray-gpu/vk_layer_settings.txt),
# one line a pass, so that a pass that hangs or faults costs seconds and is named. Then the 1920x1080 displacement frame of every method at 0, 60 and 85
# degrees (with the CPU ground truth's wrong-hit fraction), each indirect-light pass at 1920x1080
# with a 512^2 RSM for every method (the default one also with the wide G-buffer and RSM) and the
# gather's candidates (runtime options; run first), given --bevy-bin the Bevy frame with and without the bounce
# (two paired rounds, Bevy's render diagnostics), then, while the time budget lasts, the paper
# tables of `quadray bench displace` and `quadray bench indirect`. Writes bench/<device>/ (the device's
# name from the adapter, e.g. bench/nvidia-h200/) with every stats file (each naming the commit
# and the adapter it measured) and a summary.md of the tables (headed by the adapter, the date and
# the commit), and packs it into gpu-tables.tar.gz beside it (one file to copy off the machine).
#
#   scripts/gpu-tables.sh [--quick] [--smoke-only] [--smoke REGEX] [--runs REGEX] [--bin PATH]
#                         [--bevy-bin PATH] [--out DIR] [--budget SECONDS]
#
# --smoke-only: the smoke stage alone.
# --smoke: only the smoke cases whose names match (grep -E; `quadray smoke --list` names them).
# --runs: only the runs after the smoke stage whose names match (bash =~; the names are the
#   logs/NAME.log files: indirect-METHOD, indirect-CANDIDATE, shadows-SCENE-RUN, equal-error-SCENE-RUN,
#   displace-METHOD-ANGLE, bevy-...).
# --quick: small frames, for trying the script on a software rasterizer (a minute on lavapipe).
# --bin: the quadray binary (default target/release/quadray, built if missing).
# --bevy-bin: the quadray-bevy-gi program (`cargo build --release --bin quadray-bevy-gi`); it
#   reads the assets from the checkout it was built in.
# --budget: seconds after which the optional paper tables are skipped (default 540).
set -euo pipefail
cd "$(dirname "$0")/.."

quick=0
smoke_only=0
smoke_cases=.
runs=.
bin=target/release/quadray
bevy_bin=
out_root=bench
budget=540
while [ $# -gt 0 ]; do
    case "$1" in
        --quick) quick=1 ;;
        --smoke-only) smoke_only=1 ;;
        --smoke) smoke_cases=$2; shift ;;
        --runs) runs=$2; shift ;;
        --bin) bin=$2; shift ;;
        --bevy-bin) bevy_bin=$2; shift ;;
        --out) out_root=$2; shift ;;
        --budget) budget=$2; shift ;;
        *) echo "gpu-tables.sh: unknown option $1" >&2; exit 2 ;;
    esac
    shift
done
if [ ! -x "$bin" ]; then
    cargo build --release --bin quadray
fi
start=$SECONDS
left() { echo $((budget - (SECONDS - start))); }

if [ $quick = 1 ]; then
    size=96x54 rsm=32 frames=3 ee_frames=2 angles=60 bevy_frames=3
else
    size=1920x1080 rsm=512 frames=20 ee_frames=10 angles="0 60 85" bevy_frames=60
fi

# The adapter's name as a folder: "NVIDIA H200 (Vulkan, NVIDIA 580.159.04)" -> nvidia-h200.
probe=$(mktemp -d)
map=assets/heightmaps/ambientcg_tiles105/Tiles105_1K_Displacement.png
adapter=$(timeout 60 "$bin" adapter)
device=$(echo "${adapter%% (*}" | tr '[:upper:]' '[:lower:]' | sed 's/[^a-z0-9]\+/-/g; s/^-//; s/-$//')
[ $quick = 1 ] && device="$device-quick"
out="$out_root/$device"
mkdir -p "$out/displace-1080p" "$out/indirect-1080p" "$out/logs" "$out/smoke"
# the build measured: `quadray 0.1.0 (commit C)` (every stats file records it too)
version=$("$bin" --version)
printf '%s\n%s\n%s\n' "$adapter" "$(date -u +%Y-%m-%dT%H:%MZ)" "$version" >"$out/adapter.txt"
echo "$adapter -> $out"

# The smoke stage. The layer is used where the Vulkan loader finds it (its manifest in a standard
# folder, or in VK_ADD_LAYER_PATH / VK_LAYER_PATH); every message it prints is counted.
layer_env=()
layer="not found"
for dir in $(echo "${VK_ADD_LAYER_PATH:-}:${VK_LAYER_PATH:-}" | tr : " ") /usr/share/vulkan/explicit_layer.d \
    /usr/local/share/vulkan/explicit_layer.d /etc/vulkan/explicit_layer.d; do
    if [ -f "$dir/VkLayer_khronos_validation.json" ]; then
        layer_env=(VK_INSTANCE_LAYERS=VK_LAYER_KHRONOS_validation
            "VK_LAYER_SETTINGS_PATH=$PWD/crates/quadray-gpu/vk_layer_settings.txt")
        layer="on ($dir)"
        break
    fi
done
echo "smoke stage: validation layer $layer"
smoke_failed=0
for case in $("$bin" smoke --list | grep -E "$smoke_cases"); do
    log="$out/smoke/$case.log"
    status=0
    env "${layer_env[@]}" QUADRAY_GPU_WAIT_S=15 timeout 45 "$bin" smoke --case "$case" >"$log" 2>&1 ||
        status=$?
    grep -a -E ': (done in|stopped after) ' "$log" || true
    messages=$(grep -a -c -E 'Validation (Error|Warning)' "$log" || true)
    if [ "$messages" != 0 ]; then
        echo "$case: $messages validation messages (smoke/$case.log)"
        smoke_failed=1
    fi
    if [ $status = 124 ]; then
        echo "$case: killed after 45 s, after the last pass above (smoke/$case.log)"
    fi
    if [ $status != 0 ]; then
        echo "$case: failed (exit $status)" >>"$out/skipped.txt"
        smoke_failed=1
    fi
done
if [ $smoke_only = 1 ]; then
    tar -czf "$out_root/gpu-tables.tar.gz" -C "$out_root" "$device"
    exit $smoke_failed
fi

# One run: its output in logs/NAME.log; a failure or a run past 3 minutes is noted in
# skipped.txt and the next run goes on (the tables that did run still come back).
step() {
    local name=$1
    shift
    [[ $name =~ $runs ]] || return 0
    echo "$((SECONDS - start)) s: $name"
    timeout 180 "$@" >"$out/logs/$name.log" 2>&1 ||
        echo "$name: failed or stopped after 180 s (logs/$name.log)" >>"$out/skipped.txt"
}

# Indirect light first (the real-time gather leads), then displacement.
for m in quadtree quadtree-passes quadtree-tiles rsm; do
    step "indirect-$m" "$bin" indirect --method $m --size $size --rsm-size $rsm \
        --frames $frames --out "$probe/i.png" --stats "$out/indirect-1080p/$m.json"
done
# The default method again with the wide G-buffer and RSM (--gbuffer-layout), beside the
# compact default: the raster passes' cost by their targets' widths.
step indirect-quadtree-tiles-wide "$bin" indirect --method quadtree-tiles --gbuffer-layout wide \
    --size $size --rsm-size $rsm --frames $frames --out "$probe/i.png" \
    --stats "$out/indirect-1080p/quadtree-tiles-wide.json"
for m in quadtree quadtree-tiles; do
    step "indirect-$m-shadows" "$bin" indirect --method $m --indirect-shadows \
        --size $size --rsm-size $rsm --frames $frames --out "$probe/i.png" \
        --stats "$out/indirect-1080p/$m-shadows.json"
done
# The gather's candidates, each a runtime option of the same binary (name, then its flags):
# interleaved sampling of the one cut and of RSM sampling, the one cut made finer under it, and
# the one cut with indirect shadows: interleaved (each pixel takes a sixteenth of its clusters),
# with each pixel walking its own rays (--shadow-corners 0), from corner receivers nearer and
# farther apart than the default's 16 pixels at 1920x1080, and with 16 or 8 threads walking a
# corner's rays instead of 64 (each lane walks 4 or 8 times the rays: do a wave's lanes end
# closer together?); the per-tile cuts with shadows in split passes (--tile-passes split: the
# walks in a pass of their own, with almost no workgroup memory), paired with
# indirect-quadtree-tiles-shadows, the fused kernel (docs/known-problems.md predicts the split),
# with 16 threads walking a tile's rays, and with 4 or 64.
while read -r name flags; do
    # shellcheck disable=SC2086 # $flags is several words
    step "indirect-$name" "$bin" indirect $flags --size $size --rsm-size $rsm \
        --frames $frames --out "$probe/i.png" --stats "$out/indirect-1080p/$name.json"
done <<'CANDIDATES'
quadtree-interleave-2 --method quadtree --interleave 2
quadtree-interleave-4 --method quadtree --interleave 4
quadtree-limit-2-interleave-4 --method quadtree --limit-level 2 --interleave 4
rsm-interleave-4 --method rsm --interleave 4
rsm-1024-interleave-4 --method rsm --samples 1024 --interleave 4
quadtree-shadows-interleave-4 --method quadtree --indirect-shadows --interleave 4
quadtree-shadows-corners-0 --method quadtree --indirect-shadows --shadow-corners 0
quadtree-shadows-corners-8 --method quadtree --indirect-shadows --shadow-corners 8
quadtree-shadows-corners-32 --method quadtree --indirect-shadows --shadow-corners 32
quadtree-shadows-corners-8-interleave-4 --method quadtree --indirect-shadows --shadow-corners 8 --interleave 4
quadtree-shadows-corner-lanes-16 --method quadtree --indirect-shadows --shadow-corner-lanes 16
quadtree-shadows-corner-lanes-8 --method quadtree --indirect-shadows --shadow-corner-lanes 8
quadtree-tiles-shadows-split --method quadtree-tiles --indirect-shadows --tile-passes split
quadtree-tiles-shadows-split-walk-lanes-4 --method quadtree-tiles --indirect-shadows --tile-passes split --tile-walk-lanes 4
quadtree-tiles-shadows-split-walk-lanes-64 --method quadtree-tiles --indirect-shadows --tile-passes split --tile-walk-lanes 64
CANDIDATES
# An indirect run that failed or hung: one tiny frame again with wgpu's trace (pipelines created,
# each submit), to see where it stops.
if grep -qs '^indirect-' "$out/skipped.txt"; then
    RUST_LOG=wgpu_core=trace,quadray=debug step indirect-trace "$bin" indirect --size 16x16 \
        --rsm-size 16 --frames 1 --out "$probe/t.png" --stats "$probe/t.json"
fi

# The bounce with indirect shadows on every visibility scene (the goal: at most 1 ms a frame at
# 1920x1080), the default method, its split passes (--tile-passes split) and the one cut
# interleaved at 4 from its shadow corners.
mkdir -p "$out/shadows-1080p"
for scene in cornell leak visibility-door visibility-corridor visibility-gap visibility-shelf \
    visibility-storeys visibility-pillars courtyard; do
    while read -r name flags; do
        # shellcheck disable=SC2086 # $flags is several words
        step "shadows-$scene-$name" "$bin" indirect --scene "assets/scenes/$scene.toml" $flags \
            --indirect-shadows --size $size --rsm-size $rsm --frames $frames --out "$probe/s.png" \
            --stats "$out/shadows-1080p/$scene-$name.json"
    done <<'RUNS'
default --method quadtree-tiles
split --method quadtree-tiles --tile-passes split
one-cut-interleave-4 --method quadtree --interleave 4
RUNS
done

# Equal error in GPU time: each method's rel. L1 to the GPU brute force (--reference) beside its
# static frame's indirect passes, on the Cornell box, the atrium and the leak scene; RSM sampling
# swept so that the summary interpolates its time at each other run's error.
mkdir -p "$out/equal-error"
for scene in cornell atrium leak; do
    while read -r name flags; do
        # shellcheck disable=SC2086 # $flags is several words or none
        step "equal-error-$scene-$name" "$bin" indirect --scene "assets/scenes/$scene.toml" $flags \
            --size $size --rsm-size $rsm --frames $ee_frames --reference --out "$probe/e.png" \
            --stats "$out/equal-error/$scene-$name.json"
    done <<'RUNS'
default
one-cut --method quadtree
one-cut-interleave-4 --method quadtree --interleave 4
one-cut-limit-2-interleave-4 --method quadtree --limit-level 2 --interleave 4
rsm-64 --method rsm --samples 64
rsm-256 --method rsm --samples 256
rsm-1024 --method rsm --samples 1024
rsm-4096 --method rsm --samples 4096
rsm-16384 --method rsm --samples 16384
rsm-1024-interleave-4 --method rsm --samples 1024 --interleave 4
RUNS
done

# Displacement.
for m in pom pyramid pyramid-ascend pyramid-bilinear relief; do
    for a in $angles; do
        step "displace-$m-$a" "$bin" displace --map $map --method $m --layers 1,16 \
            --view-angle "$a" --size $size --reference --out "$probe/d.png" \
            --stats "$out/displace-1080p/$m-$a.json"
    done
done
step displace-pyramid-lodauto-60 "$bin" displace --map $map --method pyramid --lod auto \
    --view-angle 60 --size $size --reference --out "$probe/d.png" \
    --stats "$out/displace-1080p/pyramid-lodauto-60.json"

# The Bevy frame, the light turning (every frame a new RSM, pyramid, cut and gather), with and
# without the bounce, in two paired rounds.
if [ -n "$bevy_bin" ]; then
    mkdir -p "$out/bevy"
    for round in 1 2; do
        for gi in gi gi-interleaved no-gi; do
            case $gi in
                no-gi) flags=--no-gi ;;
                gi-interleaved) flags="--method quadtree --interleave 4" ;;
                *) flags= ;;
            esac
            # shellcheck disable=SC2086 # $flags is several words or none
            step "bevy-$gi-$round" "$bevy_bin" --screenshot "$out/bevy/$gi.png" \
                --frames $bevy_frames --size $size --rsm-size $rsm $flags
            grep -a -E '^(median frame|render/)' "$out/logs/bevy-$gi-$round.log" \
                >"$out/bevy/$gi-$round.log" || true
        done
    done
fi

# The paper tables, each only if the budget still holds it.
paper() {
    local name=$1 need=$2
    shift 2
    if [ "$(left)" -gt "$need" ]; then
        echo "$((SECONDS - start)) s: $name"
        timeout "$(left)" "$bin" bench "$@" >"$out/$name.log" 2>&1 || echo "$name: stopped" >>"$out/skipped.txt"
    else
        echo "$name: skipped, $(left) s of the budget left" >>"$out/skipped.txt"
    fi
}
if [ $quick = 1 ]; then
    paper bench-indirect 30 indirect --quick --rsm-size 64 --out "$out/bench-indirect"
else
    paper bench-displace 240 displace --out "$out/bench-displace"
    paper bench-indirect 120 indirect --rsm-size 512 --out "$out/bench-indirect"
fi

# (the summary needs python3; the stats files alone hold every figure)
python3 - "$out" <<'EOF' || echo "no summary.md: python3 failed or is missing" >&2
import json, pathlib, re, sys
out = pathlib.Path(sys.argv[1])
adapter, date, version = (out / "adapter.txt").read_text().split("\n")[:3]
lines = [f"# GPU tables on {adapter}, {date}, {version}", ""]
lines += ["## Displacement frame", "",
          "| method | view angle | GPU ms | wrong-hit fraction | mean iterations | max iterations | cap hits |",
          "|---|---|---|---|---|---|---|"]
for f in sorted((out / "displace-1080p").glob("*.json")):
    s = json.loads(f.read_text())
    method = s["method"] + (" (lod auto)" if "lodauto" in f.name else "")
    wrong = f"{s['wrong_hit_fraction']:.6f}" if "wrong_hit_fraction" in s else "-"
    lines.append(f"| {method} | {s['view_angle_deg']:g} | {s['gpu_time_ms']:.3f} | {wrong} | "
                 f"{s['mean_iterations']:.1f} | {s['max_iterations']} | {s['iteration_cap_hits']} |")
lines += ["", "## Indirect light, per pass (GPU ms, median)", "",
          "| run | G-buffer layout | RSM | G-buffer | direct | indirect | reconstruct | static frame | moving-light frame | VPL evaluations / pixel |",
          "|---|---|---|---|---|---|---|---|---|---|"]
for f in sorted((out / "indirect-1080p").glob("*.json")):
    s = json.loads(f.read_text())
    still, moving = s["gpu_time_ms_static"] or {}, s["gpu_time_ms_moving"] or {}
    p = still.get("passes", {})
    cell = lambda v: f"{v:.3f}" if isinstance(v, (int, float)) else "-"
    lines.append(f"| {f.stem} | {s['settings'].get('gbuffer_layout', '-')} | {cell(p.get('rsm'))} | "
                 f"{cell(p.get('gbuffer'))} | {cell(p.get('direct'))} | "
                 f"{cell(p.get('indirect'))} | {cell(p.get('upsample'))} | {cell(still.get('total_ms'))} | "
                 f"{cell(moving.get('total_ms'))} | {s['vpl_evaluations_per_pixel']:.1f} |")
# The bounce: the frame without the G-buffer, the direct light and its shadow maps.
shadow_runs = sorted((out / "shadows-1080p").glob("*.json")) if (out / "shadows-1080p").exists() else []
if shadow_runs:
    lines += ["", "## The bounce with indirect shadows (GPU ms, median; the frame less the G-buffer and the direct light)", "",
              "| scene | run | indirect | reconstruct | bounce, light still | bounce, light moving | texel fetches / pixel |",
              "|---|---|---|---|---|---|---|"]
    def bounce(t):
        p = t.get("passes", {})
        return t["total_ms"] - sum(p.get(k, 0.0) for k in ("gbuffer", "direct", "shadow-map"))
    for f in shadow_runs:
        s = json.loads(f.read_text())
        still, moving = s["gpu_time_ms_static"] or {}, s["gpu_time_ms_moving"] or {}
        p = still.get("passes", {})
        cell = lambda v: f"{v:.3f}" if isinstance(v, (int, float)) else "-"
        scene, name = re.match(r"(.*?)-(default|split|one-cut.*)$", f.stem).groups()
        lines.append(f"| {scene} | {name} | {cell(p.get('indirect'))} | {cell(p.get('upsample'))} | "
                     f"{cell(bounce(still) if still else None)} | {cell(bounce(moving) if moving else None)} | "
                     f"{s['texel_fetches_per_pixel']:.0f} |")
# Equal error: RSM sampling's indirect time at each run's rel. L1, interpolated log-log between
# the two sample counts whose errors bracket it, over the run's own.
def indirect_ms(s):
    p = (s["gpu_time_ms_static"] or {}).get("passes", {})
    return p.get("indirect", 0.0) + p.get("upsample", 0.0)
import math
ee = {}
for f in sorted((out / "equal-error").glob("*.json")) if (out / "equal-error").exists() else []:
    s = json.loads(f.read_text())
    if s.get("error") and s.get("gpu_time_ms_static"):
        scene, name = f.stem.split("-", 1)
        ee.setdefault(scene, []).append((name, s["error"]["rel_l1"], indirect_ms(s), s["vpl_evaluations_per_pixel"]))
if ee:
    lines += ["", "## Equal error (rel. L1 to the brute force; indirect passes, GPU ms, static light)", "",
              "| scene | run | rel L1 | indirect ms | evals / px | RSM sampling's ms at that error | ratio |",
              "|---|---|---|---|---|---|---|"]
    for scene, runs in ee.items():
        rsm = sorted((e, t) for n, e, t, _ in runs if re.fullmatch(r"rsm-\d+", n))
        for name, e, t, evals in runs:
            at = "-"
            for (e1, t1), (e0, t0) in zip(rsm, rsm[1:]):
                if e1 <= e <= e0 and min(e0, e1, t0, t1) > 0:
                    k = math.log(e / e0) / math.log(e1 / e0) if e1 != e0 else 0.0
                    at = math.exp(math.log(t0) + k * (math.log(t1) - math.log(t0)))
            ratio = f"{at / t:.2f}" if at != "-" and t > 0 else "-"
            if at != "-":
                at = f"{at:.3f}"
            elif rsm:
                at = f"below the sweep's {rsm[0][0]:.4f}" if e < rsm[0][0] else "above the sweep"
            else:
                at = "no sweep"
            lines.append(f"| {scene} | {name} | {e:.4f} | {t:.3f} | {evals:.1f} | {at} | {ratio} |")
bevy = sorted((out / "bevy").glob("*.log")) if (out / "bevy").exists() else []
if bevy:
    lines += ["", "## The Bevy frame (quadray-bevy-gi, light turning; medians)", "",
              "| run | frame ms | bounce GPU ms | light passes | gather | composite | clusters in cut | VPL evaluations / pixel |",
              "|---|---|---|---|---|---|---|---|"]
    for f in bevy:
        values = {}
        for line in f.read_text().splitlines():
            if line.startswith("median frame"):
                values["frame"] = float(line.split()[2])
            elif ": median " in line:
                path, rest = line.split(": median ")
                # one camera: its path's part (render/quadray_gi/camera_{entity}/...) dropped
                key = re.sub(r"^camera_[^/]+/?", "", path.removeprefix("render/quadray_gi").strip("/"))
                values[key] = float(rest.split()[0].rstrip("ms"))
        cell = lambda k: f"{values[k]:.3f}" if k in values else "-"
        lines.append(f"| {f.stem} | {cell('frame')} | {cell('elapsed_gpu')} | {cell('light/elapsed_gpu')} | "
                     f"{cell('gather/elapsed_gpu')} | {cell('composite/elapsed_gpu')} | "
                     f"{cell('cut_clusters')} | {cell('vpl_evaluations_per_pixel')} |")
skipped = out / "skipped.txt"
if skipped.exists():
    lines += ["", "Skipped: " + "; ".join(skipped.read_text().split("\n")).strip("; ")]
(out / "summary.md").write_text("\n".join(lines) + "\n")
print("\n".join(lines))
EOF
tar -czf "$out_root/gpu-tables.tar.gz" -C "$out_root" "$device"
rm -rf "$probe"
echo "wrote $out and $out_root/gpu-tables.tar.gz in $((SECONDS - start)) s"
