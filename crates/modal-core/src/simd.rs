//! Small vector helpers shared by the numerical kernels.

/// Sum of products with eight independent partial sums: the compiler vectorises it, and the
/// additions do not wait on each other as one running sum's would.
#[inline(always)]
pub(crate) fn dot(x: &[f64], y: &[f64]) -> f64 {
    const W: usize = 8;
    let n = x.len().min(y.len());
    let (x, y) = (&x[..n], &y[..n]);
    let mut acc = [0.0f64; W];
    let (xc, xr) = x.split_at(n - n % W);
    let (yc, yr) = y.split_at(xc.len());
    for (a, b) in xc.chunks_exact(W).zip(yc.chunks_exact(W)) {
        for l in 0..W {
            acc[l] += a[l] * b[l];
        }
    }
    let tail: f64 = xr.iter().zip(yr).map(|(a, b)| a * b).sum();
    acc.iter().sum::<f64>() + tail
}

/// The largest `|x_i|` (0 for an empty slice; NaN entries are passed over, as `f64::max` does),
/// kept in eight lanes: a running maximum waits on the previous comparison at every entry. The
/// maximum of a set does not depend on the order it is taken in, so this is the sequential
/// fold's value exactly.
#[inline(always)]
pub(crate) fn max_abs(x: &[f64]) -> f64 {
    let (lanes, tail) = eight_lanes(x, |m, v| m.max(v.abs()));
    let lanes = lanes.iter().fold(0.0f64, |m, &v| m.max(v));
    tail.iter().fold(lanes, |m, v| m.max(v.abs()))
}

/// The first entry of largest magnitude (0 for an empty slice or one of NaNs): the entry a
/// sequential search keeping the first strict maximum finds.
#[inline(always)]
pub(crate) fn first_largest_abs(x: &[f64]) -> f64 {
    let top = max_abs(x);
    x.iter().copied().find(|v| v.abs() == top).unwrap_or(0.0)
}

/// Whether every entry is finite: `v · 0` is 0 for a finite `v` and NaN for ±∞ and NaN, summed
/// in eight lanes without a branch per entry.
#[inline(always)]
pub(crate) fn all_finite(x: &[f64]) -> bool {
    let (lanes, tail) = eight_lanes(x, |acc, v| acc + v * 0.0);
    lanes.iter().all(|a| *a == 0.0) && tail.iter().all(|v| v.is_finite())
}

/// Folds `x` into eight running values with `step` (lane `l` takes the entries `l`, `l + 8`, …,
/// starting from 0), which the compiler keeps in one vector register; returns them and the
/// entries after the last whole group of eight.
#[inline(always)]
fn eight_lanes(x: &[f64], step: impl Fn(f64, f64) -> f64) -> ([f64; 8], &[f64]) {
    const W: usize = 8;
    let mut acc = [0.0f64; W];
    let (body, tail) = x.split_at(x.len() - x.len() % W);
    for c in body.chunks_exact(W) {
        for l in 0..W {
            acc[l] = step(acc[l], c[l]);
        }
    }
    (acc, tail)
}

/// Clears the upper halves of the vector registers (`vzeroupper`). faer's matrix products run
/// AVX-512 kernels that return with them dirty, and until they are cleared every legacy-SSE
/// instruction — all scalar `f64` code compiled for baseline x86-64, glibc's `exp` — pays for
/// merging them: building a 60-node Gaussian model took 456 µs after a product instead of 126
/// (BENCHMARKS.md, "Eigensolver"). Called after each faer call on the solve path.
pub(crate) fn clear_upper_state() {
    // faer runs scalar code on CPUs without AVX2 (pulp's `V3`): then nothing is dirty.
    #[cfg(target_arch = "x86_64")]
    {
        if let Some(simd) = pulp::x86::V3::try_new() {
            simd.avx._mm256_zeroupper()
        }
    }
}

/// A kernel written once per vector unit: [`dispatch`] runs the copy for the widest unit this
/// CPU has, compiled by `pulp` with that unit's instructions (AVX-512: [`pulp::x86::V4`];
/// AVX2 and FMA: [`pulp::x86::V3`]; else the baseline). The unit arrives as a token whose
/// intrinsic-named methods are safe to call: no `unsafe` for the CPU's features (only raw
/// pointer loads and stores still need it). Implementations
/// mark the three methods `#[inline(always)]`, so that their bodies are compiled inside pulp's
/// `#[target_feature]` function.
pub(crate) trait Kernel: Sized {
    type Output;
    #[cfg(target_arch = "x86_64")]
    fn avx512(self, simd: pulp::x86::V4) -> Self::Output;
    #[cfg(target_arch = "x86_64")]
    fn avx2(self, simd: pulp::x86::V3) -> Self::Output;
    fn baseline(self) -> Self::Output;
}

/// Runs `kernel` on the widest vector unit this CPU has (see [`Kernel`]).
#[inline]
pub(crate) fn dispatch<K: Kernel>(kernel: K) -> K::Output {
    #[cfg(target_arch = "x86_64")]
    {
        if let Some(simd) = pulp::x86::V4::try_new() {
            return on_avx512(simd, kernel);
        }
        if let Some(simd) = pulp::x86::V3::try_new() {
            return on_avx2(simd, kernel);
        }
    }
    kernel.baseline()
}

/// The AVX-512 copy of `kernel` (tests run every copy the CPU has).
#[cfg(target_arch = "x86_64")]
#[inline]
pub(crate) fn on_avx512<K: Kernel>(simd: pulp::x86::V4, kernel: K) -> K::Output {
    struct Copy512<K>(pulp::x86::V4, K);
    impl<K: Kernel> pulp::NullaryFnOnce for Copy512<K> {
        type Output = K::Output;
        #[inline(always)]
        fn call(self) -> K::Output {
            self.1.avx512(self.0)
        }
    }
    simd.vectorize(Copy512(simd, kernel))
}

/// The AVX2 copy of `kernel`.
#[cfg(target_arch = "x86_64")]
#[inline]
pub(crate) fn on_avx2<K: Kernel>(simd: pulp::x86::V3, kernel: K) -> K::Output {
    struct Copy256<K>(pulp::x86::V3, K);
    impl<K: Kernel> pulp::NullaryFnOnce for Copy256<K> {
        type Output = K::Output;
        #[inline(always)]
        fn call(self) -> K::Output {
            self.1.avx2(self.0)
        }
    }
    simd.vectorize(Copy256(simd, kernel))
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    /// Entries with repeats, both signs of a magnitude, zeros and the odd non-finite value, so
    /// that ties and the lanes' boundaries are exercised.
    fn entries() -> impl Strategy<Value = Vec<f64>> {
        let value = prop_oneof![
            8 => (-4i32..=4).prop_map(|v| v as f64 * 0.5),
            4 => -1e3f64..1e3,
            1 => Just(-0.0),
            1 => Just(f64::NAN),
            1 => Just(f64::INFINITY),
            1 => Just(f64::NEG_INFINITY),
        ];
        prop::collection::vec(value, 0..40)
    }

    proptest! {
        #[test]
        fn max_abs_is_the_sequential_maximum(x in entries()) {
            let seq = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            prop_assert_eq!(super::max_abs(&x).to_bits(), seq.to_bits());
        }

        #[test]
        fn first_largest_abs_is_the_sequential_search(x in entries()) {
            let seq = x
                .iter()
                .copied()
                .fold(0.0f64, |acc, v| if v.abs() > acc.abs() { v } else { acc });
            let got = super::first_largest_abs(&x);
            // A slice of zeros may give −0 where the fold keeps its +0 start: equal values.
            prop_assert!(got.to_bits() == seq.to_bits() || (got == 0.0 && seq == 0.0));
        }

        #[test]
        fn all_finite_is_the_plain_check(x in entries()) {
            prop_assert_eq!(super::all_finite(&x), x.iter().all(|v| v.is_finite()));
        }
    }

    #[test]
    fn dot_matches_a_plain_sum_at_every_length() {
        for n in 0..40 {
            let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
            let y: Vec<f64> = (0..n).map(|i| (i as f64 * 1.3).cos()).collect();
            let plain: f64 = x.iter().zip(&y).map(|(a, b)| a * b).sum();
            assert!(
                (super::dot(&x, &y) - plain).abs() <= 1e-14 * (1.0 + plain.abs()),
                "n = {n}"
            );
        }
    }
}
