//! The tables of a run with physical units where the recording knows them, the
//! per-frame measures, a description of a recording and the provenance summary. The CLI writes
//! these as CSV and JSON, the Python bindings return them as dicts; both build them here.
//!
//! Column names carry their unit: `time_s` (frame × frame interval) when the frame rate is
//! known, `x_mm`/`y_mm` (pixel coordinate × pitch) when the pitch is known, beside the pixel
//! columns `x`/`y` (x = column, y = row, sensel centres at integers). Frames and object ids are
//! 0-based.

use crate::*;
use modal_core::MatchPair;
use pedo_io::recording::{kpa_per_unit, Recording};
use pedo_track::{PairMatch, PairObjects, PairRow, SequenceObject, SequenceResult, SkippedPairRow};

/// The per-pair table: ids, frames (and their times), node counts, the local, optimisation and
/// excess matches, the mean cost, the trackable matches, the crossed pairs of matches (closed
/// contours), and a status: `ok`, or `skipped` with the reason for a pair that
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
        "crossings",
        "field_residual_sensels",
        "round_trip_sensels",
        "round_trip_p95_sensels",
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
        row.crossings.map_or(Cell::Empty, Cell::int),
    ]);
    let c = row.consistency;
    cells.extend([
        Cell::opt(c.map(|c| c.field_residual), 4),
        Cell::opt(c.map(|c| c.round_trip), 4),
        Cell::opt(c.map(|c| c.round_trip_p95), 4),
        Cell::Text("ok".into()),
        Cell::Empty,
    ]);
    cells
}

/// The row of [`pairs_table`] of a pair that could not be matched.
pub(crate) fn skipped_pair_cells(recording: &Recording, s: &SkippedPairRow) -> Vec<Cell> {
    let mut cells = pair_objects_cells(recording, &s.objects);
    cells.extend(std::iter::repeat_n(Cell::Empty, 12));
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
    let [cx, cy] = o.centroid();
    push_xy(&mut cells, recording, cx, cy, mm);
    push_measures(&mut cells, recording, &u, o.measures.as_ref());
    cells
}

/// Every match of every pair: object ids, nodes, cost, excess flag, whether node tracks may
/// follow it (`trackable`: one-to-one and within the step rule of
/// [`pedo_track::pairing::StepBound`], [`pedo_track::PairMatch::trackable`]), and the in-plane distance between the two nodes in sensels
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
    let trackable =
        |k: usize, m: &MatchPair| !m.excess && p.trackable.get(k).copied().unwrap_or(false);
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
/// (pixels; `z` the pressure of a surface node), `x_mm, y_mm` when the pitch is known and, for
/// outlines (contours, isocontours), the track's `round_trip_sensels` on each of its rows
/// ([`pedo_track::chain_tracks_checked`]; empty when it has none).
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
    let mut t = steps_header(recording, "track", "node");
    if dim == 3 {
        t.push_column("z");
    } else {
        t.push_column("round_trip_sensels");
    }
    t
}

/// The columns shared by the tables of things followed step by step (tracks, points): `what`
/// (their number), step, frame, time when the rate is known, object id, `node`, `x, y` and
/// `x_mm, y_mm` when the pitch is known.
fn steps_header(recording: &Recording, what: &str, node: &str) -> Table {
    let mut t = Table::new(&[what, "step", "frame"]);
    if recording.dt_s.is_some() {
        t.push_column("time_s");
    }
    for c in ["object_id", node, "x", "y"] {
        t.push_column(c);
    }
    if recording.pitch_mm.is_some() {
        t.push_column("x_mm");
        t.push_column("y_mm");
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
        track_rows(recording, k, &steps, dim, r.track_round_trip(k), emit)?;
    }
    Ok(())
}

/// The rows of [`tracks_table`] of track `k` (its steps as object and node; `dim` that of
/// [`tracks_header_of`]; `round_trip` its round trip), one by one to `emit`.
pub(crate) fn track_rows<E>(
    recording: &Recording,
    k: usize,
    steps: &[(&SequenceObject, usize)],
    dim: usize,
    round_trip: Option<f64>,
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
        } else {
            cells.push(Cell::opt(round_trip, 4));
        }
        emit(cells)?;
    }
    Ok(())
}

/// The material points followed by anchored registration ([`pedo_track::follow`]), one row per
/// point and frame: point, step, frame, time, object id, the outline node the point was seeded
/// on (empty for a point given by position), `x, y` (pixels) and `x_mm, y_mm` when the pitch is
/// known, the pressure under the point (bilinear between sensel centres; `pressure_kpa`
/// when the units are known, else `pressure` in the file's units), its `kind` (`outline`: a
/// default point seeded on an outline node; `user`: a point the user gave) and `name` (a user
/// point's, from `inputs`; empty for the outline's) and its `round_trip_sensels` on that frame
/// ([`pedo_track::follow::FollowedPoint::round_trips`]; empty on its seed frame). The points of
/// the user's regions are not rows ([`regions_table`]); `point` numbers the rows' points from 0.
///
/// # Errors
/// A frame of a step that the recording cannot give (never for the run's own points).
pub fn points_table(
    recording: &Recording,
    r: &SequenceResult,
    points: &pedo_track::follow::FollowedPoints,
    inputs: &pedo_track::UserInputs,
) -> pedo_io::Result<Table> {
    let mut t = points_header(recording);
    let mut rows = PointRows::new(recording, inputs);
    for p in &points.points {
        let frames: Vec<usize> = p.steps.iter().map(|&(o, _)| r.objects[o].frame).collect();
        rows.point(p, &frames, &mut |cells| {
            t.rows.push(cells);
            Ok(())
        })?;
    }
    Ok(t)
}

/// The columns of [`points_table`] (no rows).
pub fn points_header(recording: &Recording) -> Table {
    let mut t = steps_header(recording, "point", "seed_node");
    t.push_column(match kpa_per_unit(&recording.units) {
        Some(_) => "pressure_kpa",
        None => "pressure",
    });
    t.push_column("kind");
    t.push_column("name");
    t.push_column("round_trip_sensels");
    t
}

/// The rows of [`points_table`], point by point in the order followed: the pressure under each
/// step read from the frames from the current point's first on (a point is seeded on its first
/// frame, and points are seeded in frame order), each frame read once.
pub(crate) struct PointRows<'a> {
    recording: &'a Recording,
    inputs: &'a pedo_track::UserInputs,
    /// The points given rows so far.
    rows: usize,
    /// The round trips of the rows so far (their summary is `summary.json`'s
    /// `point_round_trip_sensels`).
    pub(crate) round_trips: Vec<f32>,
    grids: std::collections::BTreeMap<usize, pedo_io::Grid>,
}

impl<'a> PointRows<'a> {
    pub(crate) fn new(recording: &'a Recording, inputs: &'a pedo_track::UserInputs) -> Self {
        Self {
            recording,
            inputs,
            rows: 0,
            round_trips: Vec::new(),
            grids: Default::default(),
        }
    }

    /// The rows of point `p`, the frame of each step in `frames`, one by one to `emit` (none
    /// for a region's point).
    pub(crate) fn point(
        &mut self,
        p: &pedo_track::follow::FollowedPoint,
        frames: &[usize],
        emit: &mut dyn FnMut(Vec<Cell>) -> pedo_io::Result<()>,
    ) -> pedo_io::Result<()> {
        use pedo_track::follow::Seeded;
        let recording = self.recording;
        let (timed, mm) = (recording.dt_s.is_some(), recording.pitch_mm.is_some());
        let per_unit = kpa_per_unit(&recording.units).unwrap_or(1.0);
        let (kind, name) = match p.kind {
            Seeded::Region(_) => return Ok(()),
            Seeded::Point(i) => ("user", self.inputs.points.get(i).map(|u| u.name.as_str())),
            Seeded::Outline => ("outline", None),
        };
        if let Some(&first) = frames.first() {
            self.grids = self.grids.split_off(&first);
        }
        for (s, (&(o, xy), &frame)) in p.steps.iter().zip(frames).enumerate() {
            let grid = match self.grids.entry(frame) {
                std::collections::btree_map::Entry::Occupied(g) => g.into_mut(),
                std::collections::btree_map::Entry::Vacant(v) => v.insert(recording.frame(frame)?),
            };
            let mut cells = vec![Cell::int(self.rows), Cell::int(s), Cell::int(frame)];
            if timed {
                cells.push(Cell::opt(recording.time_s(frame), 6));
            }
            cells.push(Cell::int(o));
            cells.push(p.seed.1.map_or(Cell::Empty, Cell::int));
            push_xy(&mut cells, recording, xy[0], xy[1], mm);
            cells.push(Cell::Float(bilinear(grid, xy) * per_unit, 4));
            cells.push(Cell::Text(kind.to_string()));
            cells.push(name.map_or(Cell::Empty, |n| Cell::Text(n.to_string())));
            let trip = p.round_trips.get(s).copied().flatten();
            self.round_trips.extend(trip);
            cells.push(trip.map_or(Cell::Empty, |d| Cell::Float(f64::from(d), 4)));
            emit(cells)?;
        }
        self.rows += 1;
        Ok(())
    }
}

/// The user's regions ([`pedo_track::UserInputs::regions`]) through the run, two rows per region
/// and frame on which it is followed: `kind` `moving`, the region carried by the field (the
/// share of each sensel its followed outline covers: a region moved by a tenth of a sensel
/// changes its edge sensels by a tenth, not whole sensels in or out), and `fixed`, the mask's
/// own sensels on that frame. Columns ([`region_series_header`]): `region` (its label), `kind`,
/// `frame`, `time_s`, `sensels` (existing sensors in the region, each by its covered share) and
/// its area (`area_mm2`, or `area_sensels` without a pitch), then the measures of its sensels,
/// each counted by its share, as `frames.csv` gives a frame's (contact sensors and area, total
/// force or load, peak pressure, centre of pressure in sensels and mm, named by the units known)
/// and the mean pressure of its contact sensors (`mean_pressure_kpa`, or `mean_pressure` in the
/// file's units); `name` and `stance` are those of the anatomical regions
/// ([`crate::moving_regions`]), empty for the user's. `frame_of` gives the frame of an object
/// of the run.
///
/// # Errors
/// A frame the recording cannot give.
pub fn regions_table(
    recording: &Recording,
    frame_of: &dyn Fn(usize) -> usize,
    points: &pedo_track::follow::FollowedPoints,
    inputs: &pedo_track::UserInputs,
    threshold: f64,
) -> pedo_io::Result<Table> {
    use pedo_track::follow::Seeded;
    let mut t = region_series_header(recording);
    for (k, region) in inputs.regions.iter().enumerate() {
        // The region's followed outline per frame, its points in outline order.
        let mut by_frame: std::collections::BTreeMap<usize, Vec<[f64; 2]>> = Default::default();
        for p in points.points.iter().filter(|p| p.kind == Seeded::Region(k)) {
            for &(o, xy) in &p.steps {
                by_frame.entry(frame_of(o)).or_default().push(xy);
            }
        }
        let fixed: Vec<f64> = region
            .cells
            .iter()
            .map(|&c| f64::from(u8::from(c)))
            .collect();
        for (frame, outline) in by_frame.into_iter().filter(|(_, o)| o.len() >= 3) {
            let grid = recording.frame(frame)?;
            let moving =
                pedo_io::marks::polygon_coverage(&outline, recording.rows(), recording.cols());
            for (kind, shares) in [("moving", &moving), ("fixed", &fixed)] {
                let id = RegionId {
                    label: region.label as usize,
                    kind,
                    name: None,
                    stance: None,
                    foot: None,
                };
                t.rows.push(region_series_row(
                    recording,
                    &id,
                    frame,
                    Some((&grid, shares.as_slice())),
                    threshold,
                ));
            }
        }
    }
    Ok(t)
}

/// Which region a row of `region_series.csv` is of.
pub(crate) struct RegionId<'a> {
    /// Its label (the user's mask's, or the rule's 1-based number).
    pub(crate) label: usize,
    /// `moving` or `fixed`.
    pub(crate) kind: &'a str,
    /// The anatomical region's name.
    pub(crate) name: Option<&'a str>,
    /// The anatomical region's stance.
    pub(crate) stance: Option<usize>,
    /// The anatomical region's foot, for a recording of both feet apart.
    pub(crate) foot: Option<pedo_io::regions::Side>,
}

/// The columns of `region_series.csv` ([`regions_table`]; no rows).
pub fn region_series_header(recording: &Recording) -> Table {
    let mut t = Table::new(&["region", "kind", "frame"]);
    if !recording.feet.is_empty() {
        // Both feet apart: each anatomical region's foot first, as regions.csv has it.
        t.header.insert(0, "foot".to_string());
    }
    if recording.dt_s.is_some() {
        t.push_column("time_s");
    }
    t.push_column("sensels");
    t.push_column(match recording.sensel_area() {
        Some(_) => "area_mm2",
        None => "area_sensels",
    });
    push_measure_columns(&mut t, recording);
    t.push_column(match kpa_per_unit(&recording.units) {
        Some(_) => "mean_pressure_kpa",
        None => "mean_pressure",
    });
    t.push_column("name");
    t.push_column("stance");
    t
}

/// One row of `region_series.csv`: the region `id` on `frame`, the share of each sensel of that
/// frame's `grid` it covers (`None`: the region was not followed to the frame, its measures
/// empty).
pub(crate) fn region_series_row(
    recording: &Recording,
    id: &RegionId<'_>,
    frame: usize,
    shares: Option<(&pedo_io::Grid, &[f64])>,
    threshold: f64,
) -> Vec<Cell> {
    let per_unit = kpa_per_unit(&recording.units).unwrap_or(1.0);
    let u = measure_units(recording);
    let area = recording.sensel_area().unwrap_or(1.0);
    let sensors = recording.sensor_mask();
    let mut row = Vec::new();
    if !recording.feet.is_empty() {
        row.push(
            id.foot
                .map_or(Cell::Empty, |f| Cell::Text(f.name().to_string())),
        );
    }
    row.extend([
        Cell::int(id.label),
        Cell::Text(id.kind.to_string()),
        Cell::int(frame),
    ]);
    if recording.dt_s.is_some() {
        row.push(Cell::opt(recording.time_s(frame), 6));
    }
    match shares {
        Some((grid, shares)) => {
            // Existing sensors in the region, each by the share of it the region covers.
            let n: f64 = (shares.iter().zip(sensors))
                .filter(|(_, s)| **s)
                .map(|(w, _)| w)
                .sum();
            let m = recording.covered_measures(grid, threshold, shares);
            row.push(Cell::Float(n, 3));
            row.push(Cell::Float(n * area, 4));
            push_measures(&mut row, recording, &u, Some(&m));
            // The mean of the contact sensors' values: the load over their covered count.
            let load = m.total_force / recording.force_factor().unwrap_or(area);
            let contact = m.contact_area / area;
            row.push(match contact > 0.0 {
                false => Cell::Empty,
                true => Cell::Float(load / contact * per_unit, 4),
            });
        }
        None => {
            row.push(Cell::Empty);
            row.push(Cell::Empty);
            push_measures(&mut row, recording, &u, None);
            row.push(Cell::Empty);
        }
    }
    row.push(id.name.map_or(Cell::Empty, |n| Cell::Text(n.to_string())));
    row.push(id.stance.map_or(Cell::Empty, Cell::int));
    row
}

/// The grid's value at `p` (x = column, y = row; sensel centres at whole numbers), bilinear
/// between the four nearest centres, clamped to the grid.
fn bilinear(grid: &pedo_io::Grid, p: [f64; 2]) -> f64 {
    let clamp = |v: f64, n: usize| v.clamp(0.0, n.saturating_sub(1) as f64);
    let (x, y) = (clamp(p[0], grid.cols()), clamp(p[1], grid.rows()));
    let (c0, r0) = (x.floor() as usize, y.floor() as usize);
    let (c1, r1) = ((c0 + 1).min(grid.cols() - 1), (r0 + 1).min(grid.rows() - 1));
    let (fx, fy) = (x - c0 as f64, y - r0 as f64);
    let top = grid.get(r0, c0) * (1.0 - fx) + grid.get(r0, c1) * fx;
    let bottom = grid.get(r1, c0) * (1.0 - fx) + grid.get(r1, c1) * fx;
    top * (1.0 - fy) + bottom * fy
}

/// The names and unit factors of the measures' columns for this recording.
pub(crate) struct MeasureUnits {
    pub(crate) area: (&'static str, f64),
    pub(crate) force: &'static str,
    pub(crate) peak: (&'static str, f64),
}

pub(crate) fn measure_units(recording: &Recording) -> MeasureUnits {
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

/// The columns of [`FrameMeasures`](pedo_io::recording::FrameMeasures), named by their units.
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
    m: Option<&pedo_io::recording::FrameMeasures>,
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
    measures: &[pedo_io::recording::FrameMeasures],
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
