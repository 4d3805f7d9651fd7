"""Extracts dense foot outlines and a pressure grid from the real sample recordings (F-Scan and MUN104).

Writes, beside this script:
  contours.txt  -- closed outlines as blocks "# name" followed by "x y" lines (sensel units,
                   sub-pixel marching squares on a lightly smoothed image), blank line between blocks;
  heel_strike.txt -- held-out outlines (same format): the heel alone in the first two loaded
                   frames of every stance of the F-Scan walk, nearly round (principal-axis ratio
                   1.09-1.17); not used to tune anything;
  mun104l.txt   -- the MUN104 left-foot peak-pressure template (63 x 27, whitespace separated),
                   used for the 3-D surface ground truth.
Run: python make_fixtures.py DATA_DIR   (needs numpy, scipy, scikit-image)
"""
import sys
from pathlib import Path

import numpy as np
from scipy.ndimage import gaussian_filter
from skimage.measure import find_contours

SRC = Path(sys.argv[1] if len(sys.argv) > 1 else "/work/shared/data")
OUT = Path(__file__).resolve().parent


def read_asf(path):
    frames, cur = [], None
    for line in path.read_text(errors="replace").splitlines():
        s = line.strip()
        if s.startswith("Frame"):
            cur = []
            frames.append(cur)
        elif cur is not None and s and (s[0].isdigit() or s[0] == "B"):
            cur.append([0.0 if v.strip() == "B" else float(v) for v in s.split(",")])
    return [np.array(f) for f in frames if f]


def outline(img, level, smooth=0.8):
    g = gaussian_filter(img.astype(float), smooth)
    cs = [c for c in find_contours(np.pad(g, 2), level) if np.allclose(c[0], c[-1])]
    c = max(cs, key=len)[:-1] - 2.0
    return c[:, ::-1]  # (x = column, y = row)


def write_outlines(path, out):
    with open(path, "w") as f:
        f.write("# closed outlines extracted by make_fixtures.py; x y in sensel units\n")
        for name, c in out:
            f.write(f"# {name}\n")
            for x, y in c:
                f.write(f"{x:.5f} {y:.5f}\n")
            f.write("\n")


def heel_strikes(frames):
    """The first two frames of every stance whose only outline is the heel (rows >= 45)."""
    out = []
    loaded = [f.sum() > 0.05 * max(g.sum() for g in frames) for f in frames]
    for i in range(1, len(frames) - 1):
        if loaded[i] and not loaded[i - 1]:
            for k in (i, i + 1):
                c = outline(frames[k], 20.0)
                if len(c) > 20 and c[:, 1].mean() >= 45:
                    out.append((f"FrasP01L-frame{k}-heel", c))
    return out


def main():
    out = []
    for side in "LR":
        img = np.loadtxt(SRC / f"MUN104{side}.csv", delimiter=",")
        for level in (15.0, 60.0, 150.0):
            out.append((f"MUN104{side}-level{int(level)}", outline(img, level)))
    frames = read_asf(SRC / "FrasP01L.asf")
    force = np.array([f.sum() for f in frames])
    # Frames of one stance phase at rising, peak and falling load: heel, whole foot, forefoot.
    picked = [i for i in range(len(frames)) if force[i] > 0.15 * force.max()]
    first = picked[:40]
    for tag, idx in (("early", first[2]), ("mid", first[len(first) // 2]), ("late", first[-3])):
        c = outline(frames[idx], 20.0)
        if len(c) > 20:
            out.append((f"FrasP01L-frame{idx}-{tag}", c))
    write_outlines(OUT / "contours.txt", out)
    heels = heel_strikes(frames)
    write_outlines(OUT / "heel_strike.txt", heels)
    np.savetxt(OUT / "mun104l.txt", np.loadtxt(SRC / "MUN104L.csv", delimiter=","), fmt="%d")
    for name, c in out + heels:
        print(name, len(c))


main()
