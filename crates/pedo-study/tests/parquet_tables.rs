//! `tables = parquet`: a study written as Parquet holds, file for file, the tables of the same
//! study written as CSV, value for value and typed (integers INT64, numbers DOUBLE, text UTF-8,
//! empty fields null); resuming knows which files a Parquet run writes.

#[path = "../../pedo-output/tests/common/parquet.rs"]
mod common;

use parquet::file::reader::{FileReader, SerializedFileReader};
use parquet::record::Field;
use pedo_output::TableFormat;
use pedo_output::{RunOutputs, RUN_TABLES};
use pedo_study::{run_study, RowStatus, StudyOptions};
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
            ..Default::default()
        },
        ..Default::default()
    }
}

/// CSV fields of one line (RFC 4180 quotes).
fn csv_fields(line: &str) -> Vec<String> {
    let (mut fields, mut field, mut quoted) = (Vec::new(), String::new(), false);
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                field.push('"');
                chars.next();
            }
            ('"', _) => quoted = !quoted,
            (',', false) => fields.push(std::mem::take(&mut field)),
            _ => field.push(c),
        }
    }
    fields.push(field);
    fields
}

fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = csv_fields(lines.next().unwrap());
    (header, lines.map(csv_fields).collect())
}

fn read_parquet(path: &Path) -> (Vec<String>, Vec<Vec<Field>>) {
    let (header, rows, _) = common::read_back(std::fs::File::open(path).unwrap());
    (header, rows)
}

/// Whether a Parquet value is the CSV field, type included: integers are written without a
/// decimal point, numbers with one (or as NaN/inf), text as it is, a null as an empty field.
fn same(field: &Field, csv: &str) -> bool {
    match field {
        Field::Null => csv.is_empty(),
        Field::Long(v) => csv == v.to_string(),
        Field::Double(v) if v.is_nan() => csv == "NaN",
        Field::Double(v) => {
            (csv.contains('.') || csv.contains("inf")) && csv.parse::<f64>().ok() == Some(*v)
        }
        Field::Str(s) => csv == s,
        _ => false,
    }
}

fn assert_same_table(csv: &Path, parquet: &Path) -> usize {
    let (csv_header, csv_rows) = read_csv(csv);
    let (pq_header, pq_rows) = read_parquet(parquet);
    assert_eq!(pq_header, csv_header, "{}", parquet.display());
    assert_eq!(pq_rows.len(), csv_rows.len(), "{}", parquet.display());
    for (k, (p, c)) in pq_rows.iter().zip(&csv_rows).enumerate() {
        assert_eq!(p.len(), c.len());
        for ((f, s), name) in p.iter().zip(c).zip(&csv_header) {
            assert!(
                same(f, s),
                "{} row {k} column {name}: parquet {f:?}, csv {s:?}",
                parquet.display()
            );
        }
    }
    csv_rows.len()
}

#[test]
fn a_parquet_study_holds_the_csv_tables_value_for_value_and_resumes() {
    let base = temp_dir("study");
    let paths = vec![
        data("tekscan-FrasP01L-11-20.csv"),
        data("emed-test-1-10.lst"),
        data("footscan-FrasP01L-11-20.txt"),
    ];
    let (csv_out, pq_out) = (base.join("csv"), base.join("parquet"));
    let csv_rows = run_study(&paths, &options(&csv_out, TableFormat::Csv), &|_| {})
        .unwrap()
        .rows;
    let pq_rows = run_study(&paths, &options(&pq_out, TableFormat::Parquet), &|_| {})
        .unwrap()
        .rows;
    assert!(
        pq_rows.iter().all(|r| r.status == RowStatus::Ok),
        "{pq_rows:?}"
    );
    let mut rows_compared = 0;
    for (c, p) in csv_rows.iter().zip(&pq_rows) {
        assert_eq!((c.pairs, c.tracks), (p.pairs, p.tracks));
        let (cdir, pdir) = (
            csv_out.join(c.output.as_ref().unwrap()),
            pq_out.join(p.output.as_ref().unwrap()),
        );
        for table in RUN_TABLES {
            assert!(!pdir.join(format!("{table}.csv")).exists());
            assert!(!cdir.join(format!("{table}.parquet")).exists());
            rows_compared += assert_same_table(
                &cdir.join(format!("{table}.csv")),
                &pdir.join(format!("{table}.parquet")),
            );
        }
        assert!(pdir.join("pairs.json").is_file() && pdir.join("summary.json").is_file());
    }
    assert!(rows_compared > 1000, "{rows_compared} rows compared");

    // The matches' types, read from the file's schema.
    let folder = pq_out.join(pq_rows[0].output.as_ref().unwrap());
    let reader =
        SerializedFileReader::new(std::fs::File::open(folder.join("matches.parquet")).unwrap())
            .unwrap();
    let schema = reader.metadata().file_metadata().schema_descr_ptr();
    let types: Vec<String> = schema
        .columns()
        .iter()
        .map(|c| format!("{}:{:?}", c.name(), c.physical_type()))
        .collect();
    assert_eq!(
        types[..8],
        [
            "id_a:INT64",
            "id_b:INT64",
            "node_a:INT64",
            "node_b:INT64",
            "cost:DOUBLE",
            "excess:INT64",
            "trackable:INT64",
            "distance:DOUBLE"
        ]
    );

    // The study table: study.parquet instead of study.csv, the same rows but for the wall time.
    assert!(!pq_out.join("study.csv").exists() && pq_out.join("study.parquet").is_file());
    let (header, study) = read_parquet(&pq_out.join("study.parquet"));
    let (csv_header, csv_study) = read_csv(&csv_out.join("study.csv"));
    assert_eq!(header, csv_header);
    let wall = header.iter().position(|h| h == "wall_time_s").unwrap();
    let message = header.iter().position(|h| h == "message").unwrap();
    for (p, c) in study.iter().zip(&csv_study) {
        for (k, (f, s)) in p.iter().zip(c).enumerate() {
            if k == wall {
                assert!(matches!(f, Field::Double(_)));
            } else if k == message && s.is_empty() {
                // An empty message stays an empty string (as in study.json).
                assert_eq!(f, &Field::Str(String::new()));
            } else {
                assert!(same(f, s), "study column {}: {f:?} vs {s:?}", header[k]);
            }
        }
    }

    // Resuming: the Parquet folders are complete for a Parquet run, not for a CSV one.
    let again = run_study(&paths, &options(&pq_out, TableFormat::Parquet), &|_| {})
        .unwrap()
        .rows;
    assert!(
        again.iter().all(|r| r.status == RowStatus::Skipped),
        "{again:?}"
    );
    let as_csv = run_study(&paths, &options(&pq_out, TableFormat::Csv), &|_| {})
        .unwrap()
        .rows;
    assert!(
        as_csv.iter().all(|r| r.status == RowStatus::Ok),
        "{as_csv:?}"
    );
    assert!(pq_out.join("study.csv").is_file() && !pq_out.join("study.parquet").exists());
    std::fs::remove_dir_all(&base).unwrap();
}

/// Each column's type in `path`'s schema, by name.
fn column_types(path: &Path) -> std::collections::BTreeMap<String, String> {
    let reader = SerializedFileReader::new(std::fs::File::open(path).unwrap()).unwrap();
    let schema = reader.metadata().file_metadata().schema_descr_ptr();
    schema
        .columns()
        .iter()
        .map(|c| (c.name().to_string(), format!("{:?}", c.physical_type())))
        .collect()
}

/// A one-frame recording writes tables with no pairs, matches or tracks; their columns keep the
/// types of a full recording's (Dask takes a study's types from its first file).
#[test]
fn the_empty_tables_of_a_one_frame_recording_have_the_types_of_full_ones() {
    let out = temp_dir("empty");
    let paths = vec![data("tekscan-FrasP01L-11-20.csv"), data("MUN104L.csv")];
    let rows = run_study(&paths, &options(&out, TableFormat::Parquet), &|_| {})
        .unwrap()
        .rows;
    assert_eq!(rows[1].pairs, Some(0), "{rows:?}");
    let folder = |k: usize| out.join(rows[k].output.as_ref().unwrap());
    for table in RUN_TABLES {
        let file = format!("{table}.parquet");
        let (full, empty) = (
            column_types(&folder(0).join(&file)),
            column_types(&folder(1).join(&file)),
        );
        for (name, kind) in &empty {
            if let Some(expected) = full.get(name) {
                assert_eq!(kind, expected, "{file} column {name}");
            }
        }
    }
    std::fs::remove_dir_all(&out).unwrap();
}
