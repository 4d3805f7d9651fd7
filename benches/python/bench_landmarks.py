"""Landmarks carried between real outlines annotated by other people: pymodal.match (defaults and
each solver) against coherent point drift (pycpd), shape context + Hungarian and Bayesian coherent
point drift (BCPD), on the same within-class pairs.

Data: three outline data sets of the R package Momocs (GPL >= 3, not shipped with this project):
`hearts` (240 hand-drawn hearts by 8 people, 80 points, 4 landmarks), `nsfishes` (218 North Sea
fish outlines, 120 points, 5 landmarks) and `charring` (324 cereal grains in three views, 120
points, 2 landmarks). The landmarks are indices into each outline, as distributed with the data
sets. Classes: the hearts; the five fish orders with at least 16 specimens; grains by taxon and
view (6). The `.rda` files (the package's data/ folder, Momocs 1.5.0) are read from --data (or
$LANDMARK_DATA), each checked against its SHA-256 below; the `rdata` package (PyPI) parses them.
Without a data folder the benchmark says so and exits.

Cases: every outline is resampled by arc length to its own count of points (100-185, drawn per
outline) from a random start, so counts differ within a pair and a landmark lies between nodes.
Split (fixed before any result was seen): within each class the specimens are shuffled (seed 0);
the first half is the tuning set, the second the held-out set, and pairs are drawn within one half
only (at most --pairs per class and half, each pair ordered at random).

Carrying a landmark: each method gives every node of A an image on B's outline (pymodal: its
partner node, excess matches included; point-set registrations, and pymodal's rows "moved nodes
projected" (--projected): the moved node projected onto B's outline; shape context: its assigned
node); a landmark between nodes i and i+1 of A at fraction t
goes to the point of B's outline at t of the way (along the outline, the shorter way round)
between the images of i and i+1. Nodes of A without a partner take the interpolation between their
nearest neighbours that have one. Error: the distance from the carried point to B's landmark in B's
mean point spacing. `pedomatch defaults, field` instead maps the landmark by the pair's
thin-plate-spline field (Match.field) and projects the image onto B's outline; `pedomatch
defaults, outline images` reads each node's image from Match.outline_images (after the coherent
drift the point of B's outline nearest the moved node, otherwise the partner node), with no
post-processing of the benchmark's own.

Peers: pycpd rigid then deformable, pycpd rigid alone (defaults, each shape centred and scaled to
unit RMS radius first); shape context (5 log-radius x 12 angle bins, chi-square cost) with the
Hungarian assignment (scipy); BCPD (the binary in $BCPD_BIN, run with its defaults and -N1, one
OpenMP thread; skipped, with a note, when unset). Time: wall time per pair including, for BCPD, the
writing and reading of its text files and the process start.

Run:  python benches/python/bench_landmarks.py --data DIR [--pairs 12] [--markdown]
      python benches/python/bench_landmarks.py --data DIR --halves tuning --only pedomatch \
          --by-class --variant prealign=normalize,solver=ordered  (settings tried on tuning)
      python benches/python/bench_landmarks.py --data DIR --halves tuning --projected \
          --variant prealign=normalize,position_weight=1,refine=coherent  (moved nodes read too)
      python benches/python/bench_landmarks.py --data DIR --turns --variant max_rotation=30
"""
import argparse
import hashlib
import os
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np
from scipy.optimize import linear_sum_assignment

SHA256 = {
    "hearts.rda": "9f4bdc16c3c99cfe457cd016b608f37d85dc9eddc53758a79a14efdda29564d1",
    "nsfishes.rda": "e1294498681171c4d4246d21a0044cdbaa36e269530de9a18c8ff8becb0a6091",
    "charring.rda": "a6d06f44c0bc77297e0d78a4dbc8002789254d71dca7cf99388f6f2ba4946b32",
}
MIN_ORDER = 16  # fish orders with fewer specimens are left out
COUNTS = (100, 185)


# ---------------------------------------------------------------- data


def read_rda(path, name):
    import rdata

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        obj = rdata.conversion.convert(rdata.parser.parse_file(path), default_encoding="utf8")
    return obj[name]


def load(data_dir):
    """[(class name, specimen name, (n, 2) outline, landmark vertex indices 0-based)]"""
    data_dir = Path(data_dir)
    for f, digest in SHA256.items():
        p = data_dir / f
        if not p.is_file():
            sys.exit(f"missing {p}: copy Momocs' data/{f} there (see the docstring)")
        got = hashlib.sha256(p.read_bytes()).hexdigest()
        if digest and got != digest:
            sys.exit(f"{p}: SHA-256 {got}, expected {digest}")
    out = []
    for name in ("hearts", "nsfishes", "charring"):
        d = read_rda(data_dir / f"{name}.rda", name)
        names = list(d["coo"].keys())
        coo = [np.asarray(v, float) for v in d["coo"].values()]
        ldk = [np.asarray(v, int) - 1 for v in d["ldk"]]
        fac = d["fac"]
        if name == "hearts":
            cls = ["heart"] * len(coo)
        elif name == "nsfishes":
            orders = fac["Order"].astype(str).tolist()
            keep = {o for o in set(orders) if orders.count(o) >= MIN_ORDER}
            cls = [f"fish {o}" if o in keep else None for o in orders]
        else:
            cls = [f"grain {t} {v}" for t, v in zip(fac["taxa"].astype(str), fac["view"].astype(str))]
        for c, s, p, l in zip(cls, names, coo, ldk):
            if c is not None:
                out.append((c, str(s), p, l))
    return out


def resample(poly, lm_idx, n, start):
    """n points by arc length on the closed polyline from fraction `start`; the landmarks' places
    as fractional node positions u (node floor(u), fraction u - floor(u))."""
    seg = np.linalg.norm(np.roll(poly, -1, 0) - poly, axis=1)
    cum = np.concatenate([[0], np.cumsum(seg)])
    total = cum[-1]
    s = ((start + np.arange(n) / n) % 1.0) * total
    pts = point_at(poly, cum, s)
    u = ((cum[lm_idx] / total - start) % 1.0) * n
    return pts, u


def point_at(poly, cum, s):
    total = cum[-1]
    s = np.mod(s, total)
    k = np.clip(np.searchsorted(cum, s, side="right") - 1, 0, len(poly) - 1)
    t = (s - cum[k]) / np.maximum(cum[k + 1] - cum[k], 1e-300)
    return poly[k] + t[:, None] * (np.roll(poly, -1, 0)[k] - poly[k])


class Outline:
    def __init__(self, cls, name, poly, lm_idx, rng):
        n = int(rng.integers(COUNTS[0], COUNTS[1] + 1))
        self.cls, self.name = cls, name
        self.pts, self.u = resample(poly, lm_idx, n, rng.uniform())
        self.landmarks = poly[lm_idx]
        seg = np.linalg.norm(np.roll(self.pts, -1, 0) - self.pts, axis=1)
        self.cum = np.concatenate([[0], np.cumsum(seg)])
        self.spacing = self.cum[-1] / len(self.pts)

    def project(self, q):
        """Arc-length positions on this (resampled) outline of the nearest points to q."""
        a, b = self.pts, np.roll(self.pts, -1, 0)
        d = b - a
        w = q[:, None, :] - a[None]
        t = np.clip((w * d[None]).sum(2) / np.maximum((d * d).sum(1), 1e-300)[None], 0, 1)
        foot = a[None] + t[..., None] * d[None]
        k = np.argmin(((q[:, None, :] - foot) ** 2).sum(2), axis=1)
        seg = np.diff(self.cum)
        return self.cum[k] + t[np.arange(len(q)), k] * seg[k]


def cases(outlines, half, per_class, seed):
    rng = np.random.default_rng(seed)
    by = {}
    for o in outlines:
        by.setdefault(o.cls, []).append(o)
    pairs = []
    for cls in sorted(by):
        group = sorted(by[cls], key=lambda o: o.name)
        perm = np.random.default_rng(0).permutation(len(group))
        take = perm[: len(group) // 2] if half == "tuning" else perm[len(group) // 2 :]
        members = [group[i] for i in take]
        allp = [(i, j) for i in range(len(members)) for j in range(i + 1, len(members))]
        pick = rng.choice(len(allp), size=min(per_class, len(allp)), replace=False)
        for k in pick:
            i, j = allp[k]
            if rng.uniform() < 0.5:
                i, j = j, i
            pairs.append((members[i], members[j]))
    return pairs


# ---------------------------------------------------------------- carrying


def carry(a, b, image_s):
    """Landmarks of A carried to B from the arc positions (on B) of A's nodes' images (NaN = none)."""
    n, total = len(image_s), b.cum[-1]
    s = np.array(image_s, float)
    have = np.flatnonzero(~np.isnan(s))
    if len(have) < n:  # fill gaps by interpolating along the outline between matched neighbours
        for i in np.flatnonzero(np.isnan(s)):
            k = np.searchsorted(have, i)
            p, q = have[k - 1], have[k % len(have)]
            gap = (q - p) % n or n
            f = ((i - p) % n) / gap
            s[i] = s[p] + f * wrap(s[q] - s[p], total)
    i = np.floor(a.u).astype(int) % n
    t = a.u - np.floor(a.u)
    j = (i + 1) % n
    sl = s[i] + t * wrap(s[j] - s[i], total)
    return point_at(b.pts, b.cum, sl)


def wrap(d, total):
    return (d + total / 2) % total - total / 2


def errors(b, carried):
    return np.linalg.norm(carried - b.landmarks, axis=1) / b.spacing


def from_pairs(a, b, pairs):
    s = np.full(len(a.pts), np.nan)
    s[pairs[:, 0]] = b.cum[pairs[:, 1]]
    return carry(a, b, s)


def normalise(p, ref=None):
    ref = p if ref is None else ref
    c = ref.mean(0)
    r = np.sqrt(((ref - c) ** 2).sum(1).mean())
    return (p - c) / r, c, r


# ---------------------------------------------------------------- methods


def pedomatch(projected=False, **kw):
    """pymodal.match's pairs, or with `projected` its moved nodes (Match.aligned_a: after
    refine="coherent", A drifted onto B) projected onto B's outline, as the CPD rows are read."""

    def run(a, b):
        import pymodal

        m = pymodal.match(a.pts, b.pts, **kw)
        if projected:
            return carry(a, b, b.project(np.asarray(m.aligned_a)))
        return from_pairs(a, b, np.asarray(m.pairs))

    return run


def image_arcs(m, b):
    """Arc-length positions on B of a match's images of A's nodes (Match.outline_images:
    positions j + t along B's numbering; NaN, for a node in no pair, stays NaN)."""
    at = np.asarray(m.outline_images)
    j = np.floor(np.nan_to_num(at)).astype(int) % len(b.pts)
    return b.cum[j] + (at - np.floor(at)) * np.diff(b.cum)[j]


def pedomatch_images(**kw):
    """pymodal.match's own images of A's nodes on B's outline, carried as arc-length positions."""

    def run(a, b):
        import pymodal

        return carry(a, b, image_arcs(pymodal.match(a.pts, b.pts, **kw), b))

    return run


def pedomatch_field(a, b):
    import pymodal

    m = pymodal.match(a.pts, b.pts)
    i = np.floor(a.u).astype(int) % len(a.pts)
    s = a.cum[i] + (a.u - np.floor(a.u)) * np.diff(a.cum)[i]  # the landmarks' places on A
    moved = m.field(a.pts, b.pts).apply(point_at(a.pts, a.cum, s))
    return point_at(b.pts, b.cum, b.project(moved))


def cpd(deformable):
    def run(a, b):
        import pycpd

        na, _, _ = normalise(a.pts)
        nb, c, r = normalise(b.pts)
        ty, _ = pycpd.RigidRegistration(X=nb, Y=na).register()
        if deformable:
            ty, _ = pycpd.DeformableRegistration(X=nb, Y=ty).register()
        return carry(a, b, b.project(ty * r + c))

    return run


def shape_context(p, nr=5, nt=12):
    d = p[None] - p[:, None]
    r = np.linalg.norm(d, axis=2)
    r = r / r[r > 0].mean()
    th = np.arctan2(d[..., 1], d[..., 0]) % (2 * np.pi)
    edges = np.logspace(np.log10(0.125), np.log10(2.0), nr + 1)
    rb = np.searchsorted(edges, r) - 1
    tb = np.minimum((th / (2 * np.pi) * nt).astype(int), nt - 1)
    ok = (rb >= 0) & (rb < nr) & ~np.eye(len(p), dtype=bool)
    h = np.zeros((len(p), nr * nt))
    rows = np.nonzero(ok)[0]
    np.add.at(h, (rows, (rb * nt + tb)[ok]), 1.0)
    return h / np.maximum(h.sum(1, keepdims=True), 1)


def sc_hungarian(a, b):
    ha, hb = shape_context(a.pts), shape_context(b.pts)
    num = (ha[:, None] - hb[None]) ** 2
    den = ha[:, None] + hb[None]
    cost = 0.5 * np.where(den > 0, num / np.where(den > 0, den, 1), 0).sum(2)
    i, j = linear_sum_assignment(cost)
    return from_pairs(a, b, np.stack([i, j], 1))


def bcpd(binary):
    env = dict(os.environ, OMP_NUM_THREADS="1")

    def run(a, b):
        with tempfile.TemporaryDirectory() as tmp:
            x, y = Path(tmp, "x.txt"), Path(tmp, "y.txt")
            np.savetxt(x, b.pts, delimiter="\t")
            np.savetxt(y, a.pts, delimiter="\t")
            subprocess.run([binary, "-x", str(x), "-y", str(y), "-o", str(Path(tmp, "o_")),
                            "-sy", "-q", "-N1"], check=True, env=env, cwd=tmp,
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            ty = np.loadtxt(Path(tmp, "o_y.txt"))
        return carry(a, b, b.project(ty))

    return run


def bcpd_version(binary):
    out = subprocess.run([binary, "-v"], capture_output=True, text=True).stdout
    line = next((s.strip() for s in out.splitlines() if "version" in s.lower()), "")
    return line


# ---------------------------------------------------------------- main


def variant_kw(v):
    return {k: parse_value(x) for k, x in (kv.split("=", 1) for kv in v.split(","))}


def turns(half, pairs, settings):
    """Per class: pairs whose pre-alignment (Match.transform) turns A by over 30 and 90 degrees."""
    import pymodal

    print(f"\n{half}: pairs turned by over 30 / 90 degrees by the pre-alignment\n")
    names = ["defaults" if not kw else ",".join(f"{k}={x}" for k, x in kw.items()) for kw in settings]
    print("| class | pairs | " + " | ".join(names) + " |")
    print("|---|---|" + "---|" * len(names))
    by = {}
    for a, b in pairs:
        row = by.setdefault(a.cls, [[] for _ in settings])
        for k, kw in enumerate(settings):
            t = np.asarray(pymodal.match(a.pts, b.pts, **kw).transform)
            row[k].append(abs(np.degrees(np.arctan2(t[1, 0], t[0, 0]))))
    for cls in sorted(by):
        cells = [f"{(np.array(d) > 30).sum()} / {(np.array(d) > 90).sum()}" for d in by[cls]]
        print(f"| {cls} | {len(by[cls][0])} | " + " | ".join(cells) + " |")


def parse_value(x):
    for conv in (int, float):
        try:
            return conv(x)
        except ValueError:
            pass
    return {"true": True, "false": False}.get(x.lower(), x)


def summarise(errs, times):
    e = np.concatenate(errs)
    return dict(w1=(e <= 1).mean(), w2=(e <= 2).mean(), w5=(e <= 5).mean(), med=np.median(e),
                p90=np.percentile(e, 90), ms=np.median(times) * 1e3, n=len(e))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", default=os.environ.get("LANDMARK_DATA"))
    ap.add_argument("--pairs", type=int, default=12, help="at most this many pairs per class and half")
    ap.add_argument("--halves", default="tuning,held-out")
    ap.add_argument("--only", default="", help="comma-separated method names to run (substring)")
    ap.add_argument("--variant", action="append", default=[],
                    help="extra pymodal.match row, e.g. 'position_weight=0.5,refine=modal' (repeatable)")
    ap.add_argument("--projected", action="store_true",
                    help="each --variant also read by its moved nodes (Match.aligned_a) projected onto B's outline")
    ap.add_argument("--by-class", action="store_true", help="also the share within 2 spacings per class")
    ap.add_argument("--turns", action="store_true",
                    help="only count, per class, the pairs whose pre-alignment turns A by over 30 / 90 degrees")
    ap.add_argument("--markdown", action="store_true")
    args = ap.parse_args()
    if not args.data:
        print("bench_landmarks skipped: give --data DIR (or set LANDMARK_DATA) holding Momocs' "
              "hearts.rda, nsfishes.rda and charring.rda")
        return

    rng = np.random.default_rng(1)
    outlines = [Outline(c, s, p, l, rng) for c, s, p, l in load(args.data)]
    methods = {
        "pedomatch defaults": pedomatch(),
        "pedomatch defaults, field": pedomatch_field,
        "pedomatch defaults, outline images": pedomatch_images(),
        "pedomatch solver=hungarian": pedomatch(solver="hungarian"),
        "pedomatch solver=simplex": pedomatch(solver="simplex"),
        "pedomatch solver=ordered": pedomatch(solver="ordered"),
        "CPD rigid + deformable (pycpd)": cpd(True),
        "CPD rigid (pycpd)": cpd(False),
        "shape context + Hungarian": sc_hungarian,
    }
    for v in args.variant:
        methods[f"pedomatch {v}"] = pedomatch(**variant_kw(v))
        if args.projected:
            methods[f"pedomatch {v}, moved nodes projected"] = pedomatch(projected=True, **variant_kw(v))
    binary = os.environ.get("BCPD_BIN")
    notes = []
    if binary and Path(binary).is_file():
        methods["BCPD (defaults)"] = bcpd(binary)
        notes.append(f"BCPD: {bcpd_version(binary)}, OMP_NUM_THREADS=1")
    else:
        notes.append("BCPD skipped: set BCPD_BIN to the bcpd binary")
    if args.only:
        keys = [k.strip() for k in args.only.split(",")]
        methods = {n: f for n, f in methods.items() if any(k in n for k in keys)}

    classes = sorted({o.cls for o in outlines})
    counts = [len(o.pts) for o in outlines]
    print(f"{len(outlines)} outlines, {len(classes)} classes, {min(counts)}-{max(counts)} points")
    for note in notes:
        print(note)

    for half in args.halves.split(","):
        pairs = cases(outlines, half, args.pairs, seed=2 if half == "tuning" else 3)
        if args.turns:
            turns(half, pairs, [{}] + [variant_kw(v) for v in args.variant])
            continue
        rows, per_class = measure(methods, pairs)
        print_rows(f"{half}: {len(pairs)} pairs", rows, args.markdown)
        if args.by_class:
            print_by_class(f"{half}, share within 2 spacings by class (pairs)", rows, per_class,
                           sorted(per_class))


def measure(methods, pairs):
    """Every method on every pair, after one warm-up call each: the summary per method, and the
    errors per class (A's) and method."""
    for f in methods.values():  # warm-up (imports, first-call costs)
        f(*pairs[0])
    rows, per_class = {}, {}
    for name, f in methods.items():
        errs, times = [], []
        for a, b in pairs:
            t0 = time.perf_counter()
            carried = f(a, b)
            times.append(time.perf_counter() - t0)
            errs.append(errors(b, carried))
        rows[name] = summarise(errs, times)
        for (a, _), e in zip(pairs, errs):
            per_class.setdefault(a.cls, {}).setdefault(name, []).append(e)
    return rows, per_class


def print_rows(title, rows, markdown):
    """The shares, quantiles and times of `rows`, with each one's speed against CPD's."""
    nl = rows[next(iter(rows))]["n"]
    title = f"{title}, {nl} landmarks, error in B's point spacings"
    cpd_ms = rows.get("CPD rigid + deformable (pycpd)", {}).get("ms")
    if markdown:
        print(f"\n**{title}**\n")
        print("| method | within 1 | within 2 | within 5 | median | 90th pct | ms / pair | CPD time / time |")
        print("|---|---|---|---|---|---|---|---|")
        for name, r in rows.items():
            ratio = f"{cpd_ms / r['ms']:.1f}" if cpd_ms else ""
            print(f"| {name} | {r['w1']:.3f} | {r['w2']:.3f} | {r['w5']:.3f} | {r['med']:.2f} | "
                  f"{r['p90']:.2f} | {r['ms']:.1f} | {ratio} |")
    else:
        print(f"\n{title}")
        for name, r in rows.items():
            ratio = f"{cpd_ms / r['ms']:6.1f}x" if cpd_ms else ""
            print(f"  {name:34s} {r['w1']:.3f} {r['w2']:.3f} {r['w5']:.3f}  med {r['med']:.2f}"
                  f"  p90 {r['p90']:.2f}  {r['ms']:7.1f} ms {ratio}")


def print_by_class(title, rows, per_class, classes):
    print(f"\n{title}\n")
    print("| class | pairs | " + " | ".join(rows) + " |")
    print("|---|---|" + "---|" * len(rows))
    for cls in classes:
        cells = [f"{(np.concatenate(per_class[cls][n]) <= 2).mean():.2f}" for n in rows]
        print(f"| {cls} | {len(per_class[cls][next(iter(rows))])} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
