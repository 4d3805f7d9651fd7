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

use crate::simd::{widest_simd, Lanes};

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

widest_simd! {
    /// `counts[j]` ← the number of eigenvalues below `x[j]` (the sign changes of the Sturm
    /// sequence), on the widest vector unit this CPU has. `x.len()` is a multiple of [`LANES`].
    fn sturm_counts(d: &[f64], e2: &[f64], x: &[f64], counts: &mut [u64]);
    // 6 vectors × (x, prev, cur, count) = 24 of the 32 registers.
    avx512 sturm_counts_avx512 => sturm_counts_in::<8, 6>(d, e2, x, counts);
    // 3 vectors × (x, prev, cur, count) = 12 of the 16 registers.
    avx2 sturm_counts_avx2 [] => sturm_counts_in::<4, 3>(d, e2, x, counts);
    portable => sturm_counts_in::<4, 2>(d, e2, x, counts);
}

const EXPONENT_BITS: u64 = 0x7ff0_0000_0000_0000;
/// `2^(1023 − E)` has the biased exponent `2046 − E`.
const INVERSE_EXPONENT: u64 = 2046 << 52;

/// The vectors of `W` lanes of `x` in groups of at most `GROUP` whose recurrences run side by
/// side (each one's multiply–subtract chain waits while the others compute; as many as fit in
/// the registers with their state), balanced: five vectors with groups of six run as one group
/// of five, not six and none.
#[inline(always)]
fn sturm_counts_in<const W: usize, const GROUP: usize>(
    d: &[f64],
    e2: &[f64],
    x: &[f64],
    counts: &mut [u64],
) {
    let vectors = x.len() / W;
    let groups = vectors.div_ceil(GROUP);
    let mut start = 0;
    for g in 0..groups {
        let end = (g + 1) * vectors / groups;
        let (xs, cs) = (&x[start * W..end * W], &mut counts[start * W..end * W]);
        match end - start {
            1 => sturm_group::<W, 1>(d, e2, xs, cs),
            2 => sturm_group::<W, 2>(d, e2, xs, cs),
            3 => sturm_group::<W, 3>(d, e2, xs, cs),
            4 => sturm_group::<W, 4>(d, e2, xs, cs),
            5 => sturm_group::<W, 5>(d, e2, xs, cs),
            _ => sturm_group::<W, 6>(d, e2, xs, cs),
        }
        start = end;
    }
}

/// `(d − x)·cur − e·prev`, unfused: the same bits at every width.
#[inline(always)]
fn step<const W: usize>(
    d: Lanes<W>,
    x: Lanes<W>,
    e: Lanes<W>,
    cur: Lanes<W>,
    prev: Lanes<W>,
) -> Lanes<W> {
    (d - x) * cur - e * prev
}

/// `count + 1` in the lanes where `p` and `cur` differ in sign.
#[inline(always)]
fn count_change<const W: usize>(count: [u64; W], p: Lanes<W>, cur: Lanes<W>) -> [u64; W] {
    // Wrapping (counts stay below the order): no overflow check per lane in debug builds.
    std::array::from_fn(|l| count[l].wrapping_add((p.0[l].to_bits() ^ cur.0[l].to_bits()) >> 63))
}

/// Divides both by the power of two of the larger magnitude of the pair, lane by lane (exact).
#[inline(always)]
fn rescale<const W: usize>(prev: Lanes<W>, cur: Lanes<W>) -> (Lanes<W>, Lanes<W>) {
    let f = prev.zip(cur, |a, b| {
        let (a, b) = (a.abs(), b.abs());
        let top = if a > b { a } else { b }.to_bits() & EXPONENT_BITS;
        f64::from_bits(INVERSE_EXPONENT.wrapping_sub(top))
    });
    (prev * f, cur * f)
}

/// The recurrence for `G` vectors at once, their state in registers.
#[inline(always)]
fn sturm_group<const W: usize, const G: usize>(
    d: &[f64],
    e2: &[f64],
    x: &[f64],
    counts: &mut [u64],
) {
    let n = d.len();
    let x: [Lanes<W>; G] = std::array::from_fn(|g| Lanes::load(&x[g * W..]));
    // p₀ = 1, p₁ = d₀ − x.
    let one = Lanes::splat(1.0);
    let mut prev = [one; G];
    let mut cur = [one; G];
    let mut cnt = [[0u64; W]; G];
    let (d0, zero) = (Lanes::splat(d[0]), Lanes::splat(0.0));
    for g in 0..G {
        cur[g] = step(d0, x[g], zero, one, one);
        cnt[g] = count_change(cnt[g], cur[g], one);
    }
    for i in 1..n {
        let (di, ei) = (Lanes::splat(d[i]), Lanes::splat(e2[i - 1]));
        for g in 0..G {
            // An exact zero needs no special case: with e² > 0 the next term has the sign
            // opposite to the one before the zero, so the pair still counts one change.
            let p = step(di, x[g], ei, cur[g], prev[g]);
            cnt[g] = count_change(cnt[g], p, cur[g]);
            prev[g] = cur[g];
            cur[g] = p;
        }
        if i % RESCALE_EVERY == 0 {
            for g in 0..G {
                (prev[g], cur[g]) = rescale(prev[g], cur[g]);
            }
        }
    }
    for g in 0..G {
        counts[g * W..(g + 1) * W].copy_from_slice(&cnt[g]);
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

    fn lcg(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    }

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
            let diag: Vec<f64> = (0..n).map(|_| 4.0 * lcg(&mut seed)).collect();
            let off: Vec<f64> = (0..n.saturating_sub(1)).map(|_| lcg(&mut seed)).collect();
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
        let diag: Vec<f64> = (0..n).map(|_| lcg(&mut seed)).collect();
        let off: Vec<f64> = (0..n - 1).map(|_| lcg(&mut seed)).collect();
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
        let diag: Vec<f64> = (0..n).map(|_| lcg(&mut seed)).collect();
        let off: Vec<f64> = (0..n - 1).map(|_| lcg(&mut seed)).collect();
        let e2: Vec<f64> = off.iter().map(|o| (o * o).max(E2_FLOOR)).collect();
        let all = jacobi_eigenvalues(&diag, &off);
        // 1 … 13 vectors of 8 lanes: every group size of every path, and several groups.
        for vectors in 1..=13 {
            let x: Vec<f64> = (0..vectors * LANES).map(|_| 2.0 * lcg(&mut seed)).collect();
            let run = |f: &dyn Fn(&mut [u64])| {
                let mut counts = vec![0u64; x.len()];
                f(&mut counts);
                counts
            };
            let portable = run(&|c| sturm_counts_in::<4, 2>(&diag, &e2, &x, c));
            assert_eq!(portable, run(&|c| sturm_counts(&diag, &e2, &x, c)));
            #[cfg(target_arch = "x86_64")]
            {
                if std::is_x86_feature_detected!("avx2") {
                    // SAFETY: AVX2 was just detected.
                    let avx2 = run(&|c| unsafe { sturm_counts_avx2(&diag, &e2, &x, c) });
                    assert_eq!(portable, avx2, "AVX2, {vectors} vectors");
                }
                if std::is_x86_feature_detected!("avx512f") {
                    // SAFETY: AVX-512F was just detected.
                    let avx512 = run(&|c| unsafe { sturm_counts_avx512(&diag, &e2, &x, c) });
                    assert_eq!(portable, avx512, "AVX-512, {vectors} vectors");
                }
            }
            // The counts themselves, against the dense oracle.
            for (j, xj) in x.iter().enumerate() {
                let want = all.iter().filter(|&&e| e < *xj).count() as u64;
                assert_eq!(portable[j], want, "x = {xj}");
            }
        }
    }
}
