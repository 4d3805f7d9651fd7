//! A run with a region rule writes `regions.json`, `regions.csv`, `regions.npy` and the moving
//! regions' rows of `region_series.csv`, the same whether the recording is held whole or
//! streamed (the streamed run keeps its frames to measure and carry the regions on) and whatever
//! the model (a surface or isocontour run carries them by the contour field), and its regions
//! agree with `pedo_io::regions` on the recording held whole.

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
    let mut movings = Vec::new();
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
        let mut json: serde_json::Value = serde_json::from_slice(&read("regions.json")).unwrap();
        // The fixed regions' rows and values apart from the moving ones.
        let moving = json.as_object_mut().unwrap().remove("moving").unwrap();
        let csv = String::from_utf8(read("regions.csv")).unwrap();
        let fixed: Vec<String> = csv
            .lines()
            .filter(|l| !l.ends_with(",moving"))
            .map(String::from)
            .collect();
        written.push((fixed.join("\n").into_bytes(), read("regions.npy"), json));
        movings.push((moving, csv, read("region_series.csv")));
    }
    assert!(written[0] == written[1], "streamed and held regions differ");
    // Streamed, the regions are carried as held: the same stances, values and rows.
    assert!(movings[0].0["error"].is_null(), "{}", movings[0].0);
    assert!(movings[0].1.contains(",moving"));
    assert!(
        movings[0] == movings[1],
        "streamed and held moving regions differ"
    );

    // The library on the recording held whole, frames 0..120, threshold of the file.
    let threshold = held.noise_threshold.unwrap_or(0.0);
    let (masks, values) = recording_regions(&held, threshold, 0..120, RegionRule::Fine).unwrap();
    let csv = String::from_utf8(written[0].0.clone()).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("region,measure,value,unit,kind"));
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
    let json = &written[0].2;
    assert_eq!(json["labels"]["1"], "heel_medial");
    assert_eq!(json["foot"]["heel_toe_cue"], "cop_path");
    // The label image: the masks, as float64 after the .npy header.
    let npy = &written[0].1;
    let body = &npy[npy.len() - 8 * masks.labels.len()..];
    for (i, &l) in masks.labels.iter().enumerate() {
        let v = f64::from_le_bytes(body[8 * i..8 * i + 8].try_into().unwrap());
        assert_eq!(v, f64::from(l));
    }

    // Held, the regions are also carried through the stance: each moving region's FTI in
    // regions.csv is the sum of its force over the frames of region_series.csv's moving rows,
    // and on the stance's reference frame the moving regions hold (almost) the frame's contact.
    let held_out = &outs[1];
    let (moving, csv, _) = &movings[1];
    let series = std::fs::read_to_string(held_out.join("region_series.csv")).unwrap();
    let mut lines = series.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let dt = held.dt_s.unwrap();
    let stances = moving["stances"].as_array().unwrap();
    assert!(!stances.is_empty());
    for v in &values {
        let sum: f64 = (rows.iter())
            .filter(|r| r[col("name")] == v.name && r[col("kind")] == "moving")
            .filter_map(|r| r[col("total_force_n")].parse::<f64>().ok())
            .sum();
        let line = (csv.lines())
            .find(|l| l.starts_with(&format!("{},fti,", v.name)) && l.ends_with(",moving"))
            .unwrap();
        let fti: f64 = line.split(',').nth(2).unwrap().parse().unwrap();
        assert!(
            (sum * dt - fti).abs() <= 1e-3 * fti.max(1e-9),
            "{}: {sum} vs {fti}",
            v.name
        );
    }
    let frames = std::fs::read_to_string(held_out.join("frames.csv")).unwrap();
    let mut fl = frames.lines();
    let fh: Vec<&str> = fl.next().unwrap().split(',').collect();
    let fcol = |name: &str| fh.iter().position(|h| *h == name).unwrap();
    for s in stances {
        let reference = s["reference_frame"].as_u64().unwrap().to_string();
        let contact: f64 = (frames.lines().skip(1))
            .map(|l| l.split(',').collect::<Vec<_>>())
            .find(|r| r[fcol("frame")] == reference)
            .map(|r| r[fcol("contact_sensors")].parse().unwrap())
            .unwrap();
        let held: f64 = (rows.iter())
            .filter(|r| r[col("kind")] == "moving" && r[col("frame")] == reference)
            .map(|r| r[col("contact_sensors")].parse::<f64>().unwrap())
            .sum();
        assert!(
            held <= contact && held >= 0.95 * contact,
            "{held} of {contact}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A run asked for regions streams its file where its model does (contour or surface): it keeps
/// the frames and carries the regions once the run is done.
#[test]
fn a_run_with_regions_streams_where_its_model_does() {
    let read = ReadOptions::default();
    let regions = RunOutputs {
        regions: Some(RegionRule::Coarse),
        ..Default::default()
    };
    let contour = RunParams::default();
    let surface = RunParams {
        model: pedo_track::ObjectModel::Surface,
        ..Default::default()
    };
    let streams = |params: &RunParams, outputs: &RunOutputs| {
        let input = pedo_output::read_for_run(&walk(), &read, params, outputs).unwrap();
        input.frames.is_some()
    };
    assert!(streams(&contour, &regions));
    assert!(streams(&contour, &RunOutputs::default()));
    assert!(streams(&surface, &regions));
}

/// The moving regions of a surface run (held and streamed) and of an isocontour run are those
/// of the contour run of the same frames: `regions.csv`'s moving rows, `regions.json`'s
/// `moving` and the moving regions' rows of `region_series.csv`, byte for byte.
#[test]
fn surface_and_isocontour_runs_carry_the_regions_as_the_contour_run() {
    let dir = temp_dir("regions-models");
    let outputs = RunOutputs {
        regions: Some(RegionRule::Coarse),
        ..Default::default()
    };
    let input = InputInfo::of_path(&walk()).unwrap();
    let held = read_recording(walk()).unwrap();
    // One whole stance of the walk (frames 29–50).
    let frames = Some(FrameRange {
        start: 25,
        end: Some(55),
    });
    let run = |name: &str, model, streamed: bool| {
        let params = RunParams {
            frames,
            model,
            ..Default::default()
        };
        let out = dir.join(name);
        let (header, mut source) = read_for_streaming(walk(), &ReadOptions::default()).unwrap();
        let rec = if streamed { &header } else { &held };
        let options = params.to_options(rec).unwrap();
        let source = (source.as_mut())
            .filter(|_| streamed)
            .map(|f| f as &mut dyn FrameSource);
        let (summary, _) = run_into_folder(
            rec,
            &options,
            RunPlan {
                input: &input,
                params: &params,
                frames: source,
                folder: Some(&out),
                outputs: &outputs,
                timings: &[],
                also: None,
            },
            &|_, _, _| {},
        )
        .unwrap();
        assert_eq!(summary["input"]["streamed"], streamed, "{name}");
        let read = |f: &str| std::fs::read_to_string(out.join(f)).unwrap();
        let json: serde_json::Value = serde_json::from_str(&read("regions.json")).unwrap();
        let csv = read("regions.csv");
        let moving_rows: Vec<String> = (csv.lines())
            .filter(|l| l.ends_with(",moving"))
            .map(String::from)
            .collect();
        // region_series.csv: the anatomical regions' rows (every row, with no user region).
        (
            json["moving"].clone(),
            moving_rows,
            read("region_series.csv"),
        )
    };
    use pedo_track::ObjectModel::{Contour, Isocontour, Surface};
    let contour = run("contour", Contour, false);
    assert!(contour.0["error"].is_null(), "{}", contour.0);
    assert!(!contour.1.is_empty());
    for (name, model, streamed) in [
        ("surface", Surface, false),
        ("surface-streamed", Surface, true),
        ("isocontour", Isocontour, false),
    ] {
        let other = run(name, model, streamed);
        assert!(
            other == contour,
            "{name}: moving regions differ from the contour run's"
        );
    }
    // Independently, on the streamed surface run's files: each moving FTI is the sum of its
    // rows' force times dt, and on its stance's reference frame each moving region holds the
    // force of its mask's sensels (all of it but a part no contour object holds).
    let out = dir.join("surface-streamed");
    let csv = std::fs::read_to_string(out.join("regions.csv")).unwrap();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("regions.json")).unwrap()).unwrap();
    let series = std::fs::read_to_string(out.join("region_series.csv")).unwrap();
    let mut lines = series.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let force = |r: &Vec<&str>| r[col("total_force_n")].parse::<f64>().unwrap_or(0.0);
    let dt = held.dt_s.unwrap();
    let reference = json["moving"]["stances"][0]["reference_frame"]
        .as_u64()
        .unwrap();
    let (mut moving_total, mut fixed_total) = (0.0, 0.0);
    for name in ["hindfoot", "midfoot", "forefoot", "toes"] {
        let of = |kind: &str| -> Vec<&Vec<&str>> {
            (rows.iter())
                .filter(|r| r[col("name")] == name && r[col("kind")] == kind)
                .collect()
        };
        let sum: f64 = of("moving").into_iter().map(force).sum();
        let line = (csv.lines())
            .find(|l| l.starts_with(&format!("{name},fti,")) && l.ends_with(",moving"))
            .unwrap();
        let fti: f64 = line.split(',').nth(2).unwrap().parse().unwrap();
        assert!(
            (sum * dt - fti).abs() <= 1e-3 * fti.max(1e-9),
            "{name}: {sum} vs {fti}"
        );
        let at = |kind: &str| -> f64 {
            (of(kind).into_iter())
                .filter(|r| r[col("frame")] == reference.to_string())
                .map(force)
                .sum()
        };
        let (m, f) = (at("moving"), at("fixed"));
        assert!(m <= f + 1e-3, "{name}: moving {m} above fixed {f}");
        moving_total += m;
        fixed_total += f;
    }
    assert!(
        moving_total >= 0.95 * fixed_total,
        "{moving_total} of {fixed_total}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
