"""Anatomical regions carried by the field against the true region, beside the fixed masks.

    python benches/python/bench_moving_regions.py [--frames 150] [--pedomatch target/release/pedomatch]

**Sequences.** The synthetic stances of ``stance.py`` (beside this file): a foot-like pressure field
moved by a known non-rigid map (rotation, translation, forefoot spreading, a bend) while its load
rolls from heel to toes. Laws 0-1 with seeds 0-1 are the **tuning cases**, laws 2-3 with seeds
2-3 are **held out** (nothing here was tuned on any of them: the regions' follower is the one of
the user's regions, with its defaults), printed in their own table.

**Run.** Each sequence is written as a ``.npy`` (frames, rows, columns; kPa) and run by the
command line with the defaults and ``--region-rule coarse`` (5 mm sensels, 200 Hz, tables only:
``--figures none --report none``). Its ``region_series.csv`` gives, per stance, coarse region
(hindfoot, midfoot, forefoot, toes) and frame, the force of the region carried by the field
(``kind`` moving) and of the mask left in place over the peak image (``fixed``).

**Truth.** A region's reference is the stance's reference frame R (``regions.json``'s
``moving.stances``): the mask's sensels (``regions.npy``) in contact on R. On frame t the true
region covers the share of each sensel whose material points (8 x 8 points per sensel, the exact
inverse map) lie, on frame R (the exact map), in one of those sensels; its true force is the sum
of each sensel's pressure x that share x the sensel area (the region's force as pedomatch counts
a moving region: by the share of each sensel it covers).

**Error.** Per region and frame, |force - true force| as a share of the region's largest true
force over the stance (a relative error per frame explodes where a region is barely loaded, e.g.
the toes at heel strike). Reported per group: the mean over frames, the 95th percentile and the
worst frame, over all regions and cases, for moving and fixed; and the share of frames within 5 %.
"""

import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from stance import Stance  # noqa: E402

PITCH_MM = 5.0
FRAME_RATE = 200.0
SUB = 8
TUNING = [(law, seed) for law in (0, 1) for seed in (0, 1)]
HELD_OUT = [(law, seed) for law in (2, 3) for seed in (2, 3)]


def run_case(exe, law, seed, n_frames, tmp):
    st = Stance(law=law, seed=seed, frames=n_frames + 1)
    frames = st.frames
    path = os.path.join(tmp, f"stance_{law}_{seed}.npy")
    np.save(path, frames)
    out = os.path.join(tmp, f"out_{law}_{seed}")
    subprocess.run([exe, "run", path, "--out", out, "--pitch-mm", str(PITCH_MM), "--frame-rate",
                    str(FRAME_RATE), "--units", "kPa", "--region-rule", "coarse", "--figures",
                    "none", "--report", "none"], check=True, stdout=subprocess.DEVNULL)
    labels = np.load(os.path.join(out, "regions.npy")).astype(int)
    info = json.load(open(os.path.join(out, "regions.json")))
    names = {int(k): v for k, v in info["labels"].items()}
    rows = list(csv.DictReader(open(os.path.join(out, "region_series.csv"))))
    pix = st.pixel_centres()
    # SUB x SUB points spread over every sensel: the true region covers the share of a sensel
    # whose points' material positions lie, on the reference frame, in one of its sensels (as
    # pedomatch counts a moving region by the share of each sensel it covers).
    o = (np.arange(SUB) + 0.5) / SUB - 0.5
    sub = np.concatenate([pix + [dx, dy] for dy in o for dx in o])
    area_n = PITCH_MM * PITCH_MM * 1e-3  # kPa x mm2 -> N
    errors = {"moving": [], "fixed": []}
    for s in info["moving"]["stances"]:
        ref = s["reference_frame"]
        contact = frames[ref] > 0
        at_ref = {}  # frame -> the reference-frame sensel of each sub-point (row, column, on grid)
        for label, name in names.items():
            cells = (labels == label) & contact
            if not cells.any():
                continue
            series = {k: {} for k in errors}
            for r in rows:
                if r["name"] == name and int(r["stance"]) == s["stance"] and r["total_force_n"]:
                    series[r["kind"]][int(r["frame"])] = float(r["total_force_n"])
            fr = sorted(series["moving"])
            true = []
            for t in fr:
                if t not in at_ref:
                    q = st.true_positions(ref, st.reference_positions(t, sub))
                    c, rr = np.rint(q[:, 0]).astype(int), np.rint(q[:, 1]).astype(int)
                    ok = (c >= 0) & (c < st.cols) & (rr >= 0) & (rr < st.rows)
                    at_ref[t] = (rr, c, ok)
                rr, c, ok = at_ref[t]
                inside = np.zeros(len(sub), bool)
                inside[ok] = cells[rr[ok], c[ok]]
                share = inside.reshape(SUB * SUB, len(pix)).mean(axis=0)
                true.append((frames[t].ravel() * share).sum() * area_n)
            true = np.array(true)
            top = true.max()
            for kind in errors:
                f = np.array([series[kind].get(t, np.nan) for t in fr])
                errors[kind].extend(np.abs(f - true) / top)
    return errors


def table(title, errs):
    print(f"\n{title}\n")
    print("| region force | mean | 95th pct | worst | frames within 5 % |")
    print("|---|---|---|---|---|")
    for kind in ("moving", "fixed"):
        e = np.array(errs[kind])
        e = np.nan_to_num(e, nan=np.inf)
        label = "carried by the field (moving)" if kind == "moving" else "mask left in place (fixed)"
        print(f"| {label} | {100 * np.mean(e):.1f} % | {100 * np.percentile(e, 95):.1f} % | "
              f"{100 * e.max():.1f} % | {100 * np.mean(e <= 0.05):.0f} % |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--frames", type=int, default=150)
    ap.add_argument("--pedomatch", default=os.path.join("target", "release", "pedomatch"))
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        for title, cases in (("tuning cases (laws 0-1, seeds 0-1)", TUNING),
                             ("held out (laws 2-3, seeds 2-3)", HELD_OUT)):
            errs = {"moving": [], "fixed": []}
            for law, seed in cases:
                e = run_case(a.pedomatch, law, seed, a.frames, tmp)
                for k in errs:
                    errs[k].extend(e[k])
            table(f"{title}: per-frame force error of the coarse regions, share of the region's "
                  f"largest true force, {a.frames + 1} frames", errs)


if __name__ == "__main__":
    main()
