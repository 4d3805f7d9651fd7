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

/// Clears the upper halves of the vector registers (`vzeroupper`). faer's matrix products run
/// AVX-512 kernels that return with them dirty, and until they are cleared every legacy-SSE
/// instruction — all scalar `f64` code compiled for baseline x86-64, glibc's `exp` — pays for
/// merging them: building a 60-node Gaussian model took 456 µs after a product instead of 126
/// (README, "Eigensolver"). Called after each faer call on the solve path.
pub(crate) fn clear_upper_state() {
    #[cfg(target_arch = "x86_64")]
    {
        if std::is_x86_feature_detected!("avx") {
            // SAFETY: AVX was just detected.
            unsafe { std::arch::x86_64::_mm256_zeroupper() }
        }
    }
}

/// A kernel written once per vector unit: [`dispatch`] runs the copy for the widest unit this
/// CPU has, compiled by `pulp` with that unit's instructions (AVX-512: [`pulp::x86::V4`];
/// AVX2 and FMA: [`pulp::x86::V3`]; else the baseline). The unit arrives as a token whose
/// intrinsic-named methods are safe to call, so the kernels hold no `unsafe`. Implementations
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

/// Defines `$name`, which runs its body compiled for the widest vector unit this CPU has:
/// AVX-512F, else AVX2 (with the extra features listed, detected too), else the baseline. The
/// two x86 copies get their own names (`$avx512`, `$avx2`) so tests can run every path. Each copy
/// has its own expression: a generic kernel instantiated for that copy's vector type, or the same
/// `#[inline(always)]` body compiled twice. The optional `requires` block runs first; it asserts
/// whatever the copies' unsafe kernels need (their `# Safety`), so the dispatcher stays safe.
macro_rules! widest_simd {
    (
        $(#[$meta:meta])*
        $vis:vis fn $name:ident($($arg:ident: $ty:ty),* $(,)?) $(-> $ret:ty)?;
        $(requires $pre:block;)?
        avx512 $avx512:ident => $on512:expr;
        avx2 $avx2:ident [$($feat:tt),*] => $on2:expr;
        portable => $portable:expr;
    ) => {
        $(#[$meta])*
        $vis fn $name($($arg: $ty),*) $(-> $ret)? {
            $($pre)?
            #[cfg(target_arch = "x86_64")]
            {
                if std::is_x86_feature_detected!("avx512f") {
                    // SAFETY: AVX-512F was just detected (and `requires` has run).
                    return unsafe { $avx512($($arg),*) };
                }
                if std::is_x86_feature_detected!("avx2")
                    $(&& std::is_x86_feature_detected!($feat))*
                {
                    // SAFETY: AVX2 and the listed features were just detected (and `requires`
                    // has run).
                    return unsafe { $avx2($($arg),*) };
                }
            }
            $portable
        }

        /// # Safety
        /// The CPU must support AVX-512F.
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx512f")]
        unsafe fn $avx512($($arg: $ty),*) $(-> $ret)? {
            $on512
        }

        /// # Safety
        /// The CPU must support AVX2 and the features listed.
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2")]
        $(#[target_feature(enable = $feat)])*
        unsafe fn $avx2($($arg: $ty),*) $(-> $ret)? {
            $on2
        }
    };
}
pub(crate) use widest_simd;

#[cfg(test)]
mod tests {
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
