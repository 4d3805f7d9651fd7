//! Householder tridiagonalisation `A = Q T Qᵀ` of a symmetric matrix, and `Y ← Q Y`.
//!
//! LAPACK's `dsytd2` (lower) with its two sweeps over the trailing matrix per step — the rank-2
//! update of one step and the symmetric product of the next — fused into one, as faer does; but
//! four columns at a time, so the row vectors of the sweep are loaded once for four columns and
//! the dot products of four columns are summed across lanes together. At the orders of a modal
//! solve (100–300) faer's one-column sweep spends most of its time outside its inner loop; this
//! one runs 3–4× faster there (BENCHMARKS.md, "Eigensolver").

use faer::{MatMut, MatRef};

use crate::simd::{dispatch, dot, Kernel};

/// The tridiagonal matrix of [`tridiagonalize`] and the reflectors that produced it.
#[derive(Debug, Clone)]
pub(crate) struct Tridiagonal {
    pub diag: Vec<f64>,
    pub off: Vec<f64>,
    /// `n × n`, column-major with leading dimension `ld`: reflector `k` is
    /// `H_k = I − tau[k]·v vᵀ` with `v = (0, …, 0, 1, vecs[k+2..n, k])`, 1 at row `k + 1`.
    vecs: Vec<f64>,
    ld: usize,
    tau: Vec<f64>,
}

impl Drop for Tridiagonal {
    /// Hands the reflectors' storage to the next reduction on this thread (see [`SPARE`]).
    fn drop(&mut self) {
        let done = std::mem::take(&mut self.vecs);
        SPARE.with(|spare| {
            let held = spare.take();
            spare.set(if done.capacity() >= held.capacity() {
                done
            } else {
                held
            });
        });
    }
}

thread_local! {
    /// The storage of this thread's last reduction, reused by its next one: a fresh zeroed
    /// allocation of this size (≥ 128 KiB from 120 dof) comes from the operating system on every
    /// solve, and its page faults and zeroing took about 6 % of a contour pair. One buffer per
    /// thread, as large as the largest reduction it ran.
    static SPARE: std::cell::Cell<Vec<f64>> = const { std::cell::Cell::new(Vec::new()) };
}

/// `len` zeros, in this thread's spare buffer when it has one.
fn zeroed(len: usize) -> Vec<f64> {
    let mut v = SPARE.with(|spare| spare.take());
    v.clear();
    v.resize(len, 0.0);
    v
}

/// Spare zero rows below the matrix and zeros after every row vector: a sweep's vectors may then
/// run past the last row (padding contributes nothing) instead of ending in scalar tails.
const PAD_ROWS: usize = 8;

/// Reduces the symmetric `a` (only its lower triangle is read) to tridiagonal form, on the
/// widest vector unit this CPU has. The O(n²) work around the sweeps (the reflectors, `w`, the
/// copies) is compiled for that unit too.
pub(crate) fn tridiagonalize(a: MatRef<'_, f64>) -> Tridiagonal {
    dispatch(Tridiagonalize(a))
}

/// The argument of [`tridiagonalize`], run by [`dispatch`].
struct Tridiagonalize<'a>(MatRef<'a, f64>);

impl Kernel for Tridiagonalize<'_> {
    type Output = Tridiagonal;
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn avx512(self, simd: pulp::x86::V4) -> Tridiagonal {
        tridiagonalize_body(simd, self.0)
    }
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn avx2(self, simd: pulp::x86::V3) -> Tridiagonal {
        tridiagonalize_body(simd, self.0)
    }
    #[inline(always)]
    fn baseline(self) -> Tridiagonal {
        tridiagonalize_body(Baseline, self.0)
    }
}

#[inline(always)]
fn tridiagonalize_body<U: Lanes>(unit: U, a: MatRef<'_, f64>) -> Tridiagonal {
    let n = a.nrows();
    // Columns of whole cache lines, kept off multiples of 4 KiB apart (which alias in the store
    // buffer); `COLS` spare zero columns let the last pass of a sweep be a full one.
    let mut ld = (n + PAD_ROWS).div_ceil(8) * 8;
    if ld.is_multiple_of(512) {
        ld += 8;
    }
    let mut m = zeroed(ld * (n + COLS));
    for j in 0..n {
        let dst = &mut m[j * ld + j..j * ld + n];
        match a.col(j).try_as_col_major() {
            Some(col) => dst.copy_from_slice(&col.as_slice()[j..]),
            None => dst.iter_mut().zip(j..n).for_each(|(d, i)| *d = a[(i, j)]),
        }
    }
    // A power of two (exact) bringing the largest entry to about 1: the sums of squares of the
    // reflectors then neither overflow nor underflow, whatever the units of the model. Eight
    // running maxima, so the comparisons do not wait on each other.
    let mut lanes = [0.0f64; 8];
    for chunk in m.chunks_exact(8) {
        for l in 0..8 {
            let v = chunk[l].abs();
            lanes[l] = if v > lanes[l] { v } else { lanes[l] };
        }
    }
    let amax = lanes.iter().fold(0.0f64, |x, &y| if y > x { y } else { x });
    let scale_exp = if amax > 0.0 && amax.is_finite() {
        (amax.log2().round() as i32).clamp(-1000, 1000)
    } else {
        0
    };
    let (down, up) = (2f64.powi(-scale_exp), 2f64.powi(scale_exp));
    if scale_exp != 0 {
        m.iter_mut().for_each(|v| *v *= down);
    }
    let mut diag = vec![0.0; n];
    let mut off = vec![0.0; n.saturating_sub(1)];
    let mut tau = vec![0.0; n.saturating_sub(1)];
    // The previous step's reflector `u` and `w = τ B u − ½τ²(uᵀ B u) u`, indexed by global row
    // (zero past row n); its rank-2 update `B ← B − u wᵀ − w uᵀ` is applied in the next sweep.
    let len = n + PAD_ROWS;
    let (mut u, mut w, mut v, mut y) = (
        vec![0.0; len],
        vec![0.0; len],
        vec![0.0; len],
        vec![0.0; len],
    );
    for k in 0..n {
        // Column k (rows k..n) gets the pending update first: its reflector comes from it.
        let (wk, uk) = (w[k], u[k]);
        for i in k..n {
            m[i + k * ld] -= u[i] * wk + w[i] * uk;
        }
        diag[k] = m[k + k * ld];
        if k + 1 == n {
            break;
        }
        // The reflector of column k below the diagonal (LAPACK dlarfg).
        let (beta, t) = householder_in_place(&mut m[k * ld + k + 1..k * ld + n]);
        off[k] = beta;
        tau[k] = t;
        let s = k + 1;
        v[s] = 1.0;
        v[s + 1..n].copy_from_slice(&m[k * ld + k + 2..k * ld + n]);
        // y = B v on the trailing block, B updated by the pending reflector on the way.
        sweep(
            unit,
            &mut m[s * ld + s..],
            ld,
            n - s,
            &u[s..],
            &w[s..],
            &v[s..],
            &mut y[s..],
        );
        // w = τ y − ½ τ² (yᵀ v) v, the symmetric rank-2 form of H B H.
        let alpha = -0.5 * t * t * dot(&y[s..n], &v[s..n]);
        for i in s..n {
            w[i] = t * y[i] + alpha * v[i];
        }
        u[s..n].copy_from_slice(&v[s..n]);
        // Rows above the block are no longer read; keep them zero for the next column update.
        (u[k], w[k]) = (0.0, 0.0);
    }
    for d in diag.iter_mut() {
        *d *= up;
    }
    for e in off.iter_mut() {
        *e *= up;
    }
    Tridiagonal {
        diag,
        off,
        vecs: m,
        ld,
        tau,
    }
}

impl Tridiagonal {
    /// `Y ← Q Y` for the eigenvectors `Y` (`n × k`) of the tridiagonal matrix, `Q = H₀ H₁ ⋯`.
    pub(crate) fn apply_q(&self, y: MatMut<'_, f64>) {
        let n = self.diag.len();
        if n < 2 || y.ncols() == 0 {
            return;
        }
        self.apply_q_blocked(y);
    }
}

impl Tridiagonal {
    /// `Y ← Q Y` by faer's blocked Householder sequence (faster than applying the reflectors one
    /// at a time at every order measured, BENCHMARKS.md "Eigensolver"): the reflectors are stored as faer's
    /// tridiagonalisation stores them (column `k` below row `k + 1`, the unit head implicit), and
    /// faer's `τ` is the reciprocal of LAPACK's (∞ for the identity).
    fn apply_q_blocked(&self, y: MatMut<'_, f64>) {
        use faer::dyn_stack::{MemBuffer, MemStack};
        use faer::linalg::householder as hh;
        let n = self.diag.len();
        let m = n - 1;
        let essentials = MatRef::from_column_major_slice_with_stride(&self.vecs, n, n, self.ld)
            .submatrix(1, 0, m, m);
        let bs = faer::linalg::qr::no_pivoting::factor::recommended_block_size::<f64>(m, m);
        let mut factor = faer::Mat::<f64>::zeros(bs, m);
        let mut j = 0;
        while j < m {
            let b = bs.min(m - j);
            let mut block = factor.as_mut().submatrix_mut(0, j, b, b);
            for c in 0..b {
                let t = self.tau[j + c];
                block[(c, c)] = if t == 0.0 { f64::INFINITY } else { 1.0 / t };
            }
            hh::upgrade_householder_factor(
                block,
                essentials.submatrix(j, j, m - j, b),
                b,
                1,
                faer::Par::Seq,
            );
            j += b;
        }
        let k = y.ncols();
        let mut mem = MemBuffer::new(
            hh::apply_block_householder_sequence_on_the_left_in_place_scratch::<f64>(m, bs, k),
        );
        hh::apply_block_householder_sequence_on_the_left_in_place_with_conj(
            essentials,
            factor.as_ref(),
            faer::Conj::No,
            y.subrows_mut(1, m),
            faer::Par::Seq,
            MemStack::new(&mut mem),
        );
        crate::simd::clear_upper_state();
    }
}

/// LAPACK `dlarfg` on `x = (α, x₁…)`: overwrites `x₁…` with the reflector's tail `v` (its head
/// is 1) and returns `(β, τ)` with `(I − τ v vᵀ) x = (β, 0, …)`. `τ = 0` (no reflection) when
/// `x₁… = 0`. The matrix is scaled to entries of about 1, so no rescaling loop is needed.
#[inline(always)]
fn householder_in_place(x: &mut [f64]) -> (f64, f64) {
    let alpha = x[0];
    let xnorm2 = dot(&x[1..], &x[1..]);
    if xnorm2 == 0.0 {
        return (alpha, 0.0);
    }
    let beta = -(alpha * alpha + xnorm2).sqrt().copysign(alpha);
    let tau = (beta - alpha) / beta;
    let scale = 1.0 / (alpha - beta);
    for v in x[1..].iter_mut() {
        *v *= scale;
    }
    x[0] = beta;
    (beta, tau)
}

/// The fused sweep over the lower triangle of the `m × m` block `b` (leading dimension `ld`):
/// `b ← b − u wᵀ − w uᵀ`, then `y = b v`, in one pass, on the vector unit `unit`. `b` has
/// `PAD_ROWS` zero rows below the block and `COLS` zero columns after it; `u`, `w`, `v` are zero
/// past `m`, so whole vectors can run into the padding.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn sweep<U: Lanes>(
    unit: U,
    b: &mut [f64],
    ld: usize,
    m: usize,
    u: &[f64],
    w: &[f64],
    v: &[f64],
    y: &mut [f64],
) {
    let span = m + PAD_ROWS;
    assert!(b.len() >= (m + COLS - 1) * ld + span && ld >= span);
    assert!(u.len() >= span && w.len() >= span && v.len() >= span && y.len() >= span);
    // SAFETY: the sizes were just asserted.
    unsafe { sweep_in(unit, b, ld, m, u, w, v, y) }
}

/// The vector operations of the sweep on the unit `Self` (a pulp token, or [`Baseline`]).
trait Lanes: Copy {
    const WIDTH: usize;
    type V: Copy;
    /// # Safety
    /// `p` points at `WIDTH` readable values.
    unsafe fn load(self, p: *const f64) -> Self::V;
    /// # Safety
    /// `p` points at `WIDTH` writable values.
    unsafe fn store(self, v: Self::V, p: *mut f64);
    fn splat(self, v: f64) -> Self::V;
    /// 1 in the lanes `l` with `l ≥ from`, 0 in the others.
    fn lanes_from(self, from: usize) -> Self::V;
    fn mul(self, a: Self::V, b: Self::V) -> Self::V;
    /// `a·b + c`.
    fn mul_add(self, a: Self::V, b: Self::V, c: Self::V) -> Self::V;
    /// `c − a·b`.
    fn neg_mul_add(self, a: Self::V, b: Self::V, c: Self::V) -> Self::V;
    /// The four horizontal sums.
    fn sum4(self, a: [Self::V; 4]) -> [f64; 4];
}

/// Columns of one pass of the sweep.
const COLS: usize = 4;

/// The sweep for a vector type, four columns `j..j+4` a pass, rows from the diagonal `j` down in
/// whole vectors. In the first vector, the lanes above a column's diagonal (upper-triangle
/// storage, never read) are updated too but masked out of both products, and the diagonal
/// entry enters `y` once.
///
/// # Safety
/// As asserted by [`sweep`].
#[inline(always)]
#[allow(clippy::too_many_arguments)]
unsafe fn sweep_in<U: Lanes>(
    unit: U,
    b: &mut [f64],
    ld: usize,
    m: usize,
    u: &[f64],
    w: &[f64],
    v: &[f64],
    y: &mut [f64],
) {
    // SAFETY: every pointer below stays within the sizes the caller guarantees (`sweep`'s
    // assertions): rows `j..m` rounded up to whole vectors end inside the padding rows of `b`,
    // `u`, `w`, `v` and `y`, and columns `j..j + COLS` inside the `COLS` spare columns.
    unsafe {
        y[..m + PAD_ROWS].fill(0.0);
        let bp = b.as_mut_ptr();
        let (up, wp, vp, yp) = (u.as_ptr(), w.as_ptr(), v.as_ptr(), y.as_mut_ptr());
        // Lane masks of the first vector of a pass: column c takes rows j + l with l ≥ c into its
        // dot product and rows with l > c into the symmetric half of `y`.
        // (Loops rather than `array::from_fn`: a closure is a function of its own, compiled
        // without the unit's instructions unless inlined.)
        let zero = unit.splat(0.0);
        let (mut ge, mut gt) = ([zero; COLS], [zero; COLS]);
        for c in 0..COLS {
            (ge[c], gt[c]) = (unit.lanes_from(c), unit.lanes_from(c + 1));
        }
        let mut j = 0;
        while j < m {
            let cols: [*mut f64; COLS] = std::array::from_fn(|c| bp.add((j + c) * ld));
            let (mut wj, mut uj, mut vj) = ([zero; COLS], [zero; COLS], [zero; COLS]);
            for c in 0..COLS {
                (wj[c], uj[c], vj[c]) = (
                    unit.splat(w[j + c]),
                    unit.splat(u[j + c]),
                    unit.splat(v[j + c]),
                );
            }
            let mut acc = [zero; COLS];
            let mut i = j;
            let mut first = true;
            while i < m {
                let (ui, wi, vi) = (
                    unit.load(up.add(i)),
                    unit.load(wp.add(i)),
                    unit.load(vp.add(i)),
                );
                let mut yi = unit.load(yp.add(i));
                for c in 0..COLS {
                    let e = cols[c].add(i);
                    let bij =
                        unit.neg_mul_add(wi, uj[c], unit.neg_mul_add(ui, wj[c], unit.load(e)));
                    unit.store(bij, e);
                    let (vd, vs) = if first {
                        (unit.mul(vi, ge[c]), unit.mul(vj[c], gt[c]))
                    } else {
                        (vi, vj[c])
                    };
                    acc[c] = unit.mul_add(bij, vd, acc[c]);
                    yi = unit.mul_add(bij, vs, yi);
                }
                unit.store(yi, yp.add(i));
                first = false;
                i += U::WIDTH;
            }
            let sums = unit.sum4(acc);
            for c in 0..COLS {
                y[j + c] += sums[c];
            }
            j += COLS;
        }
    }
}

/// Plain code for CPUs without AVX2 and FMA.
#[derive(Clone, Copy)]
struct Baseline;

impl Lanes for Baseline {
    const WIDTH: usize = 4;
    type V = [f64; 4];
    #[inline(always)]
    unsafe fn load(self, p: *const f64) -> [f64; 4] {
        // SAFETY: the caller guarantees 4 readable values at `p` (the trait's contract).
        std::array::from_fn(|l| unsafe { *p.add(l) })
    }
    #[inline(always)]
    unsafe fn store(self, v: [f64; 4], p: *mut f64) {
        for (l, x) in v.into_iter().enumerate() {
            // SAFETY: the caller guarantees 4 writable values at `p` (the trait's contract).
            unsafe { *p.add(l) = x };
        }
    }
    #[inline(always)]
    fn splat(self, v: f64) -> [f64; 4] {
        [v; 4]
    }
    #[inline(always)]
    fn lanes_from(self, from: usize) -> [f64; 4] {
        std::array::from_fn(|l| if l >= from { 1.0 } else { 0.0 })
    }
    #[inline(always)]
    fn mul(self, a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
        std::array::from_fn(|l| a[l] * b[l])
    }
    #[inline(always)]
    fn mul_add(self, a: [f64; 4], b: [f64; 4], c: [f64; 4]) -> [f64; 4] {
        std::array::from_fn(|l| a[l] * b[l] + c[l])
    }
    #[inline(always)]
    fn neg_mul_add(self, a: [f64; 4], b: [f64; 4], c: [f64; 4]) -> [f64; 4] {
        std::array::from_fn(|l| c[l] - a[l] * b[l])
    }
    #[inline(always)]
    fn sum4(self, a: [[f64; 4]; 4]) -> [f64; 4] {
        a.map(|x| (x[0] + x[1]) + (x[2] + x[3]))
    }
}

#[cfg(target_arch = "x86_64")]
mod units {
    use super::Lanes;
    use core::arch::x86_64::{__m256d, __m512d};
    use pulp::x86::{V3, V4};

    impl Lanes for V4 {
        const WIDTH: usize = 8;
        type V = __m512d;
        #[inline(always)]
        unsafe fn load(self, p: *const f64) -> __m512d {
            // SAFETY: the caller guarantees 8 readable values at `p` (the trait's contract).
            unsafe { self.avx512f._mm512_loadu_pd(p) }
        }
        #[inline(always)]
        unsafe fn store(self, v: __m512d, p: *mut f64) {
            // SAFETY: the caller guarantees 8 writable values at `p` (the trait's contract).
            unsafe { self.avx512f._mm512_storeu_pd(p, v) }
        }
        #[inline(always)]
        fn splat(self, v: f64) -> __m512d {
            self.avx512f._mm512_set1_pd(v)
        }
        #[inline(always)]
        fn lanes_from(self, from: usize) -> __m512d {
            pulp::cast::<[f64; 8], _>(std::array::from_fn(|l| if l >= from { 1.0 } else { 0.0 }))
        }
        #[inline(always)]
        fn mul(self, a: __m512d, b: __m512d) -> __m512d {
            self.avx512f._mm512_mul_pd(a, b)
        }
        #[inline(always)]
        fn mul_add(self, a: __m512d, b: __m512d, c: __m512d) -> __m512d {
            self.avx512f._mm512_fmadd_pd(a, b, c)
        }
        #[inline(always)]
        fn neg_mul_add(self, a: __m512d, b: __m512d, c: __m512d) -> __m512d {
            self.avx512f._mm512_fnmadd_pd(a, b, c)
        }
        #[inline(always)]
        fn sum4(self, a: [__m512d; 4]) -> [f64; 4] {
            let (f, x) = (self.avx512f, self.avx);
            // 8 → 4 lanes each, then the four 4-lane sums side by side.
            let mut h = [x._mm256_setzero_pd(); 4];
            for (h, v) in h.iter_mut().zip(a) {
                *h = x._mm256_add_pd(
                    f._mm512_castpd512_pd256(v),
                    f._mm512_extractf64x4_pd::<1>(v),
                );
            }
            let s01 = x._mm256_hadd_pd(h[0], h[1]);
            let s23 = x._mm256_hadd_pd(h[2], h[3]);
            let lo = x._mm256_permute2f128_pd::<0x20>(s01, s23);
            let hi = x._mm256_permute2f128_pd::<0x31>(s01, s23);
            pulp::cast(x._mm256_add_pd(lo, hi))
        }
    }

    impl Lanes for V3 {
        const WIDTH: usize = 4;
        type V = __m256d;
        #[inline(always)]
        unsafe fn load(self, p: *const f64) -> __m256d {
            // SAFETY: the caller guarantees 4 readable values at `p` (the trait's contract).
            unsafe { self.avx._mm256_loadu_pd(p) }
        }
        #[inline(always)]
        unsafe fn store(self, v: __m256d, p: *mut f64) {
            // SAFETY: the caller guarantees 4 writable values at `p` (the trait's contract).
            unsafe { self.avx._mm256_storeu_pd(p, v) }
        }
        #[inline(always)]
        fn splat(self, v: f64) -> __m256d {
            self.avx._mm256_set1_pd(v)
        }
        #[inline(always)]
        fn lanes_from(self, from: usize) -> __m256d {
            pulp::cast::<[f64; 4], _>(std::array::from_fn(|l| if l >= from { 1.0 } else { 0.0 }))
        }
        #[inline(always)]
        fn mul(self, a: __m256d, b: __m256d) -> __m256d {
            self.avx._mm256_mul_pd(a, b)
        }
        #[inline(always)]
        fn mul_add(self, a: __m256d, b: __m256d, c: __m256d) -> __m256d {
            self.fma._mm256_fmadd_pd(a, b, c)
        }
        #[inline(always)]
        fn neg_mul_add(self, a: __m256d, b: __m256d, c: __m256d) -> __m256d {
            self.fma._mm256_fnmadd_pd(a, b, c)
        }
        #[inline(always)]
        fn sum4(self, a: [__m256d; 4]) -> [f64; 4] {
            let x = self.avx;
            let s01 = x._mm256_hadd_pd(a[0], a[1]);
            let s23 = x._mm256_hadd_pd(a[2], a[3]);
            let lo = x._mm256_permute2f128_pd::<0x20>(s01, s23);
            let hi = x._mm256_permute2f128_pd::<0x31>(s01, s23);
            pulp::cast(x._mm256_add_pd(lo, hi))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::Mat;

    use crate::eigen::random_start;

    fn random_symmetric(n: usize, seed: u64) -> Mat<f64> {
        let mut s = seed;
        let mut a = Mat::<f64>::zeros(n, n);
        for j in 0..n {
            for i in j..n {
                let v = random_start(&mut s);
                a[(i, j)] = v;
                a[(j, i)] = v;
            }
        }
        a
    }

    /// `Q` (from `apply_q` on the identity) is orthogonal and `Q T Qᵀ = A`.
    fn check_reduction(a: &Mat<f64>, what: &str) {
        let n = a.nrows();
        let t = tridiagonalize(a.as_ref());
        let mut q = Mat::<f64>::identity(n, n);
        t.apply_q(q.as_mut());
        let tm = Mat::<f64>::from_fn(n, n, |i, j| match i.abs_diff(j) {
            0 => t.diag[i],
            1 => t.off[i.min(j)],
            _ => 0.0,
        });
        let scale = a.norm_max().max(f64::MIN_POSITIVE);
        let rebuilt = &q * &tm * q.transpose();
        let err = (&rebuilt - a).norm_max() / scale;
        assert!(err < 1e-13 * n as f64, "{what}: ‖QTQᵀ − A‖ = {err:e}·‖A‖");
        let ortho = (q.transpose() * &q - Mat::<f64>::identity(n, n)).norm_max();
        assert!(ortho < 1e-14 * n as f64, "{what}: ‖QᵀQ − I‖ = {ortho:e}");
    }

    #[test]
    fn reduction_rebuilds_the_matrix_at_every_order() {
        // Orders around the vector widths, the four-column passes and the padding.
        for n in (1..=20).chain([31, 32, 33, 63, 64, 65, 100, 128, 130]) {
            check_reduction(&random_symmetric(n, n as u64), &format!("n = {n}"));
        }
    }

    /// The reduction's storage is reused from the thread's previous one: a larger matrix's
    /// leftovers must not reach a smaller one's result (the padding is read as zeros).
    #[test]
    fn a_reused_buffer_gives_the_bits_of_a_fresh_one() {
        let small = random_symmetric(37, 5);
        let on_fresh_thread = |a: Mat<f64>| {
            std::thread::spawn(move || {
                let t = tridiagonalize(a.as_ref());
                let mut q = Mat::<f64>::identity(a.nrows(), a.nrows());
                t.apply_q(q.as_mut());
                (t.diag.clone(), t.off.clone(), t.tau.clone(), q)
            })
            .join()
            .unwrap()
        };
        let fresh = on_fresh_thread(small.clone());
        let reused = std::thread::spawn(move || {
            drop(tridiagonalize(random_symmetric(130, 6).as_ref()));
            // Whatever a spare buffer holds (here the worst: NaN everywhere) is cleared.
            super::SPARE.with(|spare| {
                let mut v = spare.take();
                v.fill(f64::NAN);
                spare.set(v);
            });
            let t = tridiagonalize(small.as_ref());
            let mut q = Mat::<f64>::identity(small.nrows(), small.nrows());
            t.apply_q(q.as_mut());
            (t.diag.clone(), t.off.clone(), t.tau.clone(), q)
        })
        .join()
        .unwrap();
        assert_eq!(
            (&fresh.0, &fresh.1, &fresh.2),
            (&reused.0, &reused.1, &reused.2)
        );
        assert_eq!(fresh.3, reused.3);
    }

    #[test]
    fn reduction_of_special_matrices() {
        // Already diagonal: every reflector is the identity (τ = 0).
        let d = Mat::<f64>::from_fn(9, 9, |i, j| if i == j { i as f64 - 4.0 } else { 0.0 });
        check_reduction(&d, "diagonal");
        let t = tridiagonalize(d.as_ref());
        assert!(t.tau.iter().all(|&x| x == 0.0));
        // A zero column in the middle, and a block-diagonal matrix.
        let mut a = random_symmetric(12, 4);
        for i in 0..12 {
            a[(i, 5)] = 0.0;
            a[(5, i)] = 0.0;
        }
        check_reduction(&a, "zero column");
        let b = Mat::<f64>::from_fn(10, 10, |i, j| {
            if (i < 5) == (j < 5) {
                1.0 / (1 + i + j) as f64
            } else {
                0.0
            }
        });
        check_reduction(&b, "block diagonal");
        // Extreme units: the reduction works at any scale, and a power-of-two scale (exact)
        // scales T exactly and leaves the reflectors as they were.
        let a = random_symmetric(40, 9);
        for s in [1e-150, 1e150] {
            check_reduction(&(&a * faer::Scale(s)), &format!("scale {s:e}"));
        }
        let t1 = tridiagonalize(a.as_ref());
        for s in [2f64.powi(-500), 2f64.powi(500)] {
            let ts = tridiagonalize((&a * faer::Scale(s)).as_ref());
            assert!(ts.diag.iter().zip(&t1.diag).all(|(x, y)| *x == y * s));
            assert!(ts.off.iter().zip(&t1.off).all(|(x, y)| *x == y * s));
            assert_eq!(ts.tau, t1.tau);
        }
    }

    #[test]
    fn eigenvalues_agree_with_faer() {
        for n in [7, 60, 129] {
            let a = random_symmetric(n, 100 + n as u64);
            let t = tridiagonalize(a.as_ref());
            let mut ours = super::super::tridiagonal_eigenvalues(&t.diag, &t.off).unwrap();
            ours.sort_by(f64::total_cmp);
            let mut theirs: Vec<f64> = a.self_adjoint_eigenvalues(faer::Side::Lower).unwrap();
            theirs.sort_by(f64::total_cmp);
            for (x, y) in ours.iter().zip(&theirs) {
                assert!((x - y).abs() < 1e-13 * n as f64, "n = {n}: {x} vs {y}");
            }
        }
    }

    #[test]
    fn every_sweep_path_agrees() {
        let mut seed = 21u64;
        for m in [1usize, 3, 4, 5, 8, 9, 17, 40] {
            let ld = (m + PAD_ROWS).div_ceil(8) * 8;
            let mut b = vec![0.0; ld * (m + COLS)];
            for j in 0..m {
                for i in j..m {
                    b[i + j * ld] = random_start(&mut seed);
                }
            }
            let vec_of = |seed: &mut u64| -> Vec<f64> {
                let mut v: Vec<f64> = (0..m).map(|_| random_start(seed)).collect();
                v.resize(m + PAD_ROWS, 0.0);
                v
            };
            let (u, w, v) = (vec_of(&mut seed), vec_of(&mut seed), vec_of(&mut seed));
            // A plain reference: update the lower triangle, then the symmetric product.
            let mut r = b.clone();
            let mut want = vec![0.0; m];
            for j in 0..m {
                for i in j..m {
                    r[i + j * ld] -= u[i] * w[j] + w[i] * u[j];
                }
            }
            for j in 0..m {
                for i in 0..m {
                    let (hi, lo) = (i.max(j), i.min(j));
                    want[i] += r[hi + lo * ld] * v[j];
                }
            }
            let run = |f: &dyn Fn(&mut [f64], &mut [f64])| {
                let mut bb = b.clone();
                let mut y = vec![0.0; m + PAD_ROWS];
                f(&mut bb, &mut y);
                (bb, y)
            };
            let mut results = vec![(
                "baseline",
                run(&|bb, y| sweep(Baseline, bb, ld, m, &u, &w, &v, y)),
            )];
            #[cfg(target_arch = "x86_64")]
            {
                use crate::simd::{on_avx2, on_avx512};
                /// The sweep alone, on one vector unit.
                struct Sweep<'a>(&'a mut [f64], usize, usize, [&'a [f64]; 3], &'a mut [f64]);
                impl Kernel for Sweep<'_> {
                    type Output = ();
                    fn avx512(self, simd: pulp::x86::V4) {
                        let [u, w, v] = self.3;
                        sweep(simd, self.0, self.1, self.2, u, w, v, self.4)
                    }
                    fn avx2(self, simd: pulp::x86::V3) {
                        let [u, w, v] = self.3;
                        sweep(simd, self.0, self.1, self.2, u, w, v, self.4)
                    }
                    fn baseline(self) {
                        let [u, w, v] = self.3;
                        sweep(Baseline, self.0, self.1, self.2, u, w, v, self.4)
                    }
                }
                let uwv = [&u[..], &w[..], &v[..]];
                if let Some(simd) = pulp::x86::V3::try_new() {
                    results.push((
                        "AVX2",
                        run(&|bb, y| on_avx2(simd, Sweep(bb, ld, m, uwv, y))),
                    ));
                }
                if let Some(simd) = pulp::x86::V4::try_new() {
                    results.push((
                        "AVX-512",
                        run(&|bb, y| on_avx512(simd, Sweep(bb, ld, m, uwv, y))),
                    ));
                }
            }
            for (name, (bb, y)) in &results {
                for j in 0..m {
                    for i in j..m {
                        assert!(
                            (bb[i + j * ld] - r[i + j * ld]).abs() < 1e-14,
                            "{name}, m = {m}"
                        );
                    }
                    // The padding stays zero.
                    for i in m..m + PAD_ROWS {
                        assert_eq!(bb[i + j * ld], 0.0, "{name}, m = {m}, padding");
                    }
                }
                for i in 0..m {
                    assert!((y[i] - want[i]).abs() < 1e-13, "{name}, m = {m}: y[{i}]");
                }
            }
        }
    }
}
