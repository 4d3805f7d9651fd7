"""pymodal.batch, batch_row and find_recordings on a small study with a corrupt file: the rows
agree with pymodal.run on each recording, a corrupt file is an error row, a second run skips,
rows are picklable, and the folders are those of `pedomatch run`."""

import json
import os
import pickle
import shutil
from pathlib import Path

import pytest

import pymodal

DATA = Path(__file__).resolve().parents[3] / "crates" / "pedo-io" / "tests" / "data"
COLUMNS = [
    "path",
    "output",
    "format",
    "frames",
    "frame_rate_hz",
    "pitch_x_mm",
    "pitch_y_mm",
    "pressure_units",
    "pairs",
    "mean_local_percent",
    "mean_optimisation_percent",
    "mean_trackable_percent",
    "mean_round_trip_sensels",
    "tracks",
    "track_round_trip_median_sensels",
    "track_round_trip_p95_sensels",
    "point_round_trip_median_sensels",
    "point_round_trip_p95_sensels",
    "peak_pressure_kpa",
    "pti_max_kpa_s",
    "peak_force_n",
    "fti_n_s",
    "contact_time_s",
    "max_contact_area_mm2",
    "wall_time_s",
    "status",
    "message",
]


@pytest.fixture()
def study(tmp_path):
    """Three recordings (two named trial.lst in different folders) and a truncated F-Scan file."""
    (tmp_path / "in" / "a").mkdir(parents=True)
    (tmp_path / "in" / "b").mkdir()
    shutil.copy(DATA / "emed-test-1-10.lst", tmp_path / "in" / "a" / "trial.lst")
    shutil.copy(DATA / "synthetic-walk.lst", tmp_path / "in" / "b" / "trial.lst")
    shutil.copy(DATA / "tekscan-FrasP01L-11-20.csv", tmp_path / "in" / "tekscan.csv")
    asf = (DATA / "FrasP01L.asf").read_bytes()
    (tmp_path / "in" / "corrupt.asf").write_bytes(asf[: len(asf) // 50])
    return tmp_path


def timeless(rows):
    return [{k: v for k, v in r.items() if k != "wall_time_s"} for r in rows]


def test_find_recordings_searches_folders_and_globs(study):
    found = pymodal.find_recordings(study / "in")
    assert [Path(p).relative_to(study / "in").as_posix() for p in found] == [
        "a/trial.lst",
        "b/trial.lst",
        "corrupt.asf",
        "tekscan.csv",
    ]
    pattern = str(study / "in" / "*" / "trial.lst")
    assert pymodal.find_recordings([pattern, study / "in" / "a"]) == found[:2]
    # A mistyped pattern is an error, not a row saying "No such file".
    with pytest.raises(pymodal.InputError, match="matches no file"):
        pymodal.find_recordings(str(study / "in" / "*" / "trail.lst"))


def test_a_file_named_as_a_recording_is_never_left_out(tmp_path):
    # An empty walk.asf or a garbled .npy is meant as a recording: found, and an error row that
    # says why; a text file that is no recording is passed over.
    shutil.copy(DATA / "synthetic-walk.lst", tmp_path / "good.lst")
    (tmp_path / "empty.asf").write_bytes(b"")
    (tmp_path / "garbled.npy").write_bytes(bytes(range(1, 200)))
    (tmp_path / "notes.txt").write_text("subject 3, left foot\n")
    # Tables of another kind that sniff as numbers are no recordings either.
    (tmp_path / "anthropometrics.csv").write_text("subject,age,mass_kg,height_m\n1,34,70.2,1.78\n2,28,65.0,1.70\n")
    (tmp_path / "forceplate.csv").write_text("time,fz\n0.00,0\n0.01,12.5\n0.02,80.1\n")
    (tmp_path / "grid.csv").write_text("0,0,1,3,4,2\n0,4,23,5,0,0\n0,2,9,7,1,0\n")
    found = pymodal.find_recordings(tmp_path)
    assert [Path(p).name for p in found] == ["empty.asf", "garbled.npy", "good.lst", "grid.csv"]
    rows = {Path(r["path"]).name: r for r in pymodal.batch(tmp_path, jobs=1, figures="none")}
    assert rows["good.lst"]["status"] == "ok"
    assert rows["empty.asf"]["status"] == "error"
    assert "empty.asf" in rows["empty.asf"]["message"]
    assert "empty" in rows["empty.asf"]["message"]
    assert rows["garbled.npy"]["status"] == "error"
    assert "garbled.npy" in rows["garbled.npy"]["message"]


def test_a_file_that_cannot_be_read_gets_a_row(tmp_path):
    shutil.copy(DATA / "synthetic-walk.lst", tmp_path / "good.lst")
    locked = tmp_path / "locked.txt"
    locked.write_text("1,2,3\n")
    locked.chmod(0)
    try:
        if os.access(locked, os.R_OK):
            pytest.skip("file permissions do not bind this user (root)")
        found = pymodal.find_recordings(tmp_path)
        assert [Path(p).name for p in found] == ["good.lst", "locked.txt"]
        rows = {Path(r["path"]).name: r for r in pymodal.batch(tmp_path, jobs=1, figures="none")}
        assert rows["locked.txt"]["status"] == "error"
        assert "ermission denied" in rows["locked.txt"]["message"]
    finally:
        locked.chmod(0o644)


def test_batch_rows_agree_with_run_and_name_the_failure(study):
    rows = pymodal.batch(study / "in", jobs=2, figures="none")
    assert [list(r) for r in rows] == [COLUMNS] * 4
    by_name = {Path(r["path"]).relative_to(study / "in").as_posix(): r for r in rows}
    bad = by_name["corrupt.asf"]
    assert bad["status"] == "error" and bad["format"] == "asf"
    assert "corrupt.asf" in bad["message"] and bad["frames"] is None
    for name in ["a/trial.lst", "b/trial.lst", "tekscan.csv"]:
        row = by_name[name]
        assert row["status"] == "ok" and row["output"] is None
        summary = pymodal.run(study / "in" / name)["summary"]
        assert row["frames"] == summary["recording"]["frames"]
        assert row["pairs"] == summary["pairs"] > 0
        assert row["tracks"] == summary["tracks"]
        recording = summary["recording"]
        assert row["frame_rate_hz"] == pytest.approx(recording["frame_rate_hz"])
        assert [row["pitch_x_mm"], row["pitch_y_mm"]] == pytest.approx(recording["pitch_mm"])
        assert row["pressure_units"] == recording["pressure_units"]
        assert row["mean_local_percent"] == pytest.approx(summary["mean_local_percent"])
        assert row["mean_optimisation_percent"] == pytest.approx(summary["mean_optimisation_percent"])
        assert row["mean_trackable_percent"] == pytest.approx(summary["mean_trackable_percent"])
        assert row["mean_round_trip_sensels"] == pytest.approx(summary["mean_round_trip_sensels"], abs=1e-4)
        s = summary["track_round_trip_sensels"]
        for q in ("median", "p95"):
            assert row[f"track_round_trip_{q}_sensels"] == pytest.approx(s[q], abs=1e-4)
            # A study of tables only follows no material points (docs/outputs.md, points.csv).
            assert row[f"point_round_trip_{q}_sensels"] is None
    assert pickle.loads(pickle.dumps(rows)) == rows


def test_batch_writes_folders_and_resumes(study):
    out = study / "out"
    first = pymodal.batch([study / "in"], out, figures="none")
    assert [r["status"] for r in first].count("ok") == 3
    table = json.loads((out / "study.json").read_text())
    assert table["rows"] == first
    assert table["inputs"] == [str(study / "in")]
    assert table["pedomatch_version"] == pymodal.__version__
    assert (table["recordings"], table["ok"], table["error"], table["kept"]) == (4, 3, 1, 0)
    assert table["options"]["spacing"] == 1.0 and table["options"]["noise"] is None
    assert (out / "study.csv").read_text().splitlines()[0] == ",".join(COLUMNS)
    for r in first:
        if r["status"] == "ok":
            folder = out / r["output"]
            for f in ["pairs.csv", "objects.csv", "matches.csv", "tracks.csv", "frames.csv", "summary.json"]:
                assert (folder / f).is_file(), folder / f
            assert (folder / "report.html").is_file(), "the folder of pedomatch run, report included"
    second = pymodal.batch([study / "in"], out, figures="none")
    assert [r["status"] for r in second] == ["skipped" if r["status"] == "ok" else "error" for r in first]
    assert timeless(second) != timeless(first)  # status and message differ ...
    keep = ["frames", "pairs", "tracks", "mean_local_percent", "wall_time_s"]
    # A skipped row keeps the earlier numbers; an error row is tried again.
    ok = [i for i, r in enumerate(first) if r["status"] == "ok"]
    assert [[second[i][k] for k in keep] for i in ok] == [[first[i][k] for k in keep] for i in ok]
    forced = pymodal.batch([study / "in"], out, figures="none", force=True)
    assert [r["status"] for r in forced] == [r["status"] for r in first]


def test_negative_frames_are_resolved_for_each_recording_of_a_study(study):
    out = study / "out"
    rows = pymodal.batch([study / "in"], out, figures="none", frames=(-3, None))
    assert [r["status"] for r in rows].count("ok") == 3
    assert json.loads((out / "study.json").read_text())["options"]["frames"] == "-3.."
    for r in rows:
        if r["status"] != "ok":
            continue
        n = r["frames"]
        summary = json.loads((out / r["output"] / "summary.json").read_text())
        assert summary["options"]["frames"] == f"{n - 3}..{n}", r["path"]
        run = pymodal.run(r["path"], frames=(n - 3, n))["summary"]
        assert (r["pairs"], r["tracks"]) == (run["pairs"], run["tracks"])
    # A second run finds each folder complete: the same frames, however they were written.
    again = pymodal.batch([study / "in"], out, figures="none", frames=(-3, None))
    assert [r["status"] for r in again].count("skipped") == 3
    row = pymodal.batch_row(study / "in" / "tekscan.csv", frames=(-300, None), figures="none")
    assert row["status"] == "error" and "frames = -300.." in row["message"]
    assert f"{row['frames']} frames" in row["message"]


def test_batch_row_is_one_row_of_batch(study):
    paths = pymodal.find_recordings(study / "in")
    rows = [pymodal.batch_row(p, spacing=1.5, figures="none") for p in paths]
    assert timeless(rows) == timeless(pymodal.batch(paths, spacing=1.5, figures="none"))


def test_bad_options_raise_before_any_work(study):
    with pytest.raises(pymodal.OptionError, match="unknown option"):
        pymodal.batch(study / "in", spacings=2)
    with pytest.raises(pymodal.OptionError):
        pymodal.batch(study / "in", spacing=-1)
    with pytest.raises(pymodal.OptionError):
        pymodal.batch(study / "in", figures="gif")
    with pytest.raises(pymodal.OptionError):
        pymodal.batch(study / "in", jobs=0)
    foreign = study / "thesis"
    foreign.mkdir()
    (foreign / "chapter.tex").write_text("precious")
    with pytest.raises(pymodal.InputError, match="not a pedomatch study"):
        pymodal.batch(study / "in", foreign)


def test_parquet_tables_load_like_the_csv(study):
    pd = pytest.importorskip("pandas")
    pytest.importorskip("pyarrow")
    csv_rows = pymodal.batch([study / "in"], study / "csv", figures="none")
    pq_rows = pymodal.batch([study / "in"], study / "pq", figures="none", tables="parquet")
    assert timeless(pq_rows) == timeless(csv_rows)
    assert not (study / "pq" / "study.csv").exists()
    study_pq = pd.read_parquet(study / "pq" / "study.parquet")
    assert list(study_pq.columns) == COLUMNS
    # Numbers as study.csv writes them: percentages to 0.1, wall times to the millisecond.
    pd.testing.assert_frame_equal(
        study_pq.drop(columns="wall_time_s"),
        pd.DataFrame(pq_rows).drop(columns="wall_time_s"),
        check_dtype=False,
        rtol=0,
        atol=0.05 + 1e-9,
    )
    assert (study_pq["wall_time_s"] - [r["wall_time_s"] for r in pq_rows]).abs().max() <= 5e-4
    compared = 0
    for r in pq_rows:
        if r["status"] != "ok":
            continue
        for table in ["pairs", "objects", "matches", "tracks", "frames"]:
            csv = pd.read_csv(study / "csv" / r["output"] / f"{table}.csv")
            pq = pd.read_parquet(study / "pq" / r["output"] / f"{table}.parquet")
            assert list(pq.columns) == list(csv.columns), table
            pd.testing.assert_frame_equal(pq, csv, check_dtype=False, rtol=1e-12)
            for c in csv.columns:
                if csv[c].notna().all() and pd.api.types.is_numeric_dtype(csv[c]):
                    assert pq[c].dtype == csv[c].dtype, (table, c)
            compared += len(pq)
    assert compared > 1000
    with pytest.raises(pymodal.OptionError, match="tables"):
        pymodal.batch(study / "in", study / "never", tables="xlsx")
    assert not (study / "never").exists()


def test_rows_say_no_pairs_name_no_unwritten_folder_and_give_frames_read(study, tmp_path):
    # A one-frame recording: ok, with no pair to match, and a row that says so.
    blob = [[100.0 * 2.718281828 ** (-((r - 7.5) ** 2 + (c - 7.5) ** 2) / 12.0) for c in range(16)] for r in range(16)]
    one = tmp_path / "one-frame.csv"
    one.write_text("".join(",".join(f"{v:.1f}" for v in row) + "\n" for row in blob))
    out = tmp_path / "out"
    row = pymodal.batch_row(one, out=out, figures="none")
    assert (row["status"], row["frames"], row["pairs"]) == ("ok", 1, 0)
    assert "no pair of objects in consecutive frames to match" in row["message"]
    # Error rows: no folder named where none was written; the frames read are given.
    bad = pymodal.batch_row(study / "in" / "corrupt.asf", out=out, figures="none")
    assert bad["status"] == "error" and bad["output"] is None
    tekscan = study / "in" / "tekscan.csv"
    row = pymodal.batch_row(tekscan, out=out, figures="none", frames=(15, 30))
    assert row["status"] == "error" and row["output"] is None
    assert row["frames"] == pymodal.run(tekscan)["summary"]["recording"]["frames"]
    # iso_frame outside the frames run is an option error naming both.
    with pytest.raises(ValueError, match="iso_frame.*frames 2..5"):
        pymodal.run(tekscan, model="isocontour", frames=(2, 5), iso_frame=7)


def test_a_batch_on_part_of_a_study_keeps_the_other_rows(study):
    out = study / "out"
    first = pymodal.batch([study / "in"], out, figures="none")
    tekscan = [r for r in first if r["path"].endswith("tekscan.csv")]
    others = [r for r in first if not r["path"].endswith("tekscan.csv")]
    again = pymodal.batch(study / "in" / "tekscan.csv", out, figures="none", spacing=1.5)
    # The list returned is this call's; the study table keeps the others after it.
    assert [r["path"] for r in again] == [r["path"] for r in tekscan]
    table = json.loads((out / "study.json").read_text())
    # Kept as they were, their messages saying so.
    note = "kept from an earlier run (not among this run's inputs)"
    kept = [dict(r, message=note + (f"; {r['message']}" if r["message"] else "")) for r in others]
    assert table["rows"] == again + kept
    assert (table["recordings"], table["kept"], table["options"]["spacing"]) == (1, 3, 1.5)
    lines = (out / "study.csv").read_text().splitlines()
    assert len(lines) == 5 and lines[1].startswith(str(study / "in" / "tekscan.csv"))
    # batch_row finds its previous row whatever the spelling of its path (the wall time kept).
    row = pymodal.batch_row(os.path.relpath(study / "in" / "tekscan.csv"), out, figures="none", spacing=1.5)
    assert row["status"] == "skipped" and row["wall_time_s"] == again[0]["wall_time_s"]


def test_units_columns_are_null_when_unknown_and_typed_in_parquet(tmp_path):
    blob = [[100.0 * 2.718281828 ** (-((r - 7.5) ** 2 + (c - 7.5) ** 2) / 12.0) for c in range(16)] for r in range(16)]
    grid = tmp_path / "grid.csv"
    grid.write_text("".join(",".join(f"{v:.1f}" for v in row) + "\n" for row in blob))
    [row] = pymodal.batch(grid, tmp_path / "out", figures="none", tables="parquet")
    assert row["status"] == "ok"
    assert [row[c] for c in ["frame_rate_hz", "pitch_x_mm", "pitch_y_mm", "pressure_units"]] == [None] * 4
    [row] = pymodal.batch(grid, figures="none", pitch_mm=(2, 3), frame_rate=50, units="N/cm2")
    assert (row["frame_rate_hz"], row["pitch_x_mm"], row["pitch_y_mm"], row["pressure_units"]) == (50, 2, 3, "N/cm²")
    pq = pytest.importorskip("pyarrow.parquet")
    schema = pq.read_schema(tmp_path / "out" / "study.parquet")
    assert str(schema.field("pressure_units").type) == "string"
    assert str(schema.field("pitch_x_mm").type) == "double"


def test_a_pedar_study_records_its_layout_file_and_runs_again_with_another(tmp_path):
    asc = tmp_path / "insoles.asc"
    shutil.copy(DATA / "pedar-example-3.01-4.00.asc", asc)
    text = (DATA.parents[1] / "layouts" / "pedar-pressuRe.csv").read_text()
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    a.write_text(text)
    # The same insole with the places of sensors 1 and 2 swapped.
    b.write_text(text.replace("R,1,", "R,#,", 1).replace("R,2,", "R,1,", 1).replace("R,#,", "R,2,", 1))
    out = tmp_path / "study"
    [row] = pymodal.batch(asc, out, figures="none", layout=a)
    summary = json.loads((out / row["output"] / "summary.json").read_text())
    assert summary["input"]["layout"]["file"] == str(a)
    assert pymodal.batch(asc, out, figures="none", layout=a)[0]["status"] == "skipped"
    assert pymodal.batch_row(asc, out, figures="none", layout=b)["status"] == "ok"
    summary = json.loads((out / row["output"] / "summary.json").read_text())
    assert summary["input"]["layout"]["file"] == str(b)


def test_batch_over_a_folder_without_recordings_raises_and_writes_nothing(tmp_path):
    # As `pedomatch batch` exits 1: "no recordings found", and no empty study is written.
    inputs = tmp_path / "notes"
    inputs.mkdir()
    (inputs / "notes.txt").write_text("subject 3, left foot\n")
    out = tmp_path / "study"
    with pytest.raises(pymodal.InputError, match="no recordings found in"):
        pymodal.batch(inputs, out, figures="none")
    assert not out.exists()
    assert pymodal.find_recordings(inputs) == []
