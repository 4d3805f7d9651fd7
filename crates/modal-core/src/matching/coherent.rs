//! Stage 7 (optional), coherent: the coherent-drift refinement of docs/method.md §7.5, after the
//! affine re-fits. A's aligned nodes are moved onto B by a smooth displacement field, the
//! non-rigid registration of coherent point drift (Myronenko & Song, *Point set registration:
//! coherent point drift*, IEEE TPAMI 32(12), 2010): an expectation-maximisation loop of
//! Gaussian-mixture responsibilities and a displacement field `u = G W` over a Gaussian kernel `G`
//! on A's nodes, regularised by `λ/2 tr(Wᵀ G W)`. The field is restricted to the kernel's leading
//! eigenvectors (CPD's low-rank variant), so one step solves a small system. Then A's nodes are
//! assigned to B's on the squared distances of the moved nodes: for closed contours by the ordered
//! (cyclic order-preserving) solver, otherwise by the search's own solver, followed by the excess
//! step.
//!
//! Where the modal match leaves two specimens whose proportions differ slid along each other
//! (the modes agree on the overall shape, not on where a bump sits), the drift pulls each part of
//! A onto the part of B it overlies, and the order constraint keeps the pairs from crossing.
//!
//! The refinement never makes a pair fail: when the field cannot be fitted (an empty or
//! singular system, nothing matched, a non-finite value) the affine pass is kept unchanged.

// Small dense linear algebra reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

use faer::Mat;

use super::deform::{initial_variance, solve_spd};
use super::features::position_costs;
use super::outline_fit::outline_distance;
use super::prepare::Pair;
use super::refine::{explained, pass_pairs_with, Iteration};
use super::result::MatchPair;
use super::MatchOptions;
use crate::error::ModalError;

/// Width `β` of the kernel in B's normalised frame (RMS radius 1): CPD's default, a field smooth
/// over about a third of the outline.
const KERNEL_WIDTH: f64 = 2.0;
/// Weight `λ` of the field's smoothness against the fit: CPD's default. On the tuning half of
/// the landmark benchmark (bench_landmarks.py), with the ordered assignment after the drift, 0.5
/// gave the same shares within 1, 2 and 5 spacings to ±0.002 and a larger median error.
const SMOOTHNESS: f64 = 2.0;
/// Leading eigenvectors of the kernel that span the field (all of them for smaller objects). On
/// the landmark benchmark's tuning half (a Python prototype) 30 gave the shares of the full kernel,
/// and 15 the same as 30 (0.445 / 0.701 / 0.929 within 1 / 2 / 5 spacings, with the tolerance
/// below); each step's system is then a quarter of the size.
const RANK: usize = 15;
/// Most expectation-maximisation steps.
const MAX_STEPS: usize = 100;
/// The loop stops once the mixture's variance changes by less than this fraction. CPD's 10⁻³
/// took 50 steps a pair on the landmark benchmark's tuning half (a Python prototype after
/// `prealign = normalize`); 10⁻² takes 29 and carried the landmarks as well (0.445 / 0.701 / 0.929
/// against 0.439 / 0.701 / 0.925 within 1 / 2 / 5 spacings).
const VARIANCE_TOLERANCE: f64 = 1e-2;

/// The gate of [`Refine::Auto`](super::Refine::Auto): two outlines whose root-mean-square
/// distance after the rotation search's outline fit (each node of either outline to the other
/// outline, both ways) exceeds this many of B's node spacings are taken for two specimens of a
/// shape, and drifted. Measured on the tuning halves (BENCHMARKS.md, "Landmarks on real outlines
/// annotated by others"): 0.19–3.2 spacings on the landmark benchmark's real specimens (5th
/// percentile 0.37), at most 0.085 / 0.24 / 0.50 on bench_match.py's synthetic warps of one
/// outline (mild / moderate / severe, 630 pairs; 95th percentile at severe 0.32).
pub(crate) const APART: f64 = 0.6;

/// Whether A's nodes `cur` (after the outline fit, in B's normalised frame) and B's outline `b`
/// lie more than [`APART`] of B's node spacings `spacing` apart.
pub(crate) fn outlines_apart(cur: &[f64], b: &[f64], spacing: f64) -> bool {
    outline_distance(cur, b).sqrt() > APART * spacing
}

/// The second gate of [`Refine::Auto`](super::Refine::Auto), read after the modal match of two
/// outlines that the first ([`APART`]) left to it: a median cost of the pairs above this (the
/// max-normalised modal distance) says the modes of the two outlines disagree as those of two
/// specimens do, and the pair is drifted after all. Measured on the tuning halves
/// (BENCHMARKS.md, "The second gate: the modes after the modal match"): at most 0.049 / 0.069 /
/// 0.140 on bench_match.py's synthetic warps of one outline (mild / moderate / severe, 810 pairs,
/// 99th percentile at severe 0.128); 0.118–0.329 on the 32 landmark pairs under the first gate
/// (median 0.167). The smallest round figure above every synthetic pair.
pub(crate) const MODES_APART: f64 = 0.15;

/// Whether the kept pass's `pairs` say two specimens (median cost over [`MODES_APART`]). Only
/// where the cost is the modal distance itself (`position_weight` 0, `cost_power` 1, the outline
/// recipe's): positions mixed in or a power would move the figure the gate was measured on.
pub(crate) fn modes_apart(pairs: &[MatchPair], opts: &MatchOptions) -> bool {
    if opts.position_weight != 0.0 || opts.cost_power != 1.0 || pairs.is_empty() {
        return false;
    }
    let mut costs: Vec<f64> = pairs.iter().map(|p| p.cost).collect();
    costs.sort_by(f64::total_cmp);
    let k = costs.len();
    let median = if k % 2 == 1 {
        costs[k / 2]
    } else {
        0.5 * (costs[k / 2 - 1] + costs[k / 2])
    };
    median > MODES_APART
}

/// The refined pass: A drifted onto B, then assigned to B on the moved positions, and `true`.
/// `kept` is returned unchanged, with `false`, when the field cannot be fitted.
///
/// # Errors
/// A failure of the search, passed through.
pub(crate) fn coherent(pair: &Pair<'_>, kept: Iteration) -> Result<(Iteration, bool), ModalError> {
    let d = pair.dim;
    let y = &pair.b.get().pts;
    let Some(moved) = drift(&kept.aligned, y, d) else {
        return Ok((kept, false));
    };
    let z = position_costs(&moved, y, d)?;
    let method = if pair.ordered {
        assign::Method::Ordered
    } else {
        pair.opts.method
    };
    // Saturating: the drift's figures (BENCHMARKS.md) were measured without the search's gaps.
    let pairs = pass_pairs_with(pair, &z, &moved, method, false)?;
    let (resid, _, _) = explained(pair, &moved, &pairs);
    Ok((
        Iteration {
            z,
            pairs,
            resid,
            aligned: moved,
            to_aligned: kept.to_aligned,
        },
        true,
    ))
}

/// The nodes `x` (row-major, `n × d`) moved onto `y` by the coherent field, or `None` when no
/// field can be fitted.
pub(crate) fn drift(x: &[f64], y: &[f64], d: usize) -> Option<Vec<f64>> {
    let (n, m) = (x.len() / d, y.len() / d);
    if n == 0 || m == 0 {
        return None;
    }
    let (basis, values) = kernel_basis(x, d)?;
    let k = values.len();
    let mut moved = x.to_vec();
    let mut var = initial_variance(x, y, d);
    if !(var.is_finite() && var > 0.0) {
        return None;
    }
    let mut post = super::drift_kernel::Posterior::new(y, d, n);
    let mut lhs = Mat::<f64>::zeros(k, k);
    let mut rhs = vec![0.0; k * d];
    for _ in 0..MAX_STEPS {
        // E-step: the posterior of each node of A having produced each node of B (see
        // drift_kernel.rs: each column normalised, its negligible entries left at 0).
        post.update(&moved, var);
        let (row_sums, pulled) = (&post.row_sums, &post.pulled);
        let (total, y_term) = (post.total, post.y_term);
        if !(total.is_finite() && total > 1e-12) {
            return None;
        }
        // M-step: (Qᵀ diag(P1) Q + λσ² Λ⁻¹) C = Qᵀ (P Y − diag(P1) X), moved = X + Q C.
        // `lhs` is rewritten whole: its lower triangle by `normal_matrix`, its upper mirrored below.
        rhs.fill(0.0);
        for i in 0..n {
            let row = &basis[i * k..(i + 1) * k];
            let p1 = row_sums[i];
            for c in 0..d {
                let target = pulled[i * d + c] - p1 * x[i * d + c];
                for a in 0..k {
                    rhs[c * k + a] += row[a] * target;
                }
            }
        }
        super::drift_kernel::normal_matrix(&basis, k, row_sums, &mut lhs);
        for a in 0..k {
            lhs[(a, a)] += SMOOTHNESS * var / values[a];
            for b in 0..a {
                lhs[(b, a)] = lhs[(a, b)];
            }
        }
        let coef = solve_spd(&lhs, &rhs, d)?;
        for i in 0..n {
            let row = &basis[i * k..(i + 1) * k];
            for c in 0..d {
                moved[i * d + c] =
                    x[i * d + c] + (0..k).map(|a| row[a] * coef[c * k + a]).sum::<f64>();
            }
        }
        // The mixture's variance at the moved nodes.
        let mut cross = 0.0;
        let mut x_term = 0.0;
        for i in 0..n {
            for c in 0..d {
                let v = moved[i * d + c];
                cross += v * pulled[i * d + c];
                x_term += row_sums[i] * v * v;
            }
        }
        let next = (y_term - 2.0 * cross + x_term) / (total * d as f64);
        if !next.is_finite() {
            return None;
        }
        let next = next.max(f64::EPSILON);
        let settled = (var - next).abs() < VARIANCE_TOLERANCE * var;
        var = next;
        if settled {
            break;
        }
    }
    moved.iter().all(|v| v.is_finite()).then_some(moved)
}

/// The leading eigenvectors of the Gaussian kernel on `x` (row-major `n × k`) and their
/// eigenvalues, every one > 0; `None` when the kernel has no positive eigenvalue.
fn kernel_basis(x: &[f64], d: usize) -> Option<(Vec<f64>, Vec<f64>)> {
    let n = x.len() / d;
    let k = RANK.min(n);
    let two_beta2 = 2.0 * KERNEL_WIDTH * KERNEL_WIDTH;
    // The largest eigenpairs of G are the lowest of −G.
    let neg = Mat::<f64>::from_fn(n, n, |i, j| {
        let d2: f64 = (0..d).map(|c| (x[i * d + c] - x[j * d + c]).powi(2)).sum();
        -(-d2 / two_beta2).exp()
    });
    let pairs = crate::eigen::symmetric_eigen_lowest(neg, k).ok()?;
    // Eigenvalues of a Gaussian kernel fall off fast: those lost in round-off are left out.
    let largest = -pairs.values.first().copied()?;
    let keep: Vec<usize> = (0..pairs.values.len())
        .filter(|&a| -pairs.values[a] > largest * 1e-10)
        .collect();
    if keep.is_empty() || !largest.is_finite() {
        return None;
    }
    let k = keep.len();
    let mut basis = vec![0.0; n * k];
    for (col, &a) in keep.iter().enumerate() {
        for i in 0..n {
            basis[i * k + col] = pairs.vectors[(i, a)];
        }
    }
    let values = keep.iter().map(|&a| -pairs.values[a]).collect();
    Some((basis, values))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::matching::outline_images::{both_ways, read_backwards};
    use crate::matching::{match_shapes, Refine};
    use crate::shape::{Shape, Topology};

    /// An asymmetric closed curve (three lobes and a tilt) at the angles `t`.
    fn curve(t: f64) -> [f64; 2] {
        let r = 1.0 + 0.2 * (3.0 * t).cos() + 0.1 * (2.0 * t).sin();
        [1.6 * r * t.cos(), r * t.sin()]
    }

    /// A smooth map that changes the curve's proportions (no affine map undoes it): one end
    /// lengthened and widened against the other.
    fn taper([x, y]: [f64; 2]) -> [f64; 2] {
        [x + 0.1 * x * x, y * (1.0 + 0.1 * x)]
    }

    /// A: `n` nodes of the curve; B: `m` nodes of the tapered curve from another start (0.37 of
    /// a spacing on); and where the taper takes each node of A (the truth).
    fn tapered_pair(n: usize, m: usize) -> (Vec<f64>, Vec<f64>, Vec<[f64; 2]>) {
        let at =
            |i: usize, k: usize, start: f64| (start + i as f64 / k as f64) * std::f64::consts::TAU;
        let a = (0..n).flat_map(|i| curve(at(i, n, 0.0))).collect();
        let b = (0..m)
            .flat_map(|i| taper(curve(at(i, m, 0.37 / m as f64))))
            .collect();
        let truth = (0..n).map(|i| taper(curve(at(i, n, 0.0)))).collect();
        (a, b, truth)
    }

    /// The mean distance between consecutive nodes of the closed planar outline `b`.
    fn mean_spacing(b: &[f64]) -> f64 {
        let m = b.len() / 2;
        (0..m)
            .map(|j| {
                let k = (j + 1) % m;
                (b[2 * k] - b[2 * j]).hypot(b[2 * k + 1] - b[2 * j + 1])
            })
            .sum::<f64>()
            / m as f64
    }

    #[test]
    fn drift_undoes_a_change_of_proportions_the_affine_match_slides_along() {
        // A: 96 nodes of the curve; B: 110 nodes of the tapered curve from another start. Each
        // node of A belongs where the taper takes it; the error of a pair is the distance of its
        // B node from there, in B's node spacings. The affine match (the outline recipe) leaves
        // the nodes slid along the outline by 2 spacings on average and some by over 20
        // (measured: mean 2.0, worst 21.5); the drift brings them to the floor of one node
        // spacing's sampling (mean 0.64, worst 1.86).
        let (n, m) = (96, 110);
        let (a, b, truth) = tapered_pair(n, m);
        let spacing = mean_spacing(&b);
        let sa = Shape::new(2, a, Topology::ClosedContour).unwrap();
        let sb = Shape::new(2, b.clone(), Topology::ClosedContour).unwrap();
        let errors = |refine: Refine| {
            let opts = MatchOptions {
                refine,
                ..MatchOptions::for_outlines()
            };
            let result = match_shapes(&sa, &sb, &opts).unwrap();
            let e: Vec<f64> = result
                .pairs
                .iter()
                .filter(|p| !p.excess)
                .map(|p| {
                    let t = truth[p.a];
                    (b[2 * p.b] - t[0]).hypot(b[2 * p.b + 1] - t[1]) / spacing
                })
                .collect();
            assert_eq!(e.len(), n, "every node of A in a one-to-one pair");
            let mean = e.iter().sum::<f64>() / n as f64;
            (mean, e.iter().copied().fold(0.0, f64::max))
        };
        let (affine, affine_worst) = errors(Refine::Affine);
        let (drifted, worst) = errors(Refine::Coherent);
        assert!(
            drifted < 1.0 && worst < 3.0,
            "drift: mean {drifted:.2}, worst {worst:.2}"
        );
        assert!(
            drifted < 0.5 * affine && worst < affine_worst,
            "drift {drifted:.2} / {worst:.2} against affine {affine:.2} / {affine_worst:.2}"
        );
    }

    #[test]
    fn outline_images_are_the_nearest_points_to_the_moved_nodes_and_finer_than_the_pairs() {
        // The tapered curve of the test above: after the drift each node's image is the point of
        // B's outline nearest its moved node (checked against 64 points per segment), and the
        // images lie nearer the true positions than the pairs' nodes (B's nodes sit 0.37 of a
        // spacing off them); without the drift each image is its pair's node.
        let (n, m) = (96, 110);
        let (a, b, truth) = tapered_pair(n, m);
        let on_b = |s: f64| {
            let (j, t) = (s.floor() as usize, s - s.floor());
            let k = (j + 1) % m;
            [
                b[2 * j] + t * (b[2 * k] - b[2 * j]),
                b[2 * j + 1] + t * (b[2 * k + 1] - b[2 * j + 1]),
            ]
        };
        let dist = |p: [f64; 2], q: &[f64]| (p[0] - q[0]).hypot(p[1] - q[1]);
        let sa = Shape::new(2, a, Topology::ClosedContour).unwrap();
        let sb = Shape::new(2, b.clone(), Topology::ClosedContour).unwrap();
        let run = |refine: Refine| {
            let opts = MatchOptions {
                refine,
                ..MatchOptions::for_outlines()
            };
            match_shapes(&sa, &sb, &opts).unwrap()
        };
        let drifted = run(Refine::Coherent);
        assert!(drifted.drifted);
        let images = drifted
            .outline_images
            .as_deref()
            .expect("two closed contours");
        assert_eq!(images.len(), n);
        let (mut image_error, mut pair_error) = (0.0, 0.0);
        for (i, &s) in images.iter().enumerate() {
            assert!((0.0..m as f64).contains(&s), "{s}");
            let moved = &drifted.aligned_a[2 * i..2 * i + 2];
            let nearest = (0..m * 64)
                .map(|k| dist(on_b(k as f64 / 64.0), moved))
                .fold(f64::INFINITY, f64::min);
            assert!(dist(on_b(s), moved) <= nearest + 1e-12);
            image_error += dist(on_b(s), &truth[i]);
        }
        for p in drifted.pairs.iter().filter(|p| !p.excess) {
            pair_error += dist(truth[p.a], &b[2 * p.b..2 * p.b + 2]);
        }
        // Measured: 4.66 against 5.19 (sums over A's nodes).
        assert!(
            image_error < 0.95 * pair_error,
            "images {image_error:.3}, pairs {pair_error:.3}"
        );
        let affine = run(Refine::Affine);
        assert!(!affine.drifted);
        let images = affine.outline_images.expect("two closed contours");
        for p in affine.pairs.iter().filter(|p| !p.excess) {
            assert_eq!(images[p.a], p.b as f64);
        }
    }

    #[test]
    fn auto_reads_the_images_both_ways_where_it_drifts() {
        // The tapered pair, which the first gate drifts. The images of the gated match are those
        // of A's drift averaged with B's drift read backwards; the rest of the result is A's
        // drift's. Against the truth (where the taper takes each node of A), in B's spacings,
        // the average lies between the two directions (measured: one way mean 0.60, worst 1.33;
        // backwards 0.73 / 2.02; both 0.66 / 1.33).
        let (n, m) = (96, 110);
        let (a, b, truth) = tapered_pair(n, m);
        let sa = Shape::new(2, a.clone(), Topology::ClosedContour).unwrap();
        let sb = Shape::new(2, b.clone(), Topology::ClosedContour).unwrap();
        let auto = MatchOptions::for_outlines();
        let one_way = crate::matching::drift_options(&auto);
        let got = match_shapes(&sa, &sb, &auto).unwrap();
        let forward = match_shapes(&sa, &sb, &one_way).unwrap();
        let backward = match_shapes(&sb, &sa, &one_way).unwrap();
        assert!(got.drifted && forward.drifted && backward.drifted);
        assert_eq!(
            (&got.pairs, &got.aligned_a),
            (&forward.pairs, &forward.aligned_a)
        );
        let (f, back) = (
            forward.outline_images.unwrap(),
            backward.outline_images.unwrap(),
        );
        let both = both_ways(&f, &back, &a, &b, 2).unwrap();
        assert_eq!(got.outline_images.as_deref(), Some(&both[..]));
        // The images as points of B's outline: `t` of the way from node `j` to node `j + 1`.
        let points = got.outline_image_points(&b).unwrap();
        for (i, &s) in both.iter().enumerate() {
            let (j, t) = (s.floor() as usize, s - s.floor());
            let k = (j + 1) % m;
            for c in 0..2 {
                let want = b[2 * j + c] + t * (b[2 * k + c] - b[2 * j + c]);
                assert!((points[2 * i + c] - want).abs() < 1e-12);
            }
        }
        // A shorter b than the match's is not read past its end.
        assert!(got.outline_image_points(&b[..m]).is_none());
        let spacing = mean_spacing(&b);
        let errors = |images: &[f64]| -> (f64, f64) {
            let e: Vec<f64> = images
                .iter()
                .zip(&truth)
                .map(|(&s, t)| {
                    let j = s.floor() as usize % m;
                    let k = (j + 1) % m;
                    let u = s - s.floor();
                    let p = [
                        b[2 * j] + u * (b[2 * k] - b[2 * j]),
                        b[2 * j + 1] + u * (b[2 * k + 1] - b[2 * j + 1]),
                    ];
                    (p[0] - t[0]).hypot(p[1] - t[1]) / spacing
                })
                .collect();
            (
                e.iter().sum::<f64>() / e.len() as f64,
                e.iter().copied().fold(0.0, f64::max),
            )
        };
        let back_on_b = read_backwards(&back, &a, &b, 2).unwrap();
        let (mean_f, worst_f) = errors(&f);
        let (mean_b, worst_b) = errors(&back_on_b);
        let (mean_both, worst_both) = errors(&both);
        assert!(
            mean_both <= 0.5 * (mean_f + mean_b) + 0.01 && worst_both <= worst_f.max(worst_b),
            "one way {mean_f:.3} / {worst_f:.3}, backwards {mean_b:.3} / {worst_b:.3}, \
             both {mean_both:.3} / {worst_both:.3}"
        );
        assert!(
            mean_both < 0.75 && worst_both < 1.5,
            "{mean_both} / {worst_both}"
        );
    }

    #[test]
    fn the_second_gate_reads_the_median_cost_of_the_modal_pairs() {
        let pairs = |costs: &[f64]| -> Vec<MatchPair> {
            costs
                .iter()
                .enumerate()
                .map(|(i, &cost)| MatchPair {
                    a: i,
                    b: i,
                    cost,
                    excess: false,
                })
                .collect()
        };
        let outlines = MatchOptions::for_outlines();
        assert!(modes_apart(&pairs(&[0.3, 0.1, 0.2]), &outlines));
        assert!(!modes_apart(&pairs(&[0.3, 0.1, 0.12]), &outlines));
        // An even count takes the mean of the middle two, as numpy's median does.
        assert!(modes_apart(&pairs(&[0.1, 0.3, 0.14, 0.17]), &outlines));
        assert!(!modes_apart(&pairs(&[0.1, 0.3, 0.13, 0.16]), &outlines));
        assert!(!modes_apart(&pairs(&[]), &outlines));
        // Only where the cost is the modal distance itself.
        let mixed = MatchOptions {
            position_weight: 0.5,
            ..outlines.clone()
        };
        let powered = MatchOptions {
            cost_power: 0.5,
            ..outlines.clone()
        };
        let apart = pairs(&[0.4, 0.5, 0.6]);
        assert!(modes_apart(&apart, &outlines));
        assert!(!modes_apart(&apart, &mixed) && !modes_apart(&apart, &powered));
    }

    #[test]
    fn auto_drifts_two_outlines_whose_modes_disagree_though_an_affine_map_lays_them_together() {
        // Two lobed outlines (different harmonics) that the rotation search's outline fit lays
        // within the first gate's distance, but whose modal pairs cost a median of 0.23.
        let lobed = |k: usize, start: f64, c: [[f64; 2]; 4]| -> Shape {
            let pts = (0..k).flat_map(|i| {
                let t = (start + i as f64 / k as f64) * std::f64::consts::TAU;
                let r = 1.0
                    + (0..4)
                        .map(|h| {
                            let w = (h + 2) as f64 * t;
                            c[h][0] * w.cos() + c[h][1] * w.sin()
                        })
                        .sum::<f64>();
                [1.6 * r * t.cos(), r * t.sin()]
            });
            Shape::new(2, pts.collect(), Topology::ClosedContour).unwrap()
        };
        // Cosine and sine weights of the 2nd to 5th harmonics of each outline's radius.
        let harmonics_a = [[0.01, 0.02], [-0.01, -0.01], [0.04, 0.07], [0.05, -0.14]];
        let harmonics_b = [[-0.01, 0.06], [0.02, 0.02], [0.06, 0.03], [0.11, -0.21]];
        let a = lobed(74, 0.0, harmonics_a);
        let b = lobed(71, 0.41 / 71.0, harmonics_b);
        let auto = MatchOptions::for_outlines();
        let affine = MatchOptions {
            refine: Refine::Affine,
            ..auto.clone()
        };
        let modal = match_shapes(&a, &b, &affine).unwrap();
        let mut costs: Vec<f64> = modal.pairs.iter().map(|p| p.cost).collect();
        costs.sort_by(f64::total_cmp);
        let median = 0.5 * (costs[costs.len() / 2 - 1] + costs[costs.len() / 2]);
        assert!(median > MODES_APART + 0.05, "median cost {median}");
        // The first gate leaves it: with the second off (a cost power other than 1) it is not
        // drifted.
        let first_only = MatchOptions {
            cost_power: 0.999,
            ..auto.clone()
        };
        assert!(!match_shapes(&a, &b, &first_only).unwrap().drifted);
        let drifted = crate::matching::drift_options(&auto);
        let got = match_shapes(&a, &b, &auto).unwrap();
        assert!(got.drifted);
        assert_eq!(got.pairs, match_shapes(&a, &b, &drifted).unwrap().pairs);
    }

    #[test]
    fn auto_drifts_two_specimens_and_leaves_one_outline_turned_to_the_affine_match() {
        // A: 90 nodes of the curve. Specimen: B is the tapered curve (proportions changed), which
        // no affine map lays on A; deformed: B is A's curve turned by 40° and stretched (an
        // affine map, which the rotation search undoes and the centroid-and-scale start cannot).
        let (n, m) = (90, 100);
        let at =
            |i: usize, k: usize, start: f64| (start + i as f64 / k as f64) * std::f64::consts::TAU;
        let turn = |[x, y]: [f64; 2]| {
            let (s, c) = 40f64.to_radians().sin_cos();
            [1.2 * (c * x - s * y), 0.9 * (s * x + c * y)]
        };
        let a: Vec<f64> = (0..n).flat_map(|i| curve(at(i, n, 0.0))).collect();
        let sa = Shape::new(2, a, Topology::ClosedContour).unwrap();
        let outline = |f: &dyn Fn([f64; 2]) -> [f64; 2]| {
            let b = (0..m).flat_map(|i| f(curve(at(i, m, 0.41 / m as f64))));
            Shape::new(2, b.collect(), Topology::ClosedContour).unwrap()
        };
        let (specimen, deformed) = (outline(&taper), outline(&turn));
        let auto = MatchOptions::for_outlines();
        assert_eq!(auto.refine, Refine::Auto);
        let affine = MatchOptions {
            refine: Refine::Affine,
            ..auto.clone()
        };
        let drifted = crate::matching::drift_options(&auto);
        let pairs = |b: &Shape, o: &MatchOptions| match_shapes(&sa, b, o).unwrap().pairs;
        assert_eq!(pairs(&specimen, &auto), pairs(&specimen, &drifted));
        assert_ne!(pairs(&specimen, &auto), pairs(&specimen, &affine));
        assert!(match_shapes(&sa, &specimen, &auto).unwrap().drifted);
        assert!(!match_shapes(&sa, &deformed, &auto).unwrap().drifted);
        let kept = pairs(&deformed, &auto);
        assert_eq!(kept, pairs(&deformed, &affine));
        // The affine match is right there (each node of A to the node of B nearest its image:
        // B's nodes lie 0.41 / 100 of a turn after A's at the same angles, so node i of A
        // belongs next to node round(i · m / n − 0.41) of B), the drift from the unturned start is not.
        let right = |p: &[crate::matching::MatchPair]| {
            p.iter()
                .filter(|p| {
                    let j = (p.a as f64 * m as f64 / n as f64 - 0.41).round() as usize % m;
                    !p.excess && ((p.b + m - j) % m <= 1 || (j + m - p.b) % m <= 1)
                })
                .count()
        };
        assert!(right(&kept) >= n - 2, "{} of {n}", right(&kept));
    }

    #[test]
    fn nothing_to_fit_gives_none() {
        assert!(drift(&[], &[0.0, 1.0], 2).is_none());
        assert!(drift(&[0.0, 1.0], &[], 2).is_none());
    }
}
