//! A run with tables only streams (`stream_run_folder`: frames read, matched, chained and
//! written window by window) and writes, file for file and byte for byte, the folder of the same
//! run held whole (`run_sequence` + `write_run_folder`); only the timings of `summary.json`
//! differ. A folder with tables only holds no material points (`points`), whole or streamed.
//! A run that fails half-way leaves no folder.

use pedo_io::formats::{read_for_streaming, ReadOptions};
use pedo_io::{read_recording, FrameSource, Recording, FRAME_WINDOW};
use pedo_output::InputInfo;
use pedo_output::TableFormat;
use pedo_output::{stream_run_folder, write_run_folder, RunOutputs, RunRecord};
use pedo_track::{run_sequence, FrameRange, ObjectModel, RunParams};
use std::path::{Path, PathBuf};

#[path = "../../pedo-io/tests/common/files.rs"]
mod files;
use files::temp_dir;

fn walk() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../pedo-io/tests/data/FrasP01L.asf")
}

/// The folder of the run held whole, as `pedomatch run` with figures writes its tables.
fn whole_folder(out: &Path, params: &RunParams, tables: TableFormat) -> serde_json::Value {
    let recording = read_recording(walk()).unwrap();
    let input = InputInfo::of_path(&walk()).unwrap();
    let mut options = params.to_options(&recording).unwrap();
    options.keep_match_details = false;
    let result = run_sequence(&recording, &options, &|_, _, _| {}).unwrap();
    let run = RunRecord {
        input: &input,
        recording: &recording,
        params,
        options: &options,
        result: &result,
    };
    let outputs = RunOutputs {
        tables,
        ..Default::default()
    };
    write_run_folder(out, &run, &outputs, &[("read", 0.0)]).unwrap()
}

/// Every file under `dir`, by path relative to it.
fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out: Vec<(String, Vec<u8>)> = walkdir(dir)
        .into_iter()
        .map(|p| {
            let rel = p.strip_prefix(dir).unwrap().display().to_string();
            (rel, std::fs::read(&p).unwrap())
        })
        .collect();
    out.sort();
    out
}

fn walkdir(dir: &Path) -> Vec<PathBuf> {
    let mut found = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            found.extend(walkdir(&p));
        } else {
            found.push(p);
        }
    }
    found
}

/// `summary.json` without its timings and without how the run read its frames (`streamed`,
/// `read_whole`).
fn without_timings(bytes: &[u8]) -> serde_json::Value {
    let mut v: serde_json::Value = serde_json::from_slice(bytes).unwrap();
    v.as_object_mut().unwrap().remove("timings_s");
    let input = v["input"].as_object_mut().unwrap();
    input.remove("streamed");
    input.remove("read_whole");
    v
}

/// Whether the run of this `summary.json` read its frames as it went, and why not.
fn how_read(dir: &Path) -> (bool, Option<String>) {
    let v: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("summary.json")).unwrap()).unwrap();
    let why = v["input"]["read_whole"].as_str().map(str::to_string);
    (v["input"]["streamed"].as_bool().unwrap(), why)
}

/// The same files, byte for byte (`summary.json` but for its timings and how the run read its
/// frames).
fn assert_same_folders(whole: &Path, streamed: &Path) {
    let a = files(whole);
    let b = files(streamed);
    let names = |f: &[(String, Vec<u8>)]| f.iter().map(|x| x.0.clone()).collect::<Vec<_>>();
    assert_eq!(names(&a), names(&b));
    for ((name, x), (_, y)) in a.iter().zip(&b) {
        if name == "summary.json" {
            assert_eq!(without_timings(x), without_timings(y));
        } else {
            assert!(
                x == y,
                "{name} differs between the whole and the streamed run"
            );
        }
    }
}

#[test]
fn a_streamed_run_writes_the_folder_of_the_whole_run() {
    // Frames 10..150: windows of FRAME_WINDOW frames, tracks and pairs across their edges.
    const { assert!(140 > 2 * FRAME_WINDOW) };
    // The drift case reads the frames as it goes with drift correction, whose reference pairs
    // reach back across windows (its objects are held to the end). The strided cases keep every
    // 3rd (2nd) frame: a stride that does not divide the window, so the kept frames fall at other
    // places of each window and pairs join kept frames across window edges.
    let cases = [
        (
            ObjectModel::Contour,
            (10, 150),
            TableFormat::Csv,
            0,
            "contour-csv",
        ),
        (
            ObjectModel::Contour,
            (10, 150),
            TableFormat::Parquet,
            0,
            "contour-parquet",
        ),
        (
            ObjectModel::Surface,
            (20, 100),
            TableFormat::Csv,
            0,
            "surface-csv",
        ),
        (
            ObjectModel::Contour,
            (10, 150),
            TableFormat::Csv,
            25,
            "contour-drift",
        ),
        (
            ObjectModel::Contour,
            (10, 150),
            TableFormat::Csv,
            0,
            "contour-every-3",
        ),
        (
            ObjectModel::Surface,
            (20, 100),
            TableFormat::Csv,
            0,
            "surface-every-2",
        ),
        (
            ObjectModel::Contour,
            (10, 150),
            TableFormat::Csv,
            30,
            "contour-drift-every-3",
        ),
    ];
    for (model, (start, end), tables, drift_reference, name) in cases {
        let every = match name {
            n if n.ends_with("every-3") => 3,
            n if n.ends_with("every-2") => 2,
            _ => 1,
        };
        let dir = temp_dir(name);
        let params = RunParams {
            model,
            frames: Some(FrameRange {
                start,
                end: Some(end),
            }),
            drift_reference,
            every: pedo_track::FrameStride::Every(every),
            ..Default::default()
        };
        let whole = dir.join("whole");
        let summary = whole_folder(&whole, &params, tables);
        let pairs = summary["pairs"].as_u64().unwrap();
        assert!(pairs > 20, "{name}: {pairs} pairs");
        assert!(summary["tracks_3_or_more"].as_u64().unwrap() > 10, "{name}");
        // Tables only: no material points, though the run is at hand (as a streamed run's).
        let has_points = files(&whole).iter().any(|f| f.0.starts_with("points."));
        assert!(!has_points, "{name}");
        if every > 1 {
            // Pairs join kept frames `every` apart, in the recording's own frame numbers.
            let pairs_csv = std::fs::read_to_string(whole.join("pairs.csv")).unwrap();
            let mut rows = pairs_csv.lines().skip(1);
            let row: Vec<&str> = rows.next().unwrap().split(',').collect();
            let (a, b): (usize, usize) = (row[2].parse().unwrap(), row[3].parse().unwrap());
            assert_eq!((a - start as usize) % every, 0, "{name}: frame_a {a}");
            assert_eq!(b - a, every, "{name}: {a} -> {b}");
            // A strided run streams unless drift correction holds it.
            assert_eq!(params.streams(), drift_reference < 2, "{name}");
        }

        // Read from the file frame by frame, and held whole.
        let (recording, mut frames) = read_for_streaming(walk(), &ReadOptions::default()).unwrap();
        assert!(frames.is_some(), "a .asf file is read as the run goes");
        let held = read_recording(walk()).unwrap();
        let input = InputInfo::of_path(&walk()).unwrap();
        let sources: [(&Recording, Option<&mut dyn FrameSource>); 2] = [
            (
                &recording,
                frames.as_mut().map(|f| f as &mut dyn FrameSource),
            ),
            (&held, None),
        ];
        for (k, (rec, source)) in sources.into_iter().enumerate() {
            let mut options = params.to_options(rec).unwrap();
            options.keep_match_details = false;
            let out = dir.join(format!("streamed-{k}"));
            let (streamed, counts) = stream_run_folder(
                &out,
                &input,
                rec,
                source,
                &params,
                &options,
                tables,
                &[("read", 0.0)],
                &|_, _, _| {},
            )
            .unwrap();
            assert_eq!(streamed["tracks"], summary["tracks"]);
            assert_eq!(counts.pairs as u64, summary["pairs"].as_u64().unwrap());
            assert_same_folders(&whole, &out);
            let (read_as_it_went, why) = how_read(&out);
            assert_eq!(read_as_it_went, k == 0, "{name}: {why:?}");
            assert_eq!(why.is_none(), k == 0, "{name}: {why:?}");
        }
        let (_, why) = how_read(&whole);
        assert_eq!(why.as_deref(), Some("the run was made whole first"));
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// Frames of a held recording, failing from the second window on.
struct FailingSource(Recording);

impl FrameSource for FailingSource {
    fn window(
        &mut self,
        recording: &Recording,
        w0: usize,
        w1: usize,
    ) -> pedo_io::Result<Recording> {
        if w0 >= FRAME_WINDOW {
            return Err(pedo_io::IoError::InvalidInput("the disk went away".into()));
        }
        let data: Vec<f32> = (w0..w1)
            .flat_map(|t| self.0.frame_slice(t).unwrap().into_owned())
            .collect();
        let mut r = Recording::new(
            w1 - w0,
            recording.rows(),
            recording.cols(),
            data,
            recording.sensor_mask().to_vec(),
        )?;
        r.pitch_mm = recording.pitch_mm;
        r.dt_s = recording.dt_s;
        r.units = recording.units.clone();
        Ok(r)
    }
}

#[test]
fn a_streamed_run_that_fails_half_way_leaves_no_folder() {
    let dir = temp_dir("fails");
    let (recording, _) = read_for_streaming(walk(), &ReadOptions::default()).unwrap();
    let mut source = FailingSource(read_recording(walk()).unwrap());
    let params = RunParams {
        frames: Some(FrameRange::new(0, FRAME_WINDOW + 10)),
        ..Default::default()
    };
    let options = params.to_options(&recording).unwrap();
    let out = dir.join("out");
    let err = stream_run_folder(
        &out,
        &InputInfo::default(),
        &recording,
        Some(&mut source),
        &params,
        &options,
        TableFormat::Csv,
        &[],
        &|_, _, _| {},
    )
    .unwrap_err();
    assert!(err.to_string().contains("disk went away"), "{err}");
    assert!(!out.exists());
    let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
    assert!(left.is_empty(), "no staging folder left: {left:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_recording_read_for_streaming_holds_no_values_but_its_shape() {
    let (shape, frames) = read_for_streaming(walk(), &ReadOptions::default()).unwrap();
    let held = read_recording(walk()).unwrap();
    assert!(frames.is_some());
    assert_eq!(shape.n_frames(), held.n_frames());
    assert_eq!(
        (shape.rows(), shape.cols(), shape.sensor_mask()),
        (held.rows(), held.cols(), held.sensor_mask())
    );
    assert_eq!((shape.pitch_mm, shape.dt_s), (held.pitch_mm, held.dt_s));
    assert_eq!(shape.units, held.units);
    assert!(shape.frames_bytes() * 20 < held.frames_bytes());
    // A .npy array, an emed .lst and a pedar export are read as the run goes too; a Zebris XML
    // export is read whole.
    let dir = temp_dir("npy");
    let npy = dir.join("walk.npy");
    pedo_io::formats::npy::write_npy(&held, &npy).unwrap();
    let (shape, frames) = read_for_streaming(&npy, &ReadOptions::default()).unwrap();
    assert!(frames.is_some());
    assert_eq!(shape.sensor_mask(), held.sensor_mask());
    let lst = files::data("emed-test-1-10.lst");
    let (shape, frames) = read_for_streaming(&lst, &ReadOptions::default()).unwrap();
    assert!(frames.is_some());
    assert_eq!(shape.n_frames(), read_recording(&lst).unwrap().n_frames());
    let pedar = files::data("pedar-example-3.01-4.00.asc");
    let (shape, frames) = read_for_streaming(&pedar, &ReadOptions::default()).unwrap();
    assert!(frames.is_some());
    assert_eq!(shape.feet, read_recording(&pedar).unwrap().feet);
    let xml = files::data("zebris-FrasP01L-26-55.xml");
    let (whole, none) = read_for_streaming(&xml, &ReadOptions::default()).unwrap();
    assert!(none.is_none());
    assert_eq!(whole.data(), read_recording(&xml).unwrap().data());
    let _ = std::fs::remove_dir_all(&dir);
}
