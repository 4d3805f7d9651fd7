//! Modal solves: the per-contour solve of the matching recipe (60 nodes, 120 dof) and the
//! generalized eigensolve at 300 and 900 dof (compare with benches/python/bench_eigen.py).
//!
//! Run: `CARGO_TARGET_DIR=target-modal cargo bench --bench eigen`

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use modal_core::eigen::generalized_eigen;
use modal_core::{modal_basis, model_matrices, ModelOptions, Shape, Topology};

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

criterion_group!(benches, bench);
criterion_main!(benches);
