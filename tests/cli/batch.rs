//! End-to-end tests of `pedomatch batch`: a folder of recordings with a corrupt one, resuming,
//! `--force`, glob and folder inputs, and the same table whatever the number of jobs.

use crate::common::{pedomatch, read_json, temp_dir};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/crates/pedo-io/tests/data");
const FAST: [&str; 4] = ["--figures", "none", "--report", "none"];
const TABLES: [&str; 7] = [
    "pairs.csv",
    "pairs.json",
    "objects.csv",
    "matches.csv",
    "tracks.csv",
    "frames.csv",
    "summary.json",
];

/// A study folder: two recordings of the same file name in different folders, a third beside
/// them, and an F-Scan file cut after its header (it sniffs as ASF but cannot be read).
fn study_inputs(base: &Path) -> PathBuf {
    let input = base.join("in");
    for sub in ["a", "b"] {
        std::fs::create_dir_all(input.join(sub)).unwrap();
    }
    let copy = |from: &str, to: &str| std::fs::copy(Path::new(DATA).join(from), input.join(to));
    copy("emed-test-1-10.lst", "a/trial.lst").unwrap();
    copy("synthetic-walk.lst", "b/trial.lst").unwrap();
    copy("tekscan-FrasP01L-11-20.csv", "tekscan.csv").unwrap();
    let asf = std::fs::read(Path::new(DATA).join("FrasP01L.asf")).unwrap();
    std::fs::write(input.join("corrupt.asf"), &asf[..asf.len() / 50]).unwrap();
    // Not a recording: a folder search leaves it out.
    std::fs::write(input.join("notes.txt"), "subject 3, left foot\n").unwrap();
    input
}

fn batch_json(args: &[&str]) -> (Option<i32>, Value, String) {
    let out = pedomatch(&[&["batch", "--json"], args, &FAST].concat());
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    let json = serde_json::from_slice(&out.stdout)
        .unwrap_or_else(|e| panic!("{e}: {}\n{stderr}", String::from_utf8_lossy(&out.stdout)));
    (out.status.code(), json, stderr)
}

fn rows(report: &Value) -> Vec<Value> {
    report["rows"].as_array().unwrap().clone()
}

fn row<'a>(rows: &'a [Value], path_end: &str) -> &'a Value {
    rows.iter()
        .find(|r| r["path"].as_str().unwrap().ends_with(path_end))
        .unwrap_or_else(|| panic!("no row for {path_end}: {rows:?}"))
}

/// The columns that do not depend on timing.
fn numbers(r: &Value) -> Value {
    let mut r = r.clone();
    r.as_object_mut().unwrap().remove("wall_time_s");
    r.as_object_mut().unwrap().remove("status");
    r.as_object_mut().unwrap().remove("message");
    r
}

fn keys(v: &Value) -> Vec<String> {
    v.as_object().unwrap().keys().cloned().collect()
}

fn sha256_of(path: &Path) -> String {
    pedo_output::sha256_hex(&std::fs::read(path).unwrap())
}

#[test]
fn a_corrupt_recording_fails_alone_and_a_second_run_resumes() {
    let base = temp_dir("resume");
    let input = study_inputs(&base);
    let out = base.join("study");
    let (i, o) = (input.to_str().unwrap(), out.to_str().unwrap());

    let (code, first, stderr) = batch_json(&[i, "--out", o, "--jobs", "2"]);
    assert_eq!(code, Some(1), "a failed recording makes exit status 1");
    assert!(stderr.contains("corrupt.asf"), "{stderr}");
    let first_rows = rows(&first);
    assert_eq!(
        first_rows.len(),
        4,
        "notes.txt is no recording: {first_rows:?}"
    );
    assert_eq!(
        (&first["ok"], &first["error"]),
        (&Value::from(3), &Value::from(1))
    );
    let bad = row(&first_rows, "corrupt.asf");
    assert_eq!(bad["status"], "error");
    assert_eq!(bad["format"], "asf", "the content was recognised");
    let message = bad["message"].as_str().unwrap();
    assert!(message.contains("corrupt.asf"), "{message}");
    assert!(bad["frames"].is_null() && bad["pairs"].is_null());

    // Every good recording: its own folder with every table, the summary of that input.
    let mut folders = Vec::new();
    for (name, source) in [
        ("a/trial.lst", "emed-test-1-10.lst"),
        ("b/trial.lst", "synthetic-walk.lst"),
        ("tekscan.csv", "tekscan-FrasP01L-11-20.csv"),
    ] {
        let r = row(&first_rows, name);
        assert_eq!(r["status"], "ok", "{r}");
        let folder = out.join(r["output"].as_str().unwrap());
        for t in TABLES {
            assert!(folder.join(t).is_file(), "{}/{t}", folder.display());
        }
        let summary: Value =
            serde_json::from_slice(&std::fs::read(folder.join("summary.json")).unwrap()).unwrap();
        assert_eq!(
            summary["input"]["sha256"].as_str().unwrap(),
            sha256_of(&Path::new(DATA).join(source))
        );
        assert_eq!(r["frames"], summary["recording"]["frames"]);
        assert_eq!(r["pairs"], summary["pairs"]);
        assert_eq!(r["tracks"], summary["tracks"]);
        assert!(r["pairs"].as_u64().unwrap() > 0, "{r}");
        let pairs_csv = std::fs::read_to_string(folder.join("pairs.csv")).unwrap();
        assert_eq!(
            pairs_csv.lines().count() - 1,
            r["pairs"].as_u64().unwrap() as usize,
            "one pairs.csv line per matched pair"
        );
        folders.push(folder);
    }
    assert_ne!(folders[0], folders[1], "same file name, different folders");

    // study.csv: the same rows, units in the header, the failure's message quoted.
    let csv = std::fs::read_to_string(out.join("study.csv")).unwrap();
    let header = csv.lines().next().unwrap();
    assert_eq!(
        header,
        "path,output,format,frames,frame_rate_hz,pitch_x_mm,pitch_y_mm,pressure_units,pairs,mean_local_percent,mean_optimisation_percent,mean_trackable_percent,mean_round_trip_sensels,tracks,track_round_trip_median_sensels,track_round_trip_p95_sensels,point_round_trip_median_sensels,point_round_trip_p95_sensels,peak_pressure_kpa,pti_max_kpa_s,peak_force_n,fti_n_s,contact_time_s,max_contact_area_mm2,wall_time_s,status,message"
    );
    assert_eq!(csv.lines().count(), 5);
    let bad_line = csv.lines().find(|l| l.contains("corrupt.asf,")).unwrap();
    assert!(bad_line.contains(",error,"), "{bad_line}");
    // study.json: what produced the rows, their counts, and the rows.
    let study_json = read_json(&out.join("study.json"));
    assert_eq!(study_json["rows"], first["rows"]);
    assert_eq!(study_json["pedomatch_version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(study_json["inputs"], serde_json::json!([i]));
    for count in ["recordings", "ok", "skipped", "error"] {
        assert_eq!(study_json[count], first[count], "{count}");
    }
    assert_eq!(study_json["kept"], 0);
    // Every option as used, as each summary.json lists them; the values a recording fills in
    // from its file are null (each recording's own) or the whole of it (`0..`).
    let summary = read_json(&folders[0].join("summary.json"));
    let (given, used) = (&study_json["options"], &summary["options"]);
    assert_eq!(keys(given), keys(used));
    for (key, value) in used.as_object().unwrap() {
        match key.as_str() {
            "frames" => assert_eq!(given[key], "0.."),
            // As given: each recording resolves it from its own frame rate.
            "every" => assert_eq!(given[key], "auto"),
            "noise" | "pitch_mm" | "frame_rate" | "units" => assert!(given[key].is_null(), "{key}"),
            _ => assert_eq!(&given[key], value, "{key}"),
        }
    }

    // Second run: the complete folders are skipped with their numbers; the corrupt file fails again.
    let before = std::fs::read(folders[2].join("summary.json")).unwrap();
    let (code, second, _) = batch_json(&[i, "--out", o]);
    assert_eq!(code, Some(1));
    let second_rows = rows(&second);
    for (a, b) in first_rows.iter().zip(&second_rows) {
        assert_eq!(a["path"], b["path"]);
        if a["status"] == "ok" {
            assert_eq!(b["status"], "skipped", "{b}");
            assert_eq!(numbers(a), numbers(b));
            assert_eq!(
                a["wall_time_s"], b["wall_time_s"],
                "the previous row's time is kept"
            );
        } else {
            assert_eq!(b["status"], "error");
        }
    }
    assert_eq!(
        std::fs::read(folders[2].join("summary.json")).unwrap(),
        before,
        "a skipped folder is not rewritten"
    );

    // Other options: not the same run, so nothing is skipped.
    let (_, changed, _) = batch_json(&[i, "--out", o, "--spacing", "1.5"]);
    assert_eq!(changed["ok"], 3, "{changed}");

    // --force redoes complete folders.
    let (_, forced, _) = batch_json(&[i, "--out", o, "--spacing", "1.5", "--force"]);
    assert_eq!(
        (&forced["ok"], &forced["skipped"]),
        (&Value::from(3), &Value::from(0))
    );
    std::fs::remove_dir_all(&base).unwrap();
}

#[test]
fn glob_and_file_inputs_and_any_number_of_jobs_give_the_same_table() {
    let base = temp_dir("glob");
    let input = study_inputs(&base);
    let pattern = format!("{}/*/trial.lst", input.display());
    let file = input.join("tekscan.csv");
    let file = file.to_str().unwrap();
    let mut tables = Vec::new();
    for jobs in ["1", "2"] {
        let out = base.join(format!("study-{jobs}"));
        let (code, report, stderr) =
            batch_json(&[&pattern, file, "--out", out.to_str().unwrap(), "-j", jobs]);
        assert_eq!(code, Some(0), "{stderr}");
        let r = rows(&report);
        assert_eq!(r.len(), 3, "{r:?}");
        assert!(r[0]["path"].as_str().unwrap().ends_with("a/trial.lst"));
        assert!(r[1]["path"].as_str().unwrap().ends_with("b/trial.lst"));
        assert!(r[2]["path"].as_str().unwrap().ends_with("tekscan.csv"));
        tables.push(r.iter().map(numbers).collect::<Vec<_>>());
    }
    assert_eq!(tables[0], tables[1], "one job or two: the same results");
    std::fs::remove_dir_all(&base).unwrap();
}

#[test]
fn a_study_folder_is_never_written_over_other_files_and_no_input_is_an_error() {
    let base = temp_dir("foreign");
    let input = study_inputs(&base);
    let mine = base.join("thesis");
    std::fs::create_dir_all(&mine).unwrap();
    std::fs::write(mine.join("chapter1.tex"), "precious").unwrap();
    let out = pedomatch(&[
        "batch",
        input.join("tekscan.csv").to_str().unwrap(),
        "--out",
        mine.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("not a pedomatch study"), "{stderr}");
    assert_eq!(std::fs::read_dir(&mine).unwrap().count(), 1);

    let empty = base.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let out = pedomatch(&[
        "batch",
        empty.to_str().unwrap(),
        "--out",
        base.join("s").to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no recordings found"));

    let out = pedomatch(&["batch", "x.asf", "--out", "s", "--jobs", "0"]);
    assert_eq!(out.status.code(), Some(2), "--jobs 0 is a usage error");
    std::fs::remove_dir_all(&base).unwrap();
}

#[test]
fn a_batch_into_a_study_folder_in_use_is_refused_in_one_line_and_writes_nothing() {
    let base = temp_dir("locked");
    let input = study_inputs(&base);
    let study = base.join("study");
    // Another batch holds the study folder (this test process, through the library).
    let held = pedo_study::lock_study_folder(&study).unwrap();
    let recording = input.join("tekscan.csv");
    let args = [
        "batch",
        recording.to_str().unwrap(),
        "--out",
        study.to_str().unwrap(),
        "--figures",
        "none",
        "--report",
        "none",
    ];
    let out = pedomatch(&args);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(stderr.starts_with("pedomatch: error: "), "{stderr}");
    assert!(stderr.contains(study.to_str().unwrap()), "{stderr}");
    assert!(
        stderr.contains(&format!(
            "in use by another pedomatch batch (process {})",
            std::process::id()
        )),
        "{stderr}"
    );
    assert!(!study.join("study.csv").exists() && !study.join("study.json").exists());
    // Released: the same command runs.
    drop(held);
    let out = pedomatch(&args);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(study.join("study.csv").is_file());
    std::fs::remove_dir_all(&base).unwrap();
}

#[test]
fn tables_parquet_writes_parquet_files_and_an_unknown_format_is_a_usage_error() {
    let base = temp_dir("parquet");
    let input = study_inputs(&base);
    let out = base.join("study");
    let (i, o) = (input.to_str().unwrap(), out.to_str().unwrap());
    let (code, report, stderr) = batch_json(&[i, "--out", o, "--tables", "parquet"]);
    assert_eq!(code, Some(1), "the corrupt file still fails: {stderr}");
    assert!(
        report["study"].as_str().unwrap().ends_with("study.parquet"),
        "{report}"
    );
    let is_parquet = |p: &Path| {
        let b = std::fs::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        b.len() > 8 && b.starts_with(b"PAR1") && b.ends_with(b"PAR1")
    };
    assert!(is_parquet(&out.join("study.parquet")));
    assert!(!out.join("study.csv").exists() && out.join("study.json").is_file());
    let ok: Vec<Value> = rows(&report)
        .into_iter()
        .filter(|r| r["status"] == "ok")
        .collect();
    assert_eq!(ok.len(), 3);
    for r in &ok {
        let folder = out.join(r["output"].as_str().unwrap());
        for t in ["pairs", "objects", "matches", "tracks", "frames"] {
            assert!(is_parquet(&folder.join(format!("{t}.parquet"))), "{t}");
            assert!(!folder.join(format!("{t}.csv")).exists(), "{t}");
        }
        assert!(folder.join("pairs.json").is_file() && folder.join("summary.json").is_file());
    }
    // A second Parquet run skips them; a CSV run does not take Parquet folders as complete.
    let (_, again, _) = batch_json(&[i, "--out", o, "--tables", "parquet"]);
    assert_eq!(again["skipped"], 3, "{again}");
    let (_, as_csv, _) = batch_json(&[i, "--out", o]);
    assert_eq!(as_csv["ok"], 3, "{as_csv}");
    assert!(out.join("study.csv").is_file() && !out.join("study.parquet").exists());

    // `run` too, and its closing line names the files.
    let run_out = base.join("run");
    let o = pedomatch(
        &[
            &[
                "run",
                input.join("tekscan.csv").to_str().unwrap(),
                "--out",
                run_out.to_str().unwrap(),
                "--tables",
                "parquet",
            ],
            &FAST[..],
        ]
        .concat(),
    );
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(stdout.contains("matches.parquet"), "{stdout}");
    assert!(is_parquet(&run_out.join("tracks.parquet")));

    let never = base.join("x");
    let bad = pedomatch(&[
        "batch",
        i,
        "--out",
        never.to_str().unwrap(),
        "--tables",
        "xlsx",
    ]);
    assert_eq!(
        bad.status.code(),
        Some(2),
        "an unknown format is a usage error"
    );
    let stderr = String::from_utf8_lossy(&bad.stderr);
    assert!(
        stderr.contains("xlsx") && stderr.contains("--tables") && stderr.contains("parquet"),
        "{stderr}"
    );
    assert!(!never.exists());
    std::fs::remove_dir_all(&base).unwrap();
}

/// A one-frame CSV grid holding one blob, peak 100.
fn one_frame_csv(path: &Path) {
    let mut text = String::new();
    for r in 0..16 {
        let row: Vec<String> = (0..16)
            .map(|c| {
                let d2 = ((r as f64 - 7.5).powi(2) + (c as f64 - 7.5).powi(2)) / 12.0;
                format!("{:.1}", 100.0 * (-d2).exp())
            })
            .collect();
        text += &row.join(",");
        text.push('\n');
    }
    std::fs::write(path, text).unwrap();
}

#[test]
fn resuming_with_an_animation_or_pair_figures_asked_for_runs_the_folder_again() {
    let base = temp_dir("animation");
    let input = study_inputs(&base);
    let file = input.join("tekscan.csv");
    let (f, out) = (file.to_str().unwrap(), base.join("study"));
    let o = out.to_str().unwrap();
    let (code, first, stderr) = batch_json(&[f, "--out", o]);
    assert_eq!(code, Some(0), "{stderr}");
    let folder = out.join(rows(&first)[0]["output"].as_str().unwrap());
    assert!(!folder.join("animation.gif").exists());
    // The folder lacks the animation now asked for: not complete.
    let (code, gif, stderr) = batch_json(&[f, "--out", o, "--animation", "gif"]);
    assert_eq!(code, Some(0), "{stderr}");
    assert_eq!(rows(&gif)[0]["status"], "ok", "{gif}");
    assert!(folder.join("animation.gif").is_file());
    let summary: Value =
        serde_json::from_slice(&std::fs::read(folder.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["options"]["animation"], "gif", "{summary}");
    let (_, again, _) = batch_json(&[f, "--out", o, "--animation", "gif"]);
    assert_eq!(rows(&again)[0]["status"], "skipped", "{again}");
    // The animation is an option like the others: leaving it out runs the folder again.
    let (_, none, _) = batch_json(&[f, "--out", o]);
    assert_eq!(rows(&none)[0]["status"], "ok", "{none}");
    assert!(!folder.join("animation.gif").exists());

    // Pair figures: a folder missing one of them is not complete when figures are asked for.
    let with_figures = |extra: &[&str]| {
        let out = pedomatch(
            &[
                &["batch", "--json", f, "--out", o, "--report", "none"],
                extra,
            ]
            .concat(),
        );
        serde_json::from_slice::<Value>(&out.stdout).unwrap()
    };
    let png = with_figures(&["--figures", "pairs"]);
    assert_eq!(rows(&png)[0]["status"], "ok");
    let pairs = rows(&png)[0]["pairs"].as_u64().unwrap();
    let figures: Vec<PathBuf> = std::fs::read_dir(folder.join("figures"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(figures.len() as u64, pairs, "{figures:?}");
    assert_eq!(
        rows(&with_figures(&["--figures", "pairs"]))[0]["status"],
        "skipped"
    );
    std::fs::remove_file(&figures[0]).unwrap();
    let redone = with_figures(&["--figures", "pairs"]);
    assert_eq!(rows(&redone)[0]["status"], "ok", "{redone}");
    assert!(figures[0].is_file());
    std::fs::remove_dir_all(&base).unwrap();
}

#[test]
fn rows_say_what_they_hold_no_pairs_no_folder_and_frames_read() {
    let base = temp_dir("rows");
    let input = study_inputs(&base);
    let one = base.join("one-frame.csv");
    one_frame_csv(&one);
    let out = base.join("study");
    let o = out.to_str().unwrap();
    let (code, report, stderr) = batch_json(&[one.to_str().unwrap(), "--out", o]);
    assert_eq!(code, Some(0), "{stderr}");
    let r = &rows(&report)[0];
    assert_eq!(
        (&r["status"], &r["frames"], &r["pairs"]),
        (&"ok".into(), &1.into(), &0.into())
    );
    assert!(
        r["message"]
            .as_str()
            .unwrap()
            .contains("no pair of objects in consecutive frames to match"),
        "{r}"
    );

    // An error row: no folder named when none was written; the frames read are given.
    let (code, report, _) = batch_json(&[input.to_str().unwrap(), "--out", o]);
    assert_eq!(code, Some(1));
    let bad = row(&rows(&report), "corrupt.asf").clone();
    assert!(bad["output"].is_null(), "{bad}");
    let frames = row(&rows(&report), "tekscan.csv")["frames"].clone();
    let tekscan = input.join("tekscan.csv");
    let (code, report, _) =
        batch_json(&[tekscan.to_str().unwrap(), "--out", o, "--frames", "15..30"]);
    assert_eq!(code, Some(1));
    let r = &rows(&report)[0];
    assert_eq!(r["status"], "error");
    assert_eq!(r["frames"], frames, "{r}");
    assert!(r["message"].as_str().unwrap().contains("15..30"), "{r}");

    // iso_frame outside the frames asked for is an option error naming both.
    let (code, report, _) = batch_json(&[
        tekscan.to_str().unwrap(),
        "--out",
        o,
        "--model",
        "isocontour",
        "--frames",
        "2..5",
        "--iso-frame",
        "7",
    ]);
    assert_eq!(code, Some(1));
    let m = rows(&report)[0]["message"].as_str().unwrap().to_string();
    assert!(
        m.contains("iso_frame") && m.contains("frames") && m.contains("2..5"),
        "{m}"
    );
    std::fs::remove_dir_all(&base).unwrap();
}

#[test]
fn counts_are_written_in_the_singular_for_one_and_isocontours_skip_levels() {
    let base = temp_dir("grammar");
    let one = base.join("one-frame.csv");
    one_frame_csv(&one);
    let o = base.join("study");
    let out = pedomatch(
        &[
            &["batch", one.to_str().unwrap(), "--out", o.to_str().unwrap()][..],
            &FAST,
        ]
        .concat(),
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.starts_with("1 recording: 1 ok, 0 skipped, 0 failed"),
        "{stdout}"
    );
    // Isocontours: many levels of a small blob, the highest too small to be objects.
    let (code, report, stderr) = batch_json(&[
        one.to_str().unwrap(),
        "--out",
        o.to_str().unwrap(),
        "--model",
        "isocontour",
        "--iso-levels",
        "30",
    ]);
    assert_eq!(code, Some(0), "{stderr}");
    let m = rows(&report)[0]["message"].as_str().unwrap().to_string();
    assert!(
        m.contains("levels skipped") || m.contains("level skipped"),
        "{m}"
    );
    assert!(
        !m.contains("frames skipped") && !m.contains(" 0 pairs"),
        "{m}"
    );
    let run = pedomatch(
        &[
            &[
                "run",
                one.to_str().unwrap(),
                "--out",
                base.join("run").to_str().unwrap(),
                "--model",
                "isocontour",
                "--iso-levels",
                "30",
            ][..],
            &FAST,
        ]
        .concat(),
    );
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(run.status.success(), "{stdout}");
    assert!(stdout.contains("isobaric level"), "{stdout}");
    assert!(
        !stdout.contains("frames that") && !stdout.contains(" 1 tracks"),
        "{stdout}"
    );
    std::fs::remove_dir_all(&base).unwrap();
}

#[test]
fn terminal_progress_counts_recordings_not_thousandths() {
    // Under a pseudo-terminal (util-linux `script`), where the bar is drawn.
    if Command::new("script").arg("--version").output().is_err() {
        eprintln!("no `script`: skipped");
        return;
    }
    let base = temp_dir("progress");
    let input = study_inputs(&base);
    let cmd = format!(
        "{} batch {} {} --out {} --figures none --report none",
        env!("CARGO_BIN_EXE_pedomatch"),
        input.join("a").display(),
        input.join("b").display(),
        base.join("study").display()
    );
    let out = Command::new("script")
        .args(["-qfec", &cmd, "/dev/null"])
        .env("COLUMNS", "120")
        .output()
        .unwrap();
    let screen = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{screen}");
    assert!(screen.contains("/2 recordings"), "{screen}");
    assert!(!screen.contains("/2000"), "{screen}");
    std::fs::remove_dir_all(&base).unwrap();
}

/// The paths of a study table's rows, in order, relative to `input`.
fn row_paths(rows: &[Value], input: &Path) -> Vec<String> {
    let input = input.to_str().unwrap();
    rows.iter()
        .map(|r| {
            let path = r["path"].as_str().unwrap();
            path.strip_prefix(input).unwrap_or(path).to_string()
        })
        .collect()
}

#[test]
fn a_run_on_part_of_a_study_keeps_the_other_rows_while_their_folders_are_there() {
    let base = temp_dir("subset");
    let input = study_inputs(&base);
    let out = base.join("study");
    let (i, o) = (input.to_str().unwrap(), out.to_str().unwrap());
    let (code, _, _) = batch_json(&[i, "--out", o]);
    assert_eq!(code, Some(1), "the corrupt file fails");
    let all = read_json(&out.join("study.json"))["rows"].clone();
    let all = all.as_array().unwrap();
    assert_eq!(
        row_paths(all, &input),
        [
            "/a/trial.lst",
            "/b/trial.lst",
            "/corrupt.asf",
            "/tekscan.csv"
        ]
    );

    // One recording, with other options: the report, the counts and the exit status are this
    // run's; the table keeps the other rows, as they were, after this run's.
    let tekscan = input.join("tekscan.csv");
    let t = tekscan.to_str().unwrap();
    let (code, report, stderr) = batch_json(&[t, "--out", o, "--spacing", "1.5"]);
    assert_eq!(
        code,
        Some(0),
        "the kept error row is not this run's: {stderr}"
    );
    assert_eq!(
        (&report["recordings"], &report["ok"]),
        (&1.into(), &1.into())
    );
    assert_eq!(rows(&report).len(), 1);
    let study = read_json(&out.join("study.json"));
    let table = study["rows"].as_array().unwrap();
    assert_eq!(
        row_paths(table, &input),
        [
            "/tekscan.csv",
            "/a/trial.lst",
            "/b/trial.lst",
            "/corrupt.asf"
        ]
    );
    assert_eq!(table[0], rows(&report)[0]);
    // Kept as they were, their messages saying so.
    let kept = |r: &Value| {
        let mut r = r.clone();
        let message = r["message"].as_str().unwrap();
        r["message"] = pedo_study::kept_message(message, true).into();
        r
    };
    assert_eq!(&table[1..], &[kept(&all[0]), kept(&all[1]), kept(&all[2])]);
    assert_eq!(
        table[1]["message"],
        "kept from an earlier run (not among this run's inputs)"
    );
    assert!(
        table[3]["message"]
            .as_str()
            .unwrap()
            .starts_with("kept from an earlier run (not among this run's inputs); /"),
        "{}",
        table[3]
    );
    assert_eq!(
        (&study["recordings"], &study["kept"]),
        (&1.into(), &3.into())
    );
    assert_eq!(study["inputs"], serde_json::json!([t]));
    assert_eq!(study["options"]["spacing"], 1.5);
    // The kept rows say which run made them, with its own options.
    let earlier = study["earlier_runs"].as_array().unwrap();
    assert_eq!(earlier.len(), 1, "{earlier:?}");
    assert_eq!(earlier[0]["inputs"], serde_json::json!([i]));
    assert_eq!(earlier[0]["options"]["spacing"], 1.0);
    assert_eq!(
        earlier[0]["paths"],
        serde_json::json!([&all[0]["path"], &all[1]["path"], &all[2]["path"]])
    );
    let csv = std::fs::read_to_string(out.join("study.csv")).unwrap();
    assert_eq!(csv.lines().count(), 5, "{csv}");
    // The closing line says the table holds more than this run.
    let line = pedomatch(&[&["batch", t, "--out", o, "--spacing", "1.5"], &FAST[..]].concat());
    let line = String::from_utf8_lossy(&line.stdout);
    assert!(
        line.contains("1 recording: 0 ok, 1 skipped")
            && line.contains("(with 3 rows of earlier runs)"),
        "{line}"
    );

    // A row goes once what it reports is gone: a deleted folder, a deleted failing recording.
    std::fs::remove_dir_all(out.join(all[0]["output"].as_str().unwrap())).unwrap();
    std::fs::remove_file(input.join("corrupt.asf")).unwrap();
    let (code, _, _) = batch_json(&[t, "--out", o]);
    assert_eq!(code, Some(0));
    let study = read_json(&out.join("study.json"));
    assert_eq!(
        row_paths(study["rows"].as_array().unwrap(), &input),
        ["/tekscan.csv", "/b/trial.lst"]
    );
    // b/trial.lst is still the first run's (with spacing 1.0); the second run's only row is
    // this run's again (found complete), so that run is no longer listed.
    let earlier = study["earlier_runs"].as_array().unwrap();
    assert_eq!(earlier.len(), 1, "{earlier:?}");
    assert_eq!(
        (&earlier[0]["options"]["spacing"], &earlier[0]["paths"]),
        (&1.0.into(), &serde_json::json!([&all[1]["path"]]))
    );
    std::fs::remove_dir_all(&base).unwrap();
}

#[test]
fn a_study_json_of_bare_rows_still_resumes() {
    // study.json was a bare list of rows without units: such a study folder resumes, its rows
    // are kept, and those it keeps get their units from their folders.
    let base = temp_dir("old-json");
    let input = study_inputs(&base);
    let out = base.join("study");
    let (i, o) = (input.to_str().unwrap(), out.to_str().unwrap());
    let (_, first, _) = batch_json(&[i, "--out", o]);
    let unit_columns = [
        "frame_rate_hz",
        "pitch_x_mm",
        "pitch_y_mm",
        "pressure_units",
    ];
    let old: Vec<Value> = rows(&first)
        .into_iter()
        .map(|mut r| {
            for c in unit_columns {
                r.as_object_mut().unwrap().remove(c);
            }
            r
        })
        .collect();
    std::fs::write(out.join("study.json"), serde_json::to_vec(&old).unwrap()).unwrap();
    let b = input.join("b");
    let (code, report, _) = batch_json(&[b.to_str().unwrap(), "--out", o]);
    assert_eq!(code, Some(0));
    let resumed = &rows(&report)[0];
    assert_eq!(resumed["status"], "skipped", "{resumed}");
    let earlier = row(&rows(&first), "b/trial.lst").clone();
    assert_eq!(resumed["wall_time_s"], earlier["wall_time_s"]);
    assert_eq!(
        numbers(resumed),
        numbers(&earlier),
        "the units come back from summary.json"
    );
    let study = read_json(&out.join("study.json"));
    let table = study["rows"].clone();
    assert_eq!(table.as_array().unwrap().len(), 4);
    // The three kept rows come from a run that recorded nothing of itself.
    let earlier = &study["earlier_runs"];
    assert_eq!(earlier.as_array().unwrap().len(), 1, "{earlier}");
    assert_eq!(earlier[0]["options"], Value::Null);
    assert_eq!(earlier[0]["paths"].as_array().unwrap().len(), 3);
    let first_rows = rows(&first);
    for r in table.as_array().unwrap() {
        let before = row(&first_rows, r["path"].as_str().unwrap());
        for c in unit_columns {
            assert_eq!(r[c], before[c], "{c} of {}", r["path"]);
        }
    }
    std::fs::remove_dir_all(&base).unwrap();
}

#[test]
fn rows_give_each_recordings_frame_rate_pitch_and_pressure_units() {
    // A study mixing sensors: emed (kPa), footscan (N/cm²), Tekscan CSV (kPa), and a CSV grid
    // that says nothing of its units.
    let base = temp_dir("units");
    let data = base.join("in");
    std::fs::create_dir_all(&data).unwrap();
    for f in [
        "emed-test-1-10.lst",
        "footscan-FrasP01L-11-20.txt",
        "tekscan-FrasP01L-11-20.csv",
    ] {
        std::fs::copy(Path::new(DATA).join(f), data.join(f)).unwrap();
    }
    let grid = base.join("grid.csv");
    one_frame_csv(&grid);
    let out = base.join("study");
    let o = out.to_str().unwrap();
    let (code, report, stderr) =
        batch_json(&[data.to_str().unwrap(), grid.to_str().unwrap(), "--out", o]);
    assert_eq!(code, Some(0), "{stderr}");
    let units = |r: &Value| {
        (
            r["frame_rate_hz"].as_f64(),
            r["pitch_x_mm"].as_f64(),
            r["pitch_y_mm"].as_f64(),
            r["pressure_units"].as_str().map(str::to_string),
        )
    };
    let r = rows(&report);
    assert_eq!(
        units(row(&r, "emed-test-1-10.lst")),
        (Some(100.0), Some(5.0), Some(5.0), Some("kPa".into()))
    );
    let footscan = units(row(&r, "footscan-FrasP01L-11-20.txt"));
    assert_eq!(footscan.3.as_deref(), Some("N/cm²"));
    assert_eq!(units(row(&r, "grid.csv")), (None, None, None, None));
    // As each summary.json gives them.
    for each in &r {
        let summary = read_json(
            &out.join(each["output"].as_str().unwrap())
                .join("summary.json"),
        );
        let rec = &summary["recording"];
        assert_eq!(each["frame_rate_hz"], rec["frame_rate_hz"]);
        assert_eq!(each["pitch_x_mm"], rec["pitch_mm"][0]);
        assert_eq!(each["pitch_y_mm"], rec["pitch_mm"][1]);
        assert_eq!(each["pressure_units"], rec["pressure_units"]);
    }
    // The CSV writes unknown ones empty.
    let csv = std::fs::read_to_string(out.join("study.csv")).unwrap();
    let grid_line = csv.lines().find(|l| l.contains("grid.csv")).unwrap();
    assert!(grid_line.contains(",1,,,,,0,"), "{grid_line}");
    // Skipped rows keep them.
    let (_, again, _) = batch_json(&[data.to_str().unwrap(), grid.to_str().unwrap(), "--out", o]);
    for (a, b) in r.iter().zip(&rows(&again)) {
        assert_eq!(b["status"], "skipped");
        assert_eq!(units(a), units(b));
    }
    // The unit options, as the run used them; an error row gives them too once the file is read.
    let g = grid.to_str().unwrap();
    let unit_args = [
        "--pitch-mm",
        "2x3",
        "--frame-rate",
        "50",
        "--units",
        "N/cm2",
    ];
    let (_, set, _) = batch_json(&[&[g, "--out", o][..], &unit_args].concat());
    let expected = (Some(50.0), Some(2.0), Some(3.0), Some("N/cm²".to_string()));
    assert_eq!(units(&rows(&set)[0]), expected);
    let (code, failed, _) =
        batch_json(&[&[g, "--out", o, "--frames", "3..9"][..], &unit_args].concat());
    assert_eq!(code, Some(1));
    assert_eq!(rows(&failed)[0]["status"], "error");
    assert_eq!(units(&rows(&failed)[0]), expected);
    std::fs::remove_dir_all(&base).unwrap();
}

#[test]
fn a_pedar_recording_read_with_another_layout_file_is_run_again() {
    let base = temp_dir("layout");
    let input = base.join("in");
    std::fs::create_dir_all(&input).unwrap();
    let asc = input.join("insoles.asc");
    std::fs::copy(Path::new(DATA).join("pedar-example-3.01-4.00.asc"), &asc).unwrap();
    let bundled = Path::new(DATA).join("../../layouts/pedar-pressuRe.csv");
    let text = std::fs::read_to_string(&bundled).unwrap();
    let (layout_a, layout_b) = (base.join("layout-a.csv"), base.join("layout-b.csv"));
    std::fs::write(&layout_a, &text).unwrap();
    // The same insole with the places of sensors 1 and 2 swapped.
    let swapped = text
        .replacen("R,1,", "R,#,", 1)
        .replacen("R,2,", "R,1,", 1)
        .replacen("R,#,", "R,2,", 1);
    assert_ne!(swapped, text);
    std::fs::write(&layout_b, swapped).unwrap();
    let out = base.join("study");
    let (a, o) = (asc.to_str().unwrap(), out.to_str().unwrap());
    let with = |layout: &Path| {
        let (code, json, stderr) =
            batch_json(&[a, "--out", o, "--layout", layout.to_str().unwrap()]);
        assert_eq!(code, Some(0), "{stderr}");
        rows(&json)[0].clone()
    };
    let first = with(&layout_a);
    assert_eq!(first["status"], "ok", "{first}");
    let summary = read_json(
        &out.join(first["output"].as_str().unwrap())
            .join("summary.json"),
    );
    assert_eq!(
        summary["input"]["layout"]["file"],
        layout_a.to_str().unwrap()
    );
    assert_eq!(summary["input"]["layout"]["sha256"], sha256_of(&layout_a));
    assert_eq!(with(&layout_a)["status"], "skipped");
    // Another layout file, or none (the bundled layout), is another input: it runs again.
    let other = with(&layout_b);
    assert_eq!(other["status"], "ok", "{other}");
    let summary = read_json(
        &out.join(other["output"].as_str().unwrap())
            .join("summary.json"),
    );
    assert_eq!(summary["input"]["layout"]["sha256"], sha256_of(&layout_b));
    let (code, json, _) = batch_json(&[a, "--out", o]);
    assert_eq!(
        (code, &rows(&json)[0]["status"]),
        (Some(0), &Value::from("ok"))
    );
    let summary = read_json(
        &out.join(rows(&json)[0]["output"].as_str().unwrap())
            .join("summary.json"),
    );
    assert_eq!(summary["input"]["layout"], Value::Null);
}

#[test]
fn a_renamed_recording_or_a_moved_study_leaves_one_row_per_recording() {
    let base = temp_dir("moved");
    let project = base.join("project");
    let input = project.join("in");
    std::fs::create_dir_all(&input).unwrap();
    for (from, to) in [
        ("emed-test-1-10.lst", "s01.lst"),
        ("tekscan-FrasP01L-11-20.csv", "s02.csv"),
    ] {
        std::fs::copy(Path::new(DATA).join(from), input.join(to)).unwrap();
    }
    // `batch --json ARGS` run in folder `dir`.
    let batch_in = |dir: &Path, args: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_pedomatch"))
            .current_dir(dir)
            .args([&["batch", "--json"], args, &FAST].concat())
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(0), "{stderr}");
        serde_json::from_slice::<Value>(&out.stdout).unwrap()
    };
    let in_project = |args: &[&str]| batch_in(&project, args);
    let table = |project: &Path| read_json(&project.join("study/study.json"))["rows"].clone();
    let paths = |rows: &Value| -> Vec<String> {
        let rows = rows.as_array().unwrap();
        rows.iter()
            .map(|r| r["path"].as_str().unwrap().to_string())
            .collect()
    };
    in_project(&["in", "--out", "study"]);
    assert_eq!(table(&project).as_array().unwrap().len(), 2);
    // A run interrupted before it wrote the study table: the folders it finished are skipped
    // with the wall time their summaries timed, not the time it took to find them complete.
    std::fs::remove_file(project.join("study/study.json")).unwrap();
    let again = in_project(&["in", "--out", "study"]);
    for row in rows(&again) {
        assert_eq!(row["status"], "skipped");
        let summary = read_json(
            &project
                .join("study")
                .join(row["output"].as_str().unwrap())
                .join("summary.json"),
        );
        let timed: f64 = summary["timings_s"]
            .as_object()
            .unwrap()
            .values()
            .map(|v| v.as_f64().unwrap())
            .sum();
        assert_eq!(row["wall_time_s"].as_f64().unwrap(), timed, "{row}");
    }

    // A renamed recording: its old row goes, its new one is this run's.
    std::fs::rename(input.join("s01.lst"), input.join("s01-left.lst")).unwrap();
    in_project(&["in/s01-left.lst", "--out", "study"]);
    let rows = table(&project);
    assert_eq!(paths(&rows), ["in/s01-left.lst", "in/s02.csv"]);
    assert_eq!(
        rows[1]["message"],
        "kept from an earlier run (not among this run's inputs)"
    );

    // A deleted recording's row is kept (its folder holds its results) and says so.
    std::fs::remove_file(input.join("s02.csv")).unwrap();
    in_project(&["in/s01-left.lst", "--out", "study"]);
    let rows = table(&project);
    assert_eq!(
        rows[1]["message"],
        "kept from an earlier run (its input is no longer at this path)"
    );
    std::fs::copy(
        Path::new(DATA).join("tekscan-FrasP01L-11-20.csv"),
        input.join("s02.csv"),
    )
    .unwrap();

    // The study moved with its recordings: every recording runs again (its folder name is a
    // hash of its absolute path), each once in the table.
    let moved = base.join("moved");
    std::fs::rename(&project, &moved).unwrap();
    batch_in(&moved, &["in", "--out", "study"]);
    let rows = table(&moved);
    assert_eq!(paths(&rows), ["in/s01-left.lst", "in/s02.csv"], "{rows}");
    std::fs::remove_dir_all(&base).unwrap();
}

/// A zip archive whose members are `names` (stored, as Office files hold their XML).
fn zip_with(names: &[&str]) -> Vec<u8> {
    let mut local = Vec::new();
    let mut central = Vec::new();
    for name in names {
        let data = b"<x/>";
        let offset = local.len() as u32;
        let header = |sig: &[u8], central: bool| {
            let mut h = sig.to_vec();
            if central {
                h.extend_from_slice(&20u16.to_le_bytes());
            }
            h.extend_from_slice(&[20, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]);
            h.extend_from_slice(&(data.len() as u32).to_le_bytes());
            h.extend_from_slice(&(data.len() as u32).to_le_bytes());
            h.extend_from_slice(&(name.len() as u16).to_le_bytes());
            h.extend_from_slice(&0u16.to_le_bytes());
            if central {
                h.extend_from_slice(&[0; 8]);
                h.extend_from_slice(&[0; 4]);
                h.extend_from_slice(&offset.to_le_bytes());
            }
            h.extend_from_slice(name.as_bytes());
            h
        };
        local.extend(header(b"PK\x03\x04", false));
        local.extend_from_slice(data);
        central.extend(header(b"PK\x01\x02", true));
    }
    let (at, size) = (local.len() as u32, central.len() as u32);
    local.extend(central);
    local.extend_from_slice(b"PK\x05\x06\0\0\0\0");
    local.extend_from_slice(&(names.len() as u16).to_le_bytes());
    local.extend_from_slice(&(names.len() as u16).to_le_bytes());
    local.extend_from_slice(&size.to_le_bytes());
    local.extend_from_slice(&at.to_le_bytes());
    local.extend_from_slice(&[0, 0]);
    local
}

#[test]
fn office_files_and_readmes_describing_the_formats_are_passed_over() {
    let base = temp_dir("office");
    let input = base.join("subject");
    std::fs::create_dir_all(&input).unwrap();
    let asf = std::fs::read(Path::new(DATA).join("FrasP01L.asf")).unwrap();
    std::fs::write(input.join("walk.asf"), &asf).unwrap();
    std::fs::write(input.join("cut.asf"), &asf[..asf.len() / 50]).unwrap();
    std::fs::write(
        input.join("subjects.xlsx"),
        zip_with(&["[Content_Types].xml", "xl/workbook.xml"]),
    )
    .unwrap();
    std::fs::write(
        input.join("protocol.docx"),
        zip_with(&["[Content_Types].xml", "word/document.xml"]),
    )
    .unwrap();
    std::fs::write(
        input.join("README.md"),
        "# Data\n\nExported with F-Scan: File > Save ASCII (ASCII_DATA format).\n\
         A header of `ROWS`, `COLS` up to\nASCII_DATA @@\nthen blocks\nFrame 1\nof numbers.\n\
         The emed pages: a `Page k` line and `Matrix: 64x95`.\nPage 1\n",
    )
    .unwrap();
    let found = pedo_study::find_recordings(&[input.to_str().unwrap()]).unwrap();
    let names: Vec<_> = found.iter().map(|p| p.file_name().unwrap()).collect();
    assert_eq!(names, ["cut.asf", "walk.asf"]);
    let o = base.join("out");
    let (code, report, stderr) = batch_json(&[
        input.to_str().unwrap(),
        "--out",
        o.to_str().unwrap(),
        "--frames",
        "0..20",
    ]);
    assert_eq!(code, Some(1), "{stderr}");
    let rows = rows(&report);
    assert_eq!(rows.len(), 2, "{rows:?}");
    assert_eq!(row(&rows, "walk.asf")["status"], "ok");
    assert_eq!(row(&rows, "cut.asf")["status"], "error");
    for other in ["README.md", "docx", "xlsx"] {
        assert!(!stderr.contains(other), "{other}: {stderr}");
    }
    // A zip of .npy members is still an .npz, found whatever its name.
    let npz = std::fs::read(Path::new(DATA).join("numpy-MUN104L-stored.npz")).unwrap();
    std::fs::write(input.join("plate.data"), npz).unwrap();
    let found = pedo_study::find_recordings(&[input.to_str().unwrap()]).unwrap();
    assert!(found.iter().any(|p| p.ends_with("plate.data")), "{found:?}");
    std::fs::remove_dir_all(&base).unwrap();
}

#[test]
fn the_test_data_folder_with_its_readme_is_only_recordings() {
    // Its README.md describes the .asf and .lst formats (ASCII_DATA, Matrix:, Page).
    let found = pedo_study::find_recordings(&[DATA]).unwrap();
    let names: Vec<_> = found
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert!(
        !names
            .iter()
            .any(|n| n.ends_with(".md") || n.ends_with(".py")),
        "{names:?}"
    );
    assert!(names.contains(&"FrasP01L.asf".to_string()), "{names:?}");
    assert!(
        names.contains(&"numpy-MUN104L-stored.npz".to_string()),
        "{names:?}"
    );
    assert!(
        names.contains(&"emed-test-1-10.lst".to_string()),
        "{names:?}"
    );
}

#[cfg(unix)]
#[test]
fn symlinked_recordings_and_folders_are_followed_and_a_broken_link_is_an_error_row() {
    use std::os::unix::fs::symlink;
    let base = temp_dir("symlinks");
    let store = base.join("store");
    let study = base.join("study");
    std::fs::create_dir_all(&store).unwrap();
    std::fs::create_dir_all(study.join("s01")).unwrap();
    std::fs::copy(
        Path::new(DATA).join("emed-test-1-10.lst"),
        store.join("raw.lst"),
    )
    .unwrap();
    symlink(store.join("raw.lst"), study.join("s01/walk.lst")).unwrap();
    symlink(&store, study.join("s02")).unwrap();
    // A link back up is a loop: passed over, not searched forever.
    symlink(&study, study.join("s01/up")).unwrap();
    symlink(base.join("gone/raw.asf"), study.join("s01/dangling.asf")).unwrap();
    symlink(base.join("gone/notes.txt"), study.join("s01/dangling.txt")).unwrap();
    let found = pedo_study::find_recordings(&[study.to_str().unwrap()]).unwrap();
    let names: Vec<_> = found
        .iter()
        .map(|p| {
            p.strip_prefix(&study)
                .unwrap()
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    // The same file by two links is found once.
    assert_eq!(names, ["s01/dangling.asf", "s01/walk.lst"]);
    // The symlinked folder alone.
    let found = pedo_study::find_recordings(&[study.join("s02").to_str().unwrap()]).unwrap();
    assert_eq!(found, [study.join("s02/raw.lst")]);
    let o = base.join("out");
    let (code, report, stderr) =
        batch_json(&[study.to_str().unwrap(), "--out", o.to_str().unwrap()]);
    assert_eq!(code, Some(1), "{stderr}");
    let rows = rows(&report);
    assert_eq!(rows.len(), 2, "{rows:?}");
    assert_eq!(row(&rows, "walk.lst")["status"], "ok");
    let dangling = row(&rows, "dangling.asf");
    assert_eq!(dangling["status"], "error");
    let message = dangling["message"].as_str().unwrap();
    assert!(message.contains("broken symbolic link"), "{message}");
    assert!(message.contains("gone/raw.asf"), "{message}");
    std::fs::remove_dir_all(&base).unwrap();
}

/// `text` as UTF-16 with its byte-order mark, little- or big-endian.
fn utf16(text: &[u8], little: bool) -> Vec<u8> {
    let text = String::from_utf8_lossy(text);
    let mut out = if little {
        vec![0xff, 0xfe]
    } else {
        vec![0xfe, 0xff]
    };
    for unit in text.encode_utf16() {
        out.extend(if little {
            unit.to_le_bytes()
        } else {
            unit.to_be_bytes()
        });
    }
    out
}

#[test]
fn utf16_text_reads_as_its_utf8_form() {
    let base = temp_dir("utf16");
    let (asfs, grids) = (base.join("asf"), base.join("grid"));
    std::fs::create_dir_all(&asfs).unwrap();
    std::fs::create_dir_all(&grids).unwrap();
    let asf = std::fs::read(Path::new(DATA).join("FrasP01L.asf")).unwrap();
    let grid = std::fs::read(Path::new(DATA).join("MUN104L.csv")).unwrap();
    std::fs::write(asfs.join("a_walk.asf"), &asf).unwrap();
    std::fs::write(asfs.join("b_walk16.asf"), utf16(&asf, true)).unwrap();
    std::fs::write(grids.join("c_grid.csv"), &grid).unwrap();
    std::fs::write(grids.join("d_grid16le.csv"), utf16(&grid, true)).unwrap();
    std::fs::write(grids.join("e_grid16be.txt"), utf16(&grid, false)).unwrap();
    let o = base.join("out");
    let (code, report, stderr) = batch_json(&[
        asfs.to_str().unwrap(),
        "--out",
        o.to_str().unwrap(),
        "--frames",
        "0..20",
    ]);
    assert_eq!(code, Some(0), "{stderr}");
    let mut rows = rows(&report);
    let (code, report, stderr) =
        batch_json(&[grids.to_str().unwrap(), "--out", o.to_str().unwrap()]);
    assert_eq!(code, Some(0), "{stderr}");
    rows.extend(self::rows(&report));
    assert_eq!(rows.len(), 5, "{rows:?}");
    let frames = |name: &str| {
        let r = row(&rows, name);
        assert_eq!(r["status"], "ok", "{r}");
        std::fs::read(o.join(r["output"].as_str().unwrap()).join("frames.csv")).unwrap()
    };
    assert_eq!(frames("b_walk16.asf"), frames("a_walk.asf"));
    assert_eq!(frames("d_grid16le.csv"), frames("c_grid.csv"));
    assert_eq!(frames("e_grid16be.txt"), frames("c_grid.csv"));
    assert_eq!(
        row(&rows, "b_walk16.asf")["format"],
        row(&rows, "a_walk.asf")["format"]
    );
    // Named on its own (`inspect`): read as well.
    let out = pedomatch(&["inspect", asfs.join("b_walk16.asf").to_str().unwrap()]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    std::fs::remove_dir_all(&base).unwrap();
}
