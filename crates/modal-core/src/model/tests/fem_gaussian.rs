//! Gaussian element: closed forms against quadrature, matrix properties, the ψ-route against the
//! explicit route, normalisation, exact-rigid option, material scaling and input errors.

use crate::eigen::generalized_eigen;
use crate::model::assembly::explicit_model;
use crate::model::gaussian::{gaussians_at, GaussianIntegrals};
use crate::{
    modal_basis, ElementKind, Material, ModalBasis, ModelOptions, PlaneModel, Shape, Topology,
};
use faer::Mat;
use rand::{Rng, SeedableRng};

/// Gauss–Legendre nodes and weights on [-1, 1] (Newton on P_n).
fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    for i in 0..n {
        let mut z = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, z);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * z * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            let dp = n as f64 * (z * p1 - p0) / (z * z - 1.0);
            let dz = p1 / dp;
            z -= dz;
            if dz.abs() < 1e-16 {
                let (mut p0, mut p1) = (1.0, z);
                for k in 2..=n {
                    let p2 = ((2 * k - 1) as f64 * z * p1 - (k - 1) as f64 * p0) / k as f64;
                    p0 = p1;
                    p1 = p2;
                }
                let dp = n as f64 * (z * p1 - p0) / (z * z - 1.0);
                w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
                break;
            }
        }
        x[i] = z;
    }
    (x, w)
}

/// Tensor quadrature of Γ, Γ^{ab} and of the explicit K and M of the element (isotropic
/// energy λ (div u)² + 2μ ε:ε, h = G⁻¹ g), over a box of ±(6σ + extent).
fn quadrature(
    shape: &Shape,
    sigma: f64,
    lambda: f64,
    mu: f64,
    rho: f64,
    npts: usize,
) -> (Mat<f64>, Vec<Mat<f64>>, Mat<f64>, Mat<f64>) {
    let dim = shape.dim();
    let m = shape.len();
    let ints = GaussianIntegrals::new(shape, sigma);
    let a_inv = ints.g.llt(faer::Side::Lower).unwrap();
    let a = faer::linalg::solvers::DenseSolveCore::inverse(&a_inv);
    let (gx, gw) = gauss_legendre(npts);
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for i in 0..m {
        for c in 0..dim {
            lo[c] = lo[c].min(shape.point(i)[c]);
            hi[c] = hi[c].max(shape.point(i)[c]);
        }
    }
    let pad = 6.0 * sigma;
    let mut gamma = Mat::<f64>::zeros(m, m);
    let mut gd: Vec<Mat<f64>> = (0..dim * dim).map(|_| Mat::zeros(m, m)).collect();
    let mut k = Mat::<f64>::zeros(dim * m, dim * m);
    let mut mm = Mat::<f64>::zeros(dim * m, dim * m);
    let total = npts.pow(dim as u32);
    let mut g = vec![0.0; m];
    let mut dg = vec![[0.0; 3]; m];
    let mut h = vec![0.0; m];
    let mut dh = vec![[0.0; 3]; m];
    for idx in 0..total {
        let mut x = [0.0; 3];
        let mut wt = 1.0;
        let mut r = idx;
        for c in 0..dim {
            let q = r % npts;
            r /= npts;
            let (l, u) = (lo[c] - pad, hi[c] + pad);
            x[c] = 0.5 * (l + u) + 0.5 * (u - l) * gx[q];
            wt *= 0.5 * (u - l) * gw[q];
        }
        for i in 0..m {
            let p = shape.point(i);
            let mut r2 = 0.0;
            for c in 0..dim {
                r2 += (x[c] - p[c]).powi(2);
            }
            g[i] = (-r2 / (2.0 * sigma * sigma)).exp();
            for c in 0..dim {
                dg[i][c] = -(x[c] - p[c]) / (sigma * sigma) * g[i];
            }
        }
        for i in 0..m {
            h[i] = 0.0;
            dh[i] = [0.0; 3];
            for kk in 0..m {
                h[i] += a[(i, kk)] * g[kk];
                for c in 0..dim {
                    dh[i][c] += a[(i, kk)] * dg[kk][c];
                }
            }
        }
        for i in 0..m {
            for j in 0..m {
                gamma[(i, j)] += wt * g[i] * g[j];
                for aa in 0..dim {
                    for bb in 0..dim {
                        gd[aa * dim + bb][(i, j)] += wt * dg[i][aa] * dg[j][bb];
                    }
                }
                for aa in 0..dim {
                    mm[(aa * m + i, aa * m + j)] += wt * rho * h[i] * h[j];
                    for bb in 0..dim {
                        let grad: f64 = (0..dim).map(|c| dh[i][c] * dh[j][c]).sum();
                        let v = lambda * dh[i][aa] * dh[j][bb]
                            + mu * dh[i][bb] * dh[j][aa]
                            + if aa == bb { mu * grad } else { 0.0 };
                        k[(aa * m + i, bb * m + j)] += wt * v;
                    }
                }
            }
        }
    }
    (gamma, gd, k, mm)
}

fn rel_err(a: &Mat<f64>, b: &Mat<f64>) -> f64 {
    (a - b).norm_max() / b.norm_max()
}

fn random_shape(dim: usize, m: usize, seed: u64) -> Shape {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let coords: Vec<f64> = (0..dim * m).map(|_| rng.random_range(-1.0..1.0)).collect();
    Shape::new(dim, coords, Topology::None).unwrap()
}

fn ellipse(n: usize, a: f64, b: f64) -> Shape {
    let pts: Vec<[f64; 2]> = (0..n)
        .map(|k| {
            let t = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
            [a * t.cos() + 0.1 * (3.0 * t).sin(), b * t.sin()]
        })
        .collect();
    Shape::from_points_2d(&pts, Topology::ClosedContour).unwrap()
}

fn unit(sigma: Option<f64>) -> ModelOptions {
    ModelOptions {
        material: Material::UNIT,
        sigma,
        ..Default::default()
    }
}

#[test]
fn closed_forms_match_quadrature_2d() {
    for seed in 0..3 {
        let shape = random_shape(2, 4, seed);
        let sigma = 0.6;
        let mat = Material::UNIT;
        let (l, mu) = mat.lame(2, PlaneModel::Stress);
        let (gamma, gd, kq, mq) = quadrature(&shape, sigma, l, mu, 1.0, 120);
        let ints = GaussianIntegrals::new(&shape, sigma);
        assert!(rel_err(&ints.gamma, &gamma) < 1e-12);
        for a in 0..2 {
            for b in 0..2 {
                assert!(
                    rel_err(ints.gamma_ab(a, b), &gd[a * 2 + b]) < 1e-11,
                    "Γ^{a}{b}"
                );
            }
        }
        let (k, m, _) = explicit_model(&shape, &unit(Some(sigma))).unwrap();
        assert!(rel_err(&k, &kq) < 1e-9, "K {}", rel_err(&k, &kq));
        assert!(rel_err(&m, &mq) < 1e-9, "M {}", rel_err(&m, &mq));
    }
}

#[test]
fn closed_forms_match_quadrature_3d() {
    for seed in 10..12 {
        let shape = random_shape(3, 4, seed);
        let sigma = 0.7;
        let mat = Material {
            young: 2.0,
            poisson: 0.25,
            density: 3.0,
        };
        let (l, mu) = mat.lame(3, PlaneModel::Stress);
        let (gamma, gd, kq, mq) = quadrature(&shape, sigma, l, mu, 3.0, 48);
        let ints = GaussianIntegrals::new(&shape, sigma);
        assert!(rel_err(&ints.gamma, &gamma) < 1e-10);
        for a in 0..3 {
            for b in 0..3 {
                assert!(rel_err(ints.gamma_ab(a, b), &gd[a * 3 + b]) < 1e-9);
            }
        }
        let opts = ModelOptions {
            material: mat,
            sigma: Some(sigma),
            ..Default::default()
        };
        let (k, m, _) = explicit_model(&shape, &opts).unwrap();
        assert!(rel_err(&k, &kq) < 1e-7, "K {}", rel_err(&k, &kq));
        assert!(rel_err(&m, &mq) < 1e-7, "M {}", rel_err(&m, &mq));
    }
}

#[test]
fn gaussians_at_the_nodes_are_the_interpolation_matrix() {
    for dim in [2, 3] {
        let shape = random_shape(dim, 9, 11 + dim as u64);
        let ints = GaussianIntegrals::new(&shape, 0.6);
        assert!(rel_err(&gaussians_at(&shape, &shape, 0.6), &ints.g) < 1e-14);
        // Rectangular: every other node as a centre picks the matching columns of G.
        let idx: Vec<usize> = (0..9).step_by(2).collect();
        let coords: Vec<f64> = idx
            .iter()
            .flat_map(|&j| shape.coords()[j * dim..(j + 1) * dim].to_vec())
            .collect();
        let centers = Shape::new(dim, coords, Topology::None).unwrap();
        let rect = gaussians_at(&shape, &centers, 0.6);
        assert_eq!((rect.nrows(), rect.ncols()), (9, idx.len()));
        for (k, &j) in idx.iter().enumerate() {
            for i in 0..9 {
                assert!((rect[(i, k)] - ints.g[(i, j)]).abs() < 1e-14);
            }
        }
    }
}

#[test]
fn plane_strain_changes_only_lambda() {
    let shape = random_shape(2, 5, 3);
    let mut opts = unit(Some(0.5));
    let (ks, _, _) = explicit_model(&shape, &opts).unwrap();
    opts.plane = PlaneModel::Strain;
    let (ke, _, _) = explicit_model(&shape, &opts).unwrap();
    // Plane strain is stiffer (λ larger) but has the same shear part.
    assert!(rel_err(&ks, &ke) > 1e-3);
    let ints = GaussianIntegrals::new(&shape, 0.5);
    let (l1, mu) = Material::UNIT.lame(2, PlaneModel::Stress);
    let (l2, _) = Material::UNIT.lame(2, PlaneModel::Strain);
    let d1 = ints.k_tilde(l1, mu);
    let d2 = ints.k_tilde(l2, mu);
    let diff = &d2 - &d1;
    let want = ints.k_tilde(l2 - l1, 0.0);
    assert!(rel_err(&diff, &want) < 1e-12);
}

/// Block `(a, b)` of `K̃` by the formula, `(λ+μ) Γ^{ab} + μ δ_ab Σ_c Γ^{cc}`, in faer's
/// matrix arithmetic: the reference `k_tilde`'s in-place loops must reproduce bit for bit.
fn k_tilde_block(ints: &GaussianIntegrals, a: usize, b: usize, lambda: f64, mu: f64) -> Mat<f64> {
    let mut out = ints.gamma_ab(a, b) * faer::Scale(lambda + mu);
    if a == b {
        for c in 0..ints.dim {
            out += ints.gamma_ab(c, c) * faer::Scale(mu);
        }
    }
    out
}

#[test]
fn k_tilde_is_its_blocks_and_the_integrals_are_exactly_symmetric() {
    for dim in [2, 3] {
        let shape = random_shape(dim, 9, 17);
        let ints = GaussianIntegrals::new(&shape, 0.7);
        let n = ints.n;
        for m in [&ints.g, &ints.gamma].into_iter().chain(&ints.gamma_d) {
            for j in 0..n {
                for i in 0..n {
                    assert_eq!(
                        m[(i, j)].to_bits(),
                        m[(j, i)].to_bits(),
                        "{dim}-D ({i}, {j})"
                    );
                }
            }
        }
        let (lambda, mu) = Material::RUBBER.lame(dim, PlaneModel::Stress);
        let k = ints.k_tilde(lambda, mu);
        for a in 0..dim {
            for b in 0..dim {
                let block = k_tilde_block(&ints, a, b, lambda, mu);
                for j in 0..n {
                    for i in 0..n {
                        assert_eq!(
                            k[(a * n + i, b * n + j)].to_bits(),
                            block[(i, j)].to_bits(),
                            "{dim}-D block ({a}, {b}) entry ({i}, {j})"
                        );
                    }
                }
            }
        }
    }
}

fn check_symmetric_pd(k: &Mat<f64>, m: &Mat<f64>) {
    let n = k.nrows();
    for i in 0..n {
        for j in 0..n {
            assert!((k[(i, j)] - k[(j, i)]).abs() <= 1e-12 * k.norm_max());
            assert!((m[(i, j)] - m[(j, i)]).abs() <= 1e-12 * m.norm_max());
        }
    }
    assert!(m.llt(faer::Side::Lower).is_ok(), "M not positive definite");
    let ev = k.self_adjoint_eigenvalues(faer::Side::Lower).unwrap();
    assert!(
        ev[0] > -1e-10 * ev[n - 1],
        "K not positive semidefinite: {}",
        ev[0]
    );
}

#[test]
fn stiffness_and_mass_are_symmetric_and_definite() {
    check_symmetric_pd(
        &explicit_model(&ellipse(30, 1.3, 0.8), &unit(None))
            .unwrap()
            .0,
        &explicit_model(&ellipse(30, 1.3, 0.8), &unit(None))
            .unwrap()
            .1,
    );
    let (k, m, _) = explicit_model(&random_shape(3, 25, 4), &ModelOptions::default()).unwrap();
    check_symmetric_pd(&k, &m);
}

fn check_normalised(basis: &ModalBasis, k: &Mat<f64>, m: &Mat<f64>) {
    let phi = &basis.modes;
    let r = phi.ncols();
    let pmp = phi.transpose() * m * phi;
    let pkp = phi.transpose() * k * phi;
    let top = basis
        .eigenvalues
        .iter()
        .fold(0.0f64, |a, &b| a.max(b.abs()));
    for i in 0..r {
        for j in 0..r {
            let e = if i == j { 1.0 } else { 0.0 };
            assert!(
                (pmp[(i, j)] - e).abs() < 1e-8,
                "ΦᵀMΦ[{i},{j}] = {}",
                pmp[(i, j)]
            );
            let l = if i == j { basis.eigenvalues[i] } else { 0.0 };
            assert!(
                (pkp[(i, j)] - l).abs() < 1e-8 * top,
                "ΦᵀKΦ[{i},{j}] = {}",
                pkp[(i, j)]
            );
        }
    }
}

#[test]
fn modes_are_mass_normalised_and_psi_route_matches_explicit() {
    for (shape, opts) in [
        (ellipse(40, 1.3, 0.8), unit(None)),
        (random_shape(3, 30, 5), ModelOptions::default()),
        (
            ellipse(24, 1.0, 1.0),
            ModelOptions {
                kappa: 2.0,
                ..ModelOptions::default()
            },
        ),
    ] {
        let basis = modal_basis(&shape, &opts).unwrap();
        let (k, m, sigma) = explicit_model(&shape, &opts).unwrap();
        assert_eq!(sigma, basis.sigma);
        check_normalised(&basis, &k, &m);
        let explicit = generalized_eigen(k.as_ref(), m.as_ref(), None).unwrap();
        for (a, b) in basis.eigenvalues.iter().zip(&explicit.values) {
            assert!((a - b).abs() < 1e-8 * b.abs(), "ψ {a} vs explicit {b}");
        }
        // Same modes up to sign wherever the eigenvalue is simple.
        let mut x = explicit.vectors.clone();
        crate::eigen::canonical_signs(x.as_mut());
        let ev = &basis.eigenvalues;
        for j in 0..ev.len() {
            let gap_lo = if j > 0 {
                ev[j] - ev[j - 1]
            } else {
                f64::INFINITY
            };
            let gap_hi = if j + 1 < ev.len() {
                ev[j + 1] - ev[j]
            } else {
                f64::INFINITY
            };
            if gap_lo.min(gap_hi) < 1e-6 * ev[j] {
                continue;
            }
            // Up to sign: the explicit route is less accurate, so near-ties of the largest entry
            // may resolve differently.
            let d = (basis.modes.col(j) - x.col(j))
                .norm_max()
                .min((basis.modes.col(j) + x.col(j)).norm_max())
                / x.col(j).norm_max();
            assert!(d < 1e-6, "mode {j} differs by {d}");
        }
    }
}

#[test]
fn partial_modes_equal_leading_full_modes() {
    let shape = ellipse(60, 1.2, 0.7);
    let full = modal_basis(&shape, &unit(None)).unwrap();
    let k = 30;
    let part = modal_basis(
        &shape,
        &ModelOptions {
            n_modes: Some(k),
            ..unit(None)
        },
    )
    .unwrap();
    assert_eq!(part.modes.ncols(), k);
    for j in 0..k {
        assert!((part.eigenvalues[j] - full.eigenvalues[j]).abs() < 1e-10 * full.eigenvalues[j]);
        let d = (part.modes.col(j) - full.modes.col(j)).norm_max();
        assert!(d < 1e-7 * full.modes.col(j).norm_max(), "mode {j}: {d}");
    }
}

#[test]
fn exact_rigid_gives_exact_zero_modes() {
    for (shape, r) in [(ellipse(40, 1.3, 0.8), 3usize), (random_shape(3, 40, 6), 6)] {
        let opts = ModelOptions {
            exact_rigid: true,
            ..ModelOptions::default()
        };
        let basis = modal_basis(&shape, &opts).unwrap();
        let (k, m, _) = explicit_model(&shape, &opts).unwrap();
        // Faithful element: no zero eigenvalue at all.
        let plain = modal_basis(&shape, &ModelOptions::default()).unwrap();
        assert!(plain.eigenvalues[0] > 1e-6 * plain.eigenvalues.last().unwrap());
        let top = *basis.eigenvalues.last().unwrap();
        assert!(basis.eigenvalues[..r].iter().all(|&v| v == 0.0));
        assert!(basis.eigenvalues[r] > 1e-6 * top);
        // Rigid modes span the rigid basis (canonical order T_x, T_y, …): projecting them onto
        // span(R) leaves nothing.
        let rb = crate::model::rigid::rigid_basis(&shape);
        let phi_r = basis.modes.as_ref().subcols(0, r);
        let qr = rb.qr();
        let q = qr.compute_thin_Q();
        let resid = phi_r - &q * (q.transpose() * phi_r);
        assert!(
            resid.norm_max() < 1e-9 * phi_r.norm_max(),
            "rigid residual {}",
            resid.norm_max()
        );
        let _ = &k;
        // Translation x is the first mode, up to normalisation.
        let tx = phi_r.col(0);
        let scale = tx[0] / rb[(0, 0)];
        assert!((tx - rb.col(0) * faer::Scale(scale)).norm_max() < 1e-9 * tx.norm_max());
        // Flexible modes are M-orthogonal to every rigid motion.
        let cross = rb.transpose() * &m * basis.modes.as_ref().subcols(r, basis.modes.ncols() - r);
        assert!(cross.norm_max() < 1e-8 * (rb.transpose() * &m * &rb).norm_max().sqrt());
        // The mass normalisation holds for the whole basis; the flexible K-orthogonality too.
        let pmp = basis.modes.transpose() * &m * &basis.modes;
        for i in 0..pmp.nrows() {
            assert!((pmp[(i, i)] - 1.0).abs() < 1e-8);
        }
    }
}

#[test]
fn young_and_density_scale_as_expected() {
    let shape = ellipse(36, 1.4, 0.9);
    let base = modal_basis(&shape, &unit(None)).unwrap();
    let stiff = modal_basis(
        &shape,
        &ModelOptions {
            material: Material {
                young: 7e6,
                ..Material::UNIT
            },
            ..unit(None)
        },
    )
    .unwrap();
    let heavy = modal_basis(
        &shape,
        &ModelOptions {
            material: Material {
                density: 1100.0,
                ..Material::UNIT
            },
            ..unit(None)
        },
    )
    .unwrap();
    for j in 0..base.eigenvalues.len() {
        assert!((stiff.eigenvalues[j] / base.eigenvalues[j] / 7e6 - 1.0).abs() < 1e-9);
        assert!((heavy.eigenvalues[j] * 1100.0 / base.eigenvalues[j] - 1.0).abs() < 1e-9);
    }
    let d1 = (&stiff.modes - &base.modes).norm_max();
    let d2 = (&heavy.modes * faer::Scale(1100f64.sqrt()) - &base.modes).norm_max();
    assert!(
        d1 < 1e-8 * base.modes.norm_max(),
        "E changed the modes: {d1}"
    );
    assert!(
        d2 < 1e-8 * base.modes.norm_max(),
        "ρ did not scale modes by 1/√ρ: {d2}"
    );
}

#[test]
fn features_are_component_major_rows() {
    let shape = random_shape(3, 10, 8);
    let b = modal_basis(&shape, &ModelOptions::default()).unwrap();
    // Row-major 10 × 12: entry (i, c) at i·12 + c.
    let f = b.features(4).unwrap();
    assert_eq!(f.len(), 10 * 12);
    assert_eq!(f[3 * 12], b.modes[(3, 0)]);
    assert_eq!(f[3 * 12 + 5], b.modes[(10 + 3, 1)]);
    assert_eq!(f[3 * 12 + 11], b.modes[(20 + 3, 3)]);
    assert_eq!(b.mode(1)[10 + 3], b.modes[(10 + 3, 1)]);
    assert_eq!((b.n_dofs(), b.n_modes()), (30, 30));
    assert_eq!(
        b.features(31),
        Err(crate::ModalError::TooFewModes {
            requested: 31,
            available: 30
        })
    );
    assert_eq!(b.frequencies()[2], b.eigenvalues[2].sqrt());
}

#[test]
fn conditioning_guard_shrinks_sigma() {
    let shape = ellipse(40, 1.0, 0.6);
    let basis = modal_basis(
        &shape,
        &ModelOptions {
            kappa: 6.0,
            ..ModelOptions::default()
        },
    )
    .unwrap();
    let (mean_nn, _, _) = crate::shape::nearest_neighbour_stats(&shape);
    let sigma = basis.sigma.unwrap();
    assert!(
        sigma < 6.0 * mean_nn && sigma > 0.5 * mean_nn,
        "σ = {sigma}, NN = {mean_nn}"
    );
    assert!(basis.eigenvalues.iter().all(|v| v.is_finite()));
}

#[test]
fn degenerate_input_is_rejected() {
    let o = ModelOptions::default();
    let two = Shape::from_points_2d(&[[0.0, 0.0], [1.0, 0.0]], Topology::None).unwrap();
    assert!(modal_basis(&two, &o)
        .unwrap_err()
        .to_string()
        .contains("at least 3"));
    let three3d = random_shape(3, 3, 1);
    assert!(modal_basis(&three3d, &o).is_err());
    let dup = Shape::from_points_2d(
        &[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 0.0]],
        Topology::None,
    )
    .unwrap();
    assert!(modal_basis(&dup, &o)
        .unwrap_err()
        .to_string()
        .contains("coincide"));
    let tri = random_shape(2, 6, 2);
    for bad in [
        ModelOptions {
            sigma: Some(-1.0),
            ..o.clone()
        },
        ModelOptions {
            sigma: Some(f64::NAN),
            ..o.clone()
        },
        ModelOptions {
            kappa: 0.0,
            ..o.clone()
        },
        ModelOptions {
            material: Material {
                poisson: 0.5,
                ..Material::RUBBER
            },
            ..o.clone()
        },
        ModelOptions {
            n_modes: Some(0),
            ..o.clone()
        },
        ModelOptions {
            n_modes: Some(13),
            ..o.clone()
        },
        ModelOptions {
            element: ElementKind::Axial,
            ..o.clone()
        },
    ] {
        assert!(modal_basis(&tri, &bad).is_err(), "{bad:?} accepted");
    }
    // Collinear 3-D nodes: the rotation about the line is not a motion of the nodes.
    let line = Shape::from_points_3d(
        &[
            [0.0, 0.0, 0.0],
            [1.0, 1.0, 1.0],
            [2.0, 2.0, 2.0],
            [3.5, 3.5, 3.5],
        ],
        Topology::None,
    )
    .unwrap();
    assert!(modal_basis(
        &line,
        &ModelOptions {
            exact_rigid: true,
            ..o.clone()
        }
    )
    .is_err());
    // … while the faithful element still has a well-defined (if degenerate-looking) spectrum.
    assert!(modal_basis(&line, &o).is_ok());
}

#[test]
fn reduced_basis_is_a_rayleigh_ritz_subspace_of_the_full_element() {
    // With the same σ, Gaussians on every second node span a subspace of the full element's
    // displacement fields, so by the min–max principle every reduced eigenvalue bounds the full
    // one from above; the smoothest modes, well resolved by the coarser basis, nearly agree.
    let shape = ellipse(60, 1.2, 0.7);
    let full = modal_basis(&shape, &unit(None)).unwrap();
    let sigma = full.sigma.unwrap() * 2.0;
    let same_sigma = |stride| ModelOptions {
        center_stride: stride,
        ..unit(Some(sigma))
    };
    let full = modal_basis(&shape, &same_sigma(1)).unwrap();
    let reduced = modal_basis(&shape, &same_sigma(2)).unwrap();
    assert_eq!(reduced.modes.nrows(), 120);
    assert_eq!(reduced.modes.ncols(), 60); // 2 · 30 centres
    let scale = full.eigenvalues[119];
    for j in 0..60 {
        assert!(
            reduced.eigenvalues[j] >= full.eigenvalues[j] - 1e-9 * scale,
            "mode {j}: reduced {} < full {}",
            reduced.eigenvalues[j],
            full.eigenvalues[j]
        );
    }
    // The ten lowest modes (the Gaussian element's quasi-rigid ones among them, docs/method.md
    // §2.6) within 1 % of the full element's, with the same shapes at the nodes.
    for j in 0..10 {
        let rel = reduced.eigenvalues[j] / full.eigenvalues[j] - 1.0;
        assert!(rel < 0.01, "mode {j}: {rel}");
        let (a, b) = (reduced.modes.col(j), full.modes.col(j));
        let cos = (a.transpose() * b) / (a.norm_l2() * b.norm_l2());
        assert!(cos.abs() > 0.99, "mode {j}: |cos| {cos}");
    }
}

#[test]
fn reduced_basis_rejects_what_it_cannot_do() {
    let shape = ellipse(12, 1.2, 0.7);
    let with = |stride, exact_rigid, n_modes| ModelOptions {
        center_stride: stride,
        exact_rigid,
        n_modes,
        ..unit(None)
    };
    let msg = |o: &ModelOptions| modal_basis(&shape, o).unwrap_err().to_string();
    assert!(msg(&with(0, false, None)).contains("center_stride"));
    // 12 nodes with stride 6 leave two centres: too few for a 2-D model.
    assert!(msg(&with(6, false, None)).contains("centres"));
    assert!(msg(&with(2, true, None)).contains("exact_rigid"));
    // Six centres have 12 modes, not the nodes' 24.
    assert!(msg(&with(2, false, Some(13))).contains("1..=12"));
    assert_eq!(
        modal_basis(&shape, &with(2, false, None))
            .unwrap()
            .modes
            .ncols(),
        12
    );
    assert!(explicit_model(&shape, &with(2, false, None))
        .unwrap_err()
        .to_string()
        .contains("reduced"));
}
