"""Match every frame of a recording with pymodal.run and load its tables with numpy (and pandas,
if it is installed).

Run:  python examples/run_recording.py [--frames 40 80] [--out-dir DIR]

Frames are 0-based and the range is half-open, like a Python slice: (40, 80) is frames 40..79.
"""

import argparse
import csv
import pathlib

import numpy as np

import pymodal

DATA = pathlib.Path(__file__).resolve().parent / "data" / "FrasP01L.asf"


def write_csv(path, rows):
    """Writes a list of dicts (one per row, same keys) as a CSV file."""
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--recording", default=str(DATA))
    ap.add_argument("--frames", type=int, nargs=2, default=[40, 80], metavar=("START", "END"))
    ap.add_argument("--out-dir", default=".")
    args = ap.parse_args()
    out = pathlib.Path(args.out_dir)
    out.mkdir(parents=True, exist_ok=True)

    # The file gives its pitch and frame rate; pitch_mm= and frame_rate= would override them.
    res = pymodal.run(args.recording, frames=tuple(args.frames))
    table = res["table"]
    print(f"{len(res['objects'])} objects, {len(table)} matched pairs, {len(res['tracks'])} tracks")

    # The per-pair table as a numpy structured array (one field per column).
    pairs_csv = out / "pairs.csv"
    write_csv(pairs_csv, table)
    pairs = np.genfromtxt(pairs_csv, delimiter=",", names=True)
    print("columns:", ", ".join(pairs.dtype.names))
    print(f"round trip through the pair's fields: median {np.nanmedian(pairs['round_trip_sensels']):.3f} sensels; "
          f"local (mutual-best) matches: mean {pairs['local_percent'].mean():.1f} %")

    # Tracks: one (k, 3) array of (frame, x, y) rows per node track.
    longest = max(res["tracks"], key=len)
    print(f"longest track: {len(longest)} steps, frames {int(longest[0, 0])}..{int(longest[-1, 0])}, "
          f"moved {np.linalg.norm(longest[-1, 1:] - longest[0, 1:]):.1f} sensels")

    # Per-frame measures (as frames.csv), when this pymodal reports them.
    if res.get("frames"):
        frames_csv = out / "frames.csv"
        write_csv(frames_csv, res["frames"])
        measures = np.genfromtxt(frames_csv, delimiter=",", names=True)
        force = [c for c in measures.dtype.names if c.startswith("total_")][0]
        print(f"{len(measures)} frames; {force}: peak {np.nanmax(measures[force]):.1f}")

    try:
        import pandas as pd
    except ImportError:
        print("pandas is not installed: skipping the DataFrame view")
        return
    df = pd.DataFrame(table)
    print(df.groupby("frame_a")[["optimisation_percent", "mean_cost"]].mean().head())


if __name__ == "__main__":
    main()
