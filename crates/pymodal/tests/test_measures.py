"""The measures of a recording (Recording.gait_measures, a run folder's peak.npy, pti.npy, mean.npy
and measures.json) against the same sums in NumPy on the real samples, and against the vendor's
own values of the XSENSOR and novel emed software where a sample ships them."""

import datetime
import gzip
import json
import re
from pathlib import Path

import numpy as np
import pytest

import pymodal

ROOT = Path(__file__).resolve().parents[3]
DATA = ROOT / "crates" / "pedo-io" / "tests" / "data"
WALK = ROOT / "examples" / "data" / "FrasP01L.asf"
KPA = {"kpa": 1.0, "n/cm²": 10.0, "mpa": 1000.0, "mmhg": 0.1333224}


def kpa(units):
    """kPa per unit of the units a recording states (1 when it states none or unknown ones)."""
    return KPA.get((units or "").lower(), 1.0)

SAMPLES = [
    WALK,
    DATA / "emed-test-1-10.lst",
    DATA / "pedar-example-3.01-4.00.asc",
    DATA / "iscan-test-1-20.csv",
    DATA / "footscan-FrasP01L-11-20.txt",
    DATA / "zebris-FrasP01L-26-55.xml",
    DATA / "synthetic-walk.lst",
]


def numpy_measures(rec, threshold=0.0):
    """Every measure from rec.frames by the definitions of docs/measures.md, in NumPy."""
    f = np.asarray(rec.frames, dtype=np.float64)  # (T, H, W), NaN where there is no sensor
    exists = ~np.isnan(f[0])
    v = np.nan_to_num(f, nan=0.0)
    loaded = (v > 0) & (v >= threshold) & exists
    k = kpa(rec.units)
    dt = rec.dt_s or 1.0
    area = rec.sensel_area_mm2 or (np.prod(rec.pitch_mm) if rec.pitch_mm else None)
    per_value = k * area * 1e-3 if ((rec.units or "").lower() in KPA and area) else (area or 1.0)
    sums = np.where(loaded, v, 0.0).sum(axis=0)
    counts = loaded.sum(axis=0)
    peak = np.where(exists, np.maximum(v.max(axis=0), 0.0) * k, np.nan)
    pti = np.where(exists, sums * k * dt, np.nan)
    mean = np.where(exists, np.divide(sums * k, counts, out=np.zeros_like(sums), where=counts > 0), np.nan)
    force = np.where(loaded, v, 0.0).sum(axis=(1, 2)) * per_value
    lo, hi = force.min(), force.max()
    above = np.flatnonzero(force > lo + 0.1 * (hi - lo))
    return {
        "peak": peak,
        "pti": pti,
        "mean": mean,
        "force": force,
        "values": {
            "peak_pressure": np.nanmax(peak),
            "pti_max": np.nanmax(pti),
            "force": hi,
            "fti": force.sum() * dt,
            "contact_time": (above[-1] - above[0] + 1) * dt,
            "max_contact_area": loaded.sum(axis=(1, 2)).max() * (area or 1.0),
        },
        "contact_frames": (int(above[0]), int(above[-1])),
    }


@pytest.mark.parametrize("path", SAMPLES, ids=lambda p: p.name)
def test_gait_measures_are_numpys_sums_on_real_samples(path):
    rec = pymodal.read_recording(str(path))
    got = rec.gait_measures()
    want = numpy_measures(rec)
    for name in ("peak", "pti", "mean"):
        assert got[name].dtype == np.float64 and got[name].shape == rec.frames.shape[1:]
        np.testing.assert_allclose(got[name], want[name], rtol=1e-9, atol=1e-12, equal_nan=True)
        assert np.array_equal(np.isnan(got[name]), np.isnan(rec.frames[0])), "NaN exactly where no sensor is"
    # The peak image is the recording's own over every frame.
    np.testing.assert_allclose(got["peak"] / kpa(rec.units), np.where(np.isnan(rec.frames[0]), np.nan, rec.peak_image), equal_nan=True)
    values, w = got["values"], want["values"]
    force = "peak_force" if "peak_force" in values else "peak_load"
    fti = "fti" if "fti" in values else "load_time_integral"
    for ours, theirs in [
        ("peak_pressure", "peak_pressure"),
        ("pti_max", "pti_max"),
        (force, "force"),
        (fti, "fti"),
        ("contact_time", "contact_time"),
        ("max_contact_area", "max_contact_area"),
    ]:
        assert values[ours] == pytest.approx(w[theirs], rel=1e-9), ours
        assert np.isfinite(values[ours])
    assert got["contact_frames"] == want["contact_frames"]
    assert got["frames"] == (0, len(rec))
    # Each frame's force is frames.csv's (Recording.total_force).
    np.testing.assert_allclose(want["force"], rec.total_force, rtol=1e-9, atol=1e-9)


def test_units_name_the_values_and_unknown_units_are_never_kpa_or_newtons():
    walk = pymodal.read_recording(str(WALK))
    units = walk.gait_measures()["units"]
    assert units == {
        "peak_pressure": "kPa",
        "pti_max": "kPa·s",
        "peak_force": "N",
        "fti": "N·s",
        "contact_time": "s",
        "max_contact_area": "mm²",
    }
    # The same values without units, rate and pitch: the file's units, frames, sensels.
    bare = pymodal.Recording.from_array(np.nan_to_num(walk.frames))
    got = bare.gait_measures()
    assert got["units"] == {
        "peak_pressure": "file units",
        "pti_max": "file units·frame",
        "peak_load": "file units·sensel",
        "load_time_integral": "file units·sensel·frame",
        "contact_time": "frame",
        "max_contact_area": "sensel",
    }
    ref = walk.gait_measures()["values"]
    assert got["values"]["contact_time"] == pytest.approx(ref["contact_time"] / walk.dt_s)
    assert got["values"]["peak_pressure"] == pytest.approx(ref["peak_pressure"])


def test_a_frame_range_and_a_threshold_bound_the_measures():
    rec = pymodal.read_recording(str(WALK))
    got = rec.gait_measures(threshold=50.0, frames=(20, 60))
    frames = rec.frames[20:60]
    sub = pymodal.Recording.from_array(np.nan_to_num(frames), pitch_mm=rec.pitch_mm, frame_rate=1 / rec.dt_s, units="kPa")
    want = numpy_measures(sub, threshold=50.0)
    np.testing.assert_allclose(np.nan_to_num(got["pti"]), want["pti"], rtol=1e-9)
    assert got["values"]["fti"] == pytest.approx(want["values"]["fti"], rel=1e-9)
    assert got["contact_frames"] == tuple(20 + f for f in want["contact_frames"])
    assert got["frames"] == (20, 60)


def test_a_recording_without_contact_is_a_clear_error():
    rec = pymodal.Recording.from_array(np.zeros((3, 4, 5)))
    with pytest.raises(pymodal.InputError, match="no sensor is loaded"):
        rec.gait_measures()
    with pytest.raises(pymodal.InputError, match="empty or beyond"):
        pymodal.read_recording(str(WALK)).gait_measures(frames=(10, 500))


def vendor_forces(path):
    """The total force of each picture as the emed software printed it: the last number of each
    page's `Force` line (N)."""
    text = path.read_bytes().decode("latin-1")
    return np.array([float(line.split()[-1]) for line in text.splitlines() if line.startswith("Force")])


def test_peak_force_and_fti_agree_with_the_emed_softwares_own_forces():
    path = DATA / "emed-test-1-10.lst"
    rec = pymodal.read_recording(str(path))
    vendor = vendor_forces(path)
    assert len(vendor) == len(rec) == 10
    got = rec.gait_measures()["values"]
    dt = rec.dt_s
    assert dt == pytest.approx(0.01)
    # Tolerances of the brief: 13 % for FTI; they agree far closer (the vendor rounds to 0.01 N).
    assert got["peak_force"] == pytest.approx(vendor.max(), rel=0.01)
    assert got["fti"] == pytest.approx(vendor.sum() * dt, rel=0.01)
    # Frame by frame too.
    np.testing.assert_allclose(rec.total_force, vendor, rtol=0.01, atol=0.01)


def test_a_run_folder_holds_the_measures(tmp_path):
    rec = pymodal.read_recording(str(WALK))
    out = tmp_path / "run"
    res = pymodal.run(rec, out=str(out), report="none")
    # The run counts contact at the file's noise threshold, as its frames table does.
    got = rec.gait_measures(threshold=rec.noise_threshold)
    for name in ("peak", "pti", "mean"):
        arr = np.load(out / f"{name}.npy")
        assert arr.dtype == np.float64
        np.testing.assert_array_equal(arr, got[name])
    doc = json.loads((out / "measures.json").read_text())
    assert doc["frames"] == [0, len(rec)]
    assert doc["contact_frames"] == list(got["contact_frames"])
    for name, value in got["values"].items():
        assert doc["values"][name] == {"value": pytest.approx(value, rel=1e-12), "unit": got["units"][name]}
    summary = json.loads((out / "summary.json").read_text())
    assert summary["measures"] == doc["values"]
    assert res["summary"]["measures"] == doc["values"]
    for figure in ("peak.png", "pti.png"):
        assert (out / figure).read_bytes().startswith(b"\x89PNG")
    # The frames table's peak pressure and force per frame reach the same maxima.
    table = np.genfromtxt(out / "frames.csv", delimiter=",", names=True)
    assert table["peak_pressure_kpa"].max() == pytest.approx(got["values"]["peak_pressure"], rel=1e-6)
    assert table["total_force_n"].max() == pytest.approx(got["values"]["peak_force"], rel=1e-4)
    assert re.fullmatch(r"[0-9.]+", str(doc["contact_threshold"]))


def test_a_run_without_a_folder_has_the_measures_in_its_summary():
    rec = pymodal.read_recording(str(WALK))
    res = pymodal.run(rec, frames=(30, 60))
    got = rec.gait_measures(threshold=rec.noise_threshold, frames=(30, 60))
    assert res["summary"]["measures"] == {
        name: {"value": pytest.approx(v, rel=1e-12), "unit": got["units"][name]} for name, v in got["values"].items()
    }


def read_xsensor(path):
    """One XSENSOR Foot CSV export, parsed here (pedomatch does not read the format): per frame
    and insole (`LF`, `RF`) its sensels (31, 11) in mmHg and the software's own values; and the
    frames' clock times (s). Region blocks (`GROUP`) are skipped."""
    lines = [l for l in gzip.open(path, "rt", encoding="utf-8-sig").read().splitlines() if l.strip(", ")]
    frames, times, block = [], [], None
    i = 0
    while i < len(lines):
        cells = lines[i].split(",")
        key, value = cells[0], cells[1].strip() if len(cells) > 1 else ""
        i += 1
        if key == "FRAME":
            frames.append({})
            block = None
        elif key == "Time" and block is None:
            t = datetime.datetime.strptime(value, "%H:%M:%S.%f")
            times.append(t.hour * 3600 + t.minute * 60 + t.second + t.microsecond / 1e6)
        elif key == "SENSOR":
            block = frames[-1].setdefault(value.split()[0].rsplit("-", 1)[-1], {})
        elif key == "GROUP":
            block = {}
        elif key == "SENSELS":
            rows = []
            while i < len(lines) and re.fullmatch(r"[0-9.]+", lines[i].split(",")[0]):
                rows.append(lines[i].split(","))
                i += 1
            block["grid"] = rows
        elif block is not None and key:
            block[key] = value
    for f in frames:
        for insole in f.values():
            insole["grid"] = np.array([[float(x) for x in r[:11]] for r in insole["grid"]])
    return frames, np.array(times)


def test_a_stance_agrees_with_the_xsensor_softwares_own_values():
    frames, times = read_xsensor(DATA / "xsensor-pressuRe.csv.gz")
    assert len(frames) == len(times) == 101
    dt = (times[-1] - times[0]) / (len(times) - 1)
    rec = pymodal.Recording.from_array(
        np.array([f["LF"]["grid"] for f in frames]), pitch_mm=(8.6, 8.6), frame_rate=1 / dt, units="mmHg"
    )
    vendor = lambda key: np.array([float(f["LF"][key]) for f in frames])
    # Frame by frame: the software's peak pressure, estimated load and contact area.
    np.testing.assert_allclose(rec.peak_pressure, vendor("Peak Pressure (mmHg)"), rtol=1e-6)  # float32
    load = vendor("Est. Load (N)")
    np.testing.assert_allclose(rec.total_force[load > 5], load[load > 5], rtol=0.01)
    np.testing.assert_allclose(rec.contact_area / 100, vendor("Contact Area (cm²)"), rtol=0.01, atol=0.01)
    # The one whole stance of the left insole in the excerpt (unloaded before and after it): the
    # software's stance values are over it.
    loaded = np.flatnonzero(rec.total_force > 0)
    gaps = np.flatnonzero(np.diff(loaded) > 1)
    start, end = loaded[gaps[0] + 1], loaded[gaps[1]] + 1 if len(gaps) > 1 else loaded[-1] + 1
    assert (start, end) == (43, 88) and rec.total_force[start - 1] == rec.total_force[end] == 0
    got = rec.gait_measures(frames=(int(start), int(end)))["values"]
    mmhg = 0.1333224  # kPa
    stance = frames[0]["LF"]
    assert got["peak_pressure"] == pytest.approx(float(stance["Stance Peak Pressure"]) * mmhg, rel=0.05)
    assert got["peak_force"] == pytest.approx(float(stance["Stance Peak Load (N)"]), rel=0.05)
    assert got["fti"] == pytest.approx(float(stance["Impulse (N-S)"]), rel=0.13)
    # The stance time (ms) is the software's own rule; ours (10 % of the force range) is within 10 %.
    assert got["contact_time"] == pytest.approx(float(stance["Stance Time"]) / 1000, rel=0.10)
