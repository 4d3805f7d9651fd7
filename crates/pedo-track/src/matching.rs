//! The pairs of a run matched: shapes prepared once per object, pairs matched in windows on the
//! rayon pool, oblong sensels in their true proportions ([`SenselAspect`]), and a part matched
//! into the numbering of the whole it split from or merges into.

use crate::consistency::PairConsistency;
use crate::*;
use modal_core::{
    match_prepared, match_shapes, prepare, AffinityMatrix, MatchOptions, MatchResult, ModalError,
    Parallelism, PreparedShape, Search, Shape, Side, Topology,
};
use pedo_io::{IoError, Result};
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Matches every candidate pair (in parallel). One pair that cannot be matched never sinks the
/// recording: it is reported with its reason and left out. Pairs whose two objects have exactly
/// the shapes of an earlier pair of the window (a 500 Hz recording holds still for frames on
/// end) take that pair's outcome: the matcher reads nothing else, so it would give the same.
pub(crate) fn match_all(
    objects: &[SequenceObject],
    candidates: &[(usize, usize)],
    parts: &HashMap<(usize, usize), PartOfWhole>,
    options: &SequenceOptions,
    progress: &(dyn Fn(Stage, usize, usize) + Sync),
) -> (Vec<PairMatch>, Vec<SkippedPair>) {
    // The pairs go in windows of MATCH_WINDOW, in order: only the objects of the current window
    // are prepared (a prepared object holds its n × n modes), so memory does not grow with the
    // recording's length. An object on a window's edge is prepared in both windows, identically.
    let done = AtomicUsize::new(0);
    let mut pairs = Vec::with_capacity(candidates.len());
    let mut skipped = Vec::new();
    for window in candidates.chunks(MATCH_WINDOW) {
        if pedo_io::cancel::cancelled(options.cancel.as_ref()) {
            break;
        }
        let same = same_shapes(objects, window);
        let prepared =
            prepare_objects(objects, &same, &options.matching, SenselAspect::of(options));
        let first = first_of_same(window, &same, parts);
        let outcomes: Vec<Option<Outcome>> = (0..window.len())
            .into_par_iter()
            .map(|i| {
                (first[i] == i).then(|| {
                    let (a, b) = window[i];
                    if pedo_io::cancel::cancelled(options.cancel.as_ref()) {
                        // Not matched: the run fails once the window is done.
                        return Err(PairFailure::Cancelled);
                    }
                    let r = pair_outcome(objects, &prepared, a, b, parts.get(&(a, b)), options);
                    let n = done.fetch_add(1, Ordering::Relaxed) + 1;
                    progress(Stage::Matching, n, candidates.len());
                    r
                })
            })
            .collect();
        // Only the window's outcomes are held twice while they are sorted out.
        for (i, &(a, b)) in window.iter().enumerate() {
            let outcome = outcomes[first[i]]
                .as_ref()
                .expect("a first pair is matched");
            // A repeat is matched when its first pair is, not after a cancellation.
            let cancelled = matches!(outcome, Err(PairFailure::Cancelled));
            if first[i] != i && !cancelled {
                let n = done.fetch_add(1, Ordering::Relaxed) + 1;
                progress(Stage::Matching, n, candidates.len());
            }
            match pair_match(objects, a, b, outcome.clone(), options) {
                Ok(p) => pairs.push(p),
                Err(s) => skipped.push(s),
            }
        }
    }
    (pairs, skipped)
}

/// Pairs matched per window of [`match_all`]: enough to keep every core busy, few enough that
/// the prepared objects of one window stay small.
const MATCH_WINDOW: usize = 128;

/// The objects prepared for matching, by index.
type Prepared = HashMap<usize, std::result::Result<PreparedShape, ModalError>>;

/// What the matcher makes of a pair, whichever objects hold its two shapes: the result and its
/// consistency figures, or why it failed.
type Outcome = std::result::Result<(MatchResult, Option<(PairConsistency, Vec<f32>)>), PairFailure>;

/// Why a pair was not matched.
#[derive(Debug, Clone)]
pub(crate) enum PairFailure {
    Cancelled,
    Modal(ModalError),
}

/// A shape exactly: its dimension, topology and every coordinate's bits. Equal keys are the same
/// input to the matcher (a cache that must be exact compares bits, not values: `0.0 == -0.0`).
#[derive(Debug, PartialEq, Eq, Hash)]
pub(crate) struct ShapeKey(Vec<u64>);

impl ShapeKey {
    pub(crate) fn of(shape: &Shape) -> Self {
        let (tag, triangles): (u64, &[[usize; 3]]) = match shape.topology() {
            Topology::None => (0, &[]),
            Topology::ClosedContour => (1, &[]),
            Topology::Mesh { triangles } => (2, triangles),
        };
        let mut key = vec![shape.dim() as u64, tag, triangles.len() as u64];
        key.extend(triangles.iter().flatten().map(|&t| t as u64));
        key.extend(shape.coords().iter().map(|c| c.to_bits()));
        Self(key)
    }
}

/// Each object of the pairs `window` with the first object of the window (by id) whose shape is
/// exactly its own ([`ShapeKey`]): objects of one shape are one input to the matcher.
pub(crate) fn same_shapes(
    objects: &[SequenceObject],
    window: &[(usize, usize)],
) -> HashMap<usize, usize> {
    let mut ids: Vec<usize> = window.iter().flat_map(|&(a, b)| [a, b]).collect();
    ids.sort_unstable();
    ids.dedup();
    let mut first: HashMap<ShapeKey, usize> = HashMap::new();
    (ids.into_iter())
        .map(|o| {
            (
                o,
                *first.entry(ShapeKey::of(&objects[o].shape)).or_insert(o),
            )
        })
        .collect()
}

/// For each pair of `window`, the first pair of the window with exactly its two shapes (itself
/// when none comes before), from the window's [`same_shapes`]. A part matched into its whole's
/// numbering also depends on its siblings: those pairs are always their own.
pub(crate) fn first_of_same(
    window: &[(usize, usize)],
    same: &HashMap<usize, usize>,
    parts: &HashMap<(usize, usize), PartOfWhole>,
) -> Vec<usize> {
    let mut seen = HashMap::new();
    (window.iter().enumerate())
        .map(|(i, &(a, b))| {
            if parts.contains_key(&(a, b)) {
                return i;
            }
            *seen.entry((same[&a], same[&b])).or_insert(i)
        })
        .collect()
}

/// Every object of a window of pairs prepared once (in parallel): as the second object of the
/// pair with its predecessor and the first of the pair with its successor. Objects of exactly the
/// same shape (`same`, the window's [`same_shapes`]) share one preparation, and with it the modes
/// it caches. An object that cannot be prepared keeps its error for the pairs that need it.
pub(crate) fn prepare_objects(
    objects: &[SequenceObject],
    same: &HashMap<usize, usize>,
    options: &MatchOptions,
    aspect: SenselAspect,
) -> Prepared {
    let firsts: Vec<usize> = (same.iter())
        .filter(|(o, s)| o == s)
        .map(|(&o, _)| o)
        .collect();
    let mut prepared: Prepared = (firsts.into_par_iter())
        .map(|o| {
            let shape = aspect.shape(&objects[o].shape);
            (o, shape.and_then(|s| prepare(&s, options)))
        })
        .collect();
    for (&o, s) in same.iter().filter(|(o, s)| o != s) {
        let p = prepared[s].clone();
        prepared.insert(o, p);
    }
    prepared
}

/// The coordinates pairs are matched in: y scaled by the sensor's row pitch over its column
/// pitch ([`SequenceOptions::sensel_aspect`]), x in sensels, so that a grid of oblong sensels
/// is matched in its true proportions. Square sensels (1) leave every shape as it is.
///
/// ```
/// use pedo_track::SenselAspect;
/// use modal_core::{Shape, Topology};
/// let aspect = SenselAspect::of_pitch(Some([5.08, 7.62])); // footscan: 1.5
/// let s = Shape::new(2, vec![0.0, 0.0, 2.0, 0.0, 0.0, 2.0], Topology::ClosedContour)?;
/// assert_eq!(aspect.shape(&s)?.coords(), &[0.0, 0.0, 2.0, 0.0, 0.0, 3.0]);
/// # Ok::<(), modal_core::ModalError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SenselAspect(pub(crate) f64);

impl SenselAspect {
    /// Square sensels: shapes are matched as they are.
    pub const SQUARE: Self = Self(1.0);

    /// The aspect of a sensor whose pitch is `pitch_mm` (x, y); square when unknown.
    pub fn of_pitch(pitch_mm: Option<[f64; 2]>) -> Self {
        Self::checked(pitch_mm.map_or(1.0, |[x, y]| y / x))
    }

    pub(crate) fn of(options: &SequenceOptions) -> Self {
        Self::checked(options.sensel_aspect)
    }

    fn checked(a: f64) -> Self {
        Self(if a.is_finite() && a > 0.0 { a } else { 1.0 })
    }

    /// `shape` in matching coordinates (an error only if scaling took a coordinate beyond
    /// the range of `f64`).
    pub fn shape<'s>(
        self,
        shape: &'s Shape,
    ) -> std::result::Result<std::borrow::Cow<'s, Shape>, ModalError> {
        if self.0 == 1.0 {
            return Ok(std::borrow::Cow::Borrowed(shape));
        }
        let d = shape.dim();
        let mut coords = shape.coords().to_vec();
        coords
            .iter_mut()
            .skip(1)
            .step_by(d)
            .for_each(|y| *y *= self.0);
        let scaled = Shape::new(d, coords, shape.topology().clone())?;
        Ok(std::borrow::Cow::Owned(scaled))
    }

    /// A result matched in matching coordinates, with its transform and aligned nodes back in
    /// sensels (the pairs are node indices, the same in both).
    pub fn back(self, mut r: MatchResult) -> MatchResult {
        if self.0 == 1.0 {
            return r;
        }
        let d = r.transform.dim;
        let s = |i: usize| if i == 1 { self.0 } else { 1.0 };
        for i in 0..d {
            for j in 0..d {
                r.transform.m[i][j] *= s(j) / s(i);
            }
            r.transform.t[i] /= s(i);
        }
        r.aligned_a
            .iter_mut()
            .skip(1)
            .step_by(d)
            .for_each(|y| *y /= self.0);
        r
    }
}

/// The matcher's outcome for the pair of objects `a` and `b` (`part`: a part matched into its
/// whole's numbering).
fn pair_outcome(
    objects: &[SequenceObject],
    prepared: &Prepared,
    a: usize,
    b: usize,
    part: Option<&PartOfWhole>,
    options: &SequenceOptions,
) -> Outcome {
    let (oa, ob) = (&objects[a], &objects[b]);
    let aspect = SenselAspect::of(options);
    // The pairs run in parallel on the pool, so each pair runs on one thread.
    let result = match (part, prepared.get(&a), prepared.get(&b)) {
        (Some(part), _, _) => {
            match_part_with_whole(objects, prepared, part, b, &options.matching, aspect)
        }
        (None, Some(Ok(pa)), Some(Ok(pb))) => {
            match_prepared(pa, pb, &options.matching, Parallelism::Serial)
        }
        // The error names the object's role in the pair, as the one-call form words it.
        _ => aspect
            .shape(&oa.shape)
            .and_then(|sa| match_shapes(&sa, aspect.shape(&ob.shape)?.as_ref(), &options.matching)),
    }
    .map(|r| aspect.back(r))
    .map_err(PairFailure::Modal)?;
    let consistency = PairConsistency::with_steps(&oa.shape, &ob.shape, &result.pairs, aspect);
    Ok((result, consistency))
}

/// The pair of objects `a` and `b` with the matcher's `outcome` for their shapes: its row, its
/// trackable matches, or why it was skipped.
fn pair_match(
    objects: &[SequenceObject],
    a: usize,
    b: usize,
    outcome: Outcome,
    options: &SequenceOptions,
) -> std::result::Result<PairMatch, SkippedPair> {
    let skipped = |reason: String| SkippedPair { a, b, reason };
    let (oa, ob) = (&objects[a], &objects[b]);
    let (result, consistency) = outcome.map_err(|e| match e {
        PairFailure::Cancelled => skipped("cancelled".into()),
        // The error names the two objects, as the one-pair form words it.
        PairFailure::Modal(e) => skipped(
            IoError::invalid(format!(
                "matching object {} (frame {}) with object {} (frame {}): {e}",
                oa.id, oa.frame, ob.id, ob.frame
            ))
            .to_string(),
        ),
    })?;
    pair_row(oa, ob, a, b, result, consistency, options).map_err(|e| skipped(e.to_string()))
}

/// A matched pair with its row of the pairs table.
fn pair_row(
    oa: &SequenceObject,
    ob: &SequenceObject,
    a: usize,
    b: usize,
    result: MatchResult,
    consistency: Option<(PairConsistency, Vec<f32>)>,
    options: &SequenceOptions,
) -> Result<PairMatch> {
    let (consistency, step_round_trips) = consistency.unzip();
    let aspect = SenselAspect::of(options);
    let (n, m) = (oa.shape.len(), ob.shape.len());
    let min = n.min(m).max(1) as f64;
    let one_to_one: Vec<_> = result.pairs.iter().filter(|p| !p.excess).collect();
    // Mutual-best matches on the final affinity are counted whatever the search.
    let local = result.local_count();
    let optimisation = if options.matching.search == Search::Local {
        0
    } else {
        one_to_one.len()
    };
    // The step rule is made once per pair and asked per match.
    let bound = crate::pairing::StepBound::new(oa, ob, aspect);
    let flags: Vec<bool> = (result.pairs.iter())
        .map(|p| !p.excess && bound.allows(oa.shape.point(p.a), ob.shape.point(p.b)))
        .collect();
    let trackable = flags.iter().filter(|&&f| f).count();
    let mean_cost = if one_to_one.is_empty() {
        0.0
    } else {
        one_to_one.iter().map(|p| p.cost).sum::<f64>() / one_to_one.len() as f64
    };
    let row = PairRow {
        objects: PairObjects::of(oa, ob),
        local_matches: local,
        local_percent: 100.0 * local as f64 / min,
        optimisation_matches: optimisation,
        optimisation_percent: 100.0 * optimisation as f64 / min,
        matches_after_excess: result.pairs.len(),
        mean_cost,
        trackable_matches: trackable,
        trackable_percent: 100.0 * trackable as f64 / min,
        crossings: result.crossings,
        consistency,
    };
    let mut pair = PairMatch {
        a,
        b,
        result,
        row,
        trackable: flags,
        step_round_trips: step_round_trips.unwrap_or_default(),
    };
    if !options.keep_match_details {
        pair.strip_details()?;
    }
    Ok(pair)
}

/// A part of a region paired with the whole region at a merge or a split (contour model): a heel
/// outline whose next frame's outline is the whole foot, or the other way round. The part is
/// matched to its own portion of the whole ([`portion_of_whole`]), never normalised onto it.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PartOfWhole {
    part: usize,
    whole: usize,
    /// The other parts of the same merge or split.
    siblings: Vec<usize>,
}

/// How far from a part, in node spacings of the whole, a node of the whole may lie and still
/// belong to the part's portion: the boundary's motion between two frames plus a margin.
pub const PORTION_REACH: f64 = 5.0;

/// The pairs among `pairs` that join a part and a whole: `(i, j)` with `i` among the objects that
/// merge into `j`, or `j` among the objects `i` splits into.
pub(crate) fn parts_of_wholes(
    pairs: &[(usize, usize)],
    splits: &[(usize, Vec<usize>)],
    merges: &[(Vec<usize>, usize)],
) -> HashMap<(usize, usize), PartOfWhole> {
    let others = |all: &[usize], one: usize| all.iter().copied().filter(|&k| k != one).collect();
    let mut out = HashMap::new();
    for &(a, b) in pairs {
        let merged = merges.iter().find(|(is, j)| *j == b && is.contains(&a));
        let split = splits.iter().find(|(i, js)| *i == a && js.contains(&b));
        let part = match (merged, split) {
            (Some((is, _)), _) => PartOfWhole {
                part: a,
                whole: b,
                siblings: others(is, a),
            },
            (None, Some((_, js))) => PartOfWhole {
                part: b,
                whole: a,
                siblings: others(js, b),
            },
            (None, None) => continue,
        };
        out.insert((a, b), part);
    }
    out
}

/// The nodes of the whole (in its order) that form the part's portion: within
/// [`PORTION_REACH`] node spacings of the part's outline, and no nearer to a sibling's outline.
pub(crate) fn portion_of_whole(part: &Shape, whole: &Shape, siblings: &[&Shape]) -> Vec<usize> {
    let spacing = crate::pairing::outline_distance(whole.coords(), [0.0, 0.0]).1;
    let reach = PORTION_REACH * spacing;
    (0..whole.len())
        .filter(|&w| {
            let p = whole.point(w);
            let near = |s: &Shape| crate::pairing::outline_distance(s.coords(), [p[0], p[1]]).0;
            let to_part = near(part);
            to_part <= reach && siblings.iter().all(|s| near(s) >= to_part)
        })
        .collect()
}

/// Matches a part with its portion of the whole (the portion closed into an outline, as the
/// region the part covers), and reports the result in the whole's numbering: the whole's nodes
/// outside the portion stay unmatched. `b` is the pair's second object.
fn match_part_with_whole(
    objects: &[SequenceObject],
    prepared: &Prepared,
    part: &PartOfWhole,
    b: usize,
    opts: &MatchOptions,
    aspect: SenselAspect,
) -> std::result::Result<MatchResult, ModalError> {
    let whole = aspect.shape(&objects[part.whole].shape)?;
    let siblings = part
        .siblings
        .iter()
        .map(|&s| aspect.shape(&objects[s].shape))
        .collect::<std::result::Result<Vec<_>, _>>()?;
    let siblings: Vec<&Shape> = siblings.iter().map(|s| s.as_ref()).collect();
    let own = aspect.shape(&objects[part.part].shape)?;
    let (whole, own) = (whole.as_ref(), own.as_ref());
    let portion = portion_of_whole(own, whole, &siblings);
    let whole_is_b = part.whole == b;
    if portion.len() < 3 {
        // The portion of the whole that the part covers is too small to be modelled.
        let side = if whole_is_b { Side::B } else { Side::A };
        let too_few = ModalError::TooFewNodes {
            nodes: portion.len(),
            min: 3,
        };
        return Err(too_few.of(side));
    }
    let coords = portion
        .iter()
        .flat_map(|&w| whole.point(w).to_vec())
        .collect();
    let sub = prepare(&Shape::new(2, coords, Topology::ClosedContour)?, opts)?;
    let own = match prepared.get(&part.part) {
        Some(Ok(p)) => p.clone(),
        _ => prepare(own, opts)?,
    };
    let r = if whole_is_b {
        match_prepared(&own, &sub, opts, Parallelism::Serial)?
    } else {
        match_prepared(&sub, &own, opts, Parallelism::Serial)?
    };
    in_whole_numbering(r, &portion, whole, whole_is_b)
}

/// A match against a portion of the whole, renumbered to the whole: pairs, local pairs and the
/// affinity (the columns or rows of the nodes outside the portion at the largest cost, 1).
fn in_whole_numbering(
    r: MatchResult,
    portion: &[usize],
    whole: &Shape,
    whole_is_b: bool,
) -> std::result::Result<MatchResult, ModalError> {
    let z = &r.affinity;
    let (rows, cols) = if whole_is_b {
        (z.rows(), whole.len())
    } else {
        (whole.len(), z.cols())
    };
    let mut data = vec![1.0; rows * cols];
    for i in 0..z.rows() {
        for j in 0..z.cols() {
            let (ri, cj) = if whole_is_b {
                (i, portion[j])
            } else {
                (portion[i], j)
            };
            data[ri * cols + cj] = z.get(i, j);
        }
    }
    let renumber = |(i, j): (usize, usize)| {
        if whole_is_b {
            (i, portion[j])
        } else {
            (portion[i], j)
        }
    };
    let pairs: Vec<modal_core::MatchPair> = r
        .pairs
        .iter()
        .map(|p| {
            let (a, b) = renumber((p.a, p.b));
            modal_core::MatchPair { a, b, ..*p }
        })
        .collect();
    let unmatched = |n: usize, used: &dyn Fn(usize) -> bool| (0..n).filter(|&k| !used(k)).collect();
    let aligned_a = if whole_is_b {
        r.aligned_a.clone()
    } else {
        r.transform.apply(whole.coords())
    };
    Ok(MatchResult {
        unmatched_a: unmatched(rows, &|k| pairs.iter().any(|p| p.a == k)),
        unmatched_b: unmatched(cols, &|k| pairs.iter().any(|p| p.b == k)),
        local_pairs: r.local_pairs.iter().copied().map(renumber).collect(),
        affinity: AffinityMatrix::new(rows, cols, data)?,
        pairs,
        aligned_a,
        outline_images: None,
        ..r
    })
}
