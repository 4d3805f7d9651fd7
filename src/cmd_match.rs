//! `pedomatch match A B`: correspondences between two objects given as images or point files.

use crate::modal_args::ModalArgs;
use crate::output::{self, OutDir};
use clap::{Args, ValueEnum};
use modal_core::{Search, Shape, Topology};
use pedo_io::figure::{FigureAxes, MatchFigure, ObjectLabel};
use pedo_io::sequence::SearchMode;
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct MatchArgs {
    /// First object: a point file (`x,y[,z]` per line) or a pressure image/recording.
    pub a: PathBuf,
    /// Second object, as the first.
    pub b: PathBuf,
    /// Read both inputs as point files even if their extension suggests an image.
    #[arg(long)]
    pub points: bool,
    /// Point files are ordered closed contours (enables the order-keeping excess step).
    #[arg(long)]
    pub closed: bool,
    /// Frame (1-based) to take from a multi-frame recording.
    #[arg(long, default_value_t = 1)]
    pub frame: usize,
    #[command(flatten)]
    pub modal: ModalArgs,
    /// Search strategy: the optimal one-to-one assignment (`global`), mutual best matches
    /// (`local`), or every node of A to its cheapest node of B (`best`: many-to-one, the most
    /// right matches between independently sampled surfaces).
    #[arg(long, value_enum, default_value = "global")]
    pub search: MatchSearchArg,
    /// Write matches.csv, match.json and match.png/svg into this folder instead of printing.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum MatchSearchArg {
    Global,
    Local,
    Best,
}

const POINT_EXTENSIONS: [&str; 4] = ["xy", "xyz", "pts", "txt"];

/// An object from a file: a point file as it is, or the largest contour of a pressure frame.
fn load_object(path: &Path, args: &MatchArgs) -> Result<Shape, String> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let topology = if args.closed {
        Topology::ClosedContour
    } else {
        Topology::None
    };
    let as_points = args.points || POINT_EXTENSIONS.contains(&ext.as_str());
    if as_points {
        return pedo_io::points::read_points(path, topology).map_err(|e| e.to_string());
    }
    // A CSV is a point file when it has 2 or 3 columns, a pressure grid otherwise.
    if ext == "csv" {
        if let Ok(shape) = pedo_io::points::read_points(path, topology.clone()) {
            return Ok(shape);
        }
    }
    let rec = pedo_io::read_recording(path).map_err(|e| e.to_string())?;
    if args.frame == 0 || args.frame > rec.n_frames() {
        return Err(format!(
            "{}: --frame {} is not in 1..={}",
            path.display(),
            args.frame,
            rec.n_frames()
        ));
    }
    let frame = rec.frame(args.frame - 1).map_err(|e| e.to_string())?;
    let opts = pedo_io::ContourOptions {
        resample: pedo_io::Resample::Spacing(1.0),
        include_holes: false,
        ..Default::default()
    };
    let contours =
        pedo_io::contours(&frame, &opts).map_err(|e| format!("{}: {e}", path.display()))?;
    let largest = contours
        .iter()
        .max_by(|x, y| x.area().total_cmp(&y.area()))
        .ok_or_else(|| {
            format!(
                "{}: frame {} has no loaded region",
                path.display(),
                args.frame
            )
        })?;
    largest.to_shape().map_err(|e| e.to_string())
}

pub fn run(args: MatchArgs) -> Result<(), String> {
    let a = load_object(&args.a, &args)?;
    let b = load_object(&args.b, &args)?;
    let params = args.modal.params(if args.search == MatchSearchArg::Local {
        SearchMode::Local
    } else {
        SearchMode::Global
    });
    // The same setting `pymodal.match` picks for these objects (unordered 3-D points: surfaces).
    let mut o = params
        .match_options_for(a.dim(), args.closed)
        .map_err(|e| e.to_string())?;
    if args.search == MatchSearchArg::Best {
        // Recordings have no such mode (their tracks follow one-to-one matches); a pair may.
        o.search = Search::Best;
    }
    let r = modal_core::match_shapes(&a, &b, &o).map_err(|e| e.to_string())?;
    let rows = r.pairs.iter().map(|p| {
        vec![
            p.a.to_string(),
            p.b.to_string(),
            format!("{:.6}", p.cost),
            (p.excess as u8).to_string(),
        ]
    });
    let table = output::csv_table(&["node_a", "node_b", "cost", "excess"], rows);
    let summary = serde_json::json!({
        "a": args.a.display().to_string(), "b": args.b.display().to_string(),
        "search": args.search.to_possible_value().map(|v| v.get_name().to_string()),
        "matches": r.pairs.len(),
        "nodes_a": a.len(), "nodes_b": b.len(),
        "local_matches": r.local_count(), "one_to_one_matches": r.one_to_one_count(),
        "excess_matches": r.excess_count(), "modes": r.n_modes, "refits": r.refits,
        "unmatched_a": r.unmatched_a, "unmatched_b": r.unmatched_b,
    });
    match &args.out {
        None => {
            print!("{table}");
            let primary = if o.search == Search::Best {
                "best (many-to-one)"
            } else {
                "one-to-one"
            };
            eprintln!(
                "{} × {} nodes: {} local, {} {primary}, {} excess matches",
                a.len(),
                b.len(),
                r.local_count(),
                r.one_to_one_count(),
                r.excess_count()
            );
        }
        Some(dir) => {
            let dir = OutDir::create(dir)?;
            dir.write("matches.csv", table.as_bytes())?;
            dir.write("match.json", format!("{summary:#}\n").as_bytes())?;
            write_match_figure(&dir, &args, (&a, &b), &r.pairs, (true, true))?;
            dir.commit()?;
            println!("{summary:#}");
        }
    }
    Ok(())
}

/// `match.png` and/or `match.svg`: A and B labelled by their file names (and frame, when taken
/// from a recording), axes in mm when the recording states its pitch.
fn write_match_figure(
    dir: &OutDir,
    args: &MatchArgs,
    (a, b): (&Shape, &Shape),
    pairs: &[modal_core::MatchPair],
    kinds: (bool, bool),
) -> Result<(), String> {
    let source = |path: &Path| -> (FigureAxes, ObjectLabel) {
        let name = path.file_name().map_or_else(
            || path.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        );
        // The recording was already read successfully by `load_object` when it is one.
        match recording_of(path, args) {
            Some(rec) => (
                FigureAxes::of_recording(&rec),
                // `--frame` counts from 1 here.
                ObjectLabel {
                    name,
                    frame: Some(args.frame.saturating_sub(1)),
                },
            ),
            None => (
                FigureAxes::unscaled("file units"),
                ObjectLabel { name, frame: None },
            ),
        }
    };
    let (axes, label_a) = source(&args.a);
    let (axes_b, label_b) = source(&args.b);
    // Both objects share one pair of axes: mm only when both files agree on the pitch.
    let axes = if axes.pitch_mm == axes_b.pitch_mm {
        axes
    } else {
        FigureAxes {
            pitch_mm: None,
            ..axes
        }
    };
    let fig = MatchFigure {
        a,
        b,
        pairs,
        axes: &axes,
        label_a,
        label_b,
    };
    output::write_figure(dir, "match", kinds, || fig.to_png(), || fig.to_svg())
}

/// The recording behind an image/recording input (`None` for point files).
fn recording_of(path: &Path, args: &MatchArgs) -> Option<pedo_io::Recording> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    if args.points || POINT_EXTENSIONS.contains(&ext.as_str()) {
        return None;
    }
    if ext == "csv" && pedo_io::points::read_points(path, Topology::None).is_ok() {
        return None;
    }
    pedo_io::read_recording(path).ok()
}
