//! Material points followed through a stance by anchored registration (docs/method.md §12).
//!
//! Chaining matches node to node rounds every step to a node: at 200 Hz a point of the foot moves
//! a tenth of the node spacing per frame, so the rounding, not the matcher, makes node tracks
//! drift. Here a point is never a node. Each object that begins a lineage (an object no earlier
//! one continues) is an *anchor*: its outline, densified, is registered onto the outline of every
//! later object of its lineage by a thin-plate smoothing spline on the anchor's fixed points
//! (factored once per anchor), one curve-ICP step per frame warm-started from the frame before,
//! its targets pulled towards the partners that modal matching of the anchor onto the frame
//! gives the anchor's nodes. A point's position in a frame is the image of its place on the
//! anchor, so errors do not add up from frame to frame.
//!
//! A lineage is re-anchored on its current object (the points keep their positions) when the
//! registered anchor outline no longer covers the frame's outline (the contact region grew or
//! shrank: heel strike, toe-off); where an object splits or objects merge, the points are carried
//! across by the pair's [`CorrespondenceField`] and a new anchor starts.

use crate::consistency::StepField;
use crate::inputs::UserInputs;
use crate::*;
use modal_core::{
    match_prepared, prepare, CorrespondenceField, FactoredSpline, MatchOptions, MatchResult,
    Parallelism, PreparedShape, SplineCoefficients, ThinPlateBasis,
};
use pedo_io::{IoError, Result};
use std::collections::HashMap;

mod sink;
pub use sink::{FollowSink, PointsSink};

/// The settings of anchored registration, in sensels (a sensel is the x pitch; oblong sensels
/// are registered in their true proportions). The defaults were chosen on the tuning stances of
/// `benches/python/anchor_study.py` and checked on its held-out ones (BENCHMARKS.md).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FollowParams {
    /// The spline's regularisation λ (scipy's `smoothing`, sensel² units): large enough that a
    /// node's own target (one closest point) cannot bend the field, small enough that the
    /// forefoot's spreading and bend pass.
    pub smoothing: f64,
    /// The weight (0–1) of the modal match's partner in an anchor node's target; the rest is the
    /// closest point of the frame's outline. The closest point alone slides along a smooth
    /// outline; the modal partner alone is a node, off by up to half a spacing.
    pub pull: f64,
    /// The anchor outline's points are at most this far apart (sensels): the spline's centres,
    /// whose factorisation is most of the cost of a new anchor (0.5 measured no more accurate
    /// than 1 on the synthetic walks, at 8× the cost).
    pub anchor_step: f64,
    /// A frame's outline is sampled this finely for its closest points (sensels).
    pub target_step: f64,
    /// Re-anchor when more than this share of either outline lies over one sensel from the
    /// other after registration.
    pub coverage: f64,
    /// ICP steps on the first frame after an anchor.
    pub first_steps: usize,
    /// A frame's ICP steps stop once no point of the anchor's image moves more than this
    /// (sensels), or after `max_steps`.
    pub settled: f64,
    /// The most ICP steps on a frame after the first.
    pub max_steps: usize,
    /// Closest points farther than this from an anchor point's image (sensels) do not pull it:
    /// where the contact region grows (heel strike) the new outline is new contact, not the
    /// anchor's outline moved.
    pub reach: f64,
    /// The anchor is matched onto an object of its lineage (modal matching: most of the cost)
    /// on its first, then once its image has moved this far (sensels, the largest motion of a
    /// point, summed over frames) since the last match: a slide along the outline, which the
    /// closest points do not see, is never larger than the motion itself. The frames between
    /// take the closest points alone.
    pub match_motion: f64,
    /// The weight (0–1) of an anchor point's predicted position in its target on every frame
    /// after the first: its image on the frame before moved on by its recent velocity (a
    /// constant-velocity prior). The frame's outline jumps as sensels cross the contour level,
    /// and a new modal match moves the image at once; the prior spreads both over a few frames.
    /// 0 (the default) turns it off: across the outline the frame's outline says where a point
    /// lies; the prior along it ([`inertia_along`](Self::inertia_along)) is the default
    /// (BENCHMARKS.md, "Tracks that follow the foot"). Scaled down as
    /// [`prior_full`](Self::prior_full) says.
    pub inertia: f64,
    /// The weight (0–1) of the predicted position's part *along* the outline (the image's
    /// tangent) in an anchor point's target: the closest points say where the outline lies
    /// across it, not where a point slides along it (a near-circular heel shows no turn), so the
    /// prediction pins the slide and nothing else. Scaled down as
    /// [`prior_full`](Self::prior_full) says; 0 turns it off.
    pub inertia_along: f64,
    /// Both priors are at full strength while the anchor's image moved at most this far on the
    /// frame before (the median over its points, sensels), off from
    /// [`prior_none`](Self::prior_none) on, and in between in proportion: at 200–500 Hz a
    /// point of the foot moves a tenth of a sensel a frame and its motion is nearly constant
    /// from frame to frame; on frames far apart (a degree of turn a frame) it is not, and the
    /// prediction carries the points off.
    pub prior_full: f64,
    /// The median motion of the anchor's image on the frame before (sensels) from which the
    /// priors are off (see [`prior_full`](Self::prior_full)).
    pub prior_none: f64,
    /// How much (0–1) of each frame's motion of an anchor point enters its velocity (an
    /// exponential average over frames). The frames of a modal match do not enter it: the
    /// match's correction is no motion of the foot.
    pub velocity_smoothing: f64,
    /// The weight (0–1) of a point's *locally rigid* position in the part of its target along
    /// the outline, on every frame: where the anchor's points around it (Gaussian weights of
    /// scale [`rigid_reach`](Self::rigid_reach) on the anchor, across the foot as well as along
    /// its outline), moved by the turn and shift that put them best on the frame's outline
    /// ([`rigid_shape`](Self::rigid_shape)), put it. Along a near-circular heel or
    /// a straight edge the frame's outline says nothing; the stretches nearby that it pins (the
    /// arch's concavity, the other side of the foot) do, and the heel moves as one piece with
    /// them instead of sliding after the forefoot's turn. 0 turns it off.
    pub rigid_along: f64,
    /// The scale (sensels, on the anchor) of the neighbourhood whose turn and shift give a
    /// point's locally rigid position (see [`rigid_along`](Self::rigid_along)); points farther
    /// than three times this do not count.
    pub rigid_reach: f64,
    /// How much (0–1) the frame's outline, rather than the anchor's current image, sets the turn
    /// and shift of a point's neighbourhood (see [`rigid_along`](Self::rigid_along)): the fit
    /// puts the neighbourhood's points on the frame's outline *across* the image (point to line,
    /// onto their closest points) with weight 1 and on their images *along* it with weight
    /// `1 − rigid_shape`. The image's places along a near-circular heel are the slide itself;
    /// where the stretches nearby have a shape (the arch, the other side of the foot), the
    /// outline sets the turn. At 0 the image along the outline weighs as much as the outline
    /// across it (the fit onto the image alone, 2-D Procrustes, where the image lies on the
    /// outline).
    pub rigid_shape: f64,
    /// The modal pull ([`pull`](Self::pull)) is full on anchor nodes where the anchor's outline
    /// turns at least this much per sensel (radians), less in proportion where it is straighter:
    /// a modal partner is placed along the outline by the match's alignment of the whole shape,
    /// and on a heel or a straight edge, which show no turn of their own, that alignment's error
    /// (the forefoot's bend taken for a turn) is all it says. 0 pulls every node fully.
    pub pull_curvature: f64,
}

impl Default for FollowParams {
    fn default() -> Self {
        Self {
            smoothing: 1000.0,
            pull: 0.2,
            anchor_step: 1.0,
            target_step: 0.25,
            coverage: 0.10,
            first_steps: 10,
            settled: 0.02,
            max_steps: 10,
            match_motion: 0.5,
            reach: 2.0,
            inertia: 0.0,
            inertia_along: 0.5,
            prior_full: 0.08,
            prior_none: 0.16,
            velocity_smoothing: 0.3,
            rigid_along: 0.7,
            rigid_reach: 8.0,
            rigid_shape: 0.5,
            pull_curvature: 0.3,
        }
    }
}

/// The smoothing of the field that starts an anchor's registration (from the modal pairs alone)
/// and of the field that carries points across a split or merge: the pairs are noisier than the
/// registration's targets.
const PAIR_SMOOTHING: f64 = crate::consistency::FIELD_SMOOTHING;
/// Distance (sensels) beyond which a point of one outline counts as not covered by the other.
const COVERED: f64 = 1.0;

/// What a followed point was seeded as.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Seeded {
    /// An outline node of an object that begins a lineage (the default points).
    Outline,
    /// A point given by position: the index among the seeds given ([`follow_seeded`]), or among
    /// the user's points ([`UserInputs::points`]).
    Point(usize),
    /// A point of a region's outline: the index of the region ([`UserInputs::regions`]). It is
    /// not ended where it leaves the contact region (a region's outline runs along the
    /// foot's).
    Region(usize),
}

/// A point to follow from its object on ([`follow_seeded`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Seed {
    /// The object (an index into the run's objects) it is given on.
    pub object: usize,
    /// Its position on that object, in sensels.
    pub xy: [f64; 2],
    /// What it is.
    pub kind: Seeded,
}

/// One material point followed through the objects of a run.
#[derive(Debug, Clone, PartialEq)]
pub struct FollowedPoint {
    /// The object it started on and, for a point seeded at an outline node, that node.
    pub seed: (usize, Option<usize>),
    /// What it was seeded as.
    pub kind: Seeded,
    /// `(object, [x, y])` of each frame it was followed through, in sequence order (sensels).
    pub steps: Vec<(usize, [f64; 2])>,
    /// Per step, its **round trip** (sensels, the x pitch): how far the backward field of the
    /// matched pair the point stepped through onto this step's object (fitted to the pair's
    /// matches, as [`crate::consistency`]'s) carries the point from where it is here to where
    /// it was on the object it came from. `None` for the step it was seeded on and where the
    /// pair gives no field. The steps of a point carried backwards ([`follow_seeded`] both
    /// ways) came from the later object: theirs is measured on the pair turned round.
    pub round_trips: Vec<Option<f32>>,
}

/// Every point followed by [`follow_points`], with how often lineages were re-anchored.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FollowedPoints {
    /// The points, in the order they were seeded.
    pub points: Vec<FollowedPoint>,
    /// Anchors started: one per lineage, plus one per re-anchoring and per split or merge.
    pub anchors: usize,
}

/// Follows material points through the contour objects of a run: by default the outline nodes of
/// every object that begins a lineage (`seeds` empty), or the given `seeds` (object, position
/// in sensels) each from its object on.
///
/// # Errors
/// [`IoError::InvalidInput`] for a run that is not of closed 2-D contours or a seed on an
/// object the run does not have; a point that cannot be followed further (an object that
/// cannot be matched or registered) ends there, as a track does, without failing the run.
pub fn follow_points(
    run: &SequenceResult,
    aspect: SenselAspect,
    params: &FollowParams,
    seeds: &[(usize, [f64; 2])],
) -> Result<FollowedPoints> {
    let seeds: Vec<Seed> = seeds
        .iter()
        .enumerate()
        .map(|(k, &(object, xy))| Seed {
            object,
            xy,
            kind: Seeded::Point(k),
        })
        .collect();
    follow_seeded(run, aspect, params, &seeds, seeds.is_empty(), false)
}

/// Follows the `seeds` (each from its object on) through the contour objects of a run and,
/// with `outline_seeds`, the outline nodes of every object that begins a lineage too (the
/// points of [`follow_points`] without seeds). A seed on an object within a lineage starts a
/// new anchor there (the lineage's points keep their positions), so that its place is its
/// position. With `both_ways`, each seed is carried backwards too, from its object to where the
/// contact that leads into it began ([`Stance`](crate::follow#backwards): the objects its
/// object continues, back to one that no earlier object continues), by the same anchored
/// registration on the pairs turned round; its steps are then those of the backward part, in
/// frame order, then its seed's frame and the forward part. The outline seeds begin where
/// their lineage begins: they have no backward part.
///
/// # Errors
/// As [`follow_points`].
pub fn follow_seeded(
    run: &SequenceResult,
    aspect: SenselAspect,
    params: &FollowParams,
    seeds: &[Seed],
    outline_seeds: bool,
    both_ways: bool,
) -> Result<FollowedPoints> {
    let mode = Mode {
        outline_seeds,
        lazy: false,
        backwards: both_ways,
    };
    follow_inner(run, aspect, params, seeds, mode)
}

/// How a [`Follower`] follows: with the outline seeds of every object that begins a lineage;
/// `lazy`, starting a lineage only for an object with seeds or points handed over and dropping
/// it once it carries no point; `backwards`, carrying each seed back to where its contact began
/// too ([`backward_steps`]).
#[derive(Debug, Clone, Copy)]
struct Mode {
    outline_seeds: bool,
    lazy: bool,
    backwards: bool,
}

/// [`follow_seeded`] as `mode` says.
fn follow_inner(
    run: &SequenceResult,
    aspect: SenselAspect,
    params: &FollowParams,
    seeds: &[Seed],
    mode: Mode,
) -> Result<FollowedPoints> {
    if run.objects.iter().any(|o| o.shape.dim() != 2) {
        return Err(surfaces_refused());
    }
    let whole = WholeRun::of(run);
    let mut follower = Follower::new(aspect, *params, mode);
    for seed in seeds {
        let (o, p) = (seed.object, seed.xy);
        if o >= run.objects.len() || !p.iter().all(|v| v.is_finite()) {
            return Err(IoError::invalid(format!(
                "point ({}, {}) seeded on object {o}: the run has {} (and points must be finite)",
                p[0],
                p[1],
                pedo_io::counted(run.objects.len(), "object")
            )));
        }
        follower.seed_on(*seed);
    }
    for b in 0..run.objects.len() {
        follower.object(&whole, b);
    }
    Ok(follower.into_points())
}

/// The error of following points on a run of surfaces.
fn surfaces_refused() -> IoError {
    IoError::invalid("points are followed on contours: this run's objects are surfaces")
}

/// What the follower reads of a run: its objects and matched pairs by id, and which object
/// continues which (from the pairs matched or skipped). A whole run ([`WholeRun`]) or the
/// window of a run as it streams ([`sink::FollowSink`]).
trait RunView {
    /// The ids of the objects it holds.
    fn held(&self) -> std::ops::Range<usize>;
    fn object(&self, id: usize) -> &SequenceObject;
    /// The matches of the pair `a → b`, if it was matched.
    fn pair(&self, a: usize, b: usize) -> Option<&MatchResult>;
    fn links(&self) -> &Links;
}

/// A whole run as the follower reads it.
struct WholeRun<'r> {
    run: &'r SequenceResult,
    links: Links,
    pairs: HashMap<(usize, usize), usize>,
}

impl<'r> WholeRun<'r> {
    fn of(run: &'r SequenceResult) -> Self {
        let mut links = Links::default();
        let matched = run.pairs.iter().map(|p| (p.a, p.b));
        let skipped = run.skipped_pairs.iter().map(|p| (p.a, p.b));
        for (a, b) in matched.chain(skipped) {
            links.add(a, b);
        }
        let pairs = (run.pairs.iter().enumerate())
            .map(|(k, p)| ((p.a, p.b), k))
            .collect();
        Self { run, links, pairs }
    }
}

impl RunView for WholeRun<'_> {
    fn held(&self) -> std::ops::Range<usize> {
        0..self.run.objects.len()
    }
    fn object(&self, id: usize) -> &SequenceObject {
        &self.run.objects[id]
    }
    fn pair(&self, a: usize, b: usize) -> Option<&MatchResult> {
        let k = *self.pairs.get(&(a, b))?;
        Some(&self.run.pairs[k].result)
    }
    fn links(&self) -> &Links {
        &self.links
    }
}

/// The state of anchored registration between objects: the lineages alive and the points
/// followed. Objects are handed in id order ([`Follower::object`]), each once every pair
/// leaving it is known.
struct Follower {
    aspect: SenselAspect,
    params: FollowParams,
    mode: Mode,
    seeds_at: HashMap<usize, Vec<Seed>>,
    /// Per object: its anchor state and the points on it (index into `points`).
    live: HashMap<usize, Lineage>,
    points: PointsKept,
    anchors: usize,
    /// The frame of the last object followed and the first object of that frame.
    frame: Option<(usize, usize)>,
    /// The objects of the last seed frame's contacts read backwards, shared by the backward
    /// passes of every object of that frame given seeds ([`backward_steps`]).
    back_view: Option<ReversedParts>,
}

/// The points followed, numbered from 0 in the order they were seeded: those from `base` on
/// are held (a streamed run hands the ones before over once they have ended), each with the
/// frame of each of its steps.
#[derive(Default)]
struct PointsKept {
    base: usize,
    held: std::collections::VecDeque<(FollowedPoint, Vec<usize>)>,
}

impl PointsKept {
    fn push(&mut self, p: FollowedPoint) -> usize {
        self.held.push_back((p, Vec::new()));
        self.base + self.held.len() - 1
    }
    /// Steps of point `k` (objects of `run`, in frame order, with their round trips) before
    /// those it has.
    fn before(&mut self, k: usize, (steps, trips): Part, run: &dyn RunView) {
        let (p, frames) = &mut self.held[k - self.base];
        let earlier: Vec<usize> = steps.iter().map(|&(o, _)| run.object(o).frame).collect();
        p.steps.splice(0..0, steps);
        p.round_trips.splice(0..0, trips);
        frames.splice(0..0, earlier);
    }
    fn step(&mut self, k: usize, object: usize, frame: usize, xy: [f64; 2], trip: Option<f32>) {
        let (p, frames) = &mut self.held[k - self.base];
        p.steps.push((object, xy));
        p.round_trips.push(trip);
        frames.push(frame);
    }
    /// The last step of point `k`, if it has one.
    fn last(&self, k: usize) -> Option<(usize, [f64; 2])> {
        self.held[k - self.base].0.steps.last().copied()
    }
}

impl Follower {
    fn new(aspect: SenselAspect, params: FollowParams, mode: Mode) -> Self {
        Self {
            aspect,
            params,
            mode,
            seeds_at: HashMap::new(),
            live: HashMap::new(),
            points: PointsKept::default(),
            anchors: 0,
            frame: None,
            back_view: None,
        }
    }

    /// A point to seed on its object, handed before that object.
    fn seed_on(&mut self, seed: Seed) {
        self.seeds_at.entry(seed.object).or_default().push(seed);
    }

    /// Every point followed (none handed over).
    fn into_points(self) -> FollowedPoints {
        FollowedPoints {
            points: self.points.held.into_iter().map(|(p, _)| p).collect(),
            anchors: self.anchors,
        }
    }

    /// Follows the points onto object `b` (every object before it followed, every pair leaving
    /// it known); a point that cannot be followed further ends there, as a track does.
    fn object(&mut self, run: &dyn RunView, b: usize) {
        let (aspect, params, links) = (self.aspect, self.params, run.links());
        let params = &params;
        let frame = run.object(b).frame;
        if self.frame.is_none_or(|(f, _)| f != frame) {
            // The lineages left on frames before the last one can continue no more.
            let last_first = self.frame.map_or(0, |(_, first)| first);
            self.live.retain(|&o, _| o >= last_first);
            self.frame = Some((frame, b));
        }
        let mut lineage = None;
        if let Some(a) = links.continues(b)
            && let Some(mut l) = self.live.remove(&a)
        {
            match l.step(run.object(b), run.pair(a, b), aspect, params) {
                Ok(()) => lineage = Some(l),
                // Not registered: the points cross by the pair's field, as at a split.
                Err(_) => {
                    self.live.insert(a, l);
                }
            }
        }
        let wanted = !self.mode.lazy
            || self.seeds_at.contains_key(&b)
            || links.preds(b).iter().any(|a| self.live.contains_key(a));
        if lineage.is_none() && wanted {
            lineage = self.start(run, b);
        }
        let Some(mut l) = lineage else { return };
        let mut back = Vec::new();
        if let Some(ps) = self.seeds_at.remove(&b) {
            // A place on the anchor is a position on the anchor's object: a seed on a later
            // object of the lineage starts a new anchor there.
            if l.object != b
                && let Ok(fresh) = l.reanchor(run.object(b), b, aspect, params)
            {
                l = fresh;
                self.anchors += 1;
            }
            if l.object == b {
                let parts = match self.mode.backwards {
                    true => self.backward_steps(run, b, &ps),
                    false => Vec::new(),
                };
                let first = self.points.base + self.points.held.len();
                back = (parts.into_iter().enumerate())
                    .map(|(k, part)| (first + k, part))
                    .collect();
                let seeded = ps.into_iter().map(|p| (None, p.xy, p.kind));
                l.seed(seeded, &mut self.points, b, aspect);
            }
        }
        // Each point's round trip from the object it came from (the backward field of that
        // pair fitted once for all its points); none for a point seeded here.
        let mut fields: HashMap<usize, Option<StepField>> = HashMap::new();
        for &(k, p) in &l.points {
            let trip = self.points.last(k).and_then(|(a, was)| {
                let field = fields.entry(a).or_insert_with(|| {
                    let pair = run.pair(a, b)?;
                    let (oa, ob) = (&run.object(a).shape, &run.object(b).shape);
                    StepField::of(oa, ob, &pair.pairs, aspect)
                });
                let d = field.as_ref()?.round_trip(was, p);
                d.is_finite().then_some(d)
            });
            self.points.step(k, b, frame, p, trip);
        }
        // The seeds' backward parts go before their seed's step.
        for (k, part) in back {
            self.points.before(k, part, run);
        }
        if links.succs(b).is_empty() || (self.mode.lazy && l.points.is_empty()) {
            // The lineage ends here: its anchor is dropped, its points end.
            return;
        }
        if l.anchor.uncovered > params.coverage
            && let Ok(fresh) = l.reanchor(run.object(b), b, aspect, params)
        {
            l = fresh;
            self.anchors += 1;
        }
        self.live.insert(b, l);
    }

    /// The backward parts of `seeds` on object `b` ([`backward_steps`]), on the reversed view
    /// of `b`'s frame: made at the frame's first seeded object, back to the earliest contact
    /// start of any of its seeded objects, and kept for the others.
    fn backward_steps(&mut self, run: &dyn RunView, b: usize, seeds: &[Seed]) -> Vec<Part> {
        let lowest = contact_start(run, b);
        if lowest == b {
            return vec![Part::default(); seeds.len()];
        }
        let highest = frame_end(run, b);
        let fits = |v: &ReversedParts| v.old.first() == Some(&highest) && v.lowest() <= lowest;
        if !self.back_view.as_ref().is_some_and(fits) {
            // The seeds still to come on this frame's objects reach back as far as theirs.
            let earliest = (b + 1..=highest)
                .filter(|o| self.seeds_at.contains_key(o))
                .map(|o| contact_start(run, o))
                .fold(lowest, usize::min);
            self.back_view = Some(ReversedParts::of(run, earliest..=highest));
        }
        match &self.back_view {
            Some(parts) => {
                let view = Reversed { run, parts };
                backward_steps(&view, highest - b, seeds, self.aspect, &self.params)
            }
            None => vec![Part::default(); seeds.len()],
        }
    }

    /// A new lineage on `b`: with the points its predecessors hand over and, for an object
    /// that begins a lineage, its outline nodes.
    fn start(&mut self, run: &dyn RunView, b: usize) -> Option<Lineage> {
        let aspect = self.aspect;
        let mut l = Lineage::start(run.object(b), b, aspect, &self.params).ok()?;
        self.anchors += 1;
        let carried = handed_over(run, b, &mut self.live, aspect);
        l.adopt(carried, aspect);
        if run.links().preds(b).is_empty() && self.mode.outline_seeds {
            let nodes = outline(run.object(b));
            let seeded = (nodes.iter().enumerate()).map(|(i, &p)| (Some(i), p, Seeded::Outline));
            l.seed(seeded, &mut self.points, b, aspect);
        }
        Some(l)
    }

    /// The points that have ended, in order, once every point before them has: those that no
    /// lineage alive carries (a streamed run hands them over and lets go of them).
    fn ended(&mut self) -> Vec<(usize, FollowedPoint, Vec<usize>)> {
        let alive: std::collections::HashSet<usize> = (self.live.values())
            .flat_map(|l| l.points.iter().map(|&(k, _)| k))
            .collect();
        let mut out = Vec::new();
        while !alive.contains(&self.points.base) {
            let Some((p, frames)) = self.points.held.pop_front() else {
                break;
            };
            out.push((self.points.base, p, frames));
            self.points.base += 1;
        }
        out
    }

    /// Every point left, once every object has been followed.
    fn finish(&mut self) -> Vec<(usize, FollowedPoint, Vec<usize>)> {
        self.live.clear();
        self.ended()
    }
}

/// The first object of `b`'s contact: the earliest of the held objects `b` continues, directly
/// or not (`b` itself when it continues none).
fn contact_start(run: &dyn RunView, b: usize) -> usize {
    let (held, links) = (run.held(), run.links());
    let mut lowest = b;
    let mut todo = vec![b];
    let mut seen = std::collections::HashSet::from([b]);
    while let Some(o) = todo.pop() {
        for &a in links.preds(o) {
            if held.contains(&a) && seen.insert(a) {
                lowest = lowest.min(a);
                todo.push(a);
            }
        }
    }
    lowest
}

/// The last held object of `b`'s frame.
fn frame_end(run: &dyn RunView, b: usize) -> usize {
    let (held, frame) = (run.held(), run.object(b).frame);
    let mut highest = b;
    while held.contains(&(highest + 1)) && run.object(highest + 1).frame == frame {
        highest += 1;
    }
    highest
}

/// The backward parts of `seeds`, all on object `b` of the reversed `view` (object `b` of the
/// view; every pair into it known in the run): each seed carried from `b` back through the
/// objects `b` continues, one frame at a time, to the first object of that contact (one that
/// no earlier object continues), by anchored registration on the objects of those frames in
/// reversed order with every pair's matches turned round (as [`follow_both_ways`]); where
/// objects merged on the way forward, the point goes back into the part whose outline its image
/// lies nearest, as at a split. Per seed, its steps before `b`'s frame in frame order, as the
/// run's objects, with their round trips (each measured from the later object, on the pair
/// turned round; none where it could not be carried).
fn backward_steps(
    view: &Reversed<'_>,
    b: usize,
    seeds: &[Seed],
    aspect: SenselAspect,
    params: &FollowParams,
) -> Vec<Part> {
    let none = || vec![Part::default(); seeds.len()];
    let mode = Mode {
        outline_seeds: false,
        lazy: true,
        backwards: false,
    };
    let mut follower = Follower::new(aspect, *params, mode);
    for s in seeds {
        follower.seed_on(Seed { object: b, ..*s });
    }
    let old = &view.parts.old;
    for n in 0..old.len() {
        follower.object(view, n);
    }
    // The points are the seeds in order, or none (no anchor could be made on `b`).
    let points = follower.into_points().points;
    if points.len() != seeds.len() {
        return none();
    }
    (points.into_iter())
        .map(|p| {
            // The seed's own step is the forward part's.
            let mut steps: Steps = (p.steps.into_iter().skip(1))
                .map(|(o, xy)| (old[o], xy))
                .collect();
            let mut trips: Vec<Option<f32>> = p.round_trips.into_iter().skip(1).collect();
            steps.reverse();
            trips.reverse();
            (steps, trips)
        })
        .collect()
}

/// Objects of a run read backwards ([`Reversed`]): object `n` is the `n`-th from the end of a
/// range of the run's objects, every pair between them turned round (its matches from the
/// later object to the earlier).
struct ReversedParts {
    /// The run's id of each object, in reversed order.
    old: Vec<usize>,
    links: Links,
    pairs: HashMap<(usize, usize), MatchResult>,
}

impl ReversedParts {
    fn of(run: &dyn RunView, ids: std::ops::RangeInclusive<usize>) -> Self {
        let hi = *ids.end();
        let new = |o: usize| hi - o;
        let mut links = Links::default();
        let mut pairs = HashMap::new();
        for a in ids.clone() {
            for &b in run.links().succs(a) {
                if !ids.contains(&b) {
                    continue;
                }
                links.add(new(b), new(a));
                if let Some(m) = run.pair(a, b)
                    && let Some(turned) = turned_round(m)
                {
                    pairs.insert((new(b), new(a)), turned);
                }
            }
        }
        Self {
            old: ids.rev().collect(),
            links,
            pairs,
        }
    }

    /// The run's id of the earliest object.
    fn lowest(&self) -> usize {
        self.old.last().copied().unwrap_or(usize::MAX)
    }
}

/// The objects of [`ReversedParts`] as a run to follow.
struct Reversed<'v> {
    run: &'v dyn RunView,
    parts: &'v ReversedParts,
}

impl RunView for Reversed<'_> {
    fn held(&self) -> std::ops::Range<usize> {
        0..self.parts.old.len()
    }
    fn object(&self, id: usize) -> &SequenceObject {
        self.run.object(self.parts.old[id])
    }
    fn pair(&self, a: usize, b: usize) -> Option<&MatchResult> {
        self.parts.pairs.get(&(a, b))
    }
    fn links(&self) -> &Links {
        &self.parts.links
    }
}

/// The matches of a pair `a → b` as those of `b → a` (what the follower reads of a pair: its
/// matches and unmatched nodes; no details, the transform left as it was).
fn turned_round(m: &MatchResult) -> Option<MatchResult> {
    let mut pairs = m.pairs.clone();
    for p in &mut pairs {
        std::mem::swap(&mut p.a, &mut p.b);
    }
    Some(MatchResult {
        pairs,
        affinity: crate::result::no_affinity().ok()?,
        local_pairs: Vec::new(),
        unmatched_a: m.unmatched_b.clone(),
        unmatched_b: m.unmatched_a.clone(),
        n_modes: m.n_modes,
        refits: m.refits,
        solves: m.solves,
        transform: m.transform,
        aligned_a: Vec::new(),
        crossings: m.crossings,
        outline_images: None,
        drifted: m.drifted,
    })
}

/// Follows `seeds`, all on objects of one frame `f`, through the objects of frames
/// `first..=last` of `run` (`first ≤ f ≤ last`) forwards from `f` to `last` and backwards from
/// `f` to `first`: the backward pass is [`follow_seeded`] on the objects of `first..=f` in
/// reversed order, each pair's matches turned round, so a point is carried by the same anchored
/// registration either way. Returns one point per seed, in the order of `seeds`, with the kind
/// given, its steps in frame order (the seed's own frame once).
///
/// # Errors
/// [`IoError::InvalidInput`] for seeds on objects of different frames, a frame `f` outside
/// `first..=last`, and as [`follow_seeded`].
pub fn follow_both_ways(
    run: &SequenceResult,
    aspect: SenselAspect,
    params: &FollowParams,
    seeds: &[Seed],
    first: usize,
    last: usize,
) -> Result<FollowedPoints> {
    let mut out = FollowedPoints::default();
    let Some(s0) = seeds.first() else {
        return Ok(out);
    };
    let frame_of = |o: usize| run.objects.get(o).map(|o| o.frame);
    let f = frame_of(s0.object).ok_or_else(|| {
        IoError::invalid(format!(
            "a seed on object {}: the run has {}",
            s0.object,
            pedo_io::counted(run.objects.len(), "object")
        ))
    })?;
    if let Some(s) = seeds.iter().find(|s| frame_of(s.object) != Some(f)) {
        return Err(IoError::invalid(format!(
            "seeds followed both ways lie on one frame: object {} is not on frame {f}",
            s.object
        )));
    }
    if !(first..=last).contains(&f) {
        return Err(IoError::invalid(format!(
            "seeds on frame {f} followed through frames {first}..={last}"
        )));
    }
    let numbered: Vec<Seed> = (seeds.iter().enumerate())
        .map(|(k, s)| Seed {
            kind: Seeded::Point(k),
            ..*s
        })
        .collect();
    let pass = |reversed: bool| -> Result<Vec<Part>> {
        let (lo, hi) = if reversed { (first, f) } else { (f, last) };
        let (sub, old) = sub_run(run, lo..=hi, reversed);
        let mut new_of = vec![usize::MAX; run.objects.len()];
        for (n, &o) in old.iter().enumerate() {
            new_of[o] = n;
        }
        let local: Vec<Seed> = (numbered.iter())
            .map(|s| Seed {
                object: new_of[s.object],
                ..*s
            })
            .collect();
        let mode = Mode {
            outline_seeds: false,
            lazy: true,
            backwards: false,
        };
        let followed = follow_inner(&sub, aspect, params, &local, mode)?;
        let mut steps = vec![Part::default(); seeds.len()];
        for p in followed.points {
            if let Seeded::Point(k) = p.kind {
                let moved = p.steps.into_iter().map(|(o, xy)| (old[o], xy)).collect();
                steps[k] = (moved, p.round_trips);
            }
        }
        Ok(steps)
    };
    let forward = pass(false)?;
    let backward = pass(true)?;
    for ((seed, fwd), bwd) in seeds.iter().zip(forward).zip(backward) {
        // The backward steps from the seed's frame down: the seed's own step is the forward's.
        let mut steps: Vec<(usize, [f64; 2])> = bwd.0.into_iter().skip(1).collect();
        let mut round_trips: Vec<Option<f32>> = bwd.1.into_iter().skip(1).collect();
        steps.reverse();
        round_trips.reverse();
        steps.extend(fwd.0);
        round_trips.extend(fwd.1);
        out.points.push(FollowedPoint {
            seed: (seed.object, None),
            kind: seed.kind,
            steps,
            round_trips,
        });
    }
    Ok(out)
}

/// The round trips ([`FollowedPoint::round_trips`]) of points that step from the first
/// position of each of `moves` on object `a` of `run` to the second on object `b` (sensels):
/// how far the backward field of the pair `a → b` carries each from its second position to its
/// first; `None` when the run has no such pair or no field can be fitted to its matches (NaN
/// for a point the field gives no finite image).
pub fn step_round_trips(
    run: &SequenceResult,
    a: usize,
    b: usize,
    aspect: SenselAspect,
    moves: &[([f64; 2], [f64; 2])],
) -> Option<Vec<f32>> {
    let pair = run.pairs.iter().find(|p| p.a == a && p.b == b)?;
    let (oa, ob) = (&run.objects.get(a)?.shape, &run.objects.get(b)?.shape);
    let field = StepField::of(oa, ob, &pair.result.pairs, aspect)?;
    Some(moves.iter().map(|&(x, y)| field.round_trip(x, y)).collect())
}

/// `(object, [x, y])` of each frame a point was followed through.
type Steps = Vec<(usize, [f64; 2])>;

/// A point's steps with their round trips ([`FollowedPoint::round_trips`]).
type Part = (Steps, Vec<Option<f32>>);

/// The objects of `run` on frames `frames` as a run of their own, in sequence order or, when
/// `reversed`, in reversed order with every pair between them turned round (its matches from
/// the later object to the earlier); with the index in `run` of each of its objects.
fn sub_run(
    run: &SequenceResult,
    frames: std::ops::RangeInclusive<usize>,
    reversed: bool,
) -> (SequenceResult, Vec<usize>) {
    let mut old: Vec<usize> = (0..run.objects.len())
        .filter(|&o| frames.contains(&run.objects[o].frame))
        .collect();
    if reversed {
        old.reverse();
    }
    let mut new_of: HashMap<usize, usize> = HashMap::new();
    for (n, &o) in old.iter().enumerate() {
        new_of.insert(o, n);
    }
    let objects = old.iter().map(|&o| run.objects[o].clone()).collect();
    let link = |a: usize, b: usize| {
        let (na, nb) = (*new_of.get(&a)?, *new_of.get(&b)?);
        Some(if reversed { (nb, na) } else { (na, nb) })
    };
    let pairs = (run.pairs.iter())
        .filter_map(|p| {
            let (a, b) = link(p.a, p.b)?;
            // The follower reads a pair's matches only (its transform is left as it was).
            let mut result = p.without_details().ok()?.result;
            if reversed {
                for m in &mut result.pairs {
                    std::mem::swap(&mut m.a, &mut m.b);
                }
                std::mem::swap(&mut result.unmatched_a, &mut result.unmatched_b);
            }
            Some(PairMatch {
                a,
                b,
                result,
                row: p.row.clone(),
                trackable: p.trackable.clone(),
                step_round_trips: Vec::new(),
            })
        })
        .collect();
    let skipped_pairs = (run.skipped_pairs.iter())
        .filter_map(|p| {
            let (a, b) = link(p.a, p.b)?;
            Some(crate::result::SkippedPair {
                a,
                b,
                reason: p.reason.clone(),
            })
        })
        .collect();
    let sub = SequenceResult {
        objects,
        pairs,
        skipped_pairs,
        ..SequenceResult::default()
    };
    (sub, old)
}

/// The material points of a run as its outputs give them: the default seeds (the outline
/// nodes of every object that begins a lineage) and the user's points and regions
/// ([`SequenceOptions::inputs`], placed by [`user_seeds`]) followed through a contour run
/// ([`follow_seeded`] with the run's sensel aspect); `None` for the surface and isocontour
/// models, whose objects are no contact outlines.
///
/// # Errors
/// As [`follow_points`] and [`user_seeds`].
pub fn run_points(
    run: &SequenceResult,
    options: &SequenceOptions,
) -> Result<Option<FollowedPoints>> {
    if options.model != ObjectModel::Contour {
        return Ok(None);
    }
    let seeds = user_seeds(run, &options.inputs)?;
    follow_seeded(
        run,
        SenselAspect::of(options),
        &FollowParams::default(),
        &seeds,
        true,
        true,
    )
    .map(Some)
}

/// How far apart (sensels) the points of a region's outline are seeded.
pub const REGION_STEP: f64 = 0.5;

/// The seeds of the user's points and regions on the objects of `run`: a point on the first
/// object (of its frame, when given) whose outline holds it; each region's outline, every
/// [`REGION_STEP`] sensels, on the object of its frame (the first frame with an object unless
/// given) whose outline holds most of its sensels' centres. In the order of their objects (on
/// one object: the points in the order given, then the regions').
///
/// # Errors
/// [`IoError::InvalidInput`] naming a point that no object's outline holds (on its frame, or on
/// any frame run), or a region that lies on no object of its frame.
pub fn user_seeds(run: &SequenceResult, inputs: &UserInputs) -> Result<Vec<Seed>> {
    let mut placer = SeedPlacer::new(inputs);
    let mut seeds = Vec::new();
    let mut rest = run.objects.as_slice();
    while let Some(first) = rest.first() {
        let n = rest.iter().take_while(|o| o.frame == first.frame).count();
        let (these, after) = rest.split_at(n);
        seeds.extend(placer.frame(first.frame, these));
        rest = after;
    }
    placer.finish()?;
    Ok(seeds)
}

/// The user's points and regions placed on a run's objects frame by frame, as they are made
/// ([`user_seeds`]).
pub(crate) struct SeedPlacer<'i> {
    inputs: &'i UserInputs,
    /// Per point: whether it is placed.
    placed: Vec<bool>,
    /// The frame the regions are drawn on, once known, and the first region found on no
    /// object of it.
    regions_frame: Option<usize>,
    regions_placed: bool,
    region_missing: Option<usize>,
}

impl<'i> SeedPlacer<'i> {
    pub(crate) fn new(inputs: &'i UserInputs) -> Self {
        Self {
            inputs,
            placed: vec![false; inputs.points.len()],
            regions_frame: inputs.regions_frame,
            regions_placed: false,
            region_missing: None,
        }
    }

    /// The seeds on `objects`, the objects of `frame` (in id order).
    pub(crate) fn frame(&mut self, frame: usize, objects: &[SequenceObject]) -> Vec<Seed> {
        let inside = |o: &SequenceObject, p: [f64; 2]| {
            o.shape.dim() == 2 && pedo_io::contour::point_in_polygon(p, &outline(o))
        };
        let mut seeds = Vec::new();
        for (k, p) in self.inputs.points.iter().enumerate() {
            if self.placed[k] || p.frame.is_some_and(|f| f != frame) {
                continue;
            }
            if let Some(o) = objects.iter().find(|o| inside(o, p.xy)) {
                self.placed[k] = true;
                let kind = Seeded::Point(k);
                seeds.push(Seed {
                    object: o.id,
                    xy: p.xy,
                    kind,
                });
            }
        }
        if self.inputs.regions.is_empty() || objects.is_empty() {
            return seeds;
        }
        if *self.regions_frame.get_or_insert(frame) != frame {
            return seeds;
        }
        self.regions_placed = true;
        for (r, region) in self.inputs.regions.iter().enumerate() {
            let centres = region.centres();
            let best = (objects.iter())
                .map(|o| (o.id, centres.iter().filter(|&&c| inside(o, c)).count()))
                .max_by_key(|&(i, n)| (n, std::cmp::Reverse(i)));
            let Some((object, _)) = best.filter(|&(_, n)| n > 0) else {
                self.region_missing.get_or_insert(r);
                continue;
            };
            let (dense, _) = densify(&region.outline, REGION_STEP);
            seeds.extend(dense.into_iter().map(|xy| Seed {
                object,
                xy,
                kind: Seeded::Region(r),
            }));
        }
        seeds
    }

    /// Every frame seen: an error naming the first point or region left unplaced.
    pub(crate) fn finish(&self) -> Result<()> {
        let points = self.inputs.points.iter().zip(&self.placed);
        if let Some((p, _)) = points.into_iter().find(|(_, placed)| !**placed) {
            let when = match p.frame {
                Some(f) => format!("on frame {f}"),
                None => "on any frame run".to_string(),
            };
            return Err(IoError::invalid(format!(
                "point {:?} at x {}, y {} (sensels) lies inside no object's outline {when}",
                p.name, p.xy[0], p.xy[1]
            )));
        }
        if self.inputs.regions.is_empty() {
            return Ok(());
        }
        let Some(frame) = self.regions_frame else {
            return Err(IoError::invalid(
                "regions: the run has no object to draw them on",
            ));
        };
        // The regions' frame given, but no object on it: the first region lies on none.
        let missing = self.region_missing.or((!self.regions_placed).then_some(0));
        match missing {
            Some(r) => Err(IoError::invalid(format!(
                "region {} lies on no object of frame {frame}",
                self.inputs.regions[r].label
            ))),
            None => Ok(()),
        }
    }
}

/// Which object continues which: from the run's candidate pairs (matched or skipped).
#[derive(Default)]
struct Links {
    succs: HashMap<usize, Vec<usize>>,
    preds: HashMap<usize, Vec<usize>>,
}

impl Links {
    /// The candidate pair `a → b`.
    fn add(&mut self, a: usize, b: usize) {
        self.succs.entry(a).or_default().push(b);
        self.preds.entry(b).or_default().push(a);
    }

    fn preds(&self, b: usize) -> &[usize] {
        self.preds.get(&b).map_or(&[], Vec::as_slice)
    }

    fn succs(&self, a: usize) -> &[usize] {
        self.succs.get(&a).map_or(&[], Vec::as_slice)
    }

    /// The one object `b` continues, when neither splits nor merges.
    fn continues(&self, b: usize) -> Option<usize> {
        match self.preds(b) {
            [a] if self.succs(*a) == [b] => Some(*a),
            _ => None,
        }
    }

    /// Lets go of the links of objects before `id`.
    fn drop_below(&mut self, id: usize) {
        self.succs.retain(|&a, _| a >= id);
        self.preds.retain(|&b, _| b >= id);
    }
}

/// The points of `b`'s predecessors that `b` takes over at a split or merge, carried by each
/// pair's field: a point of a split object goes to the part whose outline its image lies
/// nearest (inside counts as distance 0).
fn handed_over(
    run: &dyn RunView,
    b: usize,
    live: &mut HashMap<usize, Lineage>,
    aspect: SenselAspect,
) -> Vec<(usize, [f64; 2], bool)> {
    let mut carried = Vec::new();
    for &a in run.links().preds(b) {
        let Some(la) = live.get_mut(&a) else { continue };
        // Each part's field and outline once, for every point of `a`.
        let parts = parts_of(run, a, aspect);
        let (mut keep, mut keep_ends) = (Vec::new(), Vec::new());
        for (&(point, pos), &ends) in la.points.iter().zip(&la.ends_off) {
            match destination(&parts, pos) {
                Some((t, image)) if t == b => carried.push((point, image, ends)),
                Some(_) => {
                    keep.push((point, pos));
                    keep_ends.push(ends);
                }
                None => {}
            }
        }
        la.points = keep;
        la.ends_off = keep_ends;
        if la.points.is_empty() {
            live.remove(&a);
        }
    }
    carried
}

/// The parts `a` continues as that a point can cross to: each with the field of its matched
/// pair and its outline.
fn parts_of(
    run: &dyn RunView,
    a: usize,
    aspect: SenselAspect,
) -> Vec<(usize, CorrespondenceField, Contact)> {
    (run.links().succs(a).iter())
        .filter_map(|&b| {
            let pair = run.pair(a, b)?;
            let (oa, ob) = (&run.object(a).shape, &run.object(b).shape);
            let field = CorrespondenceField::fit(oa, ob, &pair.pairs, PAIR_SMOOTHING).ok()?;
            Some((b, field, Contact::of(run.object(b), aspect)))
        })
        .collect()
}

/// Where a point at `pos` goes among `parts` ([`parts_of`]): the part nearest its image.
fn destination(
    parts: &[(usize, CorrespondenceField, Contact)],
    pos: [f64; 2],
) -> Option<(usize, [f64; 2])> {
    let mut best: Option<(f64, usize, [f64; 2])> = None;
    for (b, field, contact) in parts {
        let [image] = field.apply(&[pos])[..] else {
            continue;
        };
        let d = contact.outside(image);
        if best.is_none_or(|(bd, _, _)| d < bd) {
            best = Some((d, *b, image));
        }
    }
    best.map(|(_, b, p)| (b, p))
}

/// The anchor of one lineage and the points it carries.
struct Lineage {
    anchor: Anchor,
    /// The object the anchor was made on.
    object: usize,
    /// (point index, position in sensels on the lineage's current object).
    points: Vec<(usize, [f64; 2])>,
    /// Per point: whether it ends where it leaves the contact region (not a region's).
    ends_off: Vec<bool>,
    /// The points' places on the anchor (registration coordinates) and the spline's terms there.
    places: Vec<[f64; 2]>,
    place_basis: Option<ThinPlateBasis>,
}

impl Lineage {
    /// A lineage anchored on object `b`, `o`.
    fn start(
        o: &SequenceObject,
        b: usize,
        aspect: SenselAspect,
        params: &FollowParams,
    ) -> Result<Self> {
        Ok(Self {
            anchor: Anchor::new(o, aspect, params)?,
            object: b,
            points: Vec::new(),
            ends_off: Vec::new(),
            places: Vec::new(),
            place_basis: None,
        })
    }

    /// The lineage moved onto object `b` (which continues its current object), matched onto it
    /// as `pair`; on an error it is left on its current object.
    fn step(
        &mut self,
        b: &SequenceObject,
        pair: Option<&MatchResult>,
        aspect: SenselAspect,
        params: &FollowParams,
    ) -> Result<()> {
        self.anchor.register(b, pair, aspect, params)?;
        let images = match &self.place_basis {
            Some(basis) => basis.apply(self.anchor.coefficients()),
            None => Vec::new(),
        };
        for ((_, pos), image) in self.points.iter_mut().zip(images) {
            *pos = aspect.back_from_registration(image);
        }
        // A point carried off the contact region has left the plate (the foot rolls off it):
        // it ends, as the tissue's contact does.
        let contact = Contact::of(b, aspect);
        let kept: Vec<bool> = self
            .points
            .iter()
            .zip(&self.ends_off)
            .map(|(&(_, p), &ends)| !ends || contact.outside(p) <= COVERED)
            .collect();
        if kept.contains(&false) {
            let mut k = kept.iter();
            self.points.retain(|_| *k.next().unwrap_or(&true));
            let mut k = kept.iter();
            self.ends_off.retain(|_| *k.next().unwrap_or(&true));
            let mut k = kept.iter();
            self.places.retain(|_| *k.next().unwrap_or(&true));
            self.place_basis = Some(self.anchor.spline.basis(&self.places));
        }
        Ok(())
    }

    /// Points entering on the anchor's own object: their places are their positions there.
    fn seed(
        &mut self,
        points: impl Iterator<Item = (Option<usize>, [f64; 2], Seeded)>,
        out: &mut PointsKept,
        object: usize,
        aspect: SenselAspect,
    ) {
        let carried: Vec<(usize, [f64; 2], bool)> = points
            .map(|(node, p, kind)| {
                let k = out.push(FollowedPoint {
                    seed: (object, node),
                    kind,
                    steps: Vec::new(),
                    round_trips: Vec::new(),
                });
                let ends_off = !matches!(kind, Seeded::Region(_));
                (k, p, ends_off)
            })
            .collect();
        self.adopt(carried, aspect);
    }

    /// Points entering at their positions on the object the anchor was started on (with
    /// whether each ends where it leaves the contact region).
    fn adopt(&mut self, carried: Vec<(usize, [f64; 2], bool)>, aspect: SenselAspect) {
        if carried.is_empty() {
            return;
        }
        for (k, p, ends_off) in carried {
            self.points.push((k, p));
            self.ends_off.push(ends_off);
            self.places.push(aspect.to_registration(p));
        }
        self.place_basis = Some(self.anchor.spline.basis(&self.places));
    }

    /// A new anchor on object `b`, `o`, the lineage's current object: its points keep their
    /// positions.
    fn reanchor(
        &self,
        o: &SequenceObject,
        b: usize,
        aspect: SenselAspect,
        params: &FollowParams,
    ) -> Result<Self> {
        let mut l = Self::start(o, b, aspect, params)?;
        let carried = (self.points.iter().zip(&self.ends_off))
            .map(|(&(k, p), &e)| (k, p, e))
            .collect();
        l.adopt(carried, aspect);
        Ok(l)
    }
}

/// An anchor outline and its current registration onto the lineage's latest object.
struct Anchor {
    /// The anchor object's shape in registration coordinates, for modal matching.
    shape: modal_core::Shape,
    /// That shape prepared for matching ([`prepare`]), once for every match of the anchor onto
    /// a later object: made at the first.
    prepared: Option<PreparedShape>,
    /// Where each node is among the anchor's densified outline (the spline's centres, in
    /// outline order: a node, then the points between it and the next).
    node_at: Vec<usize>,
    spline: FactoredSpline,
    dense_basis: ThinPlateBasis,
    /// The images of the densified outline on the latest object, and the spline that gives them.
    image: Vec<[f64; 2]>,
    coefficients: Option<SplineCoefficients>,
    /// The share of the latest registration's outlines left uncovered (see [`FollowParams`]).
    uncovered: f64,
    /// Whether the anchor has been registered onto a later object yet.
    registered: bool,
    /// Registrations since the last modal match.
    motion_since_match: f64,
    /// Per point of the densified outline: its image's motion per frame, averaged over the
    /// frames since the anchor's first registration that took no modal match
    /// ([`FollowParams::inertia`]).
    velocity: Vec<[f64; 2]>,
    /// The median distance the image's points moved on the latest registration (sensels;
    /// infinite before the first): how far apart the frames are, for the prior's strength.
    last_step: f64,
    /// The densified anchor outline (registration coordinates) and, per point, the points of
    /// its neighbourhood with their weights ([`FollowParams::rigid_along`]; empty when off).
    dense: Vec<[f64; 2]>,
    neighbours: Vec<Vec<(usize, f64)>>,
    /// Per point of the densified outline: how much the outline turns there, radians per
    /// sensel ([`FollowParams::pull_curvature`]).
    curvature: Vec<f64>,
}

/// Each point's neighbours (itself included) within three `sigma`, with Gaussian weights of
/// scale `sigma`.
fn neighbours_of(dense: &[[f64; 2]], sigma: f64) -> Vec<Vec<(usize, f64)>> {
    let r2 = (3.0 * sigma).powi(2);
    dense
        .iter()
        .map(|p| {
            dense
                .iter()
                .enumerate()
                .filter_map(|(j, q)| {
                    let d2 = (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2);
                    (d2 <= r2).then(|| (j, (-d2 / (2.0 * sigma * sigma)).exp()))
                })
                .collect()
        })
        .collect()
}

/// How much a closed outline turns at each point, radians per unit length: the angle between
/// the chords to the fourth point before and after it, over their mean length.
fn curvature_of(dense: &[[f64; 2]]) -> Vec<f64> {
    let n = dense.len();
    (0..n)
        .map(|i| {
            let k = 4.min(n / 3).max(1);
            let a = dense[(i + n - k) % n];
            let b = dense[i];
            let c = dense[(i + k) % n];
            let (u, v) = ([b[0] - a[0], b[1] - a[1]], [c[0] - b[0], c[1] - b[1]]);
            let turn = (u[0] * v[1] - u[1] * v[0])
                .atan2(u[0] * v[0] + u[1] * v[1])
                .abs();
            let len = 0.5 * (u[0].hypot(u[1]) + v[0].hypot(v[1]));
            if len > 0.0 {
                turn / len
            } else {
                0.0
            }
        })
        .collect()
}

impl Anchor {
    fn new(o: &SequenceObject, aspect: SenselAspect, params: &FollowParams) -> Result<Self> {
        let nodes = registration_outline(o, aspect);
        let shape = modal_core::Shape::from_points_2d(&nodes, modal_core::Topology::ClosedContour)
            .map_err(|e| IoError::invalid(e.to_string()))?;
        let (dense, node_at) = densify(&nodes, params.anchor_step);
        let spline = FactoredSpline::new(&dense, params.smoothing)
            .map_err(|e| IoError::invalid(e.to_string()))?;
        let dense_basis = spline.basis(&dense);
        let curvature = curvature_of(&dense);
        let neighbours = if params.rigid_along > 0.0 {
            neighbours_of(&dense, params.rigid_reach)
        } else {
            Vec::new()
        };
        let mut a = Self {
            dense: dense.clone(),
            neighbours,
            curvature,
            shape,
            prepared: None,
            image: dense,
            node_at,
            spline,
            dense_basis,
            coefficients: None,
            uncovered: 0.0,
            registered: false,
            motion_since_match: 0.0,
            velocity: Vec::new(),
            last_step: f64::INFINITY,
        };
        let identity = a.image.clone();
        a.coefficients = Some(a.fit(&identity)?);
        Ok(a)
    }

    fn coefficients(&self) -> &SplineCoefficients {
        self.coefficients
            .as_ref()
            .expect("an anchor is fitted when made")
    }

    fn fit(&self, values: &[[f64; 2]]) -> Result<SplineCoefficients> {
        self.spline
            .fit(values)
            .map_err(|e| IoError::invalid(e.to_string()))
    }

    /// Registers the anchor onto object `b`: the modal pairs of the anchor onto `b`, then ICP
    /// steps from the latest registration.
    fn register(
        &mut self,
        b: &SequenceObject,
        pair: Option<&MatchResult>,
        aspect: SenselAspect,
        params: &FollowParams,
    ) -> Result<()> {
        let target = registration_outline(b, aspect);
        let shape = closed_contour(&target)?;
        let matched = !self.registered || self.motion_since_match >= params.match_motion;
        let mut pairs: Vec<(usize, [f64; 2])> = Vec::new();
        let mut steps = 1;
        if matched {
            // On an anchor's first registration the run has already matched the anchor's
            // object onto this one (its own object is the frame before).
            let own;
            let m = match pair {
                Some(m) if !self.registered => m,
                _ => {
                    own = self
                        .match_onto(&shape)
                        .map_err(|e| IoError::invalid(e.to_string()))?;
                    &own
                }
            };
            pairs = m
                .pairs
                .iter()
                .filter(|p| !p.excess)
                .map(|p| (self.node_at[p.a], target[p.b]))
                .collect();
            if !self.registered {
                steps = params.first_steps;
            }
            self.motion_since_match = 0.0;
        }
        let before = self.image.clone();
        // Where each point would be at constant velocity: none on the first registration.
        // The prior's strength: full while the anchor's image moved little on the frame before,
        // none once it moves a sizeable part of a sensel a frame (frames far apart).
        let gate = ((params.prior_none - self.last_step) / (params.prior_none - params.prior_full))
            .clamp(0.0, 1.0);
        let (inertia, along) = (params.inertia * gate, params.inertia_along * gate);
        let predicted: Option<Vec<[f64; 2]>> = ((inertia > 0.0 || along > 0.0)
            && self.registered
            && self.velocity.len() == before.len())
        .then(|| {
            (before.iter().zip(&self.velocity))
                .map(|(p, v)| [p[0] + v[0], p[1] + v[1]])
                .collect()
        });
        let (dense_target, _) = densify(&target, params.target_step);
        let dense_target = Grid::new(dense_target, params.reach);
        for k in 0.. {
            let moved = self.icp_step(
                &target,
                &dense_target,
                &pairs,
                params,
                predicted.as_deref().map(|p| (p, inertia, along)),
            )?;
            if k + 1 >= steps.max(params.max_steps) || (k + 1 >= steps && moved < params.settled) {
                break;
            }
        }
        let on = params.inertia > 0.0 || params.inertia_along > 0.0;
        if on && self.velocity.len() != before.len() {
            self.velocity = vec![[0.0; 2]; before.len()];
        }
        if on && self.registered && !matched {
            let eta = params.velocity_smoothing;
            for ((v, p), q) in self.velocity.iter_mut().zip(&self.image).zip(&before) {
                v[0] = (1.0 - eta) * v[0] + eta * (p[0] - q[0]);
                v[1] = (1.0 - eta) * v[1] + eta * (p[1] - q[1]);
            }
        }
        // How far each point moved: the farthest adds to the motion since the last modal match,
        // the median says how far apart the frames are (the priors' strength on the next one).
        let mut distances: Vec<f64> = (self.image.iter().zip(&before))
            .map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1]))
            .collect();
        self.motion_since_match += distances.iter().copied().fold(0.0, f64::max);
        self.last_step = match self.registered {
            true => median(&mut distances),
            false => f64::INFINITY,
        };
        self.uncovered = uncovered(&self.image, &target, &dense_target, params.reach);
        self.registered = true;
        Ok(())
    }

    /// The anchor matched onto `shape` as [`modal_core::match_shapes`] matches them, on this
    /// thread alone (the same result: one pair at a time, beside the run's own pairs): the anchor
    /// prepared once for all its matches.
    fn match_onto(
        &mut self,
        shape: &modal_core::Shape,
    ) -> std::result::Result<MatchResult, modal_core::ModalError> {
        let opts = MatchOptions::default();
        let a = match &self.prepared {
            Some(a) => a.clone(),
            None => {
                let a = prepare(&self.shape, &opts)?;
                self.prepared = Some(a.clone());
                a
            }
        };
        match_prepared(&a, &prepare(shape, &opts)?, &opts, Parallelism::Serial)
    }

    /// One ICP step (returning how far the anchor's image moved, at most): each anchor point's
    /// target is the closest point of the frame's outline, averaged with the frame's nodes that
    /// have it as their closest anchor image (so that the frame's whole outline pulls, not only
    /// the parts nearest the anchor), drawn towards the point's `predicted` position by the
    /// inertia, and pulled towards the modal partner for anchor nodes.
    fn icp_step(
        &mut self,
        nodes: &[[f64; 2]],
        dense_target: &Grid,
        pairs: &[(usize, [f64; 2])],
        params: &FollowParams,
        predicted: Option<(&[[f64; 2]], f64, f64)>,
    ) -> Result<f64> {
        // An anchor point with no target within reach keeps its image (its own weight).
        let mut sum: Vec<[f64; 2]> = self
            .image
            .iter()
            .map(|&q| match dense_target.nearest_within(q, params.reach) {
                Some((k, _)) => dense_target.points[k],
                None => q,
            })
            .collect();
        let mut count = vec![1.0; sum.len()];
        let image = Grid::new(self.image.clone(), params.reach);
        for &p in nodes {
            if let Some((k, _)) = image.nearest_within(p, params.reach) {
                sum[k][0] += p[0];
                sum[k][1] += p[1];
                count[k] += 1.0;
            }
        }
        let mut targets: Vec<[f64; 2]> = sum
            .iter()
            .zip(&count)
            .map(|(s, c)| [s[0] / c, s[1] / c])
            .collect();
        // The frame's outline where each point's image meets it, before the priors and pulls.
        let data = targets.clone();
        if let Some((predicted, g, along)) = predicted {
            if along > 0.0 {
                // Along the outline only: the target's part along the image's tangent drawn
                // towards the prediction's (the outline tells where it lies across, not along).
                pull_along_outline(&self.image, &mut targets, predicted, along);
            }
            for (d, p) in targets.iter_mut().zip(predicted) {
                d[0] = (1.0 - g) * d[0] + g * p[0];
                d[1] = (1.0 - g) * d[1] + g * p[1];
            }
        }
        let rigid = params.rigid_along;
        if rigid > 0.0 && self.neighbours.len() == self.image.len() {
            // Along the outline only, as the prior: the part of each target along the image's
            // tangent drawn towards where its neighbourhood, moved rigidly, puts it.
            let normals = outline_normals(&self.image);
            let fit = RigidFit {
                dense: &self.dense,
                image: &self.image,
                outline: &data,
                normals: &normals,
                shape: params.rigid_shape,
            };
            let rigidly: Vec<[f64; 2]> = (self.neighbours.iter().enumerate())
                .map(|(i, nb)| fit.moved(nb, i))
                .collect();
            pull_along_outline(&self.image, &mut targets, &rigidly, rigid);
        }
        for &(i, t) in pairs {
            // A partner out of reach is a wrong match (a turned or mirrored pre-alignment of a
            // small contact): the anchor's image is within a frame's motion of the outline.
            let q = self.image[i];
            if (q[0] - t[0]).hypot(q[1] - t[1]) > params.reach {
                continue;
            }
            let pull = if params.pull_curvature > 0.0 {
                params.pull * (self.curvature[i] / params.pull_curvature).min(1.0)
            } else {
                params.pull
            };
            let d = &mut targets[i];
            d[0] = (1.0 - pull) * d[0] + pull * t[0];
            d[1] = (1.0 - pull) * d[1] + pull * t[1];
        }
        let c = self.fit(&targets)?;
        let image = self.dense_basis.apply(&c);
        let moved = image
            .iter()
            .zip(&self.image)
            .map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1]))
            .fold(0.0, f64::max);
        self.image = image;
        self.coefficients = Some(c);
        Ok(moved)
    }
}

/// Each target's part along the closed outline `image` (its tangent at the target's node, from
/// the node before to the node after) drawn the share `w` of the way towards `towards`'s; across
/// the outline the target stays.
fn pull_along_outline(image: &[[f64; 2]], targets: &mut [[f64; 2]], towards: &[[f64; 2]], w: f64) {
    let n = image.len();
    for (i, (d, p)) in targets.iter_mut().zip(towards).enumerate() {
        let (a, b) = (image[(i + n - 1) % n], image[(i + 1) % n]);
        let (tx, ty) = (b[0] - a[0], b[1] - a[1]);
        let l = tx.hypot(ty);
        if l > 0.0 {
            let (tx, ty) = (tx / l, ty / l);
            let s = (p[0] - d[0]) * tx + (p[1] - d[1]) * ty;
            d[0] += w * s * tx;
            d[1] += w * s * ty;
        }
    }
}

/// The unit normal of a closed outline at each point (across the chord from the point before
/// to the point after).
fn outline_normals(image: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let n = image.len();
    (0..n)
        .map(|i| {
            let (a, b) = (image[(i + n - 1) % n], image[(i + 1) % n]);
            let (tx, ty) = (b[0] - a[0], b[1] - a[1]);
            let l = tx.hypot(ty);
            if l > 0.0 {
                [-ty / l, tx / l]
            } else {
                [0.0, 0.0]
            }
        })
        .collect()
}

/// The locally rigid positions of an anchor's points ([`FollowParams::rigid_along`]): each
/// point's neighbourhood on the anchor (`dense`) moved by the turn and shift that put it best
/// on the frame's `outline` across the image (point to line: each image point's closest point
/// of the outline, with the image's `normals` there) and, with weight `1 − shape`, on its
/// `image` along it.
struct RigidFit<'a> {
    dense: &'a [[f64; 2]],
    image: &'a [[f64; 2]],
    outline: &'a [[f64; 2]],
    normals: &'a [[f64; 2]],
    shape: f64,
}

impl RigidFit<'_> {
    /// Where point `i` lies when its neighbourhood `nb` (weighted points of the anchor) is moved
    /// by the best turn and shift: the weighted least-squares fit onto the image (2-D
    /// Procrustes), then one Gauss–Newton step of the fit across and along the outline from it
    /// (a turn about the neighbourhood's centre and a shift, small: the image lies within a
    /// fraction of a sensel of the outline).
    fn moved(&self, nb: &[(usize, f64)], i: usize) -> [f64; 2] {
        let (dense, image) = (self.dense, self.image);
        // The weighted means and moments in one pass: the turn is that of the cross
        // covariance, the shift takes the means onto each other.
        let (mut w, mut x, mut y) = (0.0, [0.0; 2], [0.0; 2]);
        let (mut dot, mut cross, mut xx) = (0.0, 0.0, 0.0);
        for &(j, wj) in nb {
            let (p, q) = (dense[j], image[j]);
            w += wj;
            x[0] += wj * p[0];
            x[1] += wj * p[1];
            y[0] += wj * q[0];
            y[1] += wj * q[1];
            dot += wj * (p[0] * q[0] + p[1] * q[1]);
            cross += wj * (p[0] * q[1] - p[1] * q[0]);
            xx += wj * (p[0] * p[0] + p[1] * p[1]);
        }
        if w <= 0.0 {
            return image[i];
        }
        let (x, y) = ([x[0] / w, x[1] / w], [y[0] / w, y[1] / w]);
        let c = dot - w * (x[0] * y[0] + x[1] * y[1]);
        let s = cross - w * (x[0] * y[1] - x[1] * y[0]);
        let r = c.hypot(s);
        if r <= 0.0 {
            return image[i];
        }
        let (c, s) = (c / r, s / r);
        // A neighbour's offset from the centre, turned: where the fit puts it is y + that.
        let turned = |p: [f64; 2]| {
            let d = [p[0] - x[0], p[1] - x[1]];
            [c * d[0] - s * d[1], s * d[0] + c * d[1]]
        };
        let here = turned(dense[i]);
        let e = self.shape.clamp(0.0, 1.0);
        // The Gauss–Newton step (d turn, d shift) for residuals across the outline (weight 1,
        // onto the outline) and along it (weight 1 − e, onto the image). With the normal n and
        // tangent t orthonormal, w_n n nᵀ + w_t t tᵀ = w_t I + (w_n − w_t) n nᵀ: the image's
        // share is the Procrustes fit's own normal equations, whose gradient is zero at its
        // optimum and whose matrix is diagonal about the centre (the offsets' weighted sum is
        // zero); only the outline's share remains to be summed point by point.
        let spread = xx - w * (x[0] * x[0] + x[1] * x[1]);
        let mut a = [
            [(1.0 - e) * spread, 0.0, 0.0],
            [0.0, (1.0 - e) * w, 0.0],
            [0.0, 0.0, (1.0 - e) * w],
        ];
        let mut b = [0.0; 3];
        for &(j, wj) in nb {
            let d = turned(dense[j]);
            let p = [y[0] + d[0], y[1] + d[1]];
            let n = self.normals[j];
            let (o, q) = (self.outline[j], image[j]);
            // The turn's motion of the point across the outline, and the residual across it
            // onto the outline less the image's share of it onto the image.
            let vn = -d[1] * n[0] + d[0] * n[1];
            let across = (p[0] - o[0]) * n[0] + (p[1] - o[1]) * n[1];
            let image_across = (p[0] - q[0]) * n[0] + (p[1] - q[1]) * n[1];
            let res = wj * (across - (1.0 - e) * image_across);
            let jac = [vn, n[0], n[1]];
            let we = wj * e;
            for r in 0..3 {
                b[r] += res * jac[r];
                for k in r..3 {
                    a[r][k] += we * jac[r] * jac[k];
                }
            }
        }
        (a[1][0], a[2][0], a[2][1]) = (a[0][1], a[0][2], a[1][2]);
        let Some(step) = solve3(a, [-b[0], -b[1], -b[2]]) else {
            return [y[0] + here[0], y[1] + here[1]];
        };
        [
            y[0] + here[0] - step[0] * here[1] + step[1],
            y[1] + here[1] + step[0] * here[0] + step[2],
        ]
    }
}

/// The solution of the 3 × 3 system `a x = b` (nalgebra's LU), unless `a` is singular relative
/// to its largest entry or not finite.
fn solve3(a: [[f64; 3]; 3], b: [f64; 3]) -> Option<[f64; 3]> {
    let a = nalgebra::Matrix3::from_fn(|r, c| a[r][c]);
    let scale = a.amax();
    let det = a.determinant();
    if !det.is_finite() || det.abs() <= 1e-12 * scale.powi(3) {
        return None;
    }
    let x = a.lu().solve(&nalgebra::Vector3::from(b))?;
    Some([x[0], x[1], x[2]])
}

/// The median of `values` (the upper one of an even count; infinite when there is none).
fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    values
        .get(values.len() / 2)
        .copied()
        .unwrap_or(f64::INFINITY)
}

/// The share of either outline (the registered anchor's points, the frame's nodes) that lies over
/// [`COVERED`] from the other: the larger of the two.
fn uncovered(image: &[[f64; 2]], nodes: &[[f64; 2]], dense_target: &Grid, cell: f64) -> f64 {
    let far = |ps: &[[f64; 2]], of: &Grid| {
        let n = ps
            .iter()
            .filter(|&&p| of.nearest_within(p, COVERED).is_none());
        n.count() as f64 / ps.len().max(1) as f64
    };
    let image_grid = Grid::new(image.to_vec(), cell);
    far(nodes, &image_grid).max(far(image, dense_target))
}

/// Points binned in square cells, for the nearest point within a short reach: an outline's
/// points lie a fraction of a cell apart, so a query looks at a few dozen of them, not all.
/// The points are sorted by cell, column by column (each cell's in their own order), so that a
/// query finds each column's run of cells with one binary search.
struct Grid {
    points: Vec<[f64; 2]>,
    cell: f64,
    /// Each point's cell and index, sorted by cell (stably: within a cell, by index).
    bins: Vec<((i64, i64), usize)>,
}

impl Grid {
    fn new(points: Vec<[f64; 2]>, cell: f64) -> Self {
        let cell = if cell.is_finite() && cell > 0.0 {
            cell
        } else {
            1.0
        };
        let mut bins: Vec<_> = (points.iter().enumerate())
            .map(|(i, &p)| (Self::bin(p, cell), i))
            .collect();
        bins.sort_by_key(|&(b, _)| b);
        Self { points, cell, bins }
    }

    fn bin(p: [f64; 2], cell: f64) -> (i64, i64) {
        ((p[0] / cell).floor() as i64, (p[1] / cell).floor() as i64)
    }

    /// The index of the point nearest `q` and its distance, if one lies within `reach`; of
    /// points equally near, the first met going through the cells column by column.
    fn nearest_within(&self, q: [f64; 2], reach: f64) -> Option<(usize, f64)> {
        let (cx, cy) = Self::bin(q, self.cell);
        let r = (reach / self.cell).ceil() as i64;
        let mut best = (usize::MAX, reach * reach);
        for x in cx - r..=cx + r {
            let first = self.bins.partition_point(|&(b, _)| b < (x, cy - r));
            let column = self.bins[first..].iter();
            for &(_, i) in column.take_while(|&&(b, _)| b <= (x, cy + r)) {
                let p = self.points[i];
                let d = (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2);
                if d <= best.1 {
                    best = (i, d);
                }
            }
        }
        (best.0 != usize::MAX).then(|| (best.0, best.1.sqrt()))
    }
}

/// The index of the point of `ps` nearest `q`, and its distance (brute force: a few hundred
/// points, where a tree would cost more to build than it saves).
fn nearest(ps: &[[f64; 2]], q: [f64; 2]) -> (usize, f64) {
    let mut best = (0, f64::INFINITY);
    for (i, p) in ps.iter().enumerate() {
        let d = (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2);
        if d < best.1 {
            best = (i, d);
        }
    }
    (best.0, best.1.sqrt())
}

/// A closed polyline with points added so that no gap exceeds `step`: the nodes first (node `i`
/// at `node_at[i]`), then the points between them.
pub(crate) fn densify(nodes: &[[f64; 2]], step: f64) -> (Vec<[f64; 2]>, Vec<usize>) {
    let n = nodes.len();
    let mut dense = Vec::with_capacity(n * 4);
    let mut node_at = Vec::with_capacity(n);
    for i in 0..n {
        let (p, q) = (nodes[i], nodes[(i + 1) % n]);
        node_at.push(dense.len());
        let k = ((p[0] - q[0]).hypot(p[1] - q[1]) / step).ceil().max(1.0) as usize;
        for j in 0..k {
            let t = j as f64 / k as f64;
            dense.push([p[0] + (q[0] - p[0]) * t, p[1] + (q[1] - p[1]) * t]);
        }
    }
    (dense, node_at)
}

/// A closed contour through `nodes`.
fn closed_contour(nodes: &[[f64; 2]]) -> Result<modal_core::Shape> {
    modal_core::Shape::from_points_2d(nodes, modal_core::Topology::ClosedContour)
        .map_err(|e| IoError::invalid(e.to_string()))
}

/// The object's outline nodes in sensels.
pub(crate) fn outline(o: &SequenceObject) -> Vec<[f64; 2]> {
    (0..o.shape.len())
        .map(|i| [o.shape.point(i)[0], o.shape.point(i)[1]])
        .collect()
}

/// The object's outline nodes in registration coordinates (true proportions).
fn registration_outline(o: &SequenceObject, aspect: SenselAspect) -> Vec<[f64; 2]> {
    outline(o)
        .into_iter()
        .map(|p| aspect.to_registration(p))
        .collect()
}

/// A closed outline (sensels) and how far a point lies outside it.
struct Contact {
    nodes: Vec<[f64; 2]>,
    /// The outline sampled every quarter sensel, in registration coordinates.
    dense: Vec<[f64; 2]>,
    aspect: SenselAspect,
}

impl Contact {
    fn of(o: &SequenceObject, aspect: SenselAspect) -> Self {
        let nodes = outline(o);
        let (dense, _) = densify(&registration_outline(o, aspect), 0.25);
        Self {
            nodes,
            dense,
            aspect,
        }
    }

    /// 0 for a point inside the outline, else its distance to it (registration units).
    fn outside(&self, p: [f64; 2]) -> f64 {
        let nodes = &self.nodes;
        let n = nodes.len();
        let mut inside = false;
        for i in 0..n {
            let (a, b) = (nodes[i], nodes[(i + 1) % n]);
            if (a[1] > p[1]) != (b[1] > p[1]) {
                let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
                if p[0] < x {
                    inside = !inside;
                }
            }
        }
        if inside {
            return 0.0;
        }
        nearest(&self.dense, self.aspect.to_registration(p)).1
    }
}

impl SenselAspect {
    /// Sensel coordinates to registration coordinates (y in units of the x pitch).
    fn to_registration(self, p: [f64; 2]) -> [f64; 2] {
        [p[0], p[1] * self.0]
    }

    /// Registration coordinates back to sensels.
    fn back_from_registration(self, p: [f64; 2]) -> [f64; 2] {
        [p[0], p[1] / self.0]
    }
}

#[cfg(test)]
mod grid_tests {
    use super::*;
    use proptest::prelude::*;

    /// The cells visited one by one, as a map of cells lists them (the grid's former layout):
    /// column by column, each cell's points in their order, a later point at an equal distance
    /// taking the place of an earlier one.
    fn cell_by_cell(
        points: &[[f64; 2]],
        cell: f64,
        q: [f64; 2],
        reach: f64,
    ) -> Option<(usize, f64)> {
        let mut bins: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
        for (i, &p) in points.iter().enumerate() {
            bins.entry(Grid::bin(p, cell)).or_default().push(i);
        }
        let (cx, cy) = Grid::bin(q, cell);
        let r = (reach / cell).ceil() as i64;
        let mut best = (usize::MAX, reach * reach);
        for x in cx - r..=cx + r {
            for y in cy - r..=cy + r {
                for &i in bins.get(&(x, y)).map_or(&[][..], Vec::as_slice) {
                    let p = points[i];
                    let d = (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2);
                    if d <= best.1 {
                        best = (i, d);
                    }
                }
            }
        }
        (best.0 != usize::MAX).then(|| (best.0, best.1.sqrt()))
    }

    proptest! {
        // Points and queries on a quarter-unit lattice: equal distances are common, so the
        // order in which equally near points are met is tested too.
        #[test]
        fn the_sorted_grid_finds_what_the_cells_one_by_one_find(
            pts in prop::collection::vec((-40i32..40, -40i32..40), 1..80),
            queries in prop::collection::vec((-48i32..48, -48i32..48), 1..20),
            cell in prop::sample::select(vec![0.5, 1.0, 2.0, 3.0]),
            reach in prop::sample::select(vec![1.0, 2.0, 2.5]),
        ) {
            let points: Vec<[f64; 2]> =
                pts.iter().map(|&(x, y)| [f64::from(x) * 0.25, f64::from(y) * 0.25]).collect();
            let grid = Grid::new(points.clone(), cell);
            for &(x, y) in &queries {
                let q = [f64::from(x) * 0.25, f64::from(y) * 0.25];
                prop_assert_eq!(grid.nearest_within(q, reach), cell_by_cell(&points, cell, q, reach));
            }
        }
    }
}

#[cfg(test)]
mod rigid_tests {
    use super::*;

    #[test]
    fn solve3_solves_a_gauss_newton_system_and_refuses_a_singular_one() {
        // A symmetric positive definite system of the fit's kind (turn, shift x, shift y), its
        // entries of mixed scale; the residual of the solution is at rounding level.
        let a = [[250.0, -3.0, 12.0], [-3.0, 9.0, 0.5], [12.0, 0.5, 7.0]];
        let x = [0.02, -1.5, 3.25];
        let b: [f64; 3] = std::array::from_fn(|r| (0..3).map(|c| a[r][c] * x[c]).sum());
        let got = solve3(a, b).unwrap();
        for (g, w) in got.iter().zip(&x) {
            assert!((g - w).abs() < 1e-12, "{got:?} against {x:?}");
        }
        // A row that is the sum of the others, at any scale, and a non-finite entry.
        for scale in [1e-6, 1.0, 1e6] {
            let row = [a[0][0] + a[1][0], a[0][1] + a[1][1], a[0][2] + a[1][2]];
            let singular = [a[0], a[1], row].map(|r| r.map(|v| v * scale));
            assert_eq!(solve3(singular, b), None, "scale {scale}");
        }
        let mut infinite = a;
        infinite[1][1] = f64::INFINITY;
        assert_eq!(solve3(infinite, b), None);
    }

    /// A foot-sized closed outline: an ellipse with a dent, every sensel or so.
    fn outline() -> Vec<[f64; 2]> {
        (0..120)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / 120.0;
                let r = 1.0 - 0.15 * (3.0 * t).cos();
                [20.0 + 8.0 * r * t.cos(), 40.0 + 20.0 * r * t.sin()]
            })
            .collect()
    }

    /// Point `i`'s locally rigid position by the fit onto the image alone (2-D Procrustes).
    fn rigidly_moved(
        dense: &[[f64; 2]],
        image: &[[f64; 2]],
        nb: &[(usize, f64)],
        i: usize,
    ) -> [f64; 2] {
        let normals = outline_normals(image);
        let fit = RigidFit {
            dense,
            image,
            outline: image,
            normals: &normals,
            shape: 0.0,
        };
        fit.moved(nb, i)
    }

    #[test]
    fn a_neighbourhood_moved_rigidly_puts_each_point_where_the_motion_does() {
        let dense = outline();
        let (c, s) = (0.3f64.cos(), 0.3f64.sin());
        let image: Vec<[f64; 2]> = dense
            .iter()
            .map(|p| [c * p[0] - s * p[1] + 4.0, s * p[0] + c * p[1] - 7.0])
            .collect();
        let nb = neighbours_of(&dense, 10.0);
        for i in (0..dense.len()).step_by(7) {
            let p = rigidly_moved(&dense, &image, &nb[i], i);
            assert!(
                (p[0] - image[i][0]).hypot(p[1] - image[i][1]) < 1e-9,
                "point {i}"
            );
        }
    }

    #[test]
    fn a_non_rigid_neighbourhood_gives_the_least_squares_turn_and_shift() {
        // The image spreads the outline sideways and slides part of it: the turn of the
        // weighted least-squares fit, found by brute force over angles (the best shift for a
        // turn takes the weighted means onto each other), gives the same position.
        let dense = outline();
        let image: Vec<[f64; 2]> = dense
            .iter()
            .map(|p| {
                [
                    20.0 + 1.2 * (p[0] - 20.0) + 0.02 * p[1],
                    p[1] + 0.5 * (p[0] * 0.3).sin(),
                ]
            })
            .collect();
        let nb = neighbours_of(&dense, 6.0);
        for i in (0..dense.len()).step_by(11) {
            let w: f64 = nb[i].iter().map(|&(_, w)| w).sum();
            let mean = |ps: &[[f64; 2]]| {
                let m = nb[i].iter().fold([0.0; 2], |m, &(j, wj)| {
                    [m[0] + wj * ps[j][0], m[1] + wj * ps[j][1]]
                });
                [m[0] / w, m[1] / w]
            };
            let (x, y) = (mean(&dense), mean(&image));
            let moved = |a: f64, p: [f64; 2]| {
                let d = [p[0] - x[0], p[1] - x[1]];
                [
                    y[0] + a.cos() * d[0] - a.sin() * d[1],
                    y[1] + a.sin() * d[0] + a.cos() * d[1],
                ]
            };
            let cost = |a: f64| -> f64 {
                nb[i]
                    .iter()
                    .map(|&(j, wj)| {
                        let q = moved(a, dense[j]);
                        wj * ((q[0] - image[j][0]).powi(2) + (q[1] - image[j][1]).powi(2))
                    })
                    .sum()
            };
            // A coarse search over ±0.2 rad, then a fine one about its best.
            let search = |from: f64, step: f64| {
                (-200..=200)
                    .map(|k| from + f64::from(k) * step)
                    .map(|a| (cost(a), a))
                    .min_by(|p, q| p.0.total_cmp(&q.0))
                    .map_or(0.0, |(_, a)| a)
            };
            let best = search(search(0.0, 1e-3), 1e-5);
            let p = rigidly_moved(&dense, &image, &nb[i], i);
            let q = moved(best, dense[i]);
            assert!(
                (p[0] - q[0]).hypot(p[1] - q[1]) < 2e-3,
                "point {i}: {p:?} against {q:?}"
            );
        }
    }

    #[test]
    fn the_frame_outline_undoes_a_slide_the_image_shows() {
        // The frame's outline is the anchor's, turned and shifted; the image lies on it but has
        // slid along it (a point's place moved by up to 1.5 sensels of outline, smoothly). Fitted
        // onto the outline across it (one Gauss-Newton step), the neighbourhood's turn and shift
        // put every point within a fifth of a sensel of where the true motion does; fitted onto
        // the image alone, some point is left more than 0.8 sensel off.
        let fine: Vec<[f64; 2]> = (0..1200)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / 1200.0;
                let r = 1.0 - 0.15 * (3.0 * t).cos();
                [20.0 + 8.0 * r * t.cos(), 40.0 + 20.0 * r * t.sin()]
            })
            .collect();
        let (c, s) = (0.2f64.cos(), 0.2f64.sin());
        let motion = |p: [f64; 2]| [c * p[0] - s * p[1] + 3.0, s * p[0] + c * p[1] - 5.0];
        let dense: Vec<[f64; 2]> = fine.iter().step_by(10).copied().collect();
        let truth: Vec<[f64; 2]> = dense.iter().map(|&p| motion(p)).collect();
        // Slid along the true outline by up to 15 of its 1200 points (~1.5 sensels).
        let image: Vec<[f64; 2]> = (0..dense.len())
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / dense.len() as f64;
                let slide = (15.0 * (t.sin() + 0.5 * (2.0 * t).cos())).round() as i64;
                motion(fine[(10 * k as i64 + slide).rem_euclid(1200) as usize])
            })
            .collect();
        let normals = outline_normals(&image);
        let nb = neighbours_of(&dense, 8.0);
        let (mut on_outline, mut on_image) = (0.0f64, 0.0f64);
        for i in 0..dense.len() {
            let fit = |shape| RigidFit {
                dense: &dense,
                image: &image,
                outline: &image,
                normals: &normals,
                shape,
            };
            let off = |p: [f64; 2]| (p[0] - truth[i][0]).hypot(p[1] - truth[i][1]);
            on_outline = on_outline.max(off(fit(1.0).moved(&nb[i], i)));
            on_image = on_image.max(off(fit(0.0).moved(&nb[i], i)));
        }
        assert!(on_outline < 0.2, "{on_outline}");
        assert!(on_image > 0.8, "{on_image}");
    }

    #[test]
    fn a_circle_turns_by_one_over_its_radius() {
        let r = 7.0;
        let circle: Vec<[f64; 2]> = (0..44)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / 44.0;
                [r * t.cos(), r * t.sin()]
            })
            .collect();
        for k in curvature_of(&circle) {
            // Chords over four points either side: 1.4 % above 1 / r at this spacing.
            assert!((k - 1.0 / r).abs() < 0.02 / r, "{k}");
        }
        let line: Vec<[f64; 2]> = (0..40).map(|k| [k as f64, 0.0]).collect();
        // A straight stretch (away from the closing jump) does not turn.
        assert!(curvature_of(&line)[5..35].iter().all(|&k| k.abs() < 1e-12));
    }
}
