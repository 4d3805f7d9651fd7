//! `pedomatch assign`.

use clap::Args;

#[derive(Args)]
pub struct AssignArgs {
    /// CSV file of costs, one row per line.
    pub cost: std::path::PathBuf,
}

pub fn run(_args: AssignArgs) -> Result<(), String> {
    Err("not implemented yet".into())
}
