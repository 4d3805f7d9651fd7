//! A study run with a region rule writes `study_regions.csv`: every region measure of every
//! trial, in long form, the rows of each trial's `regions.csv` after its path.

use pedo_io::regions::RegionRule;
use pedo_output::RunOutputs;
use pedo_study::{run_study, StudyOptions, STUDY_REGIONS};
use std::path::PathBuf;

#[path = "../../pedo-io/tests/common/files.rs"]
mod files;
use files::temp_dir;

#[test]
fn a_study_gathers_every_trial_s_regions() {
    let data = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../pedo-io/tests/data");
    let paths = vec![
        data.join("synthetic-walk.lst"),
        data.join("footscan-FrasP01L-11-20.txt"),
    ];
    let out = temp_dir("study-regions");
    let mut opts = StudyOptions {
        inputs: Vec::new(),
        params: Default::default(),
        read: Default::default(),
        out: Some(out.clone()),
        jobs: 1,
        force: false,
        cancel: None,
        outputs: RunOutputs {
            regions: Some(RegionRule::Coarse),
            ..Default::default()
        },
    };
    let rows = run_study(&paths, &opts, &|_| {}).unwrap().rows;
    assert!(rows.iter().all(|r| r.message.is_empty()), "{rows:?}");
    let table = std::fs::read_to_string(out.join(STUDY_REGIONS)).unwrap();
    let mut lines = table.lines();
    assert_eq!(lines.next(), Some("trial,region,measure,value,unit"));
    let body: Vec<&str> = lines.collect();
    assert_eq!(body.len(), 2 * 4 * 7, "{table}");
    for row in &rows {
        let folder = out.join(row.output.as_ref().unwrap());
        let own = std::fs::read_to_string(folder.join("regions.csv")).unwrap();
        let mine: Vec<&&str> = body.iter().filter(|l| l.starts_with(&row.path)).collect();
        // The fixed regions' rows (the moving ones stay in the trial's regions.csv).
        let fixed: Vec<&str> = own.lines().filter(|l| l.ends_with(",fixed")).collect();
        assert_eq!(mine.len(), fixed.len());
        for (line, theirs) in mine.iter().zip(fixed) {
            let a: Vec<&str> = line.split(',').collect();
            let b: Vec<&str> = theirs.split(',').collect();
            assert_eq!((a[1], a[2], a[4]), (b[0], b[1], b[3]));
            let (x, y): (f64, f64) = (a[3].parse().unwrap(), b[2].parse().unwrap());
            assert!(
                (x - y).abs() <= 5e-7 * y.abs().max(1.0),
                "{line} vs {theirs}"
            );
        }
    }
    // A run again finds every folder complete (its regions.json among its files).
    let again = run_study(&paths, &opts, &|_| {}).unwrap().rows;
    assert!(again
        .iter()
        .all(|r| r.status == pedo_study::RowStatus::Skipped));
    assert!(out.join(STUDY_REGIONS).is_file());
    // Without a region rule, the study forgets the regions' table.
    opts.outputs.regions = None;
    opts.force = true;
    run_study(&paths, &opts, &|_| {}).unwrap();
    assert!(!out.join(STUDY_REGIONS).exists());
    let _ = std::fs::remove_dir_all(&out);
}
