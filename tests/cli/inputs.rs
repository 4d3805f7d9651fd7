//! Inputs that cannot mislead, and one pair one answer: an array stored time-last, pedomatch's
//! own tables given as recordings, negative values, unknown units, and `match` on two frames of
//! one recording against the run's pair.

use crate::common::{pedomatch, pedomatch_ok, read_json, stdout_json, temp_dir};
use std::path::{Path, PathBuf};

/// The bundled walk (Tekscan F-Scan, 205 frames of 60 × 21, kPa, 5.08 mm, 31.25 Hz).
fn walk() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/data/FrasP01L.asf")
}

/// A little-endian float32 `.npy` of `shape` (C order) holding `values`.
fn npy(shape: &[usize], values: &[f32]) -> Vec<u8> {
    let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
    let dict = format!(
        "{{'descr': '<f4', 'fortran_order': False, 'shape': ({},), }}",
        dims.join(", ")
    );
    let total = (10 + dict.len() + 1).div_ceil(64) * 64;
    let mut header = dict.into_bytes();
    header.resize(total - 11, b' ');
    header.push(b'\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(&header);
    for v in values {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out
}

/// The value at `[i, j, k]` of the test arrays: a blob that moves with `k` (time) over an
/// `i × j` grid, so that each axis reads differently.
fn blob(i: usize, j: usize, k: usize) -> f32 {
    let (ci, cj) = (20.0 + 10.0 * (k as f32 / 50.0).sin(), 15.0 + (k % 7) as f32);
    let d2 = (i as f32 - ci).powi(2) + (j as f32 - cj).powi(2);
    (200.0 * (-d2 / 40.0).exp()).max(0.0)
}

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn an_array_stored_time_last_is_refused_naming_both_shapes_and_read_on_request() {
    let dir = temp_dir("time-last");
    // (rows, cols, frames) = (63, 33, 500), as the SpeedPP2DS files store a recording.
    let (r, c, t) = (63, 33, 500);
    let mut values = Vec::with_capacity(r * c * t);
    for i in 0..r {
        for j in 0..c {
            for k in 0..t {
                values.push(blob(i, j, k));
            }
        }
    }
    let file = dir.join("speed.npy");
    std::fs::write(&file, npy(&[r, c, t], &values)).unwrap();
    let f = file.to_str().unwrap();
    for args in [
        &["inspect", f][..],
        &["run", f, "--out", dir.join("out").to_str().unwrap()][..],
    ] {
        let o = pedomatch(args);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {}", stderr(&o));
        let e = stderr(&o);
        for says in [
            "speed.npy",
            "(63, 33, 500)",
            "63 frames of 33 x 500",
            "500 frames of 63 x 33",
            "--time-axis last",
            "--time-axis first",
        ] {
            assert!(e.contains(says), "{args:?} should say {says:?}: {e}");
        }
        assert_eq!(e.lines().count(), 1, "{e}");
    }
    assert!(!dir.join("out").exists(), "nothing written");
    // Transposed on request: 500 frames of 63 × 33, frame k holding [.., .., k].
    let o = pedomatch(&["inspect", f, "--time-axis", "last", "--json"]);
    let d = stdout_json(&o);
    assert_eq!(
        (d["frames"].as_u64(), d["rows"].as_u64(), d["cols"].as_u64()),
        (Some(500), Some(63), Some(33))
    );
    // The peak of frame k's pressures, from the formula: an independent oracle of the order.
    let peak_max = (0..t)
        .map(|k| {
            (0..r)
                .flat_map(|i| (0..c).map(move |j| blob(i, j, k)))
                .fold(0.0f32, f32::max)
        })
        .fold(0.0f32, f32::max);
    let got = d["measures"]["peak_pressure"]["max"].as_f64().unwrap();
    assert!(
        (got - f64::from(peak_max)).abs() < 1e-3,
        "{got} vs {peak_max}"
    );
    // Kept as stored when asked.
    let o = pedomatch(&["inspect", f, "--time-axis", "first", "--json"]);
    let d = stdout_json(&o);
    assert_eq!(d["frames"].as_u64(), Some(63));
    // A time-first array of the same data passes without the option.
    let mut first = Vec::with_capacity(values.len());
    for k in 0..t {
        for i in 0..r {
            for j in 0..c {
                first.push(blob(i, j, k));
            }
        }
    }
    let ok = dir.join("first.npy");
    std::fs::write(&ok, npy(&[t, r, c], &first)).unwrap();
    let d = stdout_json(&pedomatch(&["inspect", ok.to_str().unwrap(), "--json"]));
    assert_eq!(d["frames"].as_u64(), Some(500));
    // A vendor file is no array: `last` is refused for it.
    let o = pedomatch(&["inspect", walk().to_str().unwrap(), "--time-axis", "last"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("arrays"), "{}", stderr(&o));
}

#[test]
fn pedomatchs_own_tables_are_refused_as_recordings_naming_them() {
    let dir = temp_dir("own-tables");
    let out = dir.join("walk");
    pedomatch_ok(&[
        "run",
        walk().to_str().unwrap(),
        "--frames",
        "30..45",
        "--figures",
        "none",
        "--report",
        "none",
        "--out",
        out.to_str().unwrap(),
    ]);
    let mut seen = 0;
    for entry in std::fs::read_dir(&out).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_str().unwrap().to_string();
        if !(name.ends_with(".csv") || name.ends_with(".json")) {
            continue;
        }
        seen += 1;
        let o = pedomatch(&["inspect", path.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(1), "{name}: {}", stderr(&o));
        let e = stderr(&o);
        // Every table and the run's record are named as pedomatch's own; the other JSON files
        // are refused as JSON.
        if name.ends_with(".csv") || name == "summary.json" {
            assert!(e.contains("pedomatch's own"), "{name}: {e}");
            assert!(e.contains("not a recording"), "{name}: {e}");
        }
        if name.ends_with(".csv") {
            assert!(e.contains(&format!("own {name} (a results table")), "{e}");
        }
        // `run` refuses it alike, writing nothing.
        let target = dir.join(format!("of-{name}"));
        let o = pedomatch(&[
            "run",
            path.to_str().unwrap(),
            "--out",
            target.to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(1), "{name}: {}", stderr(&o));
        assert!(!target.exists());
    }
    assert!(seen >= 6, "{seen} tables");
    // The matches of `pedomatch match` too.
    let m = dir.join("pair");
    let w = walk();
    let w = w.to_str().unwrap();
    pedomatch_ok(&[
        "match",
        w,
        w,
        "--frame",
        "40",
        "--frame-b",
        "41",
        "--out",
        m.to_str().unwrap(),
        "--figures",
        "none",
    ]);
    let o = pedomatch(&["inspect", m.join("matches.csv").to_str().unwrap()]);
    assert!(stderr(&o).contains("own matches.csv"), "{}", stderr(&o));
}

/// A Tekscan `.asf` of frames of 10 × 8 values (row-major).
fn asf(frames: &[Vec<f32>]) -> String {
    let mut s = String::from(
        "DATA_TYPE MOVIE\nROWS 10\nCOLS 8\nROW_SPACING 5 mm\nCOL_SPACING 5 mm\nSECONDS_PER_FRAME 0.01\nUNITS KPa\n",
    );
    s.push_str(&format!(
        "START_FRAME 1\nEND_FRAME {}\nASCII_DATA @@\n",
        frames.len()
    ));
    for (t, f) in frames.iter().enumerate() {
        s.push_str(&format!("Frame {}\n", t + 1));
        for row in f.chunks(8) {
            let cells: Vec<String> = row.iter().map(|v| v.to_string()).collect();
            s.push_str(&cells.join(","));
            s.push('\n');
        }
    }
    s.push_str("@@\n");
    s
}

#[test]
fn negative_values_are_counted_by_inspect_and_summary_and_clipped_on_request() {
    let dir = temp_dir("negatives");
    // An offset of -3 kPa around a loaded 5 x 4 patch, in 6 frames, and a dip at (0, 0).
    let mut frames = Vec::new();
    for t in 0..6 {
        let mut f = vec![-3.0f32; 80];
        for r in 3..8 {
            for c in 2..6 {
                f[r * 8 + c] = 40.0 + (r * c) as f32 + t as f32;
            }
        }
        f[0] = -7.5 + t as f32 * 0.5;
        frames.push(f);
    }
    let expected_count = frames.iter().flatten().filter(|v| **v < 0.0).count();
    let expected_min = frames
        .iter()
        .flatten()
        .copied()
        .fold(f32::INFINITY, f32::min);
    let file = dir.join("offset.asf");
    std::fs::write(&file, asf(&frames)).unwrap();
    let f = file.to_str().unwrap();
    let d = stdout_json(&pedomatch(&["inspect", f, "--json"]));
    assert_eq!(
        d["negative_values"]["count"].as_u64(),
        Some(expected_count as u64)
    );
    assert_eq!(
        d["negative_values"]["min"].as_f64(),
        Some(f64::from(expected_min))
    );
    assert_eq!(d["negative_values"]["clipped"].as_bool(), Some(false));
    let text = String::from_utf8_lossy(&pedomatch(&["inspect", f]).stdout).into_owned();
    assert!(
        text.contains(&format!("negative values {expected_count} (min -7.5)")),
        "{text}"
    );
    // A run (a Tekscan file streams: its values are counted as they are first read).
    for (clip, count) in [(false, expected_count), (true, expected_count)] {
        let out = dir.join(format!("run-{clip}"));
        let mut args = vec![
            "run",
            f,
            "--out",
            out.to_str().unwrap(),
            "--figures",
            "none",
            "--report",
            "none",
        ];
        if clip {
            args.push("--clip-negative");
        }
        pedomatch_ok(&args);
        let s = read_json(&out.join("summary.json"));
        let n = &s["recording"]["negative_values"];
        assert_eq!(n["count"].as_u64(), Some(count as u64), "{s}");
        assert_eq!(n["min"].as_f64(), Some(f64::from(expected_min)));
        assert_eq!(n["clipped"].as_bool(), Some(clip));
        assert_eq!(s["options"]["clip_negative"].as_bool(), Some(clip));
    }
    let d = stdout_json(&pedomatch(&["inspect", f, "--clip-negative", "--json"]));
    assert_eq!(d["negative_values"]["clipped"].as_bool(), Some(true));
    assert_eq!(
        d["negative_values"]["count"].as_u64(),
        Some(expected_count as u64)
    );
}

#[test]
fn measures_of_a_recording_without_units_are_named_by_what_they_are() {
    let dir = temp_dir("no-units");
    // The walk's frames 30..60 as an array: no units, no pitch, no rate.
    let d = stdout_json(&pedomatch(&["inspect", walk().to_str().unwrap(), "--json"]));
    assert_eq!(d["pressure_units"].as_str(), Some("kPa"));
    let (t, r, c) = (20usize, 12usize, 10usize);
    let mut values = Vec::new();
    for k in 0..t {
        for i in 0..r {
            for j in 0..c {
                values.push(blob(i + 14, j + 10, k));
            }
        }
    }
    let file = dir.join("plain.npy");
    std::fs::write(&file, npy(&[t, r, c], &values)).unwrap();
    let out = dir.join("run");
    pedomatch_ok(&[
        "run",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--report",
        "none",
    ]);
    let mut texts = Vec::new();
    for name in ["frames.csv", "objects.csv", "summary.json", "measures.json"] {
        texts.push((name, std::fs::read_to_string(out.join(name)).unwrap()));
    }
    let d = stdout_json(&pedomatch(&["inspect", file.to_str().unwrap(), "--json"]));
    texts.push(("inspect", d.to_string()));
    for (name, text) in &texts {
        let lower = text.to_ascii_lowercase();
        for wrong in ["_n\"", "_n,", "force_n", "_kpa", "\"n\"", "kpa"] {
            assert!(
                !lower.contains(wrong),
                "{name} says {wrong:?} without units: {text}"
            );
        }
    }
    let header = texts[0].1.lines().next().unwrap().to_string();
    assert!(header.contains("total_load_sensels"), "{header}");
    assert!(
        header.contains("peak_pressure") && header.contains("contact_area_sensels"),
        "{header}"
    );
    // With units and pitch given, the same columns are a force in N and pressures in kPa.
    let out = dir.join("run-kpa");
    pedomatch_ok(&[
        "run",
        file.to_str().unwrap(),
        "--units",
        "kPa",
        "--pitch-mm",
        "5",
        "--out",
        out.to_str().unwrap(),
        "--figures",
        "none",
        "--report",
        "none",
    ]);
    let header = std::fs::read_to_string(out.join("frames.csv")).unwrap();
    let header = header.lines().next().unwrap();
    assert!(
        header.contains("total_force_n") && header.contains("peak_pressure_kpa"),
        "{header}"
    );
}

/// The (node_a, node_b) matches of `pairs`.
fn node_pairs(rows: &[(usize, usize)]) -> Vec<(usize, usize)> {
    let mut v = rows.to_vec();
    v.sort_unstable();
    v
}

#[test]
fn match_of_two_frames_of_one_recording_is_the_runs_pair() {
    let dir = temp_dir("one-pair");
    let w = walk();
    let w = w.to_str().unwrap();
    let out = dir.join("run");
    pedomatch_ok(&[
        "run",
        w,
        "--out",
        out.to_str().unwrap(),
        "--figures",
        "none",
        "--report",
        "none",
    ]);
    let pairs = std::fs::read_to_string(out.join("pairs.csv")).unwrap();
    let mut lines = pairs.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |n: &str| head.iter().position(|h| *h == n).unwrap();
    let row: Vec<String> = lines
        .map(|l| l.split(',').map(str::to_string).collect::<Vec<_>>())
        .find(|r| r[col("frame_a")] == "40" && r[col("frame_b")] == "41")
        .expect("the run's 40 -> 41 pair");
    let (id_a, id_b) = (row[col("id_a")].clone(), row[col("id_b")].clone());
    let local: usize = row[col("local_matches")].parse().unwrap();
    let matches = std::fs::read_to_string(out.join("matches.csv")).unwrap();
    let mut lines = matches.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |n: &str| head.iter().position(|h| *h == n).unwrap();
    let run_pairs: Vec<(usize, usize)> = lines
        .map(|l| l.split(',').collect::<Vec<_>>())
        .filter(|r| r[col("id_a")] == id_a && r[col("id_b")] == id_b)
        .map(|r| {
            (
                r[col("node_a")].parse().unwrap(),
                r[col("node_b")].parse().unwrap(),
            )
        })
        .collect();
    assert!(run_pairs.len() > 50, "{}", run_pairs.len());
    let m = stdout_json(&pedomatch(&[
        "match",
        w,
        w,
        "--frame",
        "40",
        "--frame-b",
        "41",
        "--json",
    ]));
    let match_pairs: Vec<(usize, usize)> = m["pairs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| {
            (
                p["node_a"].as_u64().unwrap() as usize,
                p["node_b"].as_u64().unwrap() as usize,
            )
        })
        .collect();
    assert_eq!(node_pairs(&match_pairs), node_pairs(&run_pairs));
    assert_eq!(m["local_matches"].as_u64(), Some(local as u64));
    assert_eq!(m["settings"].as_str(), Some("run"));
    assert!(m["settings_reason"]
        .as_str()
        .unwrap()
        .contains("pedomatch run"));
    assert_eq!(
        m["options"]["prealign"].as_str(),
        Some("sensor"),
        "{}",
        m["options"]
    );
    assert_eq!(m["options"]["max_rotation"].as_f64(), Some(30.0));
    // The table output says which settings on stderr.
    let o = pedomatch(&["match", w, w, "--frame", "40", "--frame-b", "41"]);
    assert!(stderr(&o).contains("run settings"), "{}", stderr(&o));
    // Two separate files keep the pair defaults, and say so.
    let copy = dir.join("copy.npy");
    let o = pedomatch(&["match", w, w, "--frame", "41", "--frame-b", "40", "--json"]);
    let back = stdout_json(&o);
    assert_eq!(back["settings"].as_str(), Some("pair"));
    let _ = copy;
    // --help says it.
    let help = String::from_utf8_lossy(&pedomatch(&["match", "--help"]).stdout).into_owned();
    assert!(help.contains("settings of `pedomatch run`"), "{help}");
}
