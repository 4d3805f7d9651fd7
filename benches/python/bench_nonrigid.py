"""The optional modal non-rigid refinement (``refine="modal"``, docs/method.md §7.4) against the
affine pipeline and coherent point drift's deformable registration, on strongly non-affine warps.

Cases are those of bench_match.py (real outlines; two independent samplings of the MUN104
pressure image), with the warp's bending raised from the severe 0.12 to 0.25 and 0.4 at moderate
rotation and scale ("bent 0.25", "bent 0.4"), and today's surface severities for the 3-D metric.
The seeds (default 11) differ from those used to choose the warp's modes and stiffness (the Rust
tests' 500..512). Scores as in bench_match.py: one-to-one (global search, excess step) and, for
surfaces, many-to-one (``search="best"``, the read-out of pycpd and of the 3-D ceiling 0.555);
pycpd is read out both ways on surfaces (argmax of its posterior, and the one-to-one assignment
of largest total posterior with the same excess rule), each beside its oracle ceiling.

Run:  python benches/python/bench_nonrigid.py [--cases 20] [--seed 11] [--markdown]
"""
import argparse

import numpy as np

import bench_match as bm

BENT = {"bent 0.25": (15.0, 0.12, 0.05, 0.25), "bent 0.4": (15.0, 0.12, 0.05, 0.4)}


def cases(kind, sev, n, seed):
    bm.SEVERITY.update(BENT)
    rng = np.random.default_rng(seed)
    if kind == "contour":
        outs = bm.outlines()
        return [bm.contour_case(outs[k % len(outs)], sev, rng) for k in range(n)]
    g = np.loadtxt(bm.DATA / "mun104l.txt")
    out = []
    for _ in range(n):
        na = int(rng.integers(100, 121))
        out.append(bm.surface_case(g, sev, rng, na, na + int(rng.integers(-10, 11))))
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cases", type=int, default=20)
    ap.add_argument("--seed", type=int, default=11)
    ap.add_argument("--markdown", action="store_true")
    args = ap.parse_args()
    contour_methods = {
        "pymodal.match (defaults)": bm.modal(),
        "pymodal.match refits=2": bm.modal(refits=2),
        "pymodal.match refine='modal'": bm.modal(refine="modal"),
        "pymodal.match refits=2, refine='modal'": bm.modal(refits=2, refine="modal"),
        "pycpd deformable + argmax P": bm.cpd(),
        "pycpd rigid, affine, then deformable + argmax P": bm.cpd("rigid", "affine"),
    }
    surface_methods = {
        "pymodal.match 3-D (one-to-one, defaults)": bm.modal(),
        "pymodal.match 3-D refine='modal' (one-to-one)": bm.modal(refine="modal"),
        "pycpd deformable + one-to-one on P": bm.cpd(one_to_one=True),
        "pycpd rigid, then deformable + one-to-one on P": bm.cpd("rigid", one_to_one=True),
        "pycpd rigid, affine, then deformable + one-to-one on P": bm.cpd("rigid", "affine", one_to_one=True),
        "oracle: most true positions within tolerance, one-to-one": bm.oracle_one_to_one,
        "pymodal.match 3-D search='best' (many-to-one)": bm.modal(search="best"),
        "pymodal.match 3-D search='best', refine='modal'": bm.modal(search="best", refine="modal"),
        "pycpd deformable + argmax P (many-to-one)": bm.cpd(),
        "pycpd rigid, affine, then deformable + argmax P": bm.cpd("rigid", "affine"),
        "oracle: nearest point of b to each true position (many-to-one)": bm.oracle_nearest,
    }
    bent = list(BENT)
    res = {s: bm.evaluate(contour_methods, cases("contour", s, args.cases, args.seed)) for s in bent}
    bm.table(f"Strongly bent contours ({args.cases} cases, seed {args.seed})", bent, res, args.markdown)
    sevs = bent + ["mild", "moderate", "severe"]
    res = {s: bm.evaluate(surface_methods, cases("surface", s, args.cases, args.seed + 100)) for s in sevs}
    bm.table(f"Surfaces ({args.cases} cases, seed {args.seed + 100})", sevs, res, args.markdown)


if __name__ == "__main__":
    main()
