#!/usr/bin/env python3
"""Side-by-side timings of dense linear assignment solvers on the same matrices.

Compares pymodal.linear_sum_assignment (methods jv, hungarian, simplex) with
scipy.optimize.linear_sum_assignment, lap (gatagat) lapjv, lapx lapjvr / lapjvh and POT ot.emd,
and times pymodal's order-preserving solver (solver="ordered", rows and columns read as two closed
sequences: a constrained problem, whose total is not the others') beside them; the class
`contour` is the matrices it is for: two closed contours of n and 1.1 n nodes.

lap and lapx install the same import name `lap`, so they live in different venvs. The script
times the peers available in the interpreter that runs it and, with --other-python, runs itself in
a second interpreter (e.g. the lapx venv) for the peers only found there, then prints one merged
table. Matrices come from numpy's PCG64 with fixed seeds, so both interpreters see the same data.

Times are medians of CPU time (time.process_time) over --repeat runs; every solver is
single-threaded, and CPU time is less disturbed by other processes on a shared machine.

Example (the command behind the BENCHMARKS.md tables):
    python benches/python/bench_assign.py \
        --other-python LAPX_VENV/bin/python --sizes 1000 2000
"""

import argparse
import json
import statistics
import subprocess
import sys
import time

import numpy as np

CLASSES = ["uniform", "euclidean", "int1-100", "rect", "contour"]


def make_matrix(kind, n, seed=12345):
    rng = np.random.default_rng([seed, n, CLASSES.index(kind)])
    if kind == "uniform":
        return rng.random((n, n))
    if kind == "euclidean":
        p = rng.random((n, 2))
        q = rng.random((n, 2))
        d = p[:, None, :] - q[None, :, :]
        return np.sqrt((d * d).sum(axis=2))
    if kind == "int1-100":
        return rng.integers(1, 101, size=(n, n)).astype(np.float64)
    if kind == "rect":
        return rng.random((n, 2 * n))
    if kind == "contour":
        # Squared distance of the nodes' positions along two closed contours of n and 1.1 n nodes
        # (B's numbering started elsewhere), plus noise.
        m = n + n // 10
        s = (np.arange(n)[:, None] / n - ((np.arange(m) + rng.integers(m)) % m)[None, :] / m) % 1.0
        return np.minimum(s, 1.0 - s) ** 2 + 0.01 * rng.random((n, m))
    raise ValueError(kind)


def peers():
    """Solvers importable here: name -> callable(cost) -> (rows, cols) (or None if N/A)."""
    out = {}
    try:
        import pymodal

        for m in ["jv", "hungarian", "simplex", "ordered"]:
            out[f"pymodal-{m}"] = lambda c, m=m: pymodal.linear_sum_assignment(c, solver=m)
    except ImportError:
        pass
    try:
        from scipy.optimize import linear_sum_assignment

        out["scipy"] = linear_sum_assignment
    except ImportError:
        pass
    try:
        import lap

        def lap_lapjv(c):
            # (x, y) mapping arrays, -1 for unassigned; rectangular only through zero padding.
            x, _ = lap.lapjv(c, extend_cost=c.shape[0] != c.shape[1], return_cost=False)
            rows = np.flatnonzero(x >= 0)
            return rows, x[rows]

        if hasattr(lap, "lapjvr"):  # lapx
            out["lapx-lapjvr"] = lambda c: lap.lapjvr(c, extend_cost=True, return_cost=False)
            out["lapx-lapjvh"] = lambda c: lap.lapjvh(c, extend_cost=True, return_cost=False)
            out["lapx-lapjv"] = lap_lapjv
        else:  # gatagat/lap
            out["lap-lapjv"] = lap_lapjv
    except ImportError:
        pass
    try:
        import ot

        def emd(c):
            if c.shape[0] != c.shape[1]:
                return None  # not an assignment when the marginals differ
            n = c.shape[0]
            a = np.ones(n)
            plan = ot.emd(a, a, c, numItermax=10**9)
            rows, cols = np.nonzero(plan > 0.5)
            return rows, cols

        out["pot-emd"] = emd
    except ImportError:
        pass
    return out


def time_one(fn, cost, repeat):
    res = fn(cost)  # warm-up, and the answer to check
    if res is None:
        return None, None
    times = []
    for _ in range(repeat):
        t0 = time.process_time()
        fn(cost)
        times.append(time.process_time() - t0)
    rows, cols = res[0], res[1]
    return statistics.median(times), float(cost[np.asarray(rows), np.asarray(cols)].sum())


def run(names, sizes, classes, repeat, max_slow):
    avail = peers()
    results = []
    for kind in classes:
        for n in sizes:
            cost = make_matrix(kind, n)
            for name in names:
                if name not in avail:
                    continue
                # The order-preserving solver is O(n m (m - n + 1)): cubic on n x 2n matrices,
                # which are no pair of contours.
                if name == "pymodal-ordered" and kind == "rect":
                    continue
                # Skip solvers known to be hopeless at this size (e.g. O(n^3) with a big constant).
                if any(r["solver"] == name and r["class"] == kind and r.get("sec", 0) > max_slow for r in results):
                    continue
                sec, total = time_one(avail[name], cost, repeat)
                if sec is None:
                    continue
                results.append({"solver": name, "class": kind, "n": n, "shape": list(cost.shape), "sec": sec, "cost": total})
                print(f"  {name:16s} {kind:10s} {cost.shape[0]}x{cost.shape[1]}: {sec * 1e3:9.2f} ms", file=sys.stderr)
    return results


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", type=int, nargs="+", default=[1000, 2000])
    ap.add_argument("--classes", nargs="+", default=CLASSES, choices=CLASSES)
    ap.add_argument("--peers", nargs="+", default=None, help="solver names to run here (default: all available)")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--max-slow", type=float, default=20.0, help="skip larger n for a solver slower than this (s)")
    ap.add_argument("--other-python", default=None, help="interpreter of a second venv (e.g. with lapx)")
    ap.add_argument("--other-peers", nargs="+", default=None, help="solver names to run in --other-python (default: all)")
    ap.add_argument("--json", action="store_true", help="print raw results as JSON (used for merging)")
    args = ap.parse_args()

    names = args.peers or list(peers())
    results = []
    # One (class, size) at a time, the other interpreter's peers right after ours on the same
    # matrix: on a shared machine the load drifts, and interleaving keeps the comparison fair.
    for kind in args.classes:
        for n in args.sizes:
            # --max-slow across sizes: skip a solver already too slow on a smaller size.
            now = [s for s in names if not any(
                p["solver"] == s and p["class"] == kind and p["sec"] > args.max_slow for p in results)]
            results += run(now, [n], [kind], args.repeat, args.max_slow)
            if args.other_python:
                cmd = [args.other_python, __file__, "--json", "--sizes", str(n), "--classes", kind,
                       "--repeat", str(args.repeat), "--max-slow", str(args.max_slow)]
                if args.other_peers:
                    cmd += ["--peers", *args.other_peers]
                have = set(names)
                out = subprocess.run(cmd, check=True, stdout=subprocess.PIPE, text=True)
                results += [r for r in json.loads(out.stdout) if r["solver"] not in have]
    if args.json:
        print(json.dumps(results))
        return

    # Merged table: one row per (class, shape), ms per solver and ratio to scipy.
    solvers = []
    for r in results:
        if r["solver"] not in solvers:
            solvers.append(r["solver"])
    keys = []
    for r in results:
        k = (r["class"], tuple(r["shape"]))
        if k not in keys:
            keys.append(k)
    by = {(r["class"], tuple(r["shape"]), r["solver"]): r for r in results}
    print("CPU time, median of %d runs, ms (ratio to scipy in parentheses)\n" % args.repeat)
    print("| class | shape | " + " | ".join(solvers) + " |")
    print("|---|---|" + "---:|" * len(solvers))
    for cls, shape in keys:
        base = by.get((cls, shape, "scipy"))
        cells = []
        for s in solvers:
            r = by.get((cls, shape, s))
            if r is None:
                cells.append("–")
                continue
            ms = r["sec"] * 1e3
            cell = f"{ms:.3f}" if ms < 1 else f"{ms:.1f}"
            if base:
                cell += f" ({r['sec'] / base['sec']:.2f})"
            cells.append(cell)
        print(f"| {cls} | {shape[0]}×{shape[1]} | " + " | ".join(cells) + " |")
    # Optimal totals must agree.
    for cls, shape in keys:
        # The order-preserving solver's optimum is constrained: never below the others'.
        totals = {s: by[(cls, shape, s)]["cost"] for s in solvers
                  if (cls, shape, s) in by and s != "pymodal-ordered"}
        ref = totals.get("scipy", next(iter(totals.values())))
        bad = {s: t for s, t in totals.items() if abs(t - ref) > 1e-6 * max(1.0, abs(ref))}
        if bad:
            print(f"WARNING {cls} {shape}: totals differ from {ref}: {bad}")


if __name__ == "__main__":
    main()
