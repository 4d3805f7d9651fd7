//! The modal matching pipeline (docs/method.md §5–7), one file per stage:
//!
//! 1. [`prepare`](fn@prepare) — one object checked, normalised and oriented, its own-frame modes cached:
//!    a [`PreparedShape`] serves every pair the object takes part in;
//! 2. [`prealign`] — the first object brought into the second's normalised frame (centroid and
//!    scale, or the robust rotation search with affine ICP, ending with the outline fit for two
//!    closed outlines);
//! 3. [`features`] — the modal features, the mode alignment and the cost matrix `Z`;
//! 4. [`search`] — local, global (with the assignment of the `assign` crate) or best matches;
//! 5. [`excess`] — the nodes the one-to-one search leaves over;
//! 6. `refine` — the modal affine re-fits, which repeat stages 3–5 and keep the best pass;
//! 7. `deform` — optionally ([`Refine::Modal`]), a non-rigid warp of A by its low-order modes,
//!    then stages 3–5 once more; or `coherent` ([`Refine::Coherent`]), A drifted onto B by a
//!    smooth Gaussian-kernel field and assigned to B on the moved positions.
//!
//! [`match_shapes`] composes them for one pair; [`match_prepared`] does the same from prepared
//! objects, on one thread or two as the caller chooses ([`Parallelism`]).

mod coherent;
mod deform;
mod drift_kernel;
pub mod excess;
pub mod features;
mod first_phase;
mod outline_fit;
pub(crate) mod outline_images;
pub mod prealign;
pub mod prepare;
mod recipe;
mod refine;
mod result;
pub mod search;

use self::prealign::Affine;
use self::prepare::{inverse, prepare_as, Pair};
use self::refine::Refined;
use self::search::local_matches;
use crate::error::{ModalError, Side};
use crate::shape::{Shape, Topology};

pub use self::first_phase::Parallelism;
pub use self::prealign::Prealign;
pub use self::prepare::{prepare, PreparedShape};
pub use self::recipe::{MatchOptions, MAX_NODES};
pub use self::refine::Refine;
pub use self::result::{MatchPair, MatchResult};
pub use self::search::Search;

/// Matches the nodes of `a` to the nodes of `b` by modal matching: [`prepare`](fn@prepare) both, then
/// [`match_prepared`] with [`Parallelism::Pair`].
///
/// ```
/// use modal_core::{match_shapes, MatchOptions, Shape, Topology};
/// let ring = |r: f64, n: usize| -> Shape {
///     let c = (0..n)
///         .flat_map(|i| {
///             let t = i as f64 / n as f64 * std::f64::consts::TAU;
///             [r * 1.5 * t.cos(), r * t.sin()]
///         })
///         .collect();
///     Shape::new(2, c, Topology::ClosedContour).unwrap()
/// };
/// let result = match_shapes(&ring(1.0, 24), &ring(1.1, 24), &MatchOptions::default()).unwrap();
/// assert_eq!(result.one_to_one_count(), 24);
/// ```
///
/// # Errors
/// [`ModalError::DimensionMismatch`] for objects of different dimensions; a shape error
/// ([`ModalError::TooFewNodes`], [`ModalError::CoincidentNodes`], [`ModalError::Collinear`], …)
/// wrapped in [`ModalError::Object`] naming the object; [`ModalError::Option`] for a mode
/// fraction outside (0, 1], a negative or NaN threshold and the other values
/// [`MatchOptions`] bounds; [`Unsupported::OrderedMesh`](crate::Unsupported::OrderedMesh) for
/// `ordered` on meshes;
/// [`Unsupported::OrderedSolverNeedsContours`](crate::Unsupported::OrderedSolverNeedsContours)
/// for the ordered solver on anything but two closed contours; model and assignment failures are
/// passed through.
pub fn match_shapes(a: &Shape, b: &Shape, opts: &MatchOptions) -> Result<MatchResult, ModalError> {
    prepare::check_dims(a, b)?;
    let a = prepare_as(a, opts, Some(Side::A))?;
    let b = prepare_as(b, opts, Some(Side::B))?;
    match_prepared(&a, &b, opts, Parallelism::Pair)
}

/// Matches two prepared objects: the pre-alignment, the first modal solves, then the passes of
/// features, search and excess nodes with the affine re-fits between them. With
/// [`Refine::Auto`], two closed planar outlines that the rotation search's outline fit leaves
/// apart, or whose modal match then pairs nodes at a median cost over 0.15, are matched instead
/// as with `prealign` [`Prealign::Normalize`], `position_weight` 1, the default re-fits and
/// [`Refine::Coherent`], with the outline images taken both ways (docs/method.md §7.5). Each
/// object may take
/// part in any number of pairs; what it can share between them was done by [`prepare`](fn@prepare) (see
/// docs/method.md, "The pipeline in the code").
///
/// # Errors
/// As [`match_shapes`], except the checks of single objects, which [`prepare`](fn@prepare) made.
pub fn match_prepared(
    a: &PreparedShape,
    b: &PreparedShape,
    opts: &MatchOptions,
    parallelism: Parallelism,
) -> Result<MatchResult, ModalError> {
    let pair = Pair::new(a, b, opts)?;
    let gated = opts.refine == Refine::Auto
        && pair.ordered
        && pair.dim == 2
        && opts.prealign == Prealign::Robust;
    let apart =
        |cur: &[f64]| coherent::outlines_apart(cur, &pair.b.get().pts, pair.b.get().spacing());
    if let Some(start) = first_phase::first_phase(&pair, parallelism, gated.then_some(&apart))? {
        let refined = refine::refine(&pair, start)?;
        if !(gated && coherent::modes_apart(&refined.kept.pairs, pair.opts)) {
            return Ok(in_callers_terms(&pair, refined));
        }
    }
    two_specimens(a, b, opts, parallelism)
}

/// Two specimens of a shape, told by either gate (the outlines after the rotation search's fit,
/// or the modes after the modal match): the drift from the centroid-and-scale start, its affine
/// re-fits on positions (docs/method.md §7.5). The re-fits only place the start, by the default
/// solver; the drift's own assignment keeps the contours' order whatever the solver. B is
/// drifted onto A too, beside it, and its images read backwards are averaged with A's
/// (`outline_images`); the rest of the result is A's drift.
fn two_specimens(
    a: &PreparedShape,
    b: &PreparedShape,
    opts: &MatchOptions,
    parallelism: Parallelism,
) -> Result<MatchResult, ModalError> {
    let drift = drift_options(opts);
    let forward = || -> Result<MatchResult, ModalError> {
        let (pair, refined) = drift_pass(a, b, &drift, parallelism)?;
        Ok(in_callers_terms(&pair, refined))
    };
    // Only B's images on A are wanted from B's drift (none when it was not drifted).
    let backward = || -> Option<Vec<f64>> {
        let (pair, refined) = drift_pass(b, a, &drift, parallelism).ok()?;
        if !refined.drifted {
            return None;
        }
        let (_, aligned_b) = aligned_in_callers_terms(&pair, &refined.kept.aligned);
        let a_coords = pair.b.shape().coords();
        Some(outline_images::outline_positions(
            &aligned_b, a_coords, pair.dim,
        ))
    };
    let (forward, back) = match parallelism {
        Parallelism::Pair => rayon::join(forward, backward),
        Parallelism::Serial => (forward(), backward()),
    };
    let mut result = forward?;
    let (sa, sb) = (a.shape().coords(), b.shape().coords());
    if let (true, Some(back), Some(images)) = (result.drifted, back, result.outline_images.as_mut())
        && let Some(both) = outline_images::both_ways(images, &back, sa, sb, 2)
    {
        *images = both;
    }
    Ok(result)
}

/// `x` matched to `y` as [`drift_options`] say: the centroid-and-scale start, then the passes.
fn drift_pass<'p>(
    x: &'p PreparedShape,
    y: &'p PreparedShape,
    drift: &'p MatchOptions,
    parallelism: Parallelism,
) -> Result<(Pair<'p>, Refined), ModalError> {
    let pair = Pair::new(x, y, drift)?;
    let start = first_phase::first_phase(&pair, parallelism, None)?.expect("no gate, so a start");
    let refined = refine::refine(&pair, start)?;
    Ok((pair, refined))
}

/// What the gates of [`Refine::Auto`] match two specimens with: `opts` from the
/// centroid-and-scale start, its default affine re-fits on positions, then the coherent drift.
pub(crate) fn drift_options(opts: &MatchOptions) -> MatchOptions {
    MatchOptions {
        prealign: Prealign::Normalize,
        position_weight: 1.0,
        refits: MatchOptions::default().refits,
        refine: Refine::Coherent,
        method: MatchOptions::default().method,
        ..opts.clone()
    }
}

/// The kept pass in the callers' node numbering and coordinates.
fn in_callers_terms(pair: &Pair<'_>, refined: Refined) -> MatchResult {
    let (sa, sb) = (pair.a.get(), pair.b.get());
    let (n, m, d) = (sa.len(), sb.len(), pair.dim);
    let Refined {
        kept,
        refits,
        solves,
        drifted,
    } = refined;
    let affinity = kept.z.reindexed(&inverse(&sa.perm), &inverse(&sb.perm));
    let mut out: Vec<MatchPair> = kept
        .pairs
        .iter()
        .map(|p| MatchPair {
            a: sa.perm[p.a],
            b: sb.perm[p.b],
            ..*p
        })
        .collect();
    out.sort_by_key(|p| (p.excess, if n <= m { (p.b, p.a) } else { (p.a, p.b) }));
    let first_excess = out.iter().position(|p| p.excess).unwrap_or(out.len());
    out[..first_excess].sort_by_key(|p| p.a);
    let mut local_pairs = local_matches(&affinity, pair.threshold);
    local_pairs.sort();
    let mut used_a = vec![false; n];
    let mut used_b = vec![false; m];
    for p in &out {
        used_a[p.a] = true;
        used_b[p.b] = true;
    }
    let (from_b_frame, aligned_a) = aligned_in_callers_terms(pair, &kept.aligned);
    let crossings = contour_crossings(pair.a.shape(), pair.b.shape(), &out);
    let outline_images = crossings.map(|_| {
        let b = pair.b.shape().coords();
        if drifted {
            outline_images::outline_positions(&aligned_a, b, d)
        } else {
            let mut at = vec![f64::NAN; n];
            for p in out.iter().rev() {
                at[p.a] = p.b as f64;
            }
            at
        }
    });
    MatchResult {
        outline_images,
        drifted,
        crossings,
        pairs: out,
        affinity,
        local_pairs,
        unmatched_a: (0..n).filter(|&i| !used_a[i]).collect(),
        unmatched_b: (0..m).filter(|&j| !used_b[j]).collect(),
        n_modes: pair.k,
        refits,
        solves,
        transform: from_b_frame
            .compose(&kept.to_aligned)
            .compose(&sa.to_normalized),
        aligned_a,
    }
}

/// A's nodes `aligned` (in B's normalised frame, prepared order) in B's coordinates and the
/// callers' node order, with the map from B's normalised frame back to B's coordinates.
fn aligned_in_callers_terms(pair: &Pair<'_>, aligned: &[f64]) -> (Affine, Vec<f64>) {
    let (sa, sb, d) = (pair.a.get(), pair.b.get(), pair.dim);
    let from_b_frame = inverse_normalizing_map(&sb.to_normalized);
    let mut out = vec![0.0; aligned.len()];
    for (t, p) in from_b_frame.apply(aligned).chunks_exact(d).enumerate() {
        out[sa.perm[t] * d..(sa.perm[t] + 1) * d].copy_from_slice(p);
    }
    (from_b_frame, out)
}

/// The crossed pairs of `pairs` (callers' numbering) when both objects are closed contours, each
/// read counter-clockwise (in the x-y plane) whatever the direction of its numbering.
fn contour_crossings(a: &Shape, b: &Shape, pairs: &[MatchPair]) -> Option<usize> {
    let contour = |s: &Shape| matches!(s.topology(), Topology::ClosedContour);
    if !(contour(a) && contour(b)) {
        return None;
    }
    let counter_clockwise = |s: &Shape| {
        let d = s.dim();
        let xy: Vec<f64> = s
            .coords()
            .chunks_exact(d)
            .flat_map(|p| [p[0], p[1]])
            .collect();
        prealign::signed_area(&xy) >= 0.0
    };
    let along = |s: &Shape| {
        let (ccw, n) = (counter_clockwise(s), s.len());
        move |i: usize| if ccw { i } else { n - 1 - i }
    };
    let (fa, fb) = (along(a), along(b));
    let oriented: Vec<(usize, usize)> = pairs.iter().map(|p| (fa(p.a), fb(p.b))).collect();
    Some(assign::cyclic_crossings(&oriented))
}

/// The inverse of a `normalizing_map` (prepare.rs): `y ↦ y / scale + centroid`.
pub(crate) fn inverse_normalizing_map(map: &Affine) -> Affine {
    let mut inv = Affine::identity(map.dim);
    for a in 0..map.dim {
        inv.m[a][a] = 1.0 / map.m[a][a];
        inv.t[a] = -map.t[a] / map.m[a][a];
    }
    inv
}

/// `a` after the pre-alignment, in `b`'s normalised frame (centroid 0, RMS radius 1), and that
/// normalised `b`: the coordinates [`match_shapes`] starts from. A contour is normalised again
/// after the affine map, a point set keeps the map's frame. Exposed for diagnostics and for
/// position-only baselines.
pub fn prealign_normalized(
    a: &Shape,
    b: &Shape,
    opts: &MatchOptions,
) -> Result<(Vec<f64>, Vec<f64>), ModalError> {
    if a.dim() != b.dim() {
        return Err(ModalError::DimensionMismatch {
            a: a.dim(),
            b: b.dim(),
        });
    }
    let ordered = opts.ordered.unwrap_or(
        matches!(a.topology(), Topology::ClosedContour)
            && matches!(b.topology(), Topology::ClosedContour),
    );
    let d = a.dim();
    let (pa, ca, sa) = prealign::normalize(a.coords(), d)?;
    let (pb, cb, sb) = prealign::normalize(b.coords(), d)?;
    let t = match opts.prealign {
        Prealign::Normalize => Affine::identity(d),
        Prealign::Robust => prealign::robust_prealign(&pa, &pb, d, &opts.rotation_search, ordered),
        Prealign::Sensor => prepare::normalizing_map(d, cb, sb).compose(&inverse_normalizing_map(
            &prepare::normalizing_map(d, ca, sa),
        )),
    };
    let renormalize = opts.prealign.renormalizes(ordered);
    Ok((prealign::into_b_frame(t.apply(&pa), d, renormalize)?.0, pb))
}
