//! A study cannot lose rows: two recordings never share a folder, even when their folder names
//! would be the same, and a second batch into a study folder in use is refused.

use pedo_study::{lock_study_folder, output_name, run_study, RowStatus, StudyOptions};
use serde_json::Value;
use std::path::{Path, PathBuf};

#[path = "../../pedo-io/tests/common/files.rs"]
mod files;
use files::{data, temp_dir};

fn options(out: &Path) -> StudyOptions {
    StudyOptions {
        out: Some(out.to_path_buf()),
        jobs: 1,
        ..Default::default()
    }
}

fn study_json(out: &Path) -> Value {
    serde_json::from_slice(&std::fs::read(out.join("study.json")).unwrap()).unwrap()
}

/// `(path, output)` of every row of the study table (`study.csv`), read back from the file.
fn csv_rows(out: &Path) -> Vec<(String, String)> {
    let text = std::fs::read_to_string(out.join("study.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name| header.iter().position(|h| *h == name).unwrap();
    let (p, o) = (col("path"), col("output"));
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (f[p].to_string(), f[o].to_string())
        })
        .collect()
}

/// Two `walk.lst` in different folders.
fn two_walks(base: &Path) -> (PathBuf, PathBuf) {
    let (a, b) = (base.join("a/walk.lst"), base.join("b/walk.lst"));
    for p in [&a, &b] {
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::copy(data("emed-test-1-10.lst"), p).unwrap();
    }
    (a, b)
}

#[test]
fn a_folder_name_taken_by_another_recording_is_not_reused_and_both_rows_stay() {
    let base = temp_dir("collide");
    let (a, b) = two_walks(&base);
    let out = base.join("study");
    // b's folder, renamed to the name a would get: an earlier row whose short name collides.
    run_study(std::slice::from_ref(&b), &options(&out), &|_| {}).unwrap();
    let (b_name, a_name) = (output_name(&b), output_name(&a));
    assert_ne!(a_name, b_name);
    std::fs::rename(out.join(&b_name), out.join(&a_name)).unwrap();
    let json = std::fs::read_to_string(out.join("study.json")).unwrap();
    std::fs::write(out.join("study.json"), json.replace(&b_name, &a_name)).unwrap();
    let b_summary = std::fs::read(out.join(&a_name).join("summary.json")).unwrap();

    let run = run_study(std::slice::from_ref(&a), &options(&out), &|_| {}).unwrap();
    let a_folder = run.rows[0].output.clone().unwrap();
    assert_eq!(run.rows[0].status, RowStatus::Ok, "{}", run.rows[0].message);
    assert_ne!(a_folder, a_name, "a must not take b's folder");
    assert!(a_folder.starts_with("walk.lst-") && a_folder.len() > a_name.len());
    // b's folder untouched, and its row kept.
    assert_eq!(
        std::fs::read(out.join(&a_name).join("summary.json")).unwrap(),
        b_summary
    );
    let rows = csv_rows(&out);
    assert_eq!(rows.len(), 2, "{rows:?}");
    assert!(rows.contains(&(a.display().to_string(), a_folder.clone())));
    assert!(rows
        .iter()
        .any(|(p, o)| p == &b.display().to_string() && o == &a_name));
    let summary: Value =
        serde_json::from_slice(&std::fs::read(out.join(&a_folder).join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(summary["input"]["file"], a.display().to_string());

    // Resumed: a finds its longer name again (skipped, complete), b is still kept.
    let again = run_study(std::slice::from_ref(&a), &options(&out), &|_| {}).unwrap();
    assert_eq!(again.rows[0].output.as_deref(), Some(a_folder.as_str()));
    assert_eq!(again.rows[0].status, RowStatus::Skipped);
    assert_eq!(csv_rows(&out).len(), 2);
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn a_study_without_collisions_keeps_todays_folder_names() {
    let base = temp_dir("names");
    let (a, b) = two_walks(&base);
    let out = base.join("study");
    let run = run_study(&[a.clone(), b.clone()], &options(&out), &|_| {}).unwrap();
    let outputs: Vec<_> = run.rows.iter().map(|r| r.output.clone().unwrap()).collect();
    assert_eq!(outputs, [output_name(&a), output_name(&b)]);
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn a_second_batch_into_a_study_in_use_is_refused_and_the_first_keeps_its_rows() {
    let base = temp_dir("lock");
    let (a, _) = two_walks(&base);
    let out = base.join("study");
    let held = lock_study_folder(&out).unwrap();
    let e = run_study(std::slice::from_ref(&a), &options(&out), &|_| {})
        .unwrap_err()
        .to_string();
    assert!(e.contains("in use by another pedomatch batch"), "{e}");
    assert!(e.contains(&out.display().to_string()), "{e}");
    assert!(
        e.contains(&format!("process {}", std::process::id())),
        "{e}"
    );
    assert!(!e.contains('\n'));
    assert!(!out.join("study.csv").exists());
    drop(held);
    run_study(std::slice::from_ref(&a), &options(&out), &|_| {}).unwrap();
    assert_eq!(csv_rows(&out).len(), 1);
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn two_batches_at_once_into_one_folder_lose_no_row() {
    let base = temp_dir("concurrent");
    let files = [
        "emed-test-1-10.lst",
        "tekscan-FrasP01L-11-20.csv",
        "footscan-FrasP01L-11-20.txt",
    ];
    let paths: Vec<PathBuf> = files
        .iter()
        .enumerate()
        .map(|(i, f)| {
            let p = base.join(format!("r{i}")).join(f);
            std::fs::create_dir_all(p.parent().unwrap()).unwrap();
            std::fs::copy(data(f), &p).unwrap();
            p
        })
        .collect();
    let out = &base.join("study");
    for round in 0..3 {
        let _ = std::fs::remove_dir_all(out);
        let (first, second) = paths.split_at(1 + round % 2);
        let results: Vec<_> = std::thread::scope(|s| {
            let runs: Vec<_> = [first, second]
                .into_iter()
                .map(|part| s.spawn(move || (part, run_study(part, &options(out), &|_| {}))))
                .collect();
            runs.into_iter().map(|h| h.join().unwrap()).collect()
        });
        let rows = csv_rows(out);
        let mut expected = 0;
        for (part, result) in results {
            match result {
                Ok(_) => {
                    expected += part.len();
                    for p in part {
                        assert!(rows.iter().any(|(r, _)| r == &p.display().to_string()));
                    }
                }
                Err(e) => assert!(e.to_string().contains("in use"), "{e}"),
            }
        }
        assert_eq!(rows.len(), expected, "{rows:?}");
        assert_eq!(study_json(out)["rows"].as_array().unwrap().len(), expected);
    }
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn a_run_killed_between_the_study_files_loses_no_row_on_resume() {
    let base = temp_dir("killed");
    let (a, b) = two_walks(&base);
    let out = base.join("study");
    run_study(std::slice::from_ref(&a), &options(&out), &|_| {}).unwrap();
    let json_a = std::fs::read(out.join("study.json")).unwrap();
    let csv_a = std::fs::read(out.join("study.csv")).unwrap();
    run_study(std::slice::from_ref(&b), &options(&out), &|_| {}).unwrap();
    assert_eq!(csv_rows(&out).len(), 2);
    let b_folder = output_name(&b);
    // Every state a kill between the writes of the second run leaves: b's folder written but
    // neither study file, or one of them only.
    for (json, csv) in [(true, true), (true, false), (false, true)] {
        if json {
            std::fs::write(out.join("study.json"), &json_a).unwrap();
        }
        if csv {
            std::fs::write(out.join("study.csv"), &csv_a).unwrap();
        }
        // A third run on a alone: b's row comes back from its folder.
        let run = run_study(std::slice::from_ref(&a), &options(&out), &|_| {}).unwrap();
        assert_eq!(run.kept.len(), 1, "{:?}", run.kept);
        assert_eq!(run.kept[0].path, b.display().to_string());
        assert_eq!(run.kept[0].output.as_deref(), Some(b_folder.as_str()));
        assert!(run.kept[0].frames.is_some());
        let rows = csv_rows(&out);
        assert_eq!(rows.len(), 2, "{rows:?}");
        assert!(rows.contains(&(b.display().to_string(), b_folder.clone())));
        assert_eq!(study_json(&out)["rows"].as_array().unwrap().len(), 2);
    }
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn what_a_killed_run_was_writing_is_swept_on_the_next_run() {
    let base = temp_dir("sweep");
    let (a, _) = two_walks(&base);
    let out = base.join("study");
    run_study(std::slice::from_ref(&a), &options(&out), &|_| {}).unwrap();
    // No process has this id (beyond Linux's largest).
    let dead = 999_999_999u32;
    let staging = out.join(format!(".walk.lst-0123abcd.pedomatch-tmp-{dead}"));
    std::fs::create_dir_all(staging.join("figures")).unwrap();
    std::fs::write(staging.join("pairs.csv"), "x\n").unwrap();
    let table = out.join(format!(".study.csv.tmp-{dead}"));
    std::fs::write(&table, "x\n").unwrap();
    // One of a process that runs (this one) stays.
    let ours = out.join(format!(".other.pedomatch-tmp-{}", std::process::id()));
    std::fs::create_dir_all(&ours).unwrap();
    run_study(std::slice::from_ref(&a), &options(&out), &|_| {}).unwrap();
    assert!(!staging.exists() && !table.exists());
    assert!(ours.exists());
    assert_eq!(csv_rows(&out).len(), 1);
    let _ = std::fs::remove_dir_all(&base);
}
