"""User points carried backwards through a stance: points given mid-stance, ground truth known.

    python benches/python/bench_points_back.py PEDOMATCH [--frames 201] [--seed-frame 100]

On the synthetic stances of ``stance.py`` (roll-over from heel to toes, rotation, spreading and
a bend), every sensel centre at least 1.5 sensels inside frame ``--seed-frame``'s contact region
is given to ``PEDOMATCH run --points`` on that frame (defaults otherwise; tables only). The
run's ``points.csv`` rows of kind ``user`` are compared with each point's true position on
every frame (the known map, ``Stance.true_positions`` after ``reference_positions``): the share
within one sensel of the truth 25, 50 and 100 frames before the seed frame (the backward part)
and, beside it in the same run, 25, 50 and 100 frames after (the forward part, as before). A
point not carried to a frame counts as lost. Laws 0-1 with seeds 0-1 are the tuning stances,
laws 2-3 with seeds 2-3 the held-out ones, reported separately (mean and worst over stances).
Needs numpy; the binary is any ``pedomatch`` (e.g. ``target/release/pedomatch``).
"""

import argparse
import os
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from stance import GROUPS, Stance, run_with_points  # noqa: E402

HORIZONS = (25, 50, 100)


def seed_points(st, f):
    """Sensel centres at least 1.5 sensels inside frame f's contact region: (n, 2) x, y."""
    xy = st.pixel_centres()
    inside = st.signed_distance(st.reference_positions(f, xy)) > 1.5
    return xy[inside]


def run_case(binary, st, f, tmp):
    pts = seed_points(st, f)
    pos = np.full((st.n_frames, len(pts), 2), np.nan)
    for row in run_with_points(binary, st, pts, f, tmp):
        if row["kind"] != "user":
            continue
        pos[int(row["frame"]), int(row["name"][1:])] = float(row["x"]), float(row["y"])
    material = st.reference_positions(f, pts)
    shares = {}
    for h in HORIZONS:
        for sign in (-1, 1):
            t = f + sign * h
            if not 0 <= t < st.n_frames:
                continue
            truth = st.true_positions(t, material)
            err = np.hypot(*(pos[t] - truth).T)
            shares[sign * h] = float(np.mean(np.nan_to_num(err, nan=np.inf) <= 1.0))
    return len(pts), shares


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("pedomatch")
    ap.add_argument("--frames", type=int, default=201)
    ap.add_argument("--seed-frame", type=int, default=100)
    args = ap.parse_args()
    cols = [-h for h in reversed(HORIZONS)] + list(HORIZONS)
    print("| stances | points | " + " | ".join(
        f"{'back' if c < 0 else 'forward'} {abs(c)}" for c in cols) + " |")
    print("|---" * (2 + len(cols)) + "|")
    for group, cases in GROUPS.items():
        rows = []
        n = 0
        for law, seed in cases:
            st = Stance(law=law, seed=seed, frames=args.frames)
            with tempfile.TemporaryDirectory() as tmp:
                k, shares = run_case(args.pedomatch, st, args.seed_frame, tmp)
            n += k
            rows.append(shares)
            print(f"  law {law} seed {seed}: {k} points, " + ", ".join(
                f"{c:+d}: {100 * shares.get(c, np.nan):.0f} %" for c in cols), file=sys.stderr)
        cells = []
        for c in cols:
            v = np.array([r.get(c, np.nan) for r in rows])
            cells.append(f"{100 * np.nanmean(v):.0f} % / {100 * np.nanmin(v):.0f} %")
        print(f"| {group} | {n} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
