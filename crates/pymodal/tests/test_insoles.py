"""A pedar recording's two insoles measured per foot (Recording.gait_measures()["feet"]) against
NumPy on the export's own columns: each insole's peak pressure, PTI, force-time integral,
contact time and stances, with its force weighed by the image cells each sensor covers."""

import json
from pathlib import Path

import numpy as np
import pytest

import pymodal
from test_curves import numpy_stances

DATA = Path(__file__).resolve().parents[3] / "crates" / "pedo-io" / "tests" / "data"
ASC = DATA / "pedar-example-3.01-4.00.asc"


def export_columns():
    """The export's frame interval and values, frames × 198 (the left insole's 99 sensors, then
    the right's), read by NumPy from the text."""
    lines = ASC.read_text().splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("time[")) + 1
    a = np.loadtxt(lines[start:])
    return a[1, 0] - a[0, 0], a[:, 1:]


def sensor_cells(rec, values):
    """Per sensor, how many cells of the image hold its values over every frame; and per cell
    of a sensor, its sensor (-1 for a cell that is no sensor or never loaded)."""
    image = np.nan_to_num(rec.frames).reshape(len(rec), -1).astype(np.float32)
    series = {values[:, k].astype(np.float32).tobytes(): k for k in range(values.shape[1])}
    owner = np.full(image.shape[1], -1)
    for i in np.flatnonzero(image.any(axis=0)):
        owner[i] = series[image[:, i].tobytes()]
    return np.bincount(owner[owner >= 0], minlength=values.shape[1]), owner


def numpy_values(p, area, dt):
    """The oracle's measures of pressures `p` (frames x sensors), each sensor covering `area`
    cells: the force per frame, the frames above the contact threshold (a tenth of the force's
    range above its least) and the values the library reports."""
    force = p @ area
    lo, hi = force.min(), force.max()
    above = np.flatnonzero(force > lo + 0.1 * (hi - lo))
    want = {
        "peak_pressure": p.max(),
        "pti_max": (p * dt).sum(axis=0).max(),
        "peak_load": hi,
        "load_time_integral": force.sum() * dt,
        "contact_time": (above[-1] - above[0] + 1) * dt,
        "max_contact_area": ((p > 0) @ area).max(),
    }
    return force, above, want


def test_each_insole_is_measured_from_its_own_columns():
    rec = pymodal.read_recording(str(ASC))
    dt, values = export_columns()
    assert dt == pytest.approx(rec.dt_s)
    cells, owner = sensor_cells(rec, values)
    got = rec.gait_measures()
    assert list(got["feet"]) == ["left", "right"]
    width = rec.frames.shape[2]
    for name, sensors in [("left", slice(0, 99)), ("right", slice(99, 198))]:
        foot = got["feet"][name]
        a, b = foot["columns"]
        # Every cell of this insole's sensors lies in its columns, and no other insole's does.
        cols = np.flatnonzero(owner >= 0) % width
        mine = (owner[owner >= 0] >= sensors.start) & (owner[owner >= 0] < sensors.stop)
        assert np.all((cols >= a) & (cols < b) == mine)
        force, above, want = numpy_values(values[:, sensors], cells[sensors], dt)
        assert foot["values"] == pytest.approx(want, rel=1e-9)
        assert foot["contact_frames"] == (above[0], above[-1])
        # Its stances are found from its own force, each with its own values.
        stances = numpy_stances(force, dt)
        assert [(*s["frames"], s["complete"]) for s in foot["stances"]] == stances
        assert stances, name
        for s in foot["stances"]:
            f0, f1 = s["frames"]
            assert s["values"]["load_time_integral"] == pytest.approx(force[f0 : f1 + 1].sum() * dt, rel=1e-9)
        # Its images are the recording's on its columns, NaN elsewhere.
        for image in ("peak", "pti", "mean"):
            np.testing.assert_array_equal(foot[image][:, a:b], got[image][:, a:b])
            assert np.isnan(foot[image][:, :a]).all() and np.isnan(foot[image][:, b:]).all()
    # The two feet share the recording's load.
    total = sum(f["values"]["load_time_integral"] for f in got["feet"].values())
    assert total == pytest.approx(got["values"]["load_time_integral"], rel=1e-9)


def test_a_plate_has_no_feet_and_a_pickled_insole_recording_keeps_them():
    import pickle

    plate = pymodal.read_recording(str(DATA / "emed-test-1-10.lst"))
    assert plate.gait_measures()["feet"] == {}
    rec = pymodal.read_recording(str(ASC))
    again = pickle.loads(pickle.dumps(rec))
    assert again == rec
    feet = again.gait_measures(frames=(0, 40))["feet"]
    assert feet
    assert {k: v["columns"] for k, v in feet.items()} == {
        k: v["columns"] for k, v in rec.gait_measures(frames=(0, 40))["feet"].items()
    }


@pytest.mark.parametrize("rule", ["coarse", "fine"])
def test_each_insole_has_regions_of_its_own_measured_from_its_columns(rule):
    rec = pymodal.read_recording(str(ASC))
    dt, values = export_columns()
    cells, owner = sensor_cells(rec, values)
    got = rec.regions(rule=rule)
    feet = rec.gait_measures()["feet"]
    assert rec.feet == {side: tuple(feet[side]["columns"]) for side in ("left", "right")}
    labels = got["labels"].ravel()
    names, sides = got["names"], got["sides"]
    assert sides == ["left"] * (len(names) // 2) + ["right"] * (len(names) // 2)
    width = rec.frames.shape[2]
    loaded = np.zeros(len(labels), bool)
    loaded[owner >= 0] = values[:, owner[owner >= 0]].max(axis=0) > 0
    for foot, sensors in [("left", range(0, 99)), ("right", range(99, 198))]:
        a, b = rec.feet[foot]
        # The foot's regions partition its footprint: every cell of its sensors ever loaded.
        ks = [k + 1 for k, s in enumerate(sides) if s == foot]
        footprint = loaded & np.isin(owner, sensors)
        assert np.array_equal(np.isin(labels, ks), footprint)
        assert np.all((np.flatnonzero(np.isin(labels, ks)) % width >= a))
        foot_force = values[:, sensors.start : sensors.stop] @ cells[sensors.start : sensors.stop]
        fti = {}
        for k in ks:
            mine = owner[labels == k]
            # One column per cell of the region, each a cell's area.
            _, _, want = numpy_values(values[:, mine], np.ones(len(mine)), dt)
            v = got["values"][f"{foot}/{names[k - 1]}"]
            assert {m: v[m] for m in want} == pytest.approx(want, rel=1e-9)
            fti[k] = want["load_time_integral"]
        # A foot's regions share its own impulse, all of it.
        assert sum(fti.values()) == pytest.approx(foot_force.sum() * dt, rel=1e-9)
        for k in ks:
            share = got["values"][f"{foot}/{names[k - 1]}"]["impulse_share"]
            assert share == pytest.approx(100 * fti[k] / sum(fti.values()), rel=1e-9)


def test_a_plate_has_no_feet_property():
    assert pymodal.read_recording(str(DATA / "emed-test-1-10.lst")).feet == {}


def test_each_insole_s_regions_move_with_it_through_its_own_stances(tmp_path):
    """A contour run carries each foot's regions through its own stances: the rows returned are
    the folder's, each moving row has its foot, a moving region's FTI is the sum of its rows'
    force, its share is of its own foot's fixed impulse, and on each stance's reference frame
    the foot's moving regions hold that foot's force as NumPy sums it from its insole's columns."""
    from test_measures_masks import read_csv, same_rows

    rec = pymodal.read_recording(str(ASC))
    dt, values = export_columns()
    cells, _ = sensor_cells(rec, values)
    # 40 frames: a stance of each foot (a run is seconds in a debug wheel).
    options = dict(report="none", figures="none", region_rule="coarse", frames=(0, 40))
    out = tmp_path / "run"
    pymodal.run(rec, out=str(out), **options)
    res = pymodal.run(rec, **options)
    same_rows(res["regions"], read_csv(out / "regions.csv"))
    same_rows(res["region_series"], read_csv(out / "region_series.csv"))
    moving = [r for r in res["regions"] if r["kind"] == "moving"]
    fixed = [r for r in res["regions"] if r["kind"] == "fixed"]
    assert {r["foot"] for r in moving} == {"left", "right"}
    series = res["region_series"]
    assert {r["foot"] for r in series} == {"left", "right"}
    force_column = next(c for c in series[0] if c.startswith("total_"))
    fti_name = "fti" if any(r["measure"] == "fti" for r in fixed) else "load_time_integral"
    stances = json.loads((out / "regions.json").read_text())["moving"]["stances"]
    for foot, sensors in [("left", slice(0, 99)), ("right", slice(99, 198))]:
        foot_force = values[:, sensors] @ cells[sensors]
        fixed_fti = sum(r["value"] for r in fixed if r["foot"] == foot and r["measure"] == fti_name)
        for r in (r for r in moving if r["foot"] == foot and r["measure"] == fti_name):
            rows = [s for s in series
                    if s["foot"] == foot and s["kind"] == "moving" and s["name"] == r["region"]]
            total = sum(s[force_column] or 0.0 for s in rows) * dt
            assert r["value"] == pytest.approx(total, rel=1e-4, abs=1e-6)
            share = next(q["value"] for q in moving if q["foot"] == foot
                         and q["region"] == r["region"] and q["measure"] == "impulse_share")
            assert share == pytest.approx(100 * r["value"] / fixed_fti, rel=1e-4, abs=1e-6)
        own = [s for s in stances if s["foot"] == foot]
        assert own
        for s in own:
            t = s["reference_frame"]
            held = sum(q[force_column] or 0.0 for q in series if q["foot"] == foot
                       and q["kind"] == "moving" and q["frame"] == t)
            assert 0.9 * foot_force[t] <= held <= 1.0001 * foot_force[t], (foot, t)
