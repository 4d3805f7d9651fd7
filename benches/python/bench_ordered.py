"""The order-preserving solver (solver="ordered") against Jonker-Volgenant (the default solver) on
the ground-truth contour pairs of bench_match.py: accuracy, crossed matches and time per pair.

Cases: bench_match.py's contour cases (real foot outlines warped by known smooth deformations,
48-72 points, n_b = n_a +- 6, random starts), seeds as its accuracy table (--seed, default 1) and
as its held-out pairs (seeds from 1000 on, every second case on a heel-strike outline), each with
the defaults and with the paper's literal setting (paper=True), whose matches cross more often.
Accuracy: mean / 5th percentile / worst pair of the fraction of A's points matched within one B
spacing of the truth. Crossings: mean crossed pairs of matches per pair (Match.crossings) and the
share of pairs with any. Time: median wall time per pair of pymodal.match, and the ratio of the
ordered solver's to JV's.

Run:  python benches/python/bench_ordered.py [--cases 30] [--seed 1] [--markdown]
"""
import argparse
import time

import numpy as np

from bench_match import SEVERITY, contour_case, outlines, score


def cases(kind, sev, n, seed):
    outs = outlines()
    if kind == "tuning":
        rng = np.random.default_rng(seed)
        return [contour_case(outs[k % len(outs)], sev, rng) for k in range(n)]
    heels = outlines("heel_strike.txt")
    rng = np.random.default_rng(1000 + seed)
    pick = lambda k: (heels if k % 2 else outs)[k // 2 % len(heels if k % 2 else outs)]
    return [contour_case(pick(k), sev, rng) for k in range(n)]


def measure(pairs_of_cases, **kw):
    import pymodal

    accs, crossings, times = [], [], []
    for a, b, truth, tol in pairs_of_cases:
        t0 = time.perf_counter()
        m = pymodal.match(a, b, **kw)
        times.append(time.perf_counter() - t0)
        accs.append(score(m.pairs, m.excess, b, truth, tol))
        crossings.append(m.crossings)
    accs, crossings = np.array(accs), np.array(crossings)
    return dict(mean=accs.mean(), p5=np.percentile(accs, 5), worst=accs.min(),
                crossings=crossings.mean(), crossed=(crossings > 0).mean(),
                ms=np.median(times) * 1e3)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cases", type=int, default=30)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--markdown", action="store_true")
    args = ap.parse_args()
    import pymodal

    warm = cases("tuning", "mild", 1, args.seed)[0]
    for solver in ("jv", "ordered"):
        pymodal.match(warm[0], warm[1], solver=solver)
    head = ("| pairs | setting | severity | solver | accuracy mean / 5th pct / worst | crossings per pair "
            "| pairs with crossings | ms/pair (median) | time vs JV |")
    print(head if args.markdown else head.replace("|", " "))
    if args.markdown:
        print("|---|---|---|---|---|---:|---:|---:|---:|")
    for kind in ("tuning", "held-out"):
        for setting, kw in (("defaults", {}), ("paper=True", {"paper": True})):
            for sev in SEVERITY:
                cs = cases(kind, sev, args.cases, args.seed)
                rows = {s: measure(cs, solver=s, **kw) for s in ("jv", "ordered")}
                for s, r in rows.items():
                    ratio = r["ms"] / rows["jv"]["ms"]
                    print(f"| {kind} | {setting} | {sev} | {s} | {r['mean']:.3f} / {r['p5']:.3f} / "
                          f"{r['worst']:.3f} | {r['crossings']:.1f} | {100 * r['crossed']:.0f} % | "
                          f"{r['ms']:.2f} | {ratio:.2f} |", flush=True)


if __name__ == "__main__":
    main()
