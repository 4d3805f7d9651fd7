//! `pedomatch`: a thin command-line shell over the pedomatch library crates.

use clap::{Parser, Subcommand};
use std::process::ExitCode;

mod cmd_assign;
mod output;

#[derive(Parser)]
#[command(name = "pedomatch", version, about = "Modal matching of objects in dynamic pedobarography")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Solve a linear assignment problem read from a CSV cost matrix.
    Assign(cmd_assign::AssignArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Assign(args) => cmd_assign::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            eprintln!("pedomatch: error: {msg}");
            ExitCode::FAILURE
        }
    }
}
