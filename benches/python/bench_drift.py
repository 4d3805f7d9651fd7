"""Track drift against ground truth: how far a track wanders from the material point it started on.

    python benches/python/bench_drift.py [--frames 120] [--drift-correction ...]

A synthetic walk (`pymodal.SyntheticWalk`: a foot-like pressure field translated towards the
toes, turned and widened at the forefoot, smoothly over the frames, with the true map from frame
0 to every frame known) is run through `pymodal.run` (contour model, default options). For every
node of frame 0's outline, its track is followed; after 25, 50 and 100 frames the distance from
the track's node to the true position of the node's material point is measured in node spacings.
A track that has ended by then counts as lost (not within). Beside pedomatch, on the same
outlines: chained nearest neighbour (each node goes to the nearest node of the next outline) and
chained CPD (pycpd deformable registration of each outline onto the next, each node going to its
most probable partner). Needs numpy, scipy and pycpd (`make bench-python` installs them).
"""

import argparse
import time

import numpy as np
from scipy.spatial import cKDTree

import pymodal

HORIZONS = (25, 50, 100)


def outlines_by_frame(result):
    """The outline (largest object, index 0) of every frame: {frame: (n, 2) points}."""
    return {o["frame"]: np.asarray(o["points"])[:, :2] for o in result["objects"] if o["index"] == 0}


def pedomatch_positions(result, n_frames):
    """Tracks that start on frame 0: their start points and, per frame, their node (NaN once ended)."""
    tracks = [t for t in result["tracks"] if len(t) and t[0, 0] == 0]
    pos = np.full((n_frames, len(tracks), 2), np.nan)
    for i, t in enumerate(tracks):
        frames = t[:, 0].astype(int)
        pos[frames, i] = t[:, 1:3]
    return pos


def nn_step(a, b):
    """For each node of a, the index of the nearest node of b."""
    return cKDTree(b).query(a)[1]


def cpd_step(a, b):
    """For each node of a, its most probable partner in b after pycpd's deformable registration."""
    from pycpd import DeformableRegistration

    reg = DeformableRegistration(X=b, Y=a)
    reg.register()
    return np.argmax(reg.P, axis=1)


def chained_positions(outlines, n_frames, step):
    """Chains `step` frame to frame from every node of frame 0 (NaN after a frame with no outline)."""
    start = outlines[0]
    pos = np.full((n_frames, len(start), 2), np.nan)
    idx = np.arange(len(start))
    pos[0] = start
    for t in range(n_frames - 1):
        if t not in outlines or t + 1 not in outlines:
            break
        idx = step(outlines[t], outlines[t + 1])[idx]
        pos[t + 1] = outlines[t + 1][idx]
    return pos


def scores(walk, pos, spacing):
    """Share of frame-0 tracks within one spacing of the truth, per horizon, and median error."""
    start = pos[0]
    out = {}
    for k in HORIZONS:
        if k >= len(pos):
            continue
        truth = walk.true_positions(k, start)
        err = np.linalg.norm(pos[k] - truth, axis=1) / spacing
        within = np.nan_to_num(err, nan=np.inf) <= 1.0
        out[k] = (within.mean(), np.nanmedian(err) if np.isfinite(err).any() else np.nan,
                  np.isfinite(err).mean())
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--frames", type=int, default=120)
    ap.add_argument("--spacing", type=float, default=1.0, help="contour node spacing (sensels)")
    ap.add_argument("--no-cpd", action="store_true", help="leave chained CPD out (slow)")
    ap.add_argument("--run-option", action="append", default=[], metavar="KEY=VALUE",
                    help="extra keyword for pymodal.run (repeatable), e.g. drift_reference=25")
    a = ap.parse_args()
    extra = {}
    for kv in a.run_option:
        k, v = kv.split("=", 1)
        extra[k] = int(v) if v.lstrip("-").isdigit() else (float(v) if v.replace(".", "", 1).isdigit() else v)

    walk = pymodal.SyntheticWalk(frames=a.frames)
    rec = walk.recording()
    t0 = time.perf_counter()
    result = pymodal.run(rec, spacing=a.spacing, **extra)
    t_run = time.perf_counter() - t0
    outlines = outlines_by_frame(result)
    n = a.frames
    rows = [("pedomatch" + (f" ({', '.join(a.run_option)})" if a.run_option else ""),
             pedomatch_positions(result, n), t_run)]
    t0 = time.perf_counter()
    rows.append(("chained nearest neighbour", chained_positions(outlines, n, nn_step),
                 time.perf_counter() - t0))
    if not a.no_cpd:
        t0 = time.perf_counter()
        rows.append(("chained CPD (pycpd deformable)", chained_positions(outlines, n, cpd_step),
                     time.perf_counter() - t0))

    print(f"synthetic walk: {n} frames, outline of {len(outlines.get(0, []))} nodes at "
          f"{a.spacing} sensel spacing; {len(result['tracks'])} pedomatch tracks in all")
    head = " | ".join(f"within 1 spacing after {k}" for k in HORIZONS if k < n)
    print(f"| method | tracks from frame 0 | {head} | median error after 50 (spacings) | alive after 50 | time (s) |")
    print("|---|---|" + "---|" * sum(k < n for k in HORIZONS) + "---|---|---|")
    for name, pos, secs in rows:
        s = scores(walk, pos, a.spacing)
        cells = " | ".join(f"{100 * s[k][0]:.1f} %" for k in HORIZONS if k in s)
        med, alive = (s[50][1], s[50][2]) if 50 in s else (np.nan, np.nan)
        print(f"| {name} | {pos.shape[1]} | {cells} | {med:.2f} | {100 * alive:.0f} % | {secs:.2f} |")


if __name__ == "__main__":
    main()
