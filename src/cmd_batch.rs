//! `pedomatch batch`: a whole study, each recording like `pedomatch run` into a folder of its own,
//! several at once, one row per recording in `study.csv`. The work is [`pedo_io::study`]'s.

use crate::cmd_run::{progress_bar, ReportArg, RunOptionsArgs};
use crate::output;
use crate::CliError;
use clap::Args;
use pedo_io::study::{self, RowStatus, StudyEvent, StudyOptions};
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
    /// Recordings run at once, each on one thread [default: the available cores].
    #[arg(long, short = 'j', value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub jobs: Option<u32>,
    /// Run every recording again, even those whose folders are complete.
    #[arg(long)]
    pub force: bool,
    #[command(flatten)]
    pub read: crate::modal_args::ReadArgs,
    #[command(flatten)]
    pub options: RunOptionsArgs,
}

pub fn run(args: BatchArgs) -> Result<(), CliError> {
    let started = Instant::now();
    let params = args.options.params();
    params.validate()?;
    let paths = study::find_recordings(&args.inputs)?;
    if paths.is_empty() {
        return Err(CliError::Runtime(format!(
            "no recordings found in {}",
            args.inputs.join(" ")
        )));
    }
    let (png, svg) = args.options.figures.kinds();
    let opts = StudyOptions {
        params,
        read: pedo_io::ReadOptions {
            layout: args.read.layout.clone(),
        },
        out: Some(args.out.clone()),
        jobs: args.jobs.map_or(0, |j| j as usize),
        force: args.force,
        outputs: study::RunOutputs {
            figures: study::FigureKinds { png, svg },
            report: (args.options.report == ReportArg::Html)
                .then_some(&output::report_page as &study::ReportWriter),
            animation: args.options.animation == crate::cmd_run::AnimationArg::Gif,
            tables: args.options.tables.unwrap_or_default(),
        },
    };

    let bar = progress_bar();
    bar.set_length(1000 * paths.len() as u64);
    bar.set_message(format!("0/{} recordings", paths.len()));
    let fractions = Mutex::new(vec![0.0_f64; paths.len()]);
    let finished = Mutex::new(0_usize);
    let on_event = |event: StudyEvent<'_>| {
        let mut f = fractions.lock().unwrap();
        match event {
            StudyEvent::Progress { index, fraction } => f[index] = fraction,
            StudyEvent::Finished { index, row } => {
                f[index] = 1.0;
                let mut n = finished.lock().unwrap();
                *n += 1;
                bar.set_message(format!("{n}/{} recordings", f.len()));
                if row.status == RowStatus::Error {
                    // The bar hides itself on a non-terminal; errors are printed either way.
                    // Most errors name their file already; the others get its path.
                    let line = if row.message.starts_with(&row.path) {
                        row.message.clone()
                    } else {
                        format!("{}: {}", row.path, row.message)
                    };
                    bar.suspend(|| eprintln!("pedomatch: {line}"));
                }
            }
        }
        bar.set_position((1000.0 * f.iter().sum::<f64>()) as u64);
    };
    let rows = study::run_study(&paths, &opts, &on_event)?;
    bar.finish_and_clear();

    let counts = study::status_counts(&rows);
    let table = study::study_table_path(&args.out, opts.outputs.tables);
    if args.options.json {
        let mut report = counts.clone();
        report["study"] = table.display().to_string().into();
        report["rows"] = study::study_table(&rows).to_json();
        print!("{}", output::pretty(&report)?);
    } else {
        println!(
            "{} recordings: {} ok, {} skipped, {} failed; study table in {}",
            counts["recordings"],
            counts["ok"],
            counts["skipped"],
            counts["error"],
            table.display()
        );
    }
    if args.options.timings {
        eprintln!("timings: total {:.3} s", started.elapsed().as_secs_f64());
    }
    match counts["error"].as_u64().unwrap_or(0) {
        0 => Ok(()),
        n => Err(CliError::Runtime(format!(
            "{n} of {} recordings failed (their rows in {} say why)",
            rows.len(),
            table.display()
        ))),
    }
}
