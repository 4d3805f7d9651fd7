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

Run:  python benches/python/bench_tracks.py [--data DIR] [--markdown] [--option KEY=VALUE ...]
"""
import argparse
import time
from pathlib import Path

import numpy as np

import pymodal

ROOT = Path(__file__).resolve().parents[2]
LIMIT = 3.0  # sensels


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


def measure(path, stride=1, **options):
    """Runs a recording (every `stride`-th frame) and measures its tracks and its boundary."""
    rec = pymodal.read_recording(str(path))
    kw = dict(options)
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
    bound = boundary_motion(out["objects"])
    summary = out["summary"]
    joined = {(i, m["into"]) for m in summary["merges"] for i in m["ids"]}
    joined |= {(m["id"], j) for m in summary["splits"] for j in m["into"]}
    ordinary = [r["optimisation_percent"] for r in out["table"]
                if (r["id_a"], r["id_b"]) not in joined and not r.get("reason")
                and min(r["nodes_a"], r["nodes_b"]) >= 0.7 * max(r["nodes_a"], r["nodes_b"])]
    skipped = sum(1 for r in out["table"] if r.get("reason"))
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
    head = ["recording", "frames", "pairs", "track steps", "steps > 3 sensels", "boundary nodes > 3 sensels",
            "target met", "steps > 10", "longest step", "frames with a jump", "ordinary pairs: optimisation %", "skipped pairs", "s"]
    if args.markdown:
        print(f"options: {options or 'defaults'}\n")
        print("| " + " | ".join(head) + " |")
        print("|" + "---|" * len(head))
    for label, m in rows:
        ok = m["over3"] <= max(m["boundary"], 0.02)
        cells = [label, m["frames"], m["pairs"], m["steps"], f"{100 * m['over3']:.1f} %",
                 f"{100 * m['boundary']:.1f} %", "yes" if ok else "no", f"{100 * m['over10']:.1f} %",
                 f"{m['longest']:.1f}", m["jump_frames"], f"{m['ordinary']:.2f} ({m['n_ordinary']})",
                 m["skipped"], f"{m['seconds']:.1f}"]
        print("| " + " | ".join(map(str, cells)) + " |" if args.markdown else "  ".join(map(str, cells)))


if __name__ == "__main__":
    main()
