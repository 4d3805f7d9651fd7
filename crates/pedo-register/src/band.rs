//! A symmetric banded matrix and its Cholesky factorisation, for the non-rigid step's normal
//! equations: each B-spline control point touches only the control points of its 4 × 4
//! neighbourhoods, so the matrix is zero beyond a band of about three control rows, and a banded
//! factorisation costs `n b²` instead of the dense `n³ / 3` (a few times less at 63 × 33 sensels,
//! more on larger grids).

/// The upper band of a symmetric `n × n` matrix: entry `(i, j)`, `i ≤ j ≤ i + width`, at
/// `i (width + 1) + (j − i)`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Band {
    n: usize,
    width: usize,
    data: Vec<f64>,
}

impl Band {
    /// The zero matrix of order `n` with `width` super-diagonals.
    pub(crate) fn zeros(n: usize, width: usize) -> Self {
        Self {
            n,
            width,
            data: vec![0.0; n * (width + 1)],
        }
    }

    pub(crate) fn len(&self) -> usize {
        self.n
    }

    /// Adds `v` to entry `(i, j)` (and so to `(j, i)`); `i ≤ j ≤ i + width`.
    pub(crate) fn add(&mut self, i: usize, j: usize, v: f64) {
        debug_assert!(i <= j && j - i <= self.width);
        self.data[i * (self.width + 1) + (j - i)] += v;
    }

    pub(crate) fn diagonal(&self, i: usize) -> f64 {
        self.data[i * (self.width + 1)]
    }

    /// Factorises in place into `U` with `A = Uᵀ U` (row-oriented, right-looking); `None` when
    /// the matrix is not positive definite.
    pub(crate) fn cholesky(mut self) -> Option<Self> {
        let w1 = self.width + 1;
        for i in 0..self.n {
            let d = self.data[i * w1];
            if !(d > 0.0 && d.is_finite()) {
                return None;
            }
            let d = d.sqrt();
            let end = w1.min(self.n - i);
            let row = i * w1;
            self.data[row] = d;
            for k in 1..end {
                self.data[row + k] /= d;
            }
            // The trailing block loses row i's outer product.
            for a in 1..end {
                let ua = self.data[row + a];
                if ua == 0.0 {
                    continue;
                }
                let (head, tail) = self.data.split_at_mut((i + a) * w1);
                let urow = &head[row + a..row + end];
                for (t, u) in tail[..end - a].iter_mut().zip(urow) {
                    *t -= ua * u;
                }
            }
        }
        Some(self)
    }

    /// Solves `Uᵀ U x = b` with `self` the factor `U` of [`Band::cholesky`].
    pub(crate) fn solve(&self, b: &[f64]) -> Vec<f64> {
        let w1 = self.width + 1;
        let mut x = b.to_vec();
        for i in 0..self.n {
            let row = &self.data[i * w1..i * w1 + w1.min(self.n - i)];
            x[i] /= row[0];
            let xi = x[i];
            for (k, u) in row.iter().enumerate().skip(1) {
                x[i + k] -= u * xi;
            }
        }
        for i in (0..self.n).rev() {
            let row = &self.data[i * w1..i * w1 + w1.min(self.n - i)];
            let s: f64 = row
                .iter()
                .enumerate()
                .skip(1)
                .map(|(k, u)| u * x[i + k])
                .sum();
            x[i] = (x[i] - s) / row[0];
        }
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    /// A random symmetric positive definite banded matrix: its banded solve equals nalgebra's
    /// dense Cholesky solve of the same matrix.
    #[test]
    fn the_banded_solve_equals_the_dense_one() {
        let (n, width) = (37, 6);
        let mut seed = 12345u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let mut dense = DMatrix::zeros(n, n);
        let mut band = Band::zeros(n, width);
        for i in 0..n {
            for j in i..(i + width + 1).min(n) {
                let v = if i == j { 4.0 + next() } else { next() };
                dense[(i, j)] = v;
                dense[(j, i)] = v;
                band.add(i, j, v);
            }
        }
        let b: Vec<f64> = (0..n).map(|_| next()).collect();
        let want = dense
            .cholesky()
            .unwrap()
            .solve(&DVector::from_column_slice(&b));
        let got = band.cholesky().unwrap().solve(&b);
        for (g, w) in got.iter().zip(want.iter()) {
            assert!((g - w).abs() < 1e-12, "{g} vs {w}");
        }
    }

    #[test]
    fn an_indefinite_matrix_has_no_factor() {
        let mut band = Band::zeros(3, 1);
        band.add(0, 0, 1.0);
        band.add(0, 1, 2.0);
        band.add(1, 1, 1.0);
        band.add(2, 2, 1.0);
        assert!(band.cholesky().is_none());
    }
}
