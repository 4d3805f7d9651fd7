//! Symmetric and generalized symmetric-definite eigensolvers (docs/method.md §4).
//!
//! `K x = λ B x` with `B` positive definite is reduced to a standard problem by `B = L Lᵀ`,
//! `C = L⁻¹ K L⁻ᵀ`, `C y = λ y`, `x = L⁻ᵀ y` (so `xᵀ B x = I`). faer does the Cholesky
//! factorisation, the congruence (two triangular solves), the back-transform by the Householder
//! reflectors (its blocked compact-WY product) and the whole solve of tiny matrices. Hand-written
//! code remains where faer has no routine or where a side-by-side benchmark shows it clearly
//! faster (BENCHMARKS.md, "Eigensolver", with the lines each piece costs): the Householder
//! tridiagonalisation (`householder`: four-column fused sweeps, ~2.4× faer's at 120 dof, ~2× at
//! 300); the root-free QL iteration for every eigenvalue without vectors (~3× faer's QR); and, for
//! the lowest `k` pairs a modal solve asks for ([`symmetric_eigen_lowest`]), lane-parallel
//! bisection (`bisection`) and inverse iteration on the tridiagonal matrix (re-orthogonalised
//! inside clusters as LAPACK's `dstein` does), for which faer has no routine: its only
//! alternative, the full tridiagonal eigendecomposition, is 7–25× slower.

// Index loops over several matrices at once read better than zipped iterators here.
#![allow(clippy::needless_range_loop)]

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::evd::{self, ComputeEigenvectors};
use faer::linalg::{cholesky, triangular_solve};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::{Mat, MatMut, MatRef, Par};

use crate::error::ModalError;
use crate::simd::{clear_upper_state, dispatch, Kernel};

mod bisection;
mod householder;
#[cfg(feature = "internals")]
pub mod stages;

/// Eigenvalues (ascending) and the matching eigenvectors (columns).
#[derive(Debug, Clone)]
pub struct EigenPairs {
    /// The computed eigenvalues, ascending.
    pub values: Vec<f64>,
    /// One column per computed eigenvalue.
    pub vectors: Mat<f64>,
    /// Every eigenvalue of the problem (ascending), also those whose vectors were not computed;
    /// `None` from [`symmetric_eigen_lowest`], which finds only the wanted ones.
    pub all_values: Option<Vec<f64>>,
}

/// Below this order faer's dense solver is used directly.
const TRIDIAGONAL_MIN_ORDER: usize = 8;

/// Cholesky factorisation in place; the lower triangle of `a` becomes `L` with `a = L Lᵀ`.
/// Only the lower triangle of `a` is read. Returns the index of the first non-positive pivot.
pub fn cholesky_in_place(a: MatMut<'_, f64>) -> Result<(), usize> {
    let n = a.nrows();
    let par = Par::Seq;
    let req = cholesky::llt::factor::cholesky_in_place_scratch::<f64>(n, par, Default::default());
    let mut mem = MemBuffer::new(req);
    let stack = MemStack::new(&mut mem);
    cholesky::llt::factor::cholesky_in_place(a, Default::default(), par, stack, Default::default())
        .map(|_| clear_upper_state())
        .map_err(|e| match e {
            cholesky::llt::factor::LltError::NonPositivePivot { index } => index,
        })
}

/// `X ← L⁻¹ X` with `L` the lower triangle of `l`.
pub fn solve_lower(l: MatRef<'_, f64>, x: MatMut<'_, f64>) {
    triangular_solve::solve_lower_triangular_in_place(l, x, Par::Seq);
    clear_upper_state();
}

/// `X ← L⁻ᵀ X` with `L` the lower triangle of `l`.
pub fn solve_lower_transpose(l: MatRef<'_, f64>, x: MatMut<'_, f64>) {
    triangular_solve::solve_upper_triangular_in_place(l.transpose(), x, Par::Seq);
    clear_upper_state();
}

/// `S ← L⁻¹ S L⁻ᵀ` for a symmetric `S` (full storage in, full storage out, symmetrised).
pub fn congruence_inverse(l: MatRef<'_, f64>, mut s: MatMut<'_, f64>) {
    // L⁻¹ S L⁻ᵀ = L⁻¹ (L⁻¹ S)ᵀ because S is symmetric: two triangular solves, no transposed copy
    // of S is needed other than the in-place transpose view.
    solve_lower(l, s.rb_mut());
    let n = s.nrows();
    for j in 0..n {
        for i in (j + 1)..n {
            let (a, b) = (s[(i, j)], s[(j, i)]);
            s[(i, j)] = b;
            s[(j, i)] = a;
        }
    }
    solve_lower(l, s.rb_mut());
    symmetrise(s);
}

/// `S ← (S + Sᵀ)/2`.
pub fn symmetrise(mut s: MatMut<'_, f64>) {
    let n = s.nrows();
    for j in 0..n {
        for i in (j + 1)..n {
            let v = 0.5 * (s[(i, j)] + s[(j, i)]);
            s[(i, j)] = v;
            s[(j, i)] = v;
        }
    }
}

/// Eigenpairs of the symmetric matrix `c` (only its lower triangle is read; it is overwritten),
/// ascending; the `n_modes` lowest if given, all otherwise. Eigenvectors are orthonormal. Every
/// eigenvalue is returned in [`EigenPairs::all_values`].
pub fn symmetric_eigen(c: Mat<f64>, n_modes: Option<usize>) -> Result<EigenPairs, ModalError> {
    let n = c.nrows();
    solve_symmetric(c, n_modes.unwrap_or(n), Spectrum::All)
}

/// The `k` lowest eigenpairs of the symmetric matrix `c` (only its lower triangle is read; it is
/// overwritten), ascending, with orthonormal eigenvectors; the other eigenvalues are not computed
/// ([`EigenPairs::all_values`] is `None`). The same pairs as [`symmetric_eigen`] to round-off,
/// faster when `k` is a fraction of the order.
pub fn symmetric_eigen_lowest(c: Mat<f64>, k: usize) -> Result<EigenPairs, ModalError> {
    solve_symmetric(c, k, Spectrum::Wanted)
}

/// Which eigenvalues a solve computes besides the wanted ones.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Spectrum {
    /// Every eigenvalue (the QL iteration).
    All,
    /// Only those of the wanted pairs (bisection).
    Wanted,
}

fn solve_symmetric(
    mut c: Mat<f64>,
    k: usize,
    spectrum: Spectrum,
) -> Result<EigenPairs, ModalError> {
    let n = c.nrows();
    let k = k.min(n);
    if n == 0 || k == 0 {
        let all_values = match spectrum {
            Spectrum::All if n > 0 => Some(full_eigen_values(c.as_ref())?),
            Spectrum::All => Some(Vec::new()),
            Spectrum::Wanted => None,
        };
        return Ok(EigenPairs {
            values: Vec::new(),
            vectors: Mat::zeros(n, 0),
            all_values,
        });
    }
    if c.col_iter().any(|col| col.iter().any(|v| !v.is_finite())) {
        return Err(ModalError::NonFiniteResult {
            stage: "the matrix of the eigenproblem",
        });
    }
    let mut pairs = if n < TRIDIAGONAL_MIN_ORDER {
        full_eigen(c.as_ref(), k)?
    } else {
        tridiagonal_route(c.as_mut(), k, spectrum)?
    };
    if spectrum == Spectrum::Wanted {
        pairs.all_values = None;
    }
    Ok(pairs)
}

fn full_eigen(c: MatRef<'_, f64>, k: usize) -> Result<EigenPairs, ModalError> {
    let n = c.nrows();
    let par = Par::Seq;
    let req =
        evd::self_adjoint_evd_scratch::<f64>(n, ComputeEigenvectors::Yes, par, Default::default());
    let mut mem = MemBuffer::new(req);
    let stack = MemStack::new(&mut mem);
    let mut s = faer::diag::Diag::<f64>::zeros(n);
    let mut u = Mat::<f64>::zeros(n, n);
    evd::self_adjoint_evd(
        c,
        s.as_mut(),
        Some(u.as_mut()),
        par,
        stack,
        Default::default(),
    )
    .map_err(|_| ModalError::NotConverged {
        method: "symmetric eigensolver",
    })?;
    let raw: Vec<f64> = (0..n).map(|i| s[i]).collect();
    let order = ascending_order(&raw);
    let mut vectors = Mat::<f64>::zeros(n, k);
    for (dst, &src) in order.iter().take(k).enumerate() {
        vectors.col_mut(dst).copy_from(u.col(src));
    }
    let all_values: Vec<f64> = order.iter().map(|&i| raw[i]).collect();
    let values = all_values[..k].to_vec();
    Ok(EigenPairs {
        values,
        vectors,
        all_values: Some(all_values),
    })
}

fn full_eigen_values(c: MatRef<'_, f64>) -> Result<Vec<f64>, ModalError> {
    let n = c.nrows();
    let par = Par::Seq;
    let req =
        evd::self_adjoint_evd_scratch::<f64>(n, ComputeEigenvectors::No, par, Default::default());
    let mut mem = MemBuffer::new(req);
    let stack = MemStack::new(&mut mem);
    let mut s = faer::diag::Diag::<f64>::zeros(n);
    evd::self_adjoint_evd(c, s.as_mut(), None, par, stack, Default::default()).map_err(|_| {
        ModalError::NotConverged {
            method: "symmetric eigensolver",
        }
    })?;
    let mut v: Vec<f64> = (0..n).map(|i| s[i]).collect();
    v.sort_by(f64::total_cmp);
    Ok(v)
}

fn ascending_order(values: &[f64]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..values.len()).collect();
    order.sort_by(|&a, &b| values[a].total_cmp(&values[b]));
    order
}

fn tridiagonal_route(
    c: MatMut<'_, f64>,
    k: usize,
    spectrum: Spectrum,
) -> Result<EigenPairs, ModalError> {
    let n = c.nrows();
    let t = householder::tridiagonalize(c.rb());
    let (values, all_values) = tridiagonal_values(&t.diag, &t.off, k, spectrum)?;
    let mut u = Mat::<f64>::zeros(n, k);
    tridiagonal_inverse_iteration(&t.diag, &t.off, &values, u.as_mut())?;
    t.apply_q(u.as_mut());
    Ok(EigenPairs {
        values,
        vectors: u,
        all_values,
    })
}

/// The wanted `k` eigenvalues of the tridiagonal matrix, and every eigenvalue when asked.
fn tridiagonal_values(
    diag: &[f64],
    off: &[f64],
    k: usize,
    spectrum: Spectrum,
) -> Result<(Vec<f64>, Option<Vec<f64>>), ModalError> {
    Ok(match spectrum {
        Spectrum::All => {
            let all = tridiagonal_eigenvalues(diag, off)?;
            (all[..k].to_vec(), Some(all))
        }
        Spectrum::Wanted => (bisection::lowest_eigenvalues(diag, off, k), None),
    })
}

/// Eigenvalues (ascending) of the symmetric tridiagonal matrix (`diag`, `off`) without vectors,
/// by the root-free implicit QL iteration of Pal, Walker and Kahan (LAPACK `dsterf`), which works
/// on the squared off-diagonal and needs no square root in its inner loop. The ordinary QL with
/// Givens rotations spent its time in the dependent `sqrt`/division chain and was the largest
/// single cost of a 120-dof partial solve; faer's vector-free tridiagonal QR measured ~4× slower.
fn tridiagonal_eigenvalues(diag: &[f64], off: &[f64]) -> Result<Vec<f64>, ModalError> {
    let n = diag.len();
    // Scaled by a power of two (exact) to a largest entry of about 1, as LAPACK's dsterf scales
    // into a safe range: the iteration works with squared off-diagonals and products of three
    // entries, which over- or underflow for entries beyond about 1e±100.
    let amax = diag.iter().chain(off).fold(0.0f64, |m, v| m.max(v.abs()));
    let exp = if amax > 0.0 && amax.is_finite() {
        (amax.log2().round() as i32).clamp(-1000, 1000)
    } else {
        0
    };
    let (down, up) = (2f64.powi(-exp), 2f64.powi(exp));
    let mut d: Vec<f64> = diag.iter().map(|v| v * down).collect();
    // e[i] = off[i]²; the last slot is a sentinel.
    let mut e = vec![0.0; n];
    for (ei, o) in e.iter_mut().zip(off) {
        *ei = (o * down) * (o * down);
    }
    let eps2 = f64::EPSILON * f64::EPSILON;
    let max_iter = 30 * n.max(1);
    let mut total = 0usize;
    let mut l = 0usize;
    while l < n {
        // Split off the unreduced block starting at l: |off[m]| ≤ eps·(|d[m]| + |d[m+1]|).
        let mut m = l;
        while m + 1 < n {
            let dd = d[m].abs() + d[m + 1].abs();
            if e[m] <= eps2 * dd * dd {
                e[m] = 0.0;
                break;
            }
            m += 1;
        }
        if m == l {
            l += 1;
            continue;
        }
        if m == l + 1 {
            // A 2×2 block: closed form (LAPACK dlae2).
            let (a, b, c) = (d[l], e[l].sqrt(), d[l + 1]);
            let (rt1, rt2) = eig2(a, b, c);
            d[l] = rt1;
            d[l + 1] = rt2;
            e[l] = 0.0;
            l += 2;
            continue;
        }
        total += 1;
        if total > max_iter {
            return Err(ModalError::NotConverged {
                method: "tridiagonal QL iteration",
            });
        }
        // Wilkinson-type shift from the leading 2×2 of the block.
        let p0 = d[l];
        let rte = e[l].sqrt();
        let g = (d[l + 1] - p0) / (2.0 * rte);
        let r = g.hypot(1.0);
        let sigma = p0 - rte / (g + r.copysign(g));
        let (mut c, mut s) = (1.0f64, 0.0f64);
        let mut gamma = d[m] - sigma;
        let mut p = gamma * gamma;
        for i in (l..m).rev() {
            let bb = e[i];
            let r = p + bb;
            if i + 1 != m {
                e[i + 1] = s * r;
            }
            let old_c = c;
            let old_gamma = gamma;
            let alpha = d[i];
            // dsterf's step, rearranged so one division sits on the dependent chain from p to
            // the next p instead of two: with t = p·(α − σ) − e·γ_old (ready while 1/r is being
            // divided) γ = c·(α − σ) − s·γ_old = t/r, and the next p = γ²/c = (t/p)·γ, whose 1/p
            // is divided alongside 1/r. dsterf's own expressions stand in where these are not
            // finite (p → 0, or t beyond range). Measured: a 120-dof partial solve of 30 modes
            // 10 % faster (criterion, five alternating runs: median 665 → 598 µs).
            let inv = 1.0 / r;
            let inv_p = 1.0 / p;
            let t = p * (alpha - sigma) - bb * old_gamma;
            c = p * inv;
            s = bb * inv;
            gamma = if t.is_finite() {
                t * inv
            } else {
                c * (alpha - sigma) - s * old_gamma
            };
            d[i + 1] = old_gamma + (alpha - gamma);
            p = if c != 0.0 {
                let next = (t * inv_p) * gamma;
                if next.is_finite() {
                    next
                } else {
                    gamma * gamma / c
                }
            } else {
                old_c * bb
            };
        }
        e[l] = s * p;
        d[l] = sigma + gamma;
    }
    if d.iter().any(|v| !v.is_finite()) {
        return Err(ModalError::NonFiniteResult {
            stage: "the tridiagonal eigenvalues",
        });
    }
    for v in d.iter_mut() {
        *v *= up;
    }
    d.sort_by(f64::total_cmp);
    Ok(d)
}

/// Eigenvalues `(larger, smaller)` of the symmetric 2×2 matrix `[[a, b], [b, c]]` (LAPACK dlae2).
fn eig2(a: f64, b: f64, c: f64) -> (f64, f64) {
    let sm = a + c;
    let adf = (a - c).abs();
    let ab = 2.0 * b.abs();
    let (acmx, acmn) = if a.abs() > c.abs() { (a, c) } else { (c, a) };
    let rt = if adf > ab {
        adf * (1.0 + (ab / adf).powi(2)).sqrt()
    } else if adf < ab {
        ab * (1.0 + (adf / ab).powi(2)).sqrt()
    } else {
        ab * std::f64::consts::SQRT_2
    };
    if sm < 0.0 {
        let rt1 = 0.5 * (sm - rt);
        (rt1, (acmx / rt1) * acmn - (b / rt1) * b)
    } else if sm > 0.0 {
        let rt1 = 0.5 * (sm + rt);
        (rt1, (acmx / rt1) * acmn - (b / rt1) * b)
    } else {
        (0.5 * rt, -0.5 * rt)
    }
}

/// Eigenvectors of the symmetric tridiagonal matrix (`diag`, `off`) for the given ascending
/// eigenvalues, by inverse iteration with Gram–Schmidt inside clusters (after LAPACK `dstein`).
/// Compiled for the widest vector unit this CPU has (the interleaved lanes fill it); the same
/// operations in the same order on every path, so the same vectors.
fn tridiagonal_inverse_iteration(
    diag: &[f64],
    off: &[f64],
    values: &[f64],
    out: MatMut<'_, f64>,
) -> Result<(), ModalError> {
    dispatch(InverseIteration {
        diag,
        off,
        values,
        out,
    })
}

/// The arguments of [`tridiagonal_inverse_iteration`], run by [`dispatch`]: one portable body
/// compiled for each unit.
struct InverseIteration<'a> {
    diag: &'a [f64],
    off: &'a [f64],
    values: &'a [f64],
    out: MatMut<'a, f64>,
}

impl Kernel for InverseIteration<'_> {
    type Output = Result<(), ModalError>;
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn avx512(self, _: pulp::x86::V4) -> Self::Output {
        inverse_iteration_body(self.diag, self.off, self.values, self.out)
    }
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn avx2(self, _: pulp::x86::V3) -> Self::Output {
        inverse_iteration_body(self.diag, self.off, self.values, self.out)
    }
    #[inline(always)]
    fn baseline(self) -> Self::Output {
        inverse_iteration_body(self.diag, self.off, self.values, self.out)
    }
}

#[inline(always)]
fn inverse_iteration_body(
    diag: &[f64],
    off: &[f64],
    values: &[f64],
    mut out: MatMut<'_, f64>,
) -> Result<(), ModalError> {
    let n = diag.len();
    let eps = f64::EPSILON;
    let mut norm1 = 0.0f64;
    for i in 0..n {
        let mut r = diag[i].abs();
        if i > 0 {
            r += off[i - 1].abs();
        }
        if i + 1 < n {
            r += off[i].abs();
        }
        norm1 = norm1.max(r);
    }
    if norm1 == 0.0 {
        for (j, _) in values.iter().enumerate() {
            out[(j, j)] = 1.0;
        }
        return Ok(());
    }
    // LAPACK dstein groups eigenvalues closer than 1e-3·‖T‖; the low end of a modal spectrum
    // is then one huge cluster and Gram–Schmidt costs O(n k²). Inverse iteration leaves an
    // error of about eps·‖T‖/gap along a neighbour at distance `gap`, so 1e-6·‖T‖ keeps every
    // pair orthogonal to ~2e-10 while clustering only (near-)degenerate eigenvalues.
    let ortol = 1e-6 * norm1;
    let pertol = 10.0 * eps * norm1;
    let tiny = eps * norm1;

    let mut lu = TridiagLu::<1>::new(n);
    let mut xl = vec![[0.0]; n];
    // Scratch of the interleaved lanes, reused by every run of singletons.
    let mut lanes_lu = TridiagLu::<LANES>::new(n);
    let mut lanes_x = vec![[0.0; LANES]; n];
    let mut vecs = vec![0.0; n * values.len()];
    let mut seed: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut cluster_start = 0usize;
    let mut prev_shift = f64::NEG_INFINITY;

    let k = values.len();
    // An eigenvalue far from both neighbours needs no Gram–Schmidt: runs of such singletons are
    // solved LANES at a time, interleaved, so the dependent chains of the tridiagonal LU and of
    // the substitutions (latency-bound, one vector at a time) overlap.
    let singleton = |j: usize| {
        (j == 0 || (values[j] - values[j - 1]).abs() > ortol)
            && (j + 1 == k || (values[j + 1] - values[j]).abs() > ortol)
    };
    let mut j = 0;
    while j < k {
        if singleton(j) {
            let mut b = 1;
            while b < LANES && j + b < k && singleton(j + b) {
                b += 1;
            }
            inverse_iteration_lanes(
                diag,
                off,
                &values[j..j + b],
                norm1,
                &mut seed,
                (&mut lanes_lu, &mut lanes_x),
                &mut vecs[j * n..(j + b) * n],
            )?;
            j += b;
            continue;
        }
        let lam = values[j];
        if j > 0 && (lam - values[j - 1]).abs() > ortol {
            cluster_start = j;
        }
        // Distinct shifts for equal eigenvalues give independent start directions.
        let mut shift = lam;
        if j > cluster_start && shift - prev_shift < pertol {
            shift = prev_shift + pertol;
        }
        prev_shift = shift;

        lu.factor(diag, off, [shift], tiny);
        for v in xl.iter_mut() {
            v[0] = random_start(&mut seed);
        }
        let mut converged = false;
        for _ in 0..6 {
            // Gram–Schmidt against the cluster's previous vectors, then one solve.
            orthogonalise(&mut xl, &vecs[cluster_start * n..j * n]);
            let scale = xl.iter().fold(0.0f64, |m, v| m.max(v[0].abs()));
            if scale == 0.0 {
                break;
            }
            for v in xl.iter_mut() {
                v[0] /= scale;
            }
            lu.solve(&mut xl);
            let growth = xl.iter().fold(0.0f64, |m, v| m.max(v[0].abs()));
            if !growth.is_finite() {
                return Err(ModalError::NonFiniteResult {
                    stage: "inverse iteration",
                });
            }
            // dstein's acceptance test: a growth of 1/(√n·eps·‖T‖) means the residual is at
            // round-off level; one extra step after acceptance polishes it.
            if converged {
                break;
            }
            if growth * (n as f64).sqrt() * eps * norm1 >= 1.0 / (n as f64).sqrt() {
                converged = true;
            }
        }
        orthogonalise(&mut xl, &vecs[cluster_start * n..j * n]);
        let nrm = xl.iter().map(|v| v[0] * v[0]).sum::<f64>().sqrt();
        if !(nrm > 0.0 && nrm.is_finite()) {
            return Err(ModalError::NonFiniteResult {
                stage: "inverse iteration",
            });
        }
        for i in 0..n {
            vecs[j * n + i] = xl[i][0] / nrm;
        }
        j += 1;
    }
    for j in 0..values.len() {
        for i in 0..n {
            out[(i, j)] = vecs[j * n + i];
        }
    }
    Ok(())
}

/// Next entry of an inverse-iteration start vector, uniform in [−0.5, 0.5) (a 64-bit LCG, so the
/// eigenvectors are reproducible run to run). The eigen tests draw their matrices from it too.
fn random_start(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
}

/// Removes from `x` its components along the orthonormal columns stored one after another in
/// `cols` (classical Gram–Schmidt, as `dstein` does inside a cluster).
fn orthogonalise(x: &mut [[f64; 1]], cols: &[f64]) {
    let n = x.len();
    for col in cols.chunks_exact(n) {
        let dot: f64 = col.iter().zip(x.iter()).map(|(a, b)| a * b[0]).sum();
        for (xi, ci) in x.iter_mut().zip(col) {
            xi[0] -= dot * ci;
        }
    }
}

/// LU factorisations with partial pivoting of `T − shift_l I` for `L` shifts at once (LAPACK
/// `dgttrf` / `dgttrs`), interleaved lane by lane: with `L > 1` the dependent chains of several
/// shifts overlap; `L = 1` is the plain one-vector factorisation.
struct TridiagLu<const L: usize> {
    dd: Vec<[f64; L]>,
    /// `1 / dd`: the substitutions run up to six times per vector, so multiply, not divide.
    rd: Vec<[f64; L]>,
    du: Vec<[f64; L]>,
    du2: Vec<[f64; L]>,
    dl: Vec<[f64; L]>,
    piv: Vec<[bool; L]>,
}

impl<const L: usize> TridiagLu<L> {
    fn new(n: usize) -> Self {
        Self {
            dd: vec![[0.0; L]; n],
            rd: vec![[0.0; L]; n],
            du: vec![[0.0; L]; n],
            du2: vec![[0.0; L]; n],
            dl: vec![[0.0; L]; n],
            piv: vec![[false; L]; n],
        }
    }

    /// Factors `T − shift I` (T = `diag`, `off`) in place of any previous factorisation; pivots
    /// smaller than `tiny` are replaced by `±tiny` (a shift on an eigenvalue is singular).
    #[inline(always)]
    fn factor(&mut self, diag: &[f64], off: &[f64], shift: [f64; L], tiny: f64) {
        let n = diag.len();
        let (dd, rd, du, du2, dl, piv) = (
            &mut self.dd[..n],
            &mut self.rd[..n],
            &mut self.du[..n],
            &mut self.du2[..n],
            &mut self.dl[..n],
            &mut self.piv[..n],
        );
        for i in 0..n {
            for l in 0..L {
                dd[i][l] = diag[i] - shift[l];
            }
            du2[i] = [0.0; L];
            piv[i] = [false; L];
        }
        for i in 0..n.saturating_sub(1) {
            du[i] = [off[i]; L];
            dl[i] = [off[i]; L];
        }
        for i in 0..n.saturating_sub(1) {
            // dgttrf's step without branches (lane-wise selects, which vectorise): pivot when
            // the sub-diagonal entry is the larger. The same operations as the branches would
            // do, so the same factors.
            // Whole lane arrays in and out: the shape the compiler turns into vector code.
            let (d, lo, up, next) = (dd[i], dl[i], du[i], dd[i + 1]);
            let un = if i + 2 < n { du[i + 1] } else { [0.0; L] };
            let (mut nd, mut nf, mut nu, mut nnext, mut ndu2, mut nun) =
                ([0.0; L], [0.0; L], [0.0; L], [0.0; L], [0.0; L], [0.0; L]);
            let mut swaps = [false; L];
            for l in 0..L {
                let swap = d[l].abs() < lo[l].abs();
                // Without a pivot a zero diagonal is replaced by `tiny` (a singular shift).
                let dl_ = if !swap && d[l] == 0.0 { tiny } else { d[l] };
                let (num, den) = if swap { (dl_, lo[l]) } else { (lo[l], dl_) };
                let f = num / den;
                swaps[l] = swap;
                nd[l] = den;
                nf[l] = f;
                nu[l] = if swap { next[l] } else { up[l] };
                nnext[l] = if swap {
                    up[l] - f * next[l]
                } else {
                    next[l] - f * up[l]
                };
                ndu2[l] = if swap { un[l] } else { 0.0 };
                nun[l] = if swap { -f * un[l] } else { un[l] };
            }
            (piv[i], dd[i], dl[i], du[i], dd[i + 1]) = (swaps, nd, nf, nu, nnext);
            if i + 2 < n {
                (du2[i], du[i + 1]) = (ndu2, nun);
            }
        }
        for i in 0..n {
            for l in 0..L {
                let v = &mut dd[i][l];
                if v.abs() < tiny {
                    *v = if *v < 0.0 { -tiny } else { tiny };
                }
                rd[i][l] = 1.0 / *v;
            }
        }
    }

    /// Overwrites `x` (one column per lane) with `(T − shift I)⁻¹ x`.
    #[inline(always)]
    fn solve(&self, x: &mut [[f64; L]]) {
        let n = x.len();
        // Views of the length of `x`: lets the compiler drop the bounds checks in the chains.
        let (rd, du, du2, dl, piv) = (
            &self.rd[..n],
            &self.du[..n],
            &self.du2[..n],
            &self.dl[..n],
            &self.piv[..n],
        );
        for i in 0..n.saturating_sub(1) {
            for l in 0..L {
                let (a, c) = (x[i][l], x[i + 1][l]);
                let p = piv[i][l];
                x[i][l] = if p { c } else { a };
                x[i + 1][l] = if p {
                    a - dl[i][l] * c
                } else {
                    c - dl[i][l] * a
                };
            }
        }
        for l in 0..L {
            x[n - 1][l] *= rd[n - 1][l];
            if n > 1 {
                x[n - 2][l] = (x[n - 2][l] - du[n - 2][l] * x[n - 1][l]) * rd[n - 2][l];
            }
        }
        for i in (0..n.saturating_sub(2)).rev() {
            for l in 0..L {
                x[i][l] = (x[i][l] - du[i][l] * x[i + 1][l] - du2[i][l] * x[i + 2][l]) * rd[i][l];
            }
        }
    }
}

/// Interleaved inverse-iteration lanes of [`tridiagonal_inverse_iteration`]: one AVX-512
/// register, two AVX2 registers.
const LANES: usize = 8;

/// Eigenvectors for up to [`LANES`] well-separated eigenvalues at once (no Gram–Schmidt needed):
/// the same LU with partial pivoting, substitutions and acceptance test as the one-vector path,
/// with the lanes interleaved in every loop. Unused lanes repeat the last shift. `scratch` is
/// overwritten.
#[inline(always)]
fn inverse_iteration_lanes(
    diag: &[f64],
    off: &[f64],
    values: &[f64],
    norm1: f64,
    seed: &mut u64,
    scratch: (&mut TridiagLu<LANES>, &mut [[f64; LANES]]),
    out: &mut [f64],
) -> Result<(), ModalError> {
    const L: usize = LANES;
    let n = diag.len();
    let b = values.len();
    let eps = f64::EPSILON;
    let tiny = eps * norm1;
    let mut shift = [0.0; L];
    for (l, s) in shift.iter_mut().enumerate() {
        *s = values[l.min(b - 1)];
    }
    let (lu, x) = scratch;
    lu.factor(diag, off, shift, tiny);
    for l in 0..b {
        for xi in x.iter_mut() {
            xi[l] = random_start(seed);
        }
    }
    for l in b..L {
        for xi in x.iter_mut() {
            xi[l] = xi[0];
        }
    }
    let accept = 1.0 / ((n as f64).sqrt() * (n as f64).sqrt() * eps * norm1);
    let mut converged = [false; L];
    let mut polished = [false; L];
    for _ in 0..6 {
        let mut scale = [0.0f64; L];
        for xi in x.iter() {
            for l in 0..L {
                scale[l] = scale[l].max(xi[l].abs());
            }
        }
        if scale.contains(&0.0) {
            return Err(ModalError::NonFiniteResult {
                stage: "inverse iteration",
            });
        }
        let inv = scale.map(|v| 1.0 / v);
        for xi in x.iter_mut() {
            for l in 0..L {
                xi[l] *= inv[l];
            }
        }
        lu.solve(x);
        let mut growth = [0.0f64; L];
        for xi in x.iter() {
            for l in 0..L {
                growth[l] = growth[l].max(xi[l].abs());
            }
        }
        if growth.iter().any(|g| !g.is_finite()) {
            return Err(ModalError::NonFiniteResult {
                stage: "inverse iteration",
            });
        }
        // As in the one-vector path: accept at round-off growth, then polish once more. A lane
        // that is done keeps iterating with the others, which only polishes it further.
        for l in 0..L {
            if converged[l] {
                polished[l] = true;
            } else if growth[l] >= accept {
                converged[l] = true;
            }
        }
        if polished.iter().all(|&p| p) {
            break;
        }
    }
    for l in 0..b {
        let nrm = x.iter().map(|xi| xi[l] * xi[l]).sum::<f64>().sqrt();
        if !(nrm > 0.0 && nrm.is_finite()) {
            return Err(ModalError::NonFiniteResult {
                stage: "inverse iteration",
            });
        }
        for i in 0..n {
            out[l * n + i] = x[i][l] / nrm;
        }
    }
    Ok(())
}

/// Eigenvalues and eigenvectors of a dense generalized problem ([`generalized_eigh`]).
#[derive(Debug, Clone, PartialEq)]
pub struct EigenSolution {
    /// The computed eigenvalues, ascending.
    pub values: Vec<f64>,
    /// Order of the problem (length of an eigenvector).
    order: usize,
    /// The eigenvectors, column-major: vector `j` at `j·order ..`.
    vectors: Vec<f64>,
}

impl EigenSolution {
    /// Order of the problem: the length of each eigenvector.
    pub fn order(&self) -> usize {
        self.order
    }

    /// Eigenvector `j` (of `values[j]`), `M`-normalised.
    ///
    /// # Panics
    /// When `j >= values.len()`.
    pub fn vector(&self, j: usize) -> &[f64] {
        &self.vectors[j * self.order..(j + 1) * self.order]
    }

    /// Every eigenvector, one after the other (`order × values.len()` column-major).
    pub fn vectors_column_major(&self) -> &[f64] {
        &self.vectors
    }
}

/// The eigenpairs of `K x = λ M x` for dense symmetric `K` and symmetric positive definite `M`,
/// both `n × n` row-major (like `scipy.linalg.eigh(K, M)`): eigenvalues ascending, eigenvectors
/// with `xᵀ M x = 1`. Only the lower triangles are read (the upper ones may hold anything
/// finite). `n_modes` computes only the lowest ones (much faster).
///
/// ```
/// use modal_core::generalized_eigh;
/// let k = [2.0, 0.0, 0.0, 8.0];
/// let m = [2.0, 0.0, 0.0, 2.0];
/// let e = generalized_eigh(&k, &m, 2, None).unwrap();
/// assert!((e.values[0] - 1.0).abs() < 1e-12 && (e.values[1] - 4.0).abs() < 1e-12);
/// // M-normalised: xᵀ M x = 2 x₀² = 1.
/// assert!((e.vector(0)[0].abs() - 0.5f64.sqrt()).abs() < 1e-12);
/// ```
///
/// # Errors
/// [`ModalError::SizeMismatch`] for slices that are not `n × n`; [`ModalError::Option`] for
/// `n_modes` outside `1..=n`; [`ModalError::NotPositiveDefinite`] when `M` is not positive
/// definite; [`ModalError::NonFiniteResult`] for NaN or infinite entries.
pub fn generalized_eigh(
    k: &[f64],
    m: &[f64],
    n: usize,
    n_modes: Option<usize>,
) -> Result<EigenSolution, ModalError> {
    for (what, found) in [("entries of K", k.len()), ("entries of M", m.len())] {
        if found != n * n {
            return Err(ModalError::SizeMismatch {
                what,
                expected: n * n,
                found,
            });
        }
    }
    if let Some(j) = n_modes.filter(|&j| j == 0 || j > n) {
        return Err(crate::OptionError::new("n_modes", j, format!("an integer in 1..={n}")).into());
    }
    let pairs = generalized_eigen(
        MatRef::from_row_major_slice(k, n, n),
        MatRef::from_row_major_slice(m, n, n),
        n_modes,
    )?;
    let v = &pairs.vectors;
    let vectors = (0..v.ncols())
        .flat_map(|j| (0..n).map(move |i| v[(i, j)]))
        .collect();
    Ok(EigenSolution {
        values: pairs.values,
        order: n,
        vectors,
    })
}

/// Generalized symmetric-definite eigenpairs `K x = λ B x`, ascending, `xᵀ B x = I`.
/// Only the lower triangles of `k` and `b` are read. `n_modes` limits the number of pairs.
pub fn generalized_eigen(
    k: MatRef<'_, f64>,
    b: MatRef<'_, f64>,
    n_modes: Option<usize>,
) -> Result<EigenPairs, ModalError> {
    let n = k.nrows();
    for (what, found) in [
        ("columns of K", k.ncols()),
        ("rows of B", b.nrows()),
        ("columns of B", b.ncols()),
    ] {
        if found != n {
            return Err(ModalError::SizeMismatch {
                what,
                expected: n,
                found,
            });
        }
    }
    let mut l = Mat::<f64>::zeros(n, n);
    l.copy_from_triangular_lower(b);
    cholesky_in_place(l.as_mut()).map_err(|i| ModalError::NotPositiveDefinite {
        matrix: "M",
        pivot: Some(i),
    })?;
    let mut c = Mat::<f64>::from_fn(n, n, |i, j| if i >= j { k[(i, j)] } else { k[(j, i)] });
    congruence_inverse(l.as_ref(), c.as_mut());
    let mut pairs = symmetric_eigen(c, n_modes)?;
    solve_lower_transpose(l.as_ref(), pairs.vectors.as_mut());
    Ok(pairs)
}

/// `C = (I_d ⊗ L)⁻¹ K (I_d ⊗ L)⁻ᵀ` for a `d·n × d·n` matrix `K` (full storage, symmetric) and the
/// Cholesky factor `L` of the `n × n` diagonal block of a block-diagonal `B = I_d ⊗ L Lᵀ`.
/// Only `d(d+1)/2` block congruences with the `n × n` factor are needed instead of one with the
/// `dn × dn` factor (docs/method.md §4.1, block form). `C` is returned with full symmetric storage.
pub fn block_congruence(k: MatRef<'_, f64>, l: MatRef<'_, f64>, dim: usize) -> Mat<f64> {
    let n = l.nrows();
    let mut c = k.to_owned();
    for a in 0..dim {
        congruence_inverse(l, c.as_mut().submatrix_mut(a * n, a * n, n, n));
        for b in (a + 1)..dim {
            // C_ba = L⁻¹ K_ba L⁻ᵀ = L⁻¹ (L⁻¹ K_baᵀ)ᵀ = L⁻¹ (L⁻¹ K_ab)ᵀ, and C_ab = C_baᵀ.
            solve_lower(l, c.as_mut().submatrix_mut(a * n, b * n, n, n));
            for j in 0..n {
                for i in 0..n {
                    c[(b * n + i, a * n + j)] = c[(a * n + j, b * n + i)];
                }
            }
            solve_lower(l, c.as_mut().submatrix_mut(b * n, a * n, n, n));
            for j in 0..n {
                for i in 0..n {
                    c[(a * n + j, b * n + i)] = c[(b * n + i, a * n + j)];
                }
            }
        }
    }
    c
}

/// `X ← (I_d ⊗ L)⁻ᵀ X` for a `d·n × k` matrix `X`.
pub fn block_solve_lower_transpose(l: MatRef<'_, f64>, mut x: MatMut<'_, f64>, dim: usize) {
    let n = l.nrows();
    for a in 0..dim {
        solve_lower_transpose(l, x.rb_mut().subrows_mut(a * n, n));
    }
}

/// Column `j` of an owned matrix as a slice (an owned faer matrix is column-major).
pub(crate) fn column(m: &Mat<f64>, j: usize) -> &[f64] {
    m.col(j)
        .try_as_col_major()
        .expect("the columns of a dense matrix are contiguous")
        .as_slice()
}

/// Column `j` of an owned matrix as a mutable slice.
pub(crate) fn column_mut(m: &mut Mat<f64>, j: usize) -> &mut [f64] {
    m.col_mut(j)
        .try_as_col_major_mut()
        .expect("the columns of a dense matrix are contiguous")
        .as_slice_mut()
}

/// Flips every column so that its largest-|·| entry is positive. Entries within a relative
/// 10⁻⁶ of the largest count as ties (symmetric shapes produce exact ties up to round-off),
/// and the first of them decides: the rule is then stable under round-off.
pub fn canonical_signs(mut v: MatMut<'_, f64>) {
    for j in 0..v.ncols() {
        let mut col = v.rb_mut().col_mut(j);
        // A column of a column-major matrix is contiguous; a strided one goes through a copy.
        if let Some(slice) = col.rb_mut().try_as_col_major_mut() {
            canonical_sign(slice.as_slice_mut());
            continue;
        }
        let mut copy: Vec<f64> = col.rb().iter().copied().collect();
        canonical_sign(&mut copy);
        for (x, c) in col.iter_mut().zip(copy) {
            *x = c;
        }
    }
}

/// [`canonical_signs`] of one column: the sign rule of every eigenvector this crate returns
/// (the dense solver's and the 3 × 3 principal axes' of `geometry`), so that a vector's sign is
/// reproducible however it was computed.
pub(crate) fn canonical_sign(col: &mut [f64]) {
    let best = crate::simd::max_abs(col);
    let first = col.iter().find(|x| x.abs() >= best * (1.0 - 1e-6));
    if first.is_some_and(|&x| x < 0.0) {
        col.iter_mut().for_each(|x| *x = -*x);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn canonical_signs_flip_by_the_first_largest_entry_in_any_layout() {
        // Column 0: largest |·| negative, flipped. Column 1: a tie within 1e-6 whose first entry
        // is positive, kept. Column 2: a tie whose first entry is negative, flipped. Column 3:
        // zeros, kept.
        let cols = [
            [0.5, -2.0, 1.0, 0.0],
            [2.0, -1.0, -2.0 * (1.0 - 1e-7), 0.3],
            [0.1, -3.0, 3.0, -1.0],
            [0.0, 0.0, 0.0, 0.0],
        ];
        let want = [
            [-0.5, 2.0, -1.0, -0.0],
            cols[1],
            [-0.1, 3.0, -3.0, 1.0],
            cols[3],
        ];
        // Column-major: contiguous columns.
        let mut v = Mat::<f64>::from_fn(4, 4, |i, j| cols[j][i]);
        canonical_signs(v.as_mut());
        // The transpose of a row-major copy: columns with a stride.
        let mut t = Mat::<f64>::from_fn(4, 4, |i, j| cols[i][j]);
        canonical_signs(t.as_mut().transpose_mut());
        for j in 0..4 {
            for i in 0..4 {
                assert_eq!(
                    v[(i, j)].to_bits(),
                    want[j][i].to_bits(),
                    "contiguous ({i}, {j})"
                );
                assert_eq!(
                    t[(j, i)].to_bits(),
                    want[j][i].to_bits(),
                    "strided ({i}, {j})"
                );
            }
        }
    }

    #[test]
    fn lowest_pairs_of_the_path_laplacian() {
        // The path-graph Laplacian: eigenvalues 2 − 2cos(jπ/n), j = 0 … n−1.
        let n = 40;
        let c = Mat::<f64>::from_fn(n, n, |i, j| match (i, j) {
            _ if i == j => {
                if i == 0 || i == n - 1 {
                    1.0
                } else {
                    2.0
                }
            }
            _ if i.abs_diff(j) == 1 => -1.0,
            _ => 0.0,
        });
        let pairs = symmetric_eigen_lowest(c, 3).unwrap();
        for (j, v) in pairs.values.iter().enumerate() {
            let exact = 2.0 - 2.0 * (j as f64 * std::f64::consts::PI / n as f64).cos();
            assert!((v - exact).abs() < 1e-13);
        }
        assert!(pairs.all_values.is_none());
    }

    fn random_spd(n: usize, seed: u64, shift: f64) -> Mat<f64> {
        let mut s = seed;
        let mut next = || random_start(&mut s);
        let a = Mat::<f64>::from_fn(n, n, |_, _| next());
        let mut m = &a * a.transpose();
        for i in 0..n {
            m[(i, i)] += shift;
        }
        m
    }

    fn check_pairs(c: &Mat<f64>, p: &EigenPairs, tol: f64) {
        let n = c.nrows();
        let k = p.values.len();
        let r = c * &p.vectors
            - &p.vectors * faer::Mat::from_fn(k, k, |i, j| if i == j { p.values[i] } else { 0.0 });
        let scale = (0..n).map(|i| c[(i, i)].abs()).fold(0.0, f64::max);
        assert!(
            r.norm_max() < tol * scale * n as f64,
            "residual {}",
            r.norm_max()
        );
        let g = p.vectors.transpose() * &p.vectors;
        for i in 0..k {
            for j in 0..k {
                let e = if i == j { 1.0 } else { 0.0 };
                assert!(
                    (g[(i, j)] - e).abs() < 1e-10,
                    "orthogonality {i} {j} {}",
                    g[(i, j)]
                );
            }
        }
        for w in p.values.windows(2) {
            assert!(w[0] <= w[1]);
        }
    }

    #[test]
    fn partial_matches_full() {
        for &(n, seed) in &[(40usize, 1u64), (97, 2), (150, 3)] {
            let c = random_spd(n, seed, 0.0);
            let full = symmetric_eigen(c.clone(), None).unwrap();
            check_pairs(&c, &full, 1e-13);
            let k = n / 4;
            let part = symmetric_eigen(c.clone(), Some(k)).unwrap();
            check_pairs(&c, &part, 1e-13);
            let lowest = symmetric_eigen_lowest(c.clone(), k).unwrap();
            check_pairs(&c, &lowest, 1e-13);
            assert!(lowest.all_values.is_none());
            assert_eq!(full.all_values.as_ref().map(Vec::len), Some(n));
            for i in 0..k {
                assert!((full.values[i] - part.values[i]).abs() < 1e-11 * full.values[n - 1]);
                assert!((full.values[i] - lowest.values[i]).abs() < 1e-12 * full.values[n - 1]);
            }
        }
    }

    #[test]
    fn root_free_ql_matches_dense_eigenvalues() {
        let mut seed = 11u64;
        let mut rnd = || random_start(&mut seed);
        let mut cases: Vec<(Vec<f64>, Vec<f64>)> = Vec::new();
        for n in [1usize, 2, 3, 7, 60, 121] {
            cases.push((
                (0..n).map(|_| rnd()).collect(),
                (1..n).map(|_| rnd()).collect(),
            ));
        }
        // Path-graph Laplacian (one zero eigenvalue), Wilkinson W21+, split blocks, graded.
        let n = 50;
        let mut d = vec![2.0; n];
        d[0] = 1.0;
        d[n - 1] = 1.0;
        cases.push((d, vec![-1.0; n - 1]));
        cases.push((
            (0..21).map(|i| (10.0f64 - i as f64).abs()).collect(),
            vec![1.0; 20],
        ));
        let mut off: Vec<f64> = (1..40).map(|_| rnd()).collect();
        off[9] = 0.0;
        off[10] = 0.0;
        off[30] = 0.0;
        cases.push(((0..40).map(|_| rnd()).collect(), off));
        cases.push((
            (0..30).map(|i| 10f64.powi(i / 3 - 5)).collect(),
            (1..30).map(|i| 10f64.powi(i / 3 - 6)).collect(),
        ));
        cases.push((vec![3.0; 25], vec![0.0; 24]));
        // Entries near the ends of the exponent range: the step's products of three entries
        // over- or underflow unless the matrix is scaled first (without the scaling neither
        // case converged).
        for scale in [1e150, 1e-150] {
            cases.push((
                (0..33).map(|_| scale * rnd()).collect(),
                (1..33).map(|_| scale * rnd()).collect(),
            ));
        }
        for (d, e) in cases {
            let n = d.len();
            let dense = Mat::<f64>::from_fn(n, n, |i, j| {
                if i == j {
                    d[i]
                } else if i == j + 1 {
                    e[j]
                } else if j == i + 1 {
                    e[i]
                } else {
                    0.0
                }
            });
            let want = full_eigen_values(dense.as_ref()).unwrap();
            let got = tridiagonal_eigenvalues(&d, &e).unwrap();
            let scale = want.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
            for (g, w) in got.iter().zip(&want) {
                assert!((g - w).abs() <= 1e-13 * scale, "n = {n}: {g} vs {w}");
            }
        }
    }

    #[test]
    fn partial_handles_degenerate_clusters() {
        // Block diagonal with repeated eigenvalues: a diagonal of repeated values, rotated.
        let n = 60;
        let q = {
            let a = random_spd(n, 7, 1.0);
            let qr = a.qr();
            qr.compute_Q()
        };
        let d = Mat::<f64>::from_fn(n, n, |i, j| if i == j { (i / 4) as f64 } else { 0.0 });
        let c = &q * &d * q.transpose();
        let mut c = c.clone();
        symmetrise(c.as_mut());
        for part in [
            symmetric_eigen(c.clone(), Some(12)).unwrap(),
            symmetric_eigen_lowest(c.clone(), 12).unwrap(),
        ] {
            check_pairs(&c, &part, 1e-13);
            for i in 0..12 {
                assert!((part.values[i] - (i / 4) as f64).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn every_inverse_iteration_path_gives_the_same_bits() {
        // Singletons and a cluster (a split matrix with two equal blocks).
        let mut seed = 7u64;
        let mut next = || random_start(&mut seed);
        let half: Vec<f64> = (0..30).map(|_| 4.0 * next()).collect();
        let offs: Vec<f64> = (0..29).map(|_| next()).collect();
        let diag: Vec<f64> = half.iter().chain(&half).copied().collect();
        let off: Vec<f64> = offs.iter().chain(&[0.0]).chain(&offs).copied().collect();
        let values = bisection::lowest_eigenvalues(&diag, &off, 25);
        let run = |kernel: &dyn Fn(MatMut<'_, f64>) -> Result<(), ModalError>| {
            let mut out = Mat::<f64>::zeros(diag.len(), values.len());
            kernel(out.as_mut()).unwrap();
            out
        };
        let (d, o, v) = (&diag[..], &off[..], &values[..]);
        fn kernel<'a>(
            diag: &'a [f64],
            off: &'a [f64],
            values: &'a [f64],
            out: MatMut<'a, f64>,
        ) -> InverseIteration<'a> {
            InverseIteration {
                diag,
                off,
                values,
                out,
            }
        }
        let baseline = run(&|out| kernel(d, o, v, out).baseline());
        assert!(baseline.norm_max() > 0.5);
        assert_eq!(
            baseline,
            run(&|out| tridiagonal_inverse_iteration(d, o, v, out))
        );
        #[cfg(target_arch = "x86_64")]
        {
            if let Some(simd) = pulp::x86::V3::try_new() {
                let got = run(&|out| crate::simd::on_avx2(simd, kernel(d, o, v, out)));
                assert_eq!(baseline, got, "AVX2");
            }
            if let Some(simd) = pulp::x86::V4::try_new() {
                let got = run(&|out| crate::simd::on_avx512(simd, kernel(d, o, v, out)));
                assert_eq!(baseline, got, "AVX-512");
            }
        }
    }

    #[test]
    fn interleaved_lanes_and_clusters_mix() {
        // Singleton runs of every length 1..=5 (lanes partly filled) separated by clusters of
        // 2 and 3 equal eigenvalues, for the full spectrum and for partial counts.
        let mut vals = Vec::new();
        let mut v = 0.0;
        for run in 1..=5 {
            for _ in 0..run {
                v += 1.0;
                vals.push(v);
            }
            v += 1.0;
            for _ in 0..(2 + run % 2) {
                vals.push(v);
            }
        }
        let n = vals.len();
        let q = random_spd(n, 5, 1.0).qr().compute_Q();
        let d = Mat::<f64>::from_fn(n, n, |i, j| if i == j { vals[i] } else { 0.0 });
        let mut c = &q * &d * q.transpose();
        symmetrise(c.as_mut());
        for k in [n, 7, 13] {
            for p in [
                symmetric_eigen(c.clone(), Some(k)).unwrap(),
                symmetric_eigen_lowest(c.clone(), k).unwrap(),
            ] {
                check_pairs(&c, &p, 1e-12);
                for i in 0..k {
                    assert!((p.values[i] - vals[i]).abs() < 1e-12, "k = {k}, value {i}");
                }
            }
        }
    }

    #[test]
    fn generalized_is_mass_normalised() {
        let n = 30;
        let k = random_spd(n, 11, 0.0);
        let b = random_spd(n, 12, 1.0);
        for modes in [None, Some(7)] {
            let p = generalized_eigen(k.as_ref(), b.as_ref(), modes).unwrap();
            let x = &p.vectors;
            let xbx = x.transpose() * &b * x;
            let xkx = x.transpose() * &k * x;
            for i in 0..x.ncols() {
                for j in 0..x.ncols() {
                    let e = if i == j { 1.0 } else { 0.0 };
                    assert!((xbx[(i, j)] - e).abs() < 1e-10);
                    let l = if i == j { p.values[i] } else { 0.0 };
                    assert!((xkx[(i, j)] - l).abs() < 1e-9 * p.values.last().unwrap().abs());
                }
            }
        }
        let not_pd = Mat::<f64>::from_fn(n, n, |i, j| if i == j { -1.0 } else { 0.0 });
        assert!(generalized_eigen(k.as_ref(), not_pd.as_ref(), None).is_err());
    }
}
