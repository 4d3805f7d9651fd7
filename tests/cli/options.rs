//! The command line against the library's option tables, units and provenance of a run on the
//! bundled recording, `--json`, `inspect` and the exit codes.

use crate::common::{
    pedomatch, pedomatch_ok, read_csv as read_text_csv, read_json, stdout_json, temp_dir,
};
use std::collections::{BTreeSet, HashMap};
use std::path::Path;

const BUNDLED: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/data/FrasP01L.asf");
/// What the bundled file's header says.
const PITCH_MM: f64 = 5.08;
const DT_S: f64 = 0.032;

fn read_csv(path: &Path) -> Vec<HashMap<String, f64>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    lines
        .map(|l| {
            header
                .iter()
                .zip(l.split(','))
                // Numeric columns only (pairs.csv's status is text).
                .filter_map(|(k, v)| Some((k.to_string(), v.parse().ok()?)))
                .collect()
        })
        .collect()
}

/// The long flags a subcommand's `--help` lists.
fn long_flags(subcommand: &str) -> BTreeSet<String> {
    let o = pedomatch_ok(&[subcommand, "--help"]);
    String::from_utf8(o.stdout)
        .unwrap()
        .lines()
        .map(str::trim_start)
        .filter(|l| l.starts_with("--") || l.starts_with("-h, --"))
        .map(|l| {
            let l = l.trim_start_matches("-h, ");
            l.split([' ', '\t']).next().unwrap().to_string()
        })
        .collect()
}

fn flags_of(specs: &[modal_core::OptionSpec]) -> BTreeSet<String> {
    specs.iter().flat_map(|s| s.cli_flags()).collect()
}

#[test]
fn run_and_match_flags_are_the_library_option_tables() {
    let matching = modal_core::options::match_option_specs();
    let recording = pedo_track::recording_option_specs();
    let units = pedo_io::units::unit_option_specs();
    let pair = modal_core::options::pair_option_specs();
    let own =
        |names: &[&str]| -> BTreeSet<String> { names.iter().map(|n| format!("--{n}")).collect() };

    let mut expected = flags_of(&matching);
    expected.extend(flags_of(&recording));
    expected.extend(flags_of(&pedo_output::output_option_specs()));
    expected.extend(own(&["out", "timings", "json", "help"]));
    assert_eq!(long_flags("demo"), expected);
    // The reading options: the layout table and the limits.
    let read = flags_of(&pedo_io::formats::read_option_specs());
    expected.extend(read.clone());
    assert_eq!(long_flags("run"), expected);

    let mut expected = flags_of(&matching);
    expected.extend(flags_of(&pair));
    expected.extend(flags_of(&units));
    // The figure and report of `match` are the run's output options, from their declaration.
    let outputs = pedo_output::output_option_specs();
    let drawings: Vec<_> = outputs
        .iter()
        .filter(|s| ["figures", "figure_format", "report"].contains(&s.name))
        .cloned()
        .collect();
    expected.extend(flags_of(&drawings));
    expected.extend(own(&["points", "frame", "frame-b", "out", "json", "help"]));
    expected.extend(read.clone());
    assert_eq!(long_flags("match"), expected);

    // `inspect` takes a run's noise threshold and units, from their declaration, with its help.
    let noise: Vec<_> = recording
        .iter()
        .filter(|s| s.name == "noise")
        .cloned()
        .collect();
    let mut expected = flags_of(&units);
    expected.extend(flags_of(&noise));
    expected.extend(own(&["json", "help"]));
    expected.extend(read.clone());
    assert_eq!(long_flags("inspect"), expected);
    let help = String::from_utf8(pedomatch(&["inspect", "--help"]).stdout).unwrap();
    let first_words: String = noise[0]
        .help
        .split_whitespace()
        .take(4)
        .collect::<Vec<_>>()
        .join(" ");
    assert!(help.contains(&first_words), "{help}");
    assert!(long_flags("assign").contains("--solver"));
}

#[test]
fn run_on_the_bundled_recording_reports_time_mm_and_provenance() {
    let out = temp_dir("units").join("out");
    let o = pedomatch(&[
        "run",
        BUNDLED,
        "--frames",
        "20..60",
        "--figures",
        "none",
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]);
    let summary = stdout_json(&o);
    assert_eq!(
        summary,
        serde_json::from_slice::<serde_json::Value>(
            &std::fs::read(out.join("summary.json")).unwrap()
        )
        .unwrap()
    );
    assert_eq!(summary["pedomatch_version"], env!("CARGO_PKG_VERSION"));
    let sha = pedo_output::sha256_hex(&std::fs::read(BUNDLED).unwrap());
    assert_eq!(summary["input"]["sha256"], sha);
    assert!(summary["input"]["file"]
        .as_str()
        .unwrap()
        .ends_with("FrasP01L.asf"));
    assert_eq!(summary["input"]["format"], "asf");
    assert_eq!(
        summary["recording"]["pitch_mm"],
        serde_json::json!([PITCH_MM, PITCH_MM])
    );
    assert!((summary["recording"]["frame_rate_hz"].as_f64().unwrap() - 1.0 / DT_S).abs() < 1e-9);
    assert_eq!(summary["recording"]["pressure_units"], "kPa");
    let options = summary["options"].as_object().unwrap();
    // A limit (max_nodes) changes no result: records leave it out.
    for spec in modal_core::options::match_option_specs()
        .iter()
        .chain(&pedo_track::recording_option_specs())
        .filter(|s| s.name != "max_nodes")
    {
        assert!(
            options.contains_key(spec.name),
            "summary lacks option {}",
            spec.name
        );
    }
    assert_eq!(options["frames"], "20..60");
    assert_eq!(options["refits"], 2);
    assert_eq!(options["noise"], 3.0);
    for stage in ["read", "objects", "matching", "tracks", "output"] {
        assert!(
            summary["timings_s"][stage].as_f64().unwrap() >= 0.0,
            "{stage}"
        );
    }

    let near = |a: f64, b: f64| (a - b).abs() < 1e-3;
    let tracks = read_csv(&out.join("tracks.csv"));
    assert!(!tracks.is_empty());
    for r in &tracks {
        assert!(r["frame"] >= 20.0 && r["frame"] < 60.0);
        assert!(near(r["time_s"], r["frame"] * DT_S), "{r:?}");
        assert!(
            near(r["x_mm"], r["x"] * PITCH_MM) && near(r["y_mm"], r["y"] * PITCH_MM),
            "{r:?}"
        );
    }
    let objects = read_csv(&out.join("objects.csv"));
    for (i, r) in objects.iter().enumerate() {
        assert_eq!(r["id"], i as f64, "object ids are 0-based row indices");
        assert!(near(r["centroid_x_mm"], r["centroid_x"] * PITCH_MM));
    }
    for r in read_csv(&out.join("pairs.csv")) {
        assert!(
            near(r["time_a_s"], r["frame_a"] * DT_S) && near(r["time_b_s"], r["frame_b"] * DT_S)
        );
        assert_eq!(objects[r["id_a"] as usize]["frame"], r["frame_a"]);
    }
    for r in read_csv(&out.join("matches.csv")).iter().take(50) {
        assert!(near(r["distance_mm"], r["distance"] * PITCH_MM), "{r:?}");
    }
    let frames = read_csv(&out.join("frames.csv"));
    assert_eq!(frames.len(), 40, "one row per frame used");
    assert_eq!(frames[0]["frame"], 20.0);
    for r in &frames {
        assert!(near(r["time_s"], r["frame"] * DT_S));
        assert!(near(r["contact_area_mm2"], r["contact_sensors"] * 25.8064));
        assert!(r["total_force_n"] >= 0.0 && r["peak_pressure_kpa"] >= 0.0);
        if r["contact_sensors"] > 0.0 {
            assert!(near(r["cop_x_mm"], r["cop_x"] * PITCH_MM));
        }
    }
}

#[test]
fn negative_frames_count_back_from_the_end_of_the_recording() {
    // The bundled walk has 205 frames, the foot on the plate until frame 195.
    let dir = temp_dir("negative-frames");
    let run = |frames: &[&str], out: &str| {
        let mut args = vec!["run", BUNDLED];
        args.extend(frames);
        let out = dir.join(out);
        args.extend(["--figures", "none", "--report", "none", "--json", "--out"]);
        args.push(out.to_str().unwrap());
        pedomatch(&args)
    };
    // `--frames=-13..-10` and `--frames -13..-10` (a value may start with a minus), and the
    // same frames written from the start, give one run: frames 192..195.
    let summaries: Vec<_> = [
        (vec!["--frames=-13..-10"], "equals"),
        (vec!["--frames", "-13..-10"], "space"),
        (vec!["--frames", "192..-10"], "mixed"),
        (vec!["--frames", "192..195"], "positive"),
    ]
    .iter()
    .map(|(frames, out)| stdout_json(&run(frames, out)))
    .collect();
    for s in &summaries {
        assert_eq!(
            s["options"]["frames"], "192..195",
            "the frames run, resolved"
        );
        assert_eq!(s["pairs"], summaries[3]["pairs"]);
        assert_eq!(s["tracks"], summaries[3]["tracks"]);
    }
    let frames = read_csv(&dir.join("equals").join("frames.csv"));
    let numbers: Vec<f64> = frames.iter().map(|r| r["frame"]).collect();
    assert_eq!(numbers, [192.0, 193.0, 194.0]);
    // Out of range once resolved: a usage error naming the range and the frame count.
    for (frames, resolved) in [
        ("--frames=-300..", "-95..205"),
        ("--frames=10..-200", "10..5"),
    ] {
        let o = run(&[frames], "bad");
        let err = String::from_utf8(o.stderr).unwrap();
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(
            err.contains(&frames["--frames=".len()..])
                && err.contains("205 frames")
                && err.contains(resolved),
            "{err}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn pitch_and_frame_rate_override_the_file() {
    let d = stdout_json(&pedomatch(&[
        "inspect",
        BUNDLED,
        "--pitch-mm",
        "2x3",
        "--frame-rate",
        "100",
        "--json",
    ]));
    assert_eq!(d["pitch_mm"], serde_json::json!([2.0, 3.0]));
    assert_eq!(d["frame_rate_hz"], 100.0);
    assert_eq!(d["sensel_area_mm2"], 6.0);
}

#[test]
fn inspect_describes_the_bundled_recording() {
    let d = stdout_json(&pedomatch(&["inspect", BUNDLED, "--json"]));
    assert_eq!(d["format"], "asf");
    assert_eq!(
        (d["frames"].as_u64(), d["rows"].as_u64(), d["cols"].as_u64()),
        (Some(205), Some(60), Some(21))
    );
    assert_eq!(d["pitch_mm"], serde_json::json!([PITCH_MM, PITCH_MM]));
    assert!((d["frame_rate_hz"].as_f64().unwrap() - 31.25).abs() < 1e-9);
    assert_eq!(d["pressure_units"], "kPa");
    let area = &d["measures"]["contact_area_mm2"];
    assert_eq!(
        area["min"], 0.0,
        "the recording starts and ends without contact"
    );
    assert!(area["max"].as_f64().unwrap() > area["mean"].as_f64().unwrap());
    assert!(d["measures"]["total_force_n"]["max"].as_f64().unwrap() > 100.0);
    assert!(d["measures"]["peak_pressure_kpa"]["max"].as_f64().unwrap() > 100.0);

    let o = pedomatch_ok(&["inspect", BUNDLED]);
    let text = String::from_utf8(o.stdout).unwrap();
    for part in [
        "asf",
        "205",
        "60 rows x 21 cols",
        "5.08",
        "31.25",
        "kPa",
        "peak_pressure_kpa",
    ] {
        assert!(text.contains(part), "{part} missing in\n{text}");
    }
}

#[test]
fn json_output_of_match_and_assign_parses() {
    let dir = temp_dir("json");
    let ring: String = (0..30)
        .map(|k| {
            let t = k as f64 / 30.0 * std::f64::consts::TAU;
            format!("{},{}\n", 3.0 * t.cos(), 2.0 * t.sin())
        })
        .collect();
    std::fs::write(dir.join("a.xy"), &ring).unwrap();
    std::fs::write(dir.join("b.xy"), &ring).unwrap();
    let m = stdout_json(&pedomatch(&[
        "match",
        dir.join("a.xy").to_str().unwrap(),
        dir.join("b.xy").to_str().unwrap(),
        "--refits",
        "0",
        "--json",
    ]));
    assert_eq!(m["pairs"].as_array().unwrap().len(), 30);
    assert_eq!(m["options"]["refits"], 0);
    assert_eq!(
        m["options"]["ordered"], true,
        "a ring of nearest-neighbour points is a contour"
    );
    // Two frames of a recording: --frame is 0-based, and the pair reports its time and pitch.
    let m = stdout_json(&pedomatch(&[
        "match", BUNDLED, BUNDLED, "--frame", "40", "--json",
    ]));
    assert!((m["time_a_s"].as_f64().unwrap() - 40.0 * DT_S).abs() < 1e-9);
    assert_eq!(m["pitch_mm_a"], serde_json::json!([PITCH_MM, PITCH_MM]));
    assert_eq!(
        m["options"]["ordered"], true,
        "recording outlines are closed contours"
    );
    let o = pedomatch(&["match", BUNDLED, BUNDLED, "--frame", "205"]);
    assert_eq!(o.status.code(), Some(2), "frames are 0..205");
    std::fs::write(dir.join("cost.csv"), "4,1\n2,0\n").unwrap();
    let a = stdout_json(&pedomatch(&[
        "assign",
        dir.join("cost.csv").to_str().unwrap(),
        "--json",
    ]));
    assert_eq!(a["total_cost"], 3.0);
    assert_eq!(a["solver"], "jv");
}

#[test]
fn exit_codes_are_0_ok_1_runtime_2_usage() {
    let code = |args: &[&str]| pedomatch(args).status.code();
    assert_eq!(code(&["inspect", BUNDLED]), Some(0));
    assert_eq!(code(&["inspect", "/nonexistent/file.asf"]), Some(1));
    assert_eq!(code(&["run", "--no-such-flag", BUNDLED]), Some(2));
    assert_eq!(code(&["run", BUNDLED, "--search", "nearest"]), Some(2));
    assert_eq!(code(&["run", BUNDLED, "--modes", "1.5"]), Some(2));
    assert_eq!(code(&["run", BUNDLED, "--frames", "5..3"]), Some(2));
    assert_eq!(code(&["run", BUNDLED, "--frames", "0..999"]), Some(2));
    assert_eq!(code(&["run", BUNDLED, "--smooth", "2000"]), Some(2));
    assert_eq!(code(&["inspect", BUNDLED, "--pitch-mm", "-1"]), Some(2));
    // A decimal comma is not read as two pitches: refused, with both readings offered.
    for command in ["inspect", "run"] {
        let o = pedomatch(&[command, BUNDLED, "--pitch-mm", "5,08"]);
        let err = String::from_utf8(o.stderr).unwrap();
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains("5.08") && err.contains("5x08"), "{err}");
    }
    let two = stdout_json(&pedomatch(&[
        "inspect",
        BUNDLED,
        "--pitch-mm",
        "7.62x5.08",
        "--json",
    ]));
    assert_eq!(two["pitch_mm"], serde_json::json!([7.62, 5.08]));
    // A negative number is the option's value, checked by its own rule (not an unknown flag).
    for (flag, name) in [
        ("--pitch-mm", "pitch"),
        ("--frame-rate", "frame"),
        ("--threshold", "threshold"),
        ("--kappa", "kappa"),
    ] {
        let o = pedomatch(&["run", BUNDLED, flag, "-0.5"]);
        let err = String::from_utf8(o.stderr).unwrap();
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(
            err.contains(name) && !err.contains("unexpected argument"),
            "{err}"
        );
    }
    let help = String::from_utf8(pedomatch(&["--help"]).stdout).unwrap();
    assert!(
        help.contains("Exit status: 0 success; 1 runtime failure"),
        "{help}"
    );
}

#[test]
fn inspect_reads_a_pedar_export_with_a_given_layout() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("crates/pedo-io");
    let asc = data.join("tests/data/pedar-example-3.01-4.00.asc");
    let layout = data.join("layouts/pedar-pressuRe.csv");
    let bundled = stdout_json(&pedomatch(&["inspect", asc.to_str().unwrap(), "--json"]));
    let given = stdout_json(&pedomatch(&[
        "inspect",
        asc.to_str().unwrap(),
        "--layout",
        layout.to_str().unwrap(),
        "--json",
    ]));
    assert_eq!(bundled["format"], "pedar");
    assert_eq!(given, bundled);
    let missing = pedomatch(&[
        "inspect",
        asc.to_str().unwrap(),
        "--layout",
        "/nonexistent.csv",
    ]);
    assert_eq!(missing.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&missing.stderr).contains("nonexistent.csv"));
}

#[test]
fn a_500_hz_recording_is_matched_at_250_hz_by_default_and_at_every_frame_with_every_1() {
    let trial = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/benches/data/footscan-pressuRe-barefoot.txt"
    );
    let dir = temp_dir("every-auto");
    let run = |name: &str, extra: &[&str]| {
        let out = dir.join(name);
        let mut args = vec![
            "run",
            trial,
            "--frames",
            "100..121",
            "--figures",
            "none",
            "--report",
            "none",
        ];
        args.extend_from_slice(extra);
        args.extend(["--out", out.to_str().unwrap()]);
        pedomatch_ok(&args);
        out
    };
    let (auto, all) = (run("auto", &[]), run("all", &["--every", "1"]));
    let steps = |out: &Path| -> BTreeSet<i64> {
        read_csv(&out.join("pairs.csv"))
            .iter()
            .map(|p| (p["frame_b"] - p["frame_a"]) as i64)
            .collect()
    };
    assert_eq!(steps(&auto), BTreeSet::from([2]));
    assert_eq!(steps(&all), BTreeSet::from([1]));
    let every = |out: &Path| read_json(&out.join("summary.json"))["options"]["every"].clone();
    assert_eq!((every(&auto), every(&all)), (2.into(), 1.into()));
    // frames.csv keeps every frame of the range either way.
    assert_eq!(read_csv(&auto.join("frames.csv")).len(), 21);
    assert_eq!(read_csv(&all.join("frames.csv")).len(), 21);
    // The same run as --every 2.
    let two = run("two", &["--every", "2"]);
    for table in ["pairs.csv", "objects.csv", "tracks.csv"] {
        let read = |out: &Path| std::fs::read(out.join(table)).unwrap();
        assert_eq!(read(&auto), read(&two), "{table}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn every_second_frame_is_matched_with_the_recordings_own_frame_numbers() {
    let dir = temp_dir("every");
    let run = |name: &str, extra: &[&str]| {
        let out = dir.join(name);
        let mut args = vec!["run", BUNDLED, "--figures", "none", "--report", "none"];
        args.extend_from_slice(extra);
        args.extend(["--out", out.to_str().unwrap()]);
        pedomatch_ok(&args);
        out
    };
    let (all, strided) = (run("all", &[]), run("every2", &["--every", "2"]));

    // Pairs join consecutive kept frames: 0 → 2 → 4 …, each at its own time.
    let pairs = read_csv(&strided.join("pairs.csv"));
    assert!(pairs.len() > 50, "{} pairs", pairs.len());
    for p in &pairs {
        let (a, b) = (p["frame_a"], p["frame_b"]);
        assert!(a % 2.0 == 0.0 && b == a + 2.0, "{a} → {b}");
        assert!((p["time_a_s"] - a * DT_S).abs() < 1e-9 && (p["time_b_s"] - b * DT_S).abs() < 1e-9);
    }
    assert_eq!(pairs[0]["frame_a"], 0.0);
    for step in read_csv(&strided.join("tracks.csv")) {
        assert_eq!(step["frame"] % 2.0, 0.0);
        assert!((step["time_s"] - step["frame"] * DT_S).abs() < 1e-9);
    }
    // The kept frames' objects are those of the full run's even frames, with the same frame
    // numbers; frames.csv keeps every frame of the range.
    let key = |r: &HashMap<String, String>| {
        ["frame", "index", "nodes", "centroid_x", "centroid_y"].map(|k| r[k].clone())
    };
    let even: Vec<_> = read_text_csv(&all.join("objects.csv"))
        .iter()
        .filter(|r| r["frame"].parse::<usize>().unwrap() % 2 == 0)
        .map(key)
        .collect();
    let kept: Vec<_> = read_text_csv(&strided.join("objects.csv"))
        .iter()
        .map(key)
        .collect();
    assert!(!kept.is_empty());
    assert_eq!(kept, even);
    assert_eq!(read_text_csv(&strided.join("frames.csv")).len(), 205);
    // Recorded with the other options; 1 (every frame) by default.
    let every = |out: &Path| read_json(&out.join("summary.json"))["options"]["every"].clone();
    assert_eq!((every(&strided), every(&all)), (2.into(), 1.into()));

    // 0 is no stride, and reference frames of drift correction must be frames run.
    let code = |args: &[&str]| pedomatch(args).status.code();
    assert_eq!(code(&["run", BUNDLED, "--every", "0"]), Some(2));
    let o = pedomatch(&["run", BUNDLED, "--every", "2", "--drift-reference", "25"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("multiple of every"));
    std::fs::remove_dir_all(&dir).unwrap();
}
