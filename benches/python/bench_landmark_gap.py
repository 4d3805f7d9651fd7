"""Where the defaults lose landmarks to BCPD on bench_landmarks.py's pairs (its tuning half by
default): the pairs the defaults drift against the pairs their gates leave to the modal match,
and what carries the latter better.

The defaults decide per pair of outlines (docs/method.md §7.5). First gate: two outlines that the
rotation search's affine fit leaves more than 0.6 of B's spacings apart are two specimens of a
shape and are drifted from the centroid-and-scale start (the pose as given). Second gate: of the
others, those whose modal match pairs nodes at a median cost over 0.15 are drifted too; the rest
keep the modal match (`Match.drifted` says which). The rows:

  all pairs   - the first gate alone, one way: A's drift from the pose as given
                (prealign="normalize", position_weight=1, refine="coherent") where the first gate
                drifts, else the modal match (`refine="affine"`): the defaults before the second
                gate; both gates, one way; the defaults (both gates, images both ways:
                `Match.outline_images`);
              - BCPD on the pairs the first gate drifts, the modal match on the others;
              - BCPD on every pair.
  under the first gate (the pairs it does not drift)
              - the modal match; the defaults; BCPD; A's drift from the pose as given;
              - the similarity closest to the modal match's map of A (its turn and scale, no
                stretch), then pymodal.match from there (prealign="sensor": no further search),
                and the same drifted (refine="coherent", one way).

With --thresholds T1,T2,... it instead measures the second gate (docs/method.md §7.5) at each
threshold: a pair is drifted when the first gate drifts it (`pymodal.match` with the second gate
off, `cost_power=0.999`: the first gate reads only the rotation search) or when the median cost of
its modal match (`refine="affine"`) exceeds T; otherwise it keeps the modal match. With --signal it
prints that median cost's quantiles on the landmark pairs the first gate leaves and on
bench_match.py's synthetic tuning pairs (seeds 1-6 on the foot outlines, 1-3 on the heel strikes,
30 pairs per seed and severity), and how many of either the defaults drift.

Run:  BCPD_BIN=/path/to/bcpd python benches/python/bench_landmark_gap.py --data DIR [--half tuning]
      python benches/python/bench_landmark_gap.py --data DIR --thresholds 0.12,0.15,0.2
      python benches/python/bench_landmark_gap.py --data DIR --signal
(BCPD's rows are left out, saying so, without BCPD_BIN.)
"""
import argparse
import os
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_landmarks as bl  # noqa: E402

SECOND_GATE = 0.15  # the crate's threshold on the modal match's median pair cost


def image_errors(a, b, m):
    """The landmark errors of the match `m` of A onto B, carried by its outline images."""
    return bl.errors(b, bl.carry(a, b, bl.image_arcs(m, b)))


def closest_similarity(a_pts, aligned):
    """The map y = M x + t with M a turn times a scale closest to the affine map of `a_pts` onto
    `aligned` (its polar turn, the mean of its stretches)."""
    h = np.c_[a_pts, np.ones(len(a_pts))]
    sol = np.linalg.lstsq(h, aligned, rcond=None)[0]
    u, s, vt = np.linalg.svd(sol[:2].T)
    m = s.mean() * (u @ vt)
    return m, aligned.mean(0) - a_pts.mean(0) @ m.T


def main():
    import pymodal

    ap = argparse.ArgumentParser()
    ap.add_argument("--data", default=os.environ.get("LANDMARK_DATA"))
    ap.add_argument("--half", default="tuning")
    ap.add_argument("--pairs", type=int, default=12)
    ap.add_argument("--thresholds", default="", help="comma-separated second-gate thresholds to measure")
    ap.add_argument("--signal", action="store_true", help="the second gate's signal on both benchmarks")
    args = ap.parse_args()
    if not args.data:
        print("bench_landmark_gap skipped: give --data DIR (see bench_landmarks.py)")
        return
    binary = os.environ.get("BCPD_BIN")
    bcpd = bl.bcpd(binary) if binary and Path(binary).is_file() else None
    if bcpd is None:
        print("BCPD skipped: set BCPD_BIN to the bcpd binary")

    rng = np.random.default_rng(1)
    outlines = [bl.Outline(c, s, p, l, rng) for c, s, p, l in bl.load(args.data)]
    pairs = bl.cases(outlines, args.half, args.pairs, seed=2 if args.half == "tuning" else 3)
    if args.thresholds:
        return thresholds(pairs, [float(t) for t in args.thresholds.split(",")], args.half)
    if args.signal:
        return signal(pairs, args.half)
    every, under = {}, {}
    for a, b in pairs:
        m = pymodal.match(a.pts, b.pts)
        first = pymodal.match(a.pts, b.pts, cost_power=0.999).drifted  # the first gate alone
        modal = pymodal.match(a.pts, b.pts, refine="affine")
        gated = first or np.median(np.asarray(modal.costs)) > SECOND_GATE
        given = drift_from_the_given_pose(a.pts, b.pts)
        e_given = image_errors(a, b, given)
        e_modal = image_errors(a, b, modal)
        e = image_errors(a, b, m)
        every.setdefault("the first gate alone, one way (A's drift or the modal match)", []).append(
            e_given if first else e_modal)
        every.setdefault("both gates, one way", []).append(e_given if gated else e_modal)
        every.setdefault("the defaults (both gates, both ways)", []).append(e)
        if bcpd:
            eb = bl.errors(b, bcpd(a, b))
            every.setdefault("BCPD on the pairs the first gate drifts, the modal match on the others",
                             []).append(eb if first else e_modal)
            every.setdefault("BCPD on every pair", []).append(eb)
        if first:
            continue
        under.setdefault("the modal match (the first gate alone)", []).append(e_modal)
        under.setdefault("the defaults (both gates, both ways)", []).append(e)
        if bcpd:
            under.setdefault("BCPD", []).append(eb)
        under.setdefault("A's drift from the pose as given (one way)", []).append(e_given)
        turn, shift = closest_similarity(a.pts, np.asarray(modal.aligned_a))
        a_turned = a.pts @ turn.T + shift
        for name, kw in (("the modal match's turn and scale, matched again", {}),
                         ("the modal match's turn and scale, drifted (one way)", {"refine": "coherent"})):
            again = pymodal.match(a_turned, b.pts, prealign="sensor", **kw)
            under.setdefault(name, []).append(image_errors(a, b, again))

    table(f"{args.half}: all {len(pairs)} pairs", every)
    table(f"{args.half}: the {len(next(iter(under.values())))} pairs the first gate does not drift", under)


def table(title, rows):
    n = sum(len(e) for e in rows[next(iter(rows))])
    print(f"\n**{title}, {n} landmarks, error in B's point spacings**\n")
    print("| method | within 1 | within 2 | within 5 | median | 90th pct |")
    print("|---|---|---|---|---|---|")
    for name, errs in rows.items():
        r = bl.summarise(errs, [0.0])
        print(f"| {name} | {r['w1']:.3f} | {r['w2']:.3f} | {r['w5']:.3f} | {r['med']:.2f} | {r['p90']:.2f} |")


def drift_from_the_given_pose(a, b):
    import pymodal

    return pymodal.match(a, b, prealign="normalize", position_weight=1, refine="coherent")


def thresholds(pairs, ts, half):
    """Landmark shares with the second gate at each threshold in `ts` (None: the first gate alone),
    beside the defaults as built."""
    import pymodal

    rows = {"the defaults (as built: images both ways)": []}
    drifted = dict.fromkeys([None] + ts, 0)
    for a, b in pairs:
        rows["the defaults (as built: images both ways)"].append(image_errors(a, b, pymodal.match(a.pts, b.pts)))
        first = pymodal.match(a.pts, b.pts, cost_power=0.999).drifted
        modal = pymodal.match(a.pts, b.pts, refine="affine")
        cost = np.median(np.asarray(modal.costs))
        drift = None
        for t in [None] + ts:
            name = "first gate alone, one way" if t is None else f"second gate at {t}, one way"
            if first or (t is not None and cost > t):
                if drift is None:
                    drift = image_errors(a, b, drift_from_the_given_pose(a.pts, b.pts))
                rows.setdefault(name, []).append(drift)
                drifted[t] += 1
            else:
                rows.setdefault(name, []).append(image_errors(a, b, modal))
    table(f"{half}: {len(pairs)} pairs, the second gate's threshold", rows)
    print("\npairs drifted: " + ", ".join(
        f"{'first gate alone' if t is None else t}: {k}" for t, k in drifted.items()))


def signal(pairs, half):
    """The second gate's signal: the median cost of the modal match's pairs, on the landmark
    pairs the first gate leaves and on the synthetic tuning pairs."""
    import bench_match as bm
    import pymodal

    q = (0, 5, 25, 50, 75, 95, 99, 100)
    landmark, lm_drifted = [], 0
    for a, b in pairs:
        if not pymodal.match(a.pts, b.pts, cost_power=0.999).drifted:
            landmark.append(np.median(np.asarray(pymodal.match(a.pts, b.pts, refine="affine").costs)))
            lm_drifted += pymodal.match(a.pts, b.pts).drifted
    print(f"\nquantiles {q} of the median modal cost, and pairs the defaults drift\n")
    print("| pairs | count | quantiles | drifted by the defaults |")
    print("|---|---|---|---|")
    print(f"| landmark, {half}, under the first gate | {len(landmark)} | "
          f"{' / '.join(f'{v:.3f}' for v in np.percentile(landmark, q))} | {lm_drifted} |")
    for name, seeds in (("contours.txt", range(1, 7)), ("heel_strike.txt", range(1, 4))):
        outs = bm.outlines(name)
        for sev in ("mild", "moderate", "severe"):
            costs, drifted = [], 0
            for seed in seeds:
                rng = np.random.default_rng(seed)
                for k in range(30):
                    a, b, _, _ = bm.contour_case(outs[k % len(outs)], sev, rng)
                    costs.append(np.median(np.asarray(pymodal.match(a, b, refine="affine").costs)))
                    drifted += pymodal.match(a, b).drifted
            print(f"| synthetic {name} {sev} | {len(costs)} | "
                  f"{' / '.join(f'{v:.3f}' for v in np.percentile(costs, q))} | {drifted} |")


if __name__ == "__main__":
    main()
