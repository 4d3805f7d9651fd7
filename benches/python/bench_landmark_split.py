"""Where a landmark pair's time goes with the defaults: pymodal.match on the landmark benchmark's
pairs (bench_landmarks.py's outlines, split and pairs) under settings that stop after each stage
of a drifted pair, timed in rounds that alternate the settings.

Rows (median ms per pair over all pairs, over the pairs the gate drifts and over the others):
  defaults                        the whole pair (rotation search, gate, then the drift or the
                                  modal match)
  refine=affine                   the rotation search and the modal match (no gate)
  rotation search, positions      the rotation search and one pass on positions (no modal solve)
  normalize start                 the drift's start alone: centroid and scale, affine re-fits on
                                  positions
  normalize start, drift          the start and the drift, with its ordered assignment
So a drifted pair costs about "rotation search" + "normalize start, drift".

With --ordered, also the order-preserving solver alone (pymodal.linear_sum_assignment,
solver="ordered"), which assigns a drifted pair's moved nodes: on each pair's squared distances
between the two outlines, each centred and scaled to unit RMS radius (the pairs' own unequal
counts, 100-185 nodes), median ms per solve.

Run:  python benches/python/bench_landmark_split.py --data DIR [--halves tuning] [--rounds 3]
          [--ordered]
"""
import argparse
import os
import time

for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(var, "1")

import numpy as np

import bench_landmarks as bl
import pymodal

SETTINGS = {
    "defaults": {},
    "refine=affine": dict(refine="affine"),
    "rotation search, positions": dict(refine="affine", position_weight=1),
    "normalize start": dict(prealign="normalize", position_weight=1),
    "normalize start, drift": dict(prealign="normalize", position_weight=1, refine="coherent"),
}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", default=os.environ.get("LANDMARK_DATA"))
    ap.add_argument("--halves", default="tuning")
    ap.add_argument("--pairs", type=int, default=12)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--ordered", action="store_true", help="also time the ordered solver alone")
    args = ap.parse_args()
    if not args.data:
        print("bench_landmark_split skipped: give --data DIR (or set LANDMARK_DATA)")
        return
    rng = np.random.default_rng(1)
    outlines = [bl.Outline(c, s, p, l, rng) for c, s, p, l in bl.load(args.data)]
    for half in args.halves.split(","):
        pairs = bl.cases(outlines, half, args.pairs, seed=2 if half == "tuning" else 3)
        drifted = np.array([pymodal.match(a.pts, b.pts).drifted for a, b in pairs])
        print(f"\n{half}: {len(pairs)} pairs, {drifted.sum()} drifted by the gate\n")
        times = {name: [] for name in SETTINGS}
        for _ in range(args.rounds):
            for name, kw in SETTINGS.items():
                t = []
                for a, b in pairs:
                    t0 = time.perf_counter()
                    pymodal.match(a.pts, b.pts, **kw)
                    t.append(time.perf_counter() - t0)
                times[name].append(np.array(t) * 1e3)
        print("| setting | all pairs | drifted pairs | the others |")
        print("|---|---:|---:|---:|")
        for name, runs in times.items():
            cells = [
                " / ".join(f"{np.median(t[sel]):.2f}" for t in runs)
                for sel in (slice(None), drifted, ~drifted)
            ]
            print(f"| {name} | " + " | ".join(cells) + " |")
        if args.ordered:
            costs = []
            for a, b in pairs:
                na, nb = bl.normalise(a.pts)[0], bl.normalise(b.pts)[0]
                costs.append(((na[:, None] - nb[None]) ** 2).sum(2))
            runs = []
            for _ in range(args.rounds):
                t = []
                for c in costs:
                    t0 = time.perf_counter()
                    pymodal.linear_sum_assignment(c, solver="ordered")
                    t.append(time.perf_counter() - t0)
                runs.append(np.median(t) * 1e3)
            print("\nordered solver alone, median ms per solve: " + " / ".join(f"{r:.2f}" for r in runs))


if __name__ == "__main__":
    main()
