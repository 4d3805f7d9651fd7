"""pymodal.run on a synthetic recording with known motion and on the bundled F-Scan recording,
and the pymodal.plot helpers."""

import hashlib
import pickle
from pathlib import Path

import numpy as np
import pytest

import pymodal

ROOT = Path(__file__).resolve().parents[3]
BUNDLED = ROOT / "examples" / "data" / "FrasP01L.asf"
VELOCITY = np.array([0.5, 1.0])


def moving_blob(frames=8, rows=40, cols=26):
    r, c = np.mgrid[0:rows, 0:cols]
    out = np.empty((frames, rows, cols), np.float32)
    for t in range(frames):
        cx, cy = 12 + VELOCITY[0] * t, 12 + VELOCITY[1] * t
        q = ((c - cx) / 5.0) ** 2 + ((r - cy) / 8.0) ** 2
        out[t] = np.maximum(0.0, 200.0 * (1.0 - q))
    return out


def test_run_on_known_motion():
    frames = moving_blob()
    res = pymodal.run(frames)
    table = res["table"]
    assert len(table) == len(frames) - 1
    assert len(res["matches"]) == len(table)
    for row, m in zip(table, res["matches"]):
        n, k = row["nodes_a"], row["nodes_b"]
        assert row["frame_b"] == row["frame_a"] + 1
        assert row["optimisation_matches"] == min(n, k)
        assert row["matches_after_excess"] == max(n, k) == len(m.pairs)
        assert 0 <= row["local_matches"] <= min(n, k)
        # A blob moving half a sensel a frame: every one-to-one match is a track step.
        assert row["trackable_matches"] == int((~m.excess).sum()) == min(n, k)
    objects = res["objects"]
    assert [o["points"].shape[0] for o in objects[:2]] == [table[0]["nodes_a"], table[0]["nodes_b"]]
    steps = np.concatenate([np.diff(t, axis=0) for t in res["tracks"] if len(t) > 1])
    assert np.all(steps[:, 0] == 1), "tracks advance one frame per step"
    median = np.median(steps[:, 1:3], axis=0)
    np.testing.assert_allclose(median, VELOCITY, atol=0.25)
    assert max(len(t) for t in res["tracks"]) == len(frames)
    assert res["summary"]["mean_trackable_percent"] == pytest.approx(100.0)
    # A rigid motion: the matches agree with one smooth, invertible map, so a node comes back
    # after the forward and the backward field, and the summary is the mean of the pairs'.
    trips = [row["round_trip_sensels"] for row in table]
    assert max(trips) < 0.05, trips
    assert all(row["field_residual_sensels"] < 0.5 for row in table)
    assert res["summary"]["mean_round_trip_sensels"] == pytest.approx(np.mean(trips), abs=1e-4)


def test_each_foot_has_its_own_measures():
    # Two feet side by side: each object measures the sensors inside its own outline (as
    # objects.csv), and the feet together are the frame (frames.csv).
    left, right = moving_blob(frames=3, cols=26), moving_blob(frames=3, cols=26)
    both = np.concatenate([left, 0.5 * right], axis=2)
    res = pymodal.run(both, pitch_mm=5.0, units="kPa")
    first = [o for o in res["objects"] if o["frame"] == 0]
    assert len(first) == 2
    loads = [o["total_force_n"] for o in first]
    np.testing.assert_allclose(sum(loads), res["frames"][0]["total_force_n"], rtol=1e-9)
    np.testing.assert_allclose(loads[1] / loads[0], 0.5, rtol=1e-6)
    frame0 = both[0].astype(np.float64)
    assert first[0]["contact_sensors"] == np.count_nonzero(frame0[:, :26])
    assert first[0]["peak_pressure_kpa"] == pytest.approx(frame0[:, :26].max(), rel=1e-6)
    r, c = np.mgrid[0:40, 0:26]
    w = frame0[:, :26]
    assert first[0]["cop_x_mm"] == pytest.approx(5.0 * (w * c).sum() / w.sum(), rel=1e-9)
    assert first[1]["cop_x_mm"] == pytest.approx(5.0 * ((w * c).sum() / w.sum() + 26), rel=1e-9)
    assert first[0]["centroid_x_mm"] == pytest.approx(5.0 * first[0]["centroid_x"])
    surf = pymodal.run(both, model="surface", surface_nodes=40)
    assert all(o["contact_sensors"] is None for o in surf["objects"])


def test_run_models_and_options():
    frames = moving_blob(frames=4)
    iso = pymodal.run(frames, model="isocontour", iso_levels=5)
    assert len(iso["table"]) == 4
    levels = [o["level"] for o in iso["objects"]]
    assert levels == sorted(levels)
    assert all(o["level_kpa"] is None for o in iso["objects"]), "no units, no kPa"
    in_n_cm2 = pymodal.run(frames, model="isocontour", iso_levels=5, units="N/cm²")
    assert [o["level"] for o in in_n_cm2["objects"]] == levels
    np.testing.assert_allclose([o["level_kpa"] for o in in_n_cm2["objects"]],
                               10.0 * np.array(levels), rtol=1e-12)
    assert all(o["level"] is None and o["level_kpa"] is None for o in pymodal.run(frames)["objects"])
    surf = pymodal.run(frames, model="surface", surface_nodes=40)
    assert len(surf["table"]) == 3
    assert all(o["points"].shape[1] == 3 and o["points"].shape[0] <= 40 for o in surf["objects"])
    local = pymodal.run(frames, search="local")
    assert all(r["optimisation_matches"] == 0 for r in local["table"])
    for solver in ("hungarian", "simplex"):
        other = pymodal.run(frames, solver=solver)
        assert [r["optimisation_matches"] for r in other["table"]] == [
            r["optimisation_matches"] for r in pymodal.run(frames)["table"]
        ]


def test_run_bundled_recording_from_path_and_recording():
    res = pymodal.run(str(BUNDLED), frames=(0, 40))
    assert len(res["table"]) >= 10
    rec = pymodal.read_recording(BUNDLED)
    again = pymodal.run(rec, frames=(0, 40))
    assert [r["nodes_a"] for r in again["table"]] == [r["nodes_a"] for r in res["table"]]


@pytest.mark.parametrize(
    "kwargs",
    [
        dict(model="mesh"),
        dict(search="both"),
        dict(modes=0.0),
        dict(frames=(5, 2)),
        dict(frames=(1, 999)),
        dict(iso_frame=3),
        dict(pitch_mm=-1.0),
        dict(pitch_mm=(1.0, 2.0, 3.0)),
        dict(frame_rate=0.0),
    ],
)
def test_run_bad_options_raise_value_error(kwargs):
    with pytest.raises(ValueError):
        pymodal.run(moving_blob(frames=3), **kwargs)


def test_negative_frames_count_back_from_the_end_like_a_slice():
    frames = moving_blob(frames=8)
    last = pymodal.run(frames, frames=(-3, None))
    assert last["summary"]["options"]["frames"] == "5..8", "the frames run, resolved"
    assert [r["frame"] for r in last["frames"]] == [5, 6, 7]
    assert timeless(last["table"]) == timeless(pymodal.run(frames, frames=(5, 8))["table"])
    all_but_last = pymodal.run(frames, frames=(0, -1))
    assert [r["frame"] for r in all_but_last["frames"]] == list(range(7))
    both = pymodal.run(frames, frames=[np.int64(-4), -2])
    assert both["summary"]["options"]["frames"] == "4..6"
    # Still out of range once counted from the end: the message names the range, the frame
    # count and what the negative index came to.
    with pytest.raises(pymodal.OptionError, match=r"^frames = -9\.\.: expected .*8 frames.*-9\.\. is -1\.\.8$"):
        pymodal.run(frames, frames=(-9, None))
    with pytest.raises(pymodal.OptionError, match=r"frames = 6\.\.-3: .*8 frames.* is 6\.\.5"):
        pymodal.run(frames, frames=(6, -3))
    # iso_frame lies within the range as resolved; the error names it both ways.
    iso = pymodal.run(frames, model="isocontour", iso_levels=3, frames=(-3, None), iso_frame=6)
    assert {o["frame"] for o in iso["objects"]} == {6}
    with pytest.raises(pymodal.OptionError, match=r"iso_frame = 2: .*frames 5\.\.8 \(frames -3\.\. of 8\)"):
        pymodal.run(frames, model="isocontour", frames=(-3, None), iso_frame=2)
    # The largest load among the frames run, not the whole recording.
    iso = pymodal.run(frames, model="isocontour", iso_levels=3, frames=(-2, None))
    assert {o["frame"] for o in iso["objects"]} <= {6, 7}


def timeless(rows):
    return [{k: v for k, v in r.items() if not k.endswith("_s")} for r in rows]


def test_track_steps_name_the_object_and_node_of_every_track_step():
    for model in ("contour", "isocontour", "surface"):
        res = pymodal.run(moving_blob(frames=5), model=model, iso_levels=4, surface_nodes=30)
        objects = res["objects"]
        assert len(res["track_steps"]) == len(res["tracks"]) > 0
        for t, s in zip(res["tracks"], res["track_steps"]):
            assert s.shape == (len(t), 2) and s.dtype == np.int64
            for (frame, *xyz), (o, n) in zip(t, s):
                assert objects[o]["frame"] == frame
                np.testing.assert_array_equal(objects[o]["points"][n], xyz)
        # Every node of every object is on exactly one track.
        nodes = sorted((int(o), int(n)) for s in res["track_steps"] for o, n in s)
        assert nodes == [(o["id"], n) for o in objects for n in range(len(o["points"]))]


def test_track_round_trips_are_those_of_tracks_csv_and_summarised_in_the_summary(tmp_path):
    import csv

    res = pymodal.run(BUNDLED, frames=(30, 60), out=tmp_path, figures="none", report="none")
    trips = res["track_round_trips"]
    assert trips.shape == (len(res["tracks"]),) and trips.dtype == np.float64
    # A track of one step has none; every longer contour track has one, 0 or more.
    lengths = np.array([len(t) for t in res["tracks"]])
    np.testing.assert_array_equal(np.isnan(trips), lengths < 2)
    assert (trips[lengths >= 2] >= 0).all() and np.ptp(trips[lengths >= 2]) > 0.5
    # tracks.csv gives each track's on every one of its rows (4 decimals).
    with open(tmp_path / "tracks.csv", newline="") as f:
        for r in csv.DictReader(f):
            want = trips[int(r["track"])]
            if np.isnan(want):
                assert r["round_trip_sensels"] == ""
            else:
                assert abs(float(r["round_trip_sensels"]) - want) <= 5e-5
    # summary.json: numpy's quantiles of the known ones.
    known = trips[~np.isnan(trips)]
    s = res["summary"]["track_round_trip_sensels"]
    assert s["tracks"] == len(known)
    for key, q in (("median", 0.5), ("p95", 0.95), ("max", 1.0)):
        assert s[key] == pytest.approx(np.quantile(known, q), rel=1e-9)
    assert s["over_1_percent"] == pytest.approx(100 * np.mean(known > 1.0))
    # Surfaces have no field: no figure.
    surf = pymodal.run(moving_blob(frames=4), model="surface", surface_nodes=30)
    assert np.isnan(surf["track_round_trips"]).all()
    assert surf["summary"]["track_round_trip_sensels"] is None


def test_reference_matches_explain_the_track_steps_drift_correction_makes():
    res = pymodal.run(str(BUNDLED), frames=(0, 40), drift_reference=10)
    objects, refs = res["objects"], res["reference_matches"]
    assert refs, "40 frames with a reference frame every 10 have reference pairs"
    # The one-to-one matches of the frame-to-frame pairs, and the tracked reference matches
    # (node of the second object -> node of its ancestor on the reference frame).
    direct = set()
    for row, m in zip(res["table"], res["matches"]):
        for (a, b), excess in zip(m.pairs, m.excess):
            if not excess:
                direct.add(((row["id_a"], int(a)), (row["id_b"], int(b))))
    tracked = {}
    for r in refs:
        assert objects[r["id_a"]]["frame"] == r["frame_a"] < r["frame_b"] - 1
        assert objects[r["id_b"]]["frame"] == r["frame_b"]
        m = r["match"]
        assert r["tracked"].shape == (len(m.pairs),) and r["tracked"].dtype == np.bool_
        assert not (r["tracked"] & m.excess).any()
        for (a, b) in m.pairs[r["tracked"]]:
            tracked[(r["id_b"], int(b))] = (r["id_a"], int(a))
    assert tracked
    # Every step is a frame-to-frame match or a tracked reference match from an earlier step of
    # its track; every tracked reference match is such a step.
    through_reference, reached = 0, set()
    for steps in res["track_steps"]:
        steps = [(int(o), int(n)) for o, n in steps]
        for k in range(1, len(steps)):
            step = (steps[k - 1], steps[k])
            anchored = tracked.get(steps[k]) in steps[:k]
            assert step in direct or anchored, step
            if anchored:
                reached.add(steps[k])
                through_reference += step not in direct
    assert reached == set(tracked)
    assert through_reference > 0, "no step needs a reference match"

    plain = pymodal.run(str(BUNDLED), frames=(0, 40))
    assert plain["reference_matches"] == []
    assert pymodal.run(str(BUNDLED), frames=(0, 40), drift_reference=10,
                       model="isocontour")["reference_matches"] == []


def test_frames_objects_and_tracks_are_zero_based():
    frames = moving_blob(frames=6)
    res = pymodal.run(frames, frames=(2, None))
    assert [o["id"] for o in res["objects"]] == list(range(len(res["objects"])))
    assert [o["frame"] for o in res["objects"]] == [2, 3, 4, 5]
    assert [(r["frame_a"], r["frame_b"]) for r in res["table"]] == [(2, 3), (3, 4), (4, 5)]
    assert {int(f) for t in res["tracks"] for f in t[:, 0]} == {2, 3, 4, 5}
    assert [r["frame"] for r in res["frames"]] == [2, 3, 4, 5]
    assert res["summary"]["options"]["frames"] == "2..6"
    # No pitch nor frame rate in a bare array: pixel columns only.
    assert res["objects"][0]["time_s"] is None and res["objects"][0]["points_mm"] is None
    assert "time_a_s" not in res["table"][0]
    iso = pymodal.run(frames, model="isocontour", iso_frame=0, iso_levels=3)
    assert {o["frame"] for o in iso["objects"]} == {0}


def test_run_reports_time_mm_and_provenance():
    res = pymodal.run(str(BUNDLED), frames=(20, 60))
    s = res["summary"]
    assert s["pedomatch_version"] == pymodal.__version__
    assert s["input"]["sha256"] == hashlib.sha256(BUNDLED.read_bytes()).hexdigest()
    assert s["input"]["format"] == "asf"
    assert s["recording"]["pitch_mm"] == [5.08, 5.08]
    assert s["recording"]["frame_rate_hz"] == pytest.approx(31.25)
    assert s["recording"]["pressure_units"] == "kPa"
    names = {o["name"] for group in ("match", "recording") for o in pymodal._options()[group]}
    # max_nodes is a limit, not a setting: left out of the record.
    assert set(s["options"]) == names - {"max_nodes"}
    assert {"read", "objects", "matching", "tracks"} <= set(s["timings_s"])
    for o in res["objects"]:
        assert o["time_s"] == pytest.approx(o["frame"] * 0.032)
        np.testing.assert_allclose(o["points_mm"], o["points"][:, :2] * 5.08)
    for row in res["table"]:
        assert row["time_b_s"] == pytest.approx(row["frame_b"] * 0.032)
    assert len(res["frames"]) == 40
    for row in res["frames"]:
        assert row["contact_area_mm2"] == pytest.approx(row["contact_sensors"] * 25.8064)
        assert row["time_s"] == pytest.approx(row["frame"] * 0.032)
    # Overridden units reach every table.
    res = pymodal.run(str(BUNDLED), frames=(20, 30), pitch_mm=(2.0, 3.0), frame_rate=100.0)
    assert res["summary"]["recording"]["pitch_mm"] == [2.0, 3.0]
    o = res["objects"][0]
    assert o["time_s"] == pytest.approx(o["frame"] / 100.0)
    np.testing.assert_allclose(o["points_mm"], o["points"][:, :2] * [2.0, 3.0])


def test_read_recording_units_override():
    rec = pymodal.read_recording(BUNDLED, pitch_mm=2.5, frame_rate=50.0)
    assert rec.pitch_mm == (2.5, 2.5)
    assert rec.dt_s == pytest.approx(0.02)
    assert pymodal.read_recording(BUNDLED).pitch_mm == (5.08, 5.08)


def test_units_name_the_pressure_of_a_file_that_states_none(tmp_path):
    path = tmp_path / "blob.npy"
    np.save(path, moving_blob(frames=3))
    bare = pymodal.read_recording(path)
    # Unknown units are None, as summary.json's null (not ''): the same value everywhere.
    assert bare.units is None
    assert pymodal.run(bare)["summary"]["recording"]["pressure_units"] is None
    assert pymodal.Recording.from_array(moving_blob(frames=2)).units is None
    assert pickle.loads(pickle.dumps(bare)).units is None
    rec = pymodal.read_recording(path, pitch_mm=5.0, units="N/cm2")
    assert rec.units == "N/cm²"
    # N/cm² is 10 kPa: the force in N follows from the units and the pitch (the peak stays in
    # the stated units).
    raw = moving_blob(frames=3)
    assert rec.peak_pressure[0] == pytest.approx(raw[0].max(), rel=1e-6)
    assert rec.total_force[0] == pytest.approx(10.0 * 25.0 * 1e-3 * raw[0].sum(), rel=1e-5)
    res = pymodal.run(str(path), units="kPa", pitch_mm=5.0)
    assert res["summary"]["recording"]["pressure_units"] == "kPa"
    assert res["summary"]["options"]["units"] == "kPa"
    with pytest.raises(pymodal.OptionError, match="units"):
        pymodal.read_recording(path, units="furlongs")
    with pytest.raises(pymodal.OptionError, match="units"):
        pymodal.run(str(path), units="furlongs")


def test_run_best_search_is_accepted():
    res = pymodal.run(moving_blob(frames=3), search="best")
    assert len(res["table"]) == 2
    assert all(r["optimisation_matches"] == r["nodes_a"] for r in res["table"])


def test_run_bad_input():
    with pytest.raises(ValueError):
        pymodal.run(np.zeros((2, 2, 2, 2)))
    with pytest.raises(FileNotFoundError):
        pymodal.run("/nonexistent/recording.asf")


def test_run_without_objects_raises_like_the_cli():
    # Frames whose pressures all lie below the noise threshold hold no object: an error naming
    # the frames, as `pedomatch run` gives, not an empty result.
    with pytest.raises(pymodal.DegenerateShapeError, match=r"no object to match in frames 0\.\.4"):
        pymodal.run(np.zeros((4, 20, 20), np.float32))
    with pytest.raises(pymodal.DegenerateShapeError, match=r"frames 1\.\.3"):
        pymodal.run(moving_blob(frames=3), frames=(1, 3), noise=1e6)


def test_a_recording_without_objects_is_named(tmp_path):
    path = tmp_path / "empty.npy"
    np.save(path, np.zeros((3, 10, 10), np.float32))
    with pytest.raises(pymodal.DegenerateShapeError) as info:
        pymodal.run(str(path))
    assert str(info.value).startswith(f"{path}: no object to match in frames 0..3"), info.value


def test_options_out_of_range_fail_before_the_run():
    # A smoothing wider than the smoother takes fails at once, naming the option, instead of
    # every frame being skipped.
    with pytest.raises(pymodal.OptionError, match="smooth"):
        pymodal.run(moving_blob(frames=3), smooth=2000.0)


def test_plot_helpers_draw():
    mpl = pytest.importorskip("matplotlib")
    mpl.use("Agg")
    from pymodal.plot import plot_match, plot_tracks

    t = np.linspace(0, 2 * np.pi, 30, endpoint=False)
    a = np.c_[3 * np.cos(t), 2 * np.sin(t)]
    b = a * 1.05 + 0.2
    m = pymodal.match(a, b)
    ax = plot_match(m, a, b)
    # Two outlines; the one-to-one matches are one collection of segments.
    assert len(ax.lines) == 2
    res = pymodal.run(moving_blob(frames=4))
    ax = plot_tracks(res["tracks"], min_length=4)
    from matplotlib.collections import LineCollection

    drawn = [c for c in ax.collections if isinstance(c, LineCollection)]
    assert len(drawn) == min(40, sum(len(tr) >= 4 for tr in res["tracks"]))
    with pytest.raises(ValueError):
        plot_match(m, a, np.zeros((5, 3)))


def _files(folder):
    return sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file())



def comparable(summary):
    """A summary without its timings nor how the file was read: pymodal.run, which also returns
    the whole result, reads whole a file the command line streams with tables only
    (input.streamed, input.read_whole)."""
    out = {k: v for k, v in summary.items() if k != "timings_s"}
    out["input"] = {k: v for k, v in summary["input"].items() if k not in ("streamed", "read_whole")}
    return out

@pytest.mark.parametrize(
    "outputs",
    [{}, {"tables": "parquet", "figures": "none", "report": "none"}],
    ids=["defaults", "parquet-lean"],
)
def test_run_with_out_writes_the_folder_of_pedomatch_run(tmp_path, outputs):
    """`run(out=...)` writes the folder `pedomatch run` writes (the same writer as a study's
    recording folder, `batch_row`): the same files, `report.html` included by default, the same
    bytes but for the timings; and it returns the summary it wrote."""
    import json

    options = dict(frames=(30, 60), **outputs)
    res = pymodal.run(BUNDLED, out=tmp_path / "run", **options)
    row = pymodal.batch_row(BUNDLED, tmp_path / "study", **options)
    assert row["status"] == "ok", row["message"]
    mine, study = tmp_path / "run", tmp_path / "study" / row["output"]
    assert _files(mine) == _files(study)
    assert ("report.html" in _files(mine)) == ("report" not in outputs)
    if not outputs:
        # The default figures are the summary set, the same in every front end: no pair figures.
        assert {"tracks.png", "curves.png", "peak.png"} <= set(_files(mine))
        assert not [f for f in _files(mine) if f.startswith("figures/")]
    tables = "parquet" if outputs else "csv"
    assert {f"pairs.{tables}", f"tracks.{tables}", "pairs.json", "summary.json"} <= set(_files(mine))
    for f in _files(mine):
        if f in ("summary.json", "report.html"):
            continue  # both hold the run's timings
        assert (mine / f).read_bytes() == (study / f).read_bytes(), f
    summary = json.loads((mine / "summary.json").read_text())
    assert res["summary"] == summary
    assert comparable(summary) == comparable(json.loads((study / "summary.json").read_text()))


def _pedomatch_binary():
    """The `pedomatch` binary of this checkout (`PEDOMATCH_BIN`, else the newest of the cargo
    target folders' debug and release builds), or None."""
    import os

    given = os.environ.get("PEDOMATCH_BIN")
    if given:
        return Path(given)
    targets = [ROOT / "target"]
    if os.environ.get("CARGO_TARGET_DIR"):
        targets.insert(0, Path(os.environ["CARGO_TARGET_DIR"]))
    found = [t / p / "pedomatch" for t in targets for p in ("debug", "release")]
    found = [b for b in found if b.is_file()]
    return max(found, key=lambda b: b.stat().st_mtime) if found else None


@pytest.mark.parametrize(
    "outputs",
    [{}, {"tables": "parquet", "figures": "none", "report": "none"}],
    ids=["defaults", "parquet-lean"],
)
def test_run_with_out_writes_the_folder_of_the_command_line(tmp_path, outputs):
    """`run(out=...)` and `pedomatch run --out` on the walk write the same files, byte for
    byte (`summary.json` but for its timings; `report.html` holds them too), since one run feeds
    the folder's writer of the command line and the result returned; and what `run` returns is
    what the folder holds."""
    import json
    import subprocess

    binary = _pedomatch_binary()
    if binary is None:
        pytest.skip("no pedomatch binary built (cargo build), nor PEDOMATCH_BIN")
    flags = ["--frames", "30..60"]
    for k, v in outputs.items():
        flags += [f"--{k}", v]
    cli = tmp_path / "cli"
    subprocess.run(
        [str(binary), "run", str(BUNDLED), "--out", str(cli), *flags],
        check=True,
        capture_output=True,
    )
    res = pymodal.run(str(BUNDLED), out=tmp_path / "py", frames=(30, 60), **outputs)
    py = tmp_path / "py"
    assert _files(py) == _files(cli)
    for f in _files(py):
        if f in ("summary.json", "report.html"):
            continue
        assert (py / f).read_bytes() == (cli / f).read_bytes(), f
    summary = json.loads((py / "summary.json").read_text())
    written = json.loads((cli / "summary.json").read_text())
    assert comparable(summary) == comparable(written)
    # With tables only the command line streams the file; pymodal.run, returning the whole
    # result too, reads it whole and says why. With figures both read it whole, for them.
    assert written["input"]["streamed"] == bool(outputs)
    assert summary["input"]["streamed"] is False
    assert summary["input"]["read_whole"] == (
        "the whole result is returned" if outputs else written["input"]["read_whole"]
    )
    assert res["summary"] == summary
    # The result returned is the run the folder holds: a row of pairs per matched pair, the
    # same counts.
    tables = "parquet" if outputs else "csv"
    assert summary["pairs"] == len(res["table"]) == len(res["matches"]) > 0
    assert summary["tracks"] == len(res["tracks"])
    assert summary["objects"] == len(res["objects"])
    if tables == "csv":
        import csv

        with open(py / "pairs.csv", newline="") as fh:
            rows = list(csv.DictReader(fh))
        assert [(int(r["id_a"]), int(r["id_b"])) for r in rows] == [
            (r["id_a"], r["id_b"]) for r in res["table"]
        ]
    # Each Match keeps its details (the affinity matrix) although the folder's run holds none.
    assert res["matches"][0].affinity.size > 0


def test_run_without_out_writes_nothing_and_bad_output_values_raise(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    pymodal.run(moving_blob(4))
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(pymodal.OptionError, match="report"):
        pymodal.run(moving_blob(4), out=tmp_path / "x", report="pdf")
    assert not (tmp_path / "x").exists()


def test_every_second_frame_keeps_the_recordings_frame_numbers_and_times():
    rec = pymodal.read_recording(BUNDLED)
    res = pymodal.run(rec, every=2, frames=(0, 60))
    table = res["table"]
    assert len(table) > 20
    assert table[0]["frame_a"] == 0
    for row in table:
        assert row["frame_a"] % 2 == 0 and row["frame_b"] == row["frame_a"] + 2, row
        assert row["time_a_s"] == pytest.approx(row["frame_a"] * rec.dt_s)
        assert row["time_b_s"] == pytest.approx(row["frame_b"] * rec.dt_s)
    assert all(o["frame"] % 2 == 0 for o in res["objects"])
    for track in res["tracks"]:
        assert (track[:, 0] % 2 == 0).all()
    assert res["summary"]["options"]["every"] == 2
    # The kept frames' objects are the full run's on those frames.
    full = pymodal.run(rec, frames=(0, 60))
    even = [(o["frame"], len(o["points"])) for o in full["objects"] if o["frame"] % 2 == 0]
    assert [(o["frame"], len(o["points"])) for o in res["objects"]] == even
    assert full["summary"]["options"]["every"] == 1
    # auto (the default) is every frame at the walk's 31.25 Hz, as given.
    assert pymodal.run(rec, every="auto", frames=(0, 60))["table"] == full["table"]


def test_every_is_checked():
    with pytest.raises(pymodal.OptionError, match="every"):
        pymodal.run(BUNDLED, every=0)
    with pytest.raises(TypeError, match="every"):
        pymodal.run(BUNDLED, every=2.5)
    with pytest.raises(pymodal.OptionError, match="auto"):
        pymodal.run(BUNDLED, every="2")
    with pytest.raises(pymodal.OptionError, match="multiple of every"):
        pymodal.run(BUNDLED, every=2, drift_reference=25)


def test_material_points_follow_the_synthetic_walk_and_are_no_nodes():
    # The foot moves 10 sensels, turns 12 degrees and its forefoot widens by 15 % in 40 frames:
    # the points seeded on frame 0's outline nodes stay within a node spacing (1 sensel) of
    # their material points to the last frame.
    walk = pymodal.SyntheticWalk(frames=40)
    res = pymodal.run(walk.recording())
    objects, points, steps = res["objects"], res["points"], res["point_steps"]
    first = objects[0]
    assert len(points) == len(steps) == len(first["points"])
    errors = []
    for p, s in zip(points, steps):
        assert p.shape == (len(s), 3) and s.dtype == np.int64
        assert s[0, 0] == first["id"] and s[0, 1] >= 0
        np.testing.assert_allclose(p[0, 1:], first["points"][s[0, 1]][:2])
        for (frame, _, _), (o, _) in zip(p, s):
            assert objects[o]["frame"] == frame
        truth = walk.true_positions(39, p[:1, 1:])[0]
        errors.append(np.linalg.norm(p[-1, 1:] - truth) if p[-1, 0] == 39 else np.inf)
    assert np.mean(np.array(errors) <= 1.0) >= 0.95, np.sort(errors)[-10:]
    # The other models follow no points.
    res = pymodal.run(moving_blob(frames=4), model="surface", surface_nodes=30)
    assert res["points"] == [] and res["point_steps"] == []


def test_points_csv_holds_the_points_of_the_result(tmp_path):
    res = pymodal.run(str(BUNDLED), frames=(0, 30), out=tmp_path / "run")
    rows = (tmp_path / "run" / "points.csv").read_text().splitlines()
    header = rows[0].split(",")
    assert header == ["point", "step", "frame", "time_s", "object_id", "seed_node", "x", "y",
                      "x_mm", "y_mm", "pressure_kpa", "kind", "name", "round_trip_sensels"]
    assert len(rows) - 1 == sum(len(p) for p in res["points"])
    rec = pymodal.read_recording(str(BUNDLED))
    frames = np.asarray(rec.frames)
    for line in rows[1:200]:
        cells = line.split(",")
        k, s, frame = int(cells[0]), int(cells[1]), int(cells[2])
        x, y, p = float(cells[6]), float(cells[7]), float(cells[10])
        np.testing.assert_allclose(res["points"][k][s], [frame, x, y], atol=1e-4)
        # Bilinear between sensel centres: within the four values around the point.
        r0, c0 = int(np.floor(y)), int(np.floor(x))
        block = frames[frame, r0:r0 + 2, c0:c0 + 2]
        assert block.min() - 1e-3 <= p <= block.max() + 1e-3


def test_point_round_trips_are_those_of_points_csv_and_summarised_in_the_summary(tmp_path):
    import csv

    res = pymodal.run(BUNDLED, frames=(30, 60), out=tmp_path, figures="none", report="none",
                      points=[[9.0, 51.0]])
    trips = res["point_round_trips"]
    assert len(trips) == len(res["points"]) > 1
    for p, t in zip(res["points"], trips):
        assert t.shape == (len(p),) and t.dtype == np.float64
        # None on the frame a point was seeded on; 0 or more where it has one.
        assert (t[~np.isnan(t)] >= 0).all()
    # An outline point is seeded on its first step: NaN there, a figure on its next step.
    outline = [t for t, n in zip(trips, res["point_names"]) if n is None and len(t) > 1]
    assert outline and all(np.isnan(t[0]) and not np.isnan(t[1]) for t in outline)
    known = np.concatenate([t[~np.isnan(t)] for t in trips])
    assert np.ptp(known) > 0.2
    # points.csv gives each point's on its rows (4 decimals), empty where NaN.
    with open(tmp_path / "points.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == sum(len(t) for t in trips)
    for r in rows:
        want = trips[int(r["point"])][int(r["step"])]
        if np.isnan(want):
            assert r["round_trip_sensels"] == ""
        else:
            assert abs(float(r["round_trip_sensels"]) - want) <= 5e-5
    # summary.json (the folder's, the result's) and the summary without a folder: numpy's
    # quantiles of every point's and frame's.
    whole = pymodal.run(BUNDLED, frames=(30, 60), points=[[9.0, 51.0]])
    for summary in (res["summary"], whole["summary"]):
        s = summary["point_round_trip_sensels"]
        assert s["steps"] == len(known)
        for key, q in (("median", 0.5), ("p95", 0.95), ("max", 1.0)):
            assert s[key] == pytest.approx(np.quantile(known, q), rel=1e-6)
        assert s["over_1_percent"] == pytest.approx(100 * np.mean(known > 1.0))
    # Surfaces follow no points: no figure.
    surf = pymodal.run(moving_blob(frames=4), model="surface", surface_nodes=30)
    assert surf["point_round_trips"] == [] and surf["summary"]["point_round_trip_sensels"] is None
