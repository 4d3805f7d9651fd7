//! `pedomatch`: a thin command-line shell over the pedomatch library crates.

use clap::{Parser, Subcommand};
use std::process::ExitCode;

mod cmd_assign;
mod cmd_match;
mod cmd_run;
mod modal_args;
mod outdir;
mod output;

#[derive(Parser)]
#[command(
    name = "pedomatch",
    version,
    about = "Modal matching of objects in dynamic pedobarography"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Match the objects of a whole recording frame by frame; write tables, figures and tracks.
    Run(cmd_run::RunArgs),
    /// `run` on the bundled F-Scan recording, writing ./pedomatch-out/.
    Demo(cmd_run::DemoArgs),
    /// Match two objects given as point files or pressure images.
    Match(cmd_match::MatchArgs),
    /// Solve a linear assignment problem read from a CSV cost matrix.
    Assign(cmd_assign::AssignArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    outdir::install_interrupt_handler();
    let result = match cli.command {
        Command::Run(args) => cmd_run::run(args),
        Command::Demo(args) => cmd_run::demo(args),
        Command::Match(args) => cmd_match::run(args),
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
