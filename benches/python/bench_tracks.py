"""Do node tracks stay on the material? Per real recording, the share of track steps (a node
followed from one frame to the next, tracks.csv) longer than 3 sensels, beside the share of
contour nodes lying more than 3 sensels from the next frame's contour (how far the pressure
boundary itself moves). A track that moves no further than the boundary does has no reason to
jump; the target is first <= max(second, 2 %). Also printed: the share of steps longer than 10
sensels, the longest step, the pairs with such a jump, the mean optimisation percentage of
the ordinary pairs (one-to-one continuations outside merges and splits, node counts within 30 %)
- which a fix of the jumps must leave unchanged - and the pairs left unmatched (with a reason).

Recordings: the bundled F-Scan walk (examples/data/FrasP01L.asf, 31.25 Hz) and every recording
in benches/data (emed, pedar, footscan at 100-500 Hz; see benches/data/README.md: the three
MIT-licensed files are committed, the GPLv3 Pataky file is written by make_recordings.py and used
when present). High-rate recordings are also run at 100 Hz (every k-th frame) so
that the frame-to-frame motion is comparable.

The object model is the run's (`--option model=surface`, `model=isocontour`):
- contours: the boundary is the objects themselves;
- surfaces: the boundary is the contact outline of each frame (`pymodal.contours` at the run's
  noise threshold, 1 sensel spacing), not the surface's nodes;
- isocontours: the steps are from level to level of the one frame, and the boundary's motion is
  how far each level's line lies from the next level's.
"steps beyond the bound" checks every step against the bound of docs/method.md §9, computed
here with numpy on its own: the distance from the step's first node to the next object (its
outline; a surface's triangles, y in true sensel proportions) plus STEP_SLACK node spacings (a
surface's median edge length); between isocontour levels whose regions lie apart (fewer than
half of the smaller region's nodes inside the other's outline) no step is allowed.

Run:  python benches/python/bench_tracks.py [--data DIR] [--markdown] [--option KEY=VALUE ...]
"""
import argparse
import time
from pathlib import Path

import numpy as np

import pymodal

ROOT = Path(__file__).resolve().parents[2]
LIMIT = 3.0  # sensels
STEP_SLACK = 1.5  # node spacings (pedo_track::pairing::STEP_SLACK)


def segment_distances(p, q):
    """Distance from every point of p (n, 2) to the closed polylines in q (a list of (m, 2))."""
    best = np.full(len(p), np.inf)
    for c in q:
        a, b = c, np.roll(c, -1, 0)
        ab = b - a
        t = ((p[:, None, :] - a[None]) * ab[None]).sum(2) / np.maximum((ab ** 2).sum(1), 1e-12)[None]
        t = np.clip(t, 0.0, 1.0)
        foot = a[None] + t[:, :, None] * ab[None]
        best = np.minimum(best, np.linalg.norm(p[:, None, :] - foot, axis=2).min(1))
    return best


def boundary_motion(objects):
    """Distances from every contour node of a frame to the next frame's contours."""
    by_frame = {}
    for o in objects:
        by_frame.setdefault(o["frame"], []).append(np.asarray(o["points"])[:, :2])
    out = []
    for f, cs in by_frame.items():
        nxt = by_frame.get(f + 1)
        if nxt:
            out.append(segment_distances(np.vstack(cs), nxt))
    return np.concatenate(out) if out else np.zeros(0)


def outline_motion(rec, frames, noise):
    """Surfaces: distances from every node of a frame's contact outline to the next frame's."""
    data = np.asarray(rec.frames)
    outlines = {f: pymodal.contours(data[f], threshold=noise, spacing=1.0, include_holes=False)
                for f in sorted(set(frames))}
    out = [segment_distances(np.vstack(cs), outlines[f + 1])
           for f, cs in outlines.items() if cs and outlines.get(f + 1)]
    return np.concatenate(out) if out else np.zeros(0)


def level_motion(objects):
    """Isocontours: distances from every node of a level's line to the next level's."""
    out = [segment_distances(np.asarray(a["points"])[:, :2], [np.asarray(b["points"])[:, :2]])
           for a, b in zip(objects, objects[1:])]
    return np.concatenate(out) if out else np.zeros(0)


def track_steps(tracks):
    """Lengths of the steps between consecutive frames of every track, with the frame of each."""
    steps, frames = [], []
    for t in tracks:
        t = np.asarray(t)
        if len(t) < 2:
            continue
        d = np.linalg.norm(np.diff(t[:, 1:3], axis=0), axis=1)
        steps.append(d)
        frames.append(t[:-1, 0])
    if not steps:
        return np.zeros(0), np.zeros(0)
    return np.concatenate(steps), np.concatenate(frames)


def inside(p, poly):
    """Whether each point of p (n, 2) lies inside the closed polygon poly (m, 2)."""
    a, b = poly, np.roll(poly, -1, 0)
    crosses = (a[None, :, 1] > p[:, None, 1]) != (b[None, :, 1] > p[:, None, 1])
    with np.errstate(divide="ignore", invalid="ignore"):
        x = a[None, :, 0] + (p[:, None, 1] - a[None, :, 1]) / (b - a)[None, :, 1] * (b - a)[None, :, 0]
    return ((crosses & (p[:, None, 0] < x)).sum(1) % 2) == 1


def area(c):
    """Area enclosed by the closed polygon c (m, 2)."""
    return 0.5 * abs(np.dot(c[:, 0], np.roll(c[:, 1], -1)) - np.dot(c[:, 1], np.roll(c[:, 0], -1)))


def median(v):
    """The median as pedomatch takes it: the middle value, the upper one of an even count."""
    return float(np.sort(v)[len(v) // 2])


def median_spacing(c):
    return median(np.linalg.norm(np.roll(c, -1, 0) - c, axis=1))


def support_distance(p, tri):
    """Distance from every point of p (n, 2) to the union of the triangles tri (t, 3, 2)."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    def side(u, v):
        return (v[None, :, 0] - u[None, :, 0]) * (p[:, None, 1] - u[None, :, 1]) - \
               (v[None, :, 1] - u[None, :, 1]) * (p[:, None, 0] - u[None, :, 0])
    s1, s2, s3 = side(a, b), side(b, c), side(c, a)
    inside_any = (((s1 >= 0) & (s2 >= 0) & (s3 >= 0)) | ((s1 <= 0) & (s2 <= 0) & (s3 <= 0))).any(1)
    edges = np.concatenate([np.stack([a, b], 1), np.stack([b, c], 1), np.stack([c, a], 1)])
    u, v = edges[:, 0], edges[:, 1]
    uv = v - u
    t = ((p[:, None, :] - u[None]) * uv[None]).sum(2) / np.maximum((uv ** 2).sum(1), 1e-12)[None]
    foot = u[None] + np.clip(t, 0.0, 1.0)[:, :, None] * uv[None]
    d = np.linalg.norm(p[:, None, :] - foot, axis=2).min(1)
    return np.where(inside_any, 0.0, d)


def rebuilt_surfaces(rec, objects, noise, smooth, nodes):
    """The triangles of each surface object, rebuilt by pymodal.surface with the run's options
    (None where the rebuilt nodes are not the object's)."""
    data = np.asarray(rec.frames)
    out = {}
    for o in objects:
        s = pymodal.surface(data[o["frame"]], threshold=noise, smooth=smooth or None, max_nodes=nodes)
        pts = np.asarray(o["points"])
        same = s.points.shape == pts.shape and np.allclose(s.points, pts, atol=1e-9)
        out[o["id"]] = np.asarray(s.triangles) if same else None
    return out


def beyond_bound(out, model, rec, noise, smooth, nodes):
    """Steps of out's tracks longer than the bound of docs/method.md §9 (computed here), and the
    steps that could not be checked (a surface that could not be rebuilt)."""
    objects = out["objects"]
    pts = [np.asarray(o["points"])[:, :2] for o in objects]
    aspect = 1.0
    if model == "surface" and rec.pitch_mm:
        aspect = rec.pitch_mm[1] / rec.pitch_mm[0]
    tris = rebuilt_surfaces(rec, objects, noise, smooth, nodes) if model == "surface" else {}
    by_pair = {}
    for ts in out["track_steps"]:
        ts = np.asarray(ts)
        for (oa, na), (ob, nb) in zip(ts[:-1], ts[1:]):
            by_pair.setdefault((int(oa), int(ob)), []).append((int(na), int(nb)))
    beyond = unchecked = 0
    for (oa, ob), nodes_ab in by_pair.items():
        na, nb = np.array(nodes_ab).T
        scale = np.array([1.0, aspect])
        p, q = pts[oa][na] * scale, pts[ob][nb] * scale
        step = np.linalg.norm(q - p, axis=1)
        if model == "surface":
            t = tris.get(ob)
            if t is None:
                unchecked += len(step)
                continue
            corners = pts[ob][t] * scale
            e = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
            e = np.unique(np.sort(e, 1), axis=0)
            spacing = median(np.linalg.norm((pts[ob][e[:, 1]] - pts[ob][e[:, 0]]) * scale, axis=1))
            bound = support_distance(p, corners) + STEP_SLACK * spacing
        else:
            if model == "isocontour":
                small, large = sorted((pts[oa], pts[ob]), key=area)
                if inside(small, large).mean() < 0.5:
                    beyond += len(step)
                    continue
            bound = segment_distances(p, [pts[ob]]) + STEP_SLACK * median_spacing(pts[ob])
        beyond += int((step > bound + 1e-6).sum())
    return beyond, unchecked


def measure(path, stride=1, **options):
    """Runs a recording (every `stride`-th frame) and measures its tracks and its boundary."""
    rec = pymodal.read_recording(str(path))
    kw = dict(options)
    model = kw.get("model", "contour")
    noise = kw.get("noise", rec.noise_threshold or 0.0)
    if stride > 1:
        sub = pymodal.Recording.from_array(
            np.asarray(rec.frames)[::stride], pitch_mm=rec.pitch_mm, units=rec.units,
            frame_rate=1.0 / (rec.dt_s * stride) if rec.dt_s else None, mask=rec.sensor_mask)
        if rec.noise_threshold is not None:
            kw.setdefault("noise", rec.noise_threshold)
        rec = sub
    t0 = time.perf_counter()
    out = pymodal.run(rec if stride > 1 else str(path), **kw)
    seconds = time.perf_counter() - t0
    steps, step_frames = track_steps(out["tracks"])
    if model == "surface":
        bound = outline_motion(rec, [o["frame"] for o in out["objects"]], noise)
    elif model == "isocontour":
        bound = level_motion(out["objects"])
    else:
        bound = boundary_motion(out["objects"])
    beyond, unchecked = beyond_bound(out, model, rec, noise, kw.get("smooth", 0.0),
                                     kw.get("surface_nodes", 120))
    summary = out["summary"]
    joined = {(i, m["into"]) for m in summary["merges"] for i in m["ids"]}
    joined |= {(m["id"], j) for m in summary["splits"] for j in m["into"]}
    ordinary = [r["optimisation_percent"] for r in out["table"]
                if (r["id_a"], r["id_b"]) not in joined and not r.get("reason")
                and min(r["nodes_a"], r["nodes_b"]) >= 0.7 * max(r["nodes_a"], r["nodes_b"])]
    skipped = sum(1 for r in out["table"] if r.get("reason"))
    trackable = sum(r.get("trackable_matches") or 0 for r in out["table"])
    jumps = {int(f) for f, s in zip(step_frames, steps) if s > LIMIT}
    return dict(
        frames=rec.n_frames,
        pairs=len(out["table"]),
        steps=len(steps),
        over3=float(np.mean(steps > LIMIT)) if len(steps) else 0.0,
        over10=float(np.mean(steps > 10.0)) if len(steps) else 0.0,
        longest=float(steps.max()) if len(steps) else 0.0,
        boundary=float(np.mean(bound > LIMIT)) if len(bound) else 0.0,
        jump_frames=len(jumps),
        ordinary=float(np.mean(ordinary)) if ordinary else float("nan"),
        n_ordinary=len(ordinary),
        skipped=skipped,
        trackable=trackable,
        beyond=beyond,
        unchecked=unchecked,
        seconds=seconds,
    )


def recordings(data_dir):
    out = [("F-Scan walk FrasP01L (31.25 Hz)", ROOT / "examples" / "data" / "FrasP01L.asf", 1)]
    if data_dir.is_dir():
        for p in sorted(data_dir.iterdir()):
            if p.suffix.lower() not in {".lst", ".asc", ".txt", ".asf", ".csv"}:
                continue
            rec = pymodal.read_recording(str(p))
            rate = 1.0 / rec.dt_s if rec.dt_s else None
            label = f"{p.stem} ({rate:g} Hz)" if rate else p.stem
            out.append((label, p, 1))
            if rate and rate > 150:
                k = int(round(rate / 100.0))
                out.append((f"{p.stem} (every {k}th frame: {rate / k:g} Hz)", p, k))
    return out


def parse_option(s):
    key, value = s.split("=", 1)
    for cast in (int, float):
        try:
            return key, cast(value)
        except ValueError:
            pass
    return key, {"true": True, "false": False}.get(value.lower(), value)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", type=Path, default=ROOT / "benches" / "data")
    ap.add_argument("--markdown", action="store_true")
    ap.add_argument("--option", action="append", default=[], type=parse_option,
                    help="a pymodal.run keyword for every run, e.g. max_rotation=180")
    args = ap.parse_args()
    options = dict(args.option)
    rows = []
    for label, path, stride in recordings(args.data):
        m = measure(path, stride=stride, **options)
        rows.append((label, m))
    head = ["recording", "frames", "pairs", "trackable matches", "track steps", "steps > 3 sensels",
            "boundary nodes > 3 sensels", "steps beyond the bound", "target met", "steps > 10", "longest step",
            "frames with a jump", "ordinary pairs: optimisation %", "skipped pairs", "s"]
    if args.markdown:
        print(f"options: {options or 'defaults'}\n")
        print("| " + " | ".join(head) + " |")
        print("|" + "---|" * len(head))
    for label, m in rows:
        ok = m["over3"] <= max(m["boundary"], 0.02) and m["beyond"] == 0 and m["unchecked"] == 0
        beyond = str(m["beyond"]) + (f" ({m['unchecked']} unchecked)" if m["unchecked"] else "")
        cells = [label, m["frames"], m["pairs"], m["trackable"], m["steps"], f"{100 * m['over3']:.1f} %",
                 f"{100 * m['boundary']:.1f} %", beyond, "yes" if ok else "no", f"{100 * m['over10']:.1f} %",
                 f"{m['longest']:.1f}", m["jump_frames"], f"{m['ordinary']:.2f} ({m['n_ordinary']})",
                 m["skipped"], f"{m['seconds']:.1f}"]
        print("| " + " | ".join(map(str, cells)) + " |" if args.markdown else "  ".join(map(str, cells)))


if __name__ == "__main__":
    main()
