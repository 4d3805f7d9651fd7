//! `pedomatch`: a thin command-line shell over the pedomatch library crates.

use clap::error::ErrorKind;
use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// `print!` that survives a reader which has gone: see [`output::write_stdout`].
macro_rules! out {
    ($($arg:tt)*) => { $crate::output::write_stdout(format_args!($($arg)*)) };
}

/// `println!` that survives a reader which has gone: see [`output::write_stdout`].
macro_rules! outln {
    ($($arg:tt)*) => { $crate::output::write_stdout(format_args!("{}\n", format_args!($($arg)*))) };
}

mod cmd_assign;
mod cmd_batch;
mod cmd_inspect;
mod cmd_match;
mod cmd_register;
mod cmd_run;
mod interrupt;
mod option_args;
mod output;

const EXIT_CODES: &str = "Exit status: 0 success; 1 runtime failure (unreadable or malformed \
input, failed run, unwritable output; for batch: any recording failed, the others' outputs and \
the study table are still written); 2 usage error (unknown flag, missing argument, bad option \
value); 130 interrupted (Ctrl-C or SIGTERM: the output folder is left as it was). With --json, a \
subcommand prints one JSON object on stdout.";

#[derive(Parser)]
#[command(
    name = "pedomatch",
    version,
    about = "Modal matching of objects in dynamic pedobarography",
    after_help = EXIT_CODES
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Match the objects of a whole recording frame by frame; write tables, figures and tracks.
    #[command(after_help = EXIT_CODES)]
    Run(cmd_run::RunArgs),
    /// `run` on many recordings at once (files, folders, glob patterns), one folder each, and a
    /// study table with a row per recording.
    #[command(after_help = EXIT_CODES)]
    Batch(cmd_batch::BatchArgs),
    /// `run` on the bundled F-Scan recording, writing ./pedomatch-out/.
    #[command(after_help = EXIT_CODES)]
    Demo(cmd_run::DemoArgs),
    /// Match two objects given as point files or pressure images.
    #[command(after_help = EXIT_CODES)]
    Match(cmd_match::MatchArgs),
    /// Register the footprints of many recordings onto one template (a trial, a study
    /// template or the bundled MUN104 image) for pixel-wise statistics.
    #[command(after_help = EXIT_CODES)]
    Register(cmd_register::RegisterArgs),
    /// Solve a linear assignment problem read from a CSV cost matrix.
    #[command(after_help = EXIT_CODES)]
    Assign(cmd_assign::AssignArgs),
    /// Describe a recording: format, size, pitch, frame rate, units and per-frame measures.
    #[command(after_help = EXIT_CODES)]
    Inspect(cmd_inspect::InspectArgs),
}

/// Why a subcommand failed; decides the exit status.
#[derive(Debug)]
pub enum CliError {
    /// A bad option value found after parsing (exit 2, like clap's own usage errors).
    Usage(String),
    /// Anything else: input, computation, output (exit 1).
    Runtime(String),
}

impl From<String> for CliError {
    fn from(msg: String) -> Self {
        CliError::Runtime(msg)
    }
}

impl From<pedo_io::IoError> for CliError {
    fn from(e: pedo_io::IoError) -> Self {
        use modal_core::ModalError;
        use pedo_io::IoError;
        match e {
            IoError::Option(_) | IoError::Shape(ModalError::Option(_)) => {
                CliError::Usage(e.to_string())
            }
            other => CliError::Runtime(other.to_string()),
        }
    }
}

impl From<modal_core::OptionError> for CliError {
    fn from(e: modal_core::OptionError) -> Self {
        CliError::Usage(e.to_string())
    }
}

impl From<modal_core::ModalError> for CliError {
    fn from(e: modal_core::ModalError) -> Self {
        pedo_io::IoError::from(e).into()
    }
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        // --help, --version and a bare `pedomatch` print as clap prints them.
        Err(e)
            if !e.use_stderr()
                || e.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand =>
        {
            e.exit()
        }
        Err(e) => {
            output::error_line(&format!(
                "pedomatch: error: {}",
                one_line(&e.render().to_string())
            ));
            return ExitCode::from(2);
        }
    };
    interrupt::install_interrupt_handler();
    let result = match cli.command {
        Command::Run(args) => cmd_run::run(args),
        Command::Batch(args) => cmd_batch::run(args),
        Command::Demo(args) => cmd_run::demo(args),
        Command::Match(args) => cmd_match::run(args),
        Command::Register(args) => cmd_register::run(args),
        Command::Assign(args) => cmd_assign::run(args),
        Command::Inspect(args) => cmd_inspect::run(args),
    };
    if interrupt::interrupted() {
        // The Ctrl-C handler is removing the staging folders and exits with 130 when done.
        interrupt::wait_for_interrupt_exit();
    }
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(CliError::Usage(msg)) => {
            output::error_line(&format!("pedomatch: error: {msg}"));
            ExitCode::from(2)
        }
        Err(CliError::Runtime(msg)) => {
            output::error_line(&format!("pedomatch: error: {msg}"));
            ExitCode::FAILURE
        }
    }
}

/// clap's usage error (a message, indented details, tips, a usage line, a pointer to --help, on
/// several lines) as the one line every other error of `pedomatch` is: the message and its
/// details, then the tips, then the usage.
fn one_line(rendered: &str) -> String {
    let (mut message, mut tips, mut usage) = (Vec::new(), Vec::new(), None);
    for line in rendered.lines().map(str::trim).filter(|l| !l.is_empty()) {
        if let Some(u) = line.strip_prefix("Usage: ") {
            usage = Some(u);
        } else if line.starts_with("tip: ") {
            tips.push(line);
        } else if !line.starts_with("For more information") {
            message.push(line.strip_prefix("error: ").unwrap_or(line));
        }
    }
    let mut text = message.join(" ");
    for tip in tips {
        text += "; ";
        text += tip;
    }
    match usage {
        Some(u) => text + &format!(" (usage: {u}; see --help)"),
        None => text + " (see --help)",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_usage_error_is_one_line_with_its_details_tips_and_usage() {
        let line = |args: &[&str]| {
            let e = Cli::try_parse_from(args).err().expect("a usage error");
            assert!(e.use_stderr());
            one_line(&e.render().to_string())
        };
        assert_eq!(
            line(&["pedomatch", "run", "x.asf", "--search", "foo"]),
            "invalid value 'foo' for '--search <SEARCH>' [possible values: global, local, best] \
             (see --help)"
        );
        assert_eq!(
            line(&["pedomatch", "runn"]),
            "unrecognized subcommand 'runn'; tip: a similar subcommand exists: 'run' \
             (usage: pedomatch <COMMAND>; see --help)"
        );
        let missing = line(&["pedomatch", "run"]);
        assert!(
            missing.starts_with("the following required arguments were not provided: <RECORDING>")
                && missing.ends_with("(usage: pedomatch run <RECORDING>; see --help)")
                && !missing.contains('\n'),
            "{missing}"
        );
    }
}
