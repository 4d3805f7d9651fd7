"""CPU time of runs given user points on mid-stance frames, builds side by side.

    python benches/python/bench_points_cost.py PEDOMATCH_A PEDOMATCH_B [--rounds 5]

Points: every third sensel centre of the bundled walk whose four neighbours are loaded, on the
mid-stance frames 40, 75, 110 and 146 (307 points; frames 75 and 110 seed two objects each),
and every fourth sensel centre of the pedar recording's frame 150 whose eight neighbours are
loaded (47 points, on both insoles: two objects). Each build runs `run FILE --points POINTS`
(tables only), the builds alternating round by round; prints the median, least and largest CPU
time (user + system) of each. Needs numpy and pymodal (to read the frames).
"""

import argparse
import csv
import os
import statistics
import subprocess
import tempfile
from pathlib import Path

import numpy as np

import pymodal

ROOT = Path(__file__).resolve().parents[2]
CASES = [
    ("walk", ROOT / "examples" / "data" / "FrasP01L.asf", (40, 75, 110, 146), 3, 1),
    ("pedar", ROOT / "benches" / "data" / "pedar-pressuRe-2.01-5.00.asc", (150,), 4, 2),
]


def write_points(path, frames, stride, reach, out):
    """Every `stride`-th loaded sensel centre of `frames` whose neighbours up to `reach` (1: the
    four, 2: the eight) are loaded too."""
    rec = pymodal.read_recording(str(path))
    data, noise = np.asarray(rec.frames), rec.noise_threshold or 0.0
    near = [(0, 1), (0, -1), (1, 0), (-1, 0)]
    if reach == 2:
        near = [(dy, dx) for dy in (-1, 0, 1) for dx in (-1, 0, 1)]
    with open(out, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["x", "y", "frame"])
        for k in frames:
            m = np.nan_to_num(data[k]) > noise
            inner = m.copy()
            for dy, dx in near:
                inner &= np.roll(np.roll(m, dy, 0), dx, 1)
            ys, xs = np.nonzero(inner)
            for x, y in zip(xs[::stride], ys[::stride]):
                w.writerow([x, y, k])


def cpu(argv):
    p = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    _, status, usage = os.wait4(p.pid, 0)
    if status != 0:
        raise SystemExit(f"{argv} failed")
    return usage.ru_utime + usage.ru_stime


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("builds", nargs=2)
    ap.add_argument("--rounds", type=int, default=5)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as d:
        times = {}
        for name, path, frames, stride, reach in CASES:
            points = Path(d) / f"{name}.csv"
            write_points(path, frames, stride, reach, points)
            for _ in range(args.rounds):
                for b in args.builds:
                    out = Path(d) / "out"
                    t = cpu([b, "run", str(path), "--points", str(points), "--out", str(out),
                             "--figures", "none", "--report", "none"])
                    times.setdefault((name, b), []).append(t)
        for (name, b), v in times.items():
            print(f"{name} {b}: median {statistics.median(v):.3f} s, "
                  f"least {min(v):.3f}, largest {max(v):.3f} ({len(v)} rounds)")


if __name__ == "__main__":
    main()
