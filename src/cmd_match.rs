//! `pedomatch match A B`: correspondences between two objects given as images or point files.

use crate::option_args::{help, tri_state, ModalArgs, OptionArgs, Selection, UnitArgs};
use crate::output::{self, OutDir};
use crate::CliError;
use clap::Args;
use modal_core::shape::looks_like_closed_contour;
use modal_core::{MatchParams, Search, Shape, Topology};
use pedo_output::figure::{FigureAxes, MatchFigure, ObjectLabel};
use pedo_output::{FigureKinds, ReportFormat};
use pedo_track::SenselAspect;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Args)]
pub struct MatchArgs {
    /// First object: a point file (`x,y[,z]` per line: `.xy`, `.xyz`, `.pts`, or a `.csv`/`.txt`
    /// with 2 or 3 columns) or a pressure image/recording (its largest contour).
    pub a: PathBuf,
    /// Second object, as the first.
    pub b: PathBuf,
    /// Read both inputs as point files even if their extension suggests an image.
    #[arg(long)]
    pub points: bool,
    #[arg(long, alias = "closed", help = help("ordered"), conflicts_with = "no_ordered")]
    pub ordered: bool,
    #[arg(long, help = "Turn --ordered off")]
    pub no_ordered: bool,
    /// Frame (0-based) to take from a multi-frame recording (both inputs, unless --frame-b).
    #[arg(long, default_value_t = 0)]
    pub frame: usize,
    /// Frame (0-based) of the second input, when it differs from --frame: two frames of one
    /// recording are `match walk.asf walk.asf --frame 40 --frame-b 41`. A later frame of the
    /// same recording is matched with the settings of `pedomatch run` (its objects, its
    /// consecutive-frame defaults: sensor pre-alignment, a 30° rotation bound, node-to-node
    /// ICP), so that the pair's matches are the run's for that pair; the output says so.
    /// Two files, or an earlier frame, keep the defaults of a pair.
    #[arg(long)]
    pub frame_b: Option<usize>,
    #[command(flatten)]
    pub modal: ModalArgs,
    #[command(flatten)]
    pub units: UnitArgs,
    #[command(flatten)]
    pub read: crate::option_args::ReadArgs,
    /// Write matches.csv, match.json and the match figure into this folder instead of printing
    /// the matches.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// The figure (and its format) and report written with --out: the output options of a run.
    #[command(flatten)]
    pub outputs: OptionArgs<pedo_output::OutputOptions, Drawings>,
    /// Print the match result as one JSON object (with its pairs) instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// The output options of a run that `match` takes: its figure and its report.
#[derive(Clone, Debug, Default)]
pub struct Drawings;

impl Selection for Drawings {
    const NAMES: Option<&'static [&'static str]> = Some(&["figures", "figure_format", "report"]);
}

/// Extensions that always name point files; `.csv` and `.txt` are point files when laid out as
/// points, and recordings (CSV grids, footscan and pedar text exports) otherwise.
const POINT_EXTENSIONS: [&str; 3] = ["xy", "xyz", "pts"];

/// An object read from a file, and the pitch (mm) and frame time (s) when it came from a
/// recording that knows them.
struct Object {
    points: Shape,
    pitch_mm: Option<[f64; 2]>,
    time_s: Option<f64>,
    /// The figure axes of the recording the object was taken from (`None`: a point file).
    axes: Option<FigureAxes>,
    /// The recording and frame the object was taken from (`None`: a point file), drawn under
    /// it in the report.
    source: Option<(pedo_io::Recording, usize)>,
}

impl Object {
    /// The recording frame the object was taken from (`None`: a point file).
    fn frame(&self) -> Option<usize> {
        self.source.as_ref().map(|(_, frame)| *frame)
    }
}

/// An object from a file: a point file as it is, or the largest contour of frame `frame` of a
/// pressure recording.
fn load_object(path: &Path, frame: usize, args: &MatchArgs) -> Result<Object, CliError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let plain = |points| Object {
        points,
        pitch_mm: args.units.params().pitch_mm.map(|p| p.0),
        time_s: None,
        axes: None,
        source: None,
    };
    let as_points = args.points || POINT_EXTENSIONS.contains(&ext.as_str());
    if as_points {
        return Ok(plain(pedo_io::points::read_points(path, Topology::None)?));
    }
    // A CSV or text file is a point file when it has 2 or 3 columns (then a bad value is a point
    // file's error), a recording otherwise.
    if matches!(ext.as_str(), "csv" | "txt")
        && let Ok(text) = std::fs::read_to_string(path)
        && pedo_io::points::is_point_layout(&text)
    {
        let name = path.display().to_string();
        let points = pedo_io::points::parse_points(&text, &name, Topology::None)?;
        return Ok(plain(points));
    }
    let mut rec = args.read.read(path)?;
    args.units
        .params()
        .apply(&mut rec)
        .map_err(|e| e.of_input(&path.display().to_string()))?;
    if frame >= rec.n_frames() {
        return Err(CliError::Usage(format!(
            "{}: frame = {frame}: expected a frame in 0..{} (0-based)",
            path.display(),
            rec.n_frames()
        )));
    }
    let image = rec.frame(frame)?;
    let opts = pedo_io::ContourOptions {
        resample: pedo_io::Resample::Spacing(1.0),
        include_holes: false,
        ..Default::default()
    };
    let contours =
        pedo_io::contours(&image, &opts).map_err(|e| format!("{}: {e}", path.display()))?;
    let largest = contours
        .iter()
        .max_by(|x, y| x.area().total_cmp(&y.area()))
        .ok_or_else(|| format!("{}: frame {frame} has no loaded region", path.display()))?;
    Ok(Object {
        points: largest.to_shape()?,
        pitch_mm: rec.pitch_mm,
        time_s: rec.time_s(frame),
        axes: Some(FigureAxes::of_recording(&rec)),
        source: Some((rec, frame)),
    })
}

/// The objects with the topology `ordered` asks for (decided from the data when not given,
/// as `pymodal.match` does).
fn with_topology(
    a: Shape,
    b: Shape,
    ordered: Option<bool>,
) -> Result<(Shape, Shape, bool), CliError> {
    let closed = |s: &Shape| {
        matches!(s.topology(), Topology::ClosedContour)
            || looks_like_closed_contour(s.coords(), s.dim())
    };
    let ordered = ordered.unwrap_or_else(|| a.dim() == 2 && closed(&a) && closed(&b));
    let topology = if ordered {
        Topology::ClosedContour
    } else {
        Topology::None
    };
    let retag = |s: Shape| Shape::new(s.dim(), s.coords().to_vec(), topology.clone());
    Ok((retag(a)?, retag(b)?, ordered))
}

/// Which defaults a match used, and why: the run's for two frames of one recording in time
/// order, a pair's otherwise.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Settings {
    /// `pedomatch run`'s for consecutive frames (the pair is the run's pair).
    Run,
    /// The defaults of two objects.
    Pair,
}

impl Settings {
    /// The settings for `args`: the run's when both inputs are one recording (the same file)
    /// and `--frame-b` names a later frame than `--frame`.
    fn of(args: &MatchArgs) -> Self {
        let later = args.frame_b.is_some_and(|b| b > args.frame);
        let same = match (args.a.canonicalize(), args.b.canonicalize()) {
            (Ok(a), Ok(b)) => a == b,
            _ => false,
        };
        if later && same && !args.points && !is_point_file(&args.a) {
            Settings::Run
        } else {
            Settings::Pair
        }
    }

    fn name(self) -> &'static str {
        match self {
            Settings::Run => "run",
            Settings::Pair => "pair",
        }
    }

    /// One sentence for the output: which defaults, and why.
    fn reason(self) -> &'static str {
        match self {
            Settings::Run => {
                "two frames of one recording: matched with the settings of pedomatch run for \
                 consecutive frames (its objects, sensor pre-alignment, a 30 degree rotation \
                 bound, node-to-node ICP), so the matches are the run's for this pair"
            }
            Settings::Pair => {
                "two objects: the defaults of a pair (rotation search over any turn, the outline \
                 fit of two outlines); a later frame of the same recording (--frame-b) gets the \
                 run's settings"
            }
        }
    }
}

/// Whether `path` is a point file by its extension or layout (as [`load_object`] decides).
fn is_point_file(path: &Path) -> bool {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    POINT_EXTENSIONS.contains(&ext.as_str())
        || (matches!(ext.as_str(), "csv" | "txt")
            && std::fs::read_to_string(path).is_ok_and(|t| pedo_io::points::is_point_layout(&t)))
}

/// Two frames of one recording matched as `pedomatch run` matches them: the run's objects of
/// frames `--frame` and `--frame-b` (a run of those two frames: `--frames A..B+1 --every B-A`),
/// the object of the first frame of largest contact area and the object of the second the run
/// pairs it with, and that pair's result.
struct RunPair {
    oa: Object,
    ob: Object,
    result: modal_core::MatchResult,
    /// Every option as the run used it.
    used: Vec<(&'static str, modal_core::OptionValue)>,
    search: Search,
}

fn run_pair(args: &MatchArgs) -> Result<RunPair, CliError> {
    let (fa, fb) = (args.frame, args.frame_b.unwrap_or(args.frame));
    let mut rec = args.read.read(&args.a)?;
    let name = args.a.display().to_string();
    let params = pedo_track::RunParams {
        matching: args.modal.params(),
        units: args.units.params(),
        frames: Some(pedo_track::FrameRange::new(fa, fb + 1)),
        every: pedo_track::FrameStride::Every(fb - fa),
        ..Default::default()
    };
    args.units
        .params()
        .apply(&mut rec)
        .map_err(|e| e.of_input(&name))?;
    if fb >= rec.n_frames() {
        return Err(CliError::Usage(format!(
            "{name}: frame = {fb}: expected a frame in 0..{} (0-based)",
            rec.n_frames()
        )));
    }
    let options = params.to_options(&rec)?;
    let run = pedo_track::run_sequence(&rec, &options, &|_, _, _| {})?;
    let area = |o: &pedo_track::SequenceObject| o.measures.as_ref().map_or(0.0, |m| m.contact_area);
    let largest = run
        .objects
        .iter()
        .filter(|o| o.frame == fa)
        .max_by(|x, y| area(x).total_cmp(&area(y)))
        .ok_or_else(|| format!("{name}: frame {fa} has no loaded region"))?;
    let pair = run
        .pairs
        .iter()
        .filter(|p| p.a == largest.id)
        .max_by(|x, y| area(&run.objects[x.b]).total_cmp(&area(&run.objects[y.b])));
    let Some(pair) = pair else {
        let why = run
            .skipped_pairs
            .iter()
            .find(|s| s.a == largest.id)
            .map_or("no object of that frame continues it".to_string(), |s| {
                s.reason.clone()
            });
        return Err(CliError::Runtime(format!(
            "{name}: the largest object of frame {fa} has no match in frame {fb}: {why}"
        )));
    };
    let object = |o: &pedo_track::SequenceObject| Object {
        points: o.shape.clone(),
        pitch_mm: rec.pitch_mm,
        time_s: rec.time_s(o.frame),
        axes: Some(FigureAxes::of_recording(&rec)),
        source: Some((rec.clone(), o.frame)),
    };
    Ok(RunPair {
        oa: object(largest),
        ob: object(&run.objects[pair.b]),
        result: pair.result.clone(),
        used: params.used(&options, &rec),
        search: options.matching.search,
    })
}

/// The result of a run of two frames: its match, every option as the run used it, and its search.
type RunMatch = (
    modal_core::MatchResult,
    Vec<(&'static str, modal_core::OptionValue)>,
    Search,
);

/// The two objects of a `match`, read (or taken from a run of two frames) and made shapes.
struct LoadedPair {
    oa: Object,
    ob: Object,
    a: Shape,
    b: Shape,
    ordered: bool,
    /// The run's match of the pair, when the two frames were matched as a run matches them.
    from_run: Option<RunMatch>,
}

impl LoadedPair {
    fn load(args: &MatchArgs, settings: Settings) -> Result<Self, CliError> {
        let (oa, ob, from_run) = if settings == Settings::Run {
            let p = run_pair(args)?;
            (p.oa, p.ob, Some((p.result, p.used, p.search)))
        } else {
            let oa = load_object(&args.a, args.frame, args)?;
            let ob = load_object(&args.b, args.frame_b.unwrap_or(args.frame), args)?;
            (oa, ob, None)
        };
        warn_if_no_frames(&oa, &args.a, args.frame, "--frame");
        let flag_b = if args.frame_b.is_some() {
            "--frame-b"
        } else {
            "--frame"
        };
        warn_if_no_frames(&ob, &args.b, args.frame_b.unwrap_or(args.frame), flag_b);
        let ordered = tri_state(args.ordered, args.no_ordered);
        let (a, b, ordered) = with_topology(oa.points.clone(), ob.points.clone(), ordered)?;
        warn_if_same(&a, &b, args);
        if a.dim() != b.dim() {
            return Err(CliError::Runtime(format!(
                "{} has {}-D points but {} has {}-D points",
                args.a.display(),
                a.dim(),
                args.b.display(),
                b.dim()
            )));
        }
        Ok(Self {
            oa,
            ob,
            a,
            b,
            ordered,
            from_run,
        })
    }

    /// The pair's match: the run's, or the defaults of two objects (the setting
    /// `pymodal.match` picks for them).
    fn matched(&mut self, params: &MatchParams) -> Result<RunMatch, CliError> {
        if let Some(matched) = self.from_run.take() {
            return Ok(matched);
        }
        let mut o = params.to_match_options(self.a.dim(), self.ordered)?;
        o.ordered = Some(self.ordered);
        // Two frames of one sensor are matched in its true proportions, as `run` matches them.
        let aspect = match (self.oa.frame(), self.ob.frame()) {
            (Some(_), Some(_)) if self.oa.pitch_mm == self.ob.pitch_mm => {
                SenselAspect::of_pitch(self.oa.pitch_mm)
            }
            _ => SenselAspect::SQUARE,
        };
        let r = aspect.back(modal_core::match_shapes(
            aspect.shape(&self.a)?.as_ref(),
            aspect.shape(&self.b)?.as_ref(),
            &o,
        )?);
        Ok((r, params.used(&o), o.search))
    }
}

pub fn run(args: MatchArgs) -> Result<(), CliError> {
    let started = Instant::now();
    let params = args.modal.params();
    params.validate()?;
    args.units.params().validate()?;
    let settings = Settings::of(&args);
    if settings == Settings::Run && (args.ordered || args.no_ordered) {
        return Err(CliError::Usage(
            "--ordered/--no-ordered: two frames of one recording are matched as a run matches \
             them (closed contours, ordered); the option applies to two objects"
                .into(),
        ));
    }
    let mut pair = LoadedPair::load(&args, settings)?;
    let read_time = started.elapsed().as_secs_f64();
    let t_match = Instant::now();
    let (r, used, search) = pair.matched(&params)?;
    // The run's matching is timed with its objects (read time included).
    let match_time = t_match.elapsed().as_secs_f64();
    let mut summary = match_summary(&args, settings, &pair, (&r, &used, search));
    summary["timings_s"] = serde_json::json!({ "read": read_time, "matching": match_time });
    let table = output::csv_table(
        &["node_a", "node_b", "cost", "excess"],
        r.pairs.iter().map(|p| {
            vec![
                p.a.to_string(),
                p.b.to_string(),
                format!("{:.6}", p.cost),
                (p.excess as u8).to_string(),
            ]
        }),
    );
    if let Some(dir) = &args.out {
        write_match_folder(dir, &args, &pair, &r, (&table, &summary))?;
    }
    let counts = format!(
        "{} × {} nodes: {} local, {} {}, {} excess matches ({} settings: {})",
        pair.a.len(),
        pair.b.len(),
        r.local_count(),
        r.one_to_one_count(),
        if search == Search::Best {
            "best (many-to-one)"
        } else {
            "one-to-one"
        },
        r.excess_count(),
        settings.name(),
        settings.reason()
    );
    if args.json {
        let mut s = summary;
        s["pairs"] = r
            .pairs
            .iter()
            .map(|p| serde_json::json!({"node_a": p.a, "node_b": p.b, "cost": p.cost, "excess": p.excess}))
            .collect();
        out!("{}", output::pretty(&s)?);
    } else if let Some(out) = &args.out {
        outln!("{counts}");
        outln!("results in {}", output::folder_text(out));
    } else {
        out!("{table}");
        eprintln!("{counts}");
    }
    Ok(())
}

/// `match.json` (without timings): the inputs, the settings and every option as used, and the
/// match's counts.
fn match_summary(
    args: &MatchArgs,
    settings: Settings,
    pair: &LoadedPair,
    (r, used, search): (
        &modal_core::MatchResult,
        &[(&str, modal_core::OptionValue)],
        Search,
    ),
) -> serde_json::Value {
    let (oa, ob) = (&pair.oa, &pair.ob);
    let used: serde_json::Map<String, serde_json::Value> = used
        .iter()
        .map(|(k, v)| (k.to_string(), pedo_output::option_json(v)))
        .chain([("ordered".to_string(), serde_json::json!(pair.ordered))])
        .collect();
    serde_json::json!({
        "pedomatch_version": env!("CARGO_PKG_VERSION"),
        "a": args.a.display().to_string(), "b": args.b.display().to_string(),
        "frame_a": oa.frame(), "frame_b": ob.frame(),
        "time_a_s": oa.time_s, "time_b_s": ob.time_s,
        "pitch_mm_a": oa.pitch_mm, "pitch_mm_b": ob.pitch_mm,
        "settings": settings.name(),
        "settings_reason": settings.reason(),
        "options": used,
        "search": search.to_string(),
        "matches": r.pairs.len(),
        "nodes_a": pair.a.len(), "nodes_b": pair.b.len(),
        "local_matches": r.local_count(), "optimisation_matches": r.one_to_one_count(),
        "excess_matches": r.excess_count(), "crossings": r.crossings,
        "n_modes": r.n_modes, "refits": r.refits,
        "unmatched_a": r.unmatched_a, "unmatched_b": r.unmatched_b,
    })
}

/// `--out DIR`: matches.csv, match.json, the figure and the report, committed whole or not at all.
fn write_match_folder(
    dir: &Path,
    args: &MatchArgs,
    pair: &LoadedPair,
    r: &modal_core::MatchResult,
    (table, summary): (&str, &serde_json::Value),
) -> Result<(), CliError> {
    let outputs = args.outputs.params();
    let dir = OutDir::create(dir)?;
    dir.write("matches.csv", table.as_bytes())?;
    dir.write("match.json", output::pretty(summary)?.as_bytes())?;
    let figure = MatchFigureInput {
        args,
        shapes: (&pair.a, &pair.b),
        objects: (&pair.oa, &pair.ob),
    };
    write_match_figure(
        &dir,
        &figure,
        &r.pairs,
        FigureKinds::of(outputs.figures, outputs.figure_format),
    )?;
    if outputs.report == ReportFormat::Html {
        write_match_report(&dir, &figure, r, summary)?;
    }
    dir.commit()?;
    Ok(())
}

/// A frame asked of a point file is ignored (it holds one object, no frames): say so rather
/// than match what the user did not ask for without a word.
fn warn_if_no_frames(o: &Object, path: &Path, frame: usize, flag: &str) {
    if o.source.is_none() && frame != 0 {
        output::error_line(&format!(
            "pedomatch: warning: {flag} {frame} does not apply to {}: a point file is one object, \
             not a recording of frames",
            path.display()
        ));
    }
}

/// Two inputs that are the same object give a trivial answer (every node onto itself), which
/// is rarely what was meant: most often `--frame` without `--frame-b` on one recording.
fn warn_if_same(a: &Shape, b: &Shape, args: &MatchArgs) {
    if a.dim() == b.dim() && a.coords() == b.coords() {
        output::error_line(&format!(
            "pedomatch: warning: {} and {} are the same object{}; every node matches itself",
            args.a.display(),
            args.b.display(),
            if args.frame_b.is_none() && args.a == args.b {
                " (for two frames of one recording, give --frame-b)"
            } else {
                ""
            }
        ));
    }
}

/// What the match figure shows: the two objects and where they came from.
struct MatchFigureInput<'a> {
    args: &'a MatchArgs,
    shapes: (&'a Shape, &'a Shape),
    objects: (&'a Object, &'a Object),
}

/// `match.png` and/or `match.svg`: A and B labelled by their file names (and frame, when taken
/// from a recording), axes in mm when both objects know the same pitch.
fn write_match_figure(
    dir: &OutDir,
    input: &MatchFigureInput,
    pairs: &[modal_core::MatchPair],
    kinds: pedo_output::FigureKinds,
) -> Result<(), String> {
    let (oa, ob) = input.objects;
    let axes = input.axes();
    let fig = MatchFigure {
        a: input.shapes.0,
        b: input.shapes.1,
        pairs,
        axes: &axes,
        label_a: input.label(&input.args.a, oa),
        label_b: input.label(&input.args.b, ob),
    };
    output::write_figure(dir, "match", kinds, || fig.to_png(), || fig.to_svg())
}

impl MatchFigureInput<'_> {
    /// An object named by its file name, and its frame when taken from a recording.
    fn label(&self, path: &Path, object: &Object) -> ObjectLabel {
        ObjectLabel {
            name: path.file_name().map_or_else(
                || path.display().to_string(),
                |n| n.to_string_lossy().into_owned(),
            ),
            frame: object.frame(),
        }
    }

    /// The axes both objects share: mm only when both agree on the pitch.
    fn axes(&self) -> FigureAxes {
        let (oa, ob) = self.objects;
        let mut axes = oa
            .axes
            .clone()
            .unwrap_or_else(|| FigureAxes::unscaled("file units"));
        if oa.pitch_mm != ob.pitch_mm {
            axes.pitch_mm = None;
        }
        axes
    }
}

/// `report.html`: the pair in physical units with its matches, and the content of `match.json`
/// (inputs, result, options, version, timings) as its header.
fn write_match_report(
    dir: &OutDir,
    input: &MatchFigureInput,
    r: &modal_core::MatchResult,
    summary: &serde_json::Value,
) -> Result<(), String> {
    let (oa, ob) = input.objects;
    let axes = input.axes();
    let name = |path: &Path, o: &Object| {
        let label = input.label(path, o);
        match (label.frame, o.time_s) {
            (Some(f), Some(t)) => format!("{} (frame {f}, {t:.3} s)", label.name),
            (Some(f), None) => format!("{} (frame {f})", label.name),
            _ => label.name,
        }
    };
    let (label_a, label_b) = (name(&input.args.a, oa), name(&input.args.b, ob));
    let pair = pedo_output::html_report::MatchPairInput {
        a: input.shapes.0,
        b: input.shapes.1,
        result: r,
        pitch_mm: axes.pitch_mm,
        data_unit: &axes.data_unit,
        label_a: &label_a,
        label_b: &label_b,
        underlays: [oa, ob].map(|o| {
            o.source.as_ref().map(
                |(recording, frame)| pedo_output::html_report::FrameUnderlay {
                    recording,
                    frame: *frame,
                },
            )
        }),
    };
    let info = pedo_output::html_report::ReportInfo::of_summary(
        format!("{label_a} \u{2192} {label_b}"),
        summary,
    );
    let pitch = match axes.pitch_mm {
        Some(p) => format!("{} × {} mm", p[0], p[1]),
        None => format!("unknown (axes in {})", axes.data_unit),
    };
    let facts = [
        ("A", label_a.clone()),
        ("B", label_b.clone()),
        ("pitch", pitch),
        (
            "nodes",
            format!(
                "A {}, B {} ({}-D)",
                pair.a.len(),
                pair.b.len(),
                pair.a.dim()
            ),
        ),
        (
            "matches",
            format!(
                "{} in all: {} local, {} one-to-one, {} excess; search {}",
                r.pairs.len(),
                r.local_count(),
                r.one_to_one_count(),
                r.excess_count(),
                summary["search"].as_str().unwrap_or("?")
            ),
        ),
        (
            "unmatched",
            format!("A {}, B {}", r.unmatched_a.len(), r.unmatched_b.len()),
        ),
        ("modes", format!("{} (refits {})", r.n_modes, r.refits)),
    ]
    .map(|(k, v)| (k.to_string(), v));
    let html =
        pedo_output::html_report::match_report(&pair, &info, &facts).map_err(|e| e.to_string())?;
    dir.write("report.html", html.as_bytes())
}
