//! `study_curves.csv`: every recording folder's `curves.csv`, row for row, headed by its path
//! and folder, in the study table's order; rebuilt whole from the folders when a study resumes;
//! the same rows as Parquet.

#[path = "../../pedo-output/tests/common/parquet.rs"]
mod common;

use parquet::record::Field;
use pedo_output::{RunOutputs, TableFormat};
use pedo_study::{run_study, RowStatus, StudyOptions, STUDY_CURVES_COLUMNS};
use std::path::Path;

#[path = "../../pedo-io/tests/common/files.rs"]
mod files;
use files::{data, temp_dir};

fn options(out: &Path, tables: TableFormat) -> StudyOptions {
    StudyOptions {
        out: Some(out.to_path_buf()),
        jobs: 2,
        cancel: None,
        outputs: RunOutputs {
            tables,
            figures: pedo_output::FigureKinds::default(),
            report: false,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// Lines of a CSV of numbers and plain text (no quotes in these tables).
fn lines(path: &Path) -> Vec<Vec<String>> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

#[test]
fn the_study_curves_are_every_folders_curves_and_survive_a_resume() {
    let out = temp_dir("study-curves");
    let paths = vec![data("FrasP01L.asf"), data("emed-test-1-10.lst")];
    let rows = run_study(&paths, &options(&out, TableFormat::Csv), &|_| {})
        .unwrap()
        .rows;
    assert!(rows.iter().all(|r| r.status == RowStatus::Ok), "{rows:?}");
    let table = lines(&out.join("study_curves.csv"));
    assert_eq!(table[0], STUDY_CURVES_COLUMNS);
    // Each folder's curves, in the study's order, under its path and folder.
    let mut want = Vec::new();
    for r in &rows {
        let folder = out.join(r.output.as_ref().unwrap());
        let own = lines(&folder.join("curves.csv"));
        let header = &own[0];
        for line in &own[1..] {
            let mut full = vec![String::new(); STUDY_CURVES_COLUMNS.len()];
            full[0] = r.path.clone();
            full[1] = r.output.clone().unwrap();
            for (name, v) in header.iter().zip(line) {
                let k = STUDY_CURVES_COLUMNS.iter().position(|c| c == name).unwrap();
                full[k] = v.clone();
            }
            want.push(full);
        }
    }
    assert_eq!(table[1..], want[..]);
    // The in-shoe walk: six stances of 101 points (the first cut by the recording's start).
    let walk: Vec<_> = table[1..].iter().filter(|l| l[0] == rows[0].path).collect();
    assert_eq!(walk.len(), 6 * 101);
    assert_eq!(walk[0][3], "0", "the first stance is not complete");
    assert!(walk[101..].iter().all(|l| l[3] == "1"));
    // Resumed: both recordings skipped, the table made again from the folders, the same.
    let before = std::fs::read(out.join("study_curves.csv")).unwrap();
    let again = run_study(&paths, &options(&out, TableFormat::Csv), &|_| {})
        .unwrap()
        .rows;
    assert!(again.iter().all(|r| r.status == RowStatus::Skipped));
    assert_eq!(std::fs::read(out.join("study_curves.csv")).unwrap(), before);
    // A staging file of a process that no longer runs is swept; none of ours is left.
    let names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".tmp-"))
        .collect();
    assert!(names.is_empty(), "{names:?}");

    // As Parquet: the same values, typed; the CSV of the earlier run removed.
    let pq = temp_dir("study-curves-parquet");
    run_study(&paths, &options(&pq, TableFormat::Parquet), &|_| {}).unwrap();
    let (header, pq_rows, _) =
        common::read_back(std::fs::File::open(pq.join("study_curves.parquet")).unwrap());
    assert_eq!(header, STUDY_CURVES_COLUMNS);
    assert_eq!(pq_rows.len(), want.len());
    for (got, want) in pq_rows.iter().zip(&want) {
        for (k, (f, w)) in got.iter().zip(want).enumerate() {
            let ok = match f {
                Field::Null => w.is_empty(),
                Field::Long(v) => *w == v.to_string(),
                Field::Double(v) => w.parse::<f64>().ok() == Some(*v),
                Field::Str(s) => k < 2 && (k == 1 || s.ends_with(".asf") || s.ends_with(".lst")),
                _ => false,
            };
            assert!(ok, "column {k}: {f:?} vs {w}");
        }
    }
    std::fs::remove_dir_all(&out).unwrap();
    std::fs::remove_dir_all(&pq).unwrap();
}
