"""Writes the real-recording excerpts of benches/data/ (see README.md there) from their sources.

    python benches/data/make_recordings.py --pressure-extdata DIR [--out benches/data]
    python benches/data/make_recordings.py --pataky-trials DIR   # the batch benchmark's 8 trials

- DIR: the `inst/extdata/` folder of the public R package pressuRe (GitHub `ellenlii07/pressuRe`,
  MIT): `emed_test.lst`, `pedar_example.asc`, `footscan_test.xls` are read from it.
- The footscan walking trial of Pataky et al. (2008) is read from the PyPI package `jiku-data`
  (GPLv3; `pip install jiku-data tables`), dataset `SpeedPP2DS`.

Needs numpy, xlrd (for the .xls workbook) and tables (for jiku-data's HDF5 files). Nothing is
downloaded here: the inputs must already be on disk / installed.
"""

import argparse
import os
import sys

import numpy as np


def write_footscan(path, frames, row_mm, col_mm, dt_ms, units, side):
    """frames: (T, rows, cols) array; writes the RSscan/Materialise footscan text layout
    ([Technical] SensCountX = rows, SensCountY = cols, LDistX along the rows, LDistY along a row)."""
    t, rows, cols = frames.shape
    out = [
        "[General]",
        "UnitDistance=mm",
        f"UnitPressure={units}",
        "UnitTime=ms",
        "",
        "[Technical]",
        f"SensCountX={rows}",
        f"SensCountY={cols}",
        f"LDistX={row_mm}",
        f"LDistY={col_mm}",
        f"TimeDiff={dt_ms}",
        "MinIdx=1",
        f"MaxIdx={t}",
        f"FootSide={side}",
        "",
        "[Data]",
    ]

    def grid(a):
        return ["\t".join(f"{v:g}" for v in row) for row in a]

    out += grid(frames.max(axis=0))
    for k in range(t):
        out += ["", f"[Data{k + 1}]"] + grid(frames[k])
    with open(path, "w", newline="") as f:
        f.write("\n".join(out) + "\n")


def footscan_xls(src, dst):
    """pressuRe's footscan_test.xls: one 'Dynamic Roll' sheet, 'Frame k (t ms)' title rows, each
    followed by the rows of the right-foot rectangle (38 x 20 values, N/cm2, 500 Hz)."""
    import xlrd

    sheet = xlrd.open_workbook(src).sheet_by_index(0)
    rows = [sheet.row_values(r) for r in range(sheet.nrows)]
    height = int(next(rows[i + 1][0] for i, r in enumerate(rows) if r[0] == "Rectangle height"))
    starts = [i for i, r in enumerate(rows) if str(r[0]).startswith("Frame ")]
    frames = np.array([[rows[s + 1 + k] for k in range(height)] for s in starts], float)
    write_footscan(dst, frames, 7.62, 5.08, 2, "N/cm2", "R")
    return frames.shape


def footscan_jiku(dst, subj=0, trial=0):
    """Pataky et al. (2008) SpeedPP2DS, subject `subj`, trial `trial`: (rows, cols, 500) uint16,
    zero-padded in time; the padding is cut and the frames written as they are."""
    import tables
    import jikudata

    h5 = os.path.join(os.path.dirname(jikudata.__file__), "datasets", "SpeedPP2DS", "data_y",
                      f"subj{subj:03}.h5")
    with tables.open_file(h5, mode="r") as f:
        y = np.asarray(f.get_node(f"/img{trial:03}").read(), float)
    used = np.nonzero(y.sum(axis=(0, 1)) > 0)[0]
    frames = np.moveaxis(y[:, :, used[0]:used[-1] + 1], 2, 0)
    write_footscan(dst, frames, 5.08, 5.08, 2, "kPa", "L")
    return frames.shape


def emed_copy(src, dst):
    """The whole emed page export (one step, 10 ms per picture) is small enough to keep as is."""
    with open(src, "rb") as f:
        data = f.read()
    with open(dst, "wb") as f:
        f.write(data)
    return data.count(b"Pict-No.")


def pedar_excerpt(src, dst, first_s=2.0, last_s=5.0):
    """Frames with first_s < time <= last_s of the pedar-X export; the header's total time is
    set to the excerpt's length so that the file stays consistent."""
    with open(src, encoding="latin-1") as f:
        lines = f.read().split("\n")
    head_end = next(i for i, l in enumerate(lines) if l.strip().startswith("time[secs]")) + 1
    keep = []
    for l in lines[head_end:]:
        parts = l.split()
        if parts and first_s < float(parts[0]) <= last_s + 1e-9:
            keep.append(l)
    header = lines[:head_end]
    span = last_s - first_s
    header = [l.replace(l.split("total time [secs]:")[1].split("\t")[0],
                        f"  {span:.3f}") if "total time [secs]:" in l else l for l in header]
    with open(dst, "w", encoding="latin-1", newline="") as f:
        f.write("\n".join(header + keep) + "\n")
    return len(keep)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--pressure-extdata")
    ap.add_argument("--out", default=os.path.dirname(os.path.abspath(__file__)))
    ap.add_argument("--pataky-trials", metavar="DIR",
                    help="only write subject 0's first 8 Pataky (2008) trials into DIR (500 Hz "
                         "footscan, 0.53-0.76 s each): the default batch's benchmark "
                         "(benches/batch_speed.sh)")
    a = ap.parse_args()
    if a.pataky_trials:
        os.makedirs(a.pataky_trials, exist_ok=True)
        for t in range(8):
            dst = os.path.join(a.pataky_trials, f"footscan-Pataky2008-s00-t{t:02}.txt")
            print(dst, footscan_jiku(dst, 0, t))
        return
    if not a.pressure_extdata:
        ap.error("--pressure-extdata is required")
    src = a.pressure_extdata
    out = a.out
    print("emed pictures:", emed_copy(os.path.join(src, "emed_test.lst"),
                                      os.path.join(out, "emed-pressuRe-step.lst")))
    print("pedar frames:", pedar_excerpt(os.path.join(src, "pedar_example.asc"),
                                         os.path.join(out, "pedar-pressuRe-2.01-5.00.asc")))
    print("footscan (pressuRe) frames x rows x cols:",
          footscan_xls(os.path.join(src, "footscan_test.xls"),
                       os.path.join(out, "footscan-pressuRe-barefoot.txt")))
    print("footscan (Pataky 2008) frames x rows x cols:",
          footscan_jiku(os.path.join(out, "footscan-Pataky2008-s00-t00.txt")))


if __name__ == "__main__":
    sys.exit(main())
