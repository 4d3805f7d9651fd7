"""Material points at every frame of the synthetic stances: the default run's outline points
and its followed region against ground truth, frame by frame rather than at four horizons.

    python benches/python/bench_points_frames.py [--held-out | --extra-tuning] [--label NAME]

The cases, the run and the truth are those of ``bench_field.py`` (beside this file): laws 0-1
with seeds 0-1 are the tuning cases, laws 2-3 with seeds 2-3 (``--held-out``) the held-out ones;
each is run as ``pymodal.run(frames, pitch_mm=5, frame_rate=200, units="kPa", regions=mask)``
with the forefoot third as the mask and frame 0's contact sensel centres (every sensel with
pressure above 0, ``bench_field.py``'s interior points) as user points on frame 0
(``points=``, ``points_frame=0``; they change neither the outline's points nor the region).
``--extra-tuning`` runs laws 2-3 with seeds 0-1, part of neither group: the held-out laws'
motions (the tremor) to diagnose on while the held-out cases stay unseen. Printed, over the 4
cases (Markdown rows, labelled with ``--label``; run it once per build to compare builds side by
side):

- frame 0's outline nodes within one node spacing of their material point after 25 / 50 / 100 /
  150 frames: mean / 5th percentile / worst case, %;
- the same share on every frame: its mean over frames and cases, the worst frame of any case,
  and the share of frames at 90 % or more;
- the *swing*: the mean absolute change of that share between frames 5 apart (25 ms), in points
  of %: how much a point's agreement with the truth flickers from frame to frame;
- the region carried by the run: its relative force error on every frame of every case, worst /
  95th percentile, and the share of frames within 5 %;
- seconds per run (mean);
- a second row: the interior points within one sensel of their material point, the same
  horizons, every-frame figures and swing.
"""
import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_field as bf  # noqa: E402
import pymodal  # noqa: E402
from stance import Stance  # noqa: E402

FRAMES = 150


def interior_points(frames):
    """Frame 0's contact sensel centres (pressure > 0), x = column, y = row (``bench_field.py``'s
    interior points)."""
    return np.argwhere(frames[0] > 0)[:, ::-1].astype(float)


def interior_positions(res, n, T):
    """The user points (given in order on frame 0) at every frame: (T, n, 2), NaN once ended."""
    pos = np.full((T, n, 2), np.nan)
    user = [p for p, name in zip(res["points"], res["point_names"]) if name is not None]
    for k, pts in enumerate(user[:n]):
        pos[pts[:, 0].astype(int), k] = pts[:, 1:3]
    return pos


def one_case(spec):
    st = Stance(frames=FRAMES + 1, **spec)
    frames = st.frames
    T = len(frames)
    mask, y_cut = bf.region_mask(frames)
    _, _, true_force = bf.region_setup(st, frames, y_cut)
    interior = interior_points(frames)
    t0 = time.perf_counter()
    res = pymodal.run(frames, pitch_mm=bf.PITCH_MM, frame_rate=bf.FRAME_RATE, units="kPa", regions=mask,
                      points=interior, points_frame=0)
    secs = time.perf_counter() - t0
    obj0 = bf.outline_objects(res)[0]
    nodes0 = np.asarray(obj0["points"])[:, :2]
    truth = np.array([st.true_positions(t, nodes0) for t in range(T)])
    spacing = float(res["summary"]["options"]["spacing"])
    pos = bf.pedomatch_point_positions(res, obj0, T)
    err = np.nan_to_num(np.linalg.norm(pos - truth, axis=2), nan=np.inf)
    share = 100.0 * np.mean(err <= spacing, axis=1)
    force = bf.regions_forces(res, "moving", T)
    ferr = 100.0 * np.abs(force - true_force) / true_force
    truth_int = np.array([st.true_positions(t, interior) for t in range(T)])
    ipos = interior_positions(res, len(interior), T)
    ierr = np.nan_to_num(np.linalg.norm(ipos - truth_int, axis=2), nan=np.inf)
    ishare = 100.0 * np.mean(ierr <= 1.0, axis=1)
    return share, ferr, secs, ishare


# Laws 2-3 with seeds 0-1: neither tuning nor held out. Used to diagnose and tune the follower on
# the motions of the held-out laws (the tremor's fast small turns) without their held-out seeds.
EXTRA_TUNING = [dict(law=law, seed=seed) for law in (2, 3) for seed in (0, 1)]


def row(group, label, sh, cells_extra):
    cells = [f"{sh[:, h].mean():.1f} / {np.percentile(sh[:, h], 5):.1f} / {sh[:, h].min():.1f}"
             for h in bf.HORIZONS]
    swing = np.mean(np.abs(sh[:, 5:] - sh[:, :-5]))
    return (f"| {group} | {label} | " + " | ".join(cells)
            + f" | {sh.mean():.1f} | {sh.min():.1f} | {100 * np.mean(sh >= 90):.1f} | {swing:.2f}"
            + cells_extra + " |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    which = ap.add_mutually_exclusive_group()
    which.add_argument("--held-out", action="store_true", help="the held-out cases (laws 2-3, seeds 2-3)")
    which.add_argument("--extra-tuning", action="store_true",
                       help="laws 2-3 with seeds 0-1 (neither tuning nor held out)")
    ap.add_argument("--label", default="pedomatch points (defaults)")
    a = ap.parse_args()
    group = "held out" if a.held_out else "extra tuning" if a.extra_tuning else "tuning"
    specs = EXTRA_TUNING if a.extra_tuning else bf.GROUPS[group]
    shares, ferrs, secs, ishares = [], [], [], []
    for spec in specs:
        s, f, t, i = one_case(spec)
        shares.append(s)
        ferrs.append(f)
        secs.append(t)
        ishares.append(i)
        print(f"law {spec['law']} seed {spec['seed']}: points on every frame {s.mean():.1f} "
              f"(worst frame {s.min():.1f}); interior {i.mean():.1f} (worst frame {i.min():.1f}); "
              f"region worst {np.nanmax(f):.2f} %, {t:.1f} s", file=sys.stderr)
    sh = np.array(shares)
    fe = np.concatenate(ferrs)
    print(f"| cases | row | after {' | after '.join(map(str, bf.HORIZONS))} | every frame: mean | worst | "
          "frames ≥ 90 % | swing | region: worst | 95th pct | frames within 5 % | s per run |")
    print("|---|---|" + "---:|" * 12)
    print(row(group, a.label, sh,
              f" | {np.nanmax(fe):.2f} | {np.nanpercentile(fe, 95):.2f} | {100 * np.mean(fe <= 5):.1f}"
              f" | {np.mean(secs):.1f}"))
    print(row(group, a.label + ": interior points", np.array(ishares), " | | | | "))


if __name__ == "__main__":
    main()
