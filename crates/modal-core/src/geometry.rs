//! Small fixed-size geometry on nalgebra types: the symmetric 2×2/3×3 eigenproblems of
//! principal axes, the least-squares solves of affine fits, rotations, and the nalgebra point
//! types accepted by [`Shape`].

// Small fixed-size matrix code reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

use nalgebra::{Matrix2, Matrix3, Matrix4, Point2, Point3, Rotation3, Vector3};

use crate::error::ModalError;
use crate::shape::{Shape, Topology};

impl Shape {
    /// A 2-D shape from nalgebra points.
    ///
    /// ```
    /// use modal_core::{Shape, Topology};
    /// use nalgebra::Point2;
    /// let square = [
    ///     Point2::new(0.0, 0.0),
    ///     Point2::new(1.0, 0.0),
    ///     Point2::new(1.0, 1.0),
    ///     Point2::new(0.0, 1.0),
    /// ];
    /// let shape = Shape::from_points2(&square, Topology::ClosedContour).unwrap();
    /// assert_eq!((shape.dim(), shape.len()), (2, 4));
    /// assert_eq!(shape.point(2), &[1.0, 1.0]);
    /// ```
    pub fn from_points2(points: &[Point2<f64>], topology: Topology) -> Result<Self, ModalError> {
        Self::new(
            2,
            points.iter().flat_map(|p| [p.x, p.y]).collect(),
            topology,
        )
    }

    /// A 3-D shape from nalgebra points.
    ///
    /// ```
    /// use modal_core::{Shape, Topology};
    /// use nalgebra::Point3;
    /// let tetrahedron = [
    ///     Point3::new(0.0, 0.0, 0.0),
    ///     Point3::new(1.0, 0.0, 0.0),
    ///     Point3::new(0.0, 1.0, 0.0),
    ///     Point3::new(0.0, 0.0, 1.0),
    /// ];
    /// let shape = Shape::from_points3(&tetrahedron, Topology::None).unwrap();
    /// assert_eq!((shape.dim(), shape.len()), (3, 4));
    /// assert_eq!(shape.point(3), &[0.0, 0.0, 1.0]);
    /// ```
    pub fn from_points3(points: &[Point3<f64>], topology: Topology) -> Result<Self, ModalError> {
        Self::new(
            3,
            points.iter().flat_map(|p| [p.x, p.y, p.z]).collect(),
            topology,
        )
    }
}

/// Row-major `[[f64; 3]; 3]` as a nalgebra matrix.
pub(crate) fn matrix3(a: &[[f64; 3]; 3]) -> Matrix3<f64> {
    Matrix3::from_fn(|r, c| a[r][c])
}

/// A nalgebra matrix as row-major `[[f64; 3]; 3]`.
pub(crate) fn rows3(m: &Matrix3<f64>) -> [[f64; 3]; 3] {
    std::array::from_fn(|r| std::array::from_fn(|c| m[(r, c)]))
}

/// Eigenvalues and eigenvectors (columns, `vecs[row][k]` for eigenvalue `k`) of a symmetric 3×3
/// matrix, unsorted; each vector has its largest entry positive.
pub(crate) fn sym_eigen3(a: &[[f64; 3]; 3]) -> ([f64; 3], [[f64; 3]; 3]) {
    let eig = matrix3(a).symmetric_eigen();
    let mut vecs = [[0.0; 3]; 3];
    for k in 0..3 {
        let mut v: [f64; 3] = std::array::from_fn(|r| eig.eigenvectors[(r, k)]);
        crate::eigen::canonical_sign(&mut v);
        for r in 0..3 {
            vecs[r][k] = v[r];
        }
    }
    (eig.eigenvalues.into(), vecs)
}

/// [`sym_eigen3`] of a symmetric 2×2 matrix (the leading block of `a`), padded: the third
/// eigenpair is `(pad, e_z)`.
pub(crate) fn sym_eigen2_padded(a: &[[f64; 3]; 3], pad: f64) -> ([f64; 3], [[f64; 3]; 3]) {
    let eig = Matrix2::new(a[0][0], a[0][1], a[1][0], a[1][1]).symmetric_eigen();
    let mut vecs = [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
    for k in 0..2 {
        let mut v = [eig.eigenvectors[(0, k)], eig.eigenvectors[(1, k)]];
        crate::eigen::canonical_sign(&mut v);
        vecs[0][k] = v[0];
        vecs[1][k] = v[1];
    }
    ([eig.eigenvalues[0], eig.eigenvalues[1], pad], vecs)
}

/// Relative pivot below which a normal-equations matrix counts as singular.
const SINGULAR_PIVOT: f64 = 1e-10;

/// Solves the normal equations `A W = B` of an affine least-squares fit (`A` symmetric positive
/// semi-definite: `d + 1 = 3` rows in 2-D, 4 in 3-D, `d` right-hand sides) by LU with partial
/// pivoting; `None` when a pivot falls below `1e-10` of the largest diagonal entry (the points
/// do not determine the map).
pub(crate) fn solve_normal_equations(
    a: &[[f64; 4]; 4],
    b: &[[f64; 3]; 4],
    dim: usize,
) -> Option<[[f64; 3]; 4]> {
    let scale = (0..=dim).map(|i| a[i][i].abs()).fold(0.0, f64::max);
    let tol = SINGULAR_PIVOT * scale;
    let mut w = [[0.0; 3]; 4];
    match dim {
        2 => {
            let lu = Matrix3::from_fn(|r, c| a[r][c]).lu();
            if lu.u().diagonal().iter().any(|p| p.abs() <= tol) {
                return None;
            }
            let x = lu.solve(&Matrix3::from_fn(|r, c| if c < 2 { b[r][c] } else { 0.0 }))?;
            for r in 0..3 {
                for c in 0..2 {
                    w[r][c] = x[(r, c)];
                }
            }
        }
        3 => {
            let lu = Matrix4::from_fn(|r, c| a[r][c]).lu();
            if lu.u().diagonal().iter().any(|p| p.abs() <= tol) {
                return None;
            }
            let rhs = nalgebra::Matrix4x3::from_fn(|r, c| b[r][c]);
            let x = lu.solve(&rhs)?;
            for r in 0..4 {
                for c in 0..3 {
                    w[r][c] = x[(r, c)];
                }
            }
        }
        _ => return None,
    }
    Some(w)
}

/// The rotation by `angle` about the z axis (in 2-D: the plane rotation in the leading block).
pub(crate) fn rotation_z(angle: f64) -> [[f64; 3]; 3] {
    rows3(Rotation3::from_axis_angle(&Vector3::z_axis(), angle).matrix())
}

/// `U · T · Vᵀ` on the leading `dim × dim` blocks (zero elsewhere).
pub(crate) fn sandwich(
    dim: usize,
    u: &[[f64; 3]; 3],
    t: &[[f64; 3]; 3],
    v: &[[f64; 3]; 3],
) -> [[f64; 3]; 3] {
    let block =
        |a: &[[f64; 3]; 3]| Matrix3::from_fn(|r, c| if r < dim && c < dim { a[r][c] } else { 0.0 });
    rows3(&(block(u) * block(t) * block(v).transpose()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn symmetric_eigen_reconstructs_and_is_canonical() {
        let a = [[4.0, 1.0, 0.5], [1.0, 3.0, -0.2], [0.5, -0.2, 1.0]];
        let (vals, vecs) = sym_eigen3(&a);
        let v = matrix3(&vecs);
        let back = v * Matrix3::from_diagonal(&Vector3::from(vals)) * v.transpose();
        assert!((back - matrix3(&a)).amax() < 1e-12);
        assert!((v.transpose() * v - Matrix3::identity()).amax() < 1e-12);
        for k in 0..3 {
            let col = v.column(k);
            assert!(col[col.iamax()] > 0.0);
        }
        let (vals2, vecs2) = sym_eigen2_padded(&a, -1.0);
        assert_eq!((vals2[2], vecs2[2][2]), (-1.0, 1.0));
        let a2 = Matrix2::new(4.0, 1.0, 1.0, 3.0);
        for k in 0..2 {
            let x = nalgebra::Vector2::new(vecs2[0][k], vecs2[1][k]);
            assert!((a2 * x - x * vals2[k]).amax() < 1e-12);
        }
    }

    #[test]
    fn normal_equations_recover_a_map_and_refuse_degenerate_points() {
        // y = M x + t on four points in general position, 2-D.
        let (m, t) = ([[1.2, -0.3], [0.4, 0.9]], [0.5, -2.0]);
        let pts = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [2.0, 3.0]];
        let (mut a, mut b) = ([[0.0; 4]; 4], [[0.0; 3]; 4]);
        for p in pts {
            let x = [p[0], p[1], 1.0];
            let y = [0, 1].map(|r| m[r][0] * p[0] + m[r][1] * p[1] + t[r]);
            for r in 0..3 {
                for c in 0..3 {
                    a[r][c] += x[r] * x[c];
                }
                for c in 0..2 {
                    b[r][c] += x[r] * y[c];
                }
            }
        }
        let w = solve_normal_equations(&a, &b, 2).unwrap();
        for r in 0..2 {
            for c in 0..2 {
                assert!((w[c][r] - m[r][c]).abs() < 1e-12);
            }
            assert!((w[2][r] - t[r]).abs() < 1e-12);
        }
        // Collinear points: no affine map.
        let mut a = [[0.0; 4]; 4];
        for s in [0.0, 1.0, 2.0, 3.0] {
            let x = [s, 2.0 * s, 1.0];
            for r in 0..3 {
                for c in 0..3 {
                    a[r][c] += x[r] * x[c];
                }
            }
        }
        assert!(solve_normal_equations(&a, &b, 2).is_none());
    }

    #[test]
    fn rotations_compose_in_the_leading_block() {
        let r = rotation_z(std::f64::consts::FRAC_PI_2);
        assert!((r[0][1] + 1.0).abs() < 1e-15 && (r[1][0] - 1.0).abs() < 1e-15);
        let id = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let s = sandwich(2, &id, &r, &id);
        assert_eq!(s[2][2], 0.0);
        assert!((s[1][0] - 1.0).abs() < 1e-15);
    }
}
