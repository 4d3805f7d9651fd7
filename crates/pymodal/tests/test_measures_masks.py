"""Region curves (curves.csv's per-region columns) and the user's masks over the peak image
(masks=: polygons in mm, a label image, a 2-D array), against independent NumPy computations:
numpy.interp of each region's force and peak per frame over each stance, matplotlib's
point-in-polygon for the polygons, and the region measures of docs/measures.md recomputed from
the frames."""

import csv
import json
from pathlib import Path

import numpy as np
import pytest
from matplotlib.path import Path as Polygon

import pymodal

ROOT = Path(__file__).resolve().parents[3]
BENCH = ROOT / "benches" / "data"
WALK = ROOT / "examples" / "data" / "FrasP01L.asf"
STEP = BENCH / "emed-pressuRe-step.lst"


def read_csv(path):
    with open(path, newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))


def frames_of(rec, threshold):
    f = np.asarray(rec.frames, dtype=np.float64)
    exists = ~np.isnan(f[0])
    v = np.nan_to_num(f, nan=0.0)
    loaded = (v > 0) & (v >= threshold) & exists
    return v, loaded, exists


def region_series(rec, labels, k, threshold):
    """Region k's force (N) and peak pressure (kPa) per frame, kPa recordings only."""
    assert rec.units.lower() == "kpa"
    v, loaded, exists = frames_of(rec, threshold)
    area = rec.sensel_area_mm2 or float(np.prod(rec.pitch_mm))
    inside = labels == k
    force = np.where(loaded & inside, v, 0.0).sum(axis=(1, 2)) * area * 1e-3
    peak = np.where(inside & exists, v, 0.0).max(axis=(1, 2))
    return force, np.maximum(peak, 0.0)


def interp(first, last, values):
    return np.interp(np.linspace(first, last, 101), np.arange(first, last + 1), values[first : last + 1])


@pytest.mark.parametrize(
    "path", [WALK, pytest.param(STEP, marks=pytest.mark.xdist_group("fine-step"))], ids=lambda p: p.name
)
def test_region_curves_are_numpy_interp_of_each_region_s_frames(path, tmp_path, request):
    if path == STEP:
        # The same run as test_regions.py's: made once (conftest.py).
        rec, out = request.getfixturevalue("fine_run_of_the_step")
    else:
        rec = pymodal.read_recording(str(path))
        out = tmp_path / "run"
        pymodal.run(rec, out=str(out), report="none", figures="none", region_rule="fine")
    labels = np.load(out / "regions.npy").astype(int)
    meta = json.loads((out / "regions.json").read_text())
    measures = json.loads((out / "measures.json").read_text())
    names = [meta["labels"][str(k)] for k in range(1, len(meta["labels"]) + 1)]
    curves = read_csv(out / "curves.csv")
    threshold = measures["contact_threshold"]
    first_frame = measures["frames"][0]
    assert measures["stances"], "no stance to test on"
    assert len(curves) == 101 * len(measures["stances"])
    total = np.zeros(len(curves))
    for k, name in enumerate(names, start=1):
        assert f"{name}_force_n" in curves[0] and f"{name}_peak_pressure_kpa" in curves[0]
        force, peak = region_series(rec, labels, k, threshold)
        got_f = np.array([float(r[f"{name}_force_n"]) for r in curves])
        got_p = np.array([float(r[f"{name}_peak_pressure_kpa"]) for r in curves])
        for s, stance in enumerate(measures["stances"]):
            a, b = (f - first_frame for f in stance["frames"])
            rows = slice(101 * s, 101 * (s + 1))
            # Written with 4 decimals.
            np.testing.assert_allclose(got_f[rows], interp(a, b, force), rtol=1e-9, atol=1.5e-4, err_msg=name)
            np.testing.assert_allclose(got_p[rows], interp(a, b, peak), rtol=1e-9, atol=1.5e-4, err_msg=name)
        total += got_f
    # The fine regions cover the footprint: their forces add up to the stance's force.
    np.testing.assert_allclose(total, [float(r["total_force_n"]) for r in curves], rtol=1e-6, atol=2e-3)


def test_study_curves_carry_the_regions_columns(tmp_path):
    rows = pymodal.batch([str(WALK), str(STEP)], tmp_path / "study", figures="none", report="none",
                         region_rule="coarse")
    table = read_csv(tmp_path / "study" / "study_curves.csv")
    for region in ("hindfoot", "midfoot", "forefoot", "toes"):
        assert f"{region}_force_n" in table[0]
    for r in rows:
        own = read_csv(tmp_path / "study" / r["output"] / "curves.csv")
        mine = [t for t in table if t["output"] == r["output"]]
        assert len(mine) == len(own) > 0
        for got, want in zip(mine, own):
            assert all(got[c] == v for c, v in want.items())


def numpy_region_values(rec, labels, names, threshold):
    """docs/measures.md's region measures of the label image, in NumPy (kPa files only)."""
    v, loaded, exists = frames_of(rec, threshold)
    dt = rec.dt_s
    area = rec.sensel_area_mm2 or float(np.prod(rec.pitch_mm))
    peak = v.max(axis=0)
    pti = np.where(loaded, v, 0.0).sum(axis=0) * dt
    out, ftis = {}, {}
    for k, name in enumerate(names, start=1):
        inside = labels == k
        force = np.where(loaded & inside, v, 0.0).sum(axis=(1, 2)) * area * 1e-3
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


def polygons_of_walk(rec):
    """Two polygons in mm over the walk's footprint: the half of rows above and below its middle
    (a skewed cut, so that sensels lie on both sides of a slanted edge)."""
    f = np.nan_to_num(np.asarray(rec.frames, dtype=np.float64), nan=0.0)
    rows, cols = np.nonzero((f > 0).any(axis=0))
    dx, dy = rec.pitch_mm
    # Edges half a sensel off the centres: no centre lies on them.
    x0, x1 = (cols.min() - 0.5) * dx, (cols.max() + 0.5) * dx
    y0, y1 = (rows.min() - 0.5) * dy, (rows.max() + 0.5) * dy
    ym = 0.5 * (y0 + y1)
    return {
        "rearfoot": [(x0, ym + 7.3), (x1, ym - 4.1), (x1, y1), (x0, y1)],
        "front": [(x0, y0), (x1, y0), (x1, ym - 4.1), (x0, ym + 7.3)],
    }


def one_stance_of_the_walk():
    """The bundled walk's second stance with a blank frame or more on each side (frames 25–60 of
    205): each mask's region measures over a whole stance, at a sixth of the whole walk's cost."""
    walk = pymodal.read_recording(str(WALK))
    frames = np.asarray(walk.frames)[25:61]
    f = np.nan_to_num(frames, nan=0.0)
    assert not (f[0] > 0).any() and not (f[-1] > 0).any() and (f > 0).any()
    return pymodal.Recording.from_array(frames, pitch_mm=walk.pitch_mm, frame_rate=1.0 / walk.dt_s,
                                        units=walk.units)


def test_polygon_masks_are_measured_as_numpy_finds_them(tmp_path):
    rec = one_stance_of_the_walk()
    polygons = polygons_of_walk(rec)
    path = tmp_path / "masks.csv"
    with open(path, "w") as f:
        f.write("region,x_mm,y_mm\n")
        for name, vertices in polygons.items():
            for x, y in vertices:
                f.write(f"{name},{x},{y}\n")
    out = tmp_path / "run"
    pymodal.run(rec, out=str(out), report="none", figures="none", masks=str(path))
    # matplotlib's point-in-polygon of every sensel centre, (column × dx, row × dy).
    rows, cols = rec.frames.shape[1:]
    dx, dy = rec.pitch_mm
    yy, xx = np.mgrid[0:rows, 0:cols]
    centres = np.column_stack([xx.ravel() * dx, yy.ravel() * dy])
    labels = np.zeros(rows * cols, dtype=int)
    names = list(polygons)
    for k, name in enumerate(names, start=1):
        inside = Polygon(polygons[name]).contains_points(centres)
        assert not (inside & (labels > 0)).any()
        labels[inside] = k
    labels = labels.reshape(rows, cols)
    assert np.array_equal(np.load(out / "regions.npy").astype(int), labels)
    meta = json.loads((out / "regions.json").read_text())
    assert meta["rule"] == "masks"
    assert [meta["labels"][str(k)] for k in (1, 2)] == names
    threshold = json.loads((out / "measures.json").read_text())["contact_threshold"]
    want = numpy_region_values(rec, labels, names, threshold)
    got = [r for r in read_csv(out / "regions.csv") if r["kind"] == "fixed"]
    assert len(got) == 7 * len(names)
    for row in got:
        assert float(row["value"]) == pytest.approx(want[row["region"]][row["measure"]], rel=1e-9, abs=1e-12), row
    # The same regions as a 2-D array: the same values, regions named by their labels.
    out2 = tmp_path / "array"
    pymodal.run(rec, out=str(out2), report="none", figures="none", masks=labels * 3)
    got2 = {(r["measure"], r["region"]): r["value"] for r in read_csv(out2 / "regions.csv") if r["kind"] == "fixed"}
    for row in got:
        label = 3 * (names.index(row["region"]) + 1)
        assert got2[(row["measure"], f"region_{label}")] == row["value"]
    # And as a .npy label image, with its curves.
    npy = tmp_path / "labels.npy"
    np.save(npy, labels.astype(np.float64))
    out3 = tmp_path / "npy"
    pymodal.run(rec, out=str(out3), report="none", figures="none", masks=str(npy))
    assert [r for r in read_csv(out3 / "regions.csv") if r["kind"] == "fixed"] == [
        dict(r, region=f"region_{names.index(r['region']) + 1}") for r in got
    ]
    assert "region_1_force_n" in read_csv(out3 / "curves.csv")[0]


def test_masks_that_do_not_fit_are_input_errors(tmp_path):
    rec = pymodal.read_recording(str(WALK))
    rows, cols = rec.frames.shape[1:]
    with pytest.raises(pymodal.InputError, match="label image is"):
        pymodal.run(rec, out=str(tmp_path / "a"), report="none", figures="none",
                    masks=np.ones((rows + 1, cols)))
    bad = tmp_path / "overlap.csv"
    bad.write_text("region,x,y\na,0,0\na,10,0\na,10,10\nb,1,1\nb,9,1\nb,9,9\n")
    with pytest.raises(pymodal.InputError, match="overlap"):
        pymodal.run(rec, out=str(tmp_path / "b"), report="none", figures="none", masks=str(bad))
    with pytest.raises(ValueError, match="masks"):
        pymodal.run(rec, out=str(tmp_path / "c"), report="none", figures="none",
                    masks=str(bad), region_rule="fine")
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


def same_rows(got, written):
    """pymodal.run's rows (typed values) against a folder's CSV rows (text)."""
    assert len(got) == len(written)
    for g, w in zip(got, written):
        assert set(g) == set(w), (sorted(g), sorted(w))
        for key, text in w.items():
            value = g[key]
            if isinstance(value, str):
                assert value == text, key
            elif value is None:
                assert text == "", key
            else:
                # The CSV rounds to the decimals it shows.
                decimals = len(text.split(".")[1]) if "." in text and "e" not in text.lower() else 0
                tolerance = 0.51 * 10.0**-decimals if decimals else 1e-9 * max(1.0, abs(float(text)))
                assert abs(float(value) - float(text)) <= tolerance, (key, value, text)


@pytest.mark.parametrize("regions", ["fine", "masks"])
def test_a_run_without_a_folder_returns_the_folder_s_regions_and_region_curves(regions, tmp_path):
    rec = pymodal.read_recording(str(WALK))
    if regions == "fine":
        asked = {"region_rule": "fine"}
    else:
        labels = np.zeros(rec.frames.shape[1:], dtype=int)
        labels[: labels.shape[0] // 2] = 1
        labels[labels.shape[0] // 2 :] = 2
        asked = {"masks": labels}
    options = dict(report="none", figures="none", frames=(20, 120), **asked)
    out = tmp_path / "run"
    pymodal.run(rec, out=str(out), **options)
    res = pymodal.run(rec, **options)
    curves = read_csv(out / "curves.csv")
    region_columns = [c for c in curves[0] if c.endswith("_force_n") and c != "total_force_n"]
    assert len(region_columns) == (8 if regions == "fine" else 2)
    same_rows(res["curves"], curves)
    same_rows(res["regions"], read_csv(out / "regions.csv"))
    assert {r["kind"] for r in res["regions"]} == {"fixed", "moving"}
    same_rows(res["region_series"], read_csv(out / "region_series.csv"))
