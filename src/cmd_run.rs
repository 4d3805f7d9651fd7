//! `pedomatch run` and `pedomatch demo`: a whole recording in; tables, figures and tracks out.

use crate::option_args::OptionArgs;
use crate::output;
use crate::CliError;
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use pedo_io::counted;
use pedo_io::formats::stamp::{FileStamp, Unchanged};
use pedo_output::InputInfo;
use pedo_output::TableFormat;
use pedo_track::{RunParams, Stage};
use serde_json::Value;
use std::path::PathBuf;
use std::sync::Mutex;
use std::time::Instant;

/// Options shared by `run`, `demo` and `batch`.
#[derive(Args, Clone)]
pub struct RunOptionsArgs {
    /// The run's options: the recording, matching and unit options.
    #[command(flatten)]
    pub run: OptionArgs<RunParams>,
    /// What the run's folder holds besides its tables.
    #[command(flatten)]
    pub output: OptionArgs<pedo_output::OutputOptions>,
    /// Print the time spent in each stage.
    #[arg(long)]
    pub timings: bool,
    /// Print the run's summary (summary.json) on stdout instead of text.
    #[arg(long)]
    pub json: bool,
}

impl RunOptionsArgs {
    /// What the run's folder holds besides its tables.
    pub fn outputs(&self) -> pedo_output::RunOutputs {
        pedo_output::RunOutputs::of(&self.output.params())
    }

    /// These options as the library's parameters; absent ones at the library's defaults.
    pub fn params(&self) -> RunParams {
        self.run.params()
    }
}

#[derive(Args)]
pub struct RunArgs {
    /// The recording: Tekscan .asf or CSV export, emed .lst, pedar .asc, Zebris .apd or raw-data
    /// XML/JSON, footscan export, .npy/.npz, a CSV grid, a PNG/TIFF image, a folder of images or a
    /// numbered pattern (`walk_%03d.png`); the format is detected from the content.
    pub recording: PathBuf,
    /// Output folder [default: pedomatch-out, which a run without --out never takes from the
    /// results of another input].
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub read: crate::option_args::ReadArgs,
    #[command(flatten)]
    pub options: RunOptionsArgs,
}

#[derive(Args)]
pub struct DemoArgs {
    /// Output folder [default: pedomatch-out, which a run without --out never takes from the
    /// results of another input].
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub options: RunOptionsArgs,
}

/// The bundled real recording (Tekscan F-Scan, MIT licence: examples/data/LICENSE-footPress.txt).
const DEMO_RECORDING: &[u8] = include_bytes!("../examples/data/FrasP01L.asf");

pub fn run(args: RunArgs) -> Result<(), CliError> {
    let t = Instant::now();
    let params = args.options.params();
    params.validate()?;
    let read = args.read.params();
    // The SHA-256 recorded must be of the bytes parsed: the file must not change from before
    // the read to after the hash (nor, streamed, to its last frame).
    let path = &args.recording;
    let stamp = FileStamp::of(path);
    let pedo_io::formats::RunInput {
        recording,
        mut frames,
        sha256,
    } = pedo_output::read_for_run(path, &read, &params, &args.options.outputs())?;
    let input = InputInfo::of_read(path, sha256)?.with_layout(&read, recording.format)?;
    stamp.check(path)?;
    let out = out_folder(args.out, &input)?;
    let mut unchanged = frames.as_mut().map(|inner| Unchanged {
        inner,
        path,
        stamp: &stamp,
    });
    let frames = unchanged
        .as_mut()
        .map(|f| f as &mut dyn pedo_io::FrameSource);
    execute(recording, frames, &input, &out, &args.options, params, t)
}

pub fn demo(args: DemoArgs) -> Result<(), CliError> {
    let t = Instant::now();
    let params = args.options.params();
    params.validate()?;
    let name = "examples/data/FrasP01L.asf";
    let recording = pedo_io::parse_bytes(DEMO_RECORDING, pedo_io::Format::Asf, name)?;
    let input = InputInfo::of_bytes(name, DEMO_RECORDING);
    let out = out_folder(args.out, &input)?;
    execute(recording, None, &input, &out, &args.options, params, t)
}

/// The folder a run writes: `--out` as given, else the default folder unless it holds the
/// results of another input ([`pedo_output::refuse_other_input`]).
fn out_folder(out: Option<PathBuf>, input: &InputInfo) -> Result<PathBuf, CliError> {
    match out {
        Some(out) => Ok(out),
        None => {
            let out = PathBuf::from(pedo_output::DEFAULT_RUN_FOLDER);
            pedo_output::refuse_other_input(&out, input)?;
            Ok(out)
        }
    }
}

fn execute(
    mut recording: pedo_io::Recording,
    frames: Option<&mut dyn pedo_io::FrameSource>,
    input: &InputInfo,
    out: &std::path::Path,
    o: &RunOptionsArgs,
    params: RunParams,
    started: Instant,
) -> Result<(), CliError> {
    let options =
        pedo_track::run_options(&mut recording, &params).map_err(|e| e.of_input(&input.name))?;
    let read_time = started.elapsed();
    let bar = progress_bar();
    let bar_state = Mutex::new(None::<Stage>);
    let progress = |stage: Stage, done: usize, total: usize| {
        let mut s = bar_state.lock().unwrap();
        if *s != Some(stage) {
            *s = Some(stage);
            bar.set_length(total as u64);
            bar.set_position(0);
            bar.set_message(match stage {
                Stage::Objects => "objects",
                Stage::Matching => "matching",
                Stage::Output => "output",
            });
        }
        bar.set_position(done as u64);
    };
    let outputs = o.outputs();
    let plan = pedo_output::RunPlan {
        input,
        params: &params,
        // Reborrowed for the plan's lifetime (a trait object's may shorten, not its borrow's).
        frames: frames.map(|f| &mut *f as &mut dyn pedo_io::FrameSource),
        folder: Some(out),
        outputs: &outputs,
        timings: &[("read", read_time.as_secs_f64())],
        also: None,
    };
    let (summary, _) = pedo_output::run_into_folder(&recording, &options, plan, &progress)
        .map_err(|e| e.of_input(&input.name))?;
    bar.finish_and_clear();
    if o.json {
        out!("{}", output::pretty(&summary)?);
    } else {
        print_summary(&input.name, out, &summary, outputs.tables);
    }
    if o.timings {
        let t = &summary["timings_s"];
        let s = |k: &str| t[k].as_f64().unwrap_or(0.0);
        eprintln!(
            "timings: read {:.3} s, objects {:.3} s, matching {:.3} s, tracks {:.3} s, output {:.3} s, total {:.3} s",
            read_time.as_secs_f64(),
            s("objects"),
            s("matching"),
            s("tracks"),
            s("output"),
            started.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

pub fn progress_bar() -> ProgressBar {
    // indicatif hides itself when stderr is not a terminal, so scripted runs stay quiet.
    let bar = ProgressBar::new(0);
    bar.set_style(
        ProgressStyle::with_template("{msg:>9} [{bar:40}] {pos}/{len} ({eta})")
            .expect("static template")
            .progress_chars("=> "),
    );
    bar
}

fn print_summary(name: &str, out: &std::path::Path, summary: &Value, tables: TableFormat) {
    let int = |k: &str| summary[k].as_u64().unwrap_or(0);
    let float = |k: &str| summary[k].as_f64().unwrap_or(0.0);
    let count = |k: &str, noun: &str| counted(int(k) as usize, noun);
    outln!(
        "{name}: {}, {}, {} ({} spanning 3+ objects)",
        count("objects", "object"),
        count("pairs", "matched pair"),
        count("tracks", "track"),
        int("tracks_3_or_more")
    );
    let isocontour = summary["options"]["model"] == "isocontour";
    let skipped = |k: &str| {
        summary["skipped"][k]
            .as_array()
            .cloned()
            .unwrap_or_default()
    };
    let (pairs, frames) = (skipped("pairs"), skipped("frames"));
    if int("pairs") == 0 {
        outln!("{}", pedo_study::no_pairs_note(isocontour, pairs.len()));
    } else {
        // The share of nodes matched is near 100 % by construction (pairs.csv keeps it): the
        // line says how far the matches can be trusted.
        if summary["mean_round_trip_sensels"].is_f64() {
            outln!(
                "matches consistent to {:.3} sensels round trip (field residual {:.3}); {:.1} % trackable, {:.1} % mutual best",
                float("mean_round_trip_sensels"),
                float("mean_field_residual_sensels"),
                float("mean_trackable_percent"),
                float("mean_local_percent")
            );
            for kind in pedo_output::RoundTripSummary::ALL {
                if let Some(t) = kind.of_summary(summary) {
                    let who = match kind {
                        pedo_output::RoundTripSummary::Tracks => "tracks'",
                        pedo_output::RoundTripSummary::Points => "material points'",
                    };
                    outln!(
                        "{who} round trip {:.3} sensels median, {:.3} at the 95th percentile ({:.1} % over 1 sensel)",
                        t.median,
                        t.p95,
                        t.over_1_percent
                    );
                }
            }
        } else {
            outln!(
                "{:.1} % of matches trackable, {:.1} % mutual best, mean cost {:.4}",
                float("mean_trackable_percent"),
                float("mean_local_percent"),
                float("mean_cost")
            );
        }
    }
    if !pairs.is_empty() || !frames.is_empty() {
        let first = pairs
            .first()
            .or(frames.first())
            .and_then(|s| s["reason"].as_str())
            .unwrap_or_default();
        // For isocontours, a skipped "frame" is an isobaric level that gave no object.
        let (frame, verb) = if isocontour {
            ("isobaric level", "gave no object")
        } else {
            ("frame", "could not be matched")
        };
        let mut what = Vec::new();
        if !pairs.is_empty() {
            what.push(format!(
                "{} that could not be matched",
                counted(pairs.len(), "pair")
            ));
        }
        if !frames.is_empty() {
            what.push(format!("{} that {verb}", counted(frames.len(), frame)));
        }
        // Skipped pairs are rows of the pairs table; skipped frames are only in summary.json.
        let place = if pairs.is_empty() {
            "summary.json".to_string()
        } else {
            format!("{} and summary.json", tables.file_name("pairs"))
        };
        outln!(
            "skipped {} (reasons in {place}; first: {first})",
            what.join(" and ")
        );
    }
    outln!("results in {}", crate::output::folder_text(out));
}
