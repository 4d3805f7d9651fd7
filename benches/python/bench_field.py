"""Tracks that follow the foot: outline nodes, interior points and a region carried
through a whole stance, against ground truth, beside chained nearest neighbour, chained CPD and
chained dense optical flow.

    python benches/python/bench_field.py [--frames 150] [--quick] [--markdown]
    python benches/python/bench_field.py --rate 500 --every 1,auto [--markdown]

**Sequences.** Synthetic stances from ``stance.py`` (beside this file): a foot-like pressure
field (heel, lateral midfoot, metatarsal heads, hallux, lesser toes) moved by a smooth non-rigid
map per frame (rotation, translation, forefoot spreading and a bend of the forefoot about the
heel) while its load rolls from heel to toes, so the pressure under a material point changes
along the stance. The contact region is a fixed material shape, so frame 0's outline maps onto
frame t's outline and every point has a true position. Ground truth comes from the map alone:
the frames are rendered from the map's exact inverse, and the true position of a frame-0 point
at frame t is the map applied to it. Four motion laws; laws 0-1 with seeds 0-1 are the **tuning
cases** (every choice below -- the baselines' settings, the stand-in's -- was made on them),
laws 2-3 with seeds 2-3 are **held out** and printed in their own tables. A **control** group
(the held-out cases with the roll-over switched off: the pressure pattern only moves) shows what
the roll-over costs each method. ``--frames N`` runs N frames past frame 0 (N + 1 frames in
all; 200 Hz, 5 mm sensels, kPa); the whole stance's motion is the same whatever N.

**pedomatch** runs each sequence as ``pymodal.run(frames, pitch_mm=5, frame_rate=200,
units="kPa")``: the contour model with the default options (the units only label the forces).

**Metrics** after 25, 50, 100 and 150 frames (those that exist):
- *outline nodes*: the nodes of frame 0's outline (pedomatch's own, one node per sensel), each
  followed to frame h; the share within one node spacing (1 sensel) of the true position of its
  material point. A track that has ended by then counts as lost. Methods: pedomatch's tracks;
  chained nearest neighbour (each node to the nearest node of the next outline); chained CPD
  (pycpd rigid, then deformable registration of each outline onto the next, each node to its
  most probable partner); and the dense flows below, which carry the node's position.
- *interior points*: the sensel centres of frame 0's contact region (a grid of spacing 1 sensel;
  ``--grid 2`` for every other one); the share within one sensel of the truth. pedomatch has no
  dense field yet: its row is **"pedomatch tracks + TPS (stand-in)"**, a thin-plate spline
  (``scipy.interpolate.RBFInterpolator``, smoothing 300, chosen on the tuning cases among 0-3000)
  fitted from the frame-0 positions of the outline tracks still alive at frame h to their
  frame-h positions and applied to the points. It is NOT the product; ``pedomatch_field`` below
  is the hook that will use pedomatch's own field (e.g. a future ``Match.warp(points)``),
  composed pair by pair, once it exists, and print a "pedomatch field" row.
- *region*: the forefoot third of frame 0's contact region (the contact sensels nearest the
  toes, a third of the area: frame 0's outline cut by a line across the foot, which runs through
  the metatarsal heads). Its true force at frame t sums the pressure of the sensels whose
  material point (exact inverse map) lies in the region; a method carries the region's polygon
  (outline part and a densely sampled cut) to frame t and sums the pressure of the sensels whose
  centre lies inside it. Reported: the largest and the mean relative force error over all
  frames, beside the static frame-0 mask (the region not carried). **pedomatch follows the
  region itself**: the run is given the region as a mask of frame 0 (``regions=``, label 1 on
  the contact sensels above the cut) and its ``regions`` rows give the force of the region it
  carried (``kind`` "moving": the sensels inside its followed outline) and of the mask left in
  place ("fixed"); a second table gives the per-frame error over every frame of every case
  (mean, 95th percentile, worst, and the share of frames within the 5 % target).

Rows that are not the defaults, each labelled: pedomatch with ``drift_reference=25`` (its tracks,
and the same stand-in TPS on them); a diagnostic that matches frame 0's outline directly onto
frame h's with ``pymodal.match`` (no chaining; + TPS for points and region); and references that
are no method: the node of frame h nearest the truth (the ceiling of any node-valued tracker),
the true motion rounded to the nearest node at every step (what rounding alone does to a chained
node tracker), and the exact map with the region moved by 0.3 sensel (how much force a small
misplacement of the cut costs).

**Dense optical flow** (the tool an image-analysis user reaches for first), frame to frame and
chained: a point moves by the flow of its frame, bilinearly interpolated at its position.
scikit-image ``optical_flow_tvl1`` (its defaults) on the native grid; OpenCV DIS (medium preset)
and Farnebäck (pyramid 0.5, 3 levels, window 15) on frames upsampled 4x (bicubic), when
``opencv-python-headless`` is installed. Every flow sees sqrt(pressure / the sequence's peak)
(compressing the range: chosen on the tuning cases, where it beat linear intensities for all
three; upsampling helped DIS and Farnebäck and cost TV-L1 3x for little).

Tables give, per method and horizon, the mean share over the cases, then the 5th percentile
(linear interpolation between cases) and the worst case. The full run (12 cases) takes about six
minutes on 2 cores; ``--quick`` runs one tuning and one held-out case with the default rows only
(no control, CPD, drift_reference or diagnostic), well under a minute. Needs numpy, scipy,
scikit-image and pycpd (opencv-python-headless optional).

**Frame rate and stride** (``--rate HZ --every 1,auto``): the same 0.75 s stances rendered at
``HZ`` (round(0.75 HZ) frames past frame 0 unless ``--frames`` is given), run by
``pymodal.run(frames, pitch_mm=5, frame_rate=HZ, units="kPa", every=N)`` once per stride given
(a stride ``auto`` is the run's default, left out of the call), pedomatch's rows only (its node
tracks and material points) on the tuning and held-out cases. Horizons are the 200 Hz run's
times (0.125, 0.25, 0.5, 0.75 s), each at the last frame at or before it that every stride
compared keeps. A table per case follows the summary tables, with each run's CPU time.
"""

import os

for _v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")  # pycpd's BLAS threads would otherwise fight pedomatch's pool

import argparse  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from scipy import ndimage  # noqa: E402
from scipy.interpolate import RBFInterpolator  # noqa: E402
from scipy.spatial import cKDTree  # noqa: E402
from skimage.measure import points_in_poly  # noqa: E402
from skimage.registration import optical_flow_tvl1  # noqa: E402

import pymodal  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from stance import Stance  # noqa: E402

try:
    import cv2  # noqa: E402
except ImportError:  # optional
    cv2 = None

HORIZONS = (25, 50, 100, 150)
PITCH_MM, FRAME_RATE = 5.0, 200.0
# The horizons' times (s) and the stance's length: HORIZONS at FRAME_RATE.
HORIZON_S = tuple(h / FRAME_RATE for h in HORIZONS)
STANCE_S = 0.75
MATCH_RATE_HZ = 250.0  # pedomatch's every="auto": the smallest N with rate / N <= this
GROUPS = {
    "tuning": [dict(law=law, seed=seed) for law in (0, 1) for seed in (0, 1)],
    "held out": [dict(law=law, seed=seed) for law in (2, 3) for seed in (2, 3)],
    "control (held out, no roll-over)": [dict(law=law, seed=seed, roll=False)
                                         for law in (2, 3) for seed in (2, 3)],
}
TPS_LABEL = "pedomatch tracks + TPS (stand-in)"
POINTS_LABEL = "pedomatch points (defaults: anchored registration)"
POINTS_TPS_LABEL = "pedomatch points + TPS (stand-in for seeded points)"
DIRECT_LABEL = "diagnostic: pymodal.match(frame 0, frame h), no chaining"
CHAIN_LABEL = "reference: true motion, rounded to a node at every step"
SHIFT_LABEL = "reference: true map, region moved 0.3 sensel heelwards"
REGIONS_LABEL = "pedomatch regions= (the mask followed by the run)"
FIXED_LABEL = "pedomatch regions= fixed rows (the mask not followed)"


# ---- pedomatch ------------------------------------------------------------------------------

def outline_objects(result):
    """The outline followed in each frame (its largest object): {frame: object dict}."""
    best = {}
    for o in result["objects"]:
        f = o["frame"]
        if f not in best or len(o["points"]) > len(best[f]["points"]):
            best[f] = o
    return best


def pedomatch_outline_positions(result, obj0, n_frames):
    """Every node of frame 0's outline followed by its track: (T, n, 2), NaN once ended."""
    nodes = np.asarray(obj0["points"])[:, :2]
    pos = np.full((n_frames, len(nodes), 2), np.nan)
    for track, steps in zip(result["tracks"], result["track_steps"]):
        if len(steps) and steps[0, 0] == obj0["id"]:
            frames = track[:, 0].astype(int)
            pos[frames, steps[0, 1]] = track[:, 1:3]
    return pos


def pedomatch_point_positions(result, obj0, n_frames):
    """Every node of frame 0's outline followed as a material point (the run's ``points``,
    anchored registration): (T, n, 2), NaN once ended or when the run has no points."""
    nodes = np.asarray(obj0["points"])[:, :2]
    pos = np.full((n_frames, len(nodes), 2), np.nan)
    for pts, steps in zip(result.get("points", []), result.get("point_steps", [])):
        if len(steps) and steps[0, 0] == obj0["id"] and steps[0, 1] >= 0:
            frames = pts[:, 0].astype(int)
            pos[frames, steps[0, 1]] = pts[:, 1:3]
    return pos


def pedomatch_field(result, points):
    """HOOK (the dense field): carry frame-0 points through every frame with pedomatch's own
    dense correspondence field. Takes the run result and (n, 2) frame-0 points (x, y in
    sensels); returns (T, n, 2) carried positions (NaN where the chain of pairs breaks), or None
    while pymodal has no field.

    Assumes the field will be ``Match.warp(points)``, mapping points of a pair's first object
    into the second's frame, and composes it pair by pair along the outline's chain. Adapt here
    when the API lands (e.g. a run-level ``result["warp"](points, frame)`` or a re-anchored
    composition), and the benchmark prints a "pedomatch field" row without further change.
    """
    if not hasattr(pymodal.Match, "warp"):
        return None
    objs = outline_objects(result)
    n_frames = max(objs) + 1
    by_pair = {(r["id_a"], r["id_b"]): m for r, m in zip(result["table"], result["matches"])}
    out = np.full((n_frames, len(points), 2), np.nan)
    p = np.asarray(points, float)
    out[0] = p
    for t in range(n_frames - 1):
        m = by_pair.get((objs[t]["id"], objs.get(t + 1, {}).get("id")))
        if m is None:
            break
        p = np.asarray(m.warp(p))[:, :2]
        out[t + 1] = p
    return out


def tracks_tps(track_pos, points, smoothing=0.0):
    """STAND-IN for the field: per frame, a thin-plate spline from the frame-0 positions of the
    outline tracks alive at that frame to their positions there, applied to the points."""
    start = track_pos[0]
    out = np.full((len(track_pos), len(points), 2), np.nan)
    for t in range(len(track_pos)):
        alive = np.isfinite(track_pos[t, :, 0]) & np.isfinite(start[:, 0])
        if alive.sum() < 6:
            break
        tps = RBFInterpolator(start[alive], track_pos[t, alive], kernel="thin_plate_spline",
                              smoothing=smoothing)
        out[t] = tps(points)
    return out


# ---- outline baselines ------------------------------------------------------------------------

def nn_step(a, b):
    """For each node of a, the index of the nearest node of b."""
    return cKDTree(b).query(a)[1]


def cpd_step(a, b):
    """For each node of a, its most probable partner in b after pycpd rigid, then deformable."""
    from pycpd import DeformableRegistration, RigidRegistration

    ty, _ = RigidRegistration(X=b, Y=a).register()
    reg = DeformableRegistration(X=b, Y=ty)
    reg.register()
    return np.argmax(reg.P, axis=1)


def chained(outlines, n_frames, step):
    """Chains `step` frame to frame from every node of frame 0 (NaN after a missing outline)."""
    start = outlines[0]
    pos = np.full((n_frames, len(start), 2), np.nan)
    idx = np.arange(len(start))
    pos[0] = start
    for t in range(n_frames - 1):
        if t + 1 not in outlines:
            break
        idx = step(outlines[t], outlines[t + 1])[idx]
        pos[t + 1] = outlines[t + 1][idx]
    return pos


# ---- dense optical flow -------------------------------------------------------------------------

def _up(img, k):
    return img if k == 1 else cv2.resize(img, None, fx=k, fy=k, interpolation=cv2.INTER_CUBIC)


def _u8(img):
    return np.clip(img * 255.0, 0, 255).astype(np.uint8)


def flow_tvl1(a, b):
    v, u = optical_flow_tvl1(a, b)
    return np.stack([u, v], -1)


def flow_dis(a, b, k=4):
    dis = cv2.DISOpticalFlow_create(cv2.DISOPTICAL_FLOW_PRESET_MEDIUM)
    return dis.calc(_u8(_up(a, k)), _u8(_up(b, k)), None)


def flow_farneback(a, b, k=4):
    return cv2.calcOpticalFlowFarneback(_u8(_up(a, k)), _u8(_up(b, k)), None, 0.5, 3, 15, 3, 5, 1.2, 0)


def flow_methods():
    """(label, flow(a, b) on images in [0, 1] -> (H*k, W*k, 2) (dx, dy) in upsampled pixels, k)."""
    out = [("chained TV-L1 (scikit-image)", flow_tvl1, 1)]
    if cv2 is not None:
        out += [("chained DIS (OpenCV, 4x)", flow_dis, 4), ("chained Farnebäck (OpenCV, 4x)", flow_farneback, 4)]
    return out


def carry_by_flow(frames, points, flow, k):
    """Chains a dense flow frame to frame from frame-0 points: (T, n, 2)."""
    img = np.sqrt(np.clip(frames, 0, None) / frames.max()).astype(np.float32)
    p = np.asarray(points, float).copy()
    out = np.empty((len(frames), len(p), 2))
    out[0] = p
    for t in range(len(frames) - 1):
        f = flow(img[t], img[t + 1])
        c = [p[:, 1] * k + (k - 1) / 2.0, p[:, 0] * k + (k - 1) / 2.0]  # sensel centre -> pixel
        d = [ndimage.map_coordinates(f[..., i], c, order=1, mode="nearest") for i in (0, 1)]
        p = p + np.stack(d, 1) / k
        out[t + 1] = p
    return out


# ---- the region -------------------------------------------------------------------------------

def clip_below(poly, y_cut, step=0.5):
    """The part of a closed polygon with y < y_cut (Sutherland-Hodgman), every edge sampled at
    least every `step` sensels so that a carried cut bends with the field."""
    out = []
    n = len(poly)
    for i in range(n):
        p, q = poly[i], poly[(i + 1) % n]
        pin, qin = p[1] < y_cut, q[1] < y_cut
        if pin:
            out.append(p)
        if pin != qin:
            s = (y_cut - p[1]) / (q[1] - p[1])
            out.append(p + s * (q - p))
    dense = []
    for i in range(len(out)):
        p, q = out[i], out[(i + 1) % len(out)]
        m = max(1, int(np.ceil(np.linalg.norm(q - p) / step)))
        dense.extend(p + (q - p) * j / m for j in range(m))
    return np.array(dense)


def region_mask(frames):
    """The forefoot third of frame 0's contact region as a label mask (1 = the region) and the
    cut line: the contact sensels above it."""
    ys = np.nonzero(frames[0] > 0)[0]
    y_cut = np.floor(np.quantile(ys, 1.0 / 3.0)) + 0.5
    rows = np.arange(frames[0].shape[0])[:, None]
    return ((frames[0] > 0) & (rows < y_cut)).astype(np.int32), y_cut


def regions_forces(result, kind, n_frames):
    """The region's force per frame as pymodal.run's ``regions`` rows give it (N), in the
    truth's units (kPa x sensels); NaN on a frame without a row."""
    out = np.full(n_frames, np.nan)
    for row in result["region_series"]:
        if row["kind"] == kind:
            out[row["frame"]] = row["total_force_n"] / (PITCH_MM * PITCH_MM * 1e-3)
    return out


# Each sensel's share inside a region is counted on SUB x SUB points spread over the sensel: the
# region's force is each sensel's value times the share of it the region covers (as pedomatch's
# moving regions count it), so that a region moved by a tenth of a sensel changes by a tenth of
# its edge sensels, not by whole sensels switching in or out.
SUB = 8


def sensel_subpoints(st):
    """(SUB * SUB, sensels, 2): SUB x SUB points spread evenly over every sensel."""
    pix = st.pixel_centres()
    o = (np.arange(SUB) + 0.5) / SUB - 0.5
    return np.stack([pix + [dx, dy] for dy in o for dx in o])


def region_setup(st, frames, y_cut):
    """The forefoot third of frame 0's contact region: its polygon and true forces (each
    sensel's value times the share of it whose material point lies in the region)."""
    contour = max(pymodal.contours(frames[0], spacing=0.5), key=len)
    poly = clip_below(contour, y_cut)
    sub = sensel_subpoints(st)
    true = np.array([
        (frames[t].ravel() * np.mean([st.reference_positions(t, q)[:, 1] < y_cut for q in sub], 0)).sum()
        for t in range(len(frames))])
    return poly, sub, true


def region_forces(frames, sub, polys):
    """Force (kPa x sensels) inside each frame's polygon, each sensel by the share of it the
    polygon covers: polys (T, m, 2)."""
    out = np.full(len(frames), np.nan)
    n = sub.shape[1]
    for t, poly in enumerate(polys):
        if np.isfinite(poly).all():
            share = points_in_poly(sub.reshape(-1, 2), poly).reshape(-1, n).mean(0)
            out[t] = (frames[t].ravel() * share).sum()
    return out


# ---- one case ---------------------------------------------------------------------------------

def within(pos, truth, tol=1.0):
    """Share of points within tol of the truth per horizon (NaN positions count as lost)."""
    out = {}
    for h in HORIZONS:
        if h < len(pos):
            err = np.linalg.norm(pos[h] - truth[h], axis=1)
            out[h] = float(np.mean(np.nan_to_num(err, nan=np.inf) <= tol))
    return out


def run_case(spec, n_frames, grid, cpd, extra, tps_smoothing, log):
    st = Stance(frames=n_frames, **spec)
    frames = st.frames
    T = len(frames)
    rec = dict(describe=st.describe(), outline={}, interior={}, region={}, seconds={})

    # The forefoot third as a mask of frame 0, given to the run: pedomatch follows it itself.
    mask, y_cut = region_mask(frames)
    t0 = time.perf_counter()
    result = pymodal.run(frames, pitch_mm=PITCH_MM, frame_rate=FRAME_RATE, units="kPa", regions=mask)
    rec["seconds"]["pedomatch run (regions=mask)"] = time.perf_counter() - t0
    objs = outline_objects(result)
    outlines = {f: np.asarray(o["points"])[:, :2] for f, o in objs.items()}
    nodes0 = outlines[0]
    spacing = float(result["summary"]["options"]["spacing"])
    truth_nodes = np.array([st.true_positions(t, nodes0) for t in range(T)])

    inside = np.argwhere(frames[0] > 0)
    inside = inside[(inside[:, 0] % grid == 0) & (inside[:, 1] % grid == 0)]
    interior = inside[:, ::-1].astype(float)
    truth_int = np.array([st.true_positions(t, interior) for t in range(T)])
    poly, sub, true_force = region_setup(st, frames, y_cut)
    rec["region"]["static frame-0 mask"] = region_forces(frames, sub, [poly] * T)
    rec["region"][REGIONS_LABEL] = regions_forces(result, "moving", T)
    rec["region"][FIXED_LABEL] = regions_forces(result, "fixed", T)
    # How sensitive the force is to the region's placement: the exact map, off by 0.3 sensel.
    rec["region"][SHIFT_LABEL] = region_forces(
        frames, sub, [st.true_positions(t, poly) + [0.0, 0.3] for t in range(T)])
    rec["n"] = dict(nodes=len(nodes0), interior=len(interior), objects_per_frame=len(result["objects"]) / T)

    # Ceiling for node-to-node trackers: the nearest node of frame h to the truth.
    ceil = np.full_like(truth_nodes, np.nan)
    for t in range(T):
        if t in outlines:
            ceil[t] = outlines[t][cKDTree(outlines[t]).query(truth_nodes[t])[1]]
    rec["outline"]["ceiling: nearest node of frame h to the truth"] = within(ceil, truth_nodes, spacing)

    # Reference for chained node-to-node trackers: the true motion, each step rounded to the node
    # nearest the true image of the node before (not a ceiling: another rounding can do better).
    idx = np.arange(len(nodes0))
    cchain = np.full_like(truth_nodes, np.nan)
    cchain[0] = nodes0
    for t in range(T - 1):
        if t + 1 not in outlines:
            break
        img = st.true_positions(t + 1, st.reference_positions(t, outlines[t]))
        idx = cKDTree(outlines[t + 1]).query(img)[1][idx]
        cchain[t + 1] = outlines[t + 1][idx]
    rec["outline"][CHAIN_LABEL] = within(
        cchain, truth_nodes, spacing)

    dense_pts = np.vstack([interior, poly])
    n_int = len(interior)

    def pedomatch_rows(label, res, tps_label):
        pos = pedomatch_outline_positions(res, outline_objects(res)[0], T)
        rec["outline"][label] = within(pos, truth_nodes, spacing)
        t1 = time.perf_counter()
        tps = tracks_tps(pos, dense_pts, tps_smoothing)
        rec["seconds"][tps_label] = time.perf_counter() - t1
        rec["interior"][tps_label] = within(tps[:, :n_int], truth_int)
        rec["region"][tps_label] = region_forces(frames, sub, tps[:, n_int:])
        return pos

    track_pos = pedomatch_rows("pedomatch tracks (defaults)", result, TPS_LABEL)
    rec["alive"] = {h: float(np.isfinite(track_pos[h, :, 0]).mean()) for h in HORIZONS if h < T}
    point_pos = pedomatch_point_positions(result, objs[0], T)
    if np.isfinite(point_pos[1:]).any():
        rec["outline"][POINTS_LABEL] = within(point_pos, truth_nodes, spacing)
        tps = tracks_tps(point_pos, dense_pts, tps_smoothing)
        rec["interior"][POINTS_TPS_LABEL] = within(tps[:, :n_int], truth_int)
        rec["region"][POINTS_TPS_LABEL] = region_forces(frames, sub, tps[:, n_int:])
    field = pedomatch_field(result, dense_pts)
    if field is not None:
        rec["interior"]["pedomatch field"] = within(field[:, :n_int], truth_int)
        rec["region"]["pedomatch field"] = region_forces(frames, sub, field[:, n_int:])
    if extra:
        t0 = time.perf_counter()
        res25 = pymodal.run(frames, pitch_mm=PITCH_MM, frame_rate=FRAME_RATE, units="kPa", drift_reference=25)
        rec["seconds"]["pedomatch run, drift_reference=25"] = time.perf_counter() - t0
        pedomatch_rows("pedomatch tracks, drift_reference=25 (not the default)", res25,
                       "pedomatch drift_reference=25 tracks + TPS (stand-in)")
        # Anchored, no chaining: frame 0's outline matched directly onto frame t's.
        t0 = time.perf_counter()
        direct = np.full((T, len(nodes0), 2), np.nan)
        dtps = np.full((T, len(dense_pts), 2), np.nan)
        direct[0], dtps[0] = nodes0, dense_pts
        for t in range(1, T):
            if t not in outlines:
                continue
            m = pymodal.match(nodes0, outlines[t])
            pr = m.pairs[~m.excess]
            direct[t, pr[:, 0]] = outlines[t][pr[:, 1]]
            dtps[t] = RBFInterpolator(nodes0[pr[:, 0]], outlines[t][pr[:, 1]], kernel="thin_plate_spline",
                                      smoothing=tps_smoothing)(dense_pts)
        rec["seconds"]["direct pymodal.match 0 -> t (+ TPS)"] = time.perf_counter() - t0
        rec["outline"][DIRECT_LABEL] = within(direct, truth_nodes, spacing)
        rec["interior"][DIRECT_LABEL + " + TPS"] = within(dtps[:, :n_int], truth_int)
        rec["region"][DIRECT_LABEL + " + TPS"] = region_forces(frames, sub, dtps[:, n_int:])

    t0 = time.perf_counter()
    rec["outline"]["chained nearest neighbour"] = within(chained(outlines, T, nn_step), truth_nodes, spacing)
    rec["seconds"]["chained nearest neighbour"] = time.perf_counter() - t0
    if cpd:
        t0 = time.perf_counter()
        rec["outline"]["chained CPD (pycpd rigid + deformable)"] = within(
            chained(outlines, T, cpd_step), truth_nodes, spacing)
        rec["seconds"]["chained CPD (pycpd rigid + deformable)"] = time.perf_counter() - t0

    allpts = np.vstack([nodes0, interior, poly])
    a, b = len(nodes0), len(nodes0) + len(interior)
    for label, flow, k in flow_methods():
        t0 = time.perf_counter()
        pos = carry_by_flow(frames, allpts, flow, k)
        rec["seconds"][label] = time.perf_counter() - t0
        rec["outline"][label] = within(pos[:, :a], truth_nodes, spacing)
        rec["interior"][label] = within(pos[:, a:b], truth_int)
        rec["region"][label] = region_forces(frames, sub, pos[:, b:])

    rec["region_frames"] = {}
    for key, forces in list(rec["region"].items()):
        rel = np.abs(forces - true_force) / true_force
        rec["region_frames"][key] = rel
        rec["region"][key] = (float(np.nanmax(np.nan_to_num(rel, nan=np.inf))), float(np.nanmean(rel)))
    log(f"  {rec['describe']}: {rec['n']['nodes']} outline nodes, {rec['n']['interior']} interior points; "
        + ", ".join(f"{k} {v:.1f} s" for k, v in rec["seconds"].items()))
    return rec


# ---- frame rate and stride ---------------------------------------------------------------------

def auto_stride(rate):
    """The stride ``every="auto"`` resolves to at ``rate`` (pedo_track::FrameStride::resolve)."""
    return max(1, int(np.ceil(rate / MATCH_RATE_HZ - 1e-9)))


def stride_horizons(rate, strides, n_frames):
    """The horizons' frames at ``rate``: each HORIZON_S time, at the last frame at or before it
    that every stride in ``strides`` keeps (frames 0, N, 2N...)."""
    step = int(np.lcm.reduce([auto_stride(rate) if s == "auto" else int(s) for s in strides]))
    hs = [int(np.floor(t * rate + 1e-9)) // step * step for t in HORIZON_S]
    return tuple(h for h in hs if 0 < h < n_frames)


WINDOW_S = 0.025  # the window before each horizon over which the share is averaged


def within_window(pos, truth, tol, step, rate):
    """Per horizon, the share within tol averaged over the frames of the WINDOW_S before it
    that every stride keeps (multiples of step), the horizon's frame included; and over every
    such frame of the stance past frame 0 ("all")."""
    def share(t):
        err = np.linalg.norm(pos[t] - truth[t], axis=1)
        return float(np.mean(np.nan_to_num(err, nan=np.inf) <= tol))
    width = int(round(WINDOW_S * rate))
    out = {h: float(np.mean([share(t) for t in range(h, max(0, h - width - 1), -step) if t > 0]))
           for h in HORIZONS}
    out["all"] = float(np.mean([share(t) for t in range(step, len(pos), step)]))
    return out


def run_strides(spec, n_frames, rate, strides, log):
    """pedomatch's node tracks and material points at each stride, against the truth."""
    st = Stance(frames=n_frames, frame_rate=rate, **spec)
    frames = st.frames
    T = len(frames)
    rec = dict(describe=st.describe(), outline={}, window={}, seconds={}, cpu={})
    step = int(np.lcm.reduce([auto_stride(rate) if s == "auto" else int(s) for s in strides]))
    nodes0 = truth_nodes = None
    for every in strides:
        kw = {} if every == "auto" else dict(every=int(every))
        label = f"every={every}" + (f" ({auto_stride(rate)})" if every == "auto" else "")
        t0, c0 = time.perf_counter(), time.process_time()
        result = pymodal.run(frames, pitch_mm=PITCH_MM, frame_rate=rate, units="kPa", **kw)
        rec["seconds"][label] = time.perf_counter() - t0
        rec["cpu"][label] = time.process_time() - c0
        obj0 = outline_objects(result)[0]
        if nodes0 is None:
            nodes0 = np.asarray(obj0["points"])[:, :2]
            truth_nodes = np.array([st.true_positions(t, nodes0) for t in range(T)])
            spacing = float(result["summary"]["options"]["spacing"])
        else:  # every stride runs frame 0 alike
            assert np.array_equal(nodes0, np.asarray(obj0["points"])[:, :2])
        tracks = pedomatch_outline_positions(result, obj0, T)
        rec["outline"][f"pedomatch tracks, {label}"] = within(tracks, truth_nodes, spacing)
        points = pedomatch_point_positions(result, obj0, T)
        rec["outline"][f"pedomatch points, {label}"] = within(points, truth_nodes, spacing)
        rec["window"][f"pedomatch tracks, {label}"] = within_window(tracks, truth_nodes, spacing, step, rate)
        rec["window"][f"pedomatch points, {label}"] = within_window(points, truth_nodes, spacing, step, rate)
    rec["n"] = dict(nodes=len(nodes0))
    log(f"  {rec['describe']}: {len(nodes0)} outline nodes; "
        + ", ".join(f"{k} {v:.1f} s CPU" for k, v in rec["cpu"].items()))
    return rec


def strides_main(a, log):
    """``--every``: pedomatch's rows at each stride on the tuning and held-out cases."""
    global HORIZONS
    strides = [s.strip() for s in a.every.split(",")]
    for s in strides:
        if s != "auto" and not (s.isdigit() and int(s) >= 1):
            raise SystemExit(f"--every: auto or an integer >= 1, got {s!r}")
    frames = a.frames if a.frames is not None else int(round(STANCE_S * a.rate))
    n_frames = frames + 1
    HORIZONS = stride_horizons(a.rate, strides, n_frames)
    groups = {k: GROUPS[k] for k in ("tuning", "held out")}
    if a.quick:
        groups = {k: v[:1] for k, v in groups.items()}
    t_all = time.perf_counter()
    results = {}
    for name, specs in groups.items():
        log(f"{name}:")
        results[name] = [run_strides(s, n_frames, a.rate, strides, log) for s in specs]
    total = time.perf_counter() - t_all
    hz = ", ".join(f"{h} ({h / a.rate:.3f} s)" for h in HORIZONS)
    print(f"Synthetic stances (stance.py): {frames} frames past frame 0 at {a.rate:g} Hz, "
          f"{PITCH_MM:g} mm sensels; pedomatch {getattr(pymodal, '__version__', '?')}, default "
          f"options but the stride: every = {', '.join(strides)}. Horizons (frames): {hz}.")
    print("Outline nodes of frame 0 within one node spacing (1 sensel) of their material point, %; "
          "cells: mean over the cases / 5th percentile / worst case.\n")
    for name, recs in results.items():
        print(f"### {name}: {len(recs)} case{'s' if len(recs) > 1 else ''}\n")
        share_table(recs, "outline", a.markdown)
    width = int(round(WINDOW_S * a.rate))
    print(f"The same, each horizon's share averaged over the frames of the {1000 * WINDOW_S:g} ms before it "
          f"(the horizon's frame and those of the {width} frames before it that every stride keeps), and over every "
          "such frame of the stance (\"all\"): the share at one frame swings by tens of % from one "
          "frame to the next, for every stride.\n")
    for name, recs in results.items():
        print(f"### {name}: {len(recs)} case{'s' if len(recs) > 1 else ''}, windows\n")
        methods = list(dict.fromkeys(m for r in recs for m in r["window"]))
        cols = list(HORIZONS) + ["all"]
        rows = [[m] + [stat_cell([r["window"][m][h] for r in recs]) for h in cols] for m in methods]
        print_table(["method"] + [f"before {h}" for h in HORIZONS] + ["all frames"], rows, a.markdown)
    print("Per case (one number per horizon, %; CPU time of the run):\n")
    rows = []
    for name, recs in results.items():
        for r in recs:
            for m, v in r["outline"].items():
                lbl = m.split(", ", 1)[1]
                rows.append([f"{name}: {r['describe'].split(':')[0]}", m.split(",")[0].replace("pedomatch ", ""),
                             lbl] + [f"{100 * v[h]:.1f}" for h in HORIZONS]
                            + [f"{r['cpu'][lbl]:.1f}"])
    print_table(["case", "rows", "stride"] + [f"after {h}" for h in HORIZONS] + ["CPU s"], rows, a.markdown)
    print("Per case, the windows (%):\n")
    rows = []
    for name, recs in results.items():
        for r in recs:
            for m, v in r["window"].items():
                rows.append([f"{name}: {r['describe'].split(':')[0]}", m.split(",")[0].replace("pedomatch ", ""),
                             m.split(", ", 1)[1]] + [f"{100 * v[h]:.1f}" for h in list(HORIZONS) + ["all"]])
    print_table(["case", "rows", "stride"] + [f"before {h}" for h in HORIZONS] + ["all frames"], rows,
                a.markdown)
    cpu = {}
    for recs in results.values():
        for r in recs:
            for k, v in r["cpu"].items():
                cpu.setdefault(k, []).append(v)
    print("CPU time of the runs, all cases: " + ", ".join(f"{k} {np.sum(v):.1f} s" for k, v in cpu.items()))
    print(f"Total time {total:.0f} s.")


# ---- tables -------------------------------------------------------------------------------------

def print_table(head, rows, markdown):
    if markdown:
        print("| " + " | ".join(head) + " |")
        print("|---|" + "---:|" * (len(head) - 1))
        for r in rows:
            print("| " + " | ".join(r) + " |")
    else:
        w = [max(len(str(x)) for x in col) for col in zip(head, *rows)]
        for r in [head] + rows:
            print("  ".join(str(x).ljust(n) if i == 0 else str(x).rjust(n) for i, (x, n) in enumerate(zip(r, w))))
    print()


def order(methods):
    """pedomatch's default rows first, then the baselines, then options, diagnostics, ceilings."""
    def key(m):
        if m.startswith("ceiling") or m.startswith("reference"):
            return 4
        if "not the default" in m or "drift_reference" in m or m.startswith("diagnostic"):
            return 3
        if m.startswith("pedomatch") or m.startswith("static"):
            return 0 if "field" not in m else 1
        return 2
    return sorted(methods, key=key)


def stat_cell(values):
    """Mean / 5th percentile / worst case of shares, in %."""
    v = np.asarray(values, float)
    f = lambda x: f"{100 * x:.1f}"  # noqa: E731
    if len(v) == 1:
        return f(v[0])
    return f"{f(v.mean())} / {f(np.percentile(v, 5))} / {f(v.min())}"


def share_table(recs, key, markdown, extra=None):
    methods = order(dict.fromkeys(m for r in recs for m in r[key]))
    hs = [h for h in HORIZONS if all(h in r[key][m] for r in recs for m in r[key])]
    rows = []
    for m in methods:
        rows.append([m] + [stat_cell([r[key][m][h] for r in recs if m in r[key]]) for h in hs])
    if extra:
        rows.insert(1, extra(hs))  # beside the row it qualifies
    head = ["method"] + [f"after {h}" for h in hs]
    print_table(head, rows, markdown)


def region_table(recs, markdown):
    methods = order(dict.fromkeys(m for r in recs for m in r["region"]))
    rows = []
    for m in methods:
        mx = [r["region"][m][0] for r in recs if m in r["region"]]
        mean = [r["region"][m][1] for r in recs if m in r["region"]]
        one = len(mx) == 1
        rows.append([m, f"{100 * np.mean(mx):.1f}" if one else f"{100 * np.mean(mx):.1f} / {100 * np.max(mx):.1f}",
                     f"{100 * np.mean(mean):.1f}" if one else f"{100 * np.mean(mean):.1f} / {100 * np.max(mean):.1f}"])
    several = len(recs) > 1
    head = ["region carried by",
            "largest relative force error over frames, %" + (" (mean / worst case)" if several else ""),
            "mean relative force error over frames, %" + (" (mean / worst case)" if several else "")]
    print_table(head, rows, markdown)


def frame_error_table(recs, markdown):
    rows = []
    for m in (REGIONS_LABEL, FIXED_LABEL, "static frame-0 mask", TPS_LABEL):
        rel = np.concatenate([r["region_frames"][m] for r in recs if m in r["region_frames"]])
        rel = np.nan_to_num(rel, nan=np.inf)
        rows.append([m, f"{100 * np.mean(rel):.2f}", f"{100 * np.percentile(rel, 95):.2f}",
                     f"{100 * np.max(rel):.2f}", f"{100 * np.mean(rel <= 0.05):.1f}"])
    print_table(["region", "mean", "95th pct", "worst", "frames within 5 %"], rows, markdown)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--frames", type=int, default=None,
                    help="frames past frame 0 (default 150: round(0.75 s x the rate))")
    ap.add_argument("--rate", type=float, default=FRAME_RATE,
                    help="frame rate (Hz) of the frames rendered over the 0.75 s stance (default 200)")
    ap.add_argument("--every", default=None, metavar="N,...",
                    help="compare pedomatch at these strides (e.g. 1,auto): its rows only, tuning and "
                         "held-out cases, horizons at the 200 Hz run's times")
    ap.add_argument("--quick", action="store_true",
                    help="one tuning and one held-out case, no control, no CPD (< 2 minutes)")
    ap.add_argument("--markdown", action="store_true")
    ap.add_argument("--grid", type=int, default=1, choices=(1, 2), help="interior grid spacing (sensels)")
    ap.add_argument("--no-cpd", action="store_true", help="leave chained CPD out")
    ap.add_argument("--no-control", action="store_true", help="leave the no-roll-over control out")
    ap.add_argument("--tps-smoothing", type=float, default=300.0,
                    help="smoothing of the stand-in's thin-plate spline (chosen on the tuning cases)")
    a = ap.parse_args()
    log = lambda s: print(s, file=sys.stderr, flush=True)  # noqa: E731
    if a.every is not None:
        return strides_main(a, log)
    if a.rate != FRAME_RATE:
        raise SystemExit("--rate: the full comparison runs at 200 Hz; give --every to compare strides")
    if a.frames is None:
        a.frames = HORIZONS[-1]
    groups = dict(GROUPS)
    if a.quick:
        groups = {"tuning": groups["tuning"][:1], "held out": groups["held out"][:1]}
    elif a.no_control:
        groups.pop("control (held out, no roll-over)")
    cpd = not (a.quick or a.no_cpd)
    extra = not a.quick
    n_frames = a.frames + 1

    t_all = time.perf_counter()
    results = {}
    for name, specs in groups.items():
        log(f"{name}:")
        results[name] = [run_case(s, n_frames, a.grid, cpd, extra, a.tps_smoothing, log) for s in specs]
    total = time.perf_counter() - t_all

    flows = ", ".join(lbl for lbl, _f, _k in flow_methods())
    print(f"Synthetic stances (stance.py): {a.frames} frames past frame 0 at {FRAME_RATE:g} Hz, "
          f"{PITCH_MM:g} mm sensels; pedomatch {getattr(pymodal, '__version__', '?')} with the default "
          f"options (contour model, spacing 1 sensel); dense flows: {flows}; "
          f"interior grid spacing {a.grid} sensel{'s' if a.grid > 1 else ''}.")
    print("Cells: mean over the cases / 5th percentile / worst case, in % (one number: one case).\n")
    for name, recs in results.items():
        print(f"### {name}: {len(recs)} case{'s' if len(recs) > 1 else ''}\n")
        for r in recs:
            print(f"- {r['describe']}: {r['n']['nodes']} outline nodes, {r['n']['interior']} interior points")
        print()
        print("**Outline nodes** within one node spacing (1 sensel) of their material point, %:\n")
        share_table(recs, "outline", a.markdown, extra=lambda hs: (
            ["(pedomatch tracks alive)"] + [stat_cell([r["alive"][h] for r in recs]) for h in hs]))
        print("**Interior points** within one sensel of their material point, %:\n")
        share_table(recs, "interior", a.markdown)
        print("**Forefoot third** carried through the stance: force against the true region's:\n")
        region_table(recs, a.markdown)
        print("Per-frame relative force error over every frame of every case, %"
              " (mean / 95th percentile / worst; target: within 5 % at every frame):\n")
        frame_error_table(recs, a.markdown)
        secs = {}
        for r in recs:
            for k, v in r["seconds"].items():
                secs.setdefault(k, []).append(v)
        print("Seconds per case (mean): " + ", ".join(f"{k} {np.mean(v):.1f}" for k, v in secs.items()) + "\n")
    if not any("pedomatch field" in r["interior"] for rs in results.values() for r in rs):
        print("pedomatch field: not available yet (no Match.warp); interior points and the region use the "
              f"stand-in \"{TPS_LABEL}\", which is not the product.")
    print(f"Total time {total:.0f} s.")


if __name__ == "__main__":
    main()
