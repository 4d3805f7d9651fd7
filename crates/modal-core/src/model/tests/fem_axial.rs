//! Bar (axial) models: zero-mode counts with and without the mechanism remedies (docs/method.md
//! §3.2), normalisation, and input errors.

use crate::eigen::generalized_eigen;
use crate::model::assembly::explicit_model;
use crate::model::axial::{
    add_hinge_bending, assemble_bars, ear_clip, hinges, ring_edges, second_neighbour_edges,
    triangle_edges,
};
use crate::model::count_zero_modes;
use crate::{modal_basis, ElementKind, Material, ModelOptions, Shape, Topology};
use faer::Mat;

fn ring(n: usize) -> Shape {
    let pts: Vec<[f64; 2]> = (0..n)
        .map(|k| {
            let t = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
            // A foot-like, non-convex outline.
            let r = 1.0 + 0.25 * (2.0 * t).cos() + 0.1 * (3.0 * t).sin();
            [1.3 * r * t.cos(), 0.8 * r * t.sin()]
        })
        .collect();
    Shape::from_points_2d(&pts, Topology::ClosedContour).unwrap()
}

fn full_spectrum(shape: &Shape, edges: &[[usize; 2]]) -> Vec<f64> {
    let (k, ms) = assemble_bars(shape, edges, &Material::UNIT).unwrap();
    let n = shape.len();
    let d = shape.dim();
    let mut m = Mat::<f64>::zeros(d * n, d * n);
    for a in 0..d {
        m.as_mut().submatrix_mut(a * n, a * n, n, n).copy_from(&ms);
    }
    generalized_eigen(k.as_ref(), m.as_ref(), None)
        .unwrap()
        .values
}

/// A height-field patch on a jittered `nx × ny` grid, triangulated.
fn height_field(nx: usize, ny: usize, flat: bool) -> Shape {
    let mut pts = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let (x, y) = (
                i as f64 + 0.13 * ((i * 7 + j * 3) % 5) as f64,
                j as f64 + 0.11 * ((i * 3 + j * 5) % 7) as f64,
            );
            let z = if flat {
                0.0
            } else {
                1.5 * (0.5 * x).sin() * (0.4 * y).cos()
            };
            pts.push([x, y, z]);
        }
    }
    let mut tris = Vec::new();
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            let v = j * nx + i;
            tris.push([v, v + 1, v + nx + 1]);
            tris.push([v, v + nx + 1, v + nx]);
        }
    }
    Shape::from_points_3d(&pts, Topology::Mesh { triangles: tris }).unwrap()
}

fn axial() -> ModelOptions {
    ModelOptions {
        element: ElementKind::Axial,
        material: Material::UNIT,
        ..Default::default()
    }
}

#[test]
fn plain_ring_is_a_mechanism_with_m_zero_modes() {
    let shape = ring(40);
    let ev = full_spectrum(&shape, &ring_edges(40));
    assert_eq!(count_zero_modes(&ev), 40);
}

#[test]
fn ear_clipping_remedy_leaves_exactly_three_zero_modes() {
    let shape = ring(40);
    let tris = ear_clip(shape.coords()).expect("simple polygon");
    assert_eq!(tris.len(), 38);
    let edges = triangle_edges(&tris);
    assert_eq!(edges.len(), 2 * 40 - 3);
    let ev = full_spectrum(&shape, &edges);
    assert_eq!(count_zero_modes(&ev), 3);
    // Through the public entry point: exactly 3 zeros and a clearly positive 4th eigenvalue.
    let basis = modal_basis(&shape, &axial()).unwrap();
    let top = basis.eigenvalues.last().unwrap();
    assert!(basis.eigenvalues[..3].iter().all(|v| v.abs() < 1e-9 * top));
    assert!(
        basis.eigenvalues[3] > 1e-6 * top,
        "4th ω² = {}",
        basis.eigenvalues[3]
    );
    // The ring's rigid motions are exact: K φ = 0 for the first three modes.
    let (k, m, _) = explicit_model(&shape, &axial()).unwrap();
    let r = &k * basis.modes.as_ref().subcols(0, 3);
    assert!(r.norm_max() < 1e-9 * k.norm_max());
    let phi = &basis.modes;
    let pmp = phi.transpose() * &m * phi;
    let pkp = phi.transpose() * &k * phi;
    for i in 0..phi.ncols() {
        for j in 0..phi.ncols() {
            let e = if i == j { 1.0 } else { 0.0 };
            assert!((pmp[(i, j)] - e).abs() < 1e-9);
            let l = if i == j { basis.eigenvalues[i] } else { 0.0 };
            assert!((pkp[(i, j)] - l).abs() < 1e-9 * top);
        }
    }
}

#[test]
fn second_neighbour_bars_also_leave_three_zero_modes() {
    let shape = ring(40);
    let mut edges = ring_edges(40);
    edges.extend(second_neighbour_edges(40));
    assert_eq!(count_zero_modes(&full_spectrum(&shape, &edges)), 3);
}

#[test]
fn self_intersecting_contour_falls_back_and_stays_rigid() {
    // A figure-eight: ear clipping fails, second-neighbour bars take over.
    let pts: Vec<[f64; 2]> = (0..30)
        .map(|k| {
            let t = 2.0 * std::f64::consts::PI * k as f64 / 30.0 + 0.05;
            [t.sin(), (2.0 * t).sin() * 0.5]
        })
        .collect();
    let shape = Shape::from_points_2d(&pts, Topology::ClosedContour).unwrap();
    assert!(ear_clip(shape.coords()).is_none());
    let basis = modal_basis(&shape, &axial()).unwrap();
    assert_eq!(count_zero_modes(&basis.eigenvalues), 3);
}

#[test]
fn surface_bars_alone_have_mechanisms_and_hinges_remove_them() {
    for flat in [false, true] {
        let shape = height_field(8, 10, flat);
        let Topology::Mesh { triangles } = shape.topology().clone() else {
            unreachable!()
        };
        let edges = triangle_edges(&triangles);
        let v = shape.len();
        let zeros = count_zero_modes(&full_spectrum(&shape, &edges));
        // Curved: 3V − E = 6 + (b − 3) for a disk; flat: also every out-of-plane vertex motion.
        let b = 2 * (8 - 1) + 2 * (10 - 1);
        if flat {
            assert!(
                zeros > 6 + (b - 3),
                "flat patch has only {zeros} zero modes"
            );
        } else {
            assert_eq!(zeros, 3 * v - edges.len());
            assert_eq!(zeros, 6 + b - 3);
        }
        let basis = modal_basis(&shape, &axial()).unwrap();
        assert_eq!(count_zero_modes(&basis.eigenvalues), 6, "flat = {flat}");
    }
}

#[test]
fn hinge_bending_is_orthogonal_to_rigid_motions() {
    let shape = height_field(5, 6, false);
    let Topology::Mesh { triangles } = shape.topology().clone() else {
        unreachable!()
    };
    let n = shape.len();
    let mut k = Mat::<f64>::zeros(3 * n, 3 * n);
    let h = hinges(&triangles);
    assert_eq!(h.len(), triangle_edges(&triangles).len() - 2 * (4 + 5));
    add_hinge_bending(&shape, &h, &Material::UNIT, &mut k).unwrap();
    let r = crate::model::rigid::rigid_basis(&shape);
    let kr = &k * &r;
    assert!(
        kr.norm_max() < 1e-10 * k.norm_max() * r.norm_max(),
        "{}",
        kr.norm_max()
    );
    assert!(k.norm_max() > 0.0);
}

#[test]
fn partial_axial_solve_matches_full() {
    let shape = ring(60);
    let full = modal_basis(&shape, &axial()).unwrap();
    let part = modal_basis(
        &shape,
        &ModelOptions {
            n_modes: Some(20),
            ..axial()
        },
    )
    .unwrap();
    let top = full.eigenvalues.last().unwrap();
    for j in 3..20 {
        assert!((full.eigenvalues[j] - part.eigenvalues[j]).abs() < 1e-9 * top);
    }
}

#[test]
fn bad_topologies_are_rejected() {
    let pts = [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [3.0, 0.0], [4.0, 0.0]];
    let line = Shape::from_points_2d(&pts, Topology::ClosedContour).unwrap();
    let err = modal_basis(&line, &axial()).unwrap_err().to_string();
    assert!(err.contains("zero-energy"), "{err}");
    let cloud =
        Shape::from_points_2d(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], Topology::None).unwrap();
    assert!(modal_basis(&cloud, &axial())
        .unwrap_err()
        .to_string()
        .contains("connectivity"));
    let c3 = Shape::from_points_3d(
        &[
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ],
        Topology::ClosedContour,
    )
    .unwrap();
    assert!(modal_basis(&c3, &axial()).is_err());
    let iso = Shape::from_points_3d(
        &[
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [5.0, 5.0, 5.0],
        ],
        Topology::Mesh {
            triangles: vec![[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]],
        },
    )
    .unwrap();
    assert!(modal_basis(&iso, &axial())
        .unwrap_err()
        .to_string()
        .contains("node 4"));
    // A closed tetrahedron surface is rigid: 6 zero modes exactly.
    let tet = Shape::from_points_3d(
        &[
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ],
        Topology::Mesh {
            triangles: vec![[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]],
        },
    )
    .unwrap();
    let b = modal_basis(&tet, &axial()).unwrap();
    assert_eq!(count_zero_modes(&b.eigenvalues), 6);
}
