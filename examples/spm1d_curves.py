"""Statistical parametric mapping (spm1d) of a study's stance-normalised force curves.

Runs a batch of recordings into a study folder (or reads one already made), takes its
``study_curves.csv`` (one row per recording, stance and per cent of contact) and compares the
force curves of two groups of stances over 0-100 % of contact with spm1d's two-sample t-test:
by default the complete stances of the first recording against those of the second.

spm1d is an optional extra (``pip install "pedomatch[spm]"``); without it the script says so
and exits 0 after writing the table, so that it runs anywhere.

    python examples/spm1d_curves.py STUDY_FOLDER [RECORDING ...]
"""

import argparse
import csv
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np


def read_curves(path, column):
    """The curves of `column` per (path, stance), complete stances only, as a dict of arrays of
    101 values (0..100 % of contact)."""
    curves = defaultdict(lambda: np.full(101, np.nan))
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            if row["complete"] != "1" or row[column] == "":
                continue
            curves[(row["path"], int(row["stance"]))][int(row["percent"])] = float(row[column])
    return {k: v for k, v in curves.items() if not np.isnan(v).any()}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("study", type=Path, help="study folder (written by a batch)")
    parser.add_argument("recordings", nargs="*", type=Path, help="recordings to run into it first")
    parser.add_argument("--column", default="total_force_n", help="the curve compared (a column of study_curves.csv)")
    args = parser.parse_args()
    if args.recordings:
        import pymodal

        pymodal.batch([str(p) for p in args.recordings], args.study, figures="none", report="none")
    table = args.study / "study_curves.csv"
    curves = read_curves(table, args.column)
    by_recording = defaultdict(list)
    for (path, _), y in sorted(curves.items()):
        by_recording[path].append(y)
    groups = list(by_recording.items())
    for path, ys in groups:
        print(f"{path}: {len(ys)} complete stances")
    if len(groups) < 2 or min(len(ys) for _, ys in groups[:2]) < 2:
        print("need two recordings with two complete stances or more each to compare")
        return 0
    (name_a, a), (name_b, b) = groups[0], groups[1]
    try:
        import spm1d
    except ImportError:
        print("spm1d is not installed (pip install 'pedomatch[spm]'): no test run")
        return 0
    t = spm1d.stats.ttest2(np.array(a), np.array(b))
    inference = t.inference(alpha=0.05, two_tailed=True)
    print(f"two-sample t-test of {args.column}, {name_a} vs {name_b}:")
    print(f"  critical t* = {inference.zstar:.3f}, reject H0: {inference.h0reject}")
    for c in inference.clusters:
        print(f"  cluster {c.endpoints[0]:.1f}..{c.endpoints[1]:.1f} % of contact, p = {c.P:.4f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
