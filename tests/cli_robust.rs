//! Runs that survive what goes wrong: bad pairs are skipped, interrupted and killed runs leave a
//! whole output or none.

mod common;
use common::temp_dir;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

fn demo(out: &Path, extra: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_pedomatch"))
        .arg("demo")
        .arg("--out")
        .arg(out)
        .args(extra)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start pedomatch")
}

fn signal(child: &Child, sig: &str) {
    let ok = Command::new("kill")
        .args([sig, &child.id().to_string()])
        .status()
        .expect("kill")
        .success();
    assert!(ok, "kill {sig} failed");
}

/// Every file under `dir`, relative, sorted.
fn listing(dir: &Path) -> Vec<String> {
    fn walk(base: &Path, dir: &Path, out: &mut Vec<String>) {
        for e in std::fs::read_dir(dir).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(base, &p, out);
            } else {
                out.push(p.strip_prefix(base).unwrap().display().to_string());
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out);
    out.sort();
    out
}

fn staging_folders(parent: &Path) -> Vec<String> {
    std::fs::read_dir(parent)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".pedomatch-tmp-"))
        .collect()
}

#[test]
fn a_killed_run_leaves_the_previous_complete_output_or_none() {
    let base = temp_dir("kill");
    let out = base.join("out");
    let reference = {
        let status = demo(&out, &[]).wait().unwrap();
        assert!(status.success());
        listing(&out)
    };
    assert!(reference.iter().any(|f| f == "summary.json"));
    // Kill runs into the same folder at moments spread over reading, matching and writing.
    let full = {
        let t = Instant::now();
        demo(&base.join("timing"), &[]).wait().unwrap();
        t.elapsed()
    };
    for k in 1..=6 {
        let mut child = demo(&out, &[]);
        std::thread::sleep(full.mul_f64(k as f64 / 7.0));
        signal(&child, "-KILL");
        child.wait().unwrap();
        assert_eq!(listing(&out), reference, "after a kill at {k}/7 of a run");
    }
    // The next run sweeps what the killed ones staged.
    assert!(demo(&out, &[]).wait().unwrap().success());
    assert_eq!(staging_folders(&base), Vec::<String>::new());
    assert_eq!(listing(&out), reference);
    std::fs::remove_dir_all(&base).unwrap();
}

#[test]
fn ctrl_c_stops_at_once_with_130_and_leaves_no_staging_folder() {
    let base = temp_dir("sigint");
    let out = base.join("out");
    let full = {
        let t = Instant::now();
        demo(&base.join("timing"), &[]).wait().unwrap();
        t.elapsed()
    };
    for k in 1..=3 {
        let mut child = demo(&out, &[]);
        std::thread::sleep(full.mul_f64(k as f64 / 4.0));
        signal(&child, "-INT");
        let sent = Instant::now();
        let status = loop {
            if let Some(s) = child.try_wait().unwrap() {
                break s;
            }
            assert!(
                sent.elapsed() < Duration::from_secs(10),
                "still running 10 s after SIGINT"
            );
            std::thread::sleep(Duration::from_millis(10));
        };
        if out.exists() {
            // The run finished before the signal arrived: its output is whole.
            assert!(out.join("summary.json").is_file());
        } else {
            assert_eq!(status.code(), Some(130), "exit code after SIGINT");
        }
        assert_eq!(staging_folders(&base), Vec::<String>::new());
    }
    std::fs::remove_dir_all(&base).unwrap();
}

#[test]
fn the_bar_model_runs_the_whole_bundled_walk() {
    // Every outline of the walk is a rigid bar structure: no pair is lost to a mechanism.
    let base = temp_dir("axial");
    let out = base.join("out");
    let status = demo(&out, &["--element", "axial", "--figures", "none"])
        .wait()
        .unwrap();
    assert!(status.success());
    let pairs = std::fs::read_to_string(out.join("pairs.csv")).unwrap();
    let rows: Vec<&str> = pairs.lines().skip(1).collect();
    assert_eq!(rows.len(), 188);
    assert!(rows.iter().all(|r| r.contains(",ok,")), "{pairs}");
    std::fs::remove_dir_all(&base).unwrap();
}

#[test]
fn two_runs_into_one_folder_never_interleave_their_files() {
    let base = temp_dir("concurrent");
    let out = base.join("out");
    // Two different outputs: with figures and without. The folder must end up exactly one of them.
    let with_figures = {
        let o = base.join("with");
        assert!(demo(&o, &[]).wait().unwrap().success());
        listing(&o)
    };
    let without = {
        let o = base.join("without");
        assert!(demo(&o, &["--figures", "none"]).wait().unwrap().success());
        listing(&o)
    };
    assert_ne!(with_figures, without);
    for _ in 0..3 {
        let mut a = demo(&out, &[]);
        let mut b = demo(&out, &["--figures", "none"]);
        assert!(a.wait().unwrap().success() && b.wait().unwrap().success());
        let got = listing(&out);
        assert!(
            got == with_figures || got == without,
            "mixed output: {got:?}"
        );
        assert_eq!(staging_folders(&base), Vec::<String>::new());
    }
    std::fs::remove_dir_all(&base).unwrap();
}

/// A reader that stops early (`pedomatch inspect … | head -1`) closes the pipe before pedomatch
/// writes: each subcommand then ends quietly with success, its outputs whole, instead of
/// panicking with exit code 101.
#[test]
fn a_reader_that_has_gone_ends_the_output_quietly() {
    let data = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/data/FrasP01L.asf");
    let cost = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/cost.csv");
    let out = temp_dir("closed-reader");
    let out_s = out.to_str().unwrap();
    let commands: [&[&str]; 4] = [
        &["inspect", data],
        &["assign", cost, "--json"],
        &[
            "match",
            data,
            data,
            "--frame",
            "40",
            "--frame-b",
            "41",
            "--json",
            "--figures",
            "none",
            "--report",
            "none",
        ],
        &[
            "run",
            data,
            "--frames",
            "40..45",
            "--out",
            out_s,
            "--figures",
            "none",
            "--report",
            "none",
            "--json",
        ],
    ];
    for args in commands {
        let mut child = Command::new(env!("CARGO_BIN_EXE_pedomatch"))
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start pedomatch");
        drop(child.stdout.take()); // the reader is gone before anything is written
        let o = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
        assert_eq!(o.status.code(), Some(0), "{args:?}: {stderr}");
    }
    assert!(out.join("summary.json").is_file() && out.join("tracks.csv").is_file());
    let _ = std::fs::remove_dir_all(&out);
}
