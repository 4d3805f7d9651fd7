//! Material points followed as a run streams: [`FollowSink`] takes the run's events, follows
//! each object once every pair leaving it is known ([`SequenceSink::settled`]) and hands every
//! point over once it has ended, holding only the objects and pairs of the frames it is
//! between and the points not yet ended.

use super::{
    surfaces_refused, FollowParams, FollowedPoint, Follower, Links, Mode, RunView, SeedPlacer,
};
use crate::*;
use modal_core::MatchResult;
use pedo_io::Result;
use std::collections::{HashMap, VecDeque};

/// Where [`FollowSink`] hands the points it follows.
pub trait PointsSink {
    /// Point `index` (numbered from 0 in the order seeded), once it has ended and every point
    /// before it has been handed over, with the frame of each of its steps.
    fn point(&mut self, index: usize, point: &FollowedPoint, frames: &[usize]) -> Result<()>;
}

/// A sink that follows the material points of a contour run as its events come
/// ([`super::run_points`]'s points: the outline nodes of every object that begins a lineage,
/// and the user's points and regions placed as their frames come), handing each point to a
/// [`PointsSink`] once it has ended: memory bounded by the longest lineage, not the run.
pub struct FollowSink<'a> {
    follower: Follower,
    placer: SeedPlacer<'a>,
    window: Window,
    /// The next object to follow.
    next: usize,
    /// Whether every object and pair is kept: the user's points and regions are carried back
    /// through the objects before theirs.
    keep_all: bool,
    out: &'a mut dyn PointsSink,
}

/// The objects and pairs of a streamed run the follower still reads: from object `base` on.
#[derive(Default)]
struct Window {
    base: usize,
    objects: VecDeque<SequenceObject>,
    links: Links,
    pairs: HashMap<(usize, usize), MatchResult>,
}

impl RunView for Window {
    fn held(&self) -> std::ops::Range<usize> {
        self.base..self.base + self.objects.len()
    }
    fn object(&self, id: usize) -> &SequenceObject {
        &self.objects[id - self.base]
    }
    fn pair(&self, a: usize, b: usize) -> Option<&MatchResult> {
        self.pairs.get(&(a, b))
    }
    fn links(&self) -> &Links {
        &self.links
    }
}

impl Window {
    /// Lets go of the objects and pairs before object `id`.
    fn drop_below(&mut self, id: usize) {
        while self.base < id && self.objects.pop_front().is_some() {
            self.base += 1;
        }
        self.links.drop_below(id);
        self.pairs.retain(|&(a, _), _| a >= id);
    }
}

impl<'a> FollowSink<'a> {
    /// Follows the points of a contour run with `options` (its sensel aspect, its user's points
    /// and regions), handing them to `out`.
    pub fn new(options: &'a SequenceOptions, out: &'a mut dyn PointsSink) -> Self {
        let aspect = SenselAspect::of(options);
        let mode = Mode {
            outline_seeds: true,
            lazy: false,
            backwards: true,
        };
        Self {
            follower: Follower::new(aspect, FollowParams::default(), mode),
            placer: SeedPlacer::new(&options.inputs),
            window: Window::default(),
            next: 0,
            keep_all: !options.inputs.is_empty(),
            out,
        }
    }

    /// Follows the objects before `end` and hands over the points that have ended.
    fn follow_to(&mut self, end: usize) -> Result<()> {
        let end = end.min(self.window.base + self.window.objects.len());
        while self.next < end {
            self.follower.object(&self.window, self.next);
            self.next += 1;
        }
        for (k, p, frames) in self.follower.ended() {
            self.out.point(k, &p, &frames)?;
        }
        // The follower reads the objects of the last frame followed and those after (and,
        // carrying the user's points back, every object).
        if !self.keep_all {
            let keep = self.follower.frame.map_or(self.next, |(_, first)| first);
            self.window.drop_below(keep);
        }
        Ok(())
    }

    /// Ends the run: follows the objects left and hands over every point; returns how many
    /// anchors were started (see [`super::FollowedPoints::anchors`]).
    ///
    /// # Errors
    /// [`pedo_io::IoError::InvalidInput`] for a user's point or region placed on no object
    /// ([`super::user_seeds`]); the errors of the [`PointsSink`].
    pub fn finish(mut self) -> Result<usize> {
        self.placer.finish()?;
        self.follow_to(usize::MAX)?;
        for (k, p, frames) in self.follower.finish() {
            self.out.point(k, &p, &frames)?;
        }
        Ok(self.follower.anchors)
    }
}

impl SequenceSink for FollowSink<'_> {
    fn frame_objects(&mut self, frame: usize, objects: &[SequenceObject]) -> Result<()> {
        if objects.iter().any(|o| o.shape.dim() != 2) {
            return Err(surfaces_refused());
        }
        for seed in self.placer.frame(frame, objects) {
            self.follower.seed_on(seed);
        }
        if self.window.objects.is_empty()
            && let Some(o) = objects.first()
        {
            self.window.base = o.id;
        }
        self.window.objects.extend(objects.iter().cloned());
        Ok(())
    }
    fn pair(&mut self, pair: &PairMatch, a: &SequenceObject, b: &SequenceObject) -> Result<()> {
        self.window.links.add(a.id, b.id);
        let kept = pair.without_details()?.result;
        self.window.pairs.insert((a.id, b.id), kept);
        Ok(())
    }
    fn skipped_pair(&mut self, a: &SequenceObject, b: &SequenceObject, _: &str) -> Result<()> {
        self.window.links.add(a.id, b.id);
        Ok(())
    }
    fn settled(&mut self, object: usize) -> Result<()> {
        self.follow_to(object)
    }
}
