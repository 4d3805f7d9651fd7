//! File input and output shared by the subcommands: small CSV readers and atomic writes.

use pedo_io::figure::{self, Figure};
use pedo_io::sequence::{PairRow, SequenceOptions, SequenceResult, SkippedPair};
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

fn pair_row_json(r: &PairRow) -> serde_json::Value {
    serde_json::json!({
        "id_a": r.id_a, "id_b": r.id_b, "frame_a": r.frame_a + 1, "frame_b": r.frame_b + 1,
        "nodes_a": r.nodes_a, "nodes_b": r.nodes_b,
        "local_matches": r.local_matches, "local_percent": r.local_percent,
        "optimisation_matches": r.optimisation_matches, "optimisation_percent": r.optimisation_percent,
        "excess_matches": r.excess_matches, "mean_cost": r.mean_cost,
    })
}

const PAIR_HEADER: [&str; 14] = [
    "id_a",
    "id_b",
    "frame_a",
    "frame_b",
    "nodes_a",
    "nodes_b",
    "local_matches",
    "local_percent",
    "optimisation_matches",
    "optimisation_percent",
    "excess_matches",
    "mean_cost",
    "status",
    "reason",
];

fn pair_row_csv(r: &PairRow) -> Vec<String> {
    vec![
        r.id_a.to_string(),
        r.id_b.to_string(),
        (r.frame_a + 1).to_string(),
        (r.frame_b + 1).to_string(),
        r.nodes_a.to_string(),
        r.nodes_b.to_string(),
        r.local_matches.to_string(),
        format!("{:.1}", r.local_percent),
        r.optimisation_matches.to_string(),
        format!("{:.1}", r.optimisation_percent),
        r.excess_matches.to_string(),
        format!("{:.6}", r.mean_cost),
        "ok".to_string(),
        String::new(),
    ]
}

/// A pair the run could not match: its identity, empty measures, and why.
fn skipped_pair_csv(r: &SequenceResult, s: &SkippedPair) -> Vec<String> {
    let (oa, ob) = (&r.objects[s.a], &r.objects[s.b]);
    let mut row = vec![
        oa.id.to_string(),
        ob.id.to_string(),
        (oa.frame + 1).to_string(),
        (ob.frame + 1).to_string(),
        oa.shape.len().to_string(),
        ob.shape.len().to_string(),
    ];
    row.extend(std::iter::repeat_n(String::new(), 6));
    row.push("skipped".to_string());
    row.push(csv_quote(&s.reason));
    row
}

/// Quotes a free-text CSV field (RFC 4180): in double quotes, inner quotes doubled.
pub fn csv_quote(field: &str) -> String {
    format!("\"{}\"", field.replace('"', "\"\""))
}

fn skipped_json(r: &SequenceResult) -> serde_json::Value {
    serde_json::json!({
        "frames": r.skipped_frames.iter().map(|s| serde_json::json!({
            "frame": s.frame, "reason": s.reason,
        })).collect::<Vec<_>>(),
        "pairs": r.skipped_pairs.iter().map(|s| serde_json::json!({
            "id_a": r.objects[s.a].id, "id_b": r.objects[s.b].id,
            "frame_a": r.objects[s.a].frame, "frame_b": r.objects[s.b].frame,
            "reason": s.reason,
        })).collect::<Vec<_>>(),
    })
}

/// Writes every result of a sequence run: tables, per-pair matches, tracks, figures, summary.
pub fn write_sequence(
    dir: &OutDir,
    name: &str,
    recording: &pedo_io::Recording,
    options: &SequenceOptions,
    r: &SequenceResult,
    (png, svg): (bool, bool),
) -> Result<(), String> {
    use rayon::prelude::*;
    dir.write(
        "pairs.csv",
        csv_table(
            &PAIR_HEADER,
            r.pairs
                .iter()
                .map(|p| pair_row_csv(&p.row))
                .chain(r.skipped_pairs.iter().map(|s| skipped_pair_csv(r, s))),
        )
        .as_bytes(),
    )?;
    let rows: Vec<_> = r.pairs.iter().map(|p| pair_row_json(&p.row)).collect();
    dir.write("pairs.json", pretty(&rows)?.as_bytes())?;

    let objects = r.objects.iter().map(|o| {
        vec![
            o.id.to_string(),
            (o.frame + 1).to_string(),
            o.index.to_string(),
            o.shape.len().to_string(),
            o.level.map(|l| format!("{l:.3}")).unwrap_or_default(),
        ]
    });
    dir.write(
        "objects.csv",
        csv_table(&["id", "frame", "index", "nodes", "level"], objects).as_bytes(),
    )?;

    let matches = r.pairs.iter().flat_map(|p| {
        let (ia, ib) = (r.objects[p.a].id, r.objects[p.b].id);
        p.result.pairs.iter().map(move |m| {
            vec![
                ia.to_string(),
                ib.to_string(),
                m.a.to_string(),
                m.b.to_string(),
                format!("{:.6}", m.cost),
                (m.excess as u8).to_string(),
            ]
        })
    });
    dir.write(
        "matches.csv",
        csv_table(
            &["id_a", "id_b", "node_a", "node_b", "cost", "excess"],
            matches,
        )
        .as_bytes(),
    )?;

    let dim = r.objects.first().map_or(2, |o| o.shape.dim());
    let mut header = vec!["track", "step", "frame", "object_id", "node", "x", "y"];
    if dim == 3 {
        header.push("z");
    }
    let track_rows = r.tracks.iter().enumerate().flat_map(|(t, tr)| {
        tr.steps.iter().enumerate().map(move |(s, &(o, n))| {
            let obj = &r.objects[o];
            let mut row = vec![
                t.to_string(),
                s.to_string(),
                (obj.frame + 1).to_string(),
                obj.id.to_string(),
                n.to_string(),
            ];
            row.extend(obj.shape.point(n).iter().map(|v| format!("{v:.4}")));
            row
        })
    });
    dir.write("tracks.csv", csv_table(&header, track_rows).as_bytes())?;

    if png || svg {
        let figures: Vec<(String, Figure)> = r
            .pairs
            .par_iter()
            .map(|p| {
                let (oa, ob) = (&r.objects[p.a], &r.objects[p.b]);
                (
                    format!("figures/pair_{:04}_{:04}", oa.id, ob.id),
                    figure::match_figure(&oa.shape, &ob.shape, &p.result.pairs),
                )
            })
            .collect();
        figures
            .par_iter()
            .try_for_each(|(stem, f)| -> Result<(), String> {
                if png {
                    dir.write(&format!("{stem}.png"), &f.to_png())?;
                }
                if svg {
                    dir.write(&format!("{stem}.svg"), f.to_svg().as_bytes())?;
                }
                Ok(())
            })?;
        let tracks = figure::tracks_figure(r, &recording.peak_image(), 3, 40);
        if png {
            dir.write("tracks.png", &tracks.to_png())?;
        }
        if svg {
            dir.write("tracks.svg", tracks.to_svg().as_bytes())?;
        }
    }

    let n = r.pairs.len().max(1) as f64;
    let mean = |f: fn(&PairRow) -> f64| r.pairs.iter().map(|p| f(&p.row)).sum::<f64>() / n;
    let summary = serde_json::json!({
        "recording": name,
        "frames": recording.n_frames(),
        "model": format!("{:?}", options.model).to_lowercase(),
        "objects": r.objects.len(),
        "pairs": r.pairs.len(),
        "tracks": r.tracks.len(),
        "tracks_3_or_more": r.tracks.iter().filter(|t| t.steps.len() >= 3).count(),
        "splits": r.splits.iter().map(|(i, js)| serde_json::json!({
            "id": r.objects[*i].id, "into": js.iter().map(|&j| r.objects[j].id).collect::<Vec<_>>(),
        })).collect::<Vec<_>>(),
        "merges": r.merges.iter().map(|(is, j)| serde_json::json!({
            "ids": is.iter().map(|&i| r.objects[i].id).collect::<Vec<_>>(), "into": r.objects[*j].id,
        })).collect::<Vec<_>>(),
        "skipped": skipped_json(r),
        "mean_local_percent": mean(|p| p.local_percent),
        "mean_optimisation_percent": mean(|p| p.optimisation_percent),
        "mean_cost": mean(|p| p.mean_cost),
        "timings_s": {
            "objects": r.timings.objects.as_secs_f64(),
            "matching": r.timings.matching.as_secs_f64(),
            "tracks": r.timings.tracks.as_secs_f64(),
        },
    });
    dir.write("summary.json", pretty(&summary)?.as_bytes())
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

fn pretty<T: serde::Serialize>(v: &T) -> Result<String, String> {
    serde_json::to_string_pretty(v)
        .map(|mut s| {
            s.push('\n');
            s
        })
        .map_err(|e| e.to_string())
}
