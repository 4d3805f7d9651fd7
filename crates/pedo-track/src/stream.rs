//! Runs that do not hold the recording or its results: frames in windows, their objects built,
//! matched and chained, every result handed to a [`SequenceSink`] as soon as it is final.

use crate::pairing::PairingMethod;
use crate::*;
use modal_core::Shape;
use pedo_io::contour::Contour;
use pedo_io::recording::{FrameSource, Recording, FRAME_WINDOW};
use pedo_io::{IoError, Result};
use std::time::Instant;

/// [`run_sequence`] without holding the run: the frames go in windows of [`FRAME_WINDOW`];
/// each window's objects are built, handed to `sink`, their pairs matched and handed over,
/// their matches chained into tracks and each track handed over as soon as it has ended and
/// every track before it has gone. Only the open tracks and the objects they pass through are
/// held, so memory does not grow with the recording's length (only with its longest track).
/// Contour and surface models without drift correction; the isocontour model (one frame) and
/// drift correction (reference pairs across windows) run whole and are handed over after.
/// The results handed to `sink` are those of [`run_sequence`] with the same options (with
/// [`SequenceOptions::keep_match_details`] off: the pairs hold only their matches);
/// `progress` reports [`Stage::Matching`] in frames done.
pub fn stream_sequence(
    recording: &Recording,
    mut source: Option<&mut dyn FrameSource>,
    options: &SequenceOptions,
    progress: &(dyn Fn(Stage, usize, usize) + Sync),
    sink: &mut dyn SequenceSink,
) -> Result<RunCounts> {
    let measures_threshold = options.contour.preprocess.threshold.unwrap_or(0.0);
    let (start, end) = options.frames.unwrap_or((0, recording.n_frames()));
    if !streams(options) {
        if source.is_some() {
            return Err(IoError::invalid(
                "this run needs the whole recording (isocontour model or drift correction)",
            ));
        }
        let r = run_sequence(recording, options, progress)?;
        return replay(recording, options, &r, sink);
    }
    if start >= end || end > recording.n_frames() {
        return Err(IoError::invalid(format!(
            "frame range {start}..{end} is empty or beyond the {} of the recording",
            pedo_io::counted(recording.n_frames(), "frame")
        )));
    }
    let mut options = options.clone();
    options.keep_match_details = false;
    let options = &options;
    let mut counts = RunCounts::default();
    let mut held = Held::default();
    let mut chain = Chainer::default();
    // The last frame built: its first object and (contour model) its contours, or (surface
    // model) its object, if any.
    let mut last_contours: Option<(usize, Vec<Contour>)> = None;
    let mut last_surface: Option<(usize, usize)> = None;
    let threshold = options.surface.preprocess.threshold.unwrap_or(0.0);
    let keep = |s: &Shape| s.len() >= options.min_nodes.max(3);
    let mut w0 = start;
    while w0 < end {
        let w1 = (w0 + FRAME_WINDOW).min(end);
        let t0 = Instant::now();
        // The window's frames: those of `recording`, or read from `source` (numbered from w0).
        let read = match source.as_mut() {
            Some(s) => Some(s.window(recording, w0, w1)?),
            None => None,
        };
        let (frames, offset) = match &read {
            Some(r) => (r, w0),
            None => (recording, 0),
        };
        let first_new = held.end();
        // The window's candidate pairs (ids), splits and merges.
        let mut candidates: Vec<(usize, usize)> = Vec::new();
        let (mut splits, mut merges) = (Vec::new(), Vec::new());
        match options.model {
            ObjectModel::Contour => {
                let per_frame: Vec<FrameObjects> = per_frame_or_skipped(
                    w0..w1,
                    &mut counts.skipped_frames,
                    options.cancel.as_ref(),
                    |t| frame_contours(frames, t - offset, options),
                )?;
                for (k, (cs, shapes)) in per_frame.into_iter().enumerate() {
                    let first = held.end();
                    for (index, (shape, measures)) in shapes.into_iter().enumerate() {
                        held.push(SequenceObject {
                            id: held.end(),
                            frame: w0 + k,
                            index,
                            level: None,
                            shape,
                            measures: Some(measures),
                        });
                    }
                    if let Some((fa, previous)) = &last_contours {
                        let (fa, fb) = (*fa, first);
                        let p =
                            crate::pairing::pair_contours(previous, &cs, PairingMethod::default())?;
                        candidates.extend(p.pairs.iter().map(|&(i, j)| (fa + i, fb + j)));
                        splits.extend(
                            p.splits
                                .iter()
                                .map(|(i, js)| (fa + i, js.iter().map(|j| fb + j).collect())),
                        );
                        merges.extend(
                            p.merges
                                .iter()
                                .map(|(is, j)| (is.iter().map(|i| fa + i).collect(), fb + j)),
                        );
                    }
                    last_contours = Some((first, cs));
                }
            }
            ObjectModel::Surface | ObjectModel::Isocontour => {
                let per_frame: Vec<Option<Shape>> = per_frame_or_skipped(
                    w0..w1,
                    &mut counts.skipped_frames,
                    options.cancel.as_ref(),
                    |t| frame_surface(frames, t - offset, threshold, options, &keep),
                )?;
                for (k, shape) in per_frame.into_iter().enumerate() {
                    let frame = w0 + k;
                    match shape {
                        Some(shape) => {
                            let o = held.end();
                            if let Some((p, pf)) = last_surface
                                && pf + 1 == frame
                            {
                                candidates.push((p, o));
                            }
                            held.push(SequenceObject {
                                id: o,
                                frame,
                                index: 0,
                                level: None,
                                shape,
                                measures: None,
                            });
                            last_surface = Some((o, frame));
                        }
                        None => last_surface = None,
                    }
                }
            }
        }
        sink.frames(
            w0,
            &frames.measures_of(measures_threshold, w0 - offset..w1 - offset),
        )?;
        drop(read);
        for id in first_new..held.end() {
            sink.object(held.get(id)?)?;
        }
        counts.objects = held.end();
        let t1 = Instant::now();

        // The window's pairs, matched on the held objects (numbered from `held.base`).
        let base = held.base;
        let local = |id: usize| id - base;
        let local_candidates: Vec<(usize, usize)> = candidates
            .iter()
            .map(|&(a, b)| (local(a), local(b)))
            .collect();
        let local_splits: Vec<(usize, Vec<usize>)> = splits
            .iter()
            .map(|(i, js): &(usize, Vec<usize>)| {
                (local(*i), js.iter().map(|&j| local(j)).collect())
            })
            .collect();
        let local_merges: Vec<(Vec<usize>, usize)> = merges
            .iter()
            .map(|(is, j): &(Vec<usize>, usize)| {
                (is.iter().map(|&i| local(i)).collect(), local(*j))
            })
            .collect();
        let parts = parts_of_wholes(&local_candidates, &local_splits, &local_merges);
        let objects = held.objects.make_contiguous();
        let (mut pairs, skipped) =
            match_all(objects, &local_candidates, &parts, options, &|_, _, _| {});
        pedo_io::cancel::check(options.cancel.as_ref())?;
        for p in &mut pairs {
            p.a += base;
            p.b += base;
        }
        for s in skipped {
            let (oa, ob) = (held.get(s.a + base)?, held.get(s.b + base)?);
            counts
                .skipped_pairs
                .push(SkippedPairRow::of_objects(oa, ob, &s.reason));
        }
        for p in &pairs {
            sink.pair(p, held.get(p.a)?, held.get(p.b)?)?;
            counts.add_pair(&p.row);
        }
        counts.splits.extend(splits);
        counts.merges.extend(merges);
        let t2 = Instant::now();

        // Every pair leaving an object before the window's last frame is known now.
        let last_first = match options.model {
            ObjectModel::Contour => last_contours.as_ref().map_or(held.end(), |l| l.0),
            _ => last_surface.map_or(held.end(), |l| l.0),
        };
        chain.chain(
            &held,
            first_new..held.end(),
            &pairs,
            last_first,
            &mut |k, track| {
                counts.add_track(track.steps.len());
                sink.track(k, &held_steps(&held, &track)?)
            },
        )?;
        drop(pairs);
        // The objects before both the first open track and the last frame are done.
        held.drop_below(chain.first_object().unwrap_or(usize::MAX).min(last_first));
        let t3 = Instant::now();
        counts.timings.objects += t1 - t0;
        counts.timings.matching += t2 - t1;
        counts.timings.tracks += t3 - t2;
        progress(Stage::Matching, w1 - start, end - start);
        w0 = w1;
    }
    let t = Instant::now();
    chain.finish(&mut |k, track| {
        counts.add_track(track.steps.len());
        sink.track(k, &held_steps(&held, &track)?)
    })?;
    counts.timings.tracks += t.elapsed();
    Ok(counts)
}

/// Whether [`stream_sequence`] streams a run with these options (the contour and surface
/// models without drift correction) rather than running it whole.
pub fn streams(options: &SequenceOptions) -> bool {
    streamable(options.model, options.drift_reference) && options.frame_step() == 1
}

/// The rule of [`streams`] and [`RunParams::streams`]: the isocontour model matches the levels
/// of one frame, and drift correction pairs frames across windows, so both run whole.
pub(crate) fn streamable(model: ObjectModel, drift_reference: usize) -> bool {
    model != ObjectModel::Isocontour && drift_reference < 2
}

/// The objects of a streamed run still needed: ids `base..base + objects.len()`.
#[derive(Default)]
pub(crate) struct Held {
    base: usize,
    objects: std::collections::VecDeque<SequenceObject>,
}

impl Held {
    /// One past the last object's id.
    fn end(&self) -> usize {
        self.base + self.objects.len()
    }
    fn push(&mut self, o: SequenceObject) {
        self.objects.push_back(o);
    }
    fn get(&self, id: usize) -> Result<&SequenceObject> {
        id.checked_sub(self.base)
            .and_then(|k| self.objects.get(k))
            .ok_or_else(|| {
                IoError::invalid(format!(
                    "internal error (please report it): object {id} no longer held"
                ))
            })
    }
    /// Lets go of the objects before `id`.
    fn drop_below(&mut self, id: usize) {
        while self.base < id && self.objects.pop_front().is_some() {
            self.base += 1;
        }
    }
}

/// A track's steps with their objects, as a [`SequenceSink`] takes them.
pub(crate) fn held_steps<'h>(
    held: &'h Held,
    track: &Track,
) -> Result<Vec<(&'h SequenceObject, usize)>> {
    track
        .steps
        .iter()
        .map(|&(o, n)| held.get(o).map(|obj| (obj, n)))
        .collect()
}

/// The objects [`Chainer`] reads by id: a whole run's, or the window a stream holds.
pub(crate) trait ObjectsById {
    fn object(&self, id: usize) -> Result<&SequenceObject>;
}

impl ObjectsById for Held {
    fn object(&self, id: usize) -> Result<&SequenceObject> {
        self.get(id)
    }
}

impl ObjectsById for [SequenceObject] {
    fn object(&self, id: usize) -> Result<&SequenceObject> {
        self.get(id).ok_or_else(|| {
            IoError::invalid(format!(
                "a pair names object {id}, beyond the {} objects chained",
                self.len()
            ))
        })
    }
}
