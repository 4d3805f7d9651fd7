//! The last step of the robust pre-alignment of two closed outlines (docs/method.md §7.1): an
//! affine ICP that fits A's outline to B's outline rather than A's nodes to B's nodes.
//!
//! Node-to-node ICP pulls every node of A towards a node of B. Two samplings of one curve never
//! put their nodes at the same places, so the fit it converges to can lie up to about a node
//! spacing along the curve from the true map: on a bent outline the map that snaps the nodes
//! best is slid, and the modal matching then pairs every node with its neighbour (a held-out
//! moderate pair scored 0.65). Here each node is paired with the closest point of the other
//! outline's segments and only its distance across the segment counts (point-to-line ICP), so
//! the fit is that of the curves, with no pull along them.

use super::prealign::{nearest_both, Affine};

/// Weight of the plain point-to-point distance beside the distance across the segment: small
/// enough not to bring the pull along the curve back, large enough to keep the 6 × 6 system
/// regular when the segments' normals span few directions (a nearly straight stretch).
const ALONG_WEIGHT: f64 = 0.01;

/// A step smaller than this (every entry of `M − I` and of `t`, in B's normalised frame, where
/// the RMS radius is 1 and nodes lie about 0.1 apart) ends the iterations. The steps shrink about
/// tenfold each: 3–5 steps on the ground-truth pairs, against 6–9 for 10⁻⁷, with the same
/// matches.
const CONVERGED: f64 = 1e-5;

/// Point-to-line affine ICP of the closed outline `a` (planar, `x y` interleaved) onto the
/// closed outline `b`, from `start`, at most `iterations` steps; both ways (A's nodes onto B's
/// segments and B's nodes onto A's), like the node ICP it follows. Returns `start` unchanged
/// when a step cannot be fitted, and never a map that reflects.
pub(crate) fn fit_outlines(a: &[f64], b: &[f64], start: Affine, iterations: usize) -> Affine {
    let mut cur = start;
    for _ in 0..iterations {
        let moved = cur.apply(a);
        let Some(step) = outline_step(&moved, b) else {
            break;
        };
        let next = step.compose(&cur);
        // A reflection, or a collapse (also when the determinant is NaN).
        if next.det().partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            break;
        }
        cur = next;
        if step.is_within_of_identity(CONVERGED) {
            break;
        }
    }
    cur
}

/// One step: the affine map that best moves the outline `moved` onto `b`, each node of either
/// outline paired with the closest point of the other's segments.
fn outline_step(moved: &[f64], b: &[f64]) -> Option<Affine> {
    let (ab, ba) = nearest_both(moved, b, 2);
    let mut fit = LineFit::default();
    for (p, q, normal) in closest_points(moved, b, &ab) {
        fit.add(p, q, normal);
    }
    for (q, p, normal) in closest_points(b, moved, &ba) {
        fit.add(p, q, normal);
    }
    fit.solve()
}

/// How far apart two closed planar outlines lie: the mean squared distance from each node of
/// either outline to the closest point of the other's segments (a chamfer distance to the
/// curves, not to their nodes).
pub(crate) fn outline_distance(moved: &[f64], b: &[f64]) -> f64 {
    let (ab, ba) = nearest_both(moved, b, 2);
    let squared =
        |(p, q, _): ([f64; 2], [f64; 2], [f64; 2])| (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2);
    let to_b: f64 = closest_points(moved, b, &ab).map(squared).sum();
    let to_a: f64 = closest_points(b, moved, &ba).map(squared).sum();
    (to_b + to_a) / (ab.len() + ba.len()) as f64
}

/// Each node of the outline `from` with the closest point of the outline `to` (on the two
/// segments at its nearest node of `to`, `nearest` from [`nearest_both`]) and that segment's
/// unit normal: the pairs of both the fit and the distance.
fn closest_points<'a>(
    from: &'a [f64],
    to: &'a [f64],
    nearest: &'a [(usize, f64)],
) -> impl Iterator<Item = ([f64; 2], [f64; 2], [f64; 2])> + 'a {
    nearest.iter().enumerate().map(move |(i, &(k, _))| {
        let p = point(from, i);
        let (q, normal) = closest_on_outline(to, k, p);
        (p, q, normal)
    })
}

fn point(c: &[f64], i: usize) -> [f64; 2] {
    [c[2 * i], c[2 * i + 1]]
}

/// The closest point to `p` on the two segments of the closed outline `c` that meet at its node
/// `k` (the node nearest `p`), and that segment's unit normal (`[0, 0]` for a segment of zero
/// length).
fn closest_on_outline(c: &[f64], k: usize, p: [f64; 2]) -> ([f64; 2], [f64; 2]) {
    let n = c.len() / 2;
    let mut best = (point(c, k), [0.0, 0.0], f64::INFINITY);
    for s in [(k + n - 1) % n, k] {
        let (x0, x1) = (point(c, s), point(c, (s + 1) % n));
        let d = [x1[0] - x0[0], x1[1] - x0[1]];
        let len2 = d[0] * d[0] + d[1] * d[1];
        // A segment of zero length (or NaN) has no normal.
        if len2.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            continue;
        }
        let t = (((p[0] - x0[0]) * d[0] + (p[1] - x0[1]) * d[1]) / len2).clamp(0.0, 1.0);
        let q = [x0[0] + t * d[0], x0[1] + t * d[1]];
        let dist = (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2);
        if dist < best.2 {
            let len = len2.sqrt();
            best = (q, [-d[1] / len, d[0] / len], dist);
        }
    }
    (best.0, best.1)
}

/// The normal equations of `min Σ (n·(T p − q))² + w |T p − q|²` over an affine `T p = M p + t`,
/// unknowns `(M₀₀, M₀₁, t₀, M₁₀, M₁₁, t₁)`. With `h = (pₓ, p_y, 1)` a pair's rows give
/// `AᵀA += (n nᵀ + w I) ⊗ h hᵀ` and `Aᵀb += (n (n·q) + w q) ⊗ h`, so only `h hᵀ` (six entries) is
/// accumulated, in three 2 × 2 weights: a few flops per pair instead of three 6 × 6 updates.
#[derive(Default)]
struct LineFit {
    /// `Σ c · h hᵀ` (upper triangle: xx, xy, x, yy, y, 1) for the weights `c` of `(0,0)`,
    /// `(0,1)` and `(1,1)` of `n nᵀ + w I`.
    hh: [[f64; 6]; 3],
    /// `Σ (n (n·q) + w q)ₐ · h` for `a` = 0, 1.
    hq: [[f64; 3]; 2],
}

impl LineFit {
    /// Pair `p` (to be moved) with `q` on a segment of unit normal `n` (`[0, 0]`: no segment).
    fn add(&mut self, p: [f64; 2], q: [f64; 2], n: [f64; 2]) {
        let [x, y] = p;
        let h = [x, y, 1.0];
        let hh = [x * x, x * y, x, y * y, y, 1.0];
        let w = ALONG_WEIGHT;
        let c = [n[0] * n[0] + w, n[0] * n[1], n[1] * n[1] + w];
        for (acc, ck) in self.hh.iter_mut().zip(c) {
            for (a, v) in acc.iter_mut().zip(hh) {
                *a += ck * v;
            }
        }
        let nq = n[0] * q[0] + n[1] * q[1];
        for a in 0..2 {
            let g = n[a] * nq + w * q[a];
            for (acc, hk) in self.hq[a].iter_mut().zip(h) {
                *acc += g * hk;
            }
        }
    }

    fn solve(self) -> Option<Affine> {
        // The 3 × 3 symmetric block of h hᵀ sums for each weight, expanded.
        let block = |s: &[f64; 6]| {
            nalgebra::Matrix3::new(s[0], s[1], s[2], s[1], s[3], s[4], s[2], s[4], s[5])
        };
        let (b00, b01, b11) = (block(&self.hh[0]), block(&self.hh[1]), block(&self.hh[2]));
        let mut ata = nalgebra::SMatrix::<f64, 6, 6>::zeros();
        ata.fixed_view_mut::<3, 3>(0, 0).copy_from(&b00);
        ata.fixed_view_mut::<3, 3>(0, 3).copy_from(&b01);
        ata.fixed_view_mut::<3, 3>(3, 0).copy_from(&b01);
        ata.fixed_view_mut::<3, 3>(3, 3).copy_from(&b11);
        let [g0, g1] = self.hq;
        let atb = nalgebra::SVector::<f64, 6>::from([g0[0], g0[1], g0[2], g1[0], g1[1], g1[2]]);
        let w = ata.cholesky()?.solve(&atb);
        if !w.iter().all(|v| v.is_finite()) {
            return None;
        }
        let mut aff = Affine::identity(2);
        aff.m[0] = [w[0], w[1], 0.0];
        aff.m[1] = [w[3], w[4], 0.0];
        aff.t[0] = w[2];
        aff.t[1] = w[5];
        Some(aff)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::matching::prealign::icp_affine;

    /// A lobed closed curve at parameter `u` (one turn per unit).
    fn curve(u: f64) -> [f64; 2] {
        let t = u * std::f64::consts::TAU;
        let r = 1.0 + 0.25 * (3.0 * t).cos() + 0.1 * (2.0 * t).sin();
        [1.4 * r * t.cos(), r * t.sin()]
    }

    fn sampled(n: usize, phase: f64, map: &Affine) -> Vec<f64> {
        let pts: Vec<f64> = (0..n)
            .flat_map(|i| curve((i as f64 + phase) / n as f64))
            .collect();
        map.apply(&pts)
    }

    fn map_error(x: &Affine, y: &Affine) -> f64 {
        (0..2)
            .flat_map(|r| (0..2).map(move |c| (r, c)))
            .map(|(r, c)| (x.m[r][c] - y.m[r][c]).abs())
            .chain((0..2).map(|r| (x.t[r] - y.t[r]).abs()))
            .fold(0.0, f64::max)
    }

    fn turned(deg: f64, scale: [f64; 2], t: [f64; 2]) -> Affine {
        let (s, c) = deg.to_radians().sin_cos();
        let mut aff = Affine::identity(2);
        aff.m[0] = [c * scale[0], -s * scale[1], 0.0];
        aff.m[1] = [s * scale[0], c * scale[1], 0.0];
        aff.t = [t[0], t[1], 0.0];
        aff
    }

    #[test]
    fn two_samplings_of_one_outline_are_fitted_where_node_icp_stops_short() {
        // B is the curve under a known map, sampled at other places and a different density.
        let truth = turned(12.0, [1.1, 0.9], [0.05, -0.02]);
        let a = sampled(60, 0.0, &Affine::identity(2));
        let b = sampled(57, 0.43, &truth);
        let start = turned(15.0, [1.05, 0.95], [0.0, 0.0]);
        let (node_fit, _) = icp_affine(&a, &b, 2, start, 200, true);
        let outline_fit = fit_outlines(&a, &b, node_fit, 20);
        let (node_err, outline_err) = (
            map_error(&node_fit, &truth),
            map_error(&outline_fit, &truth),
        );
        // What is left is the chords' own error against the curve.
        assert!(outline_err < 1e-3, "outline fit off by {outline_err}");
        assert!(
            outline_err < 0.25 * node_err,
            "{outline_err} vs node ICP {node_err}"
        );
    }

    #[test]
    fn outline_distance_measures_the_curves_not_their_nodes() {
        let a = sampled(60, 0.0, &Affine::identity(2));
        assert_eq!(outline_distance(&a, &a), 0.0);
        // The same curve sampled half a node spacing further on: its nodes lie between A's, but
        // on (the chords of) the same curve.
        let b = sampled(60, 0.5, &Affine::identity(2));
        let nodes = crate::matching::prealign::chamfer(&a, &b, 2);
        let curves = outline_distance(&a, &b);
        assert!(curves < 0.01 * nodes, "outlines {curves} vs nodes {nodes}");
        // Moved off the curve, both grow.
        let off = turned(0.0, [1.0, 1.0], [0.05, 0.0]).apply(&a);
        assert!(outline_distance(&off, &b) > 10.0 * curves);
    }

    #[test]
    fn the_exact_map_is_a_fixed_point() {
        let truth = turned(-30.0, [0.8, 1.2], [0.3, 0.1]);
        let a = sampled(48, 0.0, &Affine::identity(2));
        let b = truth.apply(&a);
        let fit = fit_outlines(&a, &b, truth, 10);
        assert!(map_error(&fit, &truth) < 1e-12);
    }

    #[test]
    fn degenerate_outlines_leave_the_start_unchanged() {
        // Every node of A at one place: no segment has a length, no step can be fitted.
        let a = vec![0.5; 20];
        let b = sampled(12, 0.0, &Affine::identity(2));
        let start = turned(5.0, [1.0, 1.0], [0.1, 0.0]);
        assert_eq!(fit_outlines(&a, &b, start, 10), start);
    }
}
