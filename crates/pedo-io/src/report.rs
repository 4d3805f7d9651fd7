//! What a run reports: its tables with physical units where the recording knows them, the
//! per-frame measures, a description of a recording and the provenance summary. The CLI writes
//! these as CSV and JSON, the Python bindings return them as dicts; both build them here.
//!
//! Column names carry their unit: `time_s` (frame × frame interval) when the frame rate is
//! known, `x_mm`/`y_mm` (pixel coordinate × pitch) when the pitch is known, beside the pixel
//! columns `x`/`y` (x = column, y = row, sensel centres at integers). Frames and object ids are
//! 0-based.

use crate::error::{IoError, Result};
use crate::formats::ReadOptions;
use crate::recording::{kpa_per_unit, Format, Recording};
use crate::sequence::{
    honest_step_of, PairMatch, PairObjects, PairRow, RunCounts, RunParams, SequenceObject,
    SequenceOptions, SequenceResult, SkippedPairRow,
};
use modal_core::{MatchPair, OptionValue};
use serde_json::{json, Map, Value};
use sha2::{Digest, Sha256};

/// One field of a table.
#[derive(Debug, Clone, PartialEq)]
pub enum Cell {
    /// An integer: a count, an id or a frame number.
    Int(i64),
    /// A number and the decimals it is written with in CSV.
    Float(f64, usize),
    /// Free text (quoted in CSV when it holds a comma, quote or line break).
    Text(String),
    /// No value (written as an empty CSV field, JSON `null`).
    Empty,
}

impl Cell {
    fn int(v: usize) -> Self {
        Cell::Int(v as i64)
    }
    fn opt(v: Option<f64>, decimals: usize) -> Self {
        v.map_or(Cell::Empty, |v| Cell::Float(v, decimals))
    }
    /// The value as JSON.
    pub fn to_json(&self) -> Value {
        match self {
            Cell::Int(v) => json!(v),
            Cell::Float(v, _) => json!(v),
            Cell::Text(s) => json!(s),
            Cell::Empty => Value::Null,
        }
    }
    fn to_csv(&self) -> String {
        match self {
            Cell::Int(v) => v.to_string(),
            Cell::Float(v, d) => format!("{v:.d$}"),
            Cell::Text(s) if s.contains([',', '"', '\n', '\r']) => {
                // RFC 4180: free text (an error message) in double quotes, inner quotes doubled.
                format!("\"{}\"", s.replace('"', "\"\""))
            }
            Cell::Text(s) => s.clone(),
            Cell::Empty => String::new(),
        }
    }
}

/// A table: named columns (units in the names) and rows of cells.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Table {
    /// Column names, units in the names (`time_s`, `x_mm`).
    pub header: Vec<String>,
    /// Rows, each meant to hold one cell per column of [`header`](Self::header) (not checked).
    pub rows: Vec<Vec<Cell>>,
}

impl Table {
    fn new(header: &[&str]) -> Self {
        Self {
            header: header.iter().map(|s| s.to_string()).collect(),
            rows: Vec::new(),
        }
    }
    fn push_column(&mut self, name: &str) {
        self.header.push(name.to_string());
    }
    /// The table as CSV with a header line (free text quoted as RFC 4180 says).
    pub fn to_csv(&self) -> String {
        let mut s = self.header.join(",");
        s.push('\n');
        for r in &self.rows {
            push_csv_row(&mut s, r);
        }
        s
    }
}

/// Appends one CSV line of `cells` (as [`Table::to_csv`] writes it) to `s`.
pub(crate) fn push_csv_line(s: &mut String, cells: &[Cell]) {
    push_csv_row(s, cells)
}

fn push_csv_row(s: &mut String, cells: &[Cell]) {
    for (k, c) in cells.iter().enumerate() {
        if k > 0 {
            s.push(',');
        }
        s.push_str(&c.to_csv());
    }
    s.push('\n');
}

/// Writes a table as CSV, byte for byte as [`Table::to_csv`] would, from its header and a source
/// of rows (`rows(emit)` calls `emit` for each row in order), without holding the rows: the
/// large tables of a long recording (matches, tracks) go to disk as they are produced.
pub fn write_csv(
    w: &mut dyn std::io::Write,
    header: &[String],
    rows: impl FnOnce(&mut dyn FnMut(Vec<Cell>) -> std::io::Result<()>) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let mut line = header.join(",");
    line.push('\n');
    w.write_all(line.as_bytes())?;
    rows(&mut |cells| {
        line.clear();
        push_csv_row(&mut line, &cells);
        w.write_all(line.as_bytes())
    })
}

impl Table {
    /// The rows as JSON objects keyed by column name.
    pub fn to_json(&self) -> Value {
        Value::Array(
            self.rows
                .iter()
                .map(|r| row_json(&self.header, r))
                .collect(),
        )
    }

    /// Writes [`Table::to_json`] pretty-printed, with a final newline, byte for byte as
    /// `serde_json::to_string_pretty` would, one row at a time: the JSON values of a long
    /// table's cells take several times the memory of the table.
    pub fn write_json(&self, w: &mut dyn std::io::Write) -> std::io::Result<()> {
        let mut rows = JsonRows::new(&self.header);
        for r in &self.rows {
            rows.push(w, r)?;
        }
        rows.finish(w)
    }
}

/// One row as a JSON object keyed by column name.
fn row_json(header: &[String], row: &[Cell]) -> Value {
    let m: Map<String, Value> = header
        .iter()
        .cloned()
        .zip(row.iter().map(Cell::to_json))
        .collect();
    Value::Object(m)
}

/// A JSON array of rows written one at a time, byte for byte as [`Table::write_json`] writes
/// the whole table: for tables whose rows are never all held (a streamed run's `pairs.json`).
pub(crate) struct JsonRows {
    header: Vec<String>,
    rows: usize,
}

impl JsonRows {
    /// An array of objects keyed by these column names.
    pub fn new(header: &[String]) -> Self {
        Self {
            header: header.to_vec(),
            rows: 0,
        }
    }

    /// Writes one row (a cell per column).
    pub fn push(&mut self, w: &mut dyn std::io::Write, row: &[Cell]) -> std::io::Result<()> {
        w.write_all(if self.rows == 0 { b"[\n" } else { b",\n" })?;
        self.rows += 1;
        // One level deeper than alone: every line indented by two spaces (strings hold no
        // line breaks: JSON escapes them).
        let row = serde_json::to_string_pretty(&row_json(&self.header, row))?;
        for (i, line) in row.lines().enumerate() {
            if i > 0 {
                w.write_all(b"\n")?;
            }
            w.write_all(b"  ")?;
            w.write_all(line.as_bytes())?;
        }
        Ok(())
    }

    /// Closes the array (with a final newline).
    pub fn finish(self, w: &mut dyn std::io::Write) -> std::io::Result<()> {
        w.write_all(if self.rows == 0 { b"[]\n" } else { b"\n]\n" })
    }
}

/// The per-pair table: ids, frames (and their times), node counts, the local, optimisation and
/// excess matches, the mean cost, and a status: `ok`, or `skipped` with the reason for a pair that
/// could not be matched (its match columns empty). The matched pairs come first, in order, then
/// the skipped ones.
pub fn pairs_table(recording: &Recording, r: &SequenceResult) -> Table {
    let mut t = pairs_header(recording);
    for p in &r.pairs {
        t.rows.push(pair_cells(recording, &p.row));
    }
    for s in &r.skipped_pairs {
        t.rows
            .push(skipped_pair_cells(recording, &SkippedPairRow::of(r, s)));
    }
    t
}

/// The columns of [`pairs_table`] (no rows).
pub(crate) fn pairs_header(recording: &Recording) -> Table {
    let mut t = Table::new(&["id_a", "id_b", "frame_a", "frame_b"]);
    if recording.dt_s.is_some() {
        t.push_column("time_a_s");
        t.push_column("time_b_s");
    }
    for c in [
        "nodes_a",
        "nodes_b",
        "local_matches",
        "local_percent",
        "optimisation_matches",
        "optimisation_percent",
        "matches_after_excess",
        "mean_cost",
        "trackable_matches",
        "trackable_percent",
        "status",
        "reason",
    ] {
        t.push_column(c);
    }
    t
}

/// The row of [`pairs_table`] of a matched pair.
pub(crate) fn pair_cells(recording: &Recording, row: &PairRow) -> Vec<Cell> {
    let mut cells = pair_objects_cells(recording, &row.objects);
    cells.extend([
        Cell::int(row.local_matches),
        Cell::Float(row.local_percent, 1),
        Cell::int(row.optimisation_matches),
        Cell::Float(row.optimisation_percent, 1),
        Cell::int(row.matches_after_excess),
        Cell::Float(row.mean_cost, 6),
        Cell::int(row.trackable_matches),
        Cell::Float(row.trackable_percent, 1),
        Cell::Text("ok".into()),
        Cell::Empty,
    ]);
    cells
}

/// The row of [`pairs_table`] of a pair that could not be matched.
pub(crate) fn skipped_pair_cells(recording: &Recording, s: &SkippedPairRow) -> Vec<Cell> {
    let mut cells = pair_objects_cells(recording, &s.objects);
    cells.extend(std::iter::repeat_n(Cell::Empty, 8));
    cells.extend([Cell::Text("skipped".into()), Cell::Text(s.reason.clone())]);
    cells
}

/// The leading cells of a [`pairs_table`] row, matched or skipped: `id_a, id_b, frame_a,
/// frame_b`, `time_a_s, time_b_s` when the frame rate is known, `nodes_a, nodes_b`.
fn pair_objects_cells(recording: &Recording, p: &PairObjects) -> Vec<Cell> {
    let frames = [p.frame_a, p.frame_b];
    let mut cells: Vec<Cell> = [p.id_a, p.id_b, p.frame_a, p.frame_b].map(Cell::int).into();
    if recording.dt_s.is_some() {
        cells.extend(frames.map(|f| Cell::opt(recording.time_s(f), 6)));
    }
    cells.extend([p.nodes_a, p.nodes_b].map(Cell::int));
    cells
}

/// Appends `x, y` (pixels) and, when the pitch is known, `x_mm, y_mm` of a point.
fn push_xy(cells: &mut Vec<Cell>, recording: &Recording, x: f64, y: f64, mm: bool) {
    cells.push(Cell::Float(x, 4));
    cells.push(Cell::Float(y, 4));
    if mm {
        let [xm, ym] = recording.to_mm(x, y).unwrap_or([f64::NAN; 2]);
        cells.push(Cell::Float(xm, 4));
        cells.push(Cell::Float(ym, 4));
    }
}

/// The objects: id (0-based, the row index), frame, time, index in the frame (or level index),
/// node count, isobaric level (`level_kpa` in kPa when the pressure units are known, else
/// `level` in the file's units), centroid of the nodes in pixels and mm, and the measures of
/// the sensors inside the outline ([`SequenceObject::measures`], the columns of
/// [`frames_table`]; empty for surfaces).
pub fn objects_table(recording: &Recording, r: &SequenceResult) -> Table {
    let mut t = objects_header(recording);
    for o in &r.objects {
        t.rows.push(object_cells(recording, o));
    }
    t
}

/// The columns of [`objects_table`] (no rows).
pub(crate) fn objects_header(recording: &Recording) -> Table {
    let mut t = Table::new(&["id", "frame"]);
    if recording.dt_s.is_some() {
        t.push_column("time_s");
    }
    let level = match kpa_per_unit(&recording.units) {
        Some(_) => "level_kpa",
        None => "level",
    };
    for c in ["index", "nodes", level, "centroid_x", "centroid_y"] {
        t.push_column(c);
    }
    if recording.pitch_mm.is_some() {
        t.push_column("centroid_x_mm");
        t.push_column("centroid_y_mm");
    }
    push_measure_columns(&mut t, recording);
    t
}

/// The row of [`objects_table`] of one object.
pub(crate) fn object_cells(recording: &Recording, o: &SequenceObject) -> Vec<Cell> {
    let (timed, mm) = (recording.dt_s.is_some(), recording.pitch_mm.is_some());
    let u = measure_units(recording);
    let mut cells = vec![Cell::int(o.id), Cell::int(o.frame)];
    if timed {
        cells.push(Cell::opt(recording.time_s(o.frame), 6));
    }
    cells.extend([
        Cell::int(o.index),
        Cell::int(o.shape.len()),
        // In kPa when the units say how (as frames.csv's peak pressure), so that the levels of
        // a study mixing sensors share one unit.
        Cell::opt(o.level.map(|l| l * u.peak.1), 3),
    ]);
    let n = o.shape.len().max(1) as f64;
    let (cx, cy) = (0..o.shape.len()).fold((0.0, 0.0), |(x, y), i| {
        let p = o.shape.point(i);
        (x + p[0] / n, y + p[1] / n)
    });
    push_xy(&mut cells, recording, cx, cy, mm);
    push_measures(&mut cells, recording, &u, o.measures.as_ref());
    cells
}

/// Every match of every pair: object ids, nodes, cost, excess flag, whether node tracks may
/// follow it (`trackable`: one-to-one and within the step rule of
/// [`crate::track::step_allowed`]), and the in-plane distance between the two nodes in sensels
/// (and mm when the pitch is known).
pub fn matches_table(recording: &Recording, r: &SequenceResult) -> Table {
    let mut t = matches_header(recording, "trackable");
    let Ok(()) = matches_rows::<std::convert::Infallible>(recording, r, &mut |cells| {
        t.rows.push(cells);
        Ok(())
    });
    t
}

/// Every match of every reference pair of drift correction
/// ([`SequenceResult::reference_pairs`]; no rows without drift correction), with the columns of
/// [`matches_table`] but for `trackable` (a rule for consecutive frames), which is `tracked`
/// instead: 1 when a track took the match ([`SequenceResult::reference_tracked`]), else 0.
pub fn reference_matches_table(recording: &Recording, r: &SequenceResult) -> Table {
    let mut t = matches_header(recording, "tracked");
    let Ok(()) = reference_matches_rows::<std::convert::Infallible>(recording, r, &mut |cells| {
        t.rows.push(cells);
        Ok(())
    });
    t
}

/// The columns of [`matches_table`] (`flag` `trackable`) and [`reference_matches_table`]
/// (`flag` `tracked`), no rows.
pub(crate) fn matches_header(recording: &Recording, flag: &str) -> Table {
    let mut t = Table::new(&[
        "id_a", "id_b", "node_a", "node_b", "cost", "excess", flag, "distance",
    ]);
    if recording.pitch_mm.is_some() {
        t.push_column("distance_mm");
    }
    t
}

/// The rows of [`matches_table`], one by one to `emit`.
pub(crate) fn matches_rows<E>(
    recording: &Recording,
    r: &SequenceResult,
    emit: &mut dyn FnMut(Vec<Cell>) -> std::result::Result<(), E>,
) -> std::result::Result<(), E> {
    for p in &r.pairs {
        pair_match_rows(recording, p, &r.objects[p.a], &r.objects[p.b], emit)?;
    }
    Ok(())
}

/// The rows of [`reference_matches_table`], one by one to `emit`.
pub(crate) fn reference_matches_rows<E>(
    recording: &Recording,
    r: &SequenceResult,
    emit: &mut dyn FnMut(Vec<Cell>) -> std::result::Result<(), E>,
) -> std::result::Result<(), E> {
    for (p, tracked) in r.reference_pairs.iter().zip(r.reference_tracked()) {
        let (oa, ob) = (&r.objects[p.a], &r.objects[p.b]);
        reference_pair_rows(recording, p, oa, ob, &tracked, emit)?;
    }
    Ok(())
}

/// The rows of [`reference_matches_table`] of one reference pair (`oa`, `ob` its two objects,
/// `tracked` its matches' flags as [`SequenceResult::reference_tracked`] gives them), one by one
/// to `emit`.
pub(crate) fn reference_pair_rows<E>(
    recording: &Recording,
    p: &PairMatch,
    oa: &SequenceObject,
    ob: &SequenceObject,
    tracked: &[bool],
    emit: &mut dyn FnMut(Vec<Cell>) -> std::result::Result<(), E>,
) -> std::result::Result<(), E> {
    let tracked = |k: usize, _: &MatchPair| tracked.get(k).copied().unwrap_or(false);
    flagged_match_rows(recording, p, oa, ob, &tracked, emit)
}

/// The rows of [`matches_table`] of one pair (`oa`, `ob` its two objects), one by one to `emit`.
pub(crate) fn pair_match_rows<E>(
    recording: &Recording,
    p: &PairMatch,
    oa: &SequenceObject,
    ob: &SequenceObject,
    emit: &mut dyn FnMut(Vec<Cell>) -> std::result::Result<(), E>,
) -> std::result::Result<(), E> {
    let trackable = |_, m: &MatchPair| !m.excess && honest_step_of(oa, m.a, ob, m.b);
    flagged_match_rows(recording, p, oa, ob, &trackable, emit)
}

/// The rows of one pair's matches as [`matches_header`] lays them out, the flag column of
/// match `k` (in `p.result.pairs`) `flag(k, match)`.
fn flagged_match_rows<E>(
    recording: &Recording,
    p: &PairMatch,
    oa: &SequenceObject,
    ob: &SequenceObject,
    flag: &dyn Fn(usize, &MatchPair) -> bool,
    emit: &mut dyn FnMut(Vec<Cell>) -> std::result::Result<(), E>,
) -> std::result::Result<(), E> {
    for (k, m) in p.result.pairs.iter().enumerate() {
        let (pa, pb) = (oa.shape.point(m.a), ob.shape.point(m.b));
        let (dx, dy) = (pb[0] - pa[0], pb[1] - pa[1]);
        let mut cells = vec![
            Cell::int(oa.id),
            Cell::int(ob.id),
            Cell::int(m.a),
            Cell::int(m.b),
            Cell::Float(m.cost, 6),
            Cell::int(m.excess as usize),
            Cell::int(flag(k, m) as usize),
            Cell::Float(dx.hypot(dy), 4),
        ];
        if let Some(p) = recording.pitch_mm {
            cells.push(Cell::Float((dx * p[0]).hypot(dy * p[1]), 4));
        }
        emit(cells)?;
    }
    Ok(())
}

/// The node tracks, one row per step: track, step, frame, time, object id, node, `x, y[, z]`
/// (pixels; `z` the pressure of a surface node) and `x_mm, y_mm` when the pitch is known.
pub fn tracks_table(recording: &Recording, r: &SequenceResult) -> Table {
    let mut t = tracks_header(recording, r);
    let Ok(()) = tracks_rows::<std::convert::Infallible>(recording, r, &mut |cells| {
        t.rows.push(cells);
        Ok(())
    });
    t
}

/// The columns of [`tracks_table`] (no rows).
pub(crate) fn tracks_header(recording: &Recording, r: &SequenceResult) -> Table {
    tracks_header_of(recording, r.objects.first().map_or(2, |o| o.shape.dim()))
}

/// The columns of [`tracks_table`] for objects of `dim` dimensions (those of the first object,
/// 2 without objects).
pub(crate) fn tracks_header_of(recording: &Recording, dim: usize) -> Table {
    let (timed, mm) = (recording.dt_s.is_some(), recording.pitch_mm.is_some());
    let mut t = Table::new(&["track", "step", "frame"]);
    if timed {
        t.push_column("time_s");
    }
    for c in ["object_id", "node", "x", "y"] {
        t.push_column(c);
    }
    if mm {
        t.push_column("x_mm");
        t.push_column("y_mm");
    }
    if dim == 3 {
        t.push_column("z");
    }
    t
}

/// The rows of [`tracks_table`], one by one to `emit`.
pub(crate) fn tracks_rows<E>(
    recording: &Recording,
    r: &SequenceResult,
    emit: &mut dyn FnMut(Vec<Cell>) -> std::result::Result<(), E>,
) -> std::result::Result<(), E> {
    let dim = r.objects.first().map_or(2, |o| o.shape.dim());
    for (k, tr) in r.all_tracks().enumerate() {
        let steps: Vec<(&SequenceObject, usize)> =
            tr.steps.iter().map(|&(o, n)| (&r.objects[o], n)).collect();
        track_rows(recording, k, &steps, dim, emit)?;
    }
    Ok(())
}

/// The rows of [`tracks_table`] of track `k` (its steps as object and node; `dim` that of
/// [`tracks_header_of`]), one by one to `emit`.
pub(crate) fn track_rows<E>(
    recording: &Recording,
    k: usize,
    steps: &[(&SequenceObject, usize)],
    dim: usize,
    emit: &mut dyn FnMut(Vec<Cell>) -> std::result::Result<(), E>,
) -> std::result::Result<(), E> {
    let (timed, mm) = (recording.dt_s.is_some(), recording.pitch_mm.is_some());
    for (s, &(obj, n)) in steps.iter().enumerate() {
        let p = obj.shape.point(n);
        let mut cells = vec![Cell::int(k), Cell::int(s), Cell::int(obj.frame)];
        if timed {
            cells.push(Cell::opt(recording.time_s(obj.frame), 6));
        }
        cells.extend([Cell::int(obj.id), Cell::int(n)]);
        push_xy(&mut cells, recording, p[0], p[1], mm);
        if dim == 3 {
            cells.push(Cell::Float(p[2], 4));
        }
        emit(cells)?;
    }
    Ok(())
}

/// The names and unit factors of the measures' columns for this recording.
struct MeasureUnits {
    area: (&'static str, f64),
    force: &'static str,
    peak: (&'static str, f64),
}

fn measure_units(recording: &Recording) -> MeasureUnits {
    MeasureUnits {
        area: match recording.sensel_area() {
            Some(_) => ("contact_area_mm2", 1.0),
            None => ("contact_area_sensels", 1.0),
        },
        // Without known pressure units the load is the values' sum times the sensel area: its
        // unit is the file's units times mm² (or times sensels without a pitch), and the name
        // says which, so that a study mixing both never compares them in one column.
        force: match (recording.force_factor(), recording.sensel_area()) {
            (Some(_), _) => "total_force_n",
            (None, Some(_)) => "total_load_mm2",
            (None, None) => "total_load_sensels",
        },
        peak: match kpa_per_unit(&recording.units) {
            Some(k) => ("peak_pressure_kpa", k),
            None => ("peak_pressure", 1.0),
        },
    }
}

/// The per-frame measures of frames `start..end` counting values at or above `threshold` (and
/// above 0, [`Recording::measures`]): frame,
/// time, contact sensors, contact area (mm² when the sensel area is known), total force (N when
/// the pressure units and the sensel area are known), peak pressure (kPa when the units are
/// known), centre of pressure in pixels and mm.
pub fn frames_table(recording: &Recording, threshold: f64, start: usize, end: usize) -> Table {
    let mut t = frames_header(recording);
    let Ok(()) =
        frames_rows::<std::convert::Infallible>(recording, threshold, start, end, &mut |cells| {
            t.rows.push(cells);
            Ok(())
        });
    t
}

/// The columns of [`frames_table`] (no rows).
pub(crate) fn frames_header(recording: &Recording) -> Table {
    let mut t = Table::new(&["frame"]);
    if recording.dt_s.is_some() {
        t.push_column("time_s");
    }
    push_measure_columns(&mut t, recording);
    t
}

/// The columns of [`FrameMeasures`](crate::recording::FrameMeasures), named by their units.
fn push_measure_columns(t: &mut Table, recording: &Recording) {
    let u = measure_units(recording);
    for c in [
        "contact_sensors",
        u.area.0,
        u.force,
        u.peak.0,
        "cop_x",
        "cop_y",
    ] {
        t.push_column(c);
    }
    if recording.pitch_mm.is_some() {
        t.push_column("cop_x_mm");
        t.push_column("cop_y_mm");
    }
}

/// The cells of [`push_measure_columns`]'s columns: `m`'s, or empty cells without measures.
fn push_measures(
    cells: &mut Vec<Cell>,
    recording: &Recording,
    u: &MeasureUnits,
    m: Option<&crate::recording::FrameMeasures>,
) {
    let mm = recording.pitch_mm.is_some();
    let xy = if mm { 4 } else { 2 };
    let Some(m) = m else {
        cells.extend(std::iter::repeat_n(Cell::Empty, 4 + xy));
        return;
    };
    cells.extend([
        Cell::int(m.contact_sensors),
        Cell::Float(m.contact_area * u.area.1, 4),
        Cell::Float(m.total_force, 4),
        Cell::Float(m.peak_pressure * u.peak.1, 4),
    ]);
    match m.cop {
        Some([x, y]) => push_xy(cells, recording, x, y, mm),
        None => cells.extend(std::iter::repeat_n(Cell::Empty, xy)),
    }
}

/// The rows of [`frames_table`], one by one to `emit`.
pub(crate) fn frames_rows<E>(
    recording: &Recording,
    threshold: f64,
    start: usize,
    end: usize,
    emit: &mut dyn FnMut(Vec<Cell>) -> std::result::Result<(), E>,
) -> std::result::Result<(), E> {
    let measures = recording.measures_of(threshold, start..end);
    measures_rows(recording, start, &measures, emit)
}

/// The rows of [`frames_table`] of frames `first..first + measures.len()` of `recording`
/// (their measures given), one by one to `emit`.
pub(crate) fn measures_rows<E>(
    recording: &Recording,
    first: usize,
    measures: &[crate::recording::FrameMeasures],
    emit: &mut dyn FnMut(Vec<Cell>) -> std::result::Result<(), E>,
) -> std::result::Result<(), E> {
    let u = measure_units(recording);
    for (k, m) in measures.iter().enumerate() {
        let f = first + k;
        let mut cells = vec![Cell::int(f)];
        if recording.dt_s.is_some() {
            cells.push(Cell::opt(recording.time_s(f), 6));
        }
        push_measures(&mut cells, recording, &u, Some(m));
        emit(cells)?;
    }
    Ok(())
}

/// Where a recording came from: a name (the path as given) and, for files, the SHA-256 of its
/// bytes.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct InputInfo {
    /// The input's name: its path as given, or the name given to in-memory data.
    pub name: String,
    /// Lower-case hex SHA-256 of the input's bytes; `None` for in-memory arrays.
    pub sha256: Option<String>,
    /// The pedar sensor-layout file a pedar recording was read with (`--layout`), its name and
    /// SHA-256 ([`InputInfo::with_layout`]); `None` for the bundled layout and other formats.
    pub layout: Option<Box<InputInfo>>,
}

impl InputInfo {
    /// The name and hash of bytes read from `name`.
    pub fn of_bytes(name: &str, bytes: &[u8]) -> Self {
        Self {
            name: name.to_string(),
            sha256: Some(sha256_hex(bytes)),
            layout: None,
        }
    }

    /// This input with the layout file of `read` when the recording read is a pedar one
    /// (`format`): its sensors' places, and so every result, depend on that file's content.
    pub fn with_layout(mut self, read: &ReadOptions, format: Option<Format>) -> Result<Self> {
        if format == Some(Format::Pedar)
            && let Some(layout) = &read.layout
        {
            self.layout = Some(Box::new(Self::of_path(layout)?));
        }
        Ok(self)
    }

    /// The name and hash of a file, or of every file of a folder in name order (an image
    /// sequence), hashed in that order. A numbered-sequence pattern (`walk_%03d.png`) names no
    /// single file and gets no hash.
    pub fn of_path(path: &std::path::Path) -> Result<Self> {
        if !path.exists() {
            return Ok(Self {
                name: path.display().to_string(),
                ..Self::default()
            });
        }
        let io = |e| IoError::Io {
            path: path.display().to_string(),
            source: e,
        };
        let mut hasher = Sha256::new();
        if path.is_dir() {
            let mut files: Vec<_> = std::fs::read_dir(path)
                .map_err(io)?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.is_file())
                .collect();
            files.sort();
            for f in files {
                hash_file(&mut hasher, &f).map_err(io)?;
            }
        } else {
            hash_file(&mut hasher, path).map_err(io)?;
        }
        Ok(Self {
            name: path.display().to_string(),
            sha256: Some(hex(&hasher.finalize())),
            layout: None,
        })
    }
}

/// Feeds a file to `hasher` piece by piece (a long recording is not read twice into memory).
fn hash_file(hasher: &mut Sha256, path: &std::path::Path) -> std::io::Result<()> {
    use std::io::Read;
    let mut file = std::fs::File::open(path)?;
    let mut buf = vec![0u8; 1 << 16];
    loop {
        match file.read(&mut buf) {
            Ok(0) => return Ok(()),
            Ok(n) => hasher.update(&buf[..n]),
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// `n` and a noun, in the singular for one and with a plain `s` otherwise: the counts of the
/// messages and terminal lines.
///
/// ```
/// use pedo_io::report::counted;
/// assert_eq!(counted(1, "recording"), "1 recording");
/// assert_eq!(counted(0, "isobaric level"), "0 isobaric levels");
/// ```
pub fn counted(n: usize, noun: &str) -> String {
    if n == 1 {
        format!("1 {noun}")
    } else {
        format!("{n} {noun}s")
    }
}

/// Lower-case hex SHA-256 of `bytes`.
///
/// ```
/// assert_eq!(
///     pedo_io::report::sha256_hex(b"abc"),
///     "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
/// );
/// ```
pub fn sha256_hex(bytes: &[u8]) -> String {
    hex(&Sha256::digest(bytes))
}

/// An option value as JSON.
pub fn option_json(v: &OptionValue) -> Value {
    match v {
        OptionValue::Absent => Value::Null,
        OptionValue::Bool(b) => json!(b),
        OptionValue::Int(i) => json!(i),
        OptionValue::Float(f) => json!(f),
        OptionValue::Word(w) => json!(w),
        OptionValue::Numbers(v) => json!(v),
    }
}

fn min_mean_max(values: impl Iterator<Item = f64>) -> Value {
    let v: Vec<f64> = values.collect();
    if v.is_empty() {
        return Value::Null;
    }
    let min = v.iter().copied().fold(f64::INFINITY, f64::min);
    let max = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    json!({"min": min, "mean": v.iter().sum::<f64>() / v.len() as f64, "max": max})
}

/// What a recording holds: format, size, pitch, frame rate, units, noise threshold and the
/// min / mean / max over all frames of the per-frame measures at or above `threshold` (as in
/// [`frames_table`]; the unit is in each measure's name).
pub fn describe(recording: &Recording, input: &InputInfo, threshold: f64) -> Value {
    let u = measure_units(recording);
    let m = recording.measures(threshold);
    let loaded = m.iter().filter(|x| x.contact_sensors > 0).count();
    let mut measures = Map::new();
    measures.insert(
        u.area.0.into(),
        min_mean_max(m.iter().map(|x| x.contact_area * u.area.1)),
    );
    measures.insert(
        u.force.into(),
        min_mean_max(m.iter().map(|x| x.total_force)),
    );
    measures.insert(
        u.peak.0.into(),
        min_mean_max(m.iter().map(|x| x.peak_pressure * u.peak.1)),
    );
    json!({
        "file": input.name,
        "sha256": input.sha256,
        "format": recording.format.map(|f| f.name()),
        "frames": recording.n_frames(),
        "rows": recording.rows(),
        "cols": recording.cols(),
        "sensors": recording.n_sensors(),
        "pitch_mm": recording.pitch_mm,
        "sensel_area_mm2": recording.sensel_area(),
        "frame_rate_hz": recording.frame_rate(),
        "duration_s": recording.dt_s.map(|dt| dt * recording.n_frames() as f64),
        "pressure_units": recording.known_units(),
        "noise_threshold": recording.noise_threshold,
        "measures_threshold": threshold,
        "loaded_frames": loaded,
        "measures": measures,
    })
}

/// The provenance and outcome of a run, as written to `summary.json` and returned by
/// `pymodal.run`: the pedomatch version, the input (name, SHA-256, format), the recording's
/// size and units, every option actually used (defaults included), the counts and means of the
/// results, and the seconds spent in each stage (`timings`: the stages measured outside the
/// sequence run, e.g. reading, are passed in and come first).
pub fn run_summary(
    input: &InputInfo,
    recording: &Recording,
    params: &RunParams,
    options: &SequenceOptions,
    r: &SequenceResult,
    timings: &[(&str, f64)],
) -> Value {
    run_summary_of(
        input,
        recording,
        params,
        options,
        &RunCounts::of(r),
        timings,
    )
}

/// [`run_summary`] from the counts of a run ([`RunCounts`]: what a streamed run keeps).
pub fn run_summary_of(
    input: &InputInfo,
    recording: &Recording,
    params: &RunParams,
    options: &SequenceOptions,
    c: &RunCounts,
    timings: &[(&str, f64)],
) -> Value {
    let used: Map<String, Value> = params
        .used(options, recording)
        .iter()
        .map(|(k, v)| (k.to_string(), option_json(v)))
        .collect();
    let mut stages: Map<String, Value> = timings
        .iter()
        .map(|(k, v)| (k.to_string(), json!(v)))
        .collect();
    stages.insert("objects".into(), json!(c.timings.objects.as_secs_f64()));
    stages.insert("matching".into(), json!(c.timings.matching.as_secs_f64()));
    stages.insert("tracks".into(), json!(c.timings.tracks.as_secs_f64()));
    // Object ids are their indices.
    json!({
        "pedomatch_version": env!("CARGO_PKG_VERSION"),
        "input": {
            "file": input.name,
            "sha256": input.sha256,
            "format": recording.format.map(|f| f.name()),
            "layout": input.layout.as_ref().map(|l| json!({"file": l.name, "sha256": l.sha256})),
        },
        "recording": {
            "frames": recording.n_frames(),
            "rows": recording.rows(),
            "cols": recording.cols(),
            "pitch_mm": recording.pitch_mm,
            "frame_rate_hz": recording.frame_rate(),
            "pressure_units": recording.known_units(),
        },
        "options": used,
        "objects": c.objects,
        "pairs": c.pairs,
        "tracks": c.tracks,
        "tracks_3_or_more": c.tracks_3_or_more,
        "splits": c.splits.iter().map(|(i, js)| json!({
            "id": i, "into": js,
        })).collect::<Vec<_>>(),
        "merges": c.merges.iter().map(|(is, j)| json!({
            "ids": is, "into": j,
        })).collect::<Vec<_>>(),
        "skipped": {
            "frames": c.skipped_frames.iter().map(|s| json!({
                "frame": s.frame, "reason": s.reason,
            })).collect::<Vec<_>>(),
            "pairs": c.skipped_pairs.iter().map(|s| json!({
                "id_a": s.objects.id_a, "id_b": s.objects.id_b,
                "frame_a": s.objects.frame_a, "frame_b": s.objects.frame_b,
                "reason": s.reason,
            })).collect::<Vec<_>>(),
        },
        "mean_local_percent": c.mean_local_percent(),
        "mean_optimisation_percent": c.mean_optimisation_percent(),
        "mean_cost": c.mean_cost(),
        "mean_trackable_percent": c.mean_trackable_percent(),
        "timings_s": stages,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_table_has_units_when_known() {
        let mut rec = Recording::new(
            2,
            2,
            2,
            vec![0., 10., 0., 30., 0., 0., 0., 0.],
            vec![true; 4],
        )
        .unwrap();
        let plain = frames_table(&rec, 0.0, 0, 2);
        assert_eq!(
            plain.header,
            [
                "frame",
                "contact_sensors",
                "contact_area_sensels",
                "total_load_sensels",
                "peak_pressure",
                "cop_x",
                "cop_y"
            ]
        );
        rec.pitch_mm = Some([2.0, 2.0]);
        // A pitch without pressure units: the load in the file's units × mm² (40 × 4), named so.
        let unitless = frames_table(&rec, 0.0, 0, 2);
        assert_eq!(
            unitless.header[2..4],
            ["contact_area_mm2", "total_load_mm2"]
        );
        assert!(matches!(unitless.rows[0][3], Cell::Float(f, _) if f == 160.0));
        rec.dt_s = Some(0.5);
        rec.units = "N/cm2".into();
        let t = frames_table(&rec, 0.0, 0, 2);
        assert_eq!(t.header[1], "time_s");
        assert_eq!(
            t.header[3..6],
            ["contact_area_mm2", "total_force_n", "peak_pressure_kpa"]
        );
        let row = &t.rows[0];
        assert_eq!(row[3], Cell::Float(8.0, 4)); // 2 sensels of 4 mm²
                                                 // 40 N/cm² in all = 400 kPa on sensels of 4 mm²: 400 × 4 × 1e-3 = 1.6 N.
        assert!(
            matches!(row[4], Cell::Float(f, 4) if (f - 1.6).abs() < 1e-12),
            "{:?}",
            row[4]
        );
        assert_eq!(row[5], Cell::Float(300.0, 4));
        assert_eq!(t.rows[1][1], Cell::Float(0.5, 6));
        assert_eq!(t.rows[1][6], Cell::Empty, "no load, no centre of pressure");
        let csv = t.to_csv();
        assert!(csv.starts_with("frame,time_s,"), "{csv}");
    }
}

#[cfg(test)]
mod csv_tests {
    use super::*;

    #[test]
    fn streamed_csv_equals_the_whole_table() {
        let mut t = Table::new(&["a", "b", "c"]);
        t.rows
            .push(vec![Cell::Int(1), Cell::Float(2.5, 3), Cell::Empty]);
        t.rows.push(vec![
            Cell::Text("x, \"y\"".into()),
            Cell::Int(-4),
            Cell::Float(0.1, 1),
        ]);
        let mut out = Vec::new();
        write_csv(&mut out, &t.header, |emit| {
            t.rows.iter().try_for_each(|r| emit(r.clone()))
        })
        .unwrap();
        assert_eq!(String::from_utf8(out).unwrap(), t.to_csv());
        assert_eq!(t.to_csv(), "a,b,c\n1,2.500,\n\"x, \"\"y\"\"\",-4,0.1\n");
    }

    #[test]
    fn streamed_json_equals_the_whole_table_pretty_printed() {
        let whole = |t: &Table| serde_json::to_string_pretty(&t.to_json()).unwrap() + "\n";
        let streamed = |t: &Table| {
            let mut out = Vec::new();
            t.write_json(&mut out).unwrap();
            String::from_utf8(out).unwrap()
        };
        let mut t = Table::new(&["a", "b", "c"]);
        assert_eq!(streamed(&t), whole(&t));
        t.rows
            .push(vec![Cell::Int(1), Cell::Float(2.5, 3), Cell::Empty]);
        t.rows.push(vec![
            Cell::Text("two\nlines, \"quoted\"".into()),
            Cell::Int(-4),
            Cell::Float(0.1, 1),
        ]);
        assert_eq!(streamed(&t), whole(&t));
        assert!(streamed(&t).starts_with("[\n  {\n    \"a\": 1,"));
    }
}
