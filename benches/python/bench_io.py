"""pymodal io vs scikit-image on a whole 205-frame F-Scan recording.

Build the extension in release mode first:
    cd crates/pymodal && maturin develop --release
Run:
    python benches/python/bench_io.py
Times are the best of 5 runs over all 205 frames.
"""

import pathlib
import time

import numpy as np
import pymodal
from skimage import measure

ASF = pathlib.Path(__file__).resolve().parents[2] / "crates/pedo-io/tests/data/FrasP01L.asf"


def best(f, repeat=5):
    ts = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        ts.append(time.perf_counter() - t0)
    return min(ts)


def main():
    rec = pymodal.read_recording(str(ASF))
    frames = rec.frames
    padded = [np.pad(np.nan_to_num(f).astype(np.float64), 1) for f in frames]
    level = 1.5
    rows = [
        ("read_recording (.asf)", best(lambda: pymodal.read_recording(str(ASF)))),
        ("pymodal.contours, level 1.5", best(lambda: [pymodal.contours(f, level=level) for f in frames])),
        ("skimage find_contours, level 1.5 (padded)", best(lambda: [measure.find_contours(p, level) for p in padded])),
        ("pymodal.contours, n_points=64", best(lambda: [pymodal.contours(f, n_points=64) for f in frames])),
        ("pymodal.isocontours, 10 levels, smooth=1", best(lambda: [pymodal.isocontours(f, [20.0 * i for i in range(1, 11)], smooth=1.0, threshold=3.0) for f in frames])),
    ]
    loaded = [f for f in frames if np.nansum(f) > 0]

    def surfaces():
        for f in loaded:
            pymodal.surface(f, threshold=3.0, smooth=1.0, max_nodes=120)

    rows.append((f"pymodal.surface, max_nodes=120, smooth=1 ({len(loaded)} loaded frames)", best(surfaces)))
    print("| operation (205 frames of 60 x 21) | best of 5 [ms] |")
    print("|---|---|")
    for name, t in rows:
        print(f"| {name} | {1e3 * t:.1f} |")


if __name__ == "__main__":
    main()
