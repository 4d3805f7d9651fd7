//! Objects to be matched: 2-D or 3-D point sets with optional topology.

use crate::error::ModalError;

/// How the nodes of a [`Shape`] are connected.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum Topology {
    /// Unordered point set (the Gaussian element needs no order).
    #[default]
    None,
    /// The nodes, in order, form one closed contour (node `n-1` joins node `0`).
    ClosedContour,
    /// A triangle mesh over the nodes (indices into the point list).
    Mesh {
        /// The triangles, three node indices each.
        triangles: Vec<[usize; 3]>,
    },
}

/// A 2-D or 3-D object: `n` nodes of dimension `dim`, stored row-major (`coords[i*dim + a]`).
#[derive(Debug, Clone, PartialEq)]
pub struct Shape {
    dim: usize,
    coords: Vec<f64>,
    topology: Topology,
}

impl Shape {
    /// Builds a shape from row-major coordinates, checking that every coordinate is finite and
    /// every triangle index is in range.
    pub fn new(dim: usize, coords: Vec<f64>, topology: Topology) -> Result<Self, ModalError> {
        if dim != 2 && dim != 3 {
            return Err(ModalError::UnsupportedDimension { dim });
        }
        if !coords.len().is_multiple_of(dim) {
            return Err(ModalError::CoordinateCount {
                len: coords.len(),
                dim,
            });
        }
        if let Some(k) = coords.iter().position(|v| !v.is_finite()) {
            return Err(ModalError::NonFiniteCoordinate {
                node: k / dim,
                axis: k % dim,
                value: coords[k],
            });
        }
        let n = coords.len() / dim;
        if let Topology::Mesh { triangles } = &topology
            && let Some(t) = triangles.iter().find(|t| t.iter().any(|&v| v >= n))
        {
            return Err(ModalError::InvalidTriangle {
                triangle: *t,
                nodes: n,
            });
        }
        Ok(Self {
            dim,
            coords,
            topology,
        })
    }

    /// A 2-D point set from `(x, y)` pairs.
    pub fn from_points_2d(points: &[[f64; 2]], topology: Topology) -> Result<Self, ModalError> {
        Self::new(2, points.iter().flatten().copied().collect(), topology)
    }

    /// A 3-D point set from `(x, y, z)` triples.
    pub fn from_points_3d(points: &[[f64; 3]], topology: Topology) -> Result<Self, ModalError> {
        Self::new(3, points.iter().flatten().copied().collect(), topology)
    }

    /// Dimension of the points (2 or 3).
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.coords.len() / self.dim
    }

    /// Whether the shape has no node.
    pub fn is_empty(&self) -> bool {
        self.coords.is_empty()
    }

    /// Row-major coordinates, `len() * dim()` values.
    pub fn coords(&self) -> &[f64] {
        &self.coords
    }

    /// Coordinates of node `i`.
    pub fn point(&self, i: usize) -> &[f64] {
        &self.coords[i * self.dim..(i + 1) * self.dim]
    }

    /// How the nodes are connected.
    pub fn topology(&self) -> &Topology {
        &self.topology
    }
}

/// Whether row-major 2-D points, read in their order, trace a closed outline: the mean step
/// from each point to the next (the last back to the first) is at most 1.5 × the mean
/// nearest-neighbour distance. Points sampled along a boundary pass; a scattered cloud, whose
/// consecutive points are unrelated, does not; 3-D points and fewer than 4 never do. Callers
/// that are not told whether their points are ordered use it to pick the contour recipe.
///
/// ```
/// use modal_core::shape::looks_like_closed_contour;
/// let ring: Vec<f64> = (0..12)
///     .flat_map(|i| {
///         let t = i as f64 / 12.0 * std::f64::consts::TAU;
///         [t.cos(), 0.5 * t.sin()]
///     })
///     .collect();
/// assert!(looks_like_closed_contour(&ring, 2));
/// // Every other point first: consecutive points are two steps apart.
/// let mut skipped: Vec<f64> = ring.chunks(2).step_by(2).flatten().copied().collect();
/// skipped.extend(ring.chunks(2).skip(1).step_by(2).flatten());
/// assert!(!looks_like_closed_contour(&skipped, 2));
/// ```
pub fn looks_like_closed_contour(coords: &[f64], dim: usize) -> bool {
    let n = coords.len() / dim.max(1);
    if dim != 2 || n < 4 {
        return false;
    }
    let step = (0..n)
        .map(|i| {
            let j = (i + 1) % n;
            ((coords[2 * i] - coords[2 * j]).powi(2)
                + (coords[2 * i + 1] - coords[2 * j + 1]).powi(2))
            .sqrt()
        })
        .sum::<f64>()
        / n as f64;
    step <= 1.5 * nearest_neighbour_stats_of(coords, 2).0
}

/// Mean and minimum nearest-neighbour distance, with the pair realising the minimum.
pub fn nearest_neighbour_stats(shape: &Shape) -> (f64, f64, (usize, usize)) {
    nearest_neighbour_stats_of(shape.coords(), shape.dim())
}

/// [`nearest_neighbour_stats`] of row-major `dim`-D points.
pub fn nearest_neighbour_stats_of(coords: &[f64], dim: usize) -> (f64, f64, (usize, usize)) {
    // Every model build (each modal solve) calls this O(n²) scan: 2-D and 3-D get a
    // fixed-dimension loop the compiler can unroll.
    match dim {
        2 => nn_stats::<2>(coords),
        3 => nn_stats::<3>(coords),
        d => nn_stats_dyn(coords, d),
    }
}

fn nn_stats<const D: usize>(c: &[f64]) -> (f64, f64, (usize, usize)) {
    let pts: Vec<[f64; D]> = c
        .chunks_exact(D)
        .map(|p| std::array::from_fn(|a| p[a]))
        .collect();
    finish_nn_stats(pts.len(), |i| {
        let p = pts[i];
        let mut best = f64::INFINITY;
        let mut bj = i;
        for (j, q) in pts.iter().enumerate() {
            let mut r2 = 0.0;
            for a in 0..D {
                let d = p[a] - q[a];
                r2 += d * d;
            }
            if j != i && r2 < best {
                best = r2;
                bj = j;
            }
        }
        (best, bj)
    })
}

fn nn_stats_dyn(c: &[f64], dim: usize) -> (f64, f64, (usize, usize)) {
    let n = c.len() / dim;
    finish_nn_stats(n, |i| {
        let mut best = f64::INFINITY;
        let mut bj = i;
        for j in 0..n {
            if j == i {
                continue;
            }
            let r2: f64 = (0..dim)
                .map(|a| (c[i * dim + a] - c[j * dim + a]).powi(2))
                .sum();
            if r2 < best {
                best = r2;
                bj = j;
            }
        }
        (best, bj)
    })
}

/// Reduces per-node (squared nearest distance, neighbour) into (mean, min, pair).
fn finish_nn_stats(
    n: usize,
    nearest: impl Fn(usize) -> (f64, usize),
) -> (f64, f64, (usize, usize)) {
    let mut total = 0.0;
    let mut min = f64::INFINITY;
    let mut pair = (0, 0);
    for i in 0..n {
        let (best, bj) = nearest(i);
        let r = best.sqrt();
        total += r;
        if r < min {
            min = r;
            pair = (i.min(bj), i.max(bj));
        }
    }
    (total / n as f64, min, pair)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_contours_are_told_from_scattered_points() {
        let ring: Vec<f64> = (0..40)
            .flat_map(|i| {
                let t = i as f64 / 40.0 * std::f64::consts::TAU;
                [3.0 * t.cos() + 0.4 * (3.0 * t).cos(), t.sin()]
            })
            .collect();
        assert!(looks_like_closed_contour(&ring, 2));
        // The same points in a scrambled order (a fixed permutation: 17 is coprime with 40).
        let scrambled: Vec<f64> = (0..40)
            .flat_map(|i| ring[2 * (i * 17 % 40)..2 * (i * 17 % 40) + 2].to_vec())
            .collect();
        assert!(!looks_like_closed_contour(&scrambled, 2));
        // 3-D points and too few points are never contours.
        let lifted: Vec<f64> = ring.chunks(2).flat_map(|p| [p[0], p[1], 0.0]).collect();
        assert!(!looks_like_closed_contour(&lifted, 3));
        assert!(!looks_like_closed_contour(&ring[..6], 2));
        assert!(!looks_like_closed_contour(&[], 2));
    }

    #[test]
    fn rejects_non_finite_and_bad_triangles() {
        assert!(Shape::new(2, vec![0.0, f64::NAN], Topology::None).is_err());
        assert!(Shape::new(4, vec![0.0; 4], Topology::None).is_err());
        let err = Shape::new(
            2,
            vec![0.0; 6],
            Topology::Mesh {
                triangles: vec![[0, 1, 3]],
            },
        );
        assert!(err.is_err());
        let ok = Shape::from_points_2d(&[[0.0, 0.0], [1.0, 0.0]], Topology::ClosedContour).unwrap();
        assert_eq!((ok.len(), ok.dim()), (2, 2));
        assert_eq!(ok.point(1), &[1.0, 0.0]);
    }
}
