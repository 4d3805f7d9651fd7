//! With drift correction, the matches of the reference pairs are written
//! (`reference_matches.csv`), so that every step of every track is a row of a table: a match of
//! `matches.csv` the track may follow (`trackable` 1), or a reference match a track took
//! (`tracked` 1) from an earlier step of the same track. Without drift correction no such file
//! is written; a study folder of a drift-corrected run is complete only with it.

#[path = "../../pedo-output/tests/common/parquet.rs"]
mod common;

use pedo_io::synthetic::SyntheticWalk;
use pedo_io::{read_recording, Recording};
use pedo_output::InputInfo;
use pedo_output::TableFormat;
use pedo_output::{run_into_folder, write_run_folder, RunOutputs, RunPlan, RunRecord};
use pedo_study::{run_study, RowStatus, StudyOptions};
use pedo_track::{run_sequence, FrameRange, ObjectModel, RunParams};
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

#[path = "../../pedo-io/tests/common/files.rs"]
mod files;
use files::{data, temp_dir};

/// A CSV table (no quoted fields: the tables read here hold numbers only) as rows of column →
/// integer; the non-integer columns are left out.
fn read_csv(path: &Path) -> Vec<HashMap<String, i64>> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    lines
        .map(|l| {
            header
                .iter()
                .zip(l.split(','))
                .filter_map(|(h, v)| Some((h.to_string(), v.parse().ok()?)))
                .collect()
        })
        .collect()
}

type Node = (i64, i64);

/// Checks the folder of a drift-corrected run: every step of `tracks.csv` is a trackable match
/// of `matches.csv` or a tracked reference match from an earlier step of its track, and every
/// tracked reference match is such a step. Returns the number of steps only a reference match
/// explains.
fn assert_every_step_is_traced(dir: &Path) -> usize {
    let node = |r: &HashMap<String, i64>, o: &str, n: &str| (r[o], r[n]);
    let trackable: HashSet<(Node, Node)> = read_csv(&dir.join("matches.csv"))
        .iter()
        .filter(|r| r["trackable"] == 1)
        .map(|r| (node(r, "id_a", "node_a"), node(r, "id_b", "node_b")))
        .collect();
    let mut tracked: HashMap<Node, Node> = HashMap::new();
    for r in read_csv(&dir.join("reference_matches.csv")) {
        assert!(matches!(r["tracked"], 0 | 1), "{r:?}");
        assert!(r["excess"] == 0 || r["tracked"] == 0, "{r:?}");
        if r["tracked"] == 1 {
            let into = node(&r, "id_b", "node_b");
            let from = node(&r, "id_a", "node_a");
            assert!(
                tracked.insert(into, from).is_none(),
                "two tracked into {into:?}"
            );
        }
    }
    let mut by_track: Vec<(i64, Node)> = read_csv(&dir.join("tracks.csv"))
        .iter()
        .map(|r| (r["track"], node(r, "object_id", "node")))
        .collect();
    by_track.sort_by_key(|&(t, _)| t);
    let (mut through_reference, mut reached) = (0, HashSet::new());
    for track in by_track.chunk_by(|x, y| x.0 == y.0) {
        let steps: Vec<Node> = track.iter().map(|s| s.1).collect();
        for k in 1..steps.len() {
            let (from, to) = (steps[k - 1], steps[k]);
            let anchored = tracked
                .get(&to)
                .is_some_and(|ancestor| steps[..k].contains(ancestor));
            assert!(
                trackable.contains(&(from, to)) || anchored,
                "step {from:?} → {to:?} of track {} is in no table",
                track[0].0
            );
            if anchored {
                reached.insert(to);
                through_reference += usize::from(!trackable.contains(&(from, to)));
            }
        }
    }
    // Every tracked reference match is a step of the track of its first node.
    let stray: Vec<&Node> = tracked.keys().filter(|n| !reached.contains(*n)).collect();
    assert!(stray.is_empty(), "tracked but no track step: {stray:?}");
    assert!(!tracked.is_empty(), "no tracked reference match");
    through_reference
}

/// The folder of a run held whole (`write_run_folder`, as a run with figures writes it) and
/// of the same run streamed (`run_into_folder` with tables only), which must be the same.
fn both_folders(
    dir: &Path,
    recording: &Recording,
    params: &RunParams,
    tables: TableFormat,
) -> (PathBuf, PathBuf) {
    let input = InputInfo {
        name: "walk".into(),
        ..InputInfo::default()
    };
    let mut options = params.to_options(recording).unwrap();
    options.keep_match_details = false;
    let outputs = RunOutputs {
        tables,
        ..Default::default()
    };
    let result = run_sequence(recording, &options, &|_, _, _| {}).unwrap();
    let run = RunRecord {
        input: &input,
        recording,
        params,
        options: &options,
        result: &result,
    };
    let (whole, streamed) = (dir.join("whole"), dir.join("streamed"));
    write_run_folder(&whole, &run, &outputs, &[]).unwrap();
    let plan = RunPlan {
        input: &input,
        params,
        frames: None,
        folder: Some(&streamed),
        outputs: &outputs,
        timings: &[],
        also: None,
    };
    run_into_folder(recording, &options, plan, &|_, _, _| {}).unwrap();
    (whole, streamed)
}

fn params(frames: (isize, isize), drift_reference: usize) -> RunParams {
    RunParams {
        frames: Some(FrameRange {
            start: frames.0,
            end: Some(frames.1),
        }),
        drift_reference,
        ..Default::default()
    }
}

#[test]
fn with_drift_correction_every_track_step_is_a_written_match() {
    let walk = SyntheticWalk::default().recording().unwrap();
    let real = read_recording(data("FrasP01L.asf")).unwrap();
    let cases = [
        ("walk", &walk, params((0, 31), 10), ObjectModel::Contour),
        ("real", &real, params((10, 60), 10), ObjectModel::Contour),
        ("surface", &real, params((20, 50), 8), ObjectModel::Surface),
    ];
    for (name, recording, mut params, model) in cases {
        params.model = model;
        let dir = temp_dir(name);
        let (whole, streamed) = both_folders(&dir, recording, &params, TableFormat::Csv);
        for file in ["reference_matches.csv", "tracks.csv", "matches.csv"] {
            let read = |d: &Path| std::fs::read(d.join(file)).unwrap();
            assert!(read(&whole) == read(&streamed), "{name}: {file} differs");
        }
        let through_reference = assert_every_step_is_traced(&whole);
        // The reference matches are needed: some steps are no trackable match of matches.csv.
        assert!(through_reference > 0, "{name}: no step through a reference");
        let _ = std::fs::remove_dir_all(&dir);
    }
}

#[test]
fn without_drift_correction_no_reference_matches_are_written() {
    let walk = SyntheticWalk::default().recording().unwrap();
    for tables in [TableFormat::Csv, TableFormat::Parquet] {
        let dir = temp_dir(&format!("off-{}", tables.file_name("x")));
        let (whole, streamed) = both_folders(&dir, &walk, &params((0, 12), 0), tables);
        for d in [&whole, &streamed] {
            assert!(d.join(tables.file_name("matches")).is_file());
            assert!(!d.join(tables.file_name("reference_matches")).exists());
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}

#[test]
fn a_drift_corrected_study_folder_without_its_reference_matches_runs_again() {
    let out = temp_dir("study");
    let paths = vec![data("tekscan-FrasP01L-11-20.csv")];
    for tables in [TableFormat::Csv, TableFormat::Parquet] {
        let options = StudyOptions {
            out: Some(out.clone()),
            jobs: 1,
            params: RunParams {
                drift_reference: 3,
                ..Default::default()
            },
            outputs: RunOutputs {
                tables,
                ..Default::default()
            },
            ..Default::default()
        };
        let status = || run_study(&paths, &options, &|_| {}).unwrap().rows[0].clone();
        let first = status();
        assert_eq!(first.status, RowStatus::Ok, "{first:?}");
        let file = out
            .join(first.output.as_ref().unwrap())
            .join(tables.file_name("reference_matches"));
        assert!(file.is_file());
        assert_eq!(status().status, RowStatus::Skipped);
        std::fs::remove_file(&file).unwrap();
        assert_eq!(status().status, RowStatus::Ok, "a folder without {file:?}");
        assert!(file.is_file());
        assert_eq!(status().status, RowStatus::Skipped);
    }
    let _ = std::fs::remove_dir_all(&out);
}

/// Each column's type in the Parquet file `path`, in order, as `name:TYPE`.
fn column_types(path: &Path) -> Vec<String> {
    use parquet::file::reader::{FileReader, SerializedFileReader};
    let reader = SerializedFileReader::new(std::fs::File::open(path).unwrap()).unwrap();
    let schema = reader.metadata().file_metadata().schema_descr_ptr();
    schema
        .columns()
        .iter()
        .map(|c| format!("{}:{:?}", c.name(), c.physical_type()))
        .collect()
}

/// As Parquet, `tracked` is an integer column like `trackable`, also in a table without rows
/// (a drift-corrected run too short to have a reference pair still writes the table).
#[test]
fn the_parquet_reference_matches_are_typed_as_the_matches_full_or_empty() {
    let walk = SyntheticWalk::default().recording().unwrap();
    let expected = [
        "id_a:INT64",
        "id_b:INT64",
        "node_a:INT64",
        "node_b:INT64",
        "cost:DOUBLE",
        "excess:INT64",
        "tracked:INT64",
        "distance:DOUBLE",
    ];
    for (frames, name) in [((0, 12), "full"), ((0, 2), "empty")] {
        let dir = temp_dir(&format!("types-{name}"));
        let (whole, _) = both_folders(&dir, &walk, &params(frames, 5), TableFormat::Parquet);
        let types = column_types(&whole.join("reference_matches.parquet"));
        assert_eq!(types[..8], expected, "{name}");
        let (_, rows, _) = common::read_back(
            std::fs::File::open(whole.join("reference_matches.parquet")).unwrap(),
        );
        assert_eq!(rows.is_empty(), name == "empty", "{} rows", rows.len());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
