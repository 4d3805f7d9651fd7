//! File input and output shared by the subcommands: small CSV readers and atomic writes.

use pedo_io::figure::{FigureAxes, MatchFigure, ObjectLabel, TracksFigure};
use pedo_io::sequence::{SequenceOptions, SequenceResult};
use std::path::Path;

/// Reads a dense CSV matrix of f64 (comma, semicolon, tab or space separated; `inf`, `-inf` and
/// `nan` accepted so the solver can report them). Returns row-major values and the shape.
pub fn read_cost_csv(path: &Path) -> Result<(Vec<f64>, usize, usize), String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut values = Vec::new();
    let mut cols = None;
    let mut rows = 0;
    for (lineno, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let start = values.len();
        for field in line.split([',', ';', '\t', ' ']) {
            let field = field.trim();
            if field.is_empty() {
                continue;
            }
            let v: f64 = field.parse().map_err(|_| {
                format!("{}:{}: not a number: {field:?}", path.display(), lineno + 1)
            })?;
            values.push(v);
        }
        let n = values.len() - start;
        match cols {
            None => cols = Some(n),
            Some(c) if c != n => {
                return Err(format!(
                    "{}:{}: row has {n} values, the first row has {c}",
                    path.display(),
                    lineno + 1
                ))
            }
            _ => {}
        }
        rows += 1;
    }
    Ok((values, rows, cols.unwrap_or(0)))
}

pub use crate::outdir::OutDir;

/// Formats a CSV table; fields are numbers or identifiers, so no quoting is needed.
pub fn csv_table(header: &[&str], rows: impl IntoIterator<Item = Vec<String>>) -> String {
    let mut s = header.join(",");
    s.push('\n');
    for r in rows {
        s.push_str(&r.join(","));
        s.push('\n');
    }
    s
}

/// Writes every table of a sequence run and its figures (the summary is written by the caller,
/// once the output time is known): pairs.csv/.json, objects.csv, matches.csv, tracks.csv,
/// frames.csv (the per-frame measures of the frames used), figures/.
pub fn write_sequence(
    dir: &OutDir,
    recording: &pedo_io::Recording,
    options: &SequenceOptions,
    r: &SequenceResult,
    (png, svg): (bool, bool),
) -> Result<(), String> {
    use pedo_io::report;
    let pairs = report::pairs_table(recording, r);
    dir.write("pairs.csv", pairs.to_csv().as_bytes())?;
    dir.write("pairs.json", pretty(&pairs.to_json())?.as_bytes())?;
    dir.write(
        "objects.csv",
        report::objects_table(recording, r).to_csv().as_bytes(),
    )?;
    dir.write(
        "matches.csv",
        report::matches_table(recording, r).to_csv().as_bytes(),
    )?;
    dir.write(
        "tracks.csv",
        report::tracks_table(recording, r).to_csv().as_bytes(),
    )?;
    let (start, end) = options.frames.unwrap_or((0, recording.n_frames()));
    let threshold = options.contour.preprocess.threshold.unwrap_or(0.0);
    let frames = report::frames_table(recording, threshold, start, end);
    dir.write("frames.csv", frames.to_csv().as_bytes())?;

    if png || svg {
        write_sequence_figures(dir, recording, r, (png, svg))?;
    }
    Ok(())
}

/// Writes `report.html`, the self-contained interactive report of a sequence run.
pub fn write_report(
    dir: &OutDir,
    name: &str,
    recording: &pedo_io::Recording,
    options: &SequenceOptions,
    r: &SequenceResult,
    used: Vec<(String, String)>,
    timings: Vec<(String, f64)>,
) -> Result<(), String> {
    let info = pedo_report::ReportInfo {
        input: name.to_string(),
        format: recording.format.map(|f| f.name().to_string()),
        version: env!("CARGO_PKG_VERSION").to_string(),
        options: used,
        timings,
        contact_threshold: options.contour.preprocess.threshold.unwrap_or(0.0),
    };
    let html = pedo_report::run_report(recording, r, &info).map_err(|e| e.to_string())?;
    dir.write("report.html", html.as_bytes())
}

/// Writes `animation.gif`: the frames of the run played back with their contours and matches.
pub fn write_animation(
    dir: &OutDir,
    recording: &pedo_io::Recording,
    options: &SequenceOptions,
    r: &SequenceResult,
) -> Result<(), String> {
    let axes = FigureAxes::of_recording(recording);
    let animation = pedo_io::figure::Animation {
        recording,
        result: r,
        axes: &axes,
        frames: options.frames.unwrap_or((0, recording.n_frames())),
    };
    let gif = animation
        .to_gif()
        .map_err(|e| format!("animation.gif: {e}"))?;
    dir.write("animation.gif", &gif)
}

/// Pretty JSON with a final newline.
pub fn pretty<T: serde::Serialize>(v: &T) -> Result<String, String> {
    serde_json::to_string_pretty(v)
        .map(|mut s| {
            s.push('\n');
            s
        })
        .map_err(|e| e.to_string())
}
/// The match figure of every pair (in parallel) and the tracks figure, as PNG and/or SVG.
fn write_sequence_figures(
    dir: &OutDir,
    recording: &pedo_io::Recording,
    r: &SequenceResult,
    (png, svg): (bool, bool),
) -> Result<(), String> {
    use rayon::prelude::*;
    let axes = FigureAxes::of_recording(recording);
    r.pairs.par_iter().try_for_each(|p| -> Result<(), String> {
        let (oa, ob) = (&r.objects[p.a], &r.objects[p.b]);
        let fig = MatchFigure {
            a: &oa.shape,
            b: &ob.shape,
            pairs: &p.result.pairs,
            axes: &axes,
            label_a: ObjectLabel::object(oa.id, oa.frame),
            label_b: ObjectLabel::object(ob.id, ob.frame),
        };
        let stem = format!("figures/pair_{:04}_{:04}", oa.id, ob.id);
        write_figure(dir, &stem, (png, svg), || fig.to_png(), || fig.to_svg())
    })?;
    let peak = recording.peak_image();
    let tracks = TracksFigure {
        result: r,
        peak: &peak,
        axes: &axes,
        min_steps: 3,
        max_tracks: 40,
    };
    write_figure(
        dir,
        "tracks",
        (png, svg),
        || tracks.to_png(),
        || tracks.to_svg(),
    )
}

/// Writes `{stem}.png` and/or `{stem}.svg`.
pub fn write_figure(
    dir: &OutDir,
    stem: &str,
    (png, svg): (bool, bool),
    to_png: impl FnOnce() -> pedo_io::Result<Vec<u8>>,
    to_svg: impl FnOnce() -> pedo_io::Result<String>,
) -> Result<(), String> {
    if png {
        let bytes = to_png().map_err(|e| format!("{stem}.png: {e}"))?;
        dir.write(&format!("{stem}.png"), &bytes)?;
    }
    if svg {
        let text = to_svg().map_err(|e| format!("{stem}.svg: {e}"))?;
        dir.write(&format!("{stem}.svg"), text.as_bytes())?;
    }
    Ok(())
}
