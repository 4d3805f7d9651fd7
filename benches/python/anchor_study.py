"""Design study for drift-free tracks: anchored dense fields, measured with the
benchmark's synthetic stances (benches/python/stance.py) and bench_field.py's metrics.

    python benches/python/anchor_study.py            # everything (about 25 min on 2 cores)
    python benches/python/anchor_study.py --quick    # 1 tuning + 1 held-out case, 150 frames
    python benches/python/anchor_study.py --sections tune   # how lambda and alpha were chosen

Only public pymodal calls (pymodal.run for the outlines a run extracts, pymodal.match,
pymodal.contours, pymodal.read_recording), numpy and scipy. Every setting below was chosen on
the TUNING cases (laws 0-1, seeds 0-1); the HELD-OUT cases (laws 2-3, seeds 2-3) are printed in
their own tables and were never used for a choice.

Designs (each carries frame 0's outline nodes, the interior grid and the forefoot-third polygon
to every frame; a position is the image of the frame-0 point by a field, never a node):

  chained   pedomatch's default tracks (outline); interior/region by bench_field's stand-in TPS.
  (1)       direct anchor: pymodal.match(frame-0 outline, frame-h outline) every frame, thin-plate
            smoothing spline (TPS, smoothing 300) of its one-to-one pairs.  (1a) match defaults
            (robust pre-alignment, any turn); (1b) a run's pair settings (prealign sensor,
            max_rotation 30, refits 2, no common sigma).
  (2)       key frames: the same direct match, but the anchor hops every K frames (or when the
            TPS residual at the matched nodes exceeds 0.30 sensel) and the fields are composed.
  (3)       predict + correct: the TPS of the run's consecutive pairs carries the frame-(h-1)
            positions (prediction), blended with the direct anchor field (alpha 0.3).
  (R)       anchored registration (recommended): frame 0's outline, densified to 0.5 sensel, is
            registered onto frame h's outline (densified to 0.25) by curve ICP with a TPS on the
            fixed frame-0 sources (smoothing lambda 1000, factored once per anchor):
            targets = closest point of frame h's outline, averaged with the frame-h nodes whose
            nearest warped point it is (symmetric term), blended (weight alpha 0.2) with the
            partner the direct anchor match pymodal.match(0 -> h) gives the node. Warm start:
            one ICP step per frame from the previous frame's field (10 at frame 1, which starts
            from the TPS of the anchor pairs). Variants: anchor match every 5 frames (alpha 0.5),
            no anchor pairs (alpha 0), re-anchoring every N frames (composition).
"""

import os

for _v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import pickle  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from multiprocessing import Pool  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from scipy.interpolate import RBFInterpolator  # noqa: E402
from scipy.linalg import lu_factor, lu_solve  # noqa: E402
from scipy.spatial import cKDTree  # noqa: E402
from scipy.spatial.distance import cdist  # noqa: E402
from scipy.stats import spearmanr  # noqa: E402

BENCH = Path(__file__).resolve().parent
sys.path.insert(0, str(BENCH))
import pymodal  # noqa: E402
import bench_field as bf  # noqa: E402
from stance import Stance  # noqa: E402

CACHE = Path(os.environ.get("TMPDIR", "/tmp")) / "pedomatch-anchor-study-cache"
PITCH_MM, FRAME_RATE = bf.PITCH_MM, bf.FRAME_RATE
RUN_PAIR_KW = dict(prealign="sensor", max_rotation=30, refits=2, common_sigma=False)
REAL = BENCH.parents[1] / "examples" / "data" / "FrasP01L.asf"
# Chosen on the tuning cases (see the report): TPS smoothing of raw pairs, and (R)'s settings.
SM_PAIRS = 300.0
R_LAMBDA, R_ALPHA, R_A_STEP, R_B_STEP = 1000.0, 0.2, 0.5, 0.25
REAL_COVER = 0.10  # re-anchor when > 10 % of either outline is > 1 sensel from the other


# ---- cases ----------------------------------------------------------------------------------------

class Case:
    """One synthetic stance: frames, the outlines pedomatch's default run extracts (its largest
    object per frame), its consecutive pairs and default tracks, and the truth of every point."""

    def __init__(self, spec, n_frames):
        self.spec, self.n_frames = dict(spec), n_frames
        st = self.st = Stance(frames=n_frames, **spec)
        frames = self.frames = st.frames
        self.T = len(frames)
        CACHE.mkdir(exist_ok=True)
        key = CACHE / ("study_%s_%d.pkl" % ("_".join(f"{k}{v}" for k, v in sorted(spec.items())), n_frames))
        if key.exists():
            d = pickle.load(open(key, "rb"))
        else:
            t0 = time.perf_counter()
            res = pymodal.run(frames, pitch_mm=PITCH_MM, frame_rate=FRAME_RATE, units="kPa")
            secs = time.perf_counter() - t0
            objs = bf.outline_objects(res)
            outlines = {f: np.asarray(o["points"])[:, :2] for f, o in objs.items()}
            ids = {f: o["id"] for f, o in objs.items()}
            by_pair = {(r["id_a"], r["id_b"]): m for r, m in zip(res["table"], res["matches"])}
            cons = {}
            for t in range(self.T - 1):
                m = by_pair.get((ids.get(t), ids.get(t + 1)))
                if m is not None:
                    cons[t] = (m.pairs, m.excess)
            d = dict(outlines=outlines, cons=cons, run_seconds=secs,
                     track_pos=bf.pedomatch_outline_positions(res, objs[0], self.T),
                     spacing=float(res["summary"]["options"]["spacing"]))
            pickle.dump(d, open(key, "wb"))
        self.__dict__.update(d)
        self.nodes0 = self.outlines[0]
        inside = np.argwhere(frames[0] > 0)
        self.interior = inside[:, ::-1].astype(float)
        self.poly, self.pix, self.true_force = bf.region_setup(st, frames)
        self.allpts = np.vstack([self.nodes0, self.interior, self.poly])
        self.na, self.nb = len(self.nodes0), len(self.nodes0) + len(self.interior)
        self.truth = np.array([st.true_positions(t, self.allpts) for t in range(self.T)])

    def score(self, pos, horizons):
        out = {}
        err = np.nan_to_num(np.linalg.norm(pos - self.truth, axis=2), nan=np.inf)
        out["outline"] = {h: float(np.mean(err[h, :self.na] <= self.spacing)) for h in horizons if h < self.T}
        out["interior"] = {h: float(np.mean(err[h, self.na:self.nb] <= 1.0)) for h in horizons if h < self.T}
        f = bf.region_forces(self.frames, self.pix, pos[:, self.nb:])
        rel = np.nan_to_num(np.abs(f - self.true_force) / self.true_force, nan=np.inf)
        out["region"] = (float(rel.max()), float(rel.mean()), float(np.mean(rel <= 0.05)))
        out["frame_avg"] = (float(np.mean(err[1:, :self.na] <= self.spacing)), float(np.mean(err[1:, self.na:self.nb] <= 1)))
        return out


def pairs_of(m):
    return m.pairs[~m.excess]


def tps(src, dst, sm):
    return RBFInterpolator(src, dst, kernel="thin_plate_spline", smoothing=sm)


# ---- a thin-plate smoothing spline on fixed sources, factored once ---------------------------------

def _U(r):
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.nan_to_num(r * r * np.log(r))


class PrefTPS:
    """Same model as RBFInterpolator(kernel='thin_plate_spline', degree 1, scalar smoothing):
    the (n+3)^2 system depends only on the sources, so it is LU-factored once per anchor and each
    frame costs one back-substitution."""

    def __init__(self, S, lam):
        self.S = np.asarray(S, float)
        n = self.n = len(S)
        self.shift, self.scale = self.S.mean(0), max(np.ptp(self.S, 0).max() / 2, 1e-9)
        M = np.zeros((n + 3, n + 3))
        M[:n, :n] = _U(cdist(self.S, self.S)) + lam * np.eye(n)
        P = np.c_[np.ones(n), (self.S - self.shift) / self.scale]
        M[:n, n:], M[n:, :n] = P, P.T
        self.lu = lu_factor(M)

    def solve(self, D):
        rhs = np.zeros((self.n + 3, 2))
        rhs[:self.n] = D
        self.coef = lu_solve(self.lu, rhs)
        return self

    def basis(self, X):
        X = np.asarray(X, float)
        return np.c_[_U(cdist(X, self.S)), np.ones(len(X)), (X - self.shift) / self.scale]

    def __call__(self, X=None, B=None):
        return (self.basis(X) if B is None else B) @ self.coef


def dense_poly(B, step):
    """A closed polyline resampled so that no gap exceeds `step` (its nodes kept)."""
    B = np.asarray(B, float)
    if step >= 1:
        return B
    Bn = np.roll(B, -1, 0)
    m = np.maximum(1, np.ceil(np.linalg.norm(Bn - B, axis=1) / step).astype(int))
    return np.vstack([p + (q - p) * (np.arange(k)[:, None] / k) for p, q, k in zip(B, Bn, m)])


class Anchor:
    """(R): frame-0 outline A registered onto later outlines; Q = current image of A's dense points."""

    def __init__(self, A, lam=R_LAMBDA, alpha=R_ALPHA, a_step=R_A_STEP, b_step=R_B_STEP):
        self.A = np.asarray(A, float)
        self.Ad = dense_poly(self.A, a_step)
        self.nidx = cKDTree(self.Ad).query(self.A)[1]
        self.tps = PrefTPS(self.Ad, lam)
        self.bAd = self.tps.basis(self.Ad)
        self.alpha, self.b_step = alpha, b_step
        self.Q = None

    def start(self, B, pr):
        self.Q = tps(self.A[pr[:, 0]], B[pr[:, 1]], SM_PAIRS)(self.Ad)
        self.tps.solve(self.Q)

    def step(self, B, Bd, tB, pair_tgt=None):
        D = Bd[tB.query(self.Q)[1]]
        k = cKDTree(self.Q).query(B)[1]
        acc, cnt = D.copy(), np.ones(len(D))
        np.add.at(acc, k, B)
        np.add.at(cnt, k, 1)
        D = acc / cnt[:, None]
        if pair_tgt is not None:
            idx, tgt = pair_tgt
            D[idx] = (1 - self.alpha) * D[idx] + self.alpha * tgt
        self.tps.solve(D)
        self.Q = self.tps(B=self.bAd)


def anchored(outlines, points, T, alpha=R_ALPHA, lam=R_LAMBDA, modal_every=1, reanchor=None,
             iters=1, timing=None, keep=None, cover=None):
    """(R) on a sequence of outlines {frame: (n, 2)} starting at frame min(outlines): positions
    (T, n, 2) of `points` (coordinates in the first frame). keep: dict to receive the fields
    (frame -> (Ad, Q)) for the consistency study. cover: re-anchor on the current frame when more
    than this share of its outline nodes lies > 1 sensel from the warped anchor outline, or of the
    warped anchor outline > 1 sensel from the frame's (the contact region grew or shrank)."""
    f0 = min(outlines)
    pos = np.full((T, len(points), 2), np.nan)
    pos[f0] = points
    anc = Anchor(outlines[f0], lam, alpha)
    P = np.asarray(points, float)
    bP = anc.tps.basis(P)
    k0 = f0
    t_modal = t_icp = 0.0
    for h in range(f0 + 1, T):
        if h not in outlines:
            break
        B = outlines[h]
        t0 = time.perf_counter()
        first = anc.Q is None
        pair_tgt = None
        if first or (alpha > 0 and modal_every and (h - k0) % modal_every == 0):
            pr = pairs_of(pymodal.match(anc.A, B))
            if first:
                anc.start(B, pr)
            pair_tgt = (anc.nidx[pr[:, 0]], B[pr[:, 1]])
        t1 = time.perf_counter()
        Bd = dense_poly(B, anc.b_step)
        tB = cKDTree(Bd)
        for _ in range(10 if first else iters):
            anc.step(B, Bd, tB, pair_tgt)
        pos[h] = anc.tps(B=bP)
        t_icp += time.perf_counter() - t1
        t_modal += t1 - t0
        if keep is not None:
            keep[h] = (anc.Ad.copy(), anc.Q.copy(), k0)
        trigger = reanchor and h - k0 >= reanchor
        if cover is not None and not trigger:
            lost = max(np.mean(cKDTree(anc.Q).query(B)[0] > 1.0), np.mean(tB.query(anc.Q)[0] > 1.0))
            trigger = lost > cover
        if trigger:
            if timing is not None:
                timing["reanchors"] = timing.get("reanchors", 0) + 1
            P = pos[h].copy()
            anc = Anchor(B, lam, alpha)
            anc.Q = anc.Ad.copy()
            anc.tps.solve(anc.Q)
            bP = anc.tps.basis(P)
            k0 = h
    if timing is not None:
        timing["modal"] = timing.get("modal", 0.0) + t_modal
        timing["field"] = timing.get("field", 0.0) + t_icp
    return pos


# ---- the other designs ------------------------------------------------------------------------

def d_chained(c, timing=None):
    pos = np.full((c.T, len(c.allpts), 2), np.nan)
    pos[:, :c.na] = c.track_pos
    pos[:, c.na:] = bf.tracks_tps(c.track_pos, c.allpts[c.na:], SM_PAIRS)
    return pos


def d_direct(c, kw=None, timing=None):
    kw = kw or {}
    A = c.nodes0
    pos = np.full((c.T, len(c.allpts), 2), np.nan)
    pos[0] = c.allpts
    for h in range(1, c.T):
        B = c.outlines[h]
        t0 = time.perf_counter()
        pr = pairs_of(pymodal.match(A, B, **kw))
        t1 = time.perf_counter()
        pos[h] = tps(A[pr[:, 0]], B[pr[:, 1]], SM_PAIRS)(c.allpts)
        if timing is not None:
            timing["modal"] = timing.get("modal", 0.0) + t1 - t0
            timing["field"] = timing.get("field", 0.0) + time.perf_counter() - t1
    return pos


def d_keyframes(c, K=None, thr=None, min_hop=5, timing=None):
    pos = np.full((c.T, len(c.allpts), 2), np.nan)
    pos[0] = c.allpts
    k, A, Pk, h = 0, c.nodes0, c.allpts, 1
    while h < c.T:
        B = c.outlines[h]
        pr = pairs_of(pymodal.match(A, B))
        F = tps(A[pr[:, 0]], B[pr[:, 1]], SM_PAIRS)
        if thr is not None and h - 1 - k >= min_hop and \
                np.linalg.norm(F(A[pr[:, 0]]) - B[pr[:, 1]], axis=1).mean() > thr:
            k, A, Pk = h - 1, c.outlines[h - 1], pos[h - 1]
            continue
        pos[h] = F(Pk)
        if K and h - k >= K:
            k, A, Pk = h, B, pos[h]
        h += 1
    return pos


def d_predict_correct(c, alpha=0.3, timing=None):
    A = c.nodes0
    pos = np.full((c.T, len(c.allpts), 2), np.nan)
    pos[0] = c.allpts
    for h in range(1, c.T):
        B = c.outlines[h]
        pairs, exc = c.cons[h - 1]
        pr = pairs[~exc]
        C = tps(c.outlines[h - 1][pr[:, 0]], B[pr[:, 1]], SM_PAIRS)
        pd = pairs_of(pymodal.match(A, B))
        pos[h] = (1 - alpha) * C(pos[h - 1]) + alpha * tps(A[pd[:, 0]], B[pd[:, 1]], SM_PAIRS)(c.allpts)
    return pos


def d_anchored(c, timing=None, **kw):
    return anchored(c.outlines, c.allpts, c.T, timing=timing, **kw)


DESIGNS = {
    "chained: pedomatch default tracks (+ stand-in TPS)": (d_chained, {}),
    "(1a) direct anchor 0->h, match defaults + TPS": (d_direct, {}),
    "(1b) direct anchor 0->h, a run's pair settings + TPS": (d_direct, dict(kw=RUN_PAIR_KW)),
    "(2) key frames every 25, composed": (d_keyframes, dict(K=25)),
    "(2) key frames every 50, composed": (d_keyframes, dict(K=50)),
    "(2) key frame when TPS residual > 0.30": (d_keyframes, dict(thr=0.30)),
    "(3) consecutive TPS predicts, anchor corrects (a 0.3)": (d_predict_correct, {}),
    "(R) anchored registration (recommended)": (d_anchored, {}),
    "(R) anchor match every 5 frames (a 0.5)": (d_anchored, dict(modal_every=5, alpha=0.5)),
    "(R) no anchor pairs (a 0): curve ICP only": (d_anchored, dict(alpha=0.0)),
    "(R) re-anchored every 50 frames": (d_anchored, dict(reanchor=50)),
    "(R) re-anchored every 100 frames": (d_anchored, dict(reanchor=100)),
    "(R) + re-anchor on coverage loss > 10 %": (d_anchored, dict(cover=REAL_COVER)),
}
LONG_DESIGNS = ["chained: pedomatch default tracks (+ stand-in TPS)", "(1a) direct anchor 0->h, match defaults + TPS",
                "(2) key frames every 50, composed", "(R) anchored registration (recommended)",
                "(R) anchor match every 5 frames (a 0.5)", "(R) re-anchored every 50 frames",
                "(R) re-anchored every 100 frames", "(R) + re-anchor on coverage loss > 10 %"]


# ---- forward-backward consistency ------------------------------------------------------------------

def backward_field(Bh, A0, iters=10):
    """An independent estimate of frame h -> frame 0: (R)'s registration run the other way, cold
    (anchor = frame h's outline, target = frame 0's; pairs from pymodal.match(h -> 0))."""
    anc = Anchor(Bh)
    pr = pairs_of(pymodal.match(Bh, A0))
    anc.start(A0, pr)
    pair_tgt = (anc.nidx[pr[:, 0]], A0[pr[:, 1]])
    Ad = dense_poly(A0, R_B_STEP)
    tB = cKDTree(Ad)
    for _ in range(iters):
        anc.step(A0, Ad, tB, pair_tgt)
    return anc


def consistency(c, every=10):
    """Per point, every `every` frames: candidate quality figures of (R) and the true error.
    fb: forward-backward distance; dis: distance between (R) and (1a)'s direct-anchor field;
    pair: distance of (R)'s image of an outline node to its pymodal.match(0 -> h) partner;
    curve: the frame's curve residual (mean distance of the warped anchor outline to the outline)."""
    keep = {}
    pos = anchored(c.outlines, c.allpts, c.T, keep=keep)
    rows = []
    for h in range(every, c.T, every):
        Ad, Q, _ = keep[h]
        B = c.outlines[h]
        bwd = backward_field(B, c.nodes0)
        fb = np.linalg.norm(bwd.tps(pos[h]) - c.allpts, axis=1)
        err = np.linalg.norm(pos[h] - c.truth[h], axis=1)
        curve = cKDTree(dense_poly(B, R_B_STEP)).query(Q)[0].mean()
        pr = pairs_of(pymodal.match(c.nodes0, B))
        dis = np.linalg.norm(pos[h, :c.nb] - tps(c.nodes0[pr[:, 0]], B[pr[:, 1]], SM_PAIRS)(c.allpts[:c.nb]), axis=1)
        pair = np.full(c.na, np.nan)
        pair[pr[:, 0]] = np.linalg.norm(pos[h, pr[:, 0]] - B[pr[:, 1]], axis=1)
        rows.append(dict(h=h, fb=fb[:c.nb], err=err[:c.nb], dis=dis, pair=pair, na=c.na, curve=curve))
    return rows


# ---- real recording: speed and figures ------------------------------------------------------------

def real_walk(reps=3):
    rec = pymodal.read_recording(str(REAL))
    run_t = []
    for _ in range(reps):
        t0 = time.perf_counter()
        res = pymodal.run(rec)
        run_t.append(time.perf_counter() - t0)
    best = {}
    for o in res["objects"]:
        f = o["frame"]
        if f not in best or len(o["points"]) > len(best[f]["points"]):
            best[f] = o
    frames = sorted(best)
    stances, cur = [], [frames[0]]
    for f in frames[1:]:
        if f == cur[-1] + 1:
            cur.append(f)
        else:
            stances.append(cur)
            cur = [f]
    stances.append(cur)
    out = dict(run=min(run_t), n_frames=rec.n_frames, n_obj_frames=len(frames), n_pairs=len(res["table"]),
               matching=res["timings"]["matching"], stances=[])
    for variant, kw in (("(R)", {}), ("(R) anchor match every 5", dict(modal_every=5, alpha=0.5)),
                        ("(R) + re-anchor on coverage", dict(cover=REAL_COVER))):
        tot = {}
        stance_ol = []
        t0 = time.perf_counter()
        for s in stances:
            if len(s) < 3:
                continue
            ol = {f: np.asarray(best[f]["points"])[:, :2] for f in s if len(best[f]["points"]) >= 8}
            fs = sorted(ol)
            if len(fs) < 3:
                continue
            part = [fs[0]]  # the first contiguous run of usable frames
            for f in fs[1:]:
                if f != part[-1] + 1:
                    break
                part.append(f)
            ol = {f: ol[f] for f in part}
            if len(ol) < 3:
                continue
            f0 = min(ol)
            pts = ol[f0]
            anchored(ol, pts, max(ol) + 1, timing=tot, **kw)
            stance_ol.append(ol)
        out[variant] = dict(total=time.perf_counter() - t0, **tot)
        if variant == "(R)":
            for ol in stance_ol:
                out["stances"].append(dict(frames=(min(ol), max(ol)), nodes=(len(ol[min(ol)]), max(len(v) for v in ol.values())),
                                           resid=_stance_resid(ol), resid_cover=_stance_resid(ol, cover=REAL_COVER),
                                           resid_mid=_stance_resid(ol, mid=True)))
    return out


def both_ways(ol, fn):
    """Runs fn(outlines) from the stance's largest outline (most nodes) forward to its last frame
    and backward to its first (frames re-indexed in reverse)."""
    fa = max(ol, key=lambda f: len(ol[f]))
    fwd = {f - fa: ol[f] for f in ol if f >= fa}
    bwd = {fa - f: ol[f] for f in ol if f <= fa}
    r1 = fn(fwd) if len(fwd) > 1 else []
    r2 = fn(bwd) if len(bwd) > 1 else []
    return [(fa + h, *x) for h, *x in r1] + [(fa - h, *x) for h, *x in r2]


def _stance_resid(ol, cover=None, mid=False):
    if mid:
        return sorted(both_ways(ol, lambda o: _stance_resid(o, cover)))
    """Curve residual of (R) at every frame of a stance: mean distance of the warped anchor outline
    to the frame's outline, and the share of the frame's nodes farther than 1 sensel from it."""
    f0 = min(ol)
    keep = {}
    anchored(ol, ol[f0], max(ol) + 1, keep=keep, cover=cover)
    r = []
    for h, (Ad, Q, _) in keep.items():
        B = ol[h]
        d1 = cKDTree(dense_poly(B, R_B_STEP)).query(Q)[0].mean()
        d2 = cKDTree(Q).query(B)[0]
        r.append((h, d1, float(np.mean(d2 > 1.0))))
    return r


# ---- tables ------------------------------------------------------------------------------------

def cell(v):
    v = 100 * np.asarray(v, float)
    return f"{v.mean():.1f}" if len(v) == 1 else f"{v.mean():.1f} / {np.percentile(v, 5):.1f} / {v.min():.1f}"


def table(head, rows, md):
    if md:
        print("| " + " | ".join(head) + " |")
        print("|---|" + "---:|" * (len(head) - 1))
        for r in rows:
            print("| " + " | ".join(r) + " |")
    else:
        w = [max(len(str(x)) for x in col) for col in zip(head, *rows)]
        for r in [head] + rows:
            print("  ".join(str(x).ljust(n) if i == 0 else str(x).rjust(n) for i, (x, n) in enumerate(zip(r, w))))
    print()


def _task(args):
    spec, n_frames, name, horizons = args
    c = Case(spec, n_frames)
    fn, kw = DESIGNS[name]
    tm = {}
    t0 = time.perf_counter()
    pos = fn(c, timing=tm, **kw)
    secs = time.perf_counter() - t0
    sc = c.score(pos, horizons)
    sc["seconds_per_frame"] = secs / (c.T - 1)
    sc["reanchors"] = tm.get("reanchors", 0)
    return spec, n_frames, name, sc


def _tune_task(args):
    spec, lam, alpha = args
    c = Case(spec, 151)
    sc = c.score(anchored(c.outlines, c.allpts, c.T, lam=lam, alpha=alpha), (50, 150))
    return lam, alpha, sc


def tune(jobs, md):
    """How (R)'s lambda and alpha were chosen: tuning cases only, shares averaged over every frame."""
    grid = [(lam, al) for lam in (300.0, 1000.0, 3000.0) for al in (0.0, 0.1, 0.2, 0.3, 0.5)]
    tasks = [(s, lam, al) for lam, al in grid for s in bf.GROUPS["tuning"]]
    with Pool(jobs) as pool:
        res = pool.map(_tune_task, tasks)
    rows = []
    for lam, al in grid:
        r = [x[2] for x in res if x[0] == lam and x[1] == al]
        rows.append([f"lambda {lam:g}, alpha {al:g}", f"{100 * np.mean([x['frame_avg'][0] for x in r]):.1f}",
                     f"{100 * np.mean([x['frame_avg'][1] for x in r]):.1f}", cell([x["outline"][150] for x in r]),
                     cell([x["interior"][150] for x in r]), f"{100 * np.max([x['region'][0] for x in r]):.1f}"])
    print("## Choosing (R)'s settings (tuning cases only)\n")
    table(["(R) setting", "outline, all frames", "interior, all frames", "outline after 150", "interior after 150",
           "region: worst largest error %"], rows, md)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--no-long", action="store_true", help="skip the 300-frame sequences")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--markdown", action="store_true")
    ap.add_argument("--sections", default="quality,consistency,speed",
                    help="comma-separated subset of tune, quality, consistency, speed (default: all but tune)")
    a = ap.parse_args()
    a.sections = a.sections.split(",")
    if "tune" in a.sections:
        tune(a.jobs, a.markdown)
        if a.sections == ["tune"]:
            return
    log = lambda s: print(s, file=sys.stderr, flush=True)  # noqa: E731
    groups = {"tuning": bf.GROUPS["tuning"], "held out": bf.GROUPS["held out"]}
    if a.quick:
        groups = {k: v[:1] for k, v in groups.items()}
    runs = [(150, (25, 50, 100, 150), list(DESIGNS))]
    if not (a.quick or a.no_long):
        runs.append((300, (50, 100, 150, 300), LONG_DESIGNS))

    t_all = time.perf_counter()
    # 1. the default runs (outlines, tracks), serially: pedomatch uses its own threads
    for n, _h, _d in runs:
        for g, specs in groups.items():
            for s in specs:
                Case(s, n + 1)
    log(f"runs ready ({time.perf_counter() - t_all:.0f} s)")
    # 2. every design on every case
    if "quality" not in a.sections:
        runs = [r for r in runs if r[0] == 150]
    tasks = [(s, n + 1, d, hz) for n, hz, ds in runs for g, specs in groups.items() for s in specs for d in ds]
    if "quality" not in a.sections:
        tasks = []
    with Pool(a.jobs) as pool:
        results = {}
        for spec, nf, name, sc in pool.imap_unordered(_task, tasks):
            results[(tuple(sorted(spec.items())), nf, name)] = sc
            log(f"  {nf - 1} frames {spec} {name}: {sc['seconds_per_frame'] * 1e3:.0f} ms/frame")

    for n, hz, ds in (runs if "quality" in a.sections else []):
        print(f"## {n} frames past frame 0 ({'the benchmark' if n == 150 else 'same stance, 2x the frame rate'})\n")
        print("Cells: mean over the cases / 5th percentile / worst case, in %.\n")
        for what, key in (("Outline nodes within one spacing", "outline"), ("Interior points within one sensel", "interior")):
            head = ["design"] + [f"{g}: after {h}" for g in groups for h in hz]
            rows = []
            for d in ds:
                row = [d]
                for g, specs in groups.items():
                    recs = [results[(tuple(sorted(s.items())), n + 1, d)] for s in specs]
                    row += [cell([r[key][h] for r in recs]) for h in hz]
                rows.append(row)
            print(f"**{what}** ({n} frames)\n")
            table(head, rows, a.markdown)
        head = ["design"] + [f"{g}: {x}" for g in groups for x in ("largest err % (mean / worst)", "mean err %", "frames <= 5 %")]
        rows = []
        for d in ds:
            row = [d]
            for g, specs in groups.items():
                recs = [results[(tuple(sorted(s.items())), n + 1, d)] for s in specs]
                mx = [r["region"][0] for r in recs]
                row += [f"{100 * np.mean(mx):.1f} / {100 * np.max(mx):.1f}",
                        f"{100 * np.mean([r['region'][1] for r in recs]):.1f}",
                        f"{100 * np.mean([r['region'][2] for r in recs]):.0f}"]
            rows.append(row)
        print(f"**Forefoot third**: relative force error against the true region ({n} frames)\n")
        table(head, rows, a.markdown)
        head = ["design", "outline, all frames", "interior, all frames", "ms / frame (design only)", "re-anchors per case"]
        rows = []
        for d in ds:
            recs = [results[(tuple(sorted(s.items())), n + 1, d)] for specs in groups.values() for s in specs]
            rows.append([d, f"{100 * np.mean([r['frame_avg'][0] for r in recs]):.1f}",
                         f"{100 * np.mean([r['frame_avg'][1] for r in recs]):.1f}",
                         f"{1e3 * np.mean([r['seconds_per_frame'] for r in recs]):.0f}",
                         f"{np.mean([r['reanchors'] for r in recs]):.1f}"])
        print(f"**Averaged over every frame and all cases** ({n} frames; the ms are Python, 2 jobs on 2 cores)\n")
        table(head, rows, a.markdown)

    # 3. quality figures of (R): do they predict the true error?
    if "consistency" in a.sections:
        print("## Quality figures of (R) against its true error\n")
        print("Every 10th frame of the 150-frame cases; outline nodes and interior points. FB: forward-backward\n"
              "distance, the backward field being (R)'s registration run cold from frame h's outline onto frame\n"
              "0's (pairs from pymodal.match(h -> 0)); disagreement: distance between (R) and the direct-anchor\n"
              "field (1a); anchor-pair residual: outline nodes only; curve residual: one value per frame.\n")
        head = ["group", "figure", "Spearman per point", "Spearman per frame (means)", "errors > 1 flagged (figure > 0.5)",
                "good points flagged", "figure <= 0.5: share within 1"]
        rows = []
        for g, specs in groups.items():
            rs = [r for s_ in specs for r in consistency(Case(s_, 151))]
            err = np.concatenate([r["err"] for r in rs])
            m_err = [r["err"].mean() for r in rs]
            for lbl, key in (("FB distance", "fb"), ("disagreement with (1a)", "dis"), ("anchor-pair residual", "pair")):
                if key == "pair":
                    v = np.concatenate([r["pair"] for r in rs])
                    e = np.concatenate([r["err"][:r["na"]] for r in rs])
                    m_v = [np.nanmean(r["pair"]) for r in rs]
                else:
                    v, e = np.concatenate([r[key] for r in rs]), err
                    m_v = [r[key].mean() for r in rs]
                ok = np.isfinite(v)
                v, e = v[ok], e[ok]
                bad = e > 1
                rows.append([g, lbl, f"{spearmanr(v, e)[0]:.2f}", f"{spearmanr(m_v, m_err)[0]:.2f}",
                             f"{100 * np.mean(v[bad] > 0.5):.0f} % of {bad.sum()}" if bad.any() else "-",
                             f"{100 * np.mean(v[~bad] > 0.5):.0f} %", f"{100 * np.mean(e[v <= 0.5] <= 1):.1f}"])
            rows.append([g, "curve residual", "-", f"{spearmanr([r['curve'] for r in rs], m_err)[0]:.2f}", "-", "-", "-"])
        table(head, rows, a.markdown)

    # 4. speed
    if "speed" not in a.sections:
        print(f"Total {time.perf_counter() - t_all:.0f} s.")
        return
    print("## Speed\n")
    c = Case(bf.GROUPS["tuning"][0], 151)
    t0 = time.perf_counter()
    pymodal.run(c.frames, pitch_mm=PITCH_MM, frame_rate=FRAME_RATE, units="kPa")
    run_s = time.perf_counter() - t0
    rows = [["pymodal.run, defaults (whole run)", f"{1e3 * run_s / (c.T - 1):.1f}", "", ""]]
    for d in ("(1a) direct anchor 0->h, match defaults + TPS", "(R) anchored registration (recommended)",
              "(R) anchor match every 5 frames (a 0.5)", "(R) no anchor pairs (a 0): curve ICP only"):
        fn, kw = DESIGNS[d]
        tm = {}
        t0 = time.perf_counter()
        fn(c, timing=tm, **kw)
        tot = time.perf_counter() - t0
        rows.append([d, f"{1e3 * tot / (c.T - 1):.1f}", f"{1e3 * tm.get('modal', 0) / (c.T - 1):.1f}",
                     f"{1e3 * tm.get('field', 0) / (c.T - 1):.1f}"])
    print(f"Synthetic stance law 0 seed 0, 150 frames, one process:\n")
    table(["", "ms / frame", "of which pymodal.match", "of which field (Python)"], rows, a.markdown)
    rw = real_walk()
    print(f"Bundled walk {REAL.name}: {rw['n_frames']} frames, {rw['n_obj_frames']} with contact, {rw['n_pairs']} pairs;"
          f" pymodal.run defaults {rw['run']:.2f} s (matching {rw['matching']:.2f} s).\n")
    rows = []
    for v in ("(R)", "(R) anchor match every 5", "(R) + re-anchor on coverage"):
        x = rw[v]
        rows.append([v + " on the largest object per frame, anchor = first frame of each stance",
                     f"{x['total']:.2f}", f"{x.get('modal', 0):.2f}", f"{x.get('field', 0):.2f}",
                     f"{(rw['run'] + x['total']) / rw['run']:.2f}x", f"{(rw['run'] + x.get('modal', 0)) / rw['run']:.2f}x",
                     str(x.get("reanchors", 0))])
    table(["", "s", "pymodal.match s", "field s (Python)", "run + design / run", "run + anchor matches / run", "re-anchors"], rows, a.markdown)
    print("Real walk, (R) per stance (anchor = first frame unless said): curve residual (mean distance of the warped anchor\n"
          "outline to the frame's outline, sensels) and share of the frame's nodes > 1 sensel from it, at\n"
          "the first, middle and last frames:\n")
    rows = []
    for s in rw["stances"]:
        for lbl, key in (("", "resid"), (" + re-anchor on coverage", "resid_cover"),
                         (", anchor = largest outline, both ways", "resid_mid")):
            r = s[key]
            pick = [r[0], r[len(r) // 2], r[-1]] if r else []
            rows.append([f"frames {s['frames'][0]}-{s['frames'][1]}{lbl}", f"{s['nodes'][0]} -> max {s['nodes'][1]}"]
                        + [f"{d1:.2f} / {100 * d2:.0f} %" for _h, d1, d2 in pick]
                        + [f"{np.mean([d1 for _h, d1, _d in r]):.2f} / {100 * np.mean([d2 for _h, _d, d2 in r]):.0f} %"])
    table(["stance", "nodes (anchor -> max)", "first", "middle", "last", "mean over frames"], rows, a.markdown)
    print(f"Total {time.perf_counter() - t_all:.0f} s.")


if __name__ == "__main__":
    main()
