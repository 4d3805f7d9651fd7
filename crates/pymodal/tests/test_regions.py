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


@pytest.mark.xdist_group("fine-step")
def test_a_run_folder_s_regions_are_the_recording_s(fine_run_of_the_step):
    # The run of emed-pressuRe-step.lst with the fine regions (conftest.py), which
    # test_measures_masks.py's region curves read too.
    rec, out = fine_run_of_the_step
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


def test_a_surface_run_carries_the_regions_as_the_contour_run():
    """A surface run's moving regions are carried by the contour field of its frames: the
    contour run's moving regions on the same frames, row for row; each moving FTI is the sum of
    its region_series rows' force times dt, each fixed row's force NumPy's sum over its mask, and
    on the frame of largest contact the moving regions hold most of the foot's force."""
    rec = pymodal.read_recording(str(WALK))
    # One whole stance of the walk (frames 29–50).
    options = dict(region_rule="coarse", frames=(25, 55))
    surface = pymodal.run(rec, model="surface", **options)
    contour = pymodal.run(rec, model="contour", **options)

    def moving(res):
        return [r for r in res["regions"] if r["kind"] == "moving"]

    names = ["hindfoot", "midfoot", "forefoot", "toes"]
    assert {r["region"] for r in moving(surface)} == set(names)
    assert moving(surface) == moving(contour)
    series = surface["region_series"]
    assert series and series == contour["region_series"]
    assert {s["kind"] for s in series} == {"fixed", "moving"}

    labels = rec.regions("coarse", frames=options["frames"])["labels"]
    f = np.nan_to_num(np.asarray(rec.frames, dtype=np.float64), nan=0.0)
    area = rec.sensel_area_mm2 or float(np.prod(rec.pitch_mm))
    frame_force = f.sum(axis=(1, 2)) * area * 1e-3

    def force(rows):
        return np.array([s["total_force_n"] or 0.0 for s in rows])

    held = {}
    for k, name in enumerate(names, start=1):
        rows = {kind: [s for s in series if s["name"] == name and s["kind"] == kind]
                for kind in ("fixed", "moving")}
        frames = [s["frame"] for s in rows["moving"]]
        assert frames == [s["frame"] for s in rows["fixed"]] and frames
        fti = next(r["value"] for r in moving(surface)
                   if r["region"] == name and r["measure"] == "fti")
        assert fti > 0
        assert fti == pytest.approx(force(rows["moving"]).sum() * rec.dt_s, rel=1e-6)
        mask = np.where(labels == k, f[frames], 0.0).sum(axis=(1, 2)) * area * 1e-3
        assert np.allclose(force(rows["fixed"]), mask, rtol=1e-6, atol=1e-9)
        held[name] = dict(zip(frames, force(rows["moving"])))
    stance = sorted(held["hindfoot"])
    # The moving regions never hold more than the frame's force; on the frame of largest
    # contact (where they are drawn from the masks) nearly all of it.
    for t in stance:
        total = sum(h.get(t, 0.0) for h in held.values())
        assert total <= frame_force[t] * (1 + 1e-6) + 1e-9, t
    widest = max(stance, key=lambda t: int((f[t] > 0).sum()))
    total = sum(h.get(widest, 0.0) for h in held.values())
    assert total >= 0.95 * frame_force[widest], (widest, total, frame_force[widest])
