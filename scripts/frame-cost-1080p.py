#!/usr/bin/env python3
"""The frame cost at 1920x1080 on the tile map: per method and view angle the mean
iterations and texel fetches per pixel that `quadray displace` counts in the shader, then GPU-time
ratios to POM-16 from paired rounds (each round times every method once, in turn, so slow phases
of a shared machine hit all of them; the ratio is the median over rounds of the per-round ratios).

Usage: scripts/frame-cost-1080p.py [QUADRAY_BINARY] [ROUNDS]   (prints markdown tables)
"""

import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

QUADRAY = sys.argv[1] if len(sys.argv) > 1 else "target/release/quadray"
ROUNDS = int(sys.argv[2]) if len(sys.argv) > 2 else 5
MAP = "assets/heightmaps/ambientcg_tiles105/Tiles105_1K_Displacement.png"
ANGLES = [0, 45, 60, 70, 85]
TIMED_ANGLE = 60
METHODS = {
    "pom-16": ["--method", "pom", "--layers", "16,16"],
    "pyramid": ["--method", "pyramid"],
    "pyramid lod-auto": ["--method", "pyramid", "--lod", "auto"],
    "relief 20..25+5 (three.js)": ["--method", "relief", "--layers", "20,25"],
    "cone 15+8": ["--method", "cone", "--layers", "15,15", "--binary-steps", "8"],
}


def run(flags, angle, frames):
    with tempfile.TemporaryDirectory() as tmp:
        stats = Path(tmp) / "stats.json"
        subprocess.run(
            [QUADRAY, "displace", "--map", MAP, "--size", "1920x1080",
             "--view-angle", str(angle), "--frames", str(frames),
             "--out", str(Path(tmp) / "frame.png"), "--stats", str(stats), *flags],
            check=True, stdout=subprocess.DEVNULL)
        return json.loads(stats.read_text())


print("| method | " + " | ".join(f"{a} deg" for a in ANGLES) + " |")
print("|---" * (len(ANGLES) + 1) + "|")
for name, flags in METHODS.items():
    cells = []
    for angle in ANGLES:
        s = run(flags, angle, 1)
        cells.append(f"{s['mean_iterations']:.1f} / {s['texel_fetches_per_pixel']:.1f}")
    print(f"| {name} | " + " | ".join(cells) + " |")

base = next(iter(METHODS))
ratios = {name: [] for name in METHODS}
for _ in range(ROUNDS):
    times = {name: run(flags, TIMED_ANGLE, 5)["gpu_time_ms"] for name, flags in METHODS.items()}
    for name in METHODS:
        ratios[name].append(times[name] / times[base])
print()
print(f"| method | time / {base}, {TIMED_ANGLE} deg (median of {ROUNDS} paired rounds) |")
print("|---|---|")
for name in METHODS:
    print(f"| {name} | {statistics.median(ratios[name]):.2f} |")
