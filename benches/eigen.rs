//! Modal solves: the per-contour solve of the matching recipe (60 nodes, 120 dof) and the
//! generalized eigensolve at 300 and 900 dof (compare with benches/python/bench_eigen.py).
//!
//! The `eigen_stages_*` groups time every stage of the solve with faer's routine beside the
//! hand-written one, at the orders the matching uses (60-node contour: 120 dof, 30 modes) and at
//! 300 and 900 dof (a quarter of the modes), on the matrices of the Gaussian model.
//!
//! Run: `cargo bench --bench eigen`

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use modal_core::internals::{
    generalized_eigen, model_matrices, stages, symmetric_eigen, symmetric_eigen_lowest,
};
use modal_core::{modal_basis, ModelOptions, Shape, Topology};

/// A foot-like closed outline with `n` nodes, centred, RMS radius ≈ 1.
fn contour(n: usize) -> Shape {
    let pts: Vec<[f64; 2]> = (0..n)
        .map(|k| {
            let t = 2.0 * std::f64::consts::PI * (k as f64 + 0.3) / n as f64;
            let r = 1.0 + 0.25 * (2.0 * t).cos() + 0.1 * (3.0 * t).sin();
            [1.3 * r * t.cos(), 0.8 * r * t.sin()]
        })
        .collect();
    Shape::from_points_2d(&pts, Topology::ClosedContour).unwrap()
}

fn bench(c: &mut Criterion) {
    let shape = contour(60);
    let k = 30; // ⌊0.25 · 2 · 60⌋, the recipe's mode count
    let mut g = c.benchmark_group("modal_solve_60_nodes");
    g.bench_function("gaussian_all_120_modes", |b| {
        b.iter(|| modal_basis(black_box(&shape), &ModelOptions::default()).unwrap())
    });
    let partial = ModelOptions {
        n_modes: Some(k),
        ..ModelOptions::default()
    };
    g.bench_function("gaussian_lowest_30_modes", |b| {
        b.iter(|| modal_basis(black_box(&shape), &partial).unwrap())
    });
    g.finish();

    let mut g = c.benchmark_group("generalized_eigen");
    g.sample_size(20);
    for nodes in [150usize, 450] {
        let shape = contour(nodes);
        let dof = 2 * nodes;
        let (kk, mm, _) = model_matrices(&shape, &ModelOptions::default()).unwrap();
        g.bench_function(format!("dense_KM_all_{dof}"), |b| {
            b.iter(|| generalized_eigen(black_box(kk.as_ref()), mm.as_ref(), None).unwrap())
        });
        g.bench_function(format!("dense_KM_lowest25pct_{dof}"), |b| {
            b.iter(|| {
                generalized_eigen(black_box(kk.as_ref()), mm.as_ref(), Some(dof / 4)).unwrap()
            })
        });
        g.bench_function(format!("modal_basis_all_{dof}"), |b| {
            b.iter(|| modal_basis(black_box(&shape), &ModelOptions::default()).unwrap())
        });
        let part = ModelOptions {
            n_modes: Some(dof / 4),
            ..ModelOptions::default()
        };
        g.bench_function(format!("modal_basis_lowest25pct_{dof}"), |b| {
            b.iter(|| modal_basis(black_box(&shape), &part).unwrap())
        });
    }
    g.finish();
}

/// Each stage of the symmetric-definite solve, hand-written beside faer, on the same matrices.
fn bench_stages(c: &mut Criterion) {
    for nodes in [60usize, 150, 450] {
        let dof = 2 * nodes;
        let k = dof / 4;
        let shape = contour(nodes);
        let (kk, mm, _) = model_matrices(&shape, &ModelOptions::default()).unwrap();
        let l = stages::cholesky_factor(mm.as_ref()).unwrap();
        let cc = stages::congruence_faer(l.as_ref(), kk.as_ref());
        let hand_t = stages::tridiagonalize_hand(cc.as_ref());
        let faer_t = stages::tridiagonalize_faer(cc.as_ref());
        let (d, e) = faer_t.entries();
        let lowest = stages::lowest_eigenvalues_bisection(&d, &e, k);
        let vecs = stages::eigenvectors_inverse_iteration(&d, &e, &lowest).unwrap();

        let mut g = c.benchmark_group(format!("eigen_stages_{dof}"));
        g.sample_size(if dof > 500 { 10 } else { 30 });
        g.bench_function("cholesky/faer", |b| {
            b.iter(|| stages::cholesky_factor(black_box(mm.as_ref())).unwrap())
        });
        g.bench_function("congruence/faer_two_trsm", |b| {
            b.iter(|| stages::congruence_faer(l.as_ref(), black_box(kk.as_ref())))
        });
        g.bench_function("tridiagonalize/hand", |b| {
            b.iter(|| stages::tridiagonalize_hand(black_box(cc.as_ref())))
        });
        g.bench_function("tridiagonalize/faer", |b| {
            b.iter(|| stages::tridiagonalize_faer(black_box(cc.as_ref())))
        });
        g.bench_function("all_values/hand_root_free_ql", |b| {
            b.iter(|| stages::eigenvalues_ql(black_box(&d), &e).unwrap())
        });
        g.bench_function("all_values/faer_qr", |b| {
            b.iter(|| stages::eigenvalues_faer(black_box(&d), &e).unwrap())
        });
        g.bench_function(format!("lowest_{k}_values/hand_bisection"), |b| {
            b.iter(|| stages::lowest_eigenvalues_bisection(black_box(&d), &e, k))
        });
        g.bench_function(format!("lowest_{k}_vectors/hand_inverse_iteration"), |b| {
            b.iter(|| stages::eigenvectors_inverse_iteration(black_box(&d), &e, &lowest).unwrap())
        });
        g.bench_function("tridiagonal_all_pairs/faer", |b| {
            b.iter(|| stages::tridiagonal_evd_faer(black_box(&d), &e, true).unwrap())
        });
        g.bench_function(
            format!("back_transform_{k}/hand_reflectors_faer_blocked"),
            |b| {
                b.iter(|| {
                    let mut y = vecs.clone();
                    hand_t.apply_q(black_box(y.as_mut()));
                    y
                })
            },
        );
        g.bench_function(format!("back_transform_{k}/faer"), |b| {
            b.iter(|| {
                let mut y = vecs.clone();
                faer_t.apply_q(black_box(y.as_mut()));
                y
            })
        });
        g.bench_function("symmetric_all/hand", |b| {
            b.iter(|| symmetric_eigen(black_box(cc.clone()), None).unwrap())
        });
        g.bench_function("symmetric_all/faer_evd", |b| {
            b.iter(|| stages::symmetric_eigen_faer(black_box(cc.as_ref()), dof).unwrap())
        });
        g.bench_function(format!("symmetric_lowest_{k}/hand"), |b| {
            b.iter(|| symmetric_eigen_lowest(black_box(cc.clone()), k).unwrap())
        });
        g.bench_function(format!("symmetric_lowest_{k}/faer_evd"), |b| {
            b.iter(|| stages::symmetric_eigen_faer(black_box(cc.as_ref()), k).unwrap())
        });
        g.bench_function("generalized_all/hand", |b| {
            b.iter(|| generalized_eigen(black_box(kk.as_ref()), mm.as_ref(), None).unwrap())
        });
        g.bench_function("generalized_all/faer", |b| {
            b.iter(|| {
                stages::generalized_eigen_faer(black_box(kk.as_ref()), mm.as_ref(), dof).unwrap()
            })
        });
        g.bench_function(format!("generalized_lowest_{k}/hand"), |b| {
            b.iter(|| generalized_eigen(black_box(kk.as_ref()), mm.as_ref(), Some(k)).unwrap())
        });
        g.bench_function(format!("generalized_lowest_{k}/faer"), |b| {
            b.iter(|| {
                stages::generalized_eigen_faer(black_box(kk.as_ref()), mm.as_ref(), k).unwrap()
            })
        });
        g.bench_function(
            format!("generalized_lowest_{k}/faer_with_hand_bisection_inverse_iteration"),
            |b| {
                b.iter(|| {
                    stages::generalized_eigen_lowest_mixed(black_box(kk.as_ref()), mm.as_ref(), k)
                        .unwrap()
                })
            },
        );
        g.finish();
    }
}

criterion_group!(benches, bench, bench_stages);
criterion_main!(benches);
