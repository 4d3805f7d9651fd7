//! `pedomatch batch`: a whole study, each recording like `pedomatch run` into a folder of its own,
//! several at once, one row per recording in `study.csv`. The work is [`pedo_study`]'s.

use crate::cmd_run::RunOptionsArgs;
use crate::option_args::{OptionArgs, Selection};
use crate::output;
use crate::CliError;
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use pedo_io::counted;
use pedo_study::{RowStatus, StudyEvent, StudyOptions};
use std::path::PathBuf;
use std::sync::Mutex;
use std::time::Instant;

#[derive(Args)]
pub struct BatchArgs {
    /// Recordings: files, folders (searched recursively for recordings) or glob patterns
    /// (quoted, e.g. 'data/**/*.asf').
    #[arg(required = true, value_name = "INPUTS")]
    pub inputs: Vec<String>,
    /// The study folder: one folder per recording, study.csv and study.json.
    #[arg(long)]
    pub out: PathBuf,
    /// How the study runs: recordings at once, and whether complete folders run again.
    #[command(flatten)]
    pub study: OptionArgs<pedo_study::StudyParams, StudyFlags>,
    #[command(flatten)]
    pub read: crate::option_args::ReadArgs,
    #[command(flatten)]
    pub options: RunOptionsArgs,
}

/// Every study option, `--jobs` also as `-j`.
#[derive(Clone, Debug, Default)]
pub struct StudyFlags;

impl Selection for StudyFlags {
    const NAMES: Option<&'static [&'static str]> = None;
    const SHORT: &'static [(&'static str, char)] = &[("jobs", 'j')];
}

pub fn run(args: BatchArgs) -> Result<(), CliError> {
    let started = Instant::now();
    let params = args.options.params();
    params.validate()?;
    let paths = pedo_study::find_recordings(&args.inputs)?;
    if paths.is_empty() {
        return Err(CliError::Runtime(format!(
            "no recordings found in {}",
            args.inputs.join(" ")
        )));
    }
    let mut opts = StudyOptions {
        inputs: args.inputs.clone(),
        params,
        read: args.read.params(),
        out: Some(args.out.clone()),
        cancel: None,
        outputs: args.options.outputs(),
        ..StudyOptions::default()
    };
    args.study.params().apply(&mut opts)?;

    // The bar moves in thousandths of a recording (so that it and its ETA advance within one),
    // but the text counts recordings: the finished ones and how far the running ones are.
    let bar = progress_bar_with_text();
    bar.set_length(1000 * paths.len() as u64);
    bar.set_message(progress_text(&[], paths.len()));
    // Per recording: `None` before it starts, its fraction while it runs, 1 once finished.
    let fractions = Mutex::new(vec![None::<f64>; paths.len()]);
    let on_event = |event: StudyEvent<'_>| {
        let mut f = fractions.lock().unwrap();
        match event {
            StudyEvent::Progress { index, fraction } => {
                if f[index] != Some(1.0) {
                    f[index] = Some(fraction.min(0.999));
                }
            }
            StudyEvent::Finished { index, row } => {
                f[index] = Some(1.0);
                if row.status == RowStatus::Error {
                    // The bar hides itself on a non-terminal; errors are printed either way.
                    // Most errors name their file already; the others get its path.
                    let line = if row.message.starts_with(&row.path) {
                        row.message.clone()
                    } else {
                        format!("{}: {}", row.path, row.message)
                    };
                    bar.suspend(|| output::error_line(&format!("pedomatch: {line}")));
                }
            }
        }
        bar.set_message(progress_text(&f, f.len()));
        bar.set_position((1000.0 * f.iter().flatten().sum::<f64>()) as u64);
    };
    let pedo_study::StudyRun { rows, kept } = pedo_study::run_study(&paths, &opts, &on_event)?;
    bar.finish_and_clear();

    // The counts, `--json` and the exit status are this run's recordings; the table also holds
    // the rows it kept of earlier runs, which the closing line mentions.
    let counts = pedo_study::status_counts(&rows);
    let table = pedo_study::study_table_path(&args.out, opts.outputs.tables);
    if args.options.json {
        let mut report = counts.clone();
        report["study"] = table.display().to_string().into();
        report["rows"] = pedo_study::study_table(&rows).to_json();
        out!("{}", output::pretty(&report)?);
    } else {
        outln!(
            "{}: {} ok, {} skipped, {} failed; study table in {}{}",
            counted(rows.len(), "recording"),
            counts["ok"],
            counts["skipped"],
            counts["error"],
            table.display(),
            kept_note(kept.len())
        );
    }
    if args.options.timings {
        eprintln!("timings: total {:.3} s", started.elapsed().as_secs_f64());
    }
    match counts["error"].as_u64().unwrap_or(0) {
        0 => Ok(()),
        n => Err(CliError::Runtime(format!(
            "{n} of {} failed (their rows in {} say why)",
            counted(rows.len(), "recording"),
            table.display()
        ))),
    }
}

/// What the closing line adds about the rows of earlier runs the study table kept.
fn kept_note(kept: usize) -> String {
    match kept {
        0 => String::new(),
        n => format!(" (with {} of earlier runs)", counted(n, "row")),
    }
}

/// A bar whose text says the progress (no internal position/length shown).
fn progress_bar_with_text() -> ProgressBar {
    // indicatif hides itself when stderr is not a terminal, so scripted runs stay quiet.
    let bar = ProgressBar::new(0);
    bar.set_style(
        ProgressStyle::with_template("[{bar:40}] {msg} ({eta})")
            .expect("static template")
            .progress_chars("=> "),
    );
    bar
}

/// The bar's text: `3/8 recordings`, and how far the running ones are: `, 1 running (45 %)` or
/// `, 2 running (45 %, 10 %)`. `fractions` holds, per recording, `None` before it starts, its
/// fraction while it runs and 1 once finished (empty before anything started).
fn progress_text(fractions: &[Option<f64>], total: usize) -> String {
    let finished = fractions.iter().filter(|f| **f == Some(1.0)).count();
    let running: Vec<String> = fractions
        .iter()
        .flatten()
        .filter(|&&f| f < 1.0)
        .map(|f| format!("{:.0} %", 100.0 * f))
        .collect();
    let mut text = format!("{finished}/{}", counted(total, "recording"));
    if !running.is_empty() {
        text += &format!(", {} running ({})", running.len(), running.join(", "));
    }
    text
}

#[cfg(test)]
mod tests {
    use super::progress_text;

    #[test]
    fn progress_counts_recordings() {
        assert_eq!(progress_text(&[], 8), "0/8 recordings");
        let f = [Some(1.0), Some(1.0), Some(1.0), Some(0.456), None];
        assert_eq!(progress_text(&f, 5), "3/5 recordings, 1 running (46 %)");
        let f = [Some(1.0), Some(0.5), Some(0.1)];
        assert_eq!(
            progress_text(&f, 3),
            "1/3 recordings, 2 running (50 %, 10 %)"
        );
        assert_eq!(progress_text(&[Some(1.0)], 1), "1/1 recording");
    }
}
