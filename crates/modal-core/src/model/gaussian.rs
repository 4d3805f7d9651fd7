//! Sclaroff's isoparametric Gaussian element in 2-D and 3-D (docs/method.md §2).
//!
//! Interpolants `h = A g` with `g_k(x) = exp(−|x−X_k|²/2σ²)` and `A = G⁻¹`. All integrals are over
//! ℝ^d and closed-form (§2.2). The stiffness and mass are `K = Â K̃ Â`, `M = Â Γ̃ Â` with
//! `Â = I_d ⊗ A`; the eigenproblem is solved in the ψ-form `K̃ ψ = ω² Γ̃ ψ`, `φ = (I_d ⊗ G) ψ`
//! (§2.6), so `G⁻¹` is never formed on the solve path.

// Index loops over several matrices at once read better than zipped iterators here.
#![allow(clippy::needless_range_loop)]

use faer::linalg::solvers::DenseSolveCore;
use faer::Mat;

use super::material::{Material, PlaneModel};
use crate::error::ModalError;
use crate::shape::Shape;

/// The closed-form integrals of one Gaussian element (without material constants).
#[derive(Debug, Clone)]
pub struct GaussianIntegrals {
    pub dim: usize,
    pub n: usize,
    /// `G_ij = exp(−r²/2σ²)`.
    pub g: Mat<f64>,
    /// `Γ_ij = ∫ g_i g_j`.
    pub gamma: Mat<f64>,
    /// `Γ^{ab}_ij = ∫ ∂_a g_i ∂_b g_j`, stored for `a ≤ b` in the order of `pair_index`.
    pub gamma_d: Vec<Mat<f64>>,
}

/// Index of the unordered component pair `(a, b)` in [`GaussianIntegrals::gamma_d`]:
/// 2-D `xx, xy, yy`; 3-D `xx, xy, xz, yy, yz, zz`.
pub(crate) fn pair_index(dim: usize, a: usize, b: usize) -> usize {
    let (a, b) = if a <= b { (a, b) } else { (b, a) };
    // Row-major upper triangle.
    a * dim - a * a.saturating_sub(1) / 2 + (b - a)
}

/// `G_ij = exp(−|x_i − c_j|² / 2σ²)`: the Gaussians centred on `centers` evaluated at `nodes`,
/// `nodes.len() × centers.len()`. With the nodes as centres this is [`GaussianIntegrals::g`]
/// (which shares its exponentials with `Γ` instead); a reduced basis interpolates its modes to
/// every node with it.
pub fn gaussians_at(nodes: &Shape, centers: &Shape, sigma: f64) -> Mat<f64> {
    let dim = nodes.dim();
    let (x, c) = (nodes.coords(), centers.coords());
    let inv = 0.5 / (sigma * sigma);
    Mat::from_fn(nodes.len(), centers.len(), |i, j| {
        let r2: f64 = (0..dim)
            .map(|a| (x[i * dim + a] - c[j * dim + a]).powi(2))
            .sum();
        gaussian(r2 * inv)
    })
}

/// Exponents beyond which a Gaussian is stored as an exact zero: `e^−600 ≈ 3·10⁻²⁶¹`, a relative
/// perturbation no sum of these matrices can see, while the values between it and the smallest
/// normal number (`e^−708`) are subnormal, and every product that touches a subnormal runs
/// through a microcode assist ~100× slower: a 150-node contour's `G` had 348 of them, and
/// `φ = G ψ` (300 modes) took 7.6 ms instead of 0.37 ms.
const NEGLIGIBLE_EXPONENT: f64 = 600.0;

/// `e^−x` for `x ≥ 0`, an exact zero where it would be negligible (and possibly subnormal).
#[inline]
fn gaussian(x: f64) -> f64 {
    if x > NEGLIGIBLE_EXPONENT {
        0.0
    } else {
        (-x).exp()
    }
}

impl GaussianIntegrals {
    /// Closed forms of docs/method.md §2.2 for the nodes of `shape` and width `sigma`.
    pub fn new(shape: &Shape, sigma: f64) -> Self {
        let dim = shape.dim();
        let n = shape.len();
        let c = shape.coords();
        let s2 = sigma * sigma;
        let v = (std::f64::consts::PI * s2).powf(dim as f64 / 2.0);
        let npairs = dim * (dim + 1) / 2;
        let mut g = Mat::<f64>::zeros(n, n);
        let mut gamma = Mat::<f64>::zeros(n, n);
        let mut gamma_d: Vec<Mat<f64>> = (0..npairs).map(|_| Mat::zeros(n, n)).collect();
        let inv4s4 = 1.0 / (4.0 * s2 * s2);
        let mut d = [0.0f64; 3];
        for j in 0..n {
            for i in j..n {
                let mut r2 = 0.0;
                for a in 0..dim {
                    d[a] = c[j * dim + a] - c[i * dim + a];
                    r2 += d[a] * d[a];
                }
                let arg = r2 / (4.0 * s2);
                let e = gaussian(arg);
                // G's exponent is twice Γ's: it reaches the negligible range first.
                let gij = gaussian(2.0 * arg);
                let gm = v * e;
                g[(i, j)] = gij;
                g[(j, i)] = gij;
                gamma[(i, j)] = gm;
                gamma[(j, i)] = gm;
                let mut p = 0;
                for a in 0..dim {
                    for b in a..dim {
                        let delta = if a == b { 2.0 * s2 } else { 0.0 };
                        let val = gm * (delta - d[a] * d[b]) * inv4s4;
                        gamma_d[p][(i, j)] = val;
                        gamma_d[p][(j, i)] = val;
                        p += 1;
                    }
                }
            }
        }
        Self {
            dim,
            n,
            g,
            gamma,
            gamma_d,
        }
    }

    /// `Γ^{ab}` for any ordered pair.
    pub fn gamma_ab(&self, a: usize, b: usize) -> &Mat<f64> {
        &self.gamma_d[pair_index(self.dim, a, b)]
    }

    /// Full `K̃` (d·n × d·n, component-major), block `(a, b)` being
    /// `(λ+μ) Γ^{ab} + μ δ_ab Σ_c Γ^{cc}` (docs/method.md §2.4 without the `A`s), written in place
    /// column by column.
    pub fn k_tilde(&self, lambda: f64, mu: f64) -> Mat<f64> {
        let (n, dim) = (self.n, self.dim);
        let mut k = Mat::<f64>::zeros(dim * n, dim * n);
        for j in 0..n {
            let diagonal: Vec<&[f64]> = (0..dim)
                .map(|c| crate::eigen::column(self.gamma_ab(c, c), j))
                .collect();
            for b in 0..dim {
                let col = crate::eigen::column_mut(&mut k, b * n + j);
                for a in 0..dim {
                    let ab = crate::eigen::column(self.gamma_ab(a, b), j);
                    let out = &mut col[a * n..(a + 1) * n];
                    if a != b {
                        for (o, x) in out.iter_mut().zip(ab) {
                            *o = x * (lambda + mu);
                        }
                        continue;
                    }
                    for i in 0..n {
                        let mut v = ab[i] * (lambda + mu);
                        for cc in &diagonal {
                            v += cc[i] * mu;
                        }
                        out[i] = v;
                    }
                }
            }
        }
        k
    }

    /// Explicit `K = Â K̃ Â` and `M = Â Γ̃ Â` with `A = G⁻¹` (docs/method.md §2.3–2.4). For tests,
    /// exports and oracles only; the modal solve never forms `G⁻¹`.
    pub(crate) fn explicit_matrices(
        &self,
        material: &Material,
        plane: PlaneModel,
    ) -> Result<(Mat<f64>, Mat<f64>), ModalError> {
        let n = self.n;
        let dim = self.dim;
        let (lambda, mu) = material.lame(dim, plane);
        let llt = self
            .g
            .llt(faer::Side::Lower)
            .map_err(|_| ModalError::NotPositiveDefinite {
                matrix: "the Gaussian matrix G",
                pivot: None,
            })?;
        let a = llt.inverse();
        let ms = &a * (&self.gamma * faer::Scale(material.density)) * &a;
        let k_tilde = self.k_tilde(lambda, mu);
        let mut m = Mat::<f64>::zeros(dim * n, dim * n);
        let mut k = Mat::<f64>::zeros(dim * n, dim * n);
        for p in 0..dim {
            m.as_mut().submatrix_mut(p * n, p * n, n, n).copy_from(&ms);
            for q in 0..dim {
                let block = k_tilde.submatrix(p * n, q * n, n, n).to_owned();
                let blk = &a * block * &a;
                k.as_mut().submatrix_mut(p * n, q * n, n, n).copy_from(&blk);
            }
        }
        crate::eigen::symmetrise(m.as_mut());
        crate::eigen::symmetrise(k.as_mut());
        Ok((k, m))
    }
}
