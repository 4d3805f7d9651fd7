//! A [`Cancel`] stops a run at its next progress step with `IoError::Cancelled`, and a study as
//! the command line's Ctrl-C does: the recordings finished keep their folders, the one running
//! and those not started leave none, and no study table is written.

use pedo_io::cancel::Cancel;
use pedo_io::synthetic::SyntheticWalk;
use pedo_io::IoError;
use pedo_output::RunOutputs;
use pedo_study::{run_study, StudyEvent, StudyOptions};
use pedo_track::{run_sequence, RunParams, Stage};
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

#[test]
fn a_run_stops_at_its_next_progress_step() {
    let recording = SyntheticWalk::default().recording().unwrap();
    let mut options = RunParams::default().to_options(&recording).unwrap();
    let cancel = Cancel::new();
    options.cancel = Some(cancel.clone());
    let matched = AtomicUsize::new(0);
    let total = AtomicUsize::new(0);
    let r = run_sequence(&recording, &options, &|stage, _, n| {
        if stage == Stage::Matching {
            matched.fetch_add(1, Ordering::Relaxed);
            total.store(n, Ordering::Relaxed);
            cancel.cancel();
        }
    });
    assert!(matches!(r, Err(IoError::Cancelled)), "{r:?}");
    // The pairs under way finish; no other starts (the matching runs on every core).
    let (matched, total) = (matched.into_inner(), total.into_inner());
    assert!(
        matched <= rayon::current_num_threads() && matched < total,
        "{matched} of {total} pairs matched after the cancellation"
    );
    // The same options without the request run to the end.
    options.cancel = Some(Cancel::new());
    assert!(run_sequence(&recording, &options, &|_, _, _| {}).is_ok());
}

#[test]
fn a_cancelled_study_keeps_finished_folders_and_writes_no_table() {
    let data = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../pedo-io/tests/data");
    let dir = std::env::temp_dir().join(format!("pedo-io-cancel-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let mut paths = Vec::new();
    for name in ["a.txt", "b.txt", "c.txt"] {
        std::fs::copy(data.join("footscan-FrasP01L-11-20.txt"), dir.join(name)).unwrap();
        paths.push(dir.join(name));
    }
    let out = dir.join("study");
    let cancel = Cancel::new();
    let opts = StudyOptions {
        inputs: Vec::new(),
        params: Default::default(),
        read: Default::default(),
        out: Some(out.clone()),
        jobs: 1,
        force: false,
        cancel: Some(cancel.clone()),
        outputs: RunOutputs {
            figures: Default::default(),
            pair_figures: false,
            report: false,
            animation: false,
            tables: Default::default(),
            regions: None,
            masks: None,
        },
    };
    // Cancelled as b makes progress, once a is done.
    let r = run_study(&paths, &opts, &|event| {
        if let StudyEvent::Progress { index: 1, .. } = event {
            cancel.cancel();
        }
    });
    assert!(matches!(r, Err(IoError::Cancelled)), "{r:?}");
    let mut names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !n.starts_with(".pedomatch-"))
        .collect();
    names.sort();
    assert_eq!(names.len(), 1, "{names:?}");
    assert!(names[0].starts_with("a.txt"), "{names:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}
