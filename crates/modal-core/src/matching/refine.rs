//! Stage 6, refine: the modal affine re-fits (docs/method.md §7.2). Each pass matches A at its
//! current coordinates (features → search → excess), fits one affine map to its pairs and, unless
//! that map already explains them, moves A by it and solves A's modes again. The pass whose pairs
//! one affine map explains best is kept.

// Small fixed-size matrix code reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

use std::sync::Arc;

use super::excess::excess_pairs;
use super::features::{cost_matrix, AffinityMatrix, ModalFeatures, PositionTermAhead};
use super::prealign::{fit_affine, into_b_frame, Affine};
use super::prepare::Pair;
use super::result::MatchPair;
use super::search::primary_matches;
use crate::error::ModalError;

/// What follows the affine re-fits (docs/method.md §7.4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Refine {
    /// Nothing: the kept affine pass is the result (the default).
    #[default]
    Affine,
    /// A's aligned nodes warped onto B by A's low-order modes, amplitudes fitted with the modes'
    /// strain energy as regulariser, then matched once more.
    Modal,
    /// A's aligned nodes drifted onto B by a smooth Gaussian-kernel displacement field fitted to
    /// soft correspondences (coherent point drift), then assigned to B's nodes on the moved
    /// positions (the ordered solver for two closed contours).
    Coherent,
    /// Two closed planar outlines pre-aligned by the rotation search: [`Refine::Coherent`] from
    /// the centroid-and-scale start (with affine re-fits on positions) when the outline fit
    /// leaves the outlines apart, or the modal match that follows pairs nodes whose modes
    /// disagree (two specimens of a shape); nothing more ([`Refine::Affine`]) when neither
    /// (one outline deformed). [`Refine::Affine`] for any other input or pre-alignment
    /// (docs/method.md §7.5).
    Auto,
}

/// Where the passes start: A after the pre-alignment, with the modes solved for it.
pub(crate) struct Start {
    /// A's coordinates in B's normalised frame.
    pub cur: Vec<f64>,
    /// The map from A's normalised frame to `cur`.
    pub to_cur: Affine,
    /// B's modes (`None` when the cost is positions only).
    pub modes_b: Option<Arc<ModalFeatures>>,
    /// A's modes at `cur`.
    pub modes_a: Option<Arc<ModalFeatures>>,
    /// The position term of the first pass's cost at `cur`, which another thread may compute.
    pub positions: Option<Arc<PositionTermAhead>>,
}

/// One pass of the search loop, kept when it explains its pairs best.
pub(crate) struct Iteration {
    pub z: AffinityMatrix,
    /// Pairs in the prepared (oriented) numbering.
    pub pairs: Vec<MatchPair>,
    /// Mean squared residual of the pairs under the affine map fitted to them.
    pub resid: f64,
    /// A's coordinates the pass matched, in B's normalised frame.
    pub aligned: Vec<f64>,
    /// The map from A's normalised frame to `aligned`.
    pub to_aligned: Affine,
}

/// What the passes return: the kept pass, and how many re-fits and A-solves were run.
pub(crate) struct Refined {
    pub kept: Iteration,
    pub refits: usize,
    pub solves: usize,
    /// Whether the coherent drift moved A's nodes (its field was fitted).
    pub drifted: bool,
}

/// Runs the passes from `start` until the pairs stop changing, one affine map explains them, or
/// `refits` re-fits were made.
pub(crate) fn refine(pair: &Pair<'_>, start: Start) -> Result<Refined, ModalError> {
    let opts = pair.opts;
    let Start {
        mut cur,
        mut to_cur,
        modes_b,
        modes_a,
        positions,
    } = start;
    let mut first_modes = modes_a;
    let mut first_positions = positions;
    let mut prev: Option<Vec<MatchPair>> = None;
    let (mut refits, mut solves) = (0, 0);
    let mut best: Option<Iteration> = None;
    loop {
        let fa = match (&modes_b, first_modes.take()) {
            (None, _) => None,
            (Some(_), Some(fa)) => Some(fa),
            (Some(_), None) => Some(pair.modes_a(&cur)?),
        };
        if fa.is_some() {
            solves += 1;
        }
        let Pass {
            z,
            pairs,
            resid,
            worst,
            fit,
        } = pass(
            pair,
            &cur,
            fa.as_deref().zip(modes_b.as_deref()),
            first_positions.take().as_deref(),
        )?;
        let stable = prev.as_ref().is_some_and(|p| same_pairs(p, &pairs));
        let better = !opts.keep_best_fit || best.as_ref().is_none_or(|b| resid < b.resid);
        if better {
            best = Some(Iteration {
                z,
                pairs: pairs.clone(),
                resid,
                aligned: cur.clone(),
                to_aligned: to_cur,
            });
        }
        let explained = worst.sqrt() < opts.refit_tolerance * pair.spacing_b;
        if stable || explained || refits >= opts.refits {
            break;
        }
        let Some(t) = fit else { break };
        if !moves(&t) || (pair.ordered && t.det() <= 0.0) {
            break;
        }
        let renormalizes = pair.opts.prealign.renormalizes(pair.ordered);
        let Ok((next, renormalize)) = into_b_frame(t.apply(&cur), pair.dim, renormalizes) else {
            break;
        };
        cur = next;
        to_cur = renormalize.compose(&t).compose(&to_cur);
        prev = Some(pairs);
        refits += 1;
    }
    let kept = best.expect("at least one iteration ran");
    let (kept, drifted) = match opts.refine {
        Refine::Affine | Refine::Auto => (kept, false),
        Refine::Modal => (super::deform::deform(pair, kept)?, false),
        Refine::Coherent => super::coherent::coherent(pair, kept)?,
    };
    Ok(Refined {
        kept,
        refits,
        solves,
        drifted,
    })
}

/// One pass at A's coordinates `aligned`: its cost matrix, its pairs, and how well one affine
/// map explains them (see [`explained`]).
pub(super) struct Pass {
    pub z: AffinityMatrix,
    pub pairs: Vec<MatchPair>,
    pub resid: f64,
    pub worst: f64,
    pub fit: Option<Affine>,
}

/// Matches A at `aligned` (features → search → excess) with the modes of A there and of B
/// (`None`: positions only), and the cost's position term at `aligned` if it is computed ahead.
pub(super) fn pass(
    pair: &Pair<'_>,
    aligned: &[f64],
    modes: Option<(&ModalFeatures, &ModalFeatures)>,
    positions: Option<&PositionTermAhead>,
) -> Result<Pass, ModalError> {
    let z = cost_matrix(
        aligned,
        &pair.b.get().pts,
        pair.dim,
        modes,
        pair.k,
        pair.opts,
        positions,
    )?;
    let pairs = pass_pairs(pair, &z, aligned)?;
    let (resid, worst, fit) = explained(pair, aligned, &pairs);
    Ok(Pass {
        z,
        pairs,
        resid,
        worst,
        fit,
    })
}

/// One pass's pairs on `z`: the search's, then the excess step's.
fn pass_pairs(
    pair: &Pair<'_>,
    z: &AffinityMatrix,
    cur: &[f64],
) -> Result<Vec<MatchPair>, ModalError> {
    pass_pairs_with(pair, z, cur, pair.opts.method, pair.excess())
}

/// [`pass_pairs`] with the global search's solver `method`; `gaps`: the order-preserving search
/// may leave nodes out for the excess step (`search::ORDERED_GAP`).
pub(super) fn pass_pairs_with(
    pair: &Pair<'_>,
    z: &AffinityMatrix,
    cur: &[f64],
    method: assign::Method,
    gaps: bool,
) -> Result<Vec<MatchPair>, ModalError> {
    let opts = pair.opts;
    let mode = opts.threshold_mode;
    let one = primary_matches(z, opts.search, method, pair.threshold, mode, gaps)?;
    let as_pair = |excess: bool| {
        move |(i, j): (usize, usize)| MatchPair {
            a: i,
            b: j,
            cost: z.get(i, j),
            excess,
        }
    };
    let mut pairs: Vec<MatchPair> = one.iter().copied().map(as_pair(false)).collect();
    if pair.excess() {
        pairs.extend(
            excess_pairs(
                z,
                &one,
                pair.threshold,
                pair.ordered,
                gaps && method == assign::Method::Ordered,
                (pair.dim, cur, &pair.b.get().pts),
                || (pair.a.get().neighbours(), pair.b.get().neighbours()),
            )
            .into_iter()
            .map(as_pair(true)),
        );
    }
    Ok(pairs)
}

/// How well one affine map explains the pairs, measured in B's fixed frame, so the passes are
/// comparable: wrong pairs do not fit a smooth map. The mean squared residual of all pairs ranks
/// the passes; the largest of the one-to-one pairs decides whether another re-fit is worth a
/// solve. Excess pairs are left out of that: they are many-to-one by construction, so their
/// offsets along the contour measure the sampling, not the fit. Returns both and the map.
pub(super) fn explained(
    pair: &Pair<'_>,
    cur: &[f64],
    pairs: &[MatchPair],
) -> (f64, f64, Option<Affine>) {
    let (d, b) = (pair.dim, &pair.b.get().pts);
    let idx: Vec<(usize, usize)> = pairs.iter().map(|p| (p.a, p.b)).collect();
    let fit = fit_affine(cur, b, d, &idx);
    let (resid, worst) = fit.as_ref().map_or((f64::INFINITY, f64::INFINITY), |t| {
        let moved = t.apply(cur);
        let (sum, max) = pairs.iter().fold((0.0, 0.0f64), |(sum, max), p| {
            let r2 = (0..d)
                .map(|c| (moved[p.a * d + c] - b[p.b * d + c]).powi(2))
                .sum::<f64>();
            (sum + r2, if p.excess { max } else { max.max(r2) })
        });
        (sum / pairs.len().max(1) as f64, max)
    });
    (resid, worst, fit)
}

/// Whether a map moves A at all: one this close to the identity cannot change the pairs, so the
/// solve it would cost is skipped. A map with a NaN entry does not count as moving (every
/// comparison with NaN is false), so it ends the re-fits and the best pass so far is kept.
fn moves(t: &Affine) -> bool {
    (0..t.dim).any(|r| {
        t.t[r].abs() > 1e-4
            || (0..t.dim).any(|c| (t.m[r][c] - if r == c { 1.0 } else { 0.0 }).abs() > 1e-4)
    })
}

fn same_pairs(x: &[MatchPair], y: &[MatchPair]) -> bool {
    x.len() == y.len() && x.iter().zip(y).all(|(p, q)| p.a == q.a && p.b == q.b)
}
