#!/usr/bin/env python3
"""HST's total time against the conventional test's, per bundled scene, in paired rounds.

Each round renders the scene with `--shadows conventional` and `--shadows hst` (`--nth auto`),
alternating which goes first, and the medians of the per-round ratios are printed with the
preprocessing split out (CPU seconds of all threads, from `--stats`), and HST's disagreements
with the conventional test (`--check`, one extra render each).

    python3 scripts/hst-total.py [ROUNDS] [WxH] [--embree]    (defaults 5, 384x360)

With --embree (a build with `--features embree`), each round also renders `--shadows embree`,
and HST's shadow time over Embree's is added (median of the per-round ratios).
"""
import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
QUADRAY = ROOT / "target/release/quadray"
SCENES = [("glasses", ["--builtin", "glasses"]), ("desk", ["--builtin", "desk"]),
          ("stars", ["--builtin", "stars"]), ("kaist", ["--builtin", "kaist"])] + [
    (name, ["--scene", str(ROOT / f"assets/scenes/{name}.toml")])
    for name in ["shadows-cornell", "shadows-demo", "example-hst", "shadows-bunny",
                 "shadows-buddha"]]


def render(scene_args, scheme, size, out, extra=()):
    stats = out / "stats.json"
    subprocess.run([str(QUADRAY), "raytrace", *scene_args, "--shadows", scheme, "--size", size,
                    "--out", str(out / "x.png"), "--stats", str(stats), *extra],
                   check=True, capture_output=True)
    return json.loads(stats.read_text())


def main():
    embree = "--embree" in sys.argv
    args = [a for a in sys.argv[1:] if a != "--embree"]
    rounds = int(args[0]) if args else 5
    size = args[1] if len(args) > 1 else "384x360"
    schemes = ["conventional", "hst"] + (["embree"] if embree else [])
    print(f"{rounds} paired rounds, {size}, 1 sample per pixel")
    print("| scene | polygons | conv total s (pre) | hst total s (pre, of it shadow volumes) "
          "| hst/conv total | hst/conv without preprocessing | disagreements |"
          + (" hst/Embree shadow |" if embree else ""))
    print("|---|---|---|---|---|---|---|" + ("---|" if embree else ""))
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        for name, args in SCENES:
            runs = {s: [] for s in schemes}
            for r in range(rounds):
                for scheme in schemes if r % 2 == 0 else schemes[::-1]:
                    runs[scheme].append(render(args, scheme, size, out))
            conv, hst = runs["conventional"], runs["hst"]
            med = lambda xs: statistics.median(xs)
            ratio = med([h["times_s"]["total"] / c["times_s"]["total"]
                         for c, h in zip(conv, hst)])
            render_ratio = med([
                (h["times_s"]["total"] - h["times_s"]["preprocess"])
                / (c["times_s"]["total"] - c["times_s"]["preprocess"])
                for c, h in zip(conv, hst)])
            checked = render(args, "hst", size, out, ["--check"])
            c_tot = med([c["times_s"]["total"] for c in conv])
            c_pre = med([c["times_s"]["preprocess"] for c in conv])
            h_tot = med([h["times_s"]["total"] for h in hst])
            h_pre = med([h["times_s"]["preprocess"] for h in hst])
            h_vol = med([h["times_s"]["shadow_volumes"] for h in hst])
            d, n = checked["disagreements"], checked["shading_points"]
            print(f"| {name} | {conv[0]['polygons']:,} | {c_tot:.3f} ({c_pre:.3f}) "
                  f"| {h_tot:.3f} ({h_pre:.3f}, {h_vol:.3f}) | {ratio:.2f} | {render_ratio:.2f} "
                  f"| {d} of {n:,} ({d / n:.1e}) |", end="")
            if embree:
                shadow = med([h["times_s"]["shadow"] / e["times_s"]["shadow"]
                              for h, e in zip(hst, runs["embree"])])
                print(f" {shadow:.2f} |", end="")
            print(flush=True)


if __name__ == "__main__":
    main()
