"""Speed of pymodal.match relative to coherent point drift, timed case by case.

bench_match.py times each method over all cases back to back. Here every case is matched by each
method in turn, so the ratios are per case and share the machine's state, and pymodal meets the
cold thread pool a call meets after other work. Also times pymodal back to back and after a pause,
which shows what waking rayon's idle worker costs on this machine.

With --surface-cases N it also times N surface pairs per severity (two independent samplings of
the loaded region of the MUN104 template, as in bench_match.py, on seeds bench_match.py does not
use) and prints each method's one-to-one accuracy beside its time.

Run:  python benches/python/bench_speed_ratio.py [--cases 30] [--pause-ms 15] [--surface-cases 10]
"""
import argparse
import os
import time

# OpenBLAS's worker threads spin for a while after each call of pycpd's; on two cores they then
# take half of the core pymodal runs on (a surface pair took 23 ms instead of 12). One BLAS
# thread keeps the peers' own times within 10 % and stops them slowing the next method down.
for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(var, "1")

import numpy as np

import pymodal
from bench_match import DATA, SEVERITY, contour_case, cpd, outlines, score, surface_case


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cases", type=int, default=30, help="contour cases per severity")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--pause-ms", type=float, default=15.0)
    ap.add_argument("--surface-cases", type=int, default=0, help="surface cases per severity")
    ap.add_argument("--surface-option", action="append", default=[], metavar="KEY=VALUE",
                    help="an extra pymodal.match option for a third surface row (repeatable)")
    args = ap.parse_args()
    if args.surface_cases:
        surfaces(args)
    if args.cases == 0:
        return
    outs = outlines()
    cases = []
    for sev in SEVERITY:
        rng = np.random.default_rng(args.seed)
        cases += [contour_case(outs[k % len(outs)], sev, rng) for k in range(args.cases)]
    peers = {
        "pycpd rigid, affine, then deformable": cpd("rigid", "affine"),
        "pycpd rigid, then deformable": cpd("rigid"),
        "pycpd deformable": cpd(),
    }
    # The re-fits of the earlier default (two closed outlines now have none) for comparison.
    ours = {"pymodal.match defaults": {}, "pymodal.match refits=2": {"refits": 2}}
    pymodal.match(cases[0][0], cases[0][1])
    t = {k: [] for k in list(peers) + list(ours)}
    for case, (a, b, *_) in enumerate(cases):
        for k, f in peers.items():
            t0 = time.perf_counter()
            f(a, b)
            t[k].append(time.perf_counter() - t0)
        # The first call after CPD meets an idle thread pool: the order alternates by case.
        order = list(ours.items())
        for k, kw in order if case % 2 == 0 else order[::-1]:
            t0 = time.perf_counter()
            pymodal.match(a, b, **kw)
            t[k].append(time.perf_counter() - t0)
    t = {k: np.array(v) for k, v in t.items()}
    print(f"Interleaved, {len(cases)} contour pairs (median ms per pair; per-case ratio median):")
    for k in peers:
        print(f"  {k:40s} {np.median(t[k]) * 1e3:7.2f}")
    for k in ours:
        ratios = ", ".join(f"{np.median(t[p] / t[k]):.1f}x {p}" for p in peers)
        print(f"  {k:40s} {np.median(t[k]) * 1e3:7.2f}   ({ratios})")

    def timed(pause):
        ts = []
        for a, b, *_ in cases:
            if pause:
                time.sleep(pause)
            t0 = time.perf_counter()
            pymodal.match(a, b)
            ts.append(time.perf_counter() - t0)
        return np.median(ts) * 1e3

    warm, cold = timed(0.0), timed(args.pause_ms / 1e3)
    print(f"pymodal.match defaults back to back {warm:.2f} ms, after a {args.pause_ms:g} ms pause {cold:.2f} ms")


def interleaved(cases, methods):
    """Times and one-to-one accuracies of every method, each case matched by all in turn."""
    t = {k: [] for k in methods}
    acc = {k: [] for k in methods}
    for a, b, truth, tol in cases:
        for k, f in methods.items():
            t0 = time.perf_counter()
            pairs, excess = f(a, b)
            t[k].append(time.perf_counter() - t0)
            acc[k].append(score(pairs, excess, b, truth, tol))
    return {k: np.array(v) for k, v in t.items()}, {k: np.mean(v) for k, v in acc.items()}


def surfaces(args):
    g = np.loadtxt(DATA / "mun104l.txt")
    cases = []
    for sev in SEVERITY:
        rng = np.random.default_rng(args.seed + 700)
        for _ in range(args.surface_cases):
            na = int(rng.integers(100, 121))
            cases.append(surface_case(g, sev, rng, na, na + int(rng.integers(-10, 11))))

    def ours(**kw):
        def run(a, b):
            m = pymodal.match(a, b, **kw)
            return m.pairs, m.excess
        return run

    extra = {}
    for kv in args.surface_option:
        k, v = kv.split("=", 1)
        extra[k] = v if k in ("search", "prealign", "refine") else int(v) if v.isdigit() else float(v)
    peers = {
        "pycpd rigid, affine, then deformable": cpd("rigid", "affine"),
        "pycpd rigid, then deformable": cpd("rigid"),
        "pycpd deformable": cpd(),
    }
    mine = {"pymodal.match 3-D defaults": ours()}
    if extra:
        mine["pymodal.match 3-D " + ", ".join(args.surface_option)] = ours(**extra)
    ours()(cases[0][0], cases[0][1])
    t, acc = interleaved(cases, {**peers, **mine})
    print(f"Interleaved, {len(cases)} surface pairs (median ms per pair, mean one-to-one accuracy; "
          "per-case ratio median):")
    for k in peers:
        print(f"  {k:40s} {np.median(t[k]) * 1e3:7.2f}  acc {acc[k]:.3f}")
    for k in mine:
        ratios = ", ".join(f"{np.median(t[p] / t[k]):.1f}x {p}" for p in peers)
        print(f"  {k:40s} {np.median(t[k]) * 1e3:7.2f}  acc {acc[k]:.3f}   ({ratios})")


if __name__ == "__main__":
    main()
