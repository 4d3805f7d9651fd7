//! A recording of both feet apart has each foot's regions carried through that foot's own
//! stances: one stance of the bundled walk placed twice side by side, as two insoles of one grid
//! (a gap of columns without sensors between them), gives on each foot the moving regions of
//! the same stance recorded alone at the same place of the grid, with the same masks.

use modal_core::PathOrRows;
use pedo_io::read_recording;
use pedo_io::recording::{FootColumns, Recording};
use pedo_io::regions::{recording_regions, RegionRule, Side};
use pedo_output::{run_into_folder, InputInfo, RunOutputs, RunPlan};
use pedo_track::RunParams;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

#[path = "../../pedo-io/tests/common/files.rs"]
mod files;
use files::temp_dir;

/// The walk's frames used: its second stance (frames 29..=50) and unloaded frames around it.
const FRAMES: std::ops::Range<usize> = 26..53;
/// Columns without sensors between the two insoles.
const GAP: usize = 3;

fn walk() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../pedo-io/tests/data/FrasP01L.asf")
}

/// The walk's frames `FRAMES` on a grid of `2C + GAP` columns: at columns `0..C` (`left`) and
/// `C + GAP..2C + GAP` (`right`) when asked, 0 elsewhere; with `feet`, the two as the insoles of
/// the left and the right foot, else one sensor.
fn placed(walk: &Recording, left: bool, right: bool, feet: bool) -> Recording {
    let (n, rows, cols) = (FRAMES.len(), walk.rows(), walk.cols());
    let wide = 2 * cols + GAP;
    let data = walk.data();
    let mut out = vec![0.0f32; n * rows * wide];
    let mut mask = vec![false; rows * wide];
    for r in 0..rows {
        for c in 0..cols {
            for (at, on) in [(c, left), (cols + GAP + c, right)] {
                mask[r * wide + at] = walk.sensor_mask()[r * cols + c];
                for (t, f) in FRAMES.enumerate() {
                    if on {
                        out[(t * rows + r) * wide + at] = data[(f * rows + r) * cols + c];
                    }
                }
            }
        }
    }
    let mut rec = Recording::new(n, rows, wide, out, mask)
        .unwrap()
        .with_pitch_mm(walk.pitch_mm.unwrap())
        .unwrap()
        .with_frame_rate(walk.frame_rate().unwrap())
        .unwrap()
        .with_units(walk.units.clone());
    rec.noise_threshold = walk.noise_threshold;
    if feet {
        rec.feet = vec![
            FootColumns {
                side: Side::Left,
                columns: 0..cols,
            },
            FootColumns {
                side: Side::Right,
                columns: cols + GAP..wide,
            },
        ];
    }
    rec
}

/// Runs `rec` (frames `0..FRAMES`) with the label image `labels` as the user's masks into
/// `out`; returns `regions.csv`'s moving rows as (foot, region, measure) → value and
/// `regions.json`.
fn run(
    rec: &Recording,
    labels: Vec<Vec<f64>>,
    out: &Path,
) -> (BTreeMap<(String, String, String), f64>, serde_json::Value) {
    let params = RunParams::default();
    let outputs = RunOutputs {
        masks: Some(Arc::new(PathOrRows::Rows(labels))),
        ..Default::default()
    };
    let options = params.to_options(rec).unwrap();
    let input = InputInfo::of_path(&walk()).unwrap();
    run_into_folder(
        rec,
        &options,
        RunPlan {
            input: &input,
            params: &params,
            frames: None,
            folder: Some(out),
            outputs: &outputs,
            timings: &[],
            also: None,
        },
        &|_, _, _| {},
    )
    .unwrap();
    let csv = std::fs::read_to_string(out.join("regions.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let feet = header[0] == "foot";
    let mut moving = BTreeMap::new();
    for l in lines.filter(|l| l.ends_with(",moving")) {
        let f: Vec<&str> = l.split(',').collect();
        let (foot, f) = if feet {
            (f[0].to_string(), &f[1..])
        } else {
            (String::new(), &f[..])
        };
        moving.insert(
            (foot, f[0].to_string(), f[1].to_string()),
            f[2].parse::<f64>().unwrap(),
        );
    }
    let json = std::fs::read(out.join("regions.json")).unwrap();
    (moving, serde_json::from_slice(&json).unwrap())
}

/// `regions.csv`'s moving rows as (region, measure) → value for `foot` ("" for one sensor).
fn of_foot(
    rows: &BTreeMap<(String, String, String), f64>,
    foot: &str,
) -> BTreeMap<(String, String), f64> {
    (rows.iter())
        .filter(|((f, _, _), _)| f == foot)
        .map(|((_, r, m), &v)| ((r.clone(), m.clone()), v))
        .collect()
}

/// `region_series.csv`'s rows of `foot` (all for one sensor) without the foot and the label
/// (a foot's labels follow the other's), each row as its cells.
fn series_of(dir: &Path, foot: Option<&str>) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(dir.join("region_series.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let skip = |name: &str| name == "foot" || name == "region";
    (lines.map(|l| l.split(',').collect::<Vec<_>>()))
        .filter(|r| foot.is_none_or(|f| r[0] == f))
        .map(|r| {
            (r.iter().zip(&header))
                .filter(|(_, h)| !skip(h))
                .map(|(c, _)| c.to_string())
                .collect()
        })
        .collect()
}

#[test]
fn each_foot_s_moving_regions_are_those_of_the_foot_recorded_alone() {
    let dir = temp_dir("feet-moving");
    let walk = read_recording(walk()).unwrap();
    let threshold = walk.noise_threshold.unwrap_or(0.0);
    let (masks, _) = recording_regions(&walk, threshold, FRAMES, RegionRule::Coarse).unwrap();
    let (rows, cols) = (walk.rows(), walk.cols());
    let label = |r: usize, c: usize| f64::from(masks.labels[r * cols + c]);
    // The walk's coarse masks over each insole (or over the one place of the walk alone).
    let labels = |left: bool, right: bool| -> Vec<Vec<f64>> {
        (0..rows)
            .map(|r| {
                let row = |on: bool| (0..cols).map(move |c| if on { label(r, c) } else { 0.0 });
                (row(left)
                    .chain(std::iter::repeat_n(0.0, GAP))
                    .chain(row(right)))
                .collect()
            })
            .collect()
    };
    let both = placed(&walk, true, true, true);
    let (feet, feet_json) = run(&both, labels(true, true), &dir.join("both"));
    assert!(feet_json["moving"]["error"].is_null(), "{feet_json}");
    let feet_stances = feet_json["moving"]["stances"].as_array().unwrap();
    let mut seen = 0;
    for (side, left) in [("left", true), ("right", false)] {
        let alone = placed(&walk, left, !left, false);
        let out = dir.join(side);
        let (moving, json) = run(&alone, labels(left, !left), &out);
        assert!(json["moving"]["error"].is_null(), "{json}");
        // Every moving value of the foot is the foot's alone (the same frames, objects and
        // correspondences on its insole), its impulse share of its own foot's impulse.
        let (own, alone) = (of_foot(&feet, side), of_foot(&moving, ""));
        assert!(!alone.is_empty());
        assert_eq!(
            own.keys().collect::<Vec<_>>(),
            alone.keys().collect::<Vec<_>>()
        );
        for (key, &v) in &alone {
            let w = own[key];
            assert!(
                (w - v).abs() <= 1e-9 * v.abs().max(1.0),
                "{side} {key:?}: {w} vs {v} alone"
            );
        }
        // The foot's stances, reference frames and followed parts are those of the foot alone.
        let stances = json["moving"]["stances"].as_array().unwrap();
        assert!(!stances.is_empty());
        let own: Vec<&serde_json::Value> = (feet_stances.iter())
            .filter(|s| s["foot"] == side)
            .collect();
        assert_eq!(own.len(), stances.len());
        for (s, a) in own.iter().zip(stances) {
            assert_eq!(s["reference_frame"], a["reference_frame"]);
            assert_eq!(s["frames"], a["frames"]);
            assert_eq!(s["regions"], a["regions"]);
        }
        seen += own.len();
        // region_series.csv: the foot's rows (moving and fixed) are those of the foot alone.
        let own = series_of(&dir.join("both"), Some(side));
        assert!(!own.is_empty());
        assert_eq!(own, series_of(&out, None), "{side}");
    }
    assert_eq!(seen, feet_stances.len());
    // Keyed per foot, as the fixed regions are.
    let keys = feet_json["moving"]["regions"].as_object().unwrap();
    assert!(!keys.is_empty());
    assert!(keys
        .keys()
        .all(|n| n.starts_with("left/") || n.starts_with("right/")));
    let header = std::fs::read_to_string(dir.join("both/region_series.csv")).unwrap();
    assert!(header.starts_with("foot,region,kind,frame,"));
    let _ = std::fs::remove_dir_all(&dir);
}
