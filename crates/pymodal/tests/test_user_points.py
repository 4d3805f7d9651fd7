"""pymodal.run(points=..., regions=...): the user's points and regions followed through a
synthetic walk with a known motion, checked against the truth and against numpy sums over the
mask."""

import numpy as np
import pytest

import pymodal


def walk_and_frames(frames=30):
    walk = pymodal.SyntheticWalk(frames=frames)
    rec = walk.recording()
    return walk, rec, np.asarray(rec.frames, dtype=np.float64)


def test_points_given_as_an_array_follow_their_material_points():
    walk, rec, _ = walk_and_frames()
    cx, cy = 20.0, 45.0  # the centre of the default walk (40 columns, 84 rows)
    given = np.array([[cx, cy - 10.0], [cx + 2.0, cy + 12.0]])
    res = pymodal.run(rec, points=given)
    names = res["point_names"]
    assert len(names) == len(res["points"]) == len(res["point_steps"])
    user = [k for k, n in enumerate(names) if n is not None]
    assert [names[k] for k in user] == ["p1", "p2"]
    assert any(n is None for n in names)  # the outline's default points too
    for k, g in zip(user, given):
        rows = res["points"][k]
        assert len(rows) == 30 and rows[0, 0] == 0
        truth = walk.true_positions(29, g[None, :])[0]
        assert np.linalg.norm(rows[-1, 1:] - truth) < 1.0
        assert (res["point_steps"][k][:, 1] == -1).all()


def test_points_from_a_file_with_names_and_a_frame(tmp_path):
    walk, rec, _ = walk_and_frames(frames=20)
    cx, cy = 20.0, 45.0
    q = walk.true_positions(5, np.array([[cx, cy]]))[0]
    f = tmp_path / "points.csv"
    f.write_text(f"name,x_mm,y_mm,frame\nmid,{q[0] * 5},{q[1] * 5},5\n")
    res = pymodal.run(rec, points=f, out=tmp_path / "run")
    k = res["point_names"].index("mid")
    # Given on frame 5, carried backwards to frame 0 and forwards to frame 19.
    got = res["points"][k]
    assert list(got[:, 0]) == list(range(20))
    assert np.allclose(got[5, 1:], q)
    truth = np.array([walk.true_positions(int(t), np.array([[cx, cy]]))[0] for t in got[:, 0]])
    assert np.hypot(*(got[:, 1:] - truth).T).max() < 1.0
    lines = (tmp_path / "run" / "points.csv").read_text().splitlines()
    header = lines[0].split(",")
    assert header[-3:] == ["kind", "name", "round_trip_sensels"]
    mine = [ln.split(",") for ln in lines[1:] if ln.split(",")[-3:-1] == ["user", "mid"]]
    assert len(mine) == 20


def test_a_region_mask_is_followed_and_its_fixed_rows_are_numpy_sums(tmp_path):
    _, rec, frames = walk_and_frames()
    threshold = 10.0  # the walk's noise threshold
    rows = np.arange(frames.shape[1])[:, None]
    mask = ((frames[0] >= threshold) & (rows < 30)).astype(np.int32)
    mask[(frames[0] >= threshold) & (rows >= 55)] = 2  # a heel region
    np.save(tmp_path / "mask.npy", mask)
    res = pymodal.run(rec, regions=tmp_path / "mask.npy", out=tmp_path / "run")
    regions = res["region_series"]
    assert {r["region"] for r in regions} == {1, 2}
    assert {r["kind"] for r in regions} == {"moving", "fixed"}
    # Oracle: the fixed region's force is the sum of its loaded values x sensel area (25 mm²)
    # in N (kPa x mm² x 1e-3), its area the mask's sensels x 25 mm², its peak the max.
    for r in regions:
        if r["kind"] != "fixed":
            continue
        f = frames[r["frame"]]
        inside = mask == r["region"]
        loaded = inside & (f >= threshold)
        np.testing.assert_allclose(r["total_force_n"], f[loaded].sum() * 25e-3, rtol=1e-6)
        np.testing.assert_allclose(r["area_mm2"], inside.sum() * 25.0)
        np.testing.assert_allclose(r["peak_pressure_kpa"], f[inside].max(), rtol=1e-5)
        if loaded.any():
            np.testing.assert_allclose(r["mean_pressure_kpa"], f[loaded].mean(), rtol=1e-5)
    # On the frame it is drawn on, the moving region is the mask.
    at0 = {(r["region"], r["kind"]): r for r in regions if r["frame"] == 0}
    for label in (1, 2):
        assert at0[(label, "moving")]["sensels"] == at0[(label, "fixed")]["sensels"]
    # The folder's region_series.csv holds the same rows.
    lines = (tmp_path / "run" / "region_series.csv").read_text().splitlines()
    assert len(lines) - 1 == len(regions)
    # As an array too, the same rows.
    again = pymodal.run(rec, regions=mask)
    assert again["region_series"] == regions


def test_bad_points_and_regions_raise_input_errors():
    _, rec, frames = walk_and_frames(frames=4)
    with pytest.raises(pymodal.InputError, match="'p1'|\"p1\""):
        pymodal.run(rec, points=[[0.5, 0.5]])
    with pytest.raises(pymodal.InputError, match="row 0"):
        pymodal.run(rec, points=[[np.nan, 1.0]])
    with pytest.raises(pymodal.InputError, match="mask is 3 × 2"):
        pymodal.run(rec, regions=np.ones((3, 2), np.int32))
    with pytest.raises(pymodal.InputError, match="points"):
        pymodal.run(rec, points=3.5)
