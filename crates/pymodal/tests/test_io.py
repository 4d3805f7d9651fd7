"""pymodal io bindings: recordings, contours against scikit-image, surfaces, isocontours."""

import pathlib

import numpy as np
import pytest

import pymodal

skimage_measure = pytest.importorskip("skimage.measure")

DATA = pathlib.Path(__file__).resolve().parents[2] / "pedo-io" / "tests" / "data"
ASF = DATA / "FrasP01L.asf"


@pytest.fixture(scope="module")
def rec():
    return pymodal.read_recording(str(ASF))


def test_read_recording_attributes(rec):
    f = rec.frames
    assert f.shape == (205, 60, 21) and f.dtype == np.float32
    assert rec.pitch_mm == (5.08, 5.08)
    assert rec.dt_s == 0.032
    assert rec.units == "kPa"
    assert rec.format == "asf"
    nan = np.isnan(f)
    # The no-sensor mask is the same in every frame and equals ~sensor_mask.
    assert (nan == nan[0]).all()
    assert (nan[0] == ~rec.sensor_mask).all()
    assert nan[0].sum() == 305
    assert np.nanmax(f) == 760.0 and np.nanmin(f) == 0.0
    # Measures against numpy.
    g = np.nan_to_num(f).astype(np.float64)
    np.testing.assert_allclose(rec.total_force, g.sum(axis=(1, 2)) * 25.8064e-3, rtol=1e-9)
    np.testing.assert_allclose(rec.contact_area, (g > 0).sum(axis=(1, 2)) * 25.8064)
    np.testing.assert_array_equal(rec.peak_pressure, g.max(axis=(1, 2)))
    np.testing.assert_array_equal(rec.peak_image, g.max(axis=0))
    loaded = g.sum(axis=(1, 2)) > 0
    rows, cols = np.mgrid[0:60, 0:21]
    cx = (g * cols).sum(axis=(1, 2))[loaded] / g.sum(axis=(1, 2))[loaded]
    cy = (g * rows).sum(axis=(1, 2))[loaded] / g.sum(axis=(1, 2))[loaded]
    np.testing.assert_allclose(rec.cop[loaded], np.c_[cx, cy], rtol=1e-9)
    assert np.isnan(rec.cop[~loaded]).all()
    m = rec.measures(50.0)
    np.testing.assert_array_equal(m["contact_sensors"], (g > 50).sum(axis=(1, 2)))


def test_read_errors_name_the_file(tmp_path):
    bad = tmp_path / "broken.asf"
    bad.write_bytes(ASF.read_bytes()[:100000])
    with pytest.raises(ValueError, match="broken.asf"):
        pymodal.read_recording(str(bad))
    with pytest.raises(FileNotFoundError, match="missing.npy"):
        pymodal.read_recording(str(tmp_path / "missing.npy"))


def test_npy_from_numpy(tmp_path):
    a = np.arange(2 * 3 * 4, dtype=np.int16).reshape(2, 3, 4)
    for order, arr in (("C", a), ("F", np.asfortranarray(a))):
        p = tmp_path / f"a{order}.npy"
        np.save(p, arr)
        r = pymodal.read_recording(str(p))
        np.testing.assert_array_equal(r.frames, a.astype(np.float32))
    f = np.random.default_rng(0).random((5, 6)).astype(np.float64)
    f[0, 0] = np.nan
    np.save(tmp_path / "b.npy", f)
    r = pymodal.read_recording(str(tmp_path / "b.npy"))
    assert r.frames.shape == (1, 5, 6)
    assert np.isnan(r.frames[0, 0, 0]) and not r.sensor_mask[0, 0]
    np.testing.assert_allclose(r.frames[0, 1:, :], f[1:, :].astype(np.float32))


def _sk_contours(frame, level, fully_connected="low"):
    padded = np.pad(np.nan_to_num(frame).astype(np.float64), 1)
    out = []
    for c in skimage_measure.find_contours(padded, level, fully_connected=fully_connected):
        xy = c[:, ::-1] - 1.0  # (row, col) -> (x, y), undo the padding
        if np.allclose(xy[0], xy[-1]):
            xy = xy[:-1]
        out.append(xy)
    return out


def _signed_area(p):
    x, y = p[:, 0], p[:, 1]
    return 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)


@pytest.mark.parametrize("fully_connected", ["low", "high"])
def test_contours_match_skimage(rec, fully_connected):
    frames = rec.frames
    checked = 0
    for t in range(0, 205, 4):
        frame = frames[t]
        for level in (1.5, 20.5, 80.5):
            ours = pymodal.contours(frame, level=level, fully_connected=fully_connected)
            theirs = _sk_contours(frame, level, fully_connected)
            assert len(ours) == len(theirs), (t, level)
            for c in ours:
                assert c.shape[1] == 2
                assert _signed_area(c) > 0  # counter-clockwise in (x, y)
                # The skimage contour with the same points, to sub-pixel (here: exact) agreement.
                best = min(
                    theirs,
                    key=lambda s: np.abs(np.sort(s, axis=0) - np.sort(c, axis=0)).max()
                    if len(s) == len(c) else np.inf,
                )
                assert len(best) == len(c)
                d = np.sqrt(((c[:, None, :] - best[None, :, :]) ** 2).sum(-1))
                assert d.min(axis=1).max() < 1e-9 and d.min(axis=0).max() < 1e-9
                checked += 1
    assert checked > 50


def test_contours_resampling_and_smoothing(rec):
    frame = rec.frames[np.argmax(rec.total_force)]
    cs = pymodal.contours(frame, n_points=64)
    assert cs and all(c.shape == (64, 2) for c in cs)
    cs = pymodal.contours(frame, spacing=1.0, smooth=1.0, threshold=3.0)
    for c in cs:
        seg = np.linalg.norm(np.diff(np.vstack([c, c[:1]]), axis=0), axis=1)
        # Uniform in arc length: chords are at most the arc step and close to it on average.
        assert seg.max() <= seg.mean() * 1.05 and seg.min() > 0.5 * seg.mean()
        assert abs(seg.mean() - 1.0) < 0.1
    up = pymodal.contours(frame, level=20.5, upsample=4)
    base = pymodal.contours(frame, level=20.5)
    # Upsampling refines, it does not move the object: total areas agree to a few percent.
    a_up = sum(abs(_signed_area(c)) for c in up)
    a = sum(abs(_signed_area(c)) for c in base)
    assert abs(a_up - a) < 0.05 * a
    chain = pymodal.contours(frame, method="chain", smooth=1.0, level=5.0)
    assert chain and all(_signed_area(c) > 0 for c in chain)
    with pytest.raises(ValueError):
        pymodal.contours(np.zeros((3, 3, 3)))
    assert pymodal.contours(np.zeros((4, 4))) == []


def test_surface_is_a_valid_triangulation(rec):
    frame = rec.frames[np.argmax(rec.total_force)]
    s = pymodal.surface(frame, threshold=3.0, smooth=1.0, max_nodes=120)
    p, t = s.points, s.triangles
    assert p.shape[1] == 3 and t.shape[1] == 3 and t.dtype == np.int64
    assert len(p) <= 120 and t.min() >= 0 and t.max() < len(p)
    a, b, c = p[t[:, 0]], p[t[:, 1]], p[t[:, 2]]
    area = 0.5 * ((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1]))
    assert (area > 1e-9).all()
    edges = {tuple(sorted(e)) for tri in t for e in ((tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0]))}
    assert len(np.unique(t)) - len(edges) + len(t) == 1  # Euler characteristic of a disc
    zr = np.ptp(p[:, 2])
    assert np.isclose(zr, max(np.ptp(p[:, 0]), np.ptp(p[:, 1])))
    with pytest.raises(ValueError):
        pymodal.surface(np.zeros((5, 5)))


def test_isocontours_nest(rec):
    frame = rec.frames[np.argmax(rec.total_force)]
    levels = [10.0, 40.0, 90.0]
    iso = pymodal.isocontours(frame, levels, smooth=1.0, threshold=3.0)
    assert [lv for lv, _ in iso] == sorted(lv for lv, _ in iso)
    by = {lv: [c for l2, c in iso if l2 == lv] for lv in levels}
    for lo, hi in zip(levels, levels[1:]):
        for c in by[hi]:
            inside = np.zeros(len(c), dtype=int)
            for outer in by[lo]:
                inside += skimage_measure.points_in_poly(c, outer)
            assert (inside % 2 == 1).all()
    iso3 = pymodal.isocontours(frame, levels, smooth=1.0, threshold=3.0, three_d=True)
    for lv, c in iso3:
        assert c.shape[1] == 3 and (c[:, 2] == lv).all()


def test_recording_from_array_keeps_values_mask_and_units(rec):
    frames = rec.frames  # NaN where there is no sensor
    r = pymodal.Recording.from_array(frames, pitch_mm=5.08, frame_rate=31.25, units="kPa")
    assert r.shape == rec.shape
    np.testing.assert_array_equal(np.isnan(r.frames), np.isnan(frames))
    np.testing.assert_array_equal(np.nan_to_num(r.frames), np.nan_to_num(frames))
    np.testing.assert_array_equal(r.sensor_mask, rec.sensor_mask)
    assert r.pitch_mm == (5.08, 5.08)
    assert r.dt_s == pytest.approx(0.032)
    assert r.units == "kPa"
    # The same measures as the file it came from.
    np.testing.assert_allclose(r.total_force, rec.total_force)


def test_recording_from_array_with_an_explicit_mask_and_one_frame():
    frame = np.arange(12, dtype=float).reshape(3, 4)
    mask = np.ones((3, 4), bool)
    mask[0, 0] = False
    r = pymodal.Recording.from_array(frame, mask=mask)
    assert r.shape == (1, 3, 4)
    assert np.isnan(r.frames[0, 0, 0]) and r.frames[0, 2, 3] == 11
    assert r.pitch_mm is None and r.dt_s is None


@pytest.mark.parametrize(
    "frames, kwargs, message",
    [
        (np.zeros(5), {}, "(T, H, W) or (H, W)"),
        (np.zeros((2, 3)), {"mask": np.ones((3, 2), bool)}, "mask has shape"),
        (np.zeros((2, 3)), {"pitch_mm": -1.0}, "pitch"),
        (np.zeros((2, 3)), {"frame_rate": 0.0}, "frame_rate"),
        # A misspelt unit would turn forces in N into the values' sum times mm², silently.
        (np.zeros((2, 3)), {"units": "kpascal"}, "units = kpascal: expected a pressure unit"),
        (np.full((2, 3), 1e39), {}, "frames: 1e39 at frame 0, row 0, column 0 is beyond the float32 range"),
    ],
)
@pytest.mark.filterwarnings("ignore:overflow encountered in cast")  # numpy's, beside the error
def test_recording_from_array_refuses_bad_input(frames, kwargs, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        pymodal.Recording.from_array(frames, **kwargs)


def test_read_recording_takes_a_pedar_layout(tmp_path):
    asc = DATA / "pedar-example-3.01-4.00.asc"
    bundled = pymodal.read_recording(asc)
    layout = DATA.parents[1] / "layouts" / "pedar-pressuRe.csv"
    same = pymodal.read_recording(asc, layout=layout)
    np.testing.assert_array_equal(np.nan_to_num(same.frames), np.nan_to_num(bundled.frames))
    with pytest.raises(FileNotFoundError):
        pymodal.read_recording(asc, layout=tmp_path / "missing.csv")


def test_measures_count_sensors_at_the_threshold():
    # As the docstring and frames.csv say: above 0 and at or above the threshold (not strictly
    # above it); the peak is the frame's whatever the threshold.
    f = np.zeros((2, 10, 10))
    f[:, 3:7, 3:7] = 5.0
    f[:, 4:6, 4:6] = 10.0
    rec = pymodal.Recording.from_array(f, pitch_mm=5.0, frame_rate=100, units="kPa")
    assert rec.measures(5.0)["contact_sensors"].tolist() == [16, 16]
    assert rec.measures(5.1)["contact_sensors"].tolist() == [4, 4]
    assert rec.measures(11.0)["contact_sensors"].tolist() == [0, 0]
    assert rec.measures(11.0)["peak_pressure"].tolist() == [10.0, 10.0]
    assert "at or above" in pymodal.Recording.measures.__doc__
    assert "strictly" not in pymodal.Recording.measures.__doc__
