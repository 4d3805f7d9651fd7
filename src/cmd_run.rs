//! `pedomatch run` and `pedomatch demo`: a whole recording in; tables, figures and tracks out.

use crate::modal_args::ModalArgs;
use crate::output::{self, OutDir};
use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use pedo_io::sequence::{
    run_sequence, ObjectModel, RunParams, SearchMode, SequenceOptions, SequenceResult, Stage,
};
use std::path::PathBuf;
use std::sync::Mutex;
use std::time::Instant;

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum ModelArg {
    Contour,
    Surface,
    Isocontour,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum SearchArg {
    Global,
    Local,
    Both,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ReportArg {
    Html,
    None,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum FigureArg {
    Png,
    Svg,
    Both,
    None,
}

/// Options shared by `run` and `demo`.
#[derive(Args, Clone)]
pub struct RunOptionsArgs {
    /// Object model of each frame.
    #[arg(long, value_enum, default_value = "contour")]
    pub model: ModelArg,
    #[command(flatten)]
    pub modal: ModalArgs,
    /// Search strategy: `both` reports local and optimisation matches side by side.
    #[arg(long, value_enum, default_value = "both")]
    pub search: SearchArg,
    /// Frames to use, 1-based and inclusive, e.g. `10..60`.
    #[arg(long)]
    pub frames: Option<String>,
    /// Noise threshold in the recording's units (default: the file's own, else 0).
    #[arg(long)]
    pub noise: Option<f64>,
    /// Gaussian smoothing of each frame, σ in sensels.
    #[arg(long, default_value_t = 0.0)]
    pub smooth: f64,
    /// Contour node spacing in sensels.
    #[arg(long, default_value_t = 1.0)]
    pub spacing: f64,
    /// Node budget of each brightness surface.
    #[arg(long, default_value_t = 120)]
    pub surface_nodes: usize,
    /// Isocontour model: the frame (1-based; default: the frame of largest load) and the number
    /// of levels.
    #[arg(long)]
    pub iso_frame: Option<usize>,
    #[arg(long, default_value_t = 10)]
    pub iso_levels: usize,
    /// Figures of every pair and of the tracks.
    #[arg(long, value_enum, default_value = "png")]
    pub figures: FigureArg,
    /// Print the time spent in each stage.
    #[arg(long)]
    pub timings: bool,
    /// The interactive report: `html` writes a self-contained `report.html` (opens offline).
    #[arg(long, value_enum, default_value = "html")]
    pub report: ReportArg,
}

#[derive(Args)]
pub struct RunArgs {
    /// The recording: .asf, .lst, .npy, .csv, a PNG/TIFF image, a folder or numbered sequence.
    pub recording: PathBuf,
    /// Output folder.
    #[arg(long, default_value = "pedomatch-out")]
    pub out: PathBuf,
    #[command(flatten)]
    pub options: RunOptionsArgs,
}

#[derive(Args)]
pub struct DemoArgs {
    /// Output folder.
    #[arg(long, default_value = "pedomatch-out")]
    pub out: PathBuf,
    #[command(flatten)]
    pub options: RunOptionsArgs,
}

/// The bundled real recording (Tekscan F-Scan, MIT licence: examples/data/LICENSE-footPress.txt).
const DEMO_RECORDING: &[u8] = include_bytes!("../examples/data/FrasP01L.asf");

pub fn run(args: RunArgs) -> Result<(), String> {
    let t = Instant::now();
    let recording = pedo_io::read_recording(&args.recording).map_err(|e| e.to_string())?;
    execute(
        recording,
        &args.recording.display().to_string(),
        &args.out,
        &args.options,
        t,
    )
}

pub fn demo(args: DemoArgs) -> Result<(), String> {
    let t = Instant::now();
    let name = "examples/data/FrasP01L.asf";
    let recording = pedo_io::parse_bytes(DEMO_RECORDING, pedo_io::Format::Asf, name)
        .map_err(|e| e.to_string())?;
    execute(recording, name, &args.out, &args.options, t)
}

fn parse_frames(spec: &str) -> Result<(usize, usize), String> {
    let bad =
        || format!("--frames {spec:?}: expected A..B, 1-based and inclusive (A.. and ..B allowed)");
    let (a, b) = spec.split_once("..").ok_or_else(bad)?;
    let a: usize = if a.trim().is_empty() {
        1
    } else {
        a.trim().parse().map_err(|_| bad())?
    };
    let b: usize = if b.trim().is_empty() {
        usize::MAX
    } else {
        b.trim().parse().map_err(|_| bad())?
    };
    Ok((a, b))
}

/// The command-line options as the library's [`RunParams`], checked against `recording`.
pub fn sequence_options(
    o: &RunOptionsArgs,
    recording: &pedo_io::Recording,
) -> Result<SequenceOptions, String> {
    let frames = o
        .frames
        .as_deref()
        .map(parse_frames)
        .transpose()?
        .map(|(a, b)| (a, b.min(recording.n_frames())));
    let params = RunParams {
        model: match o.model {
            ModelArg::Contour => ObjectModel::Contour,
            ModelArg::Surface => ObjectModel::Surface,
            ModelArg::Isocontour => ObjectModel::Isocontour,
        },
        frames,
        noise: o.noise,
        smooth: o.smooth,
        spacing: o.spacing,
        surface_nodes: o.surface_nodes,
        iso_frame: o.iso_frame,
        iso_levels: o.iso_levels,
        ..o.modal.params(match o.search {
            SearchArg::Global => SearchMode::Global,
            SearchArg::Local => SearchMode::Local,
            SearchArg::Both => SearchMode::Both,
        })
    };
    params.to_options(recording).map_err(|e| e.to_string())
}

fn execute(
    recording: pedo_io::Recording,
    name: &str,
    out: &std::path::Path,
    o: &RunOptionsArgs,
    started: Instant,
) -> Result<(), String> {
    let read_time = started.elapsed();
    let options = sequence_options(o, &recording)?;
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
            });
        }
        bar.set_position(done as u64);
    };
    let result = run_sequence(&recording, &options, &progress).map_err(|e| e.to_string())?;
    bar.finish_and_clear();

    let t_out = Instant::now();
    let dir = OutDir::create(out)?;
    output::write_sequence(
        &dir,
        name,
        &recording,
        &options,
        &result,
        figure_kinds(o.figures),
    )?;
    if o.report == ReportArg::Html {
        let timings = vec![
            ("read".to_string(), read_time.as_secs_f64()),
            ("objects".to_string(), result.timings.objects.as_secs_f64()),
            (
                "matching".to_string(),
                result.timings.matching.as_secs_f64(),
            ),
            ("tracks".to_string(), result.timings.tracks.as_secs_f64()),
            (
                "tables and figures".to_string(),
                t_out.elapsed().as_secs_f64(),
            ),
        ];
        output::write_report(
            &dir,
            name,
            &recording,
            &options,
            &result,
            report_options(o),
            timings,
        )?;
    }
    dir.commit()?;
    let write_time = t_out.elapsed();
    print_summary(name, out, &result);
    if o.timings {
        eprintln!("timings: read {:.3} s, objects {:.3} s, matching {:.3} s, tracks {:.3} s, output {:.3} s, total {:.3} s",
            read_time.as_secs_f64(),
            result.timings.objects.as_secs_f64(),
            result.timings.matching.as_secs_f64(),
            result.timings.tracks.as_secs_f64(),
            write_time.as_secs_f64(),
            started.elapsed().as_secs_f64());
    }
    Ok(())
}

/// The options of a run as (name, value) text for the report's header.
fn report_options(o: &RunOptionsArgs) -> Vec<(String, String)> {
    let opt = |v: Option<String>| v.unwrap_or_else(|| "default".into());
    [
        ("model", format!("{:?}", o.model).to_lowercase()),
        ("element", format!("{:?}", o.modal.element).to_lowercase()),
        ("modes", o.modal.modes.to_string()),
        ("search", format!("{:?}", o.search).to_lowercase()),
        ("solver", format!("{:?}", o.modal.solver).to_lowercase()),
        ("threshold", opt(o.modal.threshold.map(|t| t.to_string()))),
        ("excess", (!o.modal.no_excess).to_string()),
        ("paper", o.modal.paper.to_string()),
        ("center_stride", o.modal.center_stride.to_string()),
        ("frames", opt(o.frames.clone())),
        ("noise", opt(o.noise.map(|v| v.to_string()))),
        ("smooth", o.smooth.to_string()),
        ("spacing", o.spacing.to_string()),
        ("surface_nodes", o.surface_nodes.to_string()),
        ("iso_frame", opt(o.iso_frame.map(|v| v.to_string()))),
        ("iso_levels", o.iso_levels.to_string()),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v))
    .collect()
}

fn figure_kinds(f: FigureArg) -> (bool, bool) {
    match f {
        FigureArg::Png => (true, false),
        FigureArg::Svg => (false, true),
        FigureArg::Both => (true, true),
        FigureArg::None => (false, false),
    }
}

fn progress_bar() -> ProgressBar {
    // indicatif hides itself when stderr is not a terminal, so scripted runs stay quiet.
    let bar = ProgressBar::new(0);
    bar.set_style(
        ProgressStyle::with_template("{msg:>9} [{bar:40}] {pos}/{len} ({eta})")
            .expect("static template")
            .progress_chars("=> "),
    );
    bar
}

fn print_summary(name: &str, out: &std::path::Path, r: &SequenceResult) {
    let n = r.pairs.len().max(1) as f64;
    let mean = |f: &dyn Fn(&pedo_io::sequence::PairRow) -> f64| {
        r.pairs.iter().map(|p| f(&p.row)).sum::<f64>() / n
    };
    let long_tracks = r.tracks.iter().filter(|t| t.steps.len() >= 3).count();
    println!(
        "{name}: {} objects, {} matched pairs, {} tracks ({} spanning 3+ objects)",
        r.objects.len(),
        r.pairs.len(),
        r.tracks.len(),
        long_tracks
    );
    println!(
        "mean local matches {:.1} %, optimisation matches {:.1} %, mean cost {:.4}",
        mean(&|p| p.local_percent),
        mean(&|p| p.optimisation_percent),
        mean(&|p| p.mean_cost)
    );
    if !r.skipped_pairs.is_empty() || !r.skipped_frames.is_empty() {
        let first = r
            .skipped_pairs
            .first()
            .map(|s| s.reason.as_str())
            .or(r.skipped_frames.first().map(|s| s.reason.as_str()))
            .unwrap_or_default();
        println!(
            "skipped {} pairs and {} frames that could not be matched (reasons in pairs.csv and summary.json; first: {first})",
            r.skipped_pairs.len(),
            r.skipped_frames.len()
        );
    }
    println!(
        "results in {}/ (pairs.csv, pairs.json, tracks.csv, summary.json, figures/)",
        out.display()
    );
}
