//! Whole recordings: the objects of every frame, matched pair by pair, chained into node tracks.
//!
//! This is the job of Tables 1–3 of Tavares & Bastos (2005): for a contour or surface model, the objects of
//! consecutive frames (paired by [`crate::track`]) are matched; for the isocontour model, the
//! isobaric contours of one frame are matched level after level (docs/method.md §9). Each matched pair
//! yields one [`PairRow`] with the paper's columns, and the matches are chained into [`Track`]s.

use crate::contour::{contours, Contour, ContourOptions, Resample};
use crate::error::{IoError, Result};
use crate::recording::Recording;
use crate::track::PairingMethod;
use modal_core::{match_shapes, ElementKind, MatchOptions, MatchResult, Search, Shape};
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// Which object model represents a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ObjectModel {
    /// Closed contours of the loaded region (docs/method.md §8.2).
    #[default]
    Contour,
    /// Brightness surfaces: pressure as height over the loaded region (docs/method.md §8.3).
    Surface,
    /// Isobaric contours of a single frame, matched level after level (docs/method.md §8.4).
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
            surface: crate::surface::SurfaceOptions {
                max_nodes: Some(120),
                ..Default::default()
            },
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

/// Which searches fill the table's match columns.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SearchMode {
    /// Optimisation (global) search only.
    Global,
    /// Local (mutual-best) search only.
    Local,
    /// Both columns, as in the paper's tables; the matches themselves come from the global search.
    #[default]
    Both,
}

/// The user-facing parameters of a sequence run, shared by the CLI and the Python bindings;
/// [`RunParams::to_options`] validates them against a recording.
#[derive(Debug, Clone, PartialEq)]
pub struct RunParams {
    pub model: ObjectModel,
    pub element: ElementKind,
    /// Fraction of the modes used as features, in (0, 1].
    pub modes: f64,
    pub search: SearchMode,
    pub method: assign::Method,
    /// Threshold on the max-normalised modal cost, in [0, 1].
    pub threshold: Option<f64>,
    pub excess: bool,
    /// The paper's literal setting (no rotation pre-alignment, no re-fits).
    pub paper: bool,
    /// Gaussian element: a Gaussian on every `center_stride`-th node only (1: every node).
    pub center_stride: usize,
    /// Frames `first..=last`, 1-based.
    pub frames: Option<(usize, usize)>,
    /// Noise threshold in the recording's units (`None`: the file's own, else 0).
    pub noise: Option<f64>,
    /// Gaussian smoothing σ in sensels (0: none).
    pub smooth: f64,
    /// Contour node spacing in sensels.
    pub spacing: f64,
    /// Node budget of each brightness surface.
    pub surface_nodes: usize,
    /// Isocontour model: the frame (1-based; `None`: the frame of largest load) and level count.
    pub iso_frame: Option<usize>,
    pub iso_levels: usize,
}

impl Default for RunParams {
    fn default() -> Self {
        Self {
            model: ObjectModel::Contour,
            element: ElementKind::Gaussian,
            modes: 0.25,
            search: SearchMode::Both,
            method: assign::Method::JonkerVolgenant,
            threshold: None,
            excess: true,
            paper: false,
            center_stride: 1,
            frames: None,
            noise: None,
            smooth: 0.0,
            spacing: 1.0,
            surface_nodes: 120,
            iso_frame: None,
            iso_levels: 10,
        }
    }
}

impl RunParams {
    /// The matching part of the parameters (element, modes, search, solver, threshold, excess,
    /// paper setting), checked, for this run's object model: surfaces are unordered 3-D meshes
    /// and get the measured surface setting (on the synthetic moving blob at 60 nodes, 0.44 of
    /// the pairs within one spacing of the true position against 0.31 with the contour recipe;
    /// see the README), contours and isocontours the contour recipe.
    pub fn match_options(&self) -> Result<MatchOptions> {
        let surface = self.model == ObjectModel::Surface;
        self.match_options_for(if surface { 3 } else { 2 }, !surface)
    }

    /// [`RunParams::match_options`] for objects of `dim` dimensions, ordered contours or not,
    /// starting from [`MatchOptions::for_input`]; what `pedomatch match` uses for a single pair.
    pub fn match_options_for(&self, dim: usize, ordered: bool) -> Result<MatchOptions> {
        if !(self.modes > 0.0 && self.modes <= 1.0) {
            return Err(IoError::invalid(format!(
                "modes must be in (0, 1], got {}",
                self.modes
            )));
        }
        if let Some(t) = self.threshold {
            if !(t.is_finite() && t >= 0.0) {
                return Err(IoError::invalid(format!(
                    "threshold must be a non-negative number, got {t}"
                )));
            }
        }
        let mut matching = if self.paper {
            MatchOptions::paper()
        } else {
            MatchOptions::for_input(dim, ordered)
        };
        matching.model.element = self.element;
        matching.mode_fraction = self.modes;
        matching.search = if self.search == SearchMode::Local {
            Search::Local
        } else {
            Search::Global
        };
        matching.method = self.method;
        matching.threshold = self.threshold;
        matching.excess = self.excess;
        if self.center_stride == 0 {
            return Err(IoError::invalid("center stride must be ≥ 1, got 0"));
        }
        matching.model.center_stride = self.center_stride;
        Ok(matching)
    }

    /// Checks every parameter and turns them into [`SequenceOptions`] for `recording`.
    pub fn to_options(&self, recording: &Recording) -> Result<SequenceOptions> {
        let bad = |msg: String| Err(IoError::invalid(msg));
        let matching = self.match_options()?;
        if !(self.spacing.is_finite() && self.spacing > 0.0) {
            return bad(format!("spacing must be positive, got {}", self.spacing));
        }
        if !(self.smooth.is_finite() && self.smooth >= 0.0) {
            return bad(format!("smooth must be >= 0, got {}", self.smooth));
        }
        if self.iso_levels < 2 {
            return bad(format!(
                "iso_levels must be at least 2, got {}",
                self.iso_levels
            ));
        }
        if self.surface_nodes < 8 {
            return bad(format!(
                "surface_nodes must be at least 8, got {}",
                self.surface_nodes
            ));
        }
        let n = recording.n_frames();
        let frames = match self.frames {
            None => None,
            Some((a, b)) if a >= 1 && a <= b && b <= n => Some((a - 1, b)),
            Some((a, b)) => {
                return bad(format!(
                    "frames {a}..{b} are not within 1..{n} (1-based, inclusive)"
                ))
            }
        };
        let iso_frame = match self.iso_frame {
            None => None,
            Some(f) if f >= 1 && f <= n => Some(f - 1),
            Some(f) => return bad(format!("iso_frame {f} is not within 1..{n} (1-based)")),
        };
        let noise = self.noise.or(recording.noise_threshold).unwrap_or(0.0);
        let sigma = (self.smooth > 0.0).then_some(self.smooth);
        let mut o = SequenceOptions {
            model: self.model,
            matching,
            frames,
            iso_frame,
            iso_count: self.iso_levels,
            ..Default::default()
        };
        o.local_column = self.search != SearchMode::Global;
        o.contour.preprocess.threshold = Some(noise);
        o.contour.preprocess.sigma = sigma;
        o.contour.resample = Resample::Spacing(self.spacing);
        o.surface.preprocess.threshold = Some(noise);
        o.surface.preprocess.sigma = sigma;
        o.surface.max_nodes = Some(self.surface_nodes);
        Ok(o)
    }
}

/// One object of the sequence.
#[derive(Debug, Clone)]
pub struct SequenceObject {
    /// 1-based identifier in sequence order, as the paper's tables number images.
    pub id: usize,
    /// Frame index (0-based) in the recording.
    pub frame: usize,
    /// Index of the object within its frame (or the level index for isocontours).
    pub index: usize,
    /// The isobaric level for isocontours.
    pub level: Option<f64>,
    pub shape: Shape,
}

/// One row of the per-pair table: the paper's columns.
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
    /// Contour model: object `i` continues as several objects of the next frame.
    pub splits: Vec<(usize, Vec<usize>)>,
    /// Contour model: several objects continue as one object of the next frame.
    pub merges: Vec<(Vec<usize>, usize)>,
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
    let Built {
        objects,
        pairs: candidate_pairs,
        splits,
        merges,
    } = build_objects(recording, options, start, end, progress)?;
    let t1 = Instant::now();

    let done = AtomicUsize::new(0);
    let total = candidate_pairs.len();
    let pairs: Vec<PairMatch> = candidate_pairs
        .par_iter()
        .map(|&(a, b)| {
            let r = match_pair(&objects, a, b, options);
            progress(
                Stage::Matching,
                done.fetch_add(1, Ordering::Relaxed) + 1,
                total,
            );
            r
        })
        .collect::<Result<_>>()?;
    let t2 = Instant::now();
    let tracks = chain_tracks(&objects, &pairs);
    let timings = StageTimings {
        objects: t1 - t0,
        matching: t2 - t1,
        tracks: t2.elapsed(),
    };
    Ok(SequenceResult {
        objects,
        pairs,
        tracks,
        splits,
        merges,
        timings,
    })
}

fn match_pair(
    objects: &[SequenceObject],
    a: usize,
    b: usize,
    options: &SequenceOptions,
) -> Result<PairMatch> {
    let (oa, ob) = (&objects[a], &objects[b]);
    let result = match_shapes(&oa.shape, &ob.shape, &options.matching).map_err(|e| {
        IoError::invalid(format!(
            "matching object {} (frame {}) with object {} (frame {}): {e}",
            oa.id, oa.frame, ob.id, ob.frame
        ))
    })?;
    let (n, m) = (oa.shape.len(), ob.shape.len());
    let min = n.min(m).max(1) as f64;
    let one_to_one: Vec<_> = result.pairs.iter().filter(|p| !p.excess).collect();
    let local = if options.local_column || options.matching.search == Search::Local {
        result.local_count()
    } else {
        0
    };
    let optimisation = if options.matching.search == Search::Global {
        one_to_one.len()
    } else {
        0
    };
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
    let mut track_of: Vec<Vec<Option<usize>>> =
        objects.iter().map(|o| vec![None; o.shape.len()]).collect();
    let mut tracks: Vec<Track> = Vec::new();
    // Objects are in sequence order and every pair goes forward, so visiting the objects in order
    // sees each predecessor before its successors.
    let mut incoming: Vec<Vec<&PairMatch>> = vec![Vec::new(); objects.len()];
    for p in pairs {
        incoming[p.b].push(p);
    }
    for o in 0..objects.len() {
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
        for (node, slot) in track_of[o].iter_mut().enumerate() {
            if slot.is_none() {
                *slot = Some(tracks.len());
                tracks.push(Track {
                    steps: vec![(o, node)],
                });
            }
        }
    }
    tracks
}

/// Objects in sequence order (numbered from 1), the pairs to match (indices into the objects)
/// and, for contours, the splits and merges between consecutive frames.
struct Built {
    objects: Vec<SequenceObject>,
    pairs: Vec<(usize, usize)>,
    splits: Vec<(usize, Vec<usize>)>,
    merges: Vec<(Vec<usize>, usize)>,
}

/// The outer contours of a frame worth modelling, largest first (so object 0 of a frame is its
/// main region).
fn frame_contours(
    recording: &Recording,
    t: usize,
    options: &SequenceOptions,
) -> Result<Vec<Contour>> {
    let mut cs = contours(&recording.frame(t)?, &options.contour)?;
    cs.retain(|c| !c.hole && c.points.len() >= options.min_nodes.max(3));
    cs.sort_by(|a, b| b.area().total_cmp(&a.area()));
    Ok(cs)
}

fn build_objects(
    recording: &Recording,
    options: &SequenceOptions,
    start: usize,
    end: usize,
    progress: &(dyn Fn(Stage, usize, usize) + Sync),
) -> Result<Built> {
    let keep = |s: &Shape| s.len() >= options.min_nodes.max(3);
    let mut built = Built {
        objects: Vec::new(),
        pairs: Vec::new(),
        splits: Vec::new(),
        merges: Vec::new(),
    };
    let done = AtomicUsize::new(0);
    let tick = |total: usize| {
        progress(
            Stage::Objects,
            done.fetch_add(1, Ordering::Relaxed) + 1,
            total,
        )
    };
    match options.model {
        ObjectModel::Contour => {
            let per_frame: Vec<Vec<Contour>> = (start..end)
                .into_par_iter()
                .map(|t| {
                    let cs = frame_contours(recording, t, options);
                    tick(end - start);
                    cs
                })
                .collect::<Result<_>>()?;
            let pairings = crate::track::track(&per_frame, PairingMethod::default())?;
            let mut first = Vec::with_capacity(per_frame.len());
            for (k, cs) in per_frame.iter().enumerate() {
                first.push(built.objects.len());
                for (index, c) in cs.iter().enumerate() {
                    let id = built.objects.len() + 1;
                    built.objects.push(SequenceObject {
                        id,
                        frame: start + k,
                        index,
                        level: None,
                        shape: c.to_shape()?,
                    });
                }
            }
            for (k, p) in pairings.iter().enumerate() {
                let (fa, fb) = (first[k], first[k + 1]);
                built
                    .pairs
                    .extend(p.pairs.iter().map(|&(i, j)| (fa + i, fb + j)));
                built.splits.extend(
                    p.splits
                        .iter()
                        .map(|(i, js)| (fa + i, js.iter().map(|j| fb + j).collect())),
                );
                built.merges.extend(
                    p.merges
                        .iter()
                        .map(|(is, j)| (is.iter().map(|i| fa + i).collect(), fb + j)),
                );
            }
        }
        ObjectModel::Surface => {
            let threshold = options.surface.preprocess.threshold.unwrap_or(0.0);
            let per_frame: Vec<Option<Shape>> = (start..end)
                .into_par_iter()
                .map(|t| {
                    let frame = recording.frame(t)?;
                    let shape = if frame.max() > threshold {
                        match crate::surface::surface(&frame, &options.surface) {
                            Ok(s) => Some(s.to_shape()?).filter(|s| keep(s)),
                            // A frame whose few loaded sensels cannot be triangulated has no
                            // surface object, like a frame with no contact.
                            Err(IoError::InvalidInput(_)) => None,
                            Err(e) => return Err(e),
                        }
                    } else {
                        None
                    };
                    tick(end - start);
                    Ok(shape)
                })
                .collect::<Result<_>>()?;
            let mut previous: Option<usize> = None;
            for (k, shape) in per_frame.into_iter().enumerate() {
                match shape {
                    Some(shape) => {
                        let o = built.objects.len();
                        if let Some(p) = previous {
                            if built.objects[p].frame + 1 == start + k {
                                built.pairs.push((p, o));
                            }
                        }
                        built.objects.push(SequenceObject {
                            id: o + 1,
                            frame: start + k,
                            index: 0,
                            level: None,
                            shape,
                        });
                        previous = Some(o);
                    }
                    None => previous = None,
                }
            }
        }
        ObjectModel::Isocontour => {
            let t = match options.iso_frame {
                Some(t) => t,
                None => (start..end)
                    .max_by(|&a, &b| frame_load(recording, a).total_cmp(&frame_load(recording, b)))
                    .unwrap_or(start),
            };
            let frame = recording.frame(t)?;
            let base = match options.contour.preprocess.threshold {
                Some(th) => crate::preprocess::threshold(&frame, th)?,
                None => frame.clone(),
            };
            let levels = match &options.iso_levels {
                Some(l) => l.clone(),
                None => crate::isobar::even_levels(&base, options.iso_count),
            };
            let iso = crate::isobar::IsoOptions {
                preprocess: options.contour.preprocess,
                resample: options.contour.resample,
                include_holes: false,
                ..Default::default()
            };
            for (index, &level) in levels.iter().enumerate() {
                let cs = crate::isobar::isocontours(&frame, &[level], &iso)?;
                // The seed models one isobaric contour per level: the largest region's outline.
                if let Some(c) = cs.iter().max_by(|a, b| a.area().total_cmp(&b.area())) {
                    let shape = c.to_shape()?;
                    if keep(&shape) {
                        let o = built.objects.len();
                        if o > 0 {
                            built.pairs.push((o - 1, o));
                        }
                        built.objects.push(SequenceObject {
                            id: o + 1,
                            frame: t,
                            index,
                            level: Some(level),
                            shape,
                        });
                    }
                }
                tick(levels.len());
            }
        }
    }
    Ok(built)
}

/// Sum of the frame's values: the load the isocontour model picks its frame by.
fn frame_load(recording: &Recording, t: usize) -> f64 {
    recording
        .frame_slice(t)
        .map_or(0.0, |f| f.iter().map(|&v| v as f64).sum())
}
