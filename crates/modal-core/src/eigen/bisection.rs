//! The lowest eigenvalues of a symmetric tridiagonal matrix by bisection on Sturm counts.
//!
//! A modal solve needs about a quarter of the spectrum. The root-free QL iteration finds every
//! eigenvalue along one dependent chain of divisions (~35 cycles a step); bisection finds just
//! the wanted ones, each in its own lane, so the lanes fill the vector units. The count uses the
//! characteristic-polynomial recurrence `p_i = (d_i − x)·p_{i−1} − e²_{i−1}·p_{i−2}` rather than
//! LAPACK's ratio form `q_i = d_i − x − e²_{i−1}/q_{i−1}`: no division at all, which is what makes
//! the lanes cheap. Its rounding errors are those of the ratio form (each computed `p_i / p_{i−1}`
//! is the exact ratio for `d_i − x` and `e²_{i−1}` perturbed by a few ulps), so the counts are as
//! trustworthy as `dstebz`'s; what the ratio form gets for free, a safe range, comes from scaling
//! the pair `(p_{i−1}, p_i)` by a power of two every few steps (exact).

use crate::simd::{dispatch, Kernel};

/// Lanes are padded to a multiple of this (one AVX-512 register, two AVX2 registers).
const LANES: usize = 8;

/// Steps between two renormalisations of the recurrence. Between them `|p|` grows by at most
/// `(‖T‖ + |x| + max e²)⁴ < 2¹²` on the scaled matrix and its pair maximum shrinks by at most
/// `(E2_FLOOR / 4)⁴ ≈ 2⁻⁴⁹⁰`, both far inside the exponent range (no overflow, no subnormals).
const RESCALE_EVERY: usize = 4;

/// Squared off-diagonals are raised to at least this (relative to a largest entry of ~1): an
/// off-diagonal perturbation of 2⁻⁶⁰‖T‖, far below rounding, that keeps the recurrence from
/// collapsing to zero at a split (`e = 0` and `p_i = 0` would zero every later `p`).
const E2_FLOOR: f64 = 7.523_163_845_262_64e-37; // 2⁻¹²⁰

/// The `k` lowest eigenvalues (ascending) of the symmetric tridiagonal matrix with diagonal
/// `diag` and off-diagonal `off`, each to an absolute accuracy of a few `ε·‖T‖` (the accuracy of
/// the QL iteration). `k` is clamped to the order. The results do not depend on the CPU's
/// vector width: every path does the same operations in the same order, without FMA.
pub(crate) fn lowest_eigenvalues(diag: &[f64], off: &[f64], k: usize) -> Vec<f64> {
    let n = diag.len();
    let k = k.min(n);
    if k == 0 {
        return Vec::new();
    }
    // A power of two (exact) that brings the largest entry to about 1, as the QL does.
    let amax = diag.iter().chain(off).fold(0.0f64, |m, v| m.max(v.abs()));
    if amax == 0.0 {
        return vec![0.0; k];
    }
    let scale_exp = (amax.log2().round() as i32).clamp(-1000, 1000);
    let (down, up) = (2f64.powi(-scale_exp), 2f64.powi(scale_exp));
    let d: Vec<f64> = diag.iter().map(|v| v * down).collect();
    let e2: Vec<f64> = off
        .iter()
        .map(|o| ((o * down) * (o * down)).max(E2_FLOOR))
        .collect();

    // Gershgorin bounds, widened by the rounding of the counts (as dstebz widens them).
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut tnorm = 0.0f64;
    for i in 0..n {
        let r =
            if i > 0 { e2[i - 1].sqrt() } else { 0.0 } + if i + 1 < n { e2[i].sqrt() } else { 0.0 };
        lo = lo.min(d[i] - r);
        hi = hi.max(d[i] + r);
        tnorm = tnorm.max(d[i].abs() + r);
    }
    let pad = 2.0 * f64::EPSILON * tnorm * n as f64;
    lo -= pad;
    hi += pad;
    let abs_tol = f64::EPSILON * tnorm;

    let lanes = k.div_ceil(LANES) * LANES;
    let (mut a, mut b) = (vec![lo; lanes], vec![hi; lanes]);
    let mut x = vec![lo; lanes];
    let mut counts = vec![0u64; lanes];
    loop {
        let mut open = false;
        for j in 0..lanes {
            let (aj, bj) = (a[j], b[j]);
            // Converged lanes keep evaluating at their midpoint: a vector runs whole.
            let width_ok = bj - aj <= abs_tol.max(2.0 * f64::EPSILON * aj.abs().max(bj.abs()));
            open |= !width_ok && j < k;
            x[j] = 0.5 * (aj + bj);
        }
        if !open {
            break;
        }
        sturm_counts(&d, &e2, &x, &mut counts);
        for j in 0..lanes {
            // Lane j brackets the (j+1)-th smallest eigenvalue: N(a) ≤ j < N(b), where N(x)
            // counts the eigenvalues below x.
            if counts[j] > j as u64 {
                b[j] = x[j];
            } else {
                a[j] = x[j];
            }
        }
    }
    let mut values: Vec<f64> = (0..k).map(|j| 0.5 * (a[j] + b[j]) * up).collect();
    // Counts that are not monotone by an ulp could leave neighbours out of order.
    values.sort_by(f64::total_cmp);
    values
}

const EXPONENT_BITS: u64 = 0x7ff0_0000_0000_0000;
/// `2^(1023 − E)` has the biased exponent `2046 − E`.
const INVERSE_EXPONENT: u64 = 2046 << 52;

/// `counts[j]` ← the number of eigenvalues below `x[j]` (the sign changes of the Sturm
/// sequence), on the widest vector unit this CPU has. `x.len()` is a multiple of [`LANES`].
fn sturm_counts(d: &[f64], e2: &[f64], x: &[f64], counts: &mut [u64]) {
    dispatch(SturmCounts { d, e2, x, counts })
}

/// The arguments of [`sturm_counts`], run by [`crate::simd::dispatch`].
struct SturmCounts<'a> {
    d: &'a [f64],
    e2: &'a [f64],
    x: &'a [f64],
    counts: &'a mut [u64],
}

impl Kernel for SturmCounts<'_> {
    type Output = ();
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn avx512(self, simd: pulp::x86::V4) {
        sturm_counts_in(simd, self.d, self.e2, self.x, self.counts)
    }
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn avx2(self, simd: pulp::x86::V3) {
        sturm_counts_in(simd, self.d, self.e2, self.x, self.counts)
    }
    #[inline(always)]
    fn baseline(self) {
        sturm_counts_in(Baseline, self.d, self.e2, self.x, self.counts)
    }
}

/// The operations of the recurrence on one vector of lanes of the unit `Self` (a pulp token, or
/// [`Baseline`]). Every implementation does the same IEEE operations in the same order (no FMA),
/// so every path gives the same bits.
trait SturmUnit: Copy {
    const WIDTH: usize;
    /// Vectors whose recurrences run side by side, so that each one's multiply–subtract chain
    /// waits while the others compute (as many as fit in the registers with their state).
    const GROUP: usize;
    type V: Copy;
    type Count: Copy;
    fn splat(self, v: f64) -> Self::V;
    /// The first `WIDTH` values of `x`.
    fn load(self, x: &[f64]) -> Self::V;
    fn zero_count(self) -> Self::Count;
    /// `(d − x)·cur − e·prev`.
    fn step(self, d: Self::V, x: Self::V, e: Self::V, cur: Self::V, prev: Self::V) -> Self::V;
    /// `count + 1` in the lanes where `p` and `cur` differ in sign.
    fn count_change(self, count: Self::Count, p: Self::V, cur: Self::V) -> Self::Count;
    /// Divides both by the power of two of the larger magnitude of the pair, lane by lane.
    fn rescale(self, prev: Self::V, cur: Self::V) -> (Self::V, Self::V);
    /// Into the first `WIDTH` values of `out`.
    fn store(self, count: Self::Count, out: &mut [u64]);
}

/// Plain code for CPUs without AVX2 (the compiler vectorises what it can).
#[derive(Clone, Copy)]
struct Baseline;

impl SturmUnit for Baseline {
    const WIDTH: usize = 4;
    const GROUP: usize = 2;
    type V = [f64; 4];
    type Count = [u64; 4];
    #[inline(always)]
    fn splat(self, v: f64) -> [f64; 4] {
        [v; 4]
    }
    #[inline(always)]
    fn load(self, x: &[f64]) -> [f64; 4] {
        *x.first_chunk().expect("a full vector")
    }
    #[inline(always)]
    fn zero_count(self) -> [u64; 4] {
        [0; 4]
    }
    #[inline(always)]
    fn step(
        self,
        d: [f64; 4],
        x: [f64; 4],
        e: [f64; 4],
        cur: [f64; 4],
        prev: [f64; 4],
    ) -> [f64; 4] {
        std::array::from_fn(|l| (d[l] - x[l]) * cur[l] - e[l] * prev[l])
    }
    #[inline(always)]
    fn count_change(self, count: [u64; 4], p: [f64; 4], cur: [f64; 4]) -> [u64; 4] {
        std::array::from_fn(|l| count[l] + ((p[l].to_bits() ^ cur[l].to_bits()) >> 63))
    }
    #[inline(always)]
    fn rescale(self, prev: [f64; 4], cur: [f64; 4]) -> ([f64; 4], [f64; 4]) {
        let f: [f64; 4] = std::array::from_fn(|l| {
            let (a, b) = (prev[l].abs(), cur[l].abs());
            let top = if a > b { a } else { b }.to_bits() & EXPONENT_BITS;
            f64::from_bits(INVERSE_EXPONENT.wrapping_sub(top))
        });
        (
            std::array::from_fn(|l| prev[l] * f[l]),
            std::array::from_fn(|l| cur[l] * f[l]),
        )
    }
    #[inline(always)]
    fn store(self, count: [u64; 4], out: &mut [u64]) {
        *out.first_chunk_mut().expect("a full vector") = count;
    }
}

#[cfg(target_arch = "x86_64")]
mod units {
    use super::{SturmUnit, EXPONENT_BITS, INVERSE_EXPONENT};
    use core::arch::x86_64::{__m256d, __m256i, __m512d, __m512i};
    use pulp::x86::{V3, V4};

    impl SturmUnit for V4 {
        const WIDTH: usize = 8;
        // 6 vectors × (x, prev, cur, count) = 24 of the 32 registers.
        const GROUP: usize = 6;
        type V = __m512d;
        type Count = __m512i;
        #[inline(always)]
        fn splat(self, v: f64) -> __m512d {
            self.avx512f._mm512_set1_pd(v)
        }
        #[inline(always)]
        fn load(self, x: &[f64]) -> __m512d {
            pulp::cast(*x.first_chunk::<8>().expect("a full vector"))
        }
        #[inline(always)]
        fn zero_count(self) -> __m512i {
            self.avx512f._mm512_setzero_si512()
        }
        #[inline(always)]
        fn step(self, d: __m512d, x: __m512d, e: __m512d, cur: __m512d, prev: __m512d) -> __m512d {
            let f = self.avx512f;
            let t = f._mm512_mul_pd(f._mm512_sub_pd(d, x), cur);
            f._mm512_sub_pd(t, f._mm512_mul_pd(e, prev))
        }
        #[inline(always)]
        fn count_change(self, count: __m512i, p: __m512d, cur: __m512d) -> __m512i {
            let f = self.avx512f;
            let signs = f._mm512_xor_si512(f._mm512_castpd_si512(p), f._mm512_castpd_si512(cur));
            f._mm512_add_epi64(count, f._mm512_srli_epi64::<63>(signs))
        }
        #[inline(always)]
        fn rescale(self, prev: __m512d, cur: __m512d) -> (__m512d, __m512d) {
            let f = self.avx512f;
            let top = f._mm512_max_pd(f._mm512_abs_pd(prev), f._mm512_abs_pd(cur));
            let top = f._mm512_and_si512(
                f._mm512_castpd_si512(top),
                f._mm512_set1_epi64(EXPONENT_BITS as i64),
            );
            let s = f._mm512_castsi512_pd(
                f._mm512_sub_epi64(f._mm512_set1_epi64(INVERSE_EXPONENT as i64), top),
            );
            (f._mm512_mul_pd(prev, s), f._mm512_mul_pd(cur, s))
        }
        #[inline(always)]
        fn store(self, count: __m512i, out: &mut [u64]) {
            *out.first_chunk_mut::<8>().expect("a full vector") = pulp::cast(count);
        }
    }

    impl SturmUnit for V3 {
        const WIDTH: usize = 4;
        // 3 vectors × (x, prev, cur, count) = 12 of the 16 registers.
        const GROUP: usize = 3;
        type V = __m256d;
        type Count = __m256i;
        #[inline(always)]
        fn splat(self, v: f64) -> __m256d {
            self.avx._mm256_set1_pd(v)
        }
        #[inline(always)]
        fn load(self, x: &[f64]) -> __m256d {
            pulp::cast(*x.first_chunk::<4>().expect("a full vector"))
        }
        #[inline(always)]
        fn zero_count(self) -> __m256i {
            self.avx._mm256_setzero_si256()
        }
        #[inline(always)]
        fn step(self, d: __m256d, x: __m256d, e: __m256d, cur: __m256d, prev: __m256d) -> __m256d {
            let a = self.avx;
            let t = a._mm256_mul_pd(a._mm256_sub_pd(d, x), cur);
            a._mm256_sub_pd(t, a._mm256_mul_pd(e, prev))
        }
        #[inline(always)]
        fn count_change(self, count: __m256i, p: __m256d, cur: __m256d) -> __m256i {
            let (a, a2) = (self.avx, self.avx2);
            let signs = a2._mm256_xor_si256(a._mm256_castpd_si256(p), a._mm256_castpd_si256(cur));
            a2._mm256_add_epi64(count, a2._mm256_srli_epi64::<63>(signs))
        }
        #[inline(always)]
        fn rescale(self, prev: __m256d, cur: __m256d) -> (__m256d, __m256d) {
            let (a, a2) = (self.avx, self.avx2);
            let abs = a._mm256_castsi256_pd(a._mm256_set1_epi64x(i64::MAX));
            let top = a._mm256_max_pd(a._mm256_and_pd(prev, abs), a._mm256_and_pd(cur, abs));
            let top = a2._mm256_and_si256(
                a._mm256_castpd_si256(top),
                a._mm256_set1_epi64x(EXPONENT_BITS as i64),
            );
            let s = a._mm256_castsi256_pd(
                a2._mm256_sub_epi64(a._mm256_set1_epi64x(INVERSE_EXPONENT as i64), top),
            );
            (a._mm256_mul_pd(prev, s), a._mm256_mul_pd(cur, s))
        }
        #[inline(always)]
        fn store(self, count: __m256i, out: &mut [u64]) {
            *out.first_chunk_mut::<4>().expect("a full vector") = pulp::cast(count);
        }
    }
}

/// The vectors of `x` in groups of at most `U::GROUP`, balanced (five vectors with groups of
/// six run as one group of five, not six and none).
#[inline(always)]
fn sturm_counts_in<U: SturmUnit>(unit: U, d: &[f64], e2: &[f64], x: &[f64], counts: &mut [u64]) {
    let vectors = x.len() / U::WIDTH;
    let groups = vectors.div_ceil(U::GROUP);
    let mut start = 0;
    for g in 0..groups {
        let end = (g + 1) * vectors / groups;
        let (xs, cs) = (
            &x[start * U::WIDTH..end * U::WIDTH],
            &mut counts[start * U::WIDTH..end * U::WIDTH],
        );
        match end - start {
            1 => sturm_group::<U, 1>(unit, d, e2, xs, cs),
            2 => sturm_group::<U, 2>(unit, d, e2, xs, cs),
            3 => sturm_group::<U, 3>(unit, d, e2, xs, cs),
            4 => sturm_group::<U, 4>(unit, d, e2, xs, cs),
            5 => sturm_group::<U, 5>(unit, d, e2, xs, cs),
            _ => sturm_group::<U, 6>(unit, d, e2, xs, cs),
        }
        start = end;
    }
}

/// The recurrence for `G` vectors at once, their state in registers.
#[inline(always)]
fn sturm_group<U: SturmUnit, const G: usize>(
    unit: U,
    d: &[f64],
    e2: &[f64],
    x: &[f64],
    counts: &mut [u64],
) {
    let n = d.len();
    // p₀ = 1, p₁ = d₀ − x. (Loops rather than `array::from_fn`: a closure is a function of its
    // own, compiled without the unit's instructions unless inlined.)
    let one = unit.splat(1.0);
    let mut xs = [one; G];
    for (g, xg) in xs.iter_mut().enumerate() {
        *xg = unit.load(&x[g * U::WIDTH..]);
    }
    let x = xs;
    let mut prev = [one; G];
    let mut cur = [one; G];
    let mut cnt = [unit.zero_count(); G];
    let (d0, zero) = (unit.splat(d[0]), unit.splat(0.0));
    for g in 0..G {
        cur[g] = unit.step(d0, x[g], zero, one, one);
        cnt[g] = unit.count_change(cnt[g], cur[g], one);
    }
    for i in 1..n {
        let (di, ei) = (unit.splat(d[i]), unit.splat(e2[i - 1]));
        for g in 0..G {
            // An exact zero needs no special case: with e² > 0 the next term has the sign
            // opposite to the one before the zero, so the pair still counts one change.
            let p = unit.step(di, x[g], ei, cur[g], prev[g]);
            cnt[g] = unit.count_change(cnt[g], p, cur[g]);
            prev[g] = cur[g];
            cur[g] = p;
        }
        if i % RESCALE_EVERY == 0 {
            for g in 0..G {
                (prev[g], cur[g]) = unit.rescale(prev[g], cur[g]);
            }
        }
    }
    for g in 0..G {
        unit.store(cnt[g], &mut counts[g * U::WIDTH..]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every eigenvalue of a symmetric tridiagonal matrix by Jacobi rotations on the dense
    /// matrix: slow and simple, an oracle independent of both QL and bisection.
    fn jacobi_eigenvalues(diag: &[f64], off: &[f64]) -> Vec<f64> {
        let n = diag.len();
        let mut a = vec![vec![0.0; n]; n];
        for i in 0..n {
            a[i][i] = diag[i];
            if i + 1 < n {
                a[i][i + 1] = off[i];
                a[i + 1][i] = off[i];
            }
        }
        let total: f64 = a.iter().flatten().map(|v| v * v).sum();
        for _sweep in 0..100 {
            let off_norm: f64 = (0..n)
                .flat_map(|i| (0..n).filter(move |&j| j != i).map(move |j| (i, j)))
                .map(|(i, j)| a[i][j] * a[i][j])
                .sum();
            if off_norm <= 1e-40 * total {
                break;
            }
            for p in 0..n {
                for q in p + 1..n {
                    if a[p][q] == 0.0 {
                        continue;
                    }
                    let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                    let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                    let t = if theta == 0.0 { 1.0 } else { t };
                    let c = 1.0 / (t * t + 1.0).sqrt();
                    let s = t * c;
                    for r in 0..n {
                        let (arp, arq) = (a[r][p], a[r][q]);
                        a[r][p] = c * arp - s * arq;
                        a[r][q] = s * arp + c * arq;
                    }
                    for r in 0..n {
                        let (apr, aqr) = (a[p][r], a[q][r]);
                        a[p][r] = c * apr - s * aqr;
                        a[q][r] = s * apr + c * aqr;
                    }
                }
            }
        }
        let mut v: Vec<f64> = (0..n).map(|i| a[i][i]).collect();
        v.sort_by(f64::total_cmp);
        v
    }

    use crate::eigen::random_start;

    fn assert_close(got: &[f64], want: &[f64], tnorm: f64, what: &str) {
        assert_eq!(got.len(), want.len(), "{what}");
        for (j, (g, w)) in got.iter().zip(want).enumerate() {
            assert!(
                (g - w).abs() <= 64.0 * f64::EPSILON * tnorm,
                "{what}: eigenvalue {j}: {g} vs {w} (‖T‖ = {tnorm})"
            );
        }
    }

    fn norm(diag: &[f64], off: &[f64]) -> f64 {
        (0..diag.len())
            .map(|i| {
                diag[i].abs()
                    + if i > 0 { off[i - 1].abs() } else { 0.0 }
                    + off.get(i).map_or(0.0, |o| o.abs())
            })
            .fold(0.0, f64::max)
    }

    #[test]
    fn random_matrices_match_jacobi_at_every_k() {
        let mut seed = 11u64;
        for n in [1usize, 2, 3, 7, 8, 9, 16, 17, 40, 65] {
            let diag: Vec<f64> = (0..n).map(|_| 4.0 * random_start(&mut seed)).collect();
            let off: Vec<f64> = (0..n.saturating_sub(1))
                .map(|_| random_start(&mut seed))
                .collect();
            let all = jacobi_eigenvalues(&diag, &off);
            let t = norm(&diag, &off);
            for k in [1, n / 4, n / 2 + 1, n] {
                let got = lowest_eigenvalues(&diag, &off, k);
                assert_close(&got, &all[..k.min(n)], t, &format!("n {n}, k {k}"));
            }
        }
    }

    #[test]
    fn splits_zeros_and_repeated_eigenvalues() {
        // Exact zeros on the off-diagonal (a split matrix), eigenvalues repeated across the
        // blocks and bisection midpoints that land exactly on diagonal entries.
        let diag = [1.0, 1.0, 0.0, 2.0, 1.0, 1.0, -3.0, 0.5, 0.5];
        let off = [0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        let want = jacobi_eigenvalues(&diag, &off);
        let t = norm(&diag, &off);
        assert_close(&lowest_eigenvalues(&diag, &off, 9), &want, t, "split");
        // A diagonal matrix: its sorted diagonal.
        let diag: Vec<f64> = (0..20).map(|i| ((i * 7) % 5) as f64).collect();
        let off = vec![0.0; 19];
        let mut want = diag.clone();
        want.sort_by(f64::total_cmp);
        assert_close(&lowest_eigenvalues(&diag, &off, 20), &want, 4.0, "diagonal");
        // The 1-2-1 matrix: eigenvalues 2 − 2cos(jπ/(n+1)), closely spaced at the bottom.
        let n = 200;
        let want: Vec<f64> = (1..=n)
            .map(|j| 2.0 - 2.0 * (j as f64 * std::f64::consts::PI / (n as f64 + 1.0)).cos())
            .collect();
        let got = lowest_eigenvalues(&vec![2.0; n], &vec![-1.0; n - 1], 50);
        assert_close(&got, &want[..50], 4.0, "1-2-1");
        // Wilkinson's W21+: pairs of eigenvalues equal to ~15 digits.
        let diag: Vec<f64> = (0..21i32).map(|i| (10 - i).abs() as f64).collect();
        let off = vec![1.0; 20];
        let want = jacobi_eigenvalues(&diag, &off);
        assert_close(&lowest_eigenvalues(&diag, &off, 21), &want, 12.0, "W21+");
    }

    #[test]
    fn extreme_scales_stay_in_range() {
        let mut seed = 5u64;
        let n = 60;
        let diag: Vec<f64> = (0..n).map(|_| random_start(&mut seed)).collect();
        let off: Vec<f64> = (0..n - 1).map(|_| random_start(&mut seed)).collect();
        let want = jacobi_eigenvalues(&diag, &off);
        for s in [1e-150, 1e-30, 1e30, 1e150] {
            let d: Vec<f64> = diag.iter().map(|v| v * s).collect();
            let o: Vec<f64> = off.iter().map(|v| v * s).collect();
            let got = lowest_eigenvalues(&d, &o, 20);
            let w: Vec<f64> = want[..20].iter().map(|v| v * s).collect();
            assert_close(&got, &w, norm(&d, &o), &format!("scale {s:e}"));
        }
        // Entries spanning many orders of magnitude (a graded matrix).
        let d: Vec<f64> = (0..n).map(|i| 10f64.powi(i as i32 / 4 - 7)).collect();
        let o: Vec<f64> = (0..n - 1)
            .map(|i| 0.3 * 10f64.powi(i as i32 / 4 - 7))
            .collect();
        let want = jacobi_eigenvalues(&d, &o);
        assert_close(
            &lowest_eigenvalues(&d, &o, n),
            &want,
            norm(&d, &o),
            "graded",
        );
    }

    #[test]
    fn every_vector_path_gives_the_same_bits() {
        let mut seed = 3u64;
        let n = 130;
        let diag: Vec<f64> = (0..n).map(|_| random_start(&mut seed)).collect();
        let off: Vec<f64> = (0..n - 1).map(|_| random_start(&mut seed)).collect();
        let e2: Vec<f64> = off.iter().map(|o| (o * o).max(E2_FLOOR)).collect();
        let all = jacobi_eigenvalues(&diag, &off);
        // 1 … 13 vectors of 8 lanes: every group size of every path, and several groups.
        for vectors in 1..=13 {
            let x: Vec<f64> = (0..vectors * LANES)
                .map(|_| 2.0 * random_start(&mut seed))
                .collect();
            let run = |f: &dyn Fn(&mut [u64])| {
                let mut counts = vec![0u64; x.len()];
                f(&mut counts);
                counts
            };
            let baseline = run(&|counts| sturm_counts_in(Baseline, &diag, &e2, &x, counts));
            assert_eq!(
                baseline,
                run(&|counts| sturm_counts(&diag, &e2, &x, counts))
            );
            #[cfg(target_arch = "x86_64")]
            {
                use crate::simd::{on_avx2, on_avx512};
                let (d, e2, x) = (&diag[..], &e2[..], &x[..]);
                if let Some(simd) = pulp::x86::V3::try_new() {
                    let got = run(&|counts| on_avx2(simd, SturmCounts { d, e2, x, counts }));
                    assert_eq!(baseline, got, "AVX2, {vectors} vectors");
                }
                if let Some(simd) = pulp::x86::V4::try_new() {
                    let got = run(&|counts| on_avx512(simd, SturmCounts { d, e2, x, counts }));
                    assert_eq!(baseline, got, "AVX-512, {vectors} vectors");
                }
            }
            // The counts themselves, against the dense oracle.
            for (j, xj) in x.iter().enumerate() {
                let want = all.iter().filter(|&&e| e < *xj).count() as u64;
                assert_eq!(baseline[j], want, "x = {xj}");
            }
        }
    }
}
