//! The coherent drift's expectation step (docs/method.md §7.5) in vector lanes: the `n × m`
//! Gaussian responsibilities of A's moved nodes for B's nodes, normalised per column, and the
//! sums the maximisation step reads, and that step's matrix. Done one entry at a time, the step
//! was most of a drifted pair's time: about 30 steps of `n · m` exponentials (100–185 nodes a
//! side on the landmark benchmark; BENCHMARKS.md, "A landmark pair's time").
//!
//! The plain loop takes the exponentials one at a time from the C library; on a CPU with AVX-512
//! eight columns at a time go through one polynomial exponential (`exp_neg_avx512`, within a few
//! units in the last place of the library's), B's coordinates stored coordinate by coordinate
//! (structure of arrays, padded to a multiple of eight nodes); on a CPU with AVX2 (and FMA) but
//! not AVX-512, four columns at a time through the same polynomial (`exp_neg_avx2`), each block
//! of eight as two halves. The sums are taken in lanes, so they differ from the plain loop's in
//! the last bits only; `tests` compare each unit the CPU has with the plain loop. CPUs without
//! AVX2 run the plain loop on the same buffers. (Lane arrays left to the auto-vectoriser, one
//! body for every unit, stayed scalar and took longer than the plain loop.)

use crate::simd::{dispatch, Kernel};

/// Columns handled side by side.
const LANES: usize = 8;
/// Responsibilities below `e^-NEGLIGIBLE` of their column's largest are left at 0 (no
/// exponential is taken): 36 is below the round-off of the column's sum.
pub(crate) const NEGLIGIBLE: f64 = 36.0;
/// Coordinate of the padding columns: far from every node, so that their exponents are huge but
/// finite (their responsibilities are zeroed by the column weights anyway).
const FAR: f64 = 1e100;

/// The E-step's buffers and, after [`Posterior::update`], its sums.
pub(crate) struct Posterior {
    d: usize,
    n: usize,
    m: usize,
    /// `m` rounded up to whole lanes.
    mp: usize,
    /// B's coordinates, `d` rows of `mp` (padded with [`FAR`]).
    ys: Vec<f64>,
    /// `|y_j|²` (0 for the padding).
    y_sq: Vec<f64>,
    /// Exponents, then responsibilities before the column weights, `n × mp`.
    p: Vec<f64>,
    col_near: Vec<f64>,
    /// `1 / Σ_i e_ij` per column (0 for an empty column and the padding).
    col_inv: Vec<f64>,
    /// `Σ_j P[i, j]` for each node of A.
    pub row_sums: Vec<f64>,
    /// `Σ_j P[i, j] y_j`, row-major `n × d`.
    pub pulled: Vec<f64>,
    /// `Σ_ij P[i, j]`.
    pub total: f64,
    /// `Σ_ij P[i, j] |y_j|²`.
    pub y_term: f64,
}

impl Posterior {
    /// Buffers for `n` nodes of A against the nodes `y` (row-major, `m × d`).
    pub(crate) fn new(y: &[f64], d: usize, n: usize) -> Self {
        let m = y.len() / d;
        let mp = m.div_ceil(LANES) * LANES;
        let mut ys = vec![FAR; d * mp];
        let mut y_sq = vec![0.0; mp];
        for (j, q) in y.chunks_exact(d).enumerate() {
            for c in 0..d {
                ys[c * mp + j] = q[c];
            }
            y_sq[j] = q.iter().map(|v| v * v).sum();
        }
        Self {
            d,
            n,
            m,
            mp,
            ys,
            y_sq,
            p: vec![0.0; n * mp],
            col_near: vec![0.0; mp],
            col_inv: vec![0.0; mp],
            row_sums: vec![0.0; n],
            pulled: vec![0.0; n * d],
            total: 0.0,
            y_term: 0.0,
        }
    }

    /// The posterior of each node of A at `moved` (row-major `n × d`) having produced each node
    /// of B under the mixture of variance `var`: each column is normalised, so its exponents are
    /// taken relative to its smallest (no column underflows), and those [`NEGLIGIBLE`] above it
    /// give 0 without an exponential. Fills [`Posterior::row_sums`], [`Posterior::pulled`],
    /// [`Posterior::total`] and [`Posterior::y_term`].
    pub(crate) fn update(&mut self, moved: &[f64], var: f64) {
        debug_assert_eq!(moved.len(), self.n * self.d);
        let scale = 1.0 / (2.0 * var);
        match self.d {
            2 => dispatch(Step::<2> {
                post: self,
                moved,
                scale,
            }),
            3 => dispatch(Step::<3> {
                post: self,
                moved,
                scale,
            }),
            _ => step_any(self, moved, scale),
        }
    }
}

/// The maximisation step's matrix `Qᵀ diag(P1) Q` into the lower triangle of `lhs` (`k × k`, the
/// rest left as it is), `basis` the kernel's leading eigenvectors (row-major `n × k`) and
/// `row_sums` the posterior's `P1`; rows with `P1 = 0` add nothing. The same products and sums in
/// the same order as an update of `lhs` entry by entry, in a plain buffer (faer's indexing
/// computed each entry's address with a multiplication and a bounds check).
pub(crate) fn normal_matrix(basis: &[f64], k: usize, row_sums: &[f64], lhs: &mut faer::Mat<f64>) {
    let mut acc = vec![0.0; k * k];
    for (row, &p1) in basis.chunks_exact(k).zip(row_sums) {
        if p1 > 0.0 {
            for (a, line) in acc.chunks_exact_mut(k).enumerate() {
                let w = p1 * row[a];
                for (v, &rb) in line[..=a].iter_mut().zip(row) {
                    *v += w * rb;
                }
            }
        }
    }
    for (a, line) in acc.chunks_exact(k).enumerate() {
        for (b, &v) in line[..=a].iter().enumerate() {
            lhs[(a, b)] = v;
        }
    }
}

/// One E-step of [`Posterior::update`] for `D`-dimensional nodes, run by [`dispatch`]: AVX-512
/// and AVX2 in vector registers, the baseline by the plain loops of [`step_any`].
struct Step<'a, const D: usize> {
    post: &'a mut Posterior,
    moved: &'a [f64],
    scale: f64,
}

impl<const D: usize> Kernel for Step<'_, D> {
    type Output = ();
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn avx512(self, simd: pulp::x86::V4) {
        step_lanes::<_, D>(simd, self.post, self.moved, self.scale)
    }
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn avx2(self, simd: pulp::x86::V3) {
        step_lanes::<_, D>(simd, self.post, self.moved, self.scale)
    }
    #[inline(always)]
    fn baseline(self) {
        step_any(self.post, self.moved, self.scale)
    }
}

/// The E-step one entry at a time (the library's `exp`), for any dimension.
fn step_any(post: &mut Posterior, moved: &[f64], scale: f64) {
    let (d, n, m, mp) = (post.d, post.n, post.m, post.mp);
    post.col_near.fill(f64::INFINITY);
    for i in 0..n {
        for j in 0..m {
            let d2: f64 = (0..d)
                .map(|c| (moved[i * d + c] - post.ys[c * mp + j]).powi(2))
                .sum();
            let t = d2 * scale;
            post.p[i * mp + j] = t;
            post.col_near[j] = post.col_near[j].min(t);
        }
    }
    post.col_inv.fill(0.0);
    for i in 0..n {
        for j in 0..m {
            let t = post.p[i * mp + j] - post.col_near[j];
            let e = if t < NEGLIGIBLE { (-t).exp() } else { 0.0 };
            post.p[i * mp + j] = e;
            post.col_inv[j] += e;
        }
    }
    for s in &mut post.col_inv {
        *s = if *s > 0.0 { 1.0 / *s } else { 0.0 };
    }
    let (mut total, mut y_term) = (0.0, 0.0);
    for i in 0..n {
        let mut s = 0.0;
        let pull = &mut post.pulled[i * d..(i + 1) * d];
        pull.fill(0.0);
        for j in 0..m {
            let pij = post.p[i * mp + j] * post.col_inv[j];
            if pij == 0.0 {
                continue;
            }
            s += pij;
            y_term += pij * post.y_sq[j];
            for (c, pull) in pull.iter_mut().enumerate() {
                *pull += pij * post.ys[c * mp + j];
            }
        }
        post.row_sums[i] = s;
        total += s;
    }
    post.total = total;
    post.y_term = y_term;
}

#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::{__m256d, __m512d, _CMP_LT_OQ};

/// The operations of the E-step on one register of the unit `Self` (a pulp token): eight lanes
/// on AVX-512, four on AVX2 (each block of [`LANES`] columns as two registers). Both units run
/// [`step_lanes`], the same operations in the same order lane by lane.
#[cfg(target_arch = "x86_64")]
trait Lanes: Copy {
    /// Lanes in one register (a divisor of [`LANES`]).
    const WIDTH: usize;
    type V: Copy;
    fn splat(self, v: f64) -> Self::V;
    /// The `WIDTH` entries of `s` from `at`.
    fn load(self, s: &[f64], at: usize) -> Self::V;
    /// Stores `v` into the `WIDTH` entries of `s` from `at`.
    fn store(self, s: &mut [f64], at: usize, v: Self::V);
    fn add(self, a: Self::V, b: Self::V) -> Self::V;
    fn sub(self, a: Self::V, b: Self::V) -> Self::V;
    fn mul(self, a: Self::V, b: Self::V) -> Self::V;
    fn min(self, a: Self::V, b: Self::V) -> Self::V;
    /// `exp(−t)` in the lanes where `t < limit`, 0 in the others; `None` when no lane is.
    fn exp_neg_below(self, t: Self::V, limit: Self::V) -> Option<Self::V>;
    /// The sum of the lanes.
    fn sum(self, v: Self::V) -> f64;
}

/// [`step_any`] in the registers of `unit`: the exponentials by its polynomial (see
/// [`exp_neg_avx512`]), the sums in lanes.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn step_lanes<L: Lanes, const D: usize>(unit: L, post: &mut Posterior, moved: &[f64], scale: f64) {
    let (n, m, mp, w) = (post.n, post.m, post.mp, L::WIDTH);
    let scale_v = unit.splat(scale);
    post.col_near.fill(f64::INFINITY);
    for i in 0..n {
        let a: [L::V; D] = std::array::from_fn(|c| unit.splat(moved[i * D + c]));
        for at in (0..mp).step_by(w) {
            let mut d2 = unit.splat(0.0);
            for (c, a) in a.iter().enumerate() {
                let v = unit.sub(*a, unit.load(&post.ys, c * mp + at));
                d2 = unit.add(d2, unit.mul(v, v));
            }
            let t = unit.mul(d2, scale_v);
            unit.store(&mut post.p, i * mp + at, t);
            let near = unit.min(t, unit.load(&post.col_near, at));
            unit.store(&mut post.col_near, at, near);
        }
    }
    let negligible = unit.splat(NEGLIGIBLE);
    post.col_inv.fill(0.0);
    for i in 0..n {
        for at in (0..mp).step_by(w) {
            let t = unit.sub(
                unit.load(&post.p, i * mp + at),
                unit.load(&post.col_near, at),
            );
            let Some(e) = unit.exp_neg_below(t, negligible) else {
                // Late in the loop most registers are negligible whole: no exponential, no sum.
                unit.store(&mut post.p, i * mp + at, unit.splat(0.0));
                continue;
            };
            unit.store(&mut post.p, i * mp + at, e);
            let sums = unit.add(unit.load(&post.col_inv, at), e);
            unit.store(&mut post.col_inv, at, sums);
        }
    }
    for (j, s) in post.col_inv.iter_mut().enumerate() {
        *s = if j < m && *s > 0.0 { 1.0 / *s } else { 0.0 };
    }
    let mut total = 0.0;
    let mut y_term = unit.splat(0.0);
    for i in 0..n {
        let mut s = unit.splat(0.0);
        let mut pull = [unit.splat(0.0); D];
        for at in (0..mp).step_by(w) {
            let pij = unit.mul(
                unit.load(&post.p, i * mp + at),
                unit.load(&post.col_inv, at),
            );
            s = unit.add(s, pij);
            y_term = unit.add(y_term, unit.mul(pij, unit.load(&post.y_sq, at)));
            for (c, pull) in pull.iter_mut().enumerate() {
                *pull = unit.add(*pull, unit.mul(pij, unit.load(&post.ys, c * mp + at)));
            }
        }
        let s = unit.sum(s);
        post.row_sums[i] = s;
        total += s;
        for (c, pull) in pull.iter().enumerate() {
            post.pulled[i * D + c] = unit.sum(*pull);
        }
    }
    post.total = total;
    post.y_term = unit.sum(y_term);
}

#[cfg(target_arch = "x86_64")]
impl Lanes for pulp::x86::V4 {
    const WIDTH: usize = 8;
    type V = __m512d;
    #[inline(always)]
    fn splat(self, v: f64) -> __m512d {
        self.avx512f._mm512_set1_pd(v)
    }
    #[inline(always)]
    fn load(self, s: &[f64], at: usize) -> __m512d {
        let v: [f64; 8] = s[at..at + 8].try_into().expect("whole lanes");
        pulp::cast(v)
    }
    #[inline(always)]
    fn store(self, s: &mut [f64], at: usize, v: __m512d) {
        let v: [f64; 8] = pulp::cast(v);
        s[at..at + 8].copy_from_slice(&v);
    }
    #[inline(always)]
    fn add(self, a: __m512d, b: __m512d) -> __m512d {
        self.avx512f._mm512_add_pd(a, b)
    }
    #[inline(always)]
    fn sub(self, a: __m512d, b: __m512d) -> __m512d {
        self.avx512f._mm512_sub_pd(a, b)
    }
    #[inline(always)]
    fn mul(self, a: __m512d, b: __m512d) -> __m512d {
        self.avx512f._mm512_mul_pd(a, b)
    }
    #[inline(always)]
    fn min(self, a: __m512d, b: __m512d) -> __m512d {
        self.avx512f._mm512_min_pd(a, b)
    }
    #[inline(always)]
    fn exp_neg_below(self, t: __m512d, limit: __m512d) -> Option<__m512d> {
        let f = self.avx512f;
        let kept = f._mm512_cmp_pd_mask::<_CMP_LT_OQ>(t, limit);
        (kept != 0).then(|| f._mm512_maskz_mov_pd(kept, exp_neg_avx512(self, t)))
    }
    #[inline(always)]
    fn sum(self, v: __m512d) -> f64 {
        self.avx512f._mm512_reduce_add_pd(v)
    }
}

#[cfg(target_arch = "x86_64")]
impl Lanes for pulp::x86::V3 {
    const WIDTH: usize = 4;
    type V = __m256d;
    #[inline(always)]
    fn splat(self, v: f64) -> __m256d {
        self.avx._mm256_set1_pd(v)
    }
    #[inline(always)]
    fn load(self, s: &[f64], at: usize) -> __m256d {
        let v: [f64; 4] = s[at..at + 4].try_into().expect("whole lanes");
        pulp::cast(v)
    }
    #[inline(always)]
    fn store(self, s: &mut [f64], at: usize, v: __m256d) {
        let v: [f64; 4] = pulp::cast(v);
        s[at..at + 4].copy_from_slice(&v);
    }
    #[inline(always)]
    fn add(self, a: __m256d, b: __m256d) -> __m256d {
        self.avx._mm256_add_pd(a, b)
    }
    #[inline(always)]
    fn sub(self, a: __m256d, b: __m256d) -> __m256d {
        self.avx._mm256_sub_pd(a, b)
    }
    #[inline(always)]
    fn mul(self, a: __m256d, b: __m256d) -> __m256d {
        self.avx._mm256_mul_pd(a, b)
    }
    #[inline(always)]
    fn min(self, a: __m256d, b: __m256d) -> __m256d {
        self.avx._mm256_min_pd(a, b)
    }
    #[inline(always)]
    fn exp_neg_below(self, t: __m256d, limit: __m256d) -> Option<__m256d> {
        let a = self.avx;
        let kept = a._mm256_cmp_pd::<_CMP_LT_OQ>(t, limit);
        (a._mm256_movemask_pd(kept) != 0).then(|| a._mm256_and_pd(kept, exp_neg_avx2(self, t)))
    }
    #[inline(always)]
    fn sum(self, v: __m256d) -> f64 {
        let v: [f64; 4] = pulp::cast(v);
        (v[0] + v[1]) + (v[2] + v[3])
    }
}

/// `exp(−t)` in eight lanes, for `t ≥ 0` (lanes from [`NEGLIGIBLE`] on are not read):
/// `−t = k ln 2 + r` with `|r| ≤ ln 2 / 2` (Cody and Waite's two-part `ln 2`), `exp(r)` by its
/// Taylor polynomial to degree 13 (truncation below 10⁻¹⁷ of it), times `2^k` built in the
/// exponent bits. Within a few units in the last place of the C library's `exp` (`tests`).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn exp_neg_avx512(simd: pulp::x86::V4, t: __m512d) -> __m512d {
    const LN2_HI: f64 = 6.931_471_803_691_238e-1;
    const LN2_LO: f64 = 1.908_214_929_270_587_7e-10;
    // 1.5 · 2^52: adding it rounds to an integer held in the low bits of the mantissa.
    const SHIFT: f64 = 6_755_399_441_055_744.0;
    let f = simd.avx512f;
    // Clamped so that 2^k stays a normal number (k ≥ −1010); such lanes are not read.
    let x = f._mm512_sub_pd(
        f._mm512_setzero_pd(),
        f._mm512_min_pd(t, f._mm512_set1_pd(700.0)),
    );
    let shift = f._mm512_set1_pd(SHIFT);
    let shifted = f._mm512_fmadd_pd(x, f._mm512_set1_pd(std::f64::consts::LOG2_E), shift);
    let k = f._mm512_sub_pd(shifted, shift);
    let r = f._mm512_fnmadd_pd(k, f._mm512_set1_pd(LN2_HI), x);
    let r = f._mm512_fnmadd_pd(k, f._mm512_set1_pd(LN2_LO), r);
    let mut p = f._mm512_set1_pd(TAYLOR[13]);
    for c in TAYLOR[..13].iter().rev() {
        p = f._mm512_fmadd_pd(p, r, f._mm512_set1_pd(*c));
    }
    // k's two's complement sits in the low mantissa bits of `shifted`.
    let ki = f._mm512_sub_epi64(f._mm512_castpd_si512(shifted), f._mm512_castpd_si512(shift));
    let two_k = f._mm512_castsi512_pd(
        f._mm512_slli_epi64::<52>(f._mm512_add_epi64(ki, f._mm512_set1_epi64(1023))),
    );
    f._mm512_mul_pd(p, two_k)
}

/// [`exp_neg_avx512`] in four AVX2 lanes: the same reduction, polynomial, clamp and `2^k`.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn exp_neg_avx2(simd: pulp::x86::V3, t: __m256d) -> __m256d {
    const LN2_HI: f64 = 6.931_471_803_691_238e-1;
    const LN2_LO: f64 = 1.908_214_929_270_587_7e-10;
    // 1.5 · 2^52: adding it rounds to an integer held in the low bits of the mantissa.
    const SHIFT: f64 = 6_755_399_441_055_744.0;
    let (a, f, i) = (simd.avx, simd.fma, simd.avx2);
    // Clamped so that 2^k stays a normal number (k ≥ −1010); such lanes are not read.
    let x = a._mm256_sub_pd(
        a._mm256_setzero_pd(),
        a._mm256_min_pd(t, a._mm256_set1_pd(700.0)),
    );
    let shift = a._mm256_set1_pd(SHIFT);
    let shifted = f._mm256_fmadd_pd(x, a._mm256_set1_pd(std::f64::consts::LOG2_E), shift);
    let k = a._mm256_sub_pd(shifted, shift);
    let r = f._mm256_fnmadd_pd(k, a._mm256_set1_pd(LN2_HI), x);
    let r = f._mm256_fnmadd_pd(k, a._mm256_set1_pd(LN2_LO), r);
    let mut p = a._mm256_set1_pd(TAYLOR[13]);
    for c in TAYLOR[..13].iter().rev() {
        p = f._mm256_fmadd_pd(p, r, a._mm256_set1_pd(*c));
    }
    // k's two's complement sits in the low mantissa bits of `shifted`.
    let ki = i._mm256_sub_epi64(a._mm256_castpd_si256(shifted), a._mm256_castpd_si256(shift));
    let two_k = a._mm256_castsi256_pd(
        i._mm256_slli_epi64::<52>(i._mm256_add_epi64(ki, a._mm256_set1_epi64x(1023))),
    );
    a._mm256_mul_pd(p, two_k)
}

/// `1 / i!` for `i = 0 … 13`.
#[cfg(target_arch = "x86_64")]
const TAYLOR: [f64; 14] = [
    1.0,
    1.0,
    1.0 / 2.0,
    1.0 / 6.0,
    1.0 / 24.0,
    1.0 / 120.0,
    1.0 / 720.0,
    1.0 / 5_040.0,
    1.0 / 40_320.0,
    1.0 / 362_880.0,
    1.0 / 3_628_800.0,
    1.0 / 39_916_800.0,
    1.0 / 479_001_600.0,
    1.0 / 6_227_020_800.0,
];

#[cfg(test)]
mod tests {
    use super::*;

    /// The plain E-step (the loop of coherent.rs before the lanes), as the oracle.
    fn plain(moved: &[f64], y: &[f64], d: usize, var: f64) -> (Vec<f64>, Vec<f64>, f64, f64) {
        let (n, m) = (moved.len() / d, y.len() / d);
        let scale = 1.0 / (2.0 * var);
        let mut p = vec![0.0; n * m];
        let mut near = vec![f64::INFINITY; m];
        for i in 0..n {
            for j in 0..m {
                let d2: f64 = (0..d)
                    .map(|c| (moved[i * d + c] - y[j * d + c]).powi(2))
                    .sum();
                let t = d2 * scale;
                p[i * m + j] = t;
                near[j] = near[j].min(t);
            }
        }
        let mut col = vec![0.0; m];
        for i in 0..n {
            for j in 0..m {
                let t = p[i * m + j] - near[j];
                let e = if t < NEGLIGIBLE { (-t).exp() } else { 0.0 };
                p[i * m + j] = e;
                col[j] += e;
            }
        }
        let (mut rows, mut pulled, mut total, mut y_term) =
            (vec![0.0; n], vec![0.0; n * d], 0.0, 0.0);
        for i in 0..n {
            for j in 0..m {
                if col[j] > 0.0 && p[i * m + j] > 0.0 {
                    let pij = p[i * m + j] / col[j];
                    rows[i] += pij;
                    for c in 0..d {
                        pulled[i * d + c] += pij * y[j * d + c];
                        y_term += pij * y[j * d + c] * y[j * d + c];
                    }
                }
            }
            total += rows[i];
        }
        (rows, pulled, total, y_term)
    }

    /// A wobbly closed curve of `k` nodes in `d` dimensions.
    fn nodes(k: usize, d: usize, phase: f64) -> Vec<f64> {
        (0..k)
            .flat_map(|i| {
                let t = i as f64 / k as f64 * std::f64::consts::TAU + phase;
                let r = 1.0 + 0.2 * (3.0 * t).cos();
                (0..d).map(move |c| r * (t + c as f64 * 1.3).cos() + 0.1 * c as f64)
            })
            .collect()
    }

    #[test]
    #[cfg(target_arch = "x86_64")]
    fn exp_neg_is_the_library_exp_within_a_few_ulps() {
        // Each lane width this CPU has, called explicitly (dispatch takes the widest only).
        struct Exp(Vec<f64>);
        impl crate::simd::Kernel for Exp {
            type Output = Vec<f64>;
            #[inline(always)]
            fn avx512(self, simd: pulp::x86::V4) -> Vec<f64> {
                self.0
                    .chunks_exact(LANES)
                    .flat_map(|c| {
                        let v: [f64; 8] = pulp::cast(exp_neg_avx512(simd, simd.load(c, 0)));
                        v
                    })
                    .collect()
            }
            #[inline(always)]
            fn avx2(self, simd: pulp::x86::V3) -> Vec<f64> {
                self.0
                    .chunks_exact(4)
                    .flat_map(|c| {
                        let v: [f64; 4] = pulp::cast(exp_neg_avx2(simd, simd.load(c, 0)));
                        v
                    })
                    .collect()
            }
            fn baseline(self) -> Vec<f64> {
                unreachable!()
            }
        }
        let t: Vec<f64> = (0..36 * 8000).map(|k| k as f64 / 8000.0).collect();
        let mut runs = Vec::new();
        if let Some(simd) = pulp::x86::V4::try_new() {
            runs.push(("avx512", crate::simd::on_avx512(simd, Exp(t.clone()))));
        }
        if let Some(simd) = pulp::x86::V3::try_new() {
            runs.push(("avx2", crate::simd::on_avx2(simd, Exp(t.clone()))));
        }
        for (unit, got) in runs {
            assert_eq!(got.len(), t.len(), "{unit}");
            let worst = t
                .iter()
                .zip(&got)
                .map(|(t, g)| ((g - (-t).exp()) / (-t).exp()).abs())
                .fold(0.0, f64::max);
            assert!(
                worst < 4.0 * f64::EPSILON,
                "{unit}: relative error {worst:e}"
            );
        }
    }

    #[test]
    fn normal_matrix_is_the_entry_by_entry_update_bit_for_bit() {
        let (n, k) = (37, 15);
        let basis: Vec<f64> = (0..n * k).map(|v| (v as f64 * 0.731).sin()).collect();
        let row_sums: Vec<f64> = (0..n)
            .map(|i| {
                if i % 5 == 0 {
                    0.0
                } else {
                    1.0 + (i as f64).cos()
                }
            })
            .collect();
        let mut want = faer::Mat::<f64>::zeros(k, k);
        for i in 0..n {
            let (row, p1) = (&basis[i * k..(i + 1) * k], row_sums[i]);
            if p1 > 0.0 {
                for a in 0..k {
                    for b in 0..=a {
                        want[(a, b)] += p1 * row[a] * row[b];
                    }
                }
            }
        }
        let mut got = faer::Mat::<f64>::zeros(k, k);
        normal_matrix(&basis, k, &row_sums, &mut got);
        for a in 0..k {
            for b in 0..k {
                assert_eq!(got[(a, b)].to_bits(), want[(a, b)].to_bits(), "({a}, {b})");
            }
        }
    }

    #[test]
    fn every_unit_gives_the_plain_steps_sums() {
        // Counts on and off whole lanes, 2-D, 3-D and 4-D, and a
        // variance small enough that most responsibilities are skipped; the dispatched kernel
        // (AVX-512 where the CPU has it), the AVX2 kernel called explicitly where the CPU has
        // AVX2 (dispatch would not pick it on an AVX-512 CPU), and the loops of the baseline.
        for (d, n, m) in [(2, 97, 110), (2, 8, 16), (2, 5, 3), (3, 40, 33), (4, 12, 9)] {
            for var in [1.0, 0.02, 1e-4] {
                let x = nodes(n, d, 0.0);
                let y = nodes(m, d, 0.21);
                let (rows, pulled, total, y_term) = plain(&x, &y, d, var);
                for unit in ["dispatched", "avx2", "plain"] {
                    let mut post = Posterior::new(&y, d, n);
                    let scale = 1.0 / (2.0 * var);
                    match unit {
                        "dispatched" => post.update(&x, var),
                        "avx2" => {
                            if !step_on_avx2(&mut post, &x, scale) {
                                continue;
                            }
                        }
                        _ => step_any(&mut post, &x, scale),
                    }
                    let close = |a: f64, b: f64| (a - b).abs() <= 1e-13 * (1.0 + b.abs());
                    let at = format!("d {d}, n {n}, m {m}, var {var}, {unit}");
                    assert!(close(post.total, total), "{at}: {} {total}", post.total);
                    assert!(close(post.y_term, y_term), "{at}: {} {y_term}", post.y_term);
                    for (a, b) in post.row_sums.iter().zip(&rows) {
                        assert!(close(*a, *b), "{at}: row {a} {b}");
                    }
                    for (a, b) in post.pulled.iter().zip(&pulled) {
                        assert!(close(*a, *b), "{at}: pulled {a} {b}");
                    }
                    // Every column holds a mass of one.
                    assert!((total - m as f64).abs() < 1e-9, "{at}: {total}");
                }
            }
        }
    }

    /// One E-step by the AVX2 kernel (the plain loops for dimensions other than 2 and 3, as
    /// [`Posterior::update`] does); false where the CPU has no AVX2.
    fn step_on_avx2(post: &mut Posterior, moved: &[f64], scale: f64) -> bool {
        #[cfg(target_arch = "x86_64")]
        if let Some(simd) = pulp::x86::V3::try_new() {
            match post.d {
                2 => crate::simd::on_avx2(simd, Step::<2> { post, moved, scale }),
                3 => crate::simd::on_avx2(simd, Step::<3> { post, moved, scale }),
                _ => step_any(post, moved, scale),
            }
            return true;
        }
        let _ = (post, moved, scale);
        false
    }
}
