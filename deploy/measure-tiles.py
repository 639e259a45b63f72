#!/usr/bin/env python3
"""What splitting a frame into work items costs: the builtin glasses scene rendered in one process
and as 4 tile processes run one after another, then merged, in paired rounds (BENCHMARKS.md).

Usage: deploy/measure-tiles.py WxH [rounds]   (run from the repository root after a release build)
"""
import resource, statistics, subprocess, sys, tempfile, time
from pathlib import Path

Q = "target/release/quadray"
size, rounds = sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 3
base = [Q, "raytrace", "--builtin", "glasses", "--size", size, "--nth", "40"]
work = Path(tempfile.mkdtemp(prefix="quadray-tiles-"))


def run(args):
    """Wall seconds and CPU seconds (all threads) of one process."""
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    subprocess.run(args, check=True, stdout=subprocess.DEVNULL)
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.perf_counter() - t, (r1.ru_utime + r1.ru_stime) - (r0.ru_utime + r0.ru_stime)


rows = []
for r in range(rounds):
    one = run(base + ["--out", str(work / "one.png")])
    items = [run(base + ["--tiles", "4", "--tile", str(i), "--out", str(work / "t")]) for i in range(4)]
    merge = run([Q, "merge", str(work / "t"), "--out", str(work / "merged.png")])
    same = (work / "one.png").read_bytes() == (work / "merged.png").read_bytes()
    cpu = sum(c for _, c in items)
    slowest = max(w for w, _ in items) / one[0]
    rows.append((one[1], cpu, cpu / one[1], merge[1], slowest))
    print(f"round {r}: one {one[1]:.2f} cpu-s, 4 items {cpu:.2f} cpu-s ({cpu / one[1]:.2f}x), "
          f"merge {merge[1]:.3f} cpu-s, slowest item / one (wall) {slowest:.2f}, identical {same}")
    assert same, "the merge differs from the one-process render"
med = [statistics.median(r[i] for r in rows) for i in range(5)]
print(f"median: one {med[0]:.2f} cpu-s, items {med[1]:.2f} cpu-s ({med[2]:.2f}x), "
      f"merge {med[3]:.3f} cpu-s, slowest item / one (wall) {med[4]:.2f}")
