//! Modal matching per contour pair (~60 nodes), split into its stages, and per surface pair.
//!
//! Run: `CARGO_TARGET_DIR=target-match cargo bench --bench matching`
//! (compare with `python benches/python/bench_match.py`, which times pycpd on the same cases).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use modal_core::matching::prealign as align;
use modal_core::{
    match_prepared, match_shapes, modal_basis, prepare, MatchOptions, ModelOptions, Parallelism,
    Search, Shape, Topology,
};

// The tests' ground-truth generator (fixtures and warps), shared rather than re-written.
#[path = "../crates/modal-core/tests/match_common/mod.rs"]
mod match_common;

/// A real foot outline (MUN104 left, level 15) sampled at `n` of its vertices, and a warped copy
/// with `m`: rotation 12°, anisotropic scale, shear and bending — a pair that needs both re-fits.
fn pair(n: usize, m: usize) -> (Shape, Shape) {
    let pts = match_common::outline("MUN104L-level15");
    let sample = |c: &[[f64; 2]], k: usize, start: usize| -> Vec<[f64; 2]> {
        (0..k)
            .map(|i| c[(start + i * c.len() / k) % c.len()])
            .collect()
    };
    let (t, sx, sy) = (12f64.to_radians(), 1.08, 0.93);
    let warped: Vec<[f64; 2]> = pts
        .iter()
        .map(|p| {
            let (x, y) = ((p[0] - 12.0) * sx, (p[1] - 30.0) * sy);
            let x = x + 0.1 * y + 0.004 * y * y;
            [t.cos() * x - t.sin() * y, t.sin() * x + t.cos() * y]
        })
        .collect();
    (
        Shape::from_points_2d(&sample(&pts, n, 0), Topology::ClosedContour).unwrap(),
        Shape::from_points_2d(&sample(&warped, m, 17), Topology::ClosedContour).unwrap(),
    )
}

/// A moderate surface case of the tests' generator (the kind `bench_match.py` builds): two
/// independent samplings (`n` and `m` points) of the loaded region (> 30 kPa) of the MUN104
/// pressure template as (x, y, pressure · 20/350), the second warped.
fn surface_pair(n: usize, m: usize) -> (Shape, Shape) {
    let grid = match_common::pressure_grid();
    let case = match_common::surface_case(&grid, match_common::Severity::Moderate, 12345, n, m);
    (
        Shape::from_points_3d(&case.a, Topology::None).unwrap(),
        Shape::from_points_3d(&case.b, Topology::None).unwrap(),
    )
}

fn bench_surfaces(c: &mut Criterion) {
    let (a, b) = surface_pair(110, 118);
    let mut g = c.benchmark_group("match_surface_110x118");
    g.sample_size(20);
    let surf = MatchOptions::for_surfaces();
    g.bench_function("surface_setting", |x| {
        x.iter(|| match_shapes(black_box(&a), black_box(&b), &surf).unwrap())
    });
    let best = MatchOptions {
        search: Search::Best,
        ..surf.clone()
    };
    g.bench_function("surface_setting_search_best", |x| {
        x.iter(|| match_shapes(black_box(&a), black_box(&b), &best).unwrap())
    });
    let mut full = surf.clone();
    full.model.center_stride = 1;
    g.bench_function("surface_setting_center_stride_1", |x| {
        x.iter(|| match_shapes(black_box(&a), black_box(&b), &full).unwrap())
    });
    let positions = MatchOptions {
        position_weight: 1.0,
        ..surf.clone()
    };
    g.bench_function("positions_only", |x| {
        x.iter(|| match_shapes(black_box(&a), black_box(&b), &positions).unwrap())
    });
    g.finish();
}

fn bench(c: &mut Criterion) {
    let (a, b) = pair(60, 64);
    let mut g = c.benchmark_group("match_contour_60x64");
    g.sample_size(30);
    g.bench_function("recipe_default", |x| {
        x.iter(|| match_shapes(black_box(&a), black_box(&b), &MatchOptions::default()).unwrap())
    });
    g.bench_function("recipe_default_serial", |x| {
        let o = MatchOptions::default();
        x.iter(|| {
            let (pa, pb) = (prepare(&a, &o).unwrap(), prepare(&b, &o).unwrap());
            match_prepared(black_box(&pa), black_box(&pb), &o, Parallelism::Serial).unwrap()
        })
    });
    // The default for two closed outlines (`pedomatch match`, `pymodal.match`): no re-fit.
    g.bench_function("recipe_no_refit", |x| {
        let o = MatchOptions::for_outlines();
        x.iter(|| match_shapes(black_box(&a), black_box(&b), &o).unwrap())
    });
    // On the calling thread alone: what the helper job of `Parallelism::Pair` (rotation
    // starts, survivors, B's solve) saves one pair at a time.
    g.bench_function("recipe_no_refit_serial", |x| {
        let o = MatchOptions::for_outlines();
        x.iter(|| {
            let (pa, pb) = (prepare(&a, &o).unwrap(), prepare(&b, &o).unwrap());
            match_prepared(black_box(&pa), black_box(&pb), &o, Parallelism::Serial).unwrap()
        })
    });
    g.bench_function("recipe_center_stride_2", |x| {
        let mut o = MatchOptions::default();
        o.model.center_stride = 2;
        x.iter(|| match_shapes(black_box(&a), black_box(&b), &o).unwrap())
    });
    g.bench_function("paper_setting", |x| {
        x.iter(|| match_shapes(black_box(&a), black_box(&b), &MatchOptions::paper()).unwrap())
    });
    g.bench_function("positions_only", |x| {
        let o = MatchOptions {
            position_weight: 1.0,
            ..MatchOptions::default()
        };
        x.iter(|| match_shapes(black_box(&a), black_box(&b), &o).unwrap())
    });
    let (pa, _, _) = align::normalize(a.coords(), 2).unwrap();
    let (pb, _, _) = align::normalize(b.coords(), 2).unwrap();
    g.bench_function("robust_prealign", |x| {
        x.iter(|| {
            align::robust_prealign(
                black_box(&pa),
                black_box(&pb),
                2,
                &align::RotationSearch::default(),
                true,
            )
        })
    });
    // The same search without the outline fit that ends it: what the fit costs.
    let node_icp_only = align::RotationSearch {
        outline_iterations: 0,
        ..align::RotationSearch::default()
    };
    g.bench_function("robust_prealign_without_outline_fit", |x| {
        x.iter(|| align::robust_prealign(black_box(&pa), black_box(&pb), 2, &node_icp_only, true))
    });
    let sa = Shape::new(2, pa.clone(), Topology::ClosedContour).unwrap();
    let opts = ModelOptions {
        n_modes: Some(30),
        material: modal_core::Material {
            young: 1.0,
            poisson: 0.49,
            density: 1.0,
        },
        ..ModelOptions::default()
    };
    g.bench_function("modal_basis_30_modes", |x| {
        x.iter(|| modal_basis(black_box(&sa), &opts).unwrap())
    });
    let reduced = ModelOptions {
        center_stride: 2,
        ..opts.clone()
    };
    g.bench_function("modal_basis_30_modes_center_stride_2", |x| {
        x.iter(|| modal_basis(black_box(&sa), &reduced).unwrap())
    });
    g.finish();
}

/// A recording's worth of contours: the outline and its warped copy of [`pair`], alternately, at
/// 60–64 nodes; consecutive frames are matched, one pair after the other on one thread, either
/// from the shapes (every object prepared for each of its two pairs) or from objects prepared
/// once (`run`'s way).
fn bench_sequence(c: &mut Criterion) {
    let frames: Vec<Shape> = (0..9)
        .map(|f| {
            let (a, b) = pair(60 + f % 5, 60 + f % 5);
            if f % 2 == 0 {
                a
            } else {
                b
            }
        })
        .collect();
    let mut g = c.benchmark_group("sequence_9_contours");
    g.sample_size(20);
    for (name, o) in [
        ("recipe", MatchOptions::default()),
        ("paper", MatchOptions::paper()),
    ] {
        g.bench_function(format!("{name}_shapes_per_pair"), |x| {
            x.iter(|| {
                for w in frames.windows(2) {
                    let (pa, pb) = (prepare(&w[0], &o).unwrap(), prepare(&w[1], &o).unwrap());
                    black_box(match_prepared(&pa, &pb, &o, Parallelism::Serial).unwrap());
                }
            })
        });
        g.bench_function(format!("{name}_prepared_once"), |x| {
            x.iter(|| {
                let prepared: Vec<_> = frames.iter().map(|s| prepare(s, &o).unwrap()).collect();
                for w in prepared.windows(2) {
                    black_box(match_prepared(&w[0], &w[1], &o, Parallelism::Serial).unwrap());
                }
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench, bench_surfaces, bench_sequence);
criterion_main!(benches);
