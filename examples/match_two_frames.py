"""Read the bundled recording, match the largest contours of two frames, and plot the matches.

Run:  python examples/match_two_frames.py [--frames 40 42] [--out match.png]

Needs pymodal and matplotlib (``pip install matplotlib``). Frames are 0-based, like the arrays.
"""

import argparse
import pathlib

import matplotlib

matplotlib.use("Agg")  # no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import pymodal  # noqa: E402
from pymodal.plot import plot_match  # noqa: E402

DATA = pathlib.Path(__file__).resolve().parent / "data" / "FrasP01L.asf"


def largest_contour(frame):
    """The outline with the most points (the foot's main contact region)."""
    outlines = pymodal.contours(frame, spacing=1.0)
    if not outlines:
        raise SystemExit("no contact region in this frame")
    return max(outlines, key=len)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--recording", default=str(DATA))
    ap.add_argument("--frames", type=int, nargs=2, default=[40, 42], metavar=("A", "B"))
    ap.add_argument("--out", default="match.png")
    args = ap.parse_args()

    rec = pymodal.read_recording(args.recording)
    fa, fb = args.frames
    print(f"{rec.frames.shape[0]} frames of {rec.frames.shape[1]} x {rec.frames.shape[2]} sensels, "
          f"pitch {rec.pitch_mm} mm, {rec.units}")
    a = largest_contour(rec.frames[fa])
    b = largest_contour(rec.frames[fb])

    m = pymodal.match(a, b)
    print(f"frames {fa} -> {fb}: {len(a)} and {len(b)} nodes; {m.local_count} local, "
          f"{m.optimisation_count} one-to-one and {m.excess_count} excess matches, "
          f"mean cost {np.mean(m.costs):.4f}")

    fig, ax = plt.subplots(figsize=(4, 8), layout="constrained")
    ax.imshow(np.nan_to_num(rec.frames[fa]), cmap="Greys", alpha=0.4)
    # Coordinates in sensels, like the image; the helper adds the legend, title and axis labels.
    plot_match(m, a, b, ax=ax, labels=(f"frame {fa}", f"frame {fb}"))
    fig.savefig(args.out, dpi=120, bbox_inches="tight")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
