//! What the command-line tests share: running the built `pedomatch`, scratch folders, JSON.
//! Every module of the `cli` test binary uses it (`use crate::common;`); not every module uses
//! every helper.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs the built `pedomatch` with `args`.
#[allow(dead_code)]
pub fn pedomatch(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pedomatch"))
        .args(args)
        .output()
        .expect("run pedomatch")
}

/// Runs the built `pedomatch` with `args` and asserts it succeeded (its error line shown if not).
#[allow(dead_code)]
#[track_caller]
pub fn pedomatch_ok(args: &[&str]) -> Output {
    let o = pedomatch(args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    o
}

/// An empty scratch folder `name` of this test process and of the calling module's file (the
/// modules of the one test binary may pick the same name; emptied if a run before left it).
#[allow(dead_code)]
#[track_caller]
pub fn temp_dir(name: &str) -> PathBuf {
    let caller = Path::new(std::panic::Location::caller().file());
    let module = caller.file_stem().and_then(|s| s.to_str()).unwrap_or("cli");
    let dir = std::env::temp_dir().join(format!(
        "pedomatch-test-{}-{module}-{name}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The JSON a successful run printed.
#[allow(dead_code)]
pub fn stdout_json(o: &Output) -> serde_json::Value {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout)
        .unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&o.stdout)))
}

/// A JSON file.
#[allow(dead_code)]
pub fn read_json(path: &Path) -> serde_json::Value {
    serde_json::from_slice(
        &std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())),
    )
    .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Reads a CSV with a header into rows of (column name → field).
#[allow(dead_code)]
pub fn read_csv(path: &Path) -> Vec<std::collections::HashMap<String, String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    lines
        .map(|l| {
            header
                .iter()
                .cloned()
                .zip(l.split(',').map(String::from))
                .collect()
        })
        .collect()
}
