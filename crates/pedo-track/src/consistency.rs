//! How far a pair's matches can be trusted, measured on the matches themselves
//! (docs/method.md §13).
//!
//! A one-to-one assignment pairs every node of the smaller object, so the share of nodes matched
//! ("optimisation matches") is near 100 % on every pair, good or bad. Two figures that are not:
//! a smooth map of the plane is fitted to the pair's matches (a thin-plate smoothing spline,
//! [`CorrespondenceField`]) forwards, A onto B, and backwards, B onto A, to the same matches.
//! - The **field residual**: how far the forward field leaves a matched node from its partner.
//!   Matches a smooth deformation explains leave a small residual; a match that jumps across
//!   the outline, or two that cross, cannot be honoured by a smooth map and leave a large one.
//! - The **round trip**: how far each node of A lands from where it started after the forward
//!   and then the backward field. Where the matches agree with one smooth, invertible map the
//!   two fits undo each other; where they fold or tear the outline, each fit smooths them its
//!   own way and the point does not come back.
//!
//! Both are in sensels (the x pitch; oblong sensels are measured in their true proportions).

use crate::SenselAspect;
use modal_core::{CorrespondenceField, MatchPair, Shape};

/// The smoothing (λ, sensel²) of the fields: that of the fields the material points cross a
/// split or a merge by (`follow`), whose targets are also a pair's raw matches.
pub(crate) const FIELD_SMOOTHING: f64 = 300.0;

/// The most matches a field is fitted to (evenly spaced along the matches): the figures are a
/// median and a percentile, which 64 well-spread matches give as well as 200 at a fraction of
/// the cost (a fit is cubic in its matches).
const MOST_MATCHES: usize = 64;

/// The consistency figures of one pair (sensels).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairConsistency {
    /// Median distance from a matched node's image under the forward field to its partner.
    pub field_residual: f64,
    /// Median distance from a node of the first object to its image after the forward and the
    /// backward field.
    pub round_trip: f64,
    /// The 95th percentile of those distances.
    pub round_trip_p95: f64,
}

impl PairConsistency {
    /// The figures of the one-to-one `pairs` of objects `a` and `b` (sensor coordinates,
    /// sensels), or `None` when no field can be fitted to them: surfaces (3-D points), fewer
    /// than three one-to-one matches, or matched nodes on a line.
    pub fn of(a: &Shape, b: &Shape, pairs: &[MatchPair], aspect: SenselAspect) -> Option<Self> {
        Self::with_steps(a, b, pairs, aspect).map(|(c, _)| c)
    }

    /// [`PairConsistency::of`], with each match's **step round trip** (sensels, one per match
    /// of `pairs`, in order; NaN for an excess match): how far the backward field carries the
    /// match's node of `b` from its node of `a`. A node track that takes the match steps from
    /// `a`'s node to `b`'s; the backward field, fitted to all the pair's matches, brings it back
    /// to where the matches as a whole say it came from. A match that agrees with its
    /// neighbours comes back to its start; one that jumps, crosses or swaps with a neighbour
    /// does not. A track's figure is the largest of its steps' ([`crate::chain_tracks_checked`],
    /// `tracks.csv`'s `round_trip_sensels`).
    pub fn with_steps(
        a: &Shape,
        b: &Shape,
        pairs: &[MatchPair],
        aspect: SenselAspect,
    ) -> Option<(Self, Vec<f32>)> {
        if a.dim() != 2 || b.dim() != 2 {
            return None;
        }
        let (a, b) = (aspect.shape(a).ok()?, aspect.shape(b).ok()?);
        let forward = CorrespondenceField::fit(&a, &b, &used(pairs), FIELD_SMOOTHING).ok()?;
        let backward = forward.inverse().ok()?;
        let xy = |s: &Shape, i: usize| [s.point(i)[0], s.point(i)[1]];
        let nodes: Vec<[f64; 2]> = (0..a.len()).map(|i| xy(&a, i)).collect();
        let back = backward.apply(&forward.apply(&nodes));
        let dist = |x: &[f64; 2], y: &[f64; 2]| (x[0] - y[0]).hypot(x[1] - y[1]);
        let mut trip: Vec<f64> = nodes.iter().zip(&back).map(|(x, y)| dist(x, y)).collect();
        let mut residuals = forward.residuals();
        if !trip.iter().chain(&residuals).all(|d| d.is_finite()) {
            return None;
        }
        // Every match's node of `b` taken back by the backward field, beside its node of `a`.
        let in_range = |p: &&MatchPair| !p.excess && p.a < a.len() && p.b < b.len();
        let ends: Vec<[f64; 2]> = pairs.iter().filter(in_range).map(|p| xy(&b, p.b)).collect();
        let mut home = backward.apply(&ends).into_iter();
        let steps = pairs
            .iter()
            .map(|p| match in_range(&p).then(|| home.next()).flatten() {
                Some(h) => dist(&h, &xy(&a, p.a)) as f32,
                None => f32::NAN,
            })
            .collect();
        let figures = Self {
            field_residual: quantile(&mut residuals, 0.5),
            round_trip: quantile(&mut trip, 0.5),
            round_trip_p95: quantile(&mut trip, 0.95),
        };
        Some((figures, steps))
    }
}

/// The one-to-one matches of `pairs` a pair's fields are fitted to: at most [`MOST_MATCHES`],
/// evenly spaced along them.
fn used(pairs: &[MatchPair]) -> Vec<MatchPair> {
    let one_to_one: Vec<MatchPair> = pairs.iter().filter(|p| !p.excess).cloned().collect();
    let step = one_to_one.len().div_ceil(MOST_MATCHES).max(1);
    one_to_one.into_iter().step_by(step).collect()
}

/// The backward field of a pair of objects `a → b` and its `pairs` (the field
/// [`PairConsistency::with_steps`] takes the matches' nodes of `b` back by), in sensels of
/// sensor coordinates: what a **point round trip** is measured with ([`StepField::round_trip`]).
pub(crate) struct StepField {
    backward: CorrespondenceField,
    aspect: f64,
}

impl StepField {
    /// The backward field of the pair, or `None` when none can be fitted (as
    /// [`PairConsistency::of`]).
    pub(crate) fn of(
        a: &Shape,
        b: &Shape,
        pairs: &[MatchPair],
        aspect: SenselAspect,
    ) -> Option<Self> {
        if a.dim() != 2 || b.dim() != 2 {
            return None;
        }
        let (a, b) = (aspect.shape(a).ok()?, aspect.shape(b).ok()?);
        let turned: Vec<MatchPair> = (used(pairs).into_iter())
            .map(|p| MatchPair {
                a: p.b,
                b: p.a,
                ..p
            })
            .collect();
        let backward = CorrespondenceField::fit(&b, &a, &turned, FIELD_SMOOTHING).ok()?;
        Some(Self {
            backward,
            aspect: aspect.0,
        })
    }

    /// How far (sensels, the x pitch) the backward field carries a point at `on_b` on object
    /// `b` from `on_a`, where it was on object `a`: a point that moved from `on_a` to `on_b`
    /// as the pair's matches as a whole say comes back to its start; one whose step disagrees
    /// with them does not. NaN when the field gives no finite image.
    pub(crate) fn round_trip(&self, on_a: [f64; 2], on_b: [f64; 2]) -> f32 {
        let k = self.aspect;
        let [home] = self.backward.apply(&[[on_b[0], on_b[1] * k]])[..] else {
            return f32::NAN;
        };
        (home[0] - on_a[0]).hypot(home[1] - on_a[1] * k) as f32
    }
}

/// Round trips summarised (sensels): the points' of a run
/// ([`crate::follow::FollowedPoint::round_trips`]), as `summary.json`'s
/// `point_round_trip_sensels` gives them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RoundTrips {
    /// How many round trips (a point's steps with one).
    pub count: usize,
    /// Their median.
    pub median: f64,
    /// The 95th percentile.
    pub p95: f64,
    /// The largest.
    pub max: f64,
    /// The share of them, in %, over one sensel.
    pub over_1_percent: f64,
}

impl RoundTrips {
    /// The summary of the finite `trips` (`None` when there are none).
    pub fn of(trips: impl IntoIterator<Item = f32>) -> Option<Self> {
        let mut v: Vec<f64> = (trips.into_iter())
            .filter(|d| d.is_finite())
            .map(f64::from)
            .collect();
        if v.is_empty() {
            return None;
        }
        let over_1 = v.iter().filter(|&&d| d > 1.0).count();
        Some(Self {
            count: v.len(),
            median: quantile(&mut v, 0.5),
            p95: quantile(&mut v, 0.95),
            max: quantile(&mut v, 1.0),
            over_1_percent: 100.0 * over_1 as f64 / v.len() as f64,
        })
    }
}

/// The `q` quantile of non-empty, finite `v` (linear between order statistics, numpy's
/// default).
pub(crate) fn quantile(v: &mut [f64], q: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    let h = q * (v.len() - 1) as f64;
    let (lo, hi) = (h.floor() as usize, h.ceil() as usize);
    v[lo] + (h - lo as f64) * (v[hi] - v[lo])
}

#[cfg(test)]
mod tests {
    use super::*;
    use modal_core::Topology;

    fn outline(n: usize, warp: impl Fn([f64; 2]) -> [f64; 2]) -> Shape {
        let p: Vec<[f64; 2]> = (0..n)
            .map(|i| {
                let t = i as f64 / n as f64 * std::f64::consts::TAU;
                warp([20.0 * t.cos(), 8.0 * t.sin() + 2.0 * (2.0 * t).cos()])
            })
            .collect();
        Shape::from_points_2d(&p, Topology::ClosedContour).unwrap()
    }

    fn pairs(map: impl Fn(usize) -> usize, n: usize) -> Vec<MatchPair> {
        (0..n)
            .map(|i| MatchPair {
                a: i,
                b: map(i),
                cost: 0.0,
                excess: false,
            })
            .collect()
    }

    #[test]
    fn matches_of_a_smooth_motion_come_back_and_crossed_ones_do_not() {
        let n = 120;
        let a = outline(n, |p| p);
        // Turned by 5°, stretched 4 %, shifted: what one frame to the next does.
        let (c, s) = (5f64.to_radians().cos(), 5f64.to_radians().sin());
        let b = outline(n, |[x, y]| {
            [1.04 * (c * x - s * y) + 1.5, s * x + c * y - 0.7]
        });
        let good = PairConsistency::of(&a, &b, &pairs(|i| i, n), SenselAspect::SQUARE).unwrap();
        assert!(good.field_residual < 0.01, "{good:?}");
        assert!(good.round_trip_p95 < 0.01, "{good:?}");
        // A third of the matches sent to the opposite side of the outline: torn matches.
        let torn = |i: usize| {
            if i.is_multiple_of(3) {
                (i + n / 2) % n
            } else {
                i
            }
        };
        let bad = PairConsistency::of(&a, &b, &pairs(torn, n), SenselAspect::SQUARE).unwrap();
        assert!(bad.field_residual > 1.0, "{bad:?}");
        assert!(
            bad.round_trip > 100.0 * good.round_trip.max(1e-6),
            "{bad:?} vs {good:?}"
        );
    }

    #[test]
    fn no_figures_without_a_field() {
        let a = outline(20, |p| p);
        let few = pairs(|i| i, 2);
        assert_eq!(
            PairConsistency::of(&a, &a, &few, SenselAspect::SQUARE),
            None
        );
    }

    #[test]
    fn quantiles_are_numpys() {
        let mut v = vec![4.0, 1.0, 3.0, 2.0];
        assert_eq!(quantile(&mut v, 0.5), 2.5);
        assert!((quantile(&mut v, 0.95) - 3.85).abs() < 1e-12);
    }
}
