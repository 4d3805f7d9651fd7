//! Every table a run writes is recognised by reading as pedomatch's own, by its file name
//! (`pedo_io::formats::own_tables`, the list reading sees: this crate comes after `pedo-io`, so
//! the list lives there and is checked here), and refused as a recording naming it.

use pedo_io::formats::own_tables::own_table;
use pedo_io::{read_recording, IoError};
use pedo_output::{write_run_folder, InputInfo, RunOutputs, RunRecord};
use pedo_track::{run_sequence, FrameRange, RunParams};
use std::path::PathBuf;

#[path = "../../pedo-io/tests/common/files.rs"]
mod files;
use files::temp_dir;

fn walk() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../pedo-io/tests/data/FrasP01L.asf")
}

#[test]
fn every_table_a_run_writes_is_recognised_as_its_own_and_refused_as_a_recording() {
    let recording = read_recording(walk()).unwrap();
    let input = InputInfo::of_path(&walk()).unwrap();
    // Drift correction, so that the reference matches are written too.
    let params = RunParams {
        frames: Some(FrameRange::new(30, 70)),
        drift_reference: 10,
        ..Default::default()
    };
    let options = params.to_options(&recording).unwrap();
    let result = run_sequence(&recording, &options, &|_, _, _| {}).unwrap();
    let run = RunRecord {
        input: &input,
        recording: &recording,
        params: &params,
        options: &options,
        result: &result,
    };
    let out = temp_dir("own-tables").join("run");
    write_run_folder(&out, &run, &RunOutputs::default(), &[("read", 0.0)]).unwrap();
    let mut seen = Vec::new();
    for entry in std::fs::read_dir(&out).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_str().unwrap().to_string();
        if !name.ends_with(".csv") {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        let table = own_table(&text).unwrap_or_else(|| panic!("{name} is not recognised"));
        assert_eq!(table.file, name, "{}", text.lines().next().unwrap());
        match read_recording(&path) {
            Err(IoError::Format { msg, .. }) => {
                assert!(msg.contains(&format!("pedomatch's own {name}")), "{msg}")
            }
            other => panic!("{name} read as {other:?}"),
        }
        seen.push(name);
    }
    seen.sort();
    for table in [
        "curves.csv",
        "frames.csv",
        "matches.csv",
        "objects.csv",
        "pairs.csv",
        "reference_matches.csv",
        "tracks.csv",
    ] {
        assert!(
            seen.iter().any(|s| s == table),
            "{table} not written: {seen:?}"
        );
    }
}
