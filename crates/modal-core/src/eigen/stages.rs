//! The stages of a symmetric solve one by one, each with its faer counterpart beside the
//! hand-written one, so `benches/eigen.rs` can time them side by side (BENCHMARKS.md,
//! "Eigensolver"). Not part of the supported API.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::evd::{self, tridiag};
use faer::linalg::householder as hh;
use faer::reborrow::ReborrowMut;
use faer::{Mat, MatMut, MatRef, Par};

use super::{bisection, householder};
use crate::error::ModalError;

/// A tridiagonal matrix and the reflectors that produced it, from either reduction.
pub struct Tridiagonal(Reduction);

enum Reduction {
    /// This crate's four-column fused sweeps.
    Hand(householder::Tridiagonal),
    /// faer's `tridiag_in_place`: the reduced matrix (reflectors below the sub-diagonal) and the
    /// block Householder factors.
    Faer { reduced: Mat<f64>, factor: Mat<f64> },
}

/// The hand-written Householder reduction of `a` (lower triangle read).
pub fn tridiagonalize_hand(a: MatRef<'_, f64>) -> Tridiagonal {
    Tridiagonal(Reduction::Hand(householder::tridiagonalize(a)))
}

/// faer's Householder reduction of `a` (lower triangle read).
pub fn tridiagonalize_faer(a: MatRef<'_, f64>) -> Tridiagonal {
    let n = a.nrows();
    let mut reduced = Mat::<f64>::zeros(n, n);
    reduced.copy_from_triangular_lower(a);
    let bs = faer::linalg::qr::no_pivoting::factor::recommended_block_size::<f64>(n, n);
    let mut factor = Mat::<f64>::zeros(bs, n.saturating_sub(1));
    let mut mem = MemBuffer::new(tridiag::tridiag_in_place_scratch::<f64>(
        n,
        Par::Seq,
        Default::default(),
    ));
    tridiag::tridiag_in_place(
        reduced.as_mut(),
        factor.as_mut(),
        Par::Seq,
        MemStack::new(&mut mem),
        Default::default(),
    );
    crate::simd::clear_upper_state();
    Tridiagonal(Reduction::Faer { reduced, factor })
}

impl Tridiagonal {
    /// Diagonal and off-diagonal.
    pub fn entries(&self) -> (Vec<f64>, Vec<f64>) {
        match &self.0 {
            Reduction::Hand(t) => (t.diag.clone(), t.off.clone()),
            Reduction::Faer { reduced, .. } => {
                let n = reduced.nrows();
                (
                    (0..n).map(|i| reduced[(i, i)]).collect(),
                    (1..n).map(|i| reduced[(i, i - 1)]).collect(),
                )
            }
        }
    }

    /// `Y ← Q Y`.
    pub fn apply_q(&self, mut y: MatMut<'_, f64>) {
        match &self.0 {
            Reduction::Hand(t) => t.apply_q(y),
            Reduction::Faer { reduced, factor } => {
                let n = reduced.nrows();
                if n < 2 {
                    return;
                }
                let m = n - 1;
                let k = y.ncols();
                let mut mem = MemBuffer::new(
                    hh::apply_block_householder_sequence_on_the_left_in_place_scratch::<f64>(
                        m,
                        factor.nrows(),
                        k,
                    ),
                );
                hh::apply_block_householder_sequence_on_the_left_in_place_with_conj(
                    reduced.as_ref().submatrix(1, 0, m, m),
                    factor.as_ref(),
                    faer::Conj::No,
                    y.rb_mut().subrows_mut(1, m),
                    Par::Seq,
                    MemStack::new(&mut mem),
                );
                crate::simd::clear_upper_state();
            }
        }
    }
}

/// Every eigenvalue of the tridiagonal matrix by the hand-written root-free QL.
pub fn eigenvalues_ql(diag: &[f64], off: &[f64]) -> Result<Vec<f64>, ModalError> {
    super::tridiagonal_eigenvalues(diag, off)
}

/// Every eigenvalue of the tridiagonal matrix by faer's QR algorithm (no vectors).
pub fn eigenvalues_faer(diag: &[f64], off: &[f64]) -> Result<Vec<f64>, ModalError> {
    let (values, _) = tridiagonal_evd_faer(diag, off, false)?;
    Ok(values)
}

/// The `k` lowest eigenvalues of the tridiagonal matrix by hand-written bisection.
pub fn lowest_eigenvalues_bisection(diag: &[f64], off: &[f64], k: usize) -> Vec<f64> {
    bisection::lowest_eigenvalues(diag, off, k)
}

/// Eigenvectors of the tridiagonal matrix for the given eigenvalues by hand-written inverse
/// iteration.
pub fn eigenvectors_inverse_iteration(
    diag: &[f64],
    off: &[f64],
    values: &[f64],
) -> Result<Mat<f64>, ModalError> {
    let mut u = Mat::<f64>::zeros(diag.len(), values.len());
    super::tridiagonal_inverse_iteration(diag, off, values, u.as_mut())?;
    Ok(u)
}

/// Every eigenpair of the tridiagonal matrix by faer (QR algorithm or divide and conquer);
/// eigenvalues ascending, vectors when asked.
pub fn tridiagonal_evd_faer(
    diag: &[f64],
    off: &[f64],
    vectors: bool,
) -> Result<(Vec<f64>, Option<Mat<f64>>), ModalError> {
    let n = diag.len();
    let mut d = faer::diag::Diag::<f64>::zeros(n);
    let mut e = faer::diag::Diag::<f64>::zeros(n);
    for i in 0..n {
        d[i] = diag[i];
        if i + 1 < n {
            e[i] = off[i];
        }
    }
    let mut s = faer::diag::Diag::<f64>::zeros(n);
    let compute = if vectors {
        evd::ComputeEigenvectors::Yes
    } else {
        evd::ComputeEigenvectors::No
    };
    let mut u = vectors.then(|| Mat::<f64>::zeros(n, n));
    let mut mem = MemBuffer::new(evd::self_adjoint_evd_scratch::<f64>(
        n,
        compute,
        Par::Seq,
        Default::default(),
    ));
    evd::tridiagonal_self_adjoint_evd(
        d.as_ref(),
        e.as_ref(),
        s.as_mut(),
        u.as_mut().map(|u| u.as_mut()),
        Par::Seq,
        MemStack::new(&mut mem),
        Default::default(),
    )
    .map_err(|_| ModalError::NotConverged {
        method: "tridiagonal eigensolver",
    })?;
    crate::simd::clear_upper_state();
    Ok(((0..n).map(|i| s[i]).collect(), u))
}

/// faer's dense self-adjoint EVD of `c` (lower triangle read): every eigenvalue, the `k`
/// lowest pairs.
pub fn symmetric_eigen_faer(c: MatRef<'_, f64>, k: usize) -> Result<super::EigenPairs, ModalError> {
    super::full_eigen(c, k)
}

/// `C = L⁻¹ K L⁻ᵀ` by two faer triangular solves (full storage).
pub fn congruence_faer(l: MatRef<'_, f64>, k: MatRef<'_, f64>) -> Mat<f64> {
    let mut c = k.to_owned();
    super::congruence_inverse(l, c.as_mut());
    c
}

/// The generalized solve `K x = λ B x` with faer doing every dense step: Cholesky, the
/// congruence by two triangular solves, the dense self-adjoint EVD, `x = L⁻ᵀ y`.
pub fn generalized_eigen_faer(
    k: MatRef<'_, f64>,
    b: MatRef<'_, f64>,
    n_modes: usize,
) -> Result<super::EigenPairs, ModalError> {
    let l = cholesky_factor(b)?;
    let c = congruence_faer(l.as_ref(), k);
    let mut pairs = super::full_eigen(c.as_ref(), n_modes)?;
    super::solve_lower_transpose(l.as_ref(), pairs.vectors.as_mut());
    Ok(pairs)
}

/// The lowest `n_modes` pairs of `K x = λ B x` with faer's Cholesky, congruence, tridiagonal
/// reduction and back-transform, and the hand-written bisection and inverse iteration.
pub fn generalized_eigen_lowest_mixed(
    k: MatRef<'_, f64>,
    b: MatRef<'_, f64>,
    n_modes: usize,
) -> Result<super::EigenPairs, ModalError> {
    let l = cholesky_factor(b)?;
    let c = congruence_faer(l.as_ref(), k);
    let t = tridiagonalize_faer(c.as_ref());
    let (d, e) = t.entries();
    let values = bisection::lowest_eigenvalues(&d, &e, n_modes);
    let mut vectors = eigenvectors_inverse_iteration(&d, &e, &values)?;
    t.apply_q(vectors.as_mut());
    super::solve_lower_transpose(l.as_ref(), vectors.as_mut());
    Ok(super::EigenPairs {
        values,
        vectors,
        all_values: None,
    })
}

/// The Cholesky factor of `b` (lower triangle read) by faer.
pub fn cholesky_factor(b: MatRef<'_, f64>) -> Result<Mat<f64>, ModalError> {
    let n = b.nrows();
    let mut l = Mat::<f64>::zeros(n, n);
    l.copy_from_triangular_lower(b);
    super::cholesky_in_place(l.as_mut()).map_err(|i| ModalError::NotPositiveDefinite {
        matrix: "M",
        pivot: Some(i),
    })?;
    Ok(l)
}
