"""Isocontour track steps longer than 3 sensels, one by one: is the next level's line that far?

    python benches/python/bench_iso_steps.py [--data DIR]

For each recording of bench_tracks.py (its isocontour run, defaults otherwise), every track step
longer than 3 sensels is set beside the distance from its first node to the next level's line
(the shortest step any match could make there) and to that line's nearest node. A step is
"real" when the line itself lies more than 3 sensels away; otherwise it is longer than the
shortest possible step, and the table says by how much. The last columns compare the target's
two shares on the same nodes: bench_tracks.py's boundary share is over every node of every
level line, the steps' share over the nodes tracks leave; the share of those nodes whose next
line lies more than 3 sensels away is the boundary's share on the tracked nodes alone.
"""

import argparse
from pathlib import Path

import numpy as np

import pymodal
from bench_tracks import LIMIT, ROOT, level_motion, recordings, segment_distances


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", type=Path, default=ROOT / "benches" / "data")
    args = ap.parse_args()
    print("| recording | steps | steps > 3 | of which the next line lies > 3 away | the others: "
          "line / nearest node / step (sensels) | boundary share, all nodes | boundary share, "
          "tracked nodes |")
    print("|---|---:|---:|---:|---|---:|---:|")
    seen = set()
    for label, path, stride in recordings(args.data):
        if stride != 1 or path in seen:
            continue
        seen.add(path)
        out = pymodal.run(str(path), model="isocontour")
        pts = [np.asarray(o["points"])[:, :2] for o in out["objects"]]
        rows = []
        for ts in out["track_steps"]:
            ts = np.asarray(ts)
            for (oa, na), (ob, nb) in zip(ts[:-1], ts[1:]):
                p, q = pts[oa][na], pts[ob][nb]
                line = segment_distances(p[None], [pts[ob]])[0]
                node = np.linalg.norm(pts[ob] - p, axis=1).min()
                rows.append((np.linalg.norm(q - p), line, node))
        rows = np.array(rows)
        long = rows[rows[:, 0] > LIMIT]
        real = long[long[:, 1] > LIMIT]
        other = long[long[:, 1] <= LIMIT]
        others = ", ".join(f"{l:.2f} / {n:.2f} / {s:.2f}" for s, l, n in other) or "–"
        share_all = float(np.mean(level_motion(out["objects"]) > LIMIT))
        share_tracked = float(np.mean(rows[:, 1] > LIMIT))
        print(f"| {label} | {len(rows)} | {len(long)} ({100 * len(long) / len(rows):.1f} %) "
              f"| {len(real)} | {others} | {100 * share_all:.1f} % | {100 * share_tracked:.1f} % |")


if __name__ == "__main__":
    main()
