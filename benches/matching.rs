//! Modal matching per contour pair (~60 nodes), split into its stages, and per surface pair.
//!
//! Run: `CARGO_TARGET_DIR=target-match cargo bench --bench matching`
//! (compare with `python benches/python/bench_match.py`, which times pycpd on the same cases).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use modal_core::{
    align, match_shapes, modal_basis, MatchOptions, ModelOptions, Search, Shape, Topology,
};

/// A real foot outline (MUN104 left, level 15) resampled at `n` points, and a warped copy with
/// `m` points: rotation 12°, anisotropic scale, shear and bending.
fn pair(n: usize, m: usize) -> (Shape, Shape) {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/crates/modal-core/tests/data/contours.txt"
    );
    let text = std::fs::read_to_string(path).expect("contour fixture");
    let mut pts: Vec<[f64; 2]> = Vec::new();
    let mut on = false;
    for l in text.lines() {
        if l.starts_with("# ") {
            if on {
                break;
            }
            on = l.contains("MUN104L-level15");
        } else if on && !l.trim().is_empty() {
            let v: Vec<f64> = l.split_whitespace().map(|s| s.parse().unwrap()).collect();
            pts.push([v[0], v[1]]);
        }
    }
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

/// Two independent samplings (`n` and `m` points) of the loaded region (> 30 kPa) of the MUN104
/// pressure template as (x, y, pressure · 20/350), the second turned by 12° and scaled: the
/// surface case of `bench_match.py`.
fn surface_pair(n: usize, m: usize) -> (Shape, Shape) {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/crates/modal-core/tests/data/mun104l.txt"
    );
    let grid: Vec<Vec<f64>> = std::fs::read_to_string(path)
        .expect("pressure fixture")
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| l.split_whitespace().map(|v| v.parse().unwrap()).collect())
        .collect();
    let (rows, cols) = (grid.len(), grid[0].len());
    let pressure = |x: f64, y: f64| {
        let (j, i) = (x.floor() as usize, y.floor() as usize);
        let (fx, fy) = (x - j as f64, y - i as f64);
        grid[i][j] * (1.0 - fx) * (1.0 - fy)
            + grid[i][j + 1] * fx * (1.0 - fy)
            + grid[i + 1][j] * (1.0 - fx) * fy
            + grid[i + 1][j + 1] * fx * fy
    };
    let mut seed = 12345u64;
    let mut unit = move || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut sample = |k: usize| -> Vec<[f64; 3]> {
        let mut out = Vec::with_capacity(k);
        while out.len() < k {
            let (x, y) = (unit() * (cols - 2) as f64, unit() * (rows - 2) as f64);
            let p = pressure(x, y);
            if p > 30.0 {
                out.push([x, y, p * 20.0 / 350.0]);
            }
        }
        out
    };
    let a = sample(n);
    let (t, s) = (12f64.to_radians(), 1.05);
    let b: Vec<[f64; 3]> = sample(m)
        .into_iter()
        .map(|[x, y, z]| {
            [
                s * (t.cos() * x - t.sin() * y) + 3.0,
                s * (t.sin() * x + t.cos() * y) - 2.0,
                z,
            ]
        })
        .collect();
    (
        Shape::from_points_3d(&a, Topology::None).unwrap(),
        Shape::from_points_3d(&b, Topology::None).unwrap(),
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
    let mut reduced = surf.clone();
    reduced.model.center_stride = 2;
    g.bench_function("surface_setting_center_stride_2", |x| {
        x.iter(|| match_shapes(black_box(&a), black_box(&b), &reduced).unwrap())
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
    g.bench_function("recipe_no_refit", |x| {
        let o = MatchOptions {
            refits: 0,
            ..MatchOptions::default()
        };
        x.iter(|| match_shapes(black_box(&a), black_box(&b), &o).unwrap())
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

criterion_group!(benches, bench, bench_surfaces);
criterion_main!(benches);
