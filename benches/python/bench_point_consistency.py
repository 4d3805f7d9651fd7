"""Each material point's round trip (points.csv's round_trip_sensels) against its true error.

    python benches/python/bench_point_consistency.py PEDOMATCH [--frames 151] [--threshold 0.5 ...]
        [--group tuning|held-out]

On the synthetic stances of ``stance.py`` (roll-over from heel to toes, rotation, spreading and
a bend; ground truth known), runs ``PEDOMATCH run`` (defaults, tables only) with every sensel
centre at least 1.5 sensels inside frame 0's contact region given as ``--points`` on frame 0, and
reads ``points.csv``: the user's interior points and the outline points seeded on frame 0, each
row with the point's position and its round trip. Per row (point and frame with a round trip):

- the **true error**: the distance from the point to its material point's true position;
- the **step error**: how far the point's step from the frame before misses the true step (the
  error that step adds), what a per-step figure can see at best;
- the round trip, and its running largest along the point so far (``running max``);
- the frame (the time since the point was seeded): the baseline a figure that only grows with
  time would reach, since the true error grows along the stance too.

Printed per group of stances (laws 0-1 with seeds 0-1 are the tuning stances; laws 2-3 with
seeds 2-3 the held-out ones, on which nothing was chosen): Spearman's rank correlation of each
figure with each error, the median true error of the rows whose figure is above ``--threshold``
(sensels; chosen on the tuning stances) and of those below it, the share of rows above it, and
the share of rows over one sensel from the truth among each. Needs numpy (Spearman by ranks).
"""

import argparse
import csv
import os
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from stance import Stance  # noqa: E402

GROUPS = {"tuning (laws 0-1, seeds 0-1)": [(0, 0), (0, 1), (1, 0), (1, 1)],
          "held-out (laws 2-3, seeds 2-3)": [(2, 2), (2, 3), (3, 2), (3, 3)]}


def ranks(v):
    order = np.argsort(v, kind="stable")
    r = np.empty(len(v))
    r[order] = np.arange(len(v))
    # Ties share their mean rank.
    _, inv, counts = np.unique(v, return_inverse=True, return_counts=True)
    sums = np.bincount(inv, weights=r)
    return sums[inv] / counts[inv]


def spearman(x, y):
    return float(np.corrcoef(ranks(x), ranks(y))[0, 1])


def run_case(binary, st, tmp):
    rec = os.path.join(tmp, "stance.npy")
    np.save(rec, st.frames)
    xy = st.pixel_centres()
    pts = xy[st.signed_distance(xy) > 1.5]  # frame 0 is the material frame
    with open(os.path.join(tmp, "points.csv"), "w") as fh:
        fh.write("name,x,y,frame\n")
        for k, (x, y) in enumerate(pts):
            fh.write(f"q{k},{x},{y},0\n")
    out = os.path.join(tmp, "out")
    subprocess.run([binary, "run", rec, "--out", out, "--points", os.path.join(tmp, "points.csv"),
                    "--pitch-mm", str(st.pitch_mm), "--frame-rate", str(st.frame_rate),
                    "--units", "kPa", "--figures", "none", "--report", "none"],
                   check=True, stdout=subprocess.DEVNULL)
    tracks = {}
    with open(os.path.join(out, "points.csv")) as fh:
        for row in csv.DictReader(fh):
            trip = float(row["round_trip_sensels"]) if row["round_trip_sensels"] else np.nan
            tracks.setdefault(row["point"], []).append(
                (int(row["frame"]), float(row["x"]), float(row["y"]), trip))
    rows = []  # per row: true error, step error, round trip, running max, frame
    for steps in tracks.values():
        steps = np.array(steps)
        if steps[0, 0] != 0:
            continue  # only the points seeded on frame 0 have a known material point
        material = steps[0, 1:3]
        truth = np.array([st.true_positions(int(t), material[None])[0] for t in steps[:, 0]])
        err = np.hypot(*(steps[:, 1:3] - truth).T)
        step_err = np.r_[np.nan, np.hypot(*(np.diff(steps[:, 1:3], axis=0)
                                             - np.diff(truth, axis=0)).T)]
        trip = steps[:, 3]
        running = np.fmax.accumulate(np.nan_to_num(trip, nan=0.0))
        ok = np.isfinite(trip)
        rows.append(np.stack([err, step_err, trip, running, steps[:, 0]], axis=1)[ok])
    return np.concatenate(rows)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("pedomatch")
    ap.add_argument("--frames", type=int, default=151)
    ap.add_argument("--threshold", type=float, nargs="+", default=[0.5],
                    help="one or more thresholds (sensels): a table row per threshold")
    ap.add_argument("--group", choices=["tuning", "held-out"], help="one group only")
    args = ap.parse_args()
    print("| stances | rows | Spearman: round trip vs true error / vs step error | running max vs "
          "true error | frame vs true error | threshold t (sensels) | median true error, round trip > t / <= t | rows > t | "
          "over 1 sensel from the truth, round trip > t / <= t |")
    print("|---|---:|---|---|---|---:|---|---:|---|")
    for group, cases in GROUPS.items():
        if args.group and not group.startswith(args.group):
            continue
        th = args.threshold[0]
        per = []
        for law, seed in cases:
            st = Stance(law=law, seed=seed, frames=args.frames)
            with tempfile.TemporaryDirectory() as tmp:
                r = run_case(args.pedomatch, st, tmp)
            err, step_err, trip, running, _ = r.T
            hi = trip > th
            per.append(r)
            print(f"  law {law} seed {seed}: {len(r)} rows, rho(trip, err) "
                  f"{spearman(trip, err):.2f}, rho(trip, step) {spearman(trip, step_err):.2f}, "
                  f"rho(running, err) {spearman(running, err):.2f}; median err "
                  f"{np.median(err[hi]) if hi.any() else np.nan:.2f} / {np.median(err[~hi]):.2f}, "
                  f"{100 * hi.mean():.1f} % above", file=sys.stderr)
        r = np.concatenate(per)
        err, step_err, trip, running, frame = r.T
        med = lambda v: f"{np.median(v):.2f}" if len(v) else "-"
        share = lambda v: f"{100 * np.mean(v > 1.0):.0f} %" if len(v) else "-"
        rho = f"{spearman(trip, err):.2f} / {spearman(trip, step_err):.2f}"
        for th in args.threshold:
            hi = trip > th
            print(f"| {group} | {len(r)} | {rho} | {spearman(running, err):.2f} "
                  f"| {spearman(frame, err):.2f} | {th} "
                  f"| {med(err[hi])} / {med(err[~hi])} | {100 * hi.mean():.1f} % "
                  f"| {share(err[hi])} / {share(err[~hi])} |")


if __name__ == "__main__":
    main()
