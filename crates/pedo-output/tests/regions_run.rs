//! A run with a region rule writes `regions.json`, `regions.csv` and `regions.npy`, the same
//! whether the recording is held whole or streamed (the streamed run keeps its frames' loaded
//! sensels to measure the regions on), and its regions agree with `pedo_io::regions` on the
//! recording held whole.

use pedo_io::formats::{read_for_streaming, ReadOptions};
use pedo_io::regions::{recording_regions, RegionRule};
use pedo_io::{read_recording, FrameSource};
use pedo_output::{run_into_folder, InputInfo, RunOutputs, RunPlan};
use pedo_track::{FrameRange, RunParams};
use std::path::PathBuf;

#[path = "../../pedo-io/tests/common/files.rs"]
mod files;
use files::temp_dir;

fn walk() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../pedo-io/tests/data/FrasP01L.asf")
}

#[test]
fn a_run_s_regions_are_the_same_streamed_or_held_and_match_the_library() {
    let dir = temp_dir("regions-run");
    let params = RunParams {
        frames: Some(FrameRange {
            start: 0,
            end: Some(120),
        }),
        ..Default::default()
    };
    let outputs = RunOutputs {
        regions: Some(RegionRule::Fine),
        ..Default::default()
    };
    let input = InputInfo::of_path(&walk()).unwrap();
    let held = read_recording(walk()).unwrap();
    let (header, mut frames) = read_for_streaming(walk(), &ReadOptions::default()).unwrap();
    assert!(frames.is_some());
    let mut written = Vec::new();
    let outs = [dir.join("run-0"), dir.join("run-1")];
    for (k, (rec, source)) in [
        (&header, frames.as_mut().map(|f| f as &mut dyn FrameSource)),
        (&held, None),
    ]
    .into_iter()
    .enumerate()
    {
        let options = params.to_options(rec).unwrap();
        let out = &outs[k];
        let (summary, _) = run_into_folder(
            rec,
            &options,
            RunPlan {
                input: &input,
                params: &params,
                frames: source,
                folder: Some(out),
                outputs: &outputs,
                timings: &[],
                also: None,
            },
            &|_, _, _| {},
        )
        .unwrap();
        assert_eq!(summary["options"]["region_rule"], "fine");
        let read = |f: &str| std::fs::read(out.join(f)).unwrap();
        written.push((
            read("regions.csv"),
            read("regions.npy"),
            read("regions.json"),
        ));
    }
    assert!(written[0] == written[1], "streamed and held regions differ");

    // The library on the recording held whole, frames 0..120, threshold of the file.
    let threshold = held.noise_threshold.unwrap_or(0.0);
    let (masks, values) = recording_regions(&held, threshold, 0..120, RegionRule::Fine).unwrap();
    let csv = String::from_utf8(written[0].0.clone()).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("region,measure,value,unit"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 7 * values.len());
    for v in &values {
        let get = |m: &str| -> f64 {
            let row = rows.iter().find(|r| r[0] == v.name && r[1] == m).unwrap();
            row[2].parse().unwrap()
        };
        assert_eq!(get("fti"), v.fti);
        assert_eq!(get("impulse_share"), v.impulse_share);
        assert_eq!(get("contact_time"), v.contact_time);
        assert_eq!(get("max_contact_area"), v.max_contact_area);
    }
    let unit = |m: &str| rows.iter().find(|r| r[1] == m).unwrap()[3];
    assert_eq!(unit("fti"), "N·s");
    assert_eq!(unit("impulse_share"), "%");
    let json: serde_json::Value = serde_json::from_slice(&written[0].2).unwrap();
    assert_eq!(json["labels"]["1"], "heel_medial");
    assert_eq!(json["foot"]["heel_toe_cue"], "cop_path");
    // The label image: the masks, as float64 after the .npy header.
    let npy = &written[0].1;
    let body = &npy[npy.len() - 8 * masks.labels.len()..];
    for (i, &l) in masks.labels.iter().enumerate() {
        let v = f64::from_le_bytes(body[8 * i..8 * i + 8].try_into().unwrap());
        assert_eq!(v, f64::from(l));
    }
    let _ = std::fs::remove_dir_all(&dir);
}
