"""Stances and stance-normalised curves (curves.csv, measures.json's stances,
Recording.gait_measures()["stances"], a batch's study_curves.csv) against independent NumPy
computations: the stance rule of docs/measures.md written again here, and numpy.interp of the
frames' measures over each stance."""

import csv
import json
from pathlib import Path

import numpy as np
import pytest

import pymodal

ROOT = Path(__file__).resolve().parents[3]
DATA = ROOT / "crates" / "pedo-io" / "tests" / "data"
WALK = ROOT / "examples" / "data" / "FrasP01L.asf"
SAMPLES = [
    WALK,
    DATA / "emed-test-1-10.lst",
    DATA / "pedar-example-3.01-4.00.asc",
    DATA / "footscan-FrasP01L-11-20.txt",
    DATA / "zebris-FrasP01L-26-55.xml",
    DATA / "synthetic-walk.lst",
]
KPA = {"kpa": 1.0, "n/cm²": 10.0, "mpa": 1000.0, "mmhg": 0.1333224}


def numpy_stances(force, dt):
    """The stance rule of docs/measures.md: frames over min + 10 % of the force range, gaps
    shorter than 0.05 s joined, runs shorter than 0.1 s dropped (counted at 50 Hz without a
    rate); a run on the first or last frame is not complete."""
    dt = dt or 0.02
    min_gap = int(np.ceil(0.05 / dt * (1 - 1e-9)))
    min_frames = int(np.ceil(0.1 / dt * (1 - 1e-9)))
    lo, hi = force.min(), force.max()
    if hi == lo:
        return [(0, len(force) - 1, False)] if hi > 0 else []
    over = np.flatnonzero(force > lo + 0.1 * (hi - lo))
    runs = []
    for k in over:
        if runs and k - runs[-1][1] - 1 < min_gap:
            runs[-1][1] = k
        else:
            runs.append([k, k])
    n = len(force)
    return [(a, b, bool(a > 0 and b < n - 1)) for a, b in runs if b - a + 1 >= min_frames]


def frame_series(rec, columns=None):
    """Force, area, peak pressure and centre of pressure per frame from rec.frames, in NumPy;
    of the sensels of columns (start, end) alone when given (one foot of pedar's two)."""
    f = np.asarray(rec.frames, dtype=np.float64)
    exists = ~np.isnan(f[0])
    if columns is not None:
        exists[:, : columns[0]] = False
        exists[:, columns[1] :] = False
    v = np.nan_to_num(f, nan=0.0)
    loaded = (v > 0) & exists
    k = KPA.get((rec.units or "").lower(), 1.0)
    area = rec.sensel_area_mm2 or (np.prod(rec.pitch_mm) if rec.pitch_mm else None)
    per_value = k * area * 1e-3 if ((rec.units or "").lower() in KPA and area) else (area or 1.0)
    w = np.where(loaded, v, 0.0)
    load = w.sum(axis=(1, 2))
    rows, cols = np.indices(v.shape[1:])
    with np.errstate(invalid="ignore", divide="ignore"):
        cop_x = (w * cols).sum(axis=(1, 2)) / load
        cop_y = (w * rows).sum(axis=(1, 2)) / load
    return {
        "total_force": load * per_value,
        "contact_area": loaded.sum(axis=(1, 2)) * (area or 1.0),
        "peak_pressure": np.maximum(np.where(exists, v, 0.0).max(axis=(1, 2)), 0.0) * k,
        "cop_x": cop_x,
        "cop_y": cop_y,
    }


def interp(first, last, values):
    """numpy.interp of a stance's frame values at 101 points, frames without a value skipped."""
    t = np.arange(first, last + 1)
    y = values[first : last + 1]
    ok = ~np.isnan(y)
    return np.interp(np.linspace(first, last, 101), t[ok], y[ok])


@pytest.mark.parametrize("path", SAMPLES, ids=lambda p: p.name)
def test_gait_measures_stances_and_curves_are_numpys(path):
    rec = pymodal.read_recording(str(path))
    series = frame_series(rec)
    want = numpy_stances(series["total_force"], rec.dt_s)
    got = rec.gait_measures()["stances"]
    assert [(s["frames"][0], s["frames"][1], s["complete"]) for s in got] == want
    # The emed excerpt is 10 pictures of 10 ms: no contact lasts the 0.1 s of a stance.
    assert bool(want) == (path.name != "emed-test-1-10.lst")
    dt = rec.dt_s or 1.0
    for s in got:
        a, b = s["frames"]
        c = s["curves"]
        assert np.array_equal(c["percent"], np.arange(101.0))
        for name in ("total_force", "contact_area", "peak_pressure", "cop_x", "cop_y"):
            np.testing.assert_allclose(c[name], interp(a, b, series[name]), rtol=1e-9, atol=1e-9, err_msg=name)
        v = s["values"]
        force = series["total_force"][a : b + 1]
        assert v["contact_time"] == pytest.approx((b - a + 1) * dt, rel=1e-12)
        assert v["start_time"] == pytest.approx(a * dt, rel=1e-12)
        assert v.get("peak_force", v.get("peak_load")) == pytest.approx(force.max(), rel=1e-9)
        assert v.get("fti", v.get("load_time_integral")) == pytest.approx(force.sum() * dt, rel=1e-9)
        assert v["peak_pressure"] == pytest.approx(series["peak_pressure"][a : b + 1].max(), rel=1e-9)
        assert v["max_contact_area"] == pytest.approx(series["contact_area"][a : b + 1].max(), rel=1e-9)


def test_the_bundled_walk_has_six_stances_the_first_cut_by_the_start():
    stances = pymodal.read_recording(str(WALK)).gait_measures()["stances"]
    assert [s["frames"] for s in stances] == [(0, 13), (29, 50), (65, 85), (100, 120), (136, 156), (171, 193)]
    assert [s["complete"] for s in stances] == [False] + [True] * 5
    # Each complete stance of this in-shoe walk lasts 0.64 to 0.70 s at 31.25 Hz.
    times = [s["values"]["contact_time"] for s in stances[1:]]
    assert all(0.6 < t < 0.75 for t in times), times


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return rows


def column(rows, name):
    return np.array([float(r[name]) if r[name] != "" else np.nan for r in rows])


@pytest.mark.parametrize("path", [WALK, DATA / "pedar-example-3.01-4.00.asc"], ids=lambda p: p.name)
def test_curves_csv_is_numpy_interp_of_frames_csv(path, tmp_path):
    res = pymodal.run(str(path), out=tmp_path / "run", report="none", figures="none")
    frames = read_csv(tmp_path / "run" / "frames.csv")
    curves = read_csv(tmp_path / "run" / "curves.csv")
    measures = json.loads((tmp_path / "run" / "measures.json").read_text())
    numbers = [int(r["frame"]) for r in frames]
    assert numbers == list(range(numbers[0], numbers[0] + len(numbers)))
    assert len(res["curves"]) == len(curves)
    if "feet" in measures:
        return feet_curves_are_numpy_interp(path, measures, curves, res)
    force_col = next(c for c in curves[0] if c.startswith("total_"))
    force = column(frames, force_col)
    dt = pymodal.read_recording(str(path)).dt_s
    want = [(a + numbers[0], b + numbers[0], c) for a, b, c in numpy_stances(force, dt)]
    assert [tuple(s["frames"]) + (s["complete"],) for s in measures["stances"]] == want
    assert want
    measure_cols = [c for c in curves[0] if c not in ("stance", "complete", "percent")]
    assert measure_cols == [c for c in frames[0] if c not in ("frame", "time_s", "contact_sensors")]
    assert len(curves) == 101 * len(measures["stances"])
    for k, s in enumerate(measures["stances"]):
        a, b = (f - numbers[0] for f in s["frames"])
        rows = curves[101 * k : 101 * (k + 1)]
        assert {int(r["stance"]) for r in rows} == {k}
        assert [int(r["percent"]) for r in rows] == list(range(101))
        assert {int(r["complete"]) for r in rows} == {int(s["complete"])}
        for name in measure_cols:
            # Both tables are written with 4 decimals: 1e-4 apart at most.
            np.testing.assert_allclose(column(rows, name), interp(a, b, column(frames, name)), rtol=0, atol=1.5e-4, err_msg=name)
    # pymodal.run's result holds the same rows.
    assert res["curves"][5]["percent"] == 5


def feet_curves_are_numpy_interp(path, measures, curves, res):
    """Both insoles of a pedar recording: curves.csv's rows of each foot (its `foot` column)
    are numpy.interp of the foot's own frame measures over its own stances, and measures.json's
    `feet` are Recording.gait_measures()'s."""
    rec = pymodal.read_recording(str(path))
    mine = rec.gait_measures()["feet"]
    assert [f["foot"] for f in measures["feet"]] == list(mine) == ["left", "right"]
    assert list(curves[0])[:2] == ["foot", "stance"] and res["curves"][0]["foot"] == "left"
    for foot in measures["feet"]:
        theirs = mine[foot["foot"]]
        assert tuple(foot["columns"]) == theirs["columns"]
        assert {k: v["value"] for k, v in foot["values"].items()} == pytest.approx(theirs["values"], rel=1e-12)
        series = frame_series(rec, foot["columns"])
        want = numpy_stances(series["total_force"], rec.dt_s)
        assert [tuple(s["frames"]) + (s["complete"],) for s in foot["stances"]] == want
        rows = [r for r in curves if r["foot"] == foot["foot"]]
        assert len(rows) == 101 * len(want) > 0
        for k, (a, b, _) in enumerate(want):
            part = rows[101 * k : 101 * (k + 1)]
            assert {int(r["stance"]) for r in part} == {k}
            for name in ("contact_area", "total_", "peak_pressure", "cop_x", "cop_y"):
                col = next(c for c in part[0] if c.startswith(name))
                key = next(c for c in series if c.startswith(name))
                np.testing.assert_allclose(column(part, col), interp(a, b, series[key]), rtol=0, atol=1.5e-4, err_msg=col)


def test_study_curves_csv_is_every_folders_curves(tmp_path):
    paths = [WALK, DATA / "synthetic-walk.lst"]
    rows = pymodal.batch([str(p) for p in paths], tmp_path / "study", figures="none", report="none")
    table = read_csv(tmp_path / "study" / "study_curves.csv")
    n = 0
    for r in rows:
        own = read_csv(tmp_path / "study" / r["output"] / "curves.csv")
        mine = [t for t in table if t["output"] == r["output"]]
        assert len(mine) == len(own) > 0
        for got, want in zip(mine, own):
            assert got["path"] == r["path"]
            assert all(got[c] == v for c, v in want.items())
        n += len(own)
    assert len(table) == n
