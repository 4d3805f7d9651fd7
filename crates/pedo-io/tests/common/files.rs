//! The sample files and scratch folders of the integration tests, which include this one file
//! (with `#[path]`; not every test uses both helpers).

use std::path::PathBuf;

/// A sample file of `crates/pedo-io/tests/data` (this file is included by the tests of every
/// pipeline crate, each a sibling folder of `pedo-io`).
#[allow(dead_code)]
pub fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../pedo-io/tests/data")
        .join(name)
}

/// An empty scratch folder `name` of this test process (emptied if a run before left it).
#[allow(dead_code)]
pub fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!(
        "{}-test-{name}-{}",
        env!("CARGO_PKG_NAME"),
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}
