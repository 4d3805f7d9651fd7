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

/// `W` lanes of `f64`: the one vector type of the kernels. Every operation is a plain loop over
/// the lanes, `#[inline(always)]`, so inside a [`widest_simd!`] copy the compiler turns each into
/// one instruction of that copy's vector unit (`W` = 8 fills an AVX-512 register, 4 an AVX2 one;
/// the baseline copy gets SSE2 pairs). No operation is fused unless it says so, so a kernel gives
/// the same bits at every width.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Lanes<const W: usize>(pub(crate) [f64; W]);

impl<const W: usize> Lanes<W> {
    #[inline(always)]
    pub(crate) fn splat(v: f64) -> Self {
        Self([v; W])
    }

    /// The first `W` values of `x` (which must hold that many).
    #[inline(always)]
    pub(crate) fn load(x: &[f64]) -> Self {
        Self(x[..W].try_into().expect("W values"))
    }

    /// Lane by lane `f(a, b)`.
    #[inline(always)]
    pub(crate) fn zip(self, b: Self, f: impl Fn(f64, f64) -> f64) -> Self {
        Self(std::array::from_fn(|l| f(self.0[l], b.0[l])))
    }

    /// `self·b + c`, fused (one rounding) when `FMA`: only for copies compiled with FMA, where
    /// it is one instruction (elsewhere `f64::mul_add` is a library call).
    #[inline(always)]
    pub(crate) fn mul_add<const FMA: bool>(self, b: Self, c: Self) -> Self {
        Self(std::array::from_fn(|l| {
            if FMA {
                self.0[l].mul_add(b.0[l], c.0[l])
            } else {
                self.0[l] * b.0[l] + c.0[l]
            }
        }))
    }

    /// `c − self·b`, fused when `FMA` (as [`Lanes::mul_add`]).
    #[inline(always)]
    pub(crate) fn neg_mul_add<const FMA: bool>(self, b: Self, c: Self) -> Self {
        Self(std::array::from_fn(|l| {
            if FMA {
                (-self.0[l]).mul_add(b.0[l], c.0[l])
            } else {
                c.0[l] - self.0[l] * b.0[l]
            }
        }))
    }

    /// The horizontal sum, as halves added pairwise down to four lanes, then
    /// `(l₀ + l₁) + (l₂ + l₃)`: the same order at every width ≥ 4.
    #[inline(always)]
    pub(crate) fn sum(self) -> f64 {
        let mut v = self.0;
        let mut w = W;
        while w > 4 {
            w /= 2;
            for l in 0..w {
                v[l] += v[l + w];
            }
        }
        match w {
            4 => (v[0] + v[1]) + (v[2] + v[3]),
            _ => v[..w].iter().sum(),
        }
    }
}

impl<const W: usize> std::ops::Add for Lanes<W> {
    type Output = Self;
    #[inline(always)]
    fn add(self, b: Self) -> Self {
        self.zip(b, |x, y| x + y)
    }
}

impl<const W: usize> std::ops::Sub for Lanes<W> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, b: Self) -> Self {
        self.zip(b, |x, y| x - y)
    }
}

impl<const W: usize> std::ops::Mul for Lanes<W> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, b: Self) -> Self {
        self.zip(b, |x, y| x * y)
    }
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

/// Defines `$name`, which runs its body compiled for the widest vector unit this CPU has:
/// AVX-512F (which implies AVX2 and FMA), else AVX2 (with the extra features listed, detected
/// too), else the baseline. This is the crate's one SIMD mechanism: the kernels are plain safe
/// code on [`Lanes`], and each copy is that code compiled with its `#[target_feature]`, which
/// lets the compiler use the wider registers. The two x86 copies get their own names (`$avx512`,
/// `$avx2`) so tests can run every path. Each copy has its own expression: a generic kernel
/// instantiated at that copy's vector width, or the same `#[inline(always)]` body compiled
/// twice. Their only `unsafe` is the call of a `#[target_feature]` function, made after the
/// detection.
macro_rules! widest_simd {
    (
        $(#[$meta:meta])*
        $vis:vis fn $name:ident $(<$(const $gen:ident: $gty:ty),+>)?
            ($($arg:ident: $ty:ty),* $(,)?) $(-> $ret:ty)?;
        avx512 $avx512:ident => $on512:expr;
        avx2 $avx2:ident [$($feat:tt),*] => $on2:expr;
        portable => $portable:expr;
    ) => {
        $(#[$meta])*
        $vis fn $name $(<$(const $gen: $gty),+>)? ($($arg: $ty),*) $(-> $ret)? {
            #[cfg(target_arch = "x86_64")]
            {
                if std::is_x86_feature_detected!("avx512f") {
                    // SAFETY: AVX-512F was just detected.
                    return unsafe { $avx512 $(::<$($gen),+>)? ($($arg),*) };
                }
                if std::is_x86_feature_detected!("avx2")
                    $(&& std::is_x86_feature_detected!($feat))*
                {
                    // SAFETY: AVX2 and the listed features were just detected.
                    return unsafe { $avx2 $(::<$($gen),+>)? ($($arg),*) };
                }
            }
            $portable
        }

        /// # Safety
        /// The CPU must support AVX-512F.
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx512f")]
        unsafe fn $avx512 $(<$(const $gen: $gty),+>)? ($($arg: $ty),*) $(-> $ret)? {
            $on512
        }

        /// # Safety
        /// The CPU must support AVX2 and the features listed.
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2")]
        $(#[target_feature(enable = $feat)])*
        unsafe fn $avx2 $(<$(const $gen: $gty),+>)? ($($arg: $ty),*) $(-> $ret)? {
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
