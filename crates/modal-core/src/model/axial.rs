//! Linear axial (bar/truss) elements with consistent mass (docs/method.md §3), and the remedies for
//! the spurious zero-energy mechanisms of plain bar loops and open surfaces (§3.2).
//!
//! - 2-D closed contours: the ring of `m` bars is a mechanism with `m` zero modes. The polygon
//!   interior is triangulated by ear clipping and every diagonal becomes a bar too (2m − 3 bars, a
//!   minimally rigid framework: exactly 3 zero modes). If the contour is not a simple polygon, the
//!   fallback is second-neighbour bars `(k, k+2)`.
//! - 3-D triangle meshes: an open triangulated surface has `b − 3` first-order mechanisms (b
//!   boundary edges) and a flat patch one per interior vertex, all of them folds about edges.
//!   The regularisation adds a linearised hinge-bending stiffness on every interior edge (the
//!   discrete-shell bending energy `½ k_b Δθ²` of the dihedral angle, gradients after Bridson,
//!   Marino & Fedkiw 2003). The dihedral angle is invariant under rigid motions, so its gradient
//!   is orthogonal to all 6 rigid modes: the rigid null space stays exact while every fold gets a
//!   positive stiffness. Bending is weighted `BENDING_WEIGHT` relative to the bars so that the
//!   membrane (bar) modes still dominate the stiff end of the spectrum.

// Index loops over several matrices at once read better than zipped iterators here.
#![allow(clippy::needless_range_loop)]

use std::collections::BTreeMap;

use faer::Mat;

use super::material::Material;
use crate::eigen;
use crate::error::{ModalError, Unsupported};
use crate::shape::{Shape, Topology};

/// Section area of every bar. K and M both scale with it, so ω² does not depend on it and the
/// mass-normalised modes only scale by 1/√A.
pub(crate) const BAR_AREA: f64 = 1.0;

/// Hinge-bending stiffness relative to the bars: `k_b = BENDING_WEIGHT · E · A · |edge|`.
pub(crate) const BENDING_WEIGHT: f64 = 0.1;

/// A bending hinge: the shared edge `(e0, e1)` and the opposite vertices `o0`, `o1` of its two
/// triangles.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Hinge {
    pub e0: usize,
    pub e1: usize,
    pub o0: usize,
    pub o1: usize,
}

/// Bars `(k, k+1 mod n)` of a closed loop.
pub fn ring_edges(n: usize) -> Vec<[usize; 2]> {
    (0..n).map(|k| [k, (k + 1) % n]).collect()
}

/// Second-neighbour bars `(k, k+2 mod n)`.
pub fn second_neighbour_edges(n: usize) -> Vec<[usize; 2]> {
    (0..n).map(|k| [k, (k + 2) % n]).collect()
}

/// Bars `(k, k + n/2 mod n)` across a closed loop.
pub(crate) fn opposite_edges(n: usize) -> Vec<[usize; 2]> {
    (0..n)
        .map(|k| [k, (k + n / 2) % n])
        .filter(|[a, b]| a != b)
        .collect()
}

/// Ear-clipping triangulation of a simple polygon (2-D, row-major `coords`); `None` if the
/// polygon is not simple (no ear can be found).
pub fn ear_clip(coords: &[f64]) -> Option<Vec<[usize; 3]>> {
    let n = coords.len() / 2;
    if n < 3 {
        return None;
    }
    let p = |i: usize| (coords[2 * i], coords[2 * i + 1]);
    let mut area2 = 0.0;
    for i in 0..n {
        let (a, b) = (p(i), p((i + 1) % n));
        area2 += a.0 * b.1 - a.1 * b.0;
    }
    let mut idx: Vec<usize> = (0..n).collect();
    if area2 < 0.0 {
        idx.reverse();
    }
    let scale = coords
        .iter()
        .fold(0.0f64, |m, v| m.max(v.abs()))
        .max(1e-300);
    let eps = 1e-12 * scale * scale;
    let cross = |o: (f64, f64), a: (f64, f64), b: (f64, f64)| {
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
    };
    // Quality of a triangle: twice its area over its longest edge squared (0 for a sliver).
    let quality = |a: (f64, f64), b: (f64, f64), c: (f64, f64)| {
        let d2 = |u: (f64, f64), v: (f64, f64)| (u.0 - v.0).powi(2) + (u.1 - v.1).powi(2);
        cross(a, b, c) / d2(a, b).max(d2(b, c)).max(d2(c, a)).max(f64::MIN_POSITIVE)
    };
    let mut tris = Vec::with_capacity(n - 2);
    while idx.len() > 3 {
        let m = idx.len();
        // Clip the fattest ear, not the first one: first-found ears along straight runs of a
        // pixel outline leave slivers whose near-zero stiffness reads as a mechanism.
        let mut best: Option<(usize, f64)> = None;
        for k in 0..m {
            let (ia, ib, ic) = (idx[(k + m - 1) % m], idx[k], idx[(k + 1) % m]);
            let (a, b, c) = (p(ia), p(ib), p(ic));
            if cross(a, b, c) <= eps {
                continue;
            }
            let q = quality(a, b, c);
            if best.is_some_and(|(_, bq)| bq >= q) {
                continue;
            }
            let blocked = idx.iter().any(|&q| {
                if q == ia || q == ib || q == ic {
                    return false;
                }
                let x = p(q);
                cross(a, b, x) >= -eps && cross(b, c, x) >= -eps && cross(c, a, x) >= -eps
            });
            if !blocked {
                best = Some((k, q));
            }
        }
        let (k, _) = best?;
        tris.push([idx[(k + m - 1) % m], idx[k], idx[(k + 1) % m]]);
        idx.remove(k);
    }
    let (a, b, c) = (p(idx[0]), p(idx[1]), p(idx[2]));
    if cross(a, b, c) <= eps {
        return None;
    }
    tris.push([idx[0], idx[1], idx[2]]);
    Some(tris)
}

/// Unique undirected edges of a triangle list, sorted.
pub fn triangle_edges(triangles: &[[usize; 3]]) -> Vec<[usize; 2]> {
    let mut edges: Vec<[usize; 2]> = triangles
        .iter()
        .flat_map(|t| [[t[0], t[1]], [t[1], t[2]], [t[2], t[0]]])
        .map(|[a, b]| [a.min(b), a.max(b)])
        .collect();
    edges.sort_unstable();
    edges.dedup();
    edges
}

/// Interior edges shared by exactly two triangles, as bending hinges.
pub fn hinges(triangles: &[[usize; 3]]) -> Vec<Hinge> {
    let mut map: BTreeMap<[usize; 2], Vec<usize>> = BTreeMap::new();
    for t in triangles {
        for k in 0..3 {
            let (a, b, o) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            map.entry([a.min(b), a.max(b)]).or_default().push(o);
        }
    }
    map.into_iter()
        .filter(|(_, opp)| opp.len() == 2)
        .map(|([e0, e1], opp)| Hinge {
            e0,
            e1,
            o0: opp[0],
            o1: opp[1],
        })
        .collect()
}

/// Assembles the bar stiffness `K` (`d·n × d·n`, component-major, full storage) and the
/// consistent scalar mass block `M_s` (`n × n`; the full mass is `I_d ⊗ M_s`).
pub fn assemble_bars(
    shape: &Shape,
    edges: &[[usize; 2]],
    material: &Material,
) -> Result<(Mat<f64>, Mat<f64>), ModalError> {
    let dim = shape.dim();
    let n = shape.len();
    let mut k = Mat::<f64>::zeros(dim * n, dim * n);
    let mut ms = Mat::<f64>::zeros(n, n);
    for &[i, j] in edges {
        if i == j || i >= n || j >= n {
            return Err(ModalError::InvalidEdge {
                edge: [i, j],
                nodes: n,
            });
        }
        let (pi, pj) = (shape.point(i), shape.point(j));
        let mut c = [0.0f64; 3];
        let mut len2 = 0.0;
        for a in 0..dim {
            c[a] = pj[a] - pi[a];
            len2 += c[a] * c[a];
        }
        let len = len2.sqrt();
        if len.is_nan() || len <= 0.0 {
            return Err(ModalError::ZeroLengthEdge { edge: [i, j] });
        }
        for v in c.iter_mut() {
            *v /= len;
        }
        let stiff = material.young * BAR_AREA / len;
        for a in 0..dim {
            for b in 0..dim {
                let v = stiff * c[a] * c[b];
                k[(a * n + i, b * n + i)] += v;
                k[(a * n + j, b * n + j)] += v;
                k[(a * n + i, b * n + j)] -= v;
                k[(a * n + j, b * n + i)] -= v;
            }
        }
        let m = material.density * BAR_AREA * len / 6.0;
        ms[(i, i)] += 2.0 * m;
        ms[(j, j)] += 2.0 * m;
        ms[(i, j)] += m;
        ms[(j, i)] += m;
    }
    Ok((k, ms))
}

/// Adds the linearised hinge-bending stiffness of the given hinges to `k` (3-D only).
pub fn add_hinge_bending(
    shape: &Shape,
    hinges: &[Hinge],
    material: &Material,
    k: &mut Mat<f64>,
) -> Result<(), ModalError> {
    let n = shape.len();
    let x = |i: usize| {
        let p = shape.point(i);
        [p[0], p[1], p[2]]
    };
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let crossp = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    for h in hinges {
        // Bridson et al. notation: x3, x4 the shared edge, x1, x2 the opposite vertices.
        let (x1, x2, x3, x4) = (x(h.o0), x(h.o1), x(h.e0), x(h.e1));
        let n1 = crossp(sub(x1, x3), sub(x1, x4));
        let n2 = crossp(sub(x2, x4), sub(x2, x3));
        let e = sub(x4, x3);
        let le = dot(e, e).sqrt();
        let (a1, a2) = (dot(n1, n1), dot(n2, n2));
        if !(a1 > 1e-24 * le.powi(4) && a2 > 1e-24 * le.powi(4)) {
            return Err(ModalError::DegenerateTriangle { edge: [h.e0, h.e1] });
        }
        let s1 = n1.map(|v| v / a1);
        let s2 = n2.map(|v| v / a2);
        let t1 = dot(sub(x1, x4), e) / le;
        let t2 = dot(sub(x2, x4), e) / le;
        let r1 = dot(sub(x1, x3), e) / le;
        let r2 = dot(sub(x2, x3), e) / le;
        let u = [
            s1.map(|v| v * le),
            s2.map(|v| v * le),
            [0, 1, 2].map(|a| t1 * s1[a] + t2 * s2[a]),
            [0, 1, 2].map(|a| -r1 * s1[a] - r2 * s2[a]),
        ];
        let nodes = [h.o0, h.o1, h.e0, h.e1];
        let kb = BENDING_WEIGHT * material.young * BAR_AREA * le;
        for (p, &np) in nodes.iter().enumerate() {
            for (q, &nq) in nodes.iter().enumerate() {
                for a in 0..3 {
                    for b in 0..3 {
                        k[(a * n + np, b * n + nq)] += kb * u[p][a] * u[q][b];
                    }
                }
            }
        }
    }
    Ok(())
}

/// The bars (and hinges) of `shape` with the mechanism remedies of the module docs.
pub(crate) fn model_edges(shape: &Shape) -> Result<(Vec<[usize; 2]>, Vec<Hinge>), ModalError> {
    let n = shape.len();
    let dim = shape.dim();
    match shape.topology() {
        Topology::None => Err(Unsupported::AxialWithoutConnectivity.into()),
        Topology::ClosedContour => {
            if dim != 2 {
                return Err(Unsupported::Axial3dContour.into());
            }
            let mut edges = ring_edges(n);
            // A triangulated polygon is minimally rigid, so one thin triangle (a straight run of
            // a pixel outline) already reads as a mechanism. The second-neighbour bars and one
            // bar across the loop from every node over-brace it; a contour that is not a simple
            // polygon (resampled outlines can touch themselves at narrow necks) gets these alone.
            if let Some(tris) = ear_clip(shape.coords()) {
                edges.extend(triangle_edges(&tris));
            }
            edges.extend(second_neighbour_edges(n));
            edges.extend(opposite_edges(n));
            let mut edges: Vec<[usize; 2]> = edges
                .into_iter()
                .map(|[a, b]| [a.min(b), a.max(b)])
                .collect();
            edges.sort_unstable();
            edges.dedup();
            Ok((edges, Vec::new()))
        }
        Topology::Mesh { triangles } => {
            if let Some(t) = triangles
                .iter()
                .find(|t| t[0] == t[1] || t[1] == t[2] || t[0] == t[2])
            {
                return Err(ModalError::InvalidTriangle {
                    triangle: *t,
                    nodes: n,
                });
            }
            let edges = triangle_edges(triangles);
            let mut used = vec![false; n];
            for &[a, b] in &edges {
                used[a] = true;
                used[b] = true;
            }
            if let Some(i) = used.iter().position(|u| !u) {
                return Err(ModalError::UnconnectedNode { node: i });
            }
            let h = if dim == 3 {
                hinges(triangles)
            } else {
                Vec::new()
            };
            Ok((edges, h))
        }
    }
}

/// The bar model in solver form: stiffness `K` (`d·n × d·n`) and the lower Cholesky factor `L`
/// of the `n × n` consistent mass block `M_s` (`M = I_d ⊗ M_s = I_d ⊗ L Lᵀ`).
pub(crate) struct BarModel {
    pub stiffness: Mat<f64>,
    pub mass_factor: Mat<f64>,
}

/// Assembles the bar model of `shape` in solver form (`B = I_d ⊗ M_s`, `L = chol(M_s)`).
pub(crate) fn axial_model(shape: &Shape, material: &Material) -> Result<BarModel, ModalError> {
    let (edges, hinge_list) = model_edges(shape)?;
    axial_model_with_edges(shape, &edges, &hinge_list, material)
}

/// Bar model on the given edges (and bending hinges, 3-D only).
pub(crate) fn axial_model_with_edges(
    shape: &Shape,
    edges: &[[usize; 2]],
    hinge_list: &[Hinge],
    material: &Material,
) -> Result<BarModel, ModalError> {
    let n = shape.len();
    let mut used = vec![false; n];
    for &[a, b] in edges {
        if a >= n || b >= n || a == b {
            return Err(ModalError::InvalidEdge {
                edge: [a, b],
                nodes: n,
            });
        }
        used[a] = true;
        used[b] = true;
    }
    if let Some(i) = used.iter().position(|u| !u) {
        return Err(ModalError::UnconnectedNode { node: i });
    }
    let mut edges: Vec<[usize; 2]> = edges.iter().map(|&[a, b]| [a.min(b), a.max(b)]).collect();
    edges.sort_unstable();
    edges.dedup();
    let (mut k, ms) = assemble_bars(shape, &edges, material)?;
    if !hinge_list.is_empty() {
        if shape.dim() != 3 {
            return Err(Unsupported::Hinges2d.into());
        }
        add_hinge_bending(shape, hinge_list, material, &mut k)?;
    }
    eigen::symmetrise(k.as_mut());
    let mut l = ms;
    eigen::cholesky_in_place(l.as_mut()).map_err(|i| ModalError::NotPositiveDefinite {
        matrix: "the bar mass matrix",
        pivot: Some(i),
    })?;
    for j in 0..n {
        for i in 0..j {
            l[(i, j)] = 0.0;
        }
    }
    Ok(BarModel {
        stiffness: k,
        mass_factor: l,
    })
}
