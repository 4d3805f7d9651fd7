//! The events of a run as [`stream_sequence`] hands them over: the
//! [`SequenceSink`] trait that every writer of a run implements (tables, in `pedo-output`), and
//! [`replay`], which hands a whole [`SequenceResult`] to a sink in the same order, so that a whole
//! run and a streamed one are written by the same code.

use crate::*;
use pedo_io::{Recording, Result};

/// Where [`stream_sequence`] hands a run's results as they are made, each kind in the order of
/// the [`SequenceResult`] that [`run_sequence`] would return.
pub trait SequenceSink {
    /// The measures of frames `first..first + measures.len()` (counting values above the
    /// run's noise threshold, as the frames table does), in frame order, once each.
    fn frames(
        &mut self,
        first: usize,
        measures: &[pedo_io::recording::FrameMeasures],
    ) -> Result<()>;
    /// An object, in id order.
    fn object(&mut self, object: &SequenceObject) -> Result<()>;
    /// A matched pair with its two objects, in the order of [`SequenceResult::pairs`].
    fn pair(&mut self, pair: &PairMatch, a: &SequenceObject, b: &SequenceObject) -> Result<()>;
    /// Track number `index` (in order from 0): its steps as object and node.
    fn track(&mut self, index: usize, steps: &[(&SequenceObject, usize)]) -> Result<()>;
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
    ) -> Result<()>;
}

/// Hands a whole run of `recording` with `options` to `sink`, as [`stream_sequence`] hands a
/// streamed one: its objects, pairs, tracks and reference pairs, then the measures of the frames
/// it used; returns its counts. A writer that implements [`SequenceSink`] thus writes a whole
/// run and a streamed one by the same code.
pub fn replay(
    recording: &Recording,
    options: &SequenceOptions,
    r: &SequenceResult,
    sink: &mut dyn SequenceSink,
) -> Result<RunCounts> {
    for o in &r.objects {
        sink.object(o)?;
    }
    for p in &r.pairs {
        sink.pair(p, &r.objects[p.a], &r.objects[p.b])?;
    }
    for (k, t) in r.all_tracks().enumerate() {
        let steps: Vec<(&SequenceObject, usize)> =
            t.steps.iter().map(|&(o, n)| (&r.objects[o], n)).collect();
        sink.track(k, &steps)?;
    }
    for (p, tracked) in r.reference_pairs.iter().zip(r.reference_tracked()) {
        sink.reference_pair(p, &r.objects[p.a], &r.objects[p.b], &tracked)?;
    }
    let threshold = options.contour.preprocess.threshold.unwrap_or(0.0);
    let (start, end) = options.frames.unwrap_or((0, recording.n_frames()));
    sink.frames(start, &recording.measures_of(threshold, start..end))?;
    Ok(RunCounts::of(r))
}

/// A sink that keeps nothing (a run whose counts alone are wanted).
pub struct NoSink;

impl SequenceSink for NoSink {
    fn frames(&mut self, _: usize, _: &[pedo_io::FrameMeasures]) -> Result<()> {
        Ok(())
    }
    fn object(&mut self, _: &SequenceObject) -> Result<()> {
        Ok(())
    }
    fn pair(&mut self, _: &PairMatch, _: &SequenceObject, _: &SequenceObject) -> Result<()> {
        Ok(())
    }
    fn track(&mut self, _: usize, _: &[(&SequenceObject, usize)]) -> Result<()> {
        Ok(())
    }
    fn reference_pair(
        &mut self,
        _: &PairMatch,
        _: &SequenceObject,
        _: &SequenceObject,
        _: &[bool],
    ) -> Result<()> {
        Ok(())
    }
}
