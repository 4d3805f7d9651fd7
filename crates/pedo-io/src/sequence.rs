//! Whole recordings: the objects of every frame, matched pair by pair, chained into node tracks.
//!
//! This is the job of the seed's Tables 1–3: for a contour or surface model, the objects of
//! consecutive frames (paired by [`crate::track`]) are matched; for the isocontour model, the
//! isobaric contours of one frame are matched level after level (seed §5.3). Each matched pair
//! yields one [`PairRow`] with the seed's columns, and the matches are chained into [`Track`]s.

use crate::contour::{contours, ContourOptions, Resample};
use crate::error::{IoError, Result};
use crate::recording::Recording;
use modal_core::{match_shapes, MatchOptions, MatchResult, Search, Shape};
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// Which object model represents a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ObjectModel {
    /// Closed contours of the loaded region (seed §3.1).
    #[default]
    Contour,
    /// Brightness surfaces: pressure as height over the loaded region (seed §3.2).
    Surface,
    /// Isobaric contours of a single frame, matched level after level (seed §3.3, §5.3).
    Isocontour,
}

/// Parameters of [`run_sequence`].
#[derive(Debug, Clone)]
pub struct SequenceOptions {
    pub model: ObjectModel,
    /// Contour extraction (contour model, and the isocontours' preprocessing and resampling).
    pub contour: ContourOptions,
    /// Surface construction (surface model).
    pub surface: crate::surface::SurfaceOptions,
    /// Isocontour model: the frame whose isobaric contours are matched (`None`: the frame of
    /// largest total load) and the levels (`None`: `iso_count` levels evenly spaced between the
    /// noise threshold and the frame's peak).
    pub iso_frame: Option<usize>,
    pub iso_levels: Option<Vec<f64>>,
    pub iso_count: usize,
    /// Objects with fewer nodes are left out (too small to model).
    pub min_nodes: usize,
    /// Frames `start..end` of the recording to use (`None`: all).
    pub frames: Option<(usize, usize)>,
    pub matching: MatchOptions,
    /// Also run the local (mutual-best) search, for the table's local-match column.
    pub local_column: bool,
}

impl Default for SequenceOptions {
    fn default() -> Self {
        Self {
            model: ObjectModel::Contour,
            contour: ContourOptions {
                resample: Resample::Spacing(1.0),
                min_area: 4.0,
                ..ContourOptions::default()
            },
            surface: crate::surface::SurfaceOptions::default(),
            iso_frame: None,
            iso_levels: None,
            iso_count: 10,
            min_nodes: 8,
            frames: None,
            matching: MatchOptions::default(),
            local_column: true,
        }
    }
}

/// One object of the sequence.
#[derive(Debug, Clone)]
pub struct SequenceObject {
    /// 1-based identifier in sequence order, as the seed's tables number images.
    pub id: usize,
    /// Frame index (0-based) in the recording.
    pub frame: usize,
    /// Index of the object within its frame (or the level index for isocontours).
    pub index: usize,
    /// The isobaric level for isocontours.
    pub level: Option<f64>,
    pub shape: Shape,
}

/// One row of the per-pair table: the seed's columns.
#[derive(Debug, Clone, PartialEq)]
pub struct PairRow {
    pub id_a: usize,
    pub id_b: usize,
    pub frame_a: usize,
    pub frame_b: usize,
    pub nodes_a: usize,
    pub nodes_b: usize,
    /// Local (mutual-best) matches and their share of `min(n, m)`.
    pub local_matches: usize,
    pub local_percent: f64,
    /// One-to-one matches of the optimisation (global) search and their share of `min(n, m)`.
    pub optimisation_matches: usize,
    pub optimisation_percent: f64,
    /// Total matches after the excess-node step (one-to-one plus excess).
    pub excess_matches: usize,
    /// Mean normalised modal cost of the one-to-one matches.
    pub mean_cost: f64,
}

/// Matches of one pair of objects (indices into [`SequenceResult::objects`]).
#[derive(Debug, Clone)]
pub struct PairMatch {
    pub a: usize,
    pub b: usize,
    pub result: MatchResult,
    pub row: PairRow,
}

/// One node followed across objects: `(object index, node index)` steps in sequence order.
#[derive(Debug, Clone, PartialEq)]
pub struct Track {
    pub steps: Vec<(usize, usize)>,
}

/// Wall-clock time per stage.
#[derive(Debug, Clone, Copy, Default)]
pub struct StageTimings {
    pub objects: Duration,
    pub matching: Duration,
    pub tracks: Duration,
}

/// Everything [`run_sequence`] produces.
#[derive(Debug, Clone)]
pub struct SequenceResult {
    pub objects: Vec<SequenceObject>,
    pub pairs: Vec<PairMatch>,
    pub tracks: Vec<Track>,
    pub timings: StageTimings,
}

/// What [`run_sequence`] reports to a progress callback.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    Objects,
    Matching,
}

impl SequenceResult {
    /// Coordinates of the steps of `track` as `(frame, x, y[, z])` rows.
    pub fn track_points(&self, track: &Track) -> Vec<(usize, Vec<f64>)> {
        track
            .steps
            .iter()
            .map(|&(o, n)| {
                let obj = &self.objects[o];
                (obj.frame, obj.shape.point(n).to_vec())
            })
            .collect()
    }
}

/// Builds the objects of the recording, matches them pair by pair (in parallel) and chains the
/// matches into tracks. `progress(stage, done, total)` is called as work completes, possibly
/// from several threads.
pub fn run_sequence(
    recording: &Recording,
    options: &SequenceOptions,
    progress: &(dyn Fn(Stage, usize, usize) + Sync),
) -> Result<SequenceResult> {
    let (start, end) = options.frames.unwrap_or((0, recording.n_frames()));
    if start >= end || end > recording.n_frames() {
        return Err(IoError::invalid(format!(
            "frame range {start}..{end} is empty or beyond the {} frames of the recording",
            recording.n_frames()
        )));
    }
    let t0 = Instant::now();
    let objects = build_objects(recording, options, start, end, progress)?;
    let candidate_pairs = pair_objects(&objects, options)?;
    let t1 = Instant::now();

    let done = AtomicUsize::new(0);
    let total = candidate_pairs.len();
    let pairs: Vec<PairMatch> = candidate_pairs
        .par_iter()
        .map(|&(a, b)| {
            let r = match_pair(&objects, a, b, options);
            progress(Stage::Matching, done.fetch_add(1, Ordering::Relaxed) + 1, total);
            r
        })
        .collect::<Result<_>>()?;
    let t2 = Instant::now();
    let tracks = chain_tracks(&objects, &pairs);
    let timings = StageTimings { objects: t1 - t0, matching: t2 - t1, tracks: t2.elapsed() };
    Ok(SequenceResult { objects, pairs, tracks, timings })
}

fn match_pair(objects: &[SequenceObject], a: usize, b: usize, options: &SequenceOptions) -> Result<PairMatch> {
    let (oa, ob) = (&objects[a], &objects[b]);
    let result = match_shapes(&oa.shape, &ob.shape, &options.matching).map_err(|e| {
        IoError::invalid(format!("matching object {} (frame {}) with object {} (frame {}): {e}", oa.id, oa.frame, ob.id, ob.frame))
    })?;
    let (n, m) = (oa.shape.len(), ob.shape.len());
    let min = n.min(m).max(1) as f64;
    let one_to_one: Vec<_> = result.pairs.iter().filter(|p| !p.excess).collect();
    let local = if options.local_column || options.matching.search == Search::Local {
        result.local_count()
    } else {
        0
    };
    let optimisation = if options.matching.search == Search::Global { one_to_one.len() } else { 0 };
    let mean_cost = if one_to_one.is_empty() {
        0.0
    } else {
        one_to_one.iter().map(|p| p.cost).sum::<f64>() / one_to_one.len() as f64
    };
    let row = PairRow {
        id_a: oa.id,
        id_b: ob.id,
        frame_a: oa.frame,
        frame_b: ob.frame,
        nodes_a: n,
        nodes_b: m,
        local_matches: local,
        local_percent: 100.0 * local as f64 / min,
        optimisation_matches: optimisation,
        optimisation_percent: 100.0 * optimisation as f64 / min,
        excess_matches: result.pairs.len(),
        mean_cost,
    };
    Ok(PairMatch { a, b, result, row })
}

/// Chains matches into tracks. A node continues the track of the node it is matched to one-to-one
/// in the previous object; excess (one-to-many) matches never extend a track, since a track must
/// stay a single path. Nodes with no one-to-one predecessor start a new track.
pub fn chain_tracks(objects: &[SequenceObject], pairs: &[PairMatch]) -> Vec<Track> {
    let mut track_of: Vec<Vec<Option<usize>>> = objects.iter().map(|o| vec![None; o.shape.len()]).collect();
    let mut tracks: Vec<Track> = Vec::new();
    // Objects are in sequence order and every pair goes forward, so visiting the objects in order
    // sees each predecessor before its successors.
    let mut incoming: Vec<Vec<&PairMatch>> = vec![Vec::new(); objects.len()];
    for p in pairs {
        incoming[p.b].push(p);
    }
    for (o, obj) in objects.iter().enumerate() {
        for p in &incoming[o] {
            for mp in p.result.pairs.iter().filter(|mp| !mp.excess) {
                if track_of[o][mp.b].is_some() {
                    continue;
                }
                if let Some(t) = track_of[p.a][mp.a] {
                    // A track can pass through one node per object only: a split keeps the
                    // first continuation.
                    if tracks[t].steps.last().map(|s| s.0) == Some(p.a) {
                        tracks[t].steps.push((o, mp.b));
                        track_of[o][mp.b] = Some(t);
                    }
                }
            }
        }
        for node in 0..obj.shape.len() {
            if track_of[o][node].is_none() {
                track_of[o][node] = Some(tracks.len());
                tracks.push(Track { steps: vec![(o, node)] });
            }
        }
    }
    tracks
}
