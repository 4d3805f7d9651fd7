//! Stage 7 (optional), deform: the modal non-rigid refinement of docs/method.md §7.4, after the
//! affine re-fits. A's aligned nodes are moved by a displacement field made of A's own
//! low-order vibration modes, `u = Φ q`, whose amplitudes `q` are fitted to soft
//! correspondences with B's nodes (an expectation-maximisation loop: Gaussian-mixture
//! responsibilities, then a least-squares fit of `q` regularised by each mode's strain energy,
//! after Sclaroff & Pentland 1995's recovery of the modal deformation between matched shapes).
//! The search then runs once more on the warped A.
//!
//! The warp never makes a pair fail: when it cannot be fitted (an empty or singular system,
//! nothing matched, a non-finite value) the affine pass is kept unchanged.

// Small dense linear algebra reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

use faer::linalg::solvers::Solve;
use faer::Mat;

use super::prepare::Pair;
use super::refine::{pass, Iteration, Pass};
use crate::error::{ModalError, OptionError};
use crate::model::{modal_basis, ModelOptions};
use crate::shape::Shape;

/// Most expectation-maximisation steps of one warp.
const MAX_STEPS: usize = 50;
/// The loop stops once the mixture's variance changes by less than this fraction.
const VARIANCE_TOLERANCE: f64 = 1e-5;
/// Share of B's nodes the mixture explains as outliers (CPD's `w`): nodes of B with no partner
/// in A must not pull the warp.
const OUTLIER_SHARE: f64 = 0.1;

/// The refined pass: A warped by its modes onto B, then matched again. `kept` is returned
/// unchanged when the warp cannot be fitted.
///
/// # Errors
/// [`ModalError::Option`] for a stiffness that is not finite and > 0; a failure of the
/// modal solve of the aligned A or of the search, passed through.
pub(crate) fn deform(pair: &Pair<'_>, kept: Iteration) -> Result<Iteration, ModalError> {
    let stiffness = pair.opts.deform_stiffness;
    if !(stiffness.is_finite() && stiffness > 0.0) {
        return Err(OptionError::new("deform_stiffness", stiffness, "a finite number > 0").into());
    }
    let Some(warped) = warp(pair, &kept.aligned)? else {
        return Ok(kept);
    };
    let modes_b = pair.modal().then(|| pair.modes_b()).transpose()?;
    let modes_a = pair.modal().then(|| pair.modes_a(&warped)).transpose()?;
    let Pass {
        z, pairs, resid, ..
    } = pass(
        pair,
        &warped,
        modes_a.as_deref().zip(modes_b.as_deref()),
        None,
    )?;
    Ok(Iteration {
        z,
        pairs,
        resid,
        aligned: warped,
        to_aligned: kept.to_aligned,
    })
}

/// A's nodes `x` (B's normalised frame, row-major) moved by the fitted modal displacement, or
/// `None` when no warp can be fitted.
fn warp(pair: &Pair<'_>, x: &[f64]) -> Result<Option<Vec<f64>>, ModalError> {
    let d = pair.dim;
    let y = &pair.b.get().pts;
    let basis = match warp_basis(pair, x)? {
        Some(b) => b,
        None => return Ok(None),
    };
    let n = x.len() / d;
    let k = basis.stiffness.len();
    let stiffness = pair.opts.deform_stiffness;
    let mut moved = x.to_vec();
    // The mixture stops sharpening at B's node spacing: below it, the warp would chase the
    // sampling of B instead of its shape.
    let floor = pair.b.get().spacing().powi(2);
    let mut var = initial_variance(x, y, d);
    for _ in 0..MAX_STEPS {
        let Some(resp) = responsibilities(&moved, y, d, var) else {
            return Ok(None);
        };
        // Normal equations of Σ_ij P_ij |x_i + Φ_i q − y_j|² + stiffness · σ² · Σ_p r_p q_p².
        let mut lhs = Mat::<f64>::zeros(k, k);
        let mut rhs = vec![0.0; k];
        for i in 0..n {
            let p1 = resp.row_sums[i];
            for c in 0..d {
                let target = resp.pulled[i * d + c] - p1 * x[i * d + c];
                let row = basis.row(c * n + i);
                for p in 0..k {
                    rhs[p] += row[p] * target;
                    if p1 > 0.0 {
                        for q in 0..=p {
                            lhs[(p, q)] += p1 * row[p] * row[q];
                        }
                    }
                }
            }
        }
        for p in 0..k {
            lhs[(p, p)] += stiffness * var * basis.stiffness[p];
            for q in 0..p {
                lhs[(q, p)] = lhs[(p, q)];
            }
        }
        let Some(q) = solve_spd(&lhs, &rhs, 1) else {
            return Ok(None);
        };
        for i in 0..n {
            for c in 0..d {
                let row = basis.row(c * n + i);
                moved[i * d + c] = x[i * d + c] + (0..k).map(|p| row[p] * q[p]).sum::<f64>();
            }
        }
        let next = resp.weighted_residual(&moved, y, d) / (resp.total * d as f64);
        if !next.is_finite() {
            return Ok(None);
        }
        let settled = (var - next).abs() <= VARIANCE_TOLERANCE * var;
        var = next.max(floor).max(f64::EPSILON);
        if settled {
            break;
        }
    }
    Ok(moved.iter().all(|v| v.is_finite()).then_some(moved))
}

/// The displacement basis: A's lowest modes at its aligned coordinates, each scaled to unit RMS
/// displacement per node, with its strain energy per unit amplitude relative to the first
/// flexible mode's.
struct WarpBasis {
    /// `(dim·n) × k` component-major rows, row-major storage.
    rows: Vec<f64>,
    k: usize,
    /// Relative strain energy `r_p` of each mode (0 for the rigid ones).
    stiffness: Vec<f64>,
}

impl WarpBasis {
    fn row(&self, r: usize) -> &[f64] {
        &self.rows[r * self.k..(r + 1) * self.k]
    }
}

/// Solves A's model at `x` for the warp's modes; `None` when too few nodes are there to carry
/// more than the rigid modes.
fn warp_basis(pair: &Pair<'_>, x: &[f64]) -> Result<Option<WarpBasis>, ModalError> {
    let d = pair.dim;
    let n = x.len() / d;
    let rigid = if d == 2 { 3 } else { 6 };
    let available = pair.model.degrees_of_freedom(d, n);
    let k = pair.opts.deform_modes.min(available);
    if k <= rigid {
        return Ok(None);
    }
    let shape = Shape::new(d, x.to_vec(), pair.a.get().topology.clone())?;
    let opts = ModelOptions {
        n_modes: Some(k),
        ..pair.model.clone()
    };
    let basis = modal_basis(&shape, &opts)?;
    let k = basis.modes.ncols();
    if k <= rigid {
        return Ok(None);
    }
    let nn = n as f64;
    let mut rows = vec![0.0; d * n * k];
    let mut stiffness = vec![0.0; k];
    for p in 0..k {
        let norm = (0..d * n)
            .map(|r| basis.modes[(r, p)].powi(2))
            .sum::<f64>()
            .sqrt();
        if !(norm.is_finite() && norm > 0.0) {
            return Ok(None);
        }
        // φ scaled to unit RMS per node: u = φ' q' with q' = (‖φ‖/√n) q, so the strain energy
        // ½ ω² q² becomes ½ ω² n / ‖φ‖² q'².
        let scale = nn.sqrt() / norm;
        for r in 0..d * n {
            rows[r * k + p] = basis.modes[(r, p)] * scale;
        }
        stiffness[p] = basis.eigenvalues[p].max(0.0) * scale * scale;
    }
    let reference = stiffness[rigid];
    if !(reference.is_finite() && reference > 0.0) {
        return Ok(None);
    }
    for s in &mut stiffness {
        // The rigid modes keep a tiny weight so the system stays definite without matches.
        *s = (*s / reference).max(1e-6);
    }
    Ok(Some(WarpBasis { rows, k, stiffness }))
}

/// The mixture's first variance: the mean squared distance of all pairs, as in coherent point
/// drift (wide enough that every node of B first pulls on all of A).
pub(super) fn initial_variance(x: &[f64], y: &[f64], d: usize) -> f64 {
    let (n, m) = (x.len() / d, y.len() / d);
    let mut sum = 0.0;
    for i in 0..n {
        for j in 0..m {
            sum += (0..d)
                .map(|c| (x[i * d + c] - y[j * d + c]).powi(2))
                .sum::<f64>();
        }
    }
    sum / (d * n * m) as f64
}

/// The E-step's sufficient statistics.
struct Responsibilities {
    /// `P[i, j]`, row-major `n × m`.
    p: Vec<f64>,
    m: usize,
    /// `Σ_j P[i, j]` for each node of A.
    row_sums: Vec<f64>,
    /// `Σ_j P[i, j] y_j`, row-major `n × d`.
    pulled: Vec<f64>,
    /// `Σ_ij P[i, j]`.
    total: f64,
}

impl Responsibilities {
    fn weighted_residual(&self, moved: &[f64], y: &[f64], d: usize) -> f64 {
        let n = moved.len() / d;
        let mut sum = 0.0;
        for i in 0..n {
            for j in 0..self.m {
                let pij = self.p[i * self.m + j];
                if pij > 0.0 {
                    sum += pij
                        * (0..d)
                            .map(|c| (moved[i * d + c] - y[j * d + c]).powi(2))
                            .sum::<f64>();
                }
            }
        }
        sum
    }
}

/// Posterior of each node of A having produced each node of B under an isotropic Gaussian
/// mixture of variance `var` centred on the moved A, with a uniform outlier share; `None` when
/// nothing is matched.
fn responsibilities(moved: &[f64], y: &[f64], d: usize, var: f64) -> Option<Responsibilities> {
    let (n, m) = (moved.len() / d, y.len() / d);
    let outlier = (std::f64::consts::TAU * var).powf(d as f64 / 2.0) * OUTLIER_SHARE
        / (1.0 - OUTLIER_SHARE)
        * n as f64
        / m as f64;
    let mut p = vec![0.0; n * m];
    for j in 0..m {
        let mut col = 0.0;
        for i in 0..n {
            let d2: f64 = (0..d)
                .map(|c| (moved[i * d + c] - y[j * d + c]).powi(2))
                .sum();
            let e = (-d2 / (2.0 * var)).exp();
            p[i * m + j] = e;
            col += e;
        }
        let denom = col + outlier;
        for i in 0..n {
            p[i * m + j] /= denom;
        }
    }
    let mut row_sums = vec![0.0; n];
    let mut pulled = vec![0.0; n * d];
    for i in 0..n {
        for j in 0..m {
            let pij = p[i * m + j];
            row_sums[i] += pij;
            for c in 0..d {
                pulled[i * d + c] += pij * y[j * d + c];
            }
        }
    }
    let total: f64 = row_sums.iter().sum();
    (total.is_finite() && total > 1e-12).then_some(Responsibilities {
        p,
        m,
        row_sums,
        pulled,
        total,
    })
}

/// Solves the symmetric positive definite system `lhs · Q = R` for `cols` right-hand sides, each
/// stored after the other in `rhs` (and so in the result); `None` when it is not definite.
pub(super) fn solve_spd(lhs: &Mat<f64>, rhs: &[f64], cols: usize) -> Option<Vec<f64>> {
    let k = lhs.nrows();
    debug_assert_eq!(rhs.len(), k * cols);
    let llt = lhs.llt(faer::Side::Lower).ok()?;
    let b = Mat::from_fn(k, cols, |r, c| rhs[c * k + r]);
    let q = llt.solve(&b);
    let q: Vec<f64> = (0..cols)
        .flat_map(|c| (0..k).map(move |r| (r, c)))
        .map(|(r, c)| q[(r, c)])
        .collect();
    q.iter().all(|v| v.is_finite()).then_some(q)
}
