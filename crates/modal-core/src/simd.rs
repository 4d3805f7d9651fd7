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
