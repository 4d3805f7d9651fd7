"""The anatomical regions of a recording (Recording.regions, a run folder's regions.npy,
regions.csv and regions.json): every region measure recomputed in NumPy from the label image
and the frames of the real samples, by the definitions of docs/measures.md."""

import csv
import json
from pathlib import Path

import numpy as np
import pytest

import pymodal

ROOT = Path(__file__).resolve().parents[3]
DATA = ROOT / "crates" / "pedo-io" / "tests" / "data"
BENCH = ROOT / "benches" / "data"
WALK = ROOT / "examples" / "data" / "FrasP01L.asf"


def numpy_regions(rec, labels, names, threshold=0.0):
    """Each region's measures from rec.frames and the label image, in NumPy (kPa files only)."""
    f = np.nan_to_num(np.asarray(rec.frames, dtype=np.float64), nan=0.0)
    exists = ~np.isnan(np.asarray(rec.frames[0], dtype=np.float64))
    loaded = (f > 0) & (f >= threshold) & exists
    dt = rec.dt_s
    area = rec.sensel_area_mm2 or float(np.prod(rec.pitch_mm))
    assert rec.units.lower() == "kpa"
    peak = f.max(axis=0)
    pti = np.where(loaded, f, 0.0).sum(axis=0) * dt
    out = {}
    ftis = {}
    for k, name in enumerate(names, start=1):
        inside = labels == k
        force = np.where(loaded & inside, f, 0.0).sum(axis=(1, 2)) * area * 1e-3
        lo, hi = force.min(), force.max()
        above = np.flatnonzero(force > lo + 0.1 * (hi - lo)) if hi > 0 else []
        ftis[name] = force.sum() * dt
        out[name] = {
            "peak_pressure": peak[inside].max(),
            "pti_max": pti[inside].max(),
            "peak_force": hi,
            "fti": ftis[name],
            "max_contact_area": (loaded & inside).sum(axis=(1, 2)).max() * area,
            "contact_time": (above[-1] - above[0] + 1) * dt if len(above) else 0.0,
        }
    total = sum(ftis.values())
    for name in names:
        out[name]["impulse_share"] = 100.0 * ftis[name] / total
    return out


@pytest.mark.parametrize(
    "path", [WALK, BENCH / "emed-pressuRe-step.lst"], ids=lambda p: p.name
)
@pytest.mark.parametrize("rule", ["coarse", "fine"])
def test_regions_are_numpys_sums_on_real_recordings(path, rule):
    rec = pymodal.read_recording(str(path))
    r = rec.regions(rule)
    labels, names = r["labels"], r["names"]
    assert labels.shape == rec.frames.shape[1:]
    # A partition of the footprint: every sensel loaded in some frame in exactly one region.
    f = np.nan_to_num(np.asarray(rec.frames, dtype=np.float64), nan=0.0)
    footprint = (f > 0).any(axis=0)
    assert np.array_equal(labels > 0, footprint)
    assert set(np.unique(labels[footprint])) == set(range(1, len(names) + 1))
    want = numpy_regions(rec, labels, names)
    for name in names:
        for measure, value in want[name].items():
            assert r["values"][name][measure] == pytest.approx(value, rel=1e-9, abs=1e-12), (
                name,
                measure,
            )
    assert sum(v["impulse_share"] for v in r["values"].values()) == pytest.approx(100.0)
    assert r["units"]["fti"] == "N·s" and r["units"]["impulse_share"] == "%"
    # Toes distal to the heel along the axis the recording's centre of pressure travels.
    assert r["heel_toe_cue"] == "cop_path"


def test_a_run_folder_s_regions_are_the_recording_s(tmp_path):
    rec = pymodal.read_recording(str(BENCH / "emed-pressuRe-step.lst"))
    out = tmp_path / "run"
    pymodal.run(rec, out=str(out), report="none", figures="none", region_rule="fine")
    labels = np.load(out / "regions.npy")
    meta = json.loads((out / "regions.json").read_text())
    names = [meta["labels"][str(k)] for k in range(1, len(meta["labels"]) + 1)]
    want = numpy_regions(rec, labels.astype(int), names)
    rows = list(csv.DictReader((out / "regions.csv").open(encoding="utf-8")))
    # The masks' own rows; the regions carried through the stance follow them (`moving`).
    assert [r["kind"] for r in rows] == ["fixed"] * 7 * len(names) + ["moving"] * 7 * len(names)
    rows = rows[: 7 * len(names)]
    for row in rows:
        assert float(row["value"]) == pytest.approx(
            want[row["region"]][row["measure"]], rel=1e-9, abs=1e-12
        )
    assert meta["foot"]["side"] in ("left", "right")
    assert np.array_equal(labels.astype(int), rec.regions("fine")["labels"])


def test_regions_refuse_a_bad_rule_and_an_empty_footprint():
    rec = pymodal.Recording.from_array(np.zeros((2, 5, 5)), pitch_mm=5.0, frame_rate=100, units="kPa")
    with pytest.raises(Exception):
        rec.regions("fine")
    walk = pymodal.read_recording(str(WALK))
    with pytest.raises(ValueError):
        walk.regions("medium")
