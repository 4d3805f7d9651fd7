//! The run engine, the one loop of every run: frames in windows, their objects built, matched
//! and chained, every result handed to a [`SequenceSink`] as soon as it is final. A whole run
//! ([`run_sequence`]) is this loop feeding a [`Collect`].

use crate::pairing::PairingMethod;
use crate::*;
use modal_core::{Prealign, Shape};
use pedo_io::contour::Contour;
use pedo_io::recording::{FrameSource, Recording, FRAME_WINDOW};
use pedo_io::{IoError, Result};
use std::collections::HashMap;
use std::ops::Range;
use std::sync::OnceLock;
use std::time::Instant;

/// Runs `recording` with `options`, handing every result to `sink` as soon as it is final:
/// the frames go in windows of [`FRAME_WINDOW`]; each window's objects are built (in
/// parallel, on its kept frames: every [`SequenceOptions::frame_step`]-th of the run) and
/// handed over frame by frame, their pairs matched (in parallel) and handed
/// over, their matches chained into tracks and each track handed over as soon as it has ended
/// and every track before it has gone. Returns the run's counts.
///
/// Only the open tracks and the objects they pass through are held, so memory does not grow
/// with the recording's length (only with its longest track) — except with drift correction,
/// whose reference pairs reach back across windows: its objects and matches (without their
/// details) are held to the end, where the reference pairs are matched and the tracks anchored
/// ([`crate::drift`]). The isocontour model builds the levels of its one frame first.
///
/// `source` reads the frames window by window when `recording` holds none (see
/// [`pedo_io::formats::read_for_streaming`]); the isocontour model, which picks its frame
/// among all, needs them held. `progress` reports [`Stage::Matching`] in frames done (the
/// isocontour model: [`Stage::Objects`] in levels, then [`Stage::Matching`] in pairs).
///
/// A frame whose objects cannot be built and a pair that cannot be matched do not fail the run:
/// they are reported in [`RunCounts::skipped_frames`] and [`RunCounts::skipped_pairs`].
///
/// # Errors
///
/// [`IoError::InvalidInput`] when [`SequenceOptions::frames`] is empty or reaches past the
/// recording, or the isocontour frame is not in the recording; errors of the isocontour
/// model's options, of the contour pairing, of `source` and of `sink`; [`IoError::Cancelled`]
/// once [`SequenceOptions::cancel`] is cancelled.
pub fn stream_sequence(
    recording: &Recording,
    mut source: Option<&mut dyn FrameSource>,
    options: &SequenceOptions,
    progress: &(dyn Fn(Stage, usize, usize) + Sync),
    sink: &mut dyn SequenceSink,
) -> Result<RunCounts> {
    let (start, end) = options.frames.unwrap_or((0, recording.n_frames()));
    if start >= end || end > recording.n_frames() {
        return Err(IoError::invalid(format!(
            "frame range {start}..{end} is empty or beyond the {} of the recording",
            pedo_io::counted(recording.n_frames(), "frame")
        )));
    }
    let mut run = Engine::new(options, start..end);
    if options.model == ObjectModel::Isocontour {
        if source.is_some() {
            return Err(IoError::invalid(
                "this run needs the whole recording (isocontour model)",
            ));
        }
        run.isocontours(recording, progress, sink)?;
    }
    let mut w0 = start;
    while w0 < end {
        let w1 = (w0 + FRAME_WINDOW).min(end);
        let t = Instant::now();
        // The window's frames: those of `recording`, or read from `source` (numbered from w0).
        let read = match source.as_mut() {
            Some(s) => Some(s.window(recording, w0, w1)?),
            None => None,
        };
        run.counts.timings.objects += t.elapsed();
        let (frames, offset) = match &read {
            Some(r) => (r, w0),
            None => (recording, 0),
        };
        let new = run.build(frames, offset, w0..w1, sink)?;
        // The frames are done with: only the objects are needed from here.
        drop(read);
        if let Some(new) = new {
            run.match_and_chain(new, w0..w1, progress, sink)?;
        }
        w0 = w1;
    }
    // What the source read is checked (a file's digest) before the run's outputs are made.
    if let Some(s) = source.as_mut() {
        s.finish(recording)?;
    }
    run.finish(sink)
}

/// Hands the values of frames `w` of `frames` (whose frame 0 is frame `offset` of the run's
/// recording) to `sink`, when it [wants them](SequenceSink::wants_frame_values).
pub(crate) fn hand_values(
    frames: &Recording,
    offset: usize,
    w: Range<usize>,
    sink: &mut dyn SequenceSink,
) -> Result<()> {
    if !sink.wants_frame_values() {
        return Ok(());
    }
    let mut room = Vec::new();
    for t in w {
        if let Some(stored) = frames.stored_values(t - offset) {
            sink.stored_frame_values(t, stored)?;
            continue;
        }
        let values = frames
            .frame_into(t - offset, &mut room)
            .ok_or_else(|| IoError::invalid(format!("frame {t} is beyond the frames read")))?;
        sink.frame_values(t, values)?;
    }
    Ok(())
}

/// The state of a run between windows.
struct Engine<'o> {
    options: &'o SequenceOptions,
    frames: Range<usize>,
    counts: RunCounts,
    /// The objects still needed (every object with drift correction).
    held: Held,
    chain: Chainer,
    /// The last frame built: its first object and (contour model) its contours, or (surface
    /// model) its object and frame, if any.
    last_contours: Option<(usize, Vec<Contour>)>,
    last_surface: Option<(usize, usize)>,
    /// Drift correction: what the reference pairs and the anchored tracks are made of at the end.
    drift: Option<Anchoring>,
    /// What a frame that holds no value makes (the same for every such frame of the run).
    empty: EmptyFrame,
}

/// The objects of a frame that holds no value ([`Recording::stored_values`]), made once: they
/// depend on the run's options and the frames' size and mask only, so a recording of many
/// empty frames (a long wait on the plate, or a small file claiming many) costs no more than
/// one of them for its objects.
#[derive(Default)]
struct EmptyFrame {
    contours: OnceLock<FrameObjects>,
    surface: OnceLock<Option<Shape>>,
}

/// Whether frame `t` of `frames` holds no value.
fn holds_nothing(frames: &Recording, t: usize) -> bool {
    frames.stored_values(t).is_some_and(|s| s.is_empty())
}

/// `build()`, or for a frame that holds no value the result `once` keeps of the first such
/// frame built (an error is not kept: it is the frame's skipped reason, made again).
fn once_if_empty<T: Clone>(
    once: &OnceLock<T>,
    empty: bool,
    build: impl FnOnce() -> Result<T>,
) -> Result<T> {
    if !empty {
        return build();
    }
    if let Some(kept) = once.get() {
        return Ok(kept.clone());
    }
    let made = build()?;
    Ok(once.get_or_init(|| made).clone())
}

/// What drift correction holds to the end: every candidate pair and every pair matched (without
/// its details); the objects are all held.
#[derive(Default)]
struct Anchoring {
    candidates: Vec<(usize, usize)>,
    pairs: Vec<PairMatch>,
}

/// The pairs a window's objects bring: candidates to match, splits and merges (object ids).
#[derive(Default)]
struct NewPairs {
    /// The first object of the window.
    first: usize,
    candidates: Vec<(usize, usize)>,
    splits: Vec<(usize, Vec<usize>)>,
    merges: Vec<(Vec<usize>, usize)>,
}

impl<'o> Engine<'o> {
    fn new(options: &'o SequenceOptions, frames: Range<usize>) -> Self {
        Self {
            options,
            frames,
            counts: RunCounts::default(),
            held: Held::default(),
            chain: Chainer::default(),
            last_contours: None,
            last_surface: None,
            drift: options.drift_corrected().then(Anchoring::default),
            empty: EmptyFrame::default(),
        }
    }

    /// The isocontour model's objects, the levels of one frame, matched and chained.
    fn isocontours(
        &mut self,
        recording: &Recording,
        progress: &(dyn Fn(Stage, usize, usize) + Sync),
        sink: &mut dyn SequenceSink,
    ) -> Result<()> {
        let t0 = Instant::now();
        let range = (self.frames.start, self.frames.end);
        let levels = isocontour_objects(recording, self.options, range, progress)?;
        self.counts.skipped_frames.extend(levels.skipped_frames);
        if let Some(frame) = levels.objects.first().map(|o| o.frame) {
            sink.frame_objects(frame, &levels.objects)?;
        }
        for o in levels.objects {
            self.held.push(o);
        }
        self.counts.objects = self.held.end();
        self.counts.timings.objects += t0.elapsed();
        let new = NewPairs {
            candidates: levels.pairs,
            ..NewPairs::default()
        };
        let t1 = Instant::now();
        let pairs = self.match_new(new, progress, sink)?;
        let t2 = Instant::now();
        // Every pair is known: the levels are one frame.
        sink.settled(self.held.end())?;
        self.chain_new(0, pairs, self.held.end(), sink)?;
        self.counts.timings.matching += t2 - t1;
        self.counts.timings.tracks += t2.elapsed();
        Ok(())
    }

    /// Hands over the measures of frames `w` (of `frames`, whose frame 0 is frame `offset` of
    /// the recording) and, but for the isocontour model, builds their objects and hands them
    /// over frame by frame; returns the pairs they bring.
    fn build(
        &mut self,
        frames: &Recording,
        offset: usize,
        w: Range<usize>,
        sink: &mut dyn SequenceSink,
    ) -> Result<Option<NewPairs>> {
        let t0 = Instant::now();
        let threshold = self.options.contour.preprocess.threshold.unwrap_or(0.0);
        sink.frames(
            w.start,
            &frames.measures_of(threshold, w.start - offset..w.end - offset),
        )?;
        hand_values(frames, offset, w.clone(), sink)?;
        let first = self.held.end();
        let new = match self.options.model {
            ObjectModel::Isocontour => None,
            ObjectModel::Contour => Some(self.contours(frames, offset, w.clone())?),
            ObjectModel::Surface => Some(self.surfaces(frames, offset, w.clone())?),
        };
        if new.is_some() {
            let (kept, base) = (self.kept(w), self.held.base);
            let all = self.held.objects.make_contiguous();
            hand_frames(kept, &all[first - base..], sink)?;
            self.counts.objects = self.held.end();
        }
        self.counts.timings.objects += t0.elapsed();
        Ok(new.map(|n| NewPairs { first, ..n }))
    }

    /// The frames of `w` objects are built on: every [`SequenceOptions::frame_step`]-th of the
    /// run from its first, wherever the windows begin.
    fn kept(&self, w: Range<usize>) -> Vec<usize> {
        let (start, step) = (self.frames.start, self.options.frame_step());
        w.filter(|t| (t - start).is_multiple_of(step)).collect()
    }

    /// The contours of the kept frames of `w` as objects, paired with those of the kept frame
    /// before by overlap (with their splits and merges).
    fn contours(&mut self, frames: &Recording, offset: usize, w: Range<usize>) -> Result<NewPairs> {
        let options = self.options;
        let kept = self.kept(w);
        let per_frame: Vec<FrameObjects> = per_kept_frame(
            &kept,
            &mut self.counts.skipped_frames,
            options.cancel.as_ref(),
            |t| {
                let empty = holds_nothing(frames, t - offset);
                once_if_empty(&self.empty.contours, empty, || {
                    frame_contours(frames, t - offset, options)
                })
            },
        )?;
        let mut new = NewPairs::default();
        for (frame, (cs, shapes)) in kept.into_iter().zip(per_frame) {
            let first = self.held.end();
            for (index, (shape, measures)) in shapes.into_iter().enumerate() {
                self.held.push(SequenceObject {
                    id: self.held.end(),
                    frame,
                    index,
                    level: None,
                    shape,
                    measures: Some(measures),
                });
            }
            if let Some((fa, previous)) = &self.last_contours {
                let p = crate::pairing::pair_contours(previous, &cs, PairingMethod::default())?;
                new.add(*fa, first, p);
            }
            self.last_contours = Some((first, cs));
        }
        Ok(new)
    }

    /// The pressure surfaces of the kept frames of `w` as objects, each paired with the kept
    /// frame before's.
    fn surfaces(&mut self, frames: &Recording, offset: usize, w: Range<usize>) -> Result<NewPairs> {
        let options = self.options;
        let threshold = options.surface.preprocess.threshold.unwrap_or(0.0);
        let keep = |s: &Shape| s.len() >= options.min_nodes.max(3);
        let kept = self.kept(w);
        let per_frame: Vec<Option<Shape>> = per_kept_frame(
            &kept,
            &mut self.counts.skipped_frames,
            options.cancel.as_ref(),
            |t| {
                let empty = holds_nothing(frames, t - offset);
                once_if_empty(&self.empty.surface, empty, || {
                    frame_surface(frames, t - offset, threshold, options, &keep)
                })
            },
        )?;
        let mut new = NewPairs::default();
        for (frame, shape) in kept.into_iter().zip(per_frame) {
            let Some(shape) = shape else {
                self.last_surface = None;
                continue;
            };
            let o = self.held.end();
            // The previous kept frame's surface, if that frame had one.
            if let Some((p, pf)) = self.last_surface
                && pf + options.frame_step() == frame
            {
                new.candidates.push((p, o));
            }
            self.held.push(SequenceObject {
                id: o,
                frame,
                index: 0,
                level: None,
                shape,
                measures: None,
            });
            self.last_surface = Some((o, frame));
        }
        Ok(new)
    }

    /// Matches the pairs of window `w` and chains them; `progress` hears of the frames done.
    fn match_and_chain(
        &mut self,
        new: NewPairs,
        w: Range<usize>,
        progress: &(dyn Fn(Stage, usize, usize) + Sync),
        sink: &mut dyn SequenceSink,
    ) -> Result<()> {
        let (start, total) = (self.frames.start, self.frames.len());
        // A pair done counts as its share of the window's frames.
        let (before, width) = (w.start - start, w.len());
        let frames_done = |_: Stage, n: usize, of: usize| {
            progress(Stage::Matching, before + width * n / of.max(1), total)
        };
        let first = new.first;
        let t1 = Instant::now();
        let pairs = self.match_new(new, &frames_done, sink)?;
        let t2 = Instant::now();
        // Every pair leaving an object before the window's last frame is known now.
        let settled = match self.options.model {
            ObjectModel::Contour => self.last_contours.as_ref().map(|l| l.0),
            _ => self.last_surface.map(|l| l.0),
        };
        let settled = settled.unwrap_or(self.held.end());
        self.chain_new(first, pairs, settled, sink)?;
        self.counts.timings.matching += t2 - t1;
        self.counts.timings.tracks += t2.elapsed();
        // A sink's own work on what is settled is none of the run's stages.
        sink.settled(settled)?;
        progress(Stage::Matching, w.end - start, total);
        Ok(())
    }

    /// Matches `new`'s candidate pairs on the held objects (in windows on the rayon pool) and
    /// hands each pair over; the pairs that cannot be matched are counted as skipped.
    fn match_new(
        &mut self,
        new: NewPairs,
        progress: &(dyn Fn(Stage, usize, usize) + Sync),
        sink: &mut dyn SequenceSink,
    ) -> Result<Vec<PairMatch>> {
        // The held objects are numbered from `base`: the pairs are matched in their numbering.
        let base = self.held.base;
        let local = |(a, b): (usize, usize)| (a - base, b - base);
        let candidates: Vec<(usize, usize)> = new.candidates.iter().map(|&p| local(p)).collect();
        let splits: Vec<(usize, Vec<usize>)> = (new.splits.iter())
            .map(|(i, js)| (*i - base, js.iter().map(|&j| j - base).collect()))
            .collect();
        let merges: Vec<(Vec<usize>, usize)> = (new.merges.iter())
            .map(|(is, j)| (is.iter().map(|&i| i - base).collect(), *j - base))
            .collect();
        let parts = parts_of_wholes(&candidates, &splits, &merges);
        let objects = self.held.objects.make_contiguous();
        let (mut pairs, skipped) = match_all(objects, &candidates, &parts, self.options, progress);
        // A cancelled run's pairs are incomplete (those not matched are skipped as "cancelled").
        pedo_io::cancel::check(self.options.cancel.as_ref())?;
        for p in &mut pairs {
            p.a += base;
            p.b += base;
        }
        for s in skipped {
            let (oa, ob) = (self.held.get(s.a + base)?, self.held.get(s.b + base)?);
            sink.skipped_pair(oa, ob, &s.reason)?;
            let row = SkippedPairRow::of_objects(oa, ob, &s.reason);
            self.counts.skipped_pairs.push(row);
        }
        for p in &pairs {
            sink.pair(p, self.held.get(p.a)?, self.held.get(p.b)?)?;
            self.counts.add_pair(&p.row);
        }
        if let Some(kept) = self.drift.as_mut() {
            kept.candidates.extend(new.candidates);
            for p in &pairs {
                kept.pairs.push(p.without_details()?);
            }
        }
        self.counts.splits.extend(new.splits);
        self.counts.merges.extend(new.merges);
        Ok(pairs)
    }

    /// Chains the objects from `first` on through `pairs` (every pair leaving an object before
    /// `settled` is known), hands over the tracks that have ended and lets go of the objects no
    /// open track needs. With drift correction the tracks are made at the end instead.
    fn chain_new(
        &mut self,
        first: usize,
        pairs: Vec<PairMatch>,
        settled: usize,
        sink: &mut dyn SequenceSink,
    ) -> Result<()> {
        if self.drift.is_some() {
            return Ok(());
        }
        let (held, counts) = (&self.held, &mut self.counts);
        self.chain.chain(
            held,
            first..held.end(),
            &pairs,
            settled,
            &mut |k, track, trip| {
                counts.add_track(track.steps.len(), trip);
                sink.track(k, &held_steps(held, &track)?, trip)
            },
        )?;
        drop(pairs);
        // The objects before both the first open track and the last frame are done.
        let open = self.chain.first_object().unwrap_or(usize::MAX);
        self.held.drop_below(open.min(settled));
        Ok(())
    }

    /// Hands over the tracks left (with drift correction: every track, anchored on the
    /// reference pairs, then the reference pairs); returns the run's counts.
    fn finish(mut self, sink: &mut dyn SequenceSink) -> Result<RunCounts> {
        let t = Instant::now();
        match self.drift.take() {
            Some(kept) => self.anchor(&kept.candidates, &kept.pairs, sink)?,
            None => {
                let (held, counts) = (&self.held, &mut self.counts);
                self.chain.finish(&mut |k, track, trip| {
                    counts.add_track(track.steps.len(), trip);
                    sink.track(k, &held_steps(held, &track)?, trip)
                })?;
            }
        }
        // Drift correction matches its reference pairs after the run's pairs.
        pedo_io::cancel::check(self.options.cancel.as_ref())?;
        self.counts.timings.tracks += t.elapsed();
        Ok(self.counts)
    }

    /// Drift correction: the reference pairs matched, the tracks chained through them first
    /// ([`crate::drift::anchored_tracks`]), then both handed over.
    fn anchor(
        &mut self,
        candidates: &[(usize, usize)],
        pairs: &[PairMatch],
        sink: &mut dyn SequenceSink,
    ) -> Result<()> {
        if self.held.base != 0 {
            return Err(IoError::invalid(
                "internal error (please report it): drift correction let go of objects",
            ));
        }
        let objects: &[SequenceObject] = self.held.objects.make_contiguous();
        let refs = reference_matches(objects, candidates, self.frames.start, self.options);
        let tracks = crate::drift::anchored_tracks(objects, pairs, &refs)?;
        for (k, t) in tracks.iter().enumerate() {
            self.counts.add_track(t.steps.len(), None);
            let steps: Vec<(&SequenceObject, usize)> =
                t.steps.iter().map(|&(o, n)| (&objects[o], n)).collect();
            sink.track(k, &steps, None)?;
        }
        let tracked = reference_tracked(objects, tracks.iter(), &refs);
        for (p, tracked) in refs.iter().zip(tracked) {
            sink.reference_pair(p, &objects[p.a], &objects[p.b], &tracked)?;
        }
        Ok(())
    }
}

impl NewPairs {
    /// The pairing `p` of the frame whose first object is `fa` with the next, whose first is
    /// `fb`, in object ids.
    fn add(&mut self, fa: usize, fb: usize, p: crate::pairing::Pairing) {
        let ids = |js: &[usize]| js.iter().map(|j| fb + j).collect();
        self.candidates
            .extend(p.pairs.iter().map(|&(i, j)| (fa + i, fb + j)));
        self.splits
            .extend(p.splits.iter().map(|(i, js)| (fa + i, ids(js))));
        self.merges.extend(
            p.merges
                .iter()
                .map(|(is, j)| (is.iter().map(|i| fa + i).collect(), fb + j)),
        );
    }
}

/// The reference pairs of drift correction ([`crate::drift::reference_pairs_every`] for the
/// kept frames from `start`) matched; those that cannot be matched are left out.
fn reference_matches(
    objects: &[SequenceObject],
    candidates: &[(usize, usize)],
    start: usize,
    options: &SequenceOptions,
) -> Vec<PairMatch> {
    let refs = crate::drift::reference_pairs_every(
        objects,
        candidates,
        start,
        options.drift_reference,
        options.frame_step(),
    );
    // Reference pairs lie frames apart: the sensor prior is for consecutive frames.
    let mut apart = options.clone();
    if apart.matching.prealign == Prealign::Sensor {
        apart.matching.prealign = Prealign::Robust;
    }
    let (matched, _) = match_all(objects, &refs, &HashMap::new(), &apart, &|_, _, _| {});
    matched
}

/// The [`SequenceSink::frame_objects`] event of every frame of `frames` (the kept frames, in
/// order), with its objects among `objects` (those of the frames, in frame order).
pub(crate) fn hand_frames(
    frames: impl IntoIterator<Item = usize>,
    objects: &[SequenceObject],
    sink: &mut dyn SequenceSink,
) -> Result<()> {
    let mut rest = objects;
    for frame in frames {
        let n = rest.iter().take_while(|o| o.frame == frame).count();
        let (these, after) = rest.split_at(n);
        sink.frame_objects(frame, these)?;
        rest = after;
    }
    Ok(())
}

/// Whether a run with these options keeps its memory flat ([`stream_sequence`]): the contour
/// and surface models without drift correction, with or without a frame stride (the windows
/// build the kept frames only and pair each with the kept frame before, across windows too).
/// The isocontour model needs its frames held (it picks one among them) and drift correction
/// holds every object to the end.
pub fn streams(options: &SequenceOptions) -> bool {
    streamable(options.model, options.drift_reference)
}

/// The rule of [`streams`] and [`RunParams::streams`].
pub(crate) fn streamable(model: ObjectModel, drift_reference: usize) -> bool {
    model != ObjectModel::Isocontour && drift_reference < 2
}

/// The objects of a run still needed: ids `base..base + objects.len()`.
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
