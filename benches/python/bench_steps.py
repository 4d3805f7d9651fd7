"""Steps of the material points on real recordings: the share longer than 3 sensels beside the
outline's own motion (the share of outline nodes lying more than 3 sensels from the next frame's
outline), at the recordings' own rates and at 100 Hz.

    python benches/python/bench_steps.py [--markdown]

Recordings: the bundled walk (examples/data) and every recording of benches/data. pedomatch runs
each with the defaults (contour model); points from ``pymodal.run(...)["points"]``.
"""

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

import pymodal

ROOT = Path(__file__).resolve().parents[2]
LONG = 3.0


def recordings():
    yield ROOT / "examples" / "data" / "FrasP01L.asf"
    for p in sorted((ROOT / "benches" / "data").iterdir()):
        if p.is_file() and p.suffix.lower() not in (".md", ".py"):
            yield p


def shares(res):
    """(points' steps longer than LONG, their count, outline nodes farther than LONG from the
    next frame's outline, their count)."""
    d = [np.linalg.norm(np.diff(p[:, 1:], axis=0), axis=1) for p in res["points"] if len(p) > 1]
    d = np.concatenate(d) if d else np.zeros(0)
    by_frame = {}
    for o in res["objects"]:
        by_frame.setdefault(o["frame"], []).append(np.asarray(o["points"])[:, :2])
    frames = sorted(by_frame)
    far = total = 0
    for f, g in zip(frames, frames[1:]):
        if g != f + res["summary"]["options"].get("every", 1):
            continue
        tree = cKDTree(np.vstack(by_frame[g]))
        for outline in by_frame[f]:
            dist = tree.query(outline)[0]
            far += int(np.sum(dist > LONG))
            total += len(outline)
    return float(np.mean(d > LONG)) if len(d) else float("nan"), len(d), far / max(total, 1), total


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--markdown", action="store_true")
    a = ap.parse_args()
    rows = []
    for path in recordings():
        rec = pymodal.read_recording(str(path))
        rate = 1.0 / rec.dt_s if rec.dt_s else None
        variants = [("own rate", {})]
        if rate and rate > 100 * 1.5:
            variants.append(("100 Hz", {"every": int(round(rate / 100))}))
        for label, kw in variants:
            t0 = time.perf_counter()
            try:
                res = pymodal.run(str(path), **kw)
            except pymodal.PedomatchError as e:
                print(f"{path.name} ({label}): {e}", file=sys.stderr)
                continue
            secs = time.perf_counter() - t0
            long, n, boundary, m = shares(res)
            rows.append((path.name, f"{rate:g} Hz" if label == "own rate" and rate else label,
                         len(res["points"]), n, 100 * long, 100 * boundary, secs))
    head = ["recording", "rate", "points", "steps", "steps > 3 sensels, %", "outline nodes > 3 sensels from the next outline, %", "run, s"]
    if a.markdown:
        print("| " + " | ".join(head) + " |")
        print("|" + "---|" * len(head))
        for r in rows:
            print(f"| {r[0]} | {r[1]} | {r[2]} | {r[3]} | {r[4]:.1f} | {r[5]:.1f} | {r[6]:.1f} |")
    else:
        for r in rows:
            print(*r, sep="\t")


if __name__ == "__main__":
    main()
