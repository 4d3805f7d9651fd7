"""Each track's round trip (tracks.csv's round_trip_sensels) per recording.

    python benches/python/bench_track_consistency.py PEDOMATCH [--markdown]

Runs ``PEDOMATCH run`` (defaults, tables only) on the bundled walk and every recording in
benches/data, and prints per recording: the tracks with a round trip (two steps or more), their
median / 95th percentile / largest round trip and the share over one sensel (as
``summary.json``'s ``track_round_trip_sensels``), then the same split by whether a track steps
through a pair whose own median round trip (``pairs.csv``) exceeds half a sensel (the pairs
whose matches cross), and the median track length in steps. Needs numpy.
"""

import argparse
import collections
import csv
import json
import subprocess
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
SUFFIXES = {".lst", ".asc", ".txt", ".asf"}


def recordings():
    out = [ROOT / "examples" / "data" / "FrasP01L.asf"]
    data = ROOT / "benches" / "data"
    out += sorted(p for p in data.iterdir() if p.suffix.lower() in SUFFIXES)
    return out


def measure(binary, path):
    with tempfile.TemporaryDirectory() as d:
        subprocess.run([binary, "run", str(path), "--out", d, "--figures", "none",
                        "--report", "none"], check=True, capture_output=True)
        summary = json.load(open(Path(d) / "summary.json"))["track_round_trip_sensels"]
        pairs = {(r["id_a"], r["id_b"]): r for r in csv.DictReader(open(Path(d) / "pairs.csv"))}
        tracks = collections.OrderedDict()
        for r in csv.DictReader(open(Path(d) / "tracks.csv")):
            tracks.setdefault(r["track"], []).append(r)
    crossed, clean, lengths = [], [], []
    for rows in tracks.values():
        if rows[0]["round_trip_sensels"] == "":
            continue
        trip = float(rows[0]["round_trip_sensels"])
        pairs_trip = max(float(pairs[(a["object_id"], b["object_id"])]["round_trip_sensels"] or 0)
                         for a, b in zip(rows, rows[1:]))
        (crossed if pairs_trip > 0.5 else clean).append(trip)
        lengths.append(len(rows))
    return summary, np.array(clean), np.array(crossed), np.array(lengths)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("pedomatch")
    ap.add_argument("--markdown", action="store_true")
    args = ap.parse_args()
    q = lambda v: f"{len(v)}: {np.median(v):.2f} / {np.percentile(v, 95):.2f}" if len(v) else "0"
    print("| recording | tracks with a round trip | median / 95th pct / max (sensels) | over 1 sensel "
          "| through no pair with round trip > 0.5: median / 95th pct | through such a pair "
          "| median steps |")
    print("|---|---:|---|---:|---|---|---:|")
    for path in recordings():
        s, clean, crossed, lengths = measure(args.pedomatch, path)
        print(f"| {path.name} | {s['tracks']} | {s['median']:.2f} / {s['p95']:.2f} / {s['max']:.2f} "
              f"| {s['over_1_percent']:.1f} % | {q(clean)} | {q(crossed)} | {np.median(lengths):.0f} |")


if __name__ == "__main__":
    main()
