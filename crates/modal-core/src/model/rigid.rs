//! Exact rigid-body motions of a node set (docs/method.md §2.6).

// Index loops over several matrices at once read better than zipped iterators here.
#![allow(clippy::needless_range_loop)]

use faer::Mat;

use crate::error::ModalError;
use crate::shape::Shape;

/// The rigid nodal basis `R` (`d·n × r`, component-major rows), in the canonical order
/// `T_x, T_y, (T_z), R_z, (R_x, R_y)`; rotations are infinitesimal, about the centroid.
/// Columns are not normalised. `r` is 3 in 2-D and 6 in 3-D.
pub fn rigid_basis(shape: &Shape) -> Mat<f64> {
    let dim = shape.dim();
    let n = shape.len();
    let mut centroid = [0.0f64; 3];
    for i in 0..n {
        for (a, c) in shape.point(i).iter().enumerate() {
            centroid[a] += c / n as f64;
        }
    }
    let r = if dim == 2 { 3 } else { 6 };
    let mut basis = Mat::<f64>::zeros(dim * n, r);
    for a in 0..dim {
        for i in 0..n {
            basis[(a * n + i, a)] = 1.0;
        }
    }
    for i in 0..n {
        let p = shape.point(i);
        let x = p[0] - centroid[0];
        let y = p[1] - centroid[1];
        // R_z: (−y, x, 0)
        basis[(i, dim)] = -y;
        basis[(n + i, dim)] = x;
        if dim == 3 {
            let z = p[2] - centroid[2];
            // R_x: (0, −z, y); R_y: (z, 0, −x)
            basis[(n + i, 4)] = -z;
            basis[(2 * n + i, 4)] = y;
            basis[(i, 5)] = z;
            basis[(2 * n + i, 5)] = -x;
        }
    }
    basis
}

/// Modified Gram–Schmidt of the columns of `y` in the Euclidean inner product, in column order.
/// Fails if a column is (numerically) dependent on the previous ones: the rigid motions of
/// collinear 3-D nodes, for instance, are not independent.
pub(crate) fn orthonormalise(y: &mut Mat<f64>) -> Result<(), ModalError> {
    let (rows, cols) = (y.nrows(), y.ncols());
    for j in 0..cols {
        let norm0 = y.col(j).norm_l2();
        for p in 0..j {
            let dot: f64 = (0..rows).map(|i| y[(i, p)] * y[(i, j)]).sum();
            for i in 0..rows {
                y[(i, j)] -= dot * y[(i, p)];
            }
        }
        let norm = y.col(j).norm_l2();
        if !(norm > 1e-8 * norm0 && norm.is_finite()) {
            return Err(ModalError::DependentRigidMotion { motion: j });
        }
        for i in 0..rows {
            y[(i, j)] /= norm;
        }
    }
    Ok(())
}
