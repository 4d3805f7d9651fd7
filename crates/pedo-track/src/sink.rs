//! The events of a run: the [`SequenceSink`] trait that every writer of a run implements (the
//! tables, figures and report of `pedo-output`; [`Collect`], which gathers a whole
//! [`SequenceResult`]), and [`replay`], which hands a result already made to a sink in the order
//! the engine ([`stream_sequence`]) hands a run over as it goes.
//!
//! A run is one stream of events whatever keeps it: [`run_sequence`] is the engine feeding a
//! [`Collect`], and a folder is written by the same sinks from the engine or from [`replay`].

use crate::*;
use pedo_io::recording::FrameMeasures;
use pedo_io::{Recording, Result, StoredValues};

/// Where a run hands its results, each as soon as it is final. Each kind of event comes in the
/// order of the [`SequenceResult`] that [`run_sequence`] returns; the kinds interleave (a frame's
/// objects before the pairs that end on them, a track once it has ended). Every method does
/// nothing by default, so that a sink names only the events it uses and a new kind of event
/// breaks no sink.
pub trait SequenceSink {
    /// The measures of frames `first..first + measures.len()` (counting values above the
    /// run's noise threshold, as the frames table does), in frame order, once each.
    fn frames(&mut self, first: usize, measures: &[FrameMeasures]) -> Result<()> {
        let _ = (first, measures);
        Ok(())
    }
    /// Whether this sink wants the values of the run's frames ([`frame_values`](Self::frame_values)):
    /// the engine hands them only then (no sink wants them by default).
    fn wants_frame_values(&self) -> bool {
        false
    }
    /// The values of frame `frame` (`rows × cols` row-major, the file's units, 0 at missing
    /// sensors), for a sink that [wants them](Self::wants_frame_values): every frame of the run's
    /// range in order, as [`frames`](Self::frames) (a frame stride leaves no frame out: the
    /// measures of a recording, `pedo_io::measures`, take all of them), right after the
    /// `frames` event of its window.
    fn frame_values(&mut self, frame: usize, values: &[f32]) -> Result<()> {
        let _ = (frame, values);
        Ok(())
    }
    /// [`frame_values`](Self::frame_values) of a frame given by the values it holds (a frame
    /// held sparsely, or one of zeros: [`Recording::stored_values`]). By default the sink is
    /// handed the whole frame; a sink that can take the values held alone does, so that the
    /// empty frames of a long recording, or the few values of a large plate, cost what they
    /// hold.
    fn stored_frame_values(&mut self, frame: usize, stored: StoredValues<'_>) -> Result<()> {
        self.frame_values(frame, &stored.to_frame())
    }
    /// Frame `frame` is built: its objects in id order (none for a frame without contact or
    /// skipped, [`SequenceResult::skipped_frames`]). The contour and surface models hand every
    /// kept frame of the run in order ([`SequenceOptions::kept_frames`]: every frame but with a
    /// frame stride), each before any pair that ends on its objects; the
    /// isocontour model hands its one frame with every level.
    fn frame_objects(&mut self, frame: usize, objects: &[SequenceObject]) -> Result<()> {
        let _ = (frame, objects);
        Ok(())
    }
    /// A matched pair with its two objects, in the order of [`SequenceResult::pairs`].
    fn pair(&mut self, pair: &PairMatch, a: &SequenceObject, b: &SequenceObject) -> Result<()> {
        let _ = (pair, a, b);
        Ok(())
    }
    /// A candidate pair that could not be matched ([`SequenceResult::skipped_pairs`]), with
    /// its two objects and why, before the pairs matched beside it.
    fn skipped_pair(&mut self, a: &SequenceObject, b: &SequenceObject, reason: &str) -> Result<()> {
        let _ = (a, b, reason);
        Ok(())
    }
    /// Every pair, matched or skipped, that leaves an object before object `object` has been
    /// handed over (the objects before it will be continued by no other): a sink that follows
    /// objects into their successors can take them from here.
    fn settled(&mut self, object: usize) -> Result<()> {
        let _ = object;
        Ok(())
    }
    /// Track number `index` (in order from 0), once it has ended: its steps as object and node,
    /// and its round trip in sensels ([`crate::chain_tracks_checked`]; `None` for a track of
    /// one step, through a pair without a field, or anchored by drift correction).
    fn track(
        &mut self,
        index: usize,
        steps: &[(&SequenceObject, usize)],
        round_trip: Option<f64>,
    ) -> Result<()> {
        let _ = (index, steps, round_trip);
        Ok(())
    }
    /// A reference pair of drift correction with its two objects, in the order of
    /// [`SequenceResult::reference_pairs`], after every track; `tracked` as
    /// [`SequenceResult::reference_tracked`] gives it for this pair. A run without drift
    /// correction hands none.
    fn reference_pair(
        &mut self,
        pair: &PairMatch,
        a: &SequenceObject,
        b: &SequenceObject,
        tracked: &[bool],
    ) -> Result<()> {
        let _ = (pair, a, b, tracked);
        Ok(())
    }
}

/// Hands a whole run of `recording` with `options` to `sink`, each kind of event in the order
/// the engine hands it: the measures of the frames used, each frame's objects, the pairs, the
/// tracks and the reference pairs; returns its counts. A writer that implements
/// [`SequenceSink`] thus writes a result already made and a run as it goes by the same code.
pub fn replay(
    recording: &Recording,
    options: &SequenceOptions,
    r: &SequenceResult,
    sink: &mut dyn SequenceSink,
) -> Result<RunCounts> {
    let threshold = options.contour.preprocess.threshold.unwrap_or(0.0);
    let (start, end) = options.frames.unwrap_or((0, recording.n_frames()));
    sink.frames(start, &recording.measures_of(threshold, start..end))?;
    crate::stream::hand_values(recording, 0, start..end, sink)?;
    replay_frames(options, (start, end), &r.objects, sink)?;
    replay_matches(r, sink)?;
    Ok(RunCounts::of(r))
}

/// Hands the objects, pairs, tracks and reference pairs of a result already made to `sink`, in
/// the engine's order, without the recording: each frame holding objects (frames without any
/// are not handed, nor the frames' measures and values). For a writer that needs only these
/// events (the tracks figure and the report, gathered from a whole result); [`replay`] hands
/// every event.
pub fn replay_result(r: &SequenceResult, sink: &mut dyn SequenceSink) -> Result<()> {
    let mut frames: Vec<usize> = r.objects.iter().map(|o| o.frame).collect();
    frames.dedup();
    crate::stream::hand_frames(frames, &r.objects, sink)?;
    replay_matches(r, sink)
}

/// The pairs, tracks and reference pairs of `r`, as [`replay`] hands them.
fn replay_matches(r: &SequenceResult, sink: &mut dyn SequenceSink) -> Result<()> {
    for s in &r.skipped_pairs {
        sink.skipped_pair(&r.objects[s.a], &r.objects[s.b], &s.reason)?;
    }
    for p in &r.pairs {
        sink.pair(p, &r.objects[p.a], &r.objects[p.b])?;
    }
    sink.settled(r.objects.len())?;
    for (k, t) in r.all_tracks().enumerate() {
        let steps: Vec<(&SequenceObject, usize)> =
            t.steps.iter().map(|&(o, n)| (&r.objects[o], n)).collect();
        sink.track(k, &steps, r.track_round_trip(k))?;
    }
    for (p, tracked) in r.reference_pairs.iter().zip(r.reference_tracked()) {
        sink.reference_pair(p, &r.objects[p.a], &r.objects[p.b], &tracked)?;
    }
    Ok(())
}

/// The [`SequenceSink::frame_objects`] events of `objects` (in frame order): every kept frame
/// of `start..end` ([`SequenceOptions::kept_frames`]) for the contour and surface models, the one frame of the isocontour model.
fn replay_frames(
    options: &SequenceOptions,
    (start, end): (usize, usize),
    objects: &[SequenceObject],
    sink: &mut dyn SequenceSink,
) -> Result<()> {
    if options.model == ObjectModel::Isocontour {
        return match objects.first() {
            Some(o) => sink.frame_objects(o.frame, objects),
            None => Ok(()),
        };
    }
    crate::stream::hand_frames(options.kept_frames(start, end), objects, sink)
}

/// A sink that keeps nothing (a run whose counts alone are wanted).
pub struct NoSink;

impl SequenceSink for NoSink {}

/// A sink that gathers the whole run as the [`SequenceResult`] [`run_sequence`] returns: what
/// [`run_sequence`] is made of, and what a writer that needs the whole run (a figure of every
/// track, the report) keeps. With `details` off each pair is kept without its match details
/// ([`PairMatch::without_details`]) and the tracks packed ([`PackedTracks`]), as a run with
/// [`SequenceOptions::keep_match_details`] off holds them.
pub struct Collect {
    details: bool,
    result: SequenceResult,
}

impl Collect {
    /// An empty gathering; `details`: keep each pair's whole match and the tracks unpacked.
    pub fn new(details: bool) -> Self {
        let result = SequenceResult {
            packed_tracks: (!details).then(PackedTracks::default),
            ..SequenceResult::default()
        };
        Self { details, result }
    }

    /// The run gathered, completed by its `counts` (splits, merges, what was skipped, timings).
    pub fn into_result(self, counts: RunCounts) -> SequenceResult {
        let mut r = self.result;
        if let Some(p) = r.packed_tracks.as_mut() {
            p.shrink_to_fit();
        }
        r.splits = counts.splits;
        r.merges = counts.merges;
        r.skipped_frames = counts.skipped_frames;
        r.skipped_pairs = counts
            .skipped_pairs
            .into_iter()
            .map(|s| SkippedPair {
                a: s.objects.id_a,
                b: s.objects.id_b,
                reason: s.reason,
            })
            .collect();
        r.timings = counts.timings;
        r
    }

    fn kept(&self, pair: &PairMatch) -> Result<PairMatch> {
        if self.details {
            Ok(pair.clone())
        } else {
            pair.without_details()
        }
    }
}

impl SequenceSink for Collect {
    fn frame_objects(&mut self, _: usize, objects: &[SequenceObject]) -> Result<()> {
        self.result.objects.extend_from_slice(objects);
        Ok(())
    }
    fn pair(&mut self, pair: &PairMatch, _: &SequenceObject, _: &SequenceObject) -> Result<()> {
        let kept = self.kept(pair)?;
        self.result.pairs.push(kept);
        Ok(())
    }
    fn track(
        &mut self,
        _: usize,
        steps: &[(&SequenceObject, usize)],
        round_trip: Option<f64>,
    ) -> Result<()> {
        let track = Track {
            steps: steps.iter().map(|&(o, n)| (o.id, n)).collect(),
        };
        self.result.track_round_trips.push(round_trip);
        match self.result.packed_tracks.as_mut() {
            Some(packed) => packed.push(&track),
            None => self.result.tracks.push(track),
        }
        Ok(())
    }
    fn reference_pair(
        &mut self,
        pair: &PairMatch,
        _: &SequenceObject,
        _: &SequenceObject,
        _: &[bool],
    ) -> Result<()> {
        let kept = self.kept(pair)?;
        self.result.reference_pairs.push(kept);
        Ok(())
    }
}
