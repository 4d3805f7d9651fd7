//! Golden values of the Gaussian element's closed forms (docs/method.md §2.2–2.4), computed
//! independently.

use crate::model::assembly::explicit_model;
use crate::model::gaussian::GaussianIntegrals;
use crate::{modal_basis, Material, ModelOptions, PlaneModel, Shape, Topology};

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * b.abs().max(1.0)
}

fn assert_row(got: &[f64], want: &[f64], what: &str) {
    // Golden values are printed with 10 decimals.
    for (g, w) in got.iter().zip(want) {
        assert!(close(*g, *w, 1e-9), "{what}: got {got:?}, want {want:?}");
    }
}

fn options_unit(sigma: f64) -> ModelOptions {
    ModelOptions {
        material: Material::UNIT,
        plane: PlaneModel::Stress,
        sigma: Some(sigma),
        ..Default::default()
    }
}

fn tri() -> Shape {
    Shape::from_points_2d(&[[0.0, 0.0], [1.0, 0.0], [0.3, 0.8]], Topology::None).unwrap()
}

#[test]
#[allow(clippy::approx_constant)] // Γ^xx_00 = V/(2σ²) = π/2: the reference value is printed rounded.
fn golden_2d_integrals() {
    let ints = GaussianIntegrals::new(&tri(), 0.7);
    let row = |m: &faer::Mat<f64>, i: usize| (0..3).map(|j| m[(i, j)]).collect::<Vec<_>>();
    assert_row(
        &row(&ints.gamma, 0),
        &[1.5393804003, 0.9242024925, 1.0607020693],
        "Γ row0",
    );
    assert_row(
        &row(ints.gamma_ab(0, 0), 0),
        &[1.5707963268, -0.0192461993, 0.9829496477],
        "Γxx",
    );
    assert_row(
        &row(ints.gamma_ab(0, 1), 2),
        &[-0.2650650735, 0.5043102147, 0.0],
        "Γxy row2",
    );
    assert_row(
        &row(ints.gamma_ab(1, 0), 2),
        &[-0.2650650735, 0.5043102147, 0.0],
        "Γyx row2",
    );
}

#[test]
fn golden_2d_matrices_and_eigenvalues() {
    let (k, m, sigma) = explicit_model(&tri(), &options_unit(0.7)).unwrap();
    assert_eq!(sigma, Some(0.7));
    assert_row(
        &(0..3).map(|j| m[(0, j)]).collect::<Vec<_>>(),
        &[1.4262904065, -0.1172852121, -0.3076167619],
        "M",
    );
    assert_row(
        &(0..6).map(|j| k[(0, j)]).collect::<Vec<_>>(),
        &[
            3.4282906313,
            -1.5555156043,
            -0.930839478,
            0.4169995902,
            -0.1864503199,
            -0.5163069087,
        ],
        "K row0",
    );
    let basis = modal_basis(&tri(), &options_unit(0.7)).unwrap();
    assert_row(
        &basis.eigenvalues,
        &[
            1.0292992551,
            1.1229216021,
            1.5737176821,
            2.6719750972,
            2.7853259551,
            3.8258452966,
        ],
        "ω² 2-D",
    );
}

#[test]
fn golden_3d_eigenvalues() {
    let shape = Shape::from_points_3d(
        &[
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.3, 0.8, 0.0],
            [0.2, 0.1, 0.9],
        ],
        Topology::None,
    )
    .unwrap();
    let want = [
        1.2025942541,
        1.260592245,
        1.368907692,
        1.5275838876,
        1.5662059345,
        1.597433368,
        2.6739965551,
        2.709675163,
        2.7610575485,
        2.8568190058,
        2.9229039971,
        4.5410267254,
    ];
    let basis = modal_basis(&shape, &options_unit(0.8)).unwrap();
    assert_row(&basis.eigenvalues, &want, "ω² 3-D");
    // The explicit route (A = G⁻¹, dense generalized solve) agrees.
    let (k, m, _) = explicit_model(&shape, &options_unit(0.8)).unwrap();
    let pairs = crate::eigen::generalized_eigen(k.as_ref(), m.as_ref(), None).unwrap();
    assert_row(&pairs.values, &want, "ω² 3-D explicit");
}
