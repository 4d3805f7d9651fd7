"""An independent check of landmark accuracy on outlines nobody here tuned on: the contours and
hand-placed landmarks that Pataky et al. distribute with lmfree2d, carried between every
within-class pair by pymodal.match (defaults) and by the peers of bench_landmarks.py.

This is a check, not a benchmark to tune on: no setting of pedomatch is chosen from it. Run it
once a change of the defaults has been decided on the landmark benchmark's tuning half (and read
on its held-out half), and report what it gives.

Data: lmfree2d (Pataky, Yagi, Ichihashi & Cox, *Landmark-free, parametric hypothesis tests
regarding two-dimensional contour shapes using coherent point drift registration and statistical
parametric mapping*, PeerJ Computer Science 7:e542, 2021; github.com/0todd0000/lmfree2d, MIT
licence), whose contours are redistributed from the 2D Shape Structure Dataset (Carlier et al.,
MIT licence): nine classes (Bell, Comma, Device8, Face, Flatfish, Hammer, Heart, Horseshoe, Key)
of 10 closed contours each, 100-185 points, with 4-8 landmarks per contour placed by the authors
on contour points. --data is lmfree2d's `Data` folder (or any folder with the same
`<Class>/contours.csv` and `<Class>/landmarks.csv`); the files are checked against one SHA-256 of
their contents (lmfree2d commit 5c5d398). Not shipped with this project.

Cases: every within-class pair (45 per class, 405 in all), A the contour with the lower number;
each contour used as distributed (its own point count and start, some clockwise, some not).
A landmark of A is carried to B as in bench_landmarks.py (the images of its node and the next,
interpolated along B's outline) and its error is the distance to B's landmark in B's mean point
spacing; a landmark given on a contour point lies between no nodes, so the floor of the read-out
is 0.

Run:  python benches/python/check_lmfree2d.py --data DIR [--by-class]
      (BCPD_BIN=/path/to/bcpd adds BCPD, as in bench_landmarks.py)
"""
import argparse
import hashlib
import os
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_landmarks as bl  # noqa: E402

CLASSES = ("Bell", "Comma", "Device8", "Face", "Flatfish", "Hammer", "Heart", "Horseshoe", "Key")
# SHA-256 of the 18 files, read in CLASSES order, contours before landmarks (lmfree2d 5c5d398).
SHA256 = "6a630ea7d4d0a3c25581286ca0576580ce56ea996df58c9a32f94c44d9f7a453"


def digest(data):
    h = hashlib.sha256()
    for cls in CLASSES:
        for name in ("contours.csv", "landmarks.csv"):
            h.update(Path(data, cls, name).read_bytes())
    return h.hexdigest()


class Contour:
    """One contour as distributed, with the same fields bench_landmarks.Outline carries."""

    def __init__(self, cls, name, pts, landmarks):
        self.cls, self.name, self.pts = cls, name, pts
        seg = np.linalg.norm(np.roll(pts, -1, 0) - pts, axis=1)
        self.cum = np.concatenate([[0], np.cumsum(seg)])
        self.spacing = self.cum[-1] / len(pts)
        # The landmarks lie on contour points (within 0.32 spacings): their places are those nodes.
        self.u = np.argmin(np.linalg.norm(landmarks[:, None] - pts[None], axis=2), axis=1).astype(float)
        self.landmarks = landmarks

    project = bl.Outline.project


def load(data):
    out = []
    for cls in CLASSES:
        c = np.loadtxt(Path(data, cls, "contours.csv"), delimiter=",", skiprows=1)
        lm = np.loadtxt(Path(data, cls, "landmarks.csv"), delimiter=",", skiprows=1)
        for k in np.unique(c[:, 0]):
            out.append(Contour(cls, int(k), c[c[:, 0] == k, 1:3], lm[lm[:, 0] == k, 2:4]))
    return out


def pairs_of(contours):
    by = {}
    for c in contours:
        by.setdefault(c.cls, []).append(c)
    return [(g[i], g[j]) for cls in CLASSES for g in [by[cls]] for i in range(len(g))
            for j in range(i + 1, len(g))]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", default=os.environ.get("LMFREE2D_DATA"))
    ap.add_argument("--by-class", action="store_true", help="also the share within 2 spacings per class")
    args = ap.parse_args()
    if not args.data or not Path(args.data, "Bell", "contours.csv").is_file():
        print("check_lmfree2d skipped: give --data DIR (or set LMFREE2D_DATA), lmfree2d's Data folder")
        return
    got = digest(args.data)
    if got != SHA256:
        sys.exit(f"check_lmfree2d: the data's SHA-256 is {got}, not lmfree2d 5c5d398's {SHA256}")

    methods = {
        "pedomatch defaults, outline images": bl.pedomatch_images(),
        "pedomatch defaults": bl.pedomatch(),
        "CPD rigid + deformable (pycpd)": bl.cpd(True),
        "CPD rigid (pycpd)": bl.cpd(False),
        "shape context + Hungarian": bl.sc_hungarian,
    }
    binary = os.environ.get("BCPD_BIN")
    if binary and Path(binary).is_file():
        methods["BCPD (defaults)"] = bl.bcpd(binary)
        print(f"BCPD: {bl.bcpd_version(binary)}, OMP_NUM_THREADS=1")
    else:
        print("BCPD skipped: set BCPD_BIN to the bcpd binary")

    pairs = pairs_of(load(args.data))
    counts = [len(a.pts) for a, _ in pairs] + [len(b.pts) for _, b in pairs]
    print(f"{len(pairs)} pairs, {len(CLASSES)} classes, {min(counts)}-{max(counts)} points")
    rows, per_class = bl.measure(methods, pairs)
    bl.print_rows(f"lmfree2d: {len(pairs)} pairs", rows, markdown=True)
    if args.by_class:
        bl.print_by_class("share within 2 spacings by class", rows, per_class, CLASSES)


if __name__ == "__main__":
    main()
