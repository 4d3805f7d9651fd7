//! End-to-end tests of the `pedomatch` command-line tool, one module per command or concern.
//! One test binary for all of them: each test binary links the whole workspace, so one instead
//! of eight saves the test build minutes of linking on 2 cores.

mod common;
#[path = "../../crates/pedo-io/tests/common/gzip.rs"]
mod gzip_stream;

mod assign;
mod batch;
mod inputs;
mod options;
mod points;
mod register;
mod robust;
mod run;
