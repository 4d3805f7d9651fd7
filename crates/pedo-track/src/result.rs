//! What a run produces: the objects of every frame, the matched pairs with the paper's columns,
//! the tracks, what was skipped and why, and the counts a summary reports.

use crate::consistency::RoundTrips;
use modal_core::{MatchResult, Shape};
use pedo_io::recording::FrameMeasures;
use pedo_io::{IoError, Result};
use std::time::Duration;

/// One object of the sequence.
#[derive(Debug, Clone)]
pub struct SequenceObject {
    /// Identifier in sequence order: the object's index in [`SequenceResult::objects`].
    pub id: usize,
    /// Frame index (0-based) in the recording.
    pub frame: usize,
    /// Index of the object within its frame (or the level index for isocontours).
    pub index: usize,
    /// The isobaric level for isocontours, in the recording's pressure units; `None` for the
    /// other models.
    pub level: Option<f64>,
    /// The object's nodes, x = column and y = row in the units of the options (sensels unless
    /// [`ContourOptions::units`](pedo_io::ContourOptions::units) or [`SurfaceOptions::units`](pedo_io::surface::SurfaceOptions::units)
    /// say otherwise; always sensels from [`RunParams`](crate::RunParams)): a closed 2-D contour (contour and
    /// isocontour models) or a triangulated 3-D surface whose z is the rescaled pressure
    /// (surface model, see [`pedo_io::surface::ZScale`]).
    pub shape: Shape,
    /// The measures of the sensors inside the object's outline (contour and isocontour models,
    /// [`Recording::region_measures`](pedo_io::Recording::region_measures) with the contour threshold): one foot's contact area,
    /// force, peak pressure and centre of pressure in a recording of both feet. `None` for the
    /// surface model, whose one object per frame has the frame's measures.
    pub measures: Option<FrameMeasures>,
}

impl SequenceObject {
    /// The mean of its nodes' `(x, y)` (`objects.csv`'s `centroid_x`, `centroid_y`): for a
    /// recording of both feet apart, the object is of the insole whose columns hold its x
    /// ([`pedo_io::recording::FootColumns::holds`]).
    pub fn centroid(&self) -> [f64; 2] {
        let n = self.shape.len().max(1) as f64;
        let (cx, cy) = (0..self.shape.len()).fold((0.0, 0.0), |(x, y), i| {
            let p = self.shape.point(i);
            (x + p[0] / n, y + p[1] / n)
        });
        [cx, cy]
    }
}

/// The two objects of a pair as the pairs table and `summary.json` name them: ids, frames and
/// node counts (the leading columns of a row, matched or skipped).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PairObjects {
    /// Id of the first object (its index in [`SequenceResult::objects`]).
    pub id_a: usize,
    /// Id of the second object (larger than `id_a`).
    pub id_b: usize,
    /// Frame of the first object (0-based).
    pub frame_a: usize,
    /// Frame of the second object (0-based; the same frame for isocontour levels).
    pub frame_b: usize,
    /// Number of nodes of the first object (`n`).
    pub nodes_a: usize,
    /// Number of nodes of the second object (`m`).
    pub nodes_b: usize,
}

impl PairObjects {
    /// The pair of `oa` and `ob`.
    pub fn of(oa: &SequenceObject, ob: &SequenceObject) -> Self {
        Self {
            id_a: oa.id,
            id_b: ob.id,
            frame_a: oa.frame,
            frame_b: ob.frame,
            nodes_a: oa.shape.len(),
            nodes_b: ob.shape.len(),
        }
    }
}

/// One row of the per-pair table: the paper's columns.
#[derive(Debug, Clone, PartialEq)]
pub struct PairRow {
    /// Which objects were matched.
    pub objects: PairObjects,
    /// Local (mutual-best) matches on the final affinity, whatever the search.
    pub local_matches: usize,
    /// `local_matches` as a percentage (0–100) of `min(n, m)`, the node counts of the two
    /// objects.
    pub local_percent: f64,
    /// Matches of the optimisation (global) search, excess matches aside: one-to-one except
    /// with [`Search::Best`](modal_core::Search::Best). 0 when the search is [`Search::Local`](modal_core::Search::Local), which has no optimisation
    /// step.
    pub optimisation_matches: usize,
    /// `optimisation_matches` as a percentage (0–100) of `min(n, m)`.
    pub optimisation_percent: f64,
    /// Total matches after the excess-node step (one-to-one plus excess; the papers' "excess
    /// nodes matching" count).
    pub matches_after_excess: usize,
    /// Mean normalised modal cost ([`modal_core::MatchPair::cost`], in [0, 1]) of the matches
    /// that are not excess; 0 when there are none.
    pub mean_cost: f64,
    /// One-to-one matches that node tracks may follow: within the step rule of
    /// [`crate::pairing::StepBound`] (`matches.csv`'s `trackable`). A one-to-one assignment
    /// pairs every node of the smaller object, so `optimisation_percent` is near 100 by
    /// construction; this says how many of those pairs a track may take.
    pub trackable_matches: usize,
    /// `trackable_matches` as a percentage (0–100) of `min(n, m)`.
    pub trackable_percent: f64,
    /// Crossed pairs of matches along the two closed contours
    /// ([`MatchResult::crossings`](modal_core::MatchResult::crossings)): 0 when the matches keep
    /// the contours' cyclic order; `None` for surfaces.
    pub crossings: Option<usize>,
    /// How far the matches agree with one smooth, invertible map of the plane (field residual
    /// and round trip, sensels; [`crate::consistency`]); `None` for surfaces and pairs no field
    /// can be fitted to.
    pub consistency: Option<crate::consistency::PairConsistency>,
}

/// Matches of one pair of objects (indices into [`SequenceResult::objects`]).
#[derive(Debug, Clone)]
pub struct PairMatch {
    /// The first object (earlier in sequence order: `a < b`).
    pub a: usize,
    /// The second object.
    pub b: usize,
    /// The engine's result; its node indices are those of the two objects' shapes. Without
    /// match details ([`SequenceOptions::keep_match_details`](crate::SequenceOptions::keep_match_details) off) only the pairs, unmatched
    /// nodes and transform are kept: the affinity matrix is 0 × 0 and `aligned_a` and
    /// `local_pairs` are empty.
    pub result: MatchResult,
    /// The pair's row of the pairs table.
    pub row: PairRow,
    /// Per match of [`MatchResult::pairs`], in order: whether a node track may follow it
    /// (`matches.csv`'s `trackable`): one-to-one and within the pair's
    /// [`StepBound`](crate::pairing::StepBound), judged once when the pair is matched. Every
    /// chaining of tracks reads it.
    pub trackable: Vec<bool>,
    /// Per match of [`MatchResult::pairs`], in order: the step's round trip in sensels, how far
    /// the pair's backward field carries the match's node of `b` from its node of `a` (NaN for
    /// an excess match; [`PairConsistency::with_steps`](crate::consistency::PairConsistency::with_steps)).
    /// Empty when the pair has no consistency figures ([`PairRow::consistency`] `None`). A
    /// track's round trip is the largest of its steps'.
    pub step_round_trips: Vec<f32>,
}

impl PairMatch {
    /// The pair as a run without match details keeps it
    /// ([`SequenceOptions::keep_match_details`](crate::SequenceOptions::keep_match_details) off):
    /// its matches, unmatched nodes, transform and counts, without the affinity matrix, the
    /// aligned nodes and the local pairs.
    pub fn without_details(&self) -> Result<PairMatch> {
        let r = &self.result;
        let mut result = MatchResult {
            pairs: r.pairs.clone(),
            affinity: no_affinity()?,
            local_pairs: Vec::new(),
            unmatched_a: r.unmatched_a.clone(),
            unmatched_b: r.unmatched_b.clone(),
            n_modes: r.n_modes,
            refits: r.refits,
            solves: r.solves,
            transform: r.transform,
            aligned_a: Vec::new(),
            crossings: r.crossings,
            outline_images: None,
            drifted: r.drifted,
        };
        strip(&mut result);
        Ok(PairMatch {
            result,
            row: self.row.clone(),
            trackable: self.trackable.clone(),
            step_round_trips: self.step_round_trips.clone(),
            ..*self
        })
    }

    /// Drops the match details in place (see [`PairMatch::without_details`]).
    pub(crate) fn strip_details(&mut self) -> Result<()> {
        self.result.affinity = no_affinity()?;
        self.result.aligned_a = Vec::new();
        self.result.local_pairs = Vec::new();
        self.result.outline_images = None;
        strip(&mut self.result);
        Ok(())
    }

    /// Fails unless the pair leads forward (`a < b`) onto an object of `onto`: the chaining of
    /// tracks visits objects in sequence order.
    pub(crate) fn check_forward(&self, onto: std::ops::Range<usize>) -> Result<()> {
        if self.a < self.b && onto.contains(&self.b) {
            return Ok(());
        }
        Err(IoError::invalid(format!(
            "pair {} → {} does not lead forward onto objects {}..{}",
            self.a, self.b, onto.start, onto.end
        )))
    }

    /// The error for match `m`, whose nodes lie beyond the two objects' `len_a` and `len_b`
    /// nodes.
    pub(crate) fn beyond_nodes(
        &self,
        m: &modal_core::MatchPair,
        len_a: usize,
        len_b: usize,
    ) -> IoError {
        IoError::invalid(format!(
            "pair {} → {} matches node {} to node {}, beyond the objects' {len_a} and {len_b} nodes",
            self.a, self.b, m.a, m.b
        ))
    }
}

/// An empty affinity matrix (0 × 0), what a pair without details holds.
pub(crate) fn no_affinity() -> Result<modal_core::AffinityMatrix> {
    Ok(modal_core::AffinityMatrix::new(0, 0, Vec::new())?)
}

/// The vectors a pair without details keeps, without their spare capacity.
fn strip(r: &mut MatchResult) {
    r.pairs.shrink_to_fit();
    r.unmatched_a.shrink_to_fit();
    r.unmatched_b.shrink_to_fit();
}

/// One node followed across objects: `(object index, node index)` steps in sequence order.
#[derive(Debug, Clone, PartialEq)]
pub struct Track {
    /// `(object index, node index)` of each step: the object an index into
    /// [`SequenceResult::objects`], the node an index into that object's shape. Objects
    /// increase along a track, which passes through one node per object at most; a track has
    /// at least one step.
    pub steps: Vec<(usize, usize)>,
}

/// Wall-clock time per stage.
#[derive(Debug, Clone, Copy, Default)]
pub struct StageTimings {
    /// Building the objects of every frame (reading the frames too, when streamed).
    pub objects: Duration,
    /// Matching the pairs (with drift correction, the pairs of consecutive frames only: the
    /// reference pairs count as chaining).
    pub matching: Duration,
    /// Chaining the matches into tracks.
    pub tracks: Duration,
}

/// The tracks of a run held compactly: the steps of every track one after the other, object and
/// node numbers as `u32`. A run without match details ([`SequenceOptions::keep_match_details`](crate::SequenceOptions::keep_match_details)
/// off: the CLI's and batch runs) keeps its tracks so, in [`SequenceResult::packed_tracks`]:
/// a long recording has hundreds of thousands of short tracks, each a vector of its own in
/// [`SequenceResult::tracks`].
#[derive(Debug, Clone, PartialEq)]
pub struct PackedTracks {
    /// Track `k` is `steps[starts[k]..starts[k + 1]]`.
    starts: Vec<usize>,
    steps: Vec<(u32, u32)>,
}

impl Default for PackedTracks {
    fn default() -> Self {
        Self {
            starts: vec![0],
            steps: Vec::new(),
        }
    }
}

impl PackedTracks {
    /// Appends a track.
    pub fn push(&mut self, track: &Track) {
        let small = |v: usize| u32::try_from(v).unwrap_or(u32::MAX);
        self.steps
            .extend(track.steps.iter().map(|&(o, n)| (small(o), small(n))));
        self.starts.push(self.steps.len());
    }
    /// Number of tracks.
    pub fn len(&self) -> usize {
        self.starts.len() - 1
    }
    /// Whether there is no track.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Number of steps of track `k`.
    fn steps_of(&self, k: usize) -> usize {
        self.starts[k + 1] - self.starts[k]
    }
    /// Track `k`, if there is one.
    pub fn get(&self, k: usize) -> Option<Track> {
        (k < self.len()).then(|| Track {
            steps: self.steps[self.starts[k]..self.starts[k + 1]]
                .iter()
                .map(|&(o, n)| (o as usize, n as usize))
                .collect(),
        })
    }
    /// Every track, in order.
    pub fn iter(&self) -> impl Iterator<Item = Track> + '_ {
        (0..self.len()).filter_map(|k| self.get(k))
    }
    pub(crate) fn shrink_to_fit(&mut self) {
        self.starts.shrink_to_fit();
        self.steps.shrink_to_fit();
    }
}

impl FromIterator<Track> for PackedTracks {
    fn from_iter<I: IntoIterator<Item = Track>>(iter: I) -> Self {
        let mut p = PackedTracks::default();
        for t in iter {
            p.push(&t);
        }
        p.shrink_to_fit();
        p
    }
}

/// Everything [`run_sequence`](crate::run_sequence) produces (`Default`: a run with nothing in it).
#[derive(Debug, Clone, Default)]
pub struct SequenceResult {
    /// Every object in sequence order (by frame, then by index within the frame; isocontours
    /// by level): object `i` has id `i`.
    pub objects: Vec<SequenceObject>,
    /// The matched pairs, in the order they were proposed (frame order); the pairs that could
    /// not be matched are in [`skipped_pairs`](Self::skipped_pairs) instead.
    pub pairs: Vec<PairMatch>,
    /// With drift correction ([`SequenceOptions::drift_corrected`](crate::SequenceOptions::drift_corrected)): the reference pairs
    /// matched, each object against its ancestor on the last reference frame
    /// ([`crate::drift::reference_pairs`]), in object order; a track steps through their
    /// matches first ([`crate::drift::anchored_tracks`]), so a step of a track need not be a
    /// match of [`pairs`](Self::pairs). [`reference_tracked`](Self::reference_tracked) says
    /// which matches a track took. Their rows ([`PairMatch::row`]) count trackable matches by
    /// the step rule of consecutive frames, which tracks do not apply to them. A reference pair
    /// that cannot be matched is left out (the tracks follow the predecessors there). Empty
    /// without drift correction.
    pub reference_pairs: Vec<PairMatch>,
    /// The tracks, unless they are in [`packed_tracks`](Self::packed_tracks) (runs without
    /// match details): read them with [`all_tracks`](Self::all_tracks) to cover both.
    pub tracks: Vec<Track>,
    /// Runs without match details ([`SequenceOptions::keep_match_details`](crate::SequenceOptions::keep_match_details) off) hold their
    /// tracks here, packed, and leave [`tracks`](Self::tracks) empty.
    pub packed_tracks: Option<PackedTracks>,
    /// Each track's round trip in sensels, in track order ([`crate::chain_tracks_checked`]):
    /// the largest of its steps' ([`PairMatch::step_round_trips`]); `None` for a track of one
    /// step, one through a pair without a field (surfaces), and every track anchored by drift
    /// correction. Empty for a result made without them (read it with
    /// [`track_round_trip`](Self::track_round_trip)).
    pub track_round_trips: Vec<Option<f64>>,
    /// Contour model: object `i` continues as several objects of the next frame (object
    /// indices).
    pub splits: Vec<(usize, Vec<usize>)>,
    /// Contour model: several objects continue as one object of the next frame (object
    /// indices).
    pub merges: Vec<(Vec<usize>, usize)>,
    /// Frames whose objects could not be built, with the reason; the run goes on without them.
    pub skipped_frames: Vec<SkippedFrame>,
    /// Pairs that could not be matched (degenerate objects, a structure with too many
    /// zero-energy modes, ...), with the reason; the run goes on without them.
    pub skipped_pairs: Vec<SkippedPair>,
    /// Wall-clock time of each stage.
    pub timings: StageTimings,
}

/// A frame left out of a run: its objects could not be built (for isocontours, one entry per
/// isobaric level of the frame that gives no object, the level in the reason).
#[derive(Debug, Clone, PartialEq)]
pub struct SkippedFrame {
    /// Frame index (0-based) in the recording.
    pub frame: usize,
    /// The error, as one line.
    pub reason: String,
}

/// A pair of objects (indices into [`SequenceResult::objects`]) that could not be matched.
#[derive(Debug, Clone, PartialEq)]
pub struct SkippedPair {
    /// The first object.
    pub a: usize,
    /// The second object.
    pub b: usize,
    /// The matching error, as one line.
    pub reason: String,
}

/// What a run ([`stream_sequence`](crate::stream_sequence), [`run_sequence`](crate::run_sequence)) reports to a progress callback
/// `progress(stage, done, total)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// Building the objects of the isocontour model: `done` of `total` isobaric levels. The
    /// contour and surface models build and match window by window and report
    /// [`Stage::Matching`] only.
    Objects,
    /// Matching: `done` of `total` frames whose pairs are matched (a pair done counts as its
    /// share of its window's frames), or of `total` pairs for the isocontour model.
    Matching,
    /// Writing what a run's folder holds once the run is over (the engine reports none of it):
    /// `done` of `total` outputs (a figure, the material points, the report, the animation).
    Output,
}

impl SequenceResult {
    /// Every track in order, from [`tracks`](Self::tracks) or, packed, one at a time from
    /// [`packed_tracks`](Self::packed_tracks).
    pub fn all_tracks(&self) -> Box<dyn Iterator<Item = std::borrow::Cow<'_, Track>> + '_> {
        match &self.packed_tracks {
            Some(p) => Box::new(p.iter().map(std::borrow::Cow::Owned)),
            None => Box::new(self.tracks.iter().map(std::borrow::Cow::Borrowed)),
        }
    }

    /// The round trip of track `k` ([`track_round_trips`](Self::track_round_trips)).
    pub fn track_round_trip(&self, k: usize) -> Option<f64> {
        self.track_round_trips.get(k).copied().flatten()
    }

    /// Number of tracks (held or packed).
    pub fn track_count(&self) -> usize {
        self.packed_tracks
            .as_ref()
            .map_or(self.tracks.len(), PackedTracks::len)
    }

    /// Number of steps of every track, in order (held or packed).
    pub fn track_lengths(&self) -> Box<dyn Iterator<Item = usize> + '_> {
        match &self.packed_tracks {
            Some(p) => Box::new((0..p.len()).map(|k| p.steps_of(k))),
            None => Box::new(self.tracks.iter().map(|t| t.steps.len())),
        }
    }

    /// For each of the [`reference_pairs`](Self::reference_pairs), in order, and each of its
    /// matches (`result.pairs`, in order): whether a track took it, i.e. the match is not an
    /// excess match and its two nodes are on the same track. Such a track reached the node of
    /// the second object through this match, from its step on the first object (an earlier
    /// step of the same track, on the reference frame).
    pub fn reference_tracked(&self) -> Vec<Vec<bool>> {
        reference_tracked(&self.objects, self.all_tracks(), &self.reference_pairs)
    }

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

/// [`SequenceResult::reference_tracked`] of a run's `objects`, `tracks` and `reference` pairs:
/// the engine's, which hands it to a sink with each reference pair.
pub(crate) fn reference_tracked<T: std::borrow::Borrow<Track>>(
    objects: &[SequenceObject],
    tracks: impl Iterator<Item = T>,
    reference: &[PairMatch],
) -> Vec<Vec<bool>> {
    if reference.is_empty() {
        return Vec::new();
    }
    // The track of every node, by object and node (`None`: on no track, which a run's own
    // tracks never leave).
    let mut track_of: Vec<Vec<Option<usize>>> =
        objects.iter().map(|o| vec![None; o.shape.len()]).collect();
    for (k, t) in tracks.enumerate() {
        for &(o, n) in &t.borrow().steps {
            if let Some(slot) = track_of.get_mut(o).and_then(|row| row.get_mut(n)) {
                *slot = Some(k);
            }
        }
    }
    let on = |o: usize, n: usize| {
        track_of
            .get(o)
            .and_then(|row| row.get(n))
            .copied()
            .flatten()
    };
    reference
        .iter()
        .map(|p| {
            p.result
                .pairs
                .iter()
                .map(|m| !m.excess && on(p.a, m.a).is_some_and(|t| Some(t) == on(p.b, m.b)))
                .collect()
        })
        .collect()
}

/// A pair that could not be matched, as the pairs table and `summary.json` report it.
#[derive(Debug, Clone, PartialEq)]
pub struct SkippedPairRow {
    /// Which objects could not be matched.
    pub objects: PairObjects,
    /// The matching error, as one line.
    pub reason: String,
}

impl SkippedPairRow {
    /// The row of skipped pair `s` of run `r`.
    pub fn of(r: &SequenceResult, s: &SkippedPair) -> Self {
        Self::of_objects(&r.objects[s.a], &r.objects[s.b], &s.reason)
    }

    pub(crate) fn of_objects(oa: &SequenceObject, ob: &SequenceObject, reason: &str) -> Self {
        Self {
            objects: PairObjects::of(oa, ob),
            reason: reason.to_string(),
        }
    }
}

/// What a run's summary needs of it: counts, sums and what was left out, without the objects,
/// matches and tracks themselves. [`stream_sequence`](crate::stream_sequence) returns it; [`RunCounts::of`] reads it
/// off a whole [`SequenceResult`]. Object ids are their indices.
#[derive(Debug, Clone)]
pub struct RunCounts {
    /// Objects built.
    pub objects: usize,
    /// Pairs matched (the skipped ones aside).
    pub pairs: usize,
    /// Sum over the matched pairs, in order, of [`PairRow::local_percent`].
    pub local_percent_sum: f64,
    /// Sum over the matched pairs, in order, of [`PairRow::optimisation_percent`].
    pub optimisation_percent_sum: f64,
    /// Sum over the matched pairs, in order, of [`PairRow::mean_cost`].
    pub cost_sum: f64,
    /// Sum over the matched pairs, in order, of [`PairRow::trackable_percent`].
    pub trackable_percent_sum: f64,
    /// Matched pairs with consistency figures ([`PairRow::consistency`]).
    pub consistent_pairs: usize,
    /// Sum over those pairs, in order, of their median round trip (sensels).
    pub round_trip_sum: f64,
    /// Sum over those pairs, in order, of their median field residual (sensels).
    pub field_residual_sum: f64,
    /// Tracks chained.
    pub tracks: usize,
    /// Tracks of 3 steps or more.
    pub tracks_3_or_more: usize,
    /// The round trip (sensels) of every track that has one, in order
    /// ([`SequenceResult::track_round_trips`]).
    pub track_round_trips: Vec<f32>,
    /// As [`SequenceResult::splits`].
    pub splits: Vec<(usize, Vec<usize>)>,
    /// As [`SequenceResult::merges`].
    pub merges: Vec<(Vec<usize>, usize)>,
    /// As [`SequenceResult::skipped_frames`].
    pub skipped_frames: Vec<SkippedFrame>,
    /// The skipped pairs as the pairs table reports them.
    pub skipped_pairs: Vec<SkippedPairRow>,
    /// Wall-clock time of each stage.
    pub timings: StageTimings,
}

impl Default for RunCounts {
    fn default() -> Self {
        // The sums start as `Iterator::sum` starts, so that adding the pairs one by one gives
        // the sum of the whole list to the last bit.
        let zero = || std::iter::empty::<f64>().sum::<f64>();
        Self {
            objects: 0,
            pairs: 0,
            local_percent_sum: zero(),
            optimisation_percent_sum: zero(),
            cost_sum: zero(),
            trackable_percent_sum: zero(),
            consistent_pairs: 0,
            round_trip_sum: zero(),
            field_residual_sum: zero(),
            tracks: 0,
            tracks_3_or_more: 0,
            track_round_trips: Vec::new(),
            splits: Vec::new(),
            merges: Vec::new(),
            skipped_frames: Vec::new(),
            skipped_pairs: Vec::new(),
            timings: StageTimings::default(),
        }
    }
}

impl RunCounts {
    /// The counts of a whole run.
    pub fn of(r: &SequenceResult) -> Self {
        let mut c = RunCounts {
            objects: r.objects.len(),
            splits: r.splits.clone(),
            merges: r.merges.clone(),
            skipped_frames: r.skipped_frames.clone(),
            skipped_pairs: r
                .skipped_pairs
                .iter()
                .map(|s| SkippedPairRow::of(r, s))
                .collect(),
            timings: r.timings,
            ..Default::default()
        };
        for p in &r.pairs {
            c.add_pair(&p.row);
        }
        for (k, n) in r.track_lengths().enumerate() {
            c.add_track(n, r.track_round_trip(k));
        }
        c
    }

    pub(crate) fn add_pair(&mut self, row: &PairRow) {
        self.pairs += 1;
        self.local_percent_sum += row.local_percent;
        self.optimisation_percent_sum += row.optimisation_percent;
        self.cost_sum += row.mean_cost;
        self.trackable_percent_sum += row.trackable_percent;
        if let Some(c) = row.consistency {
            self.consistent_pairs += 1;
            self.round_trip_sum += c.round_trip;
            self.field_residual_sum += c.field_residual;
        }
    }

    pub(crate) fn add_track(&mut self, steps: usize, round_trip: Option<f64>) {
        self.tracks += 1;
        if let Some(d) = round_trip {
            self.track_round_trips.push(d as f32);
        }
        if steps >= 3 {
            self.tracks_3_or_more += 1;
        }
    }

    /// `None` without pairs: a mean over nothing is not a number to report.
    fn mean(&self, sum: f64) -> Option<f64> {
        (self.pairs > 0).then(|| sum / self.pairs as f64)
    }
    /// Mean local matches over the matched pairs, in % (`None` without pairs).
    pub fn mean_local_percent(&self) -> Option<f64> {
        self.mean(self.local_percent_sum)
    }
    /// Mean optimisation matches over the matched pairs, in % (`None` without pairs).
    pub fn mean_optimisation_percent(&self) -> Option<f64> {
        self.mean(self.optimisation_percent_sum)
    }
    /// Mean over the matched pairs of their mean cost (`None` without pairs).
    pub fn mean_cost(&self) -> Option<f64> {
        self.mean(self.cost_sum)
    }
    /// Mean trackable matches over the matched pairs, in % (`None` without pairs).
    pub fn mean_trackable_percent(&self) -> Option<f64> {
        self.mean(self.trackable_percent_sum)
    }
    /// Mean over the pairs with consistency figures of their median round trip, in sensels
    /// (`None` without such pairs).
    pub fn mean_round_trip(&self) -> Option<f64> {
        let n = self.consistent_pairs;
        (n > 0).then(|| self.round_trip_sum / n as f64)
    }
    /// Mean over the pairs with consistency figures of their median field residual, in sensels
    /// (`None` without such pairs).
    pub fn mean_field_residual(&self) -> Option<f64> {
        let n = self.consistent_pairs;
        (n > 0).then(|| self.field_residual_sum / n as f64)
    }
    /// The tracks' round trips summarised, one per track (`None` when no track has one).
    pub fn track_round_trips(&self) -> Option<RoundTrips> {
        RoundTrips::of(self.track_round_trips.iter().copied())
    }
}
