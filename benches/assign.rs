//! Dense linear assignment: the three `assign` methods and two other Rust crates
//! (`pathfinding::kuhn_munkres`, `lapjv`) on four cost classes, and the order-preserving solver
//! (`ordered`, a constrained problem: its optimum is not the others') beside them, also on a fifth
//! class, `contour`, the matrices of two closed contours (`n × 1.1 n`).
//!
//! `cargo bench --bench assign` (filter with e.g. `-- euclidean/2000` or `-- contour`). Sample
//! size 10 and short measurement times keep a full run to a few minutes; the O(n³) peer with the
//! largest constant (pathfinding) stops at n = 1000, and `ordered`, `O(n · m · (m − n + 1))`, at
//! 500 × 1000 on `rect`.

use std::hint::black_box;
use std::time::Duration;

use assign::{solve, Method, Options};
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use rand::{Rng, SeedableRng};

/// A cost matrix of one of the benchmark classes, row-major, `rows × cols`.
struct Case {
    rows: usize,
    cols: usize,
    cost: Vec<f64>,
}

fn case(class: &'static str, n: usize) -> Case {
    let mut rng = rand::rngs::StdRng::seed_from_u64(0x5eed ^ n as u64);
    let (rows, cols, cost) = match class {
        "uniform" => (n, n, (0..n * n).map(|_| rng.random::<f64>()).collect()),
        "euclidean" => {
            let p: Vec<[f64; 2]> = (0..2 * n).map(|_| [rng.random(), rng.random()]).collect();
            let mut c = Vec::with_capacity(n * n);
            for a in &p[..n] {
                for b in &p[n..] {
                    c.push(((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt());
                }
            }
            (n, n, c)
        }
        "int1-100" => (
            n,
            n,
            (0..n * n)
                .map(|_| rng.random_range(1..=100) as f64)
                .collect(),
        ),
        // n × 2n: the rectangular class is 1000 × 2000.
        "rect" => (
            n,
            2 * n,
            (0..2 * n * n).map(|_| rng.random::<f64>()).collect(),
        ),
        // Two closed contours sampled with n and 1.1 n nodes, B's numbering started elsewhere:
        // the squared distance of the nodes' positions along the contour, plus noise.
        "contour" => {
            let m = n + n / 10;
            let shift = rng.random_range(0..m);
            let mut c = Vec::with_capacity(n * m);
            for i in 0..n {
                for j in 0..m {
                    let d =
                        (i as f64 / n as f64 - ((j + shift) % m) as f64 / m as f64).rem_euclid(1.0);
                    c.push(d.min(1.0 - d).powi(2) + 0.01 * rng.random::<f64>());
                }
            }
            (n, m, c)
        }
        _ => unreachable!(),
    };
    Case { rows, cols, cost }
}

fn bench(c: &mut Criterion) {
    for class in ["uniform", "euclidean", "int1-100", "rect", "contour"] {
        let mut group = c.benchmark_group(format!("assign/{class}"));
        group.sample_size(10);
        group.warm_up_time(Duration::from_millis(500));
        let sizes: &[usize] = match class {
            "rect" => &[100, 500, 1000],
            // Contours of pressure frames have 50–300 nodes.
            "contour" => &[100, 200, 500, 1000],
            _ => &[100, 500, 1000, 2000],
        };
        for &n in sizes {
            let k = case(class, n);
            group.measurement_time(Duration::from_secs(if n >= 1000 { 4 } else { 2 }));
            let label = format!("{}x{}", k.rows, k.cols);
            for (name, method) in [
                ("jv", Method::JonkerVolgenant),
                ("hungarian", Method::Hungarian),
                ("simplex", Method::NetworkSimplex),
                ("ordered", Method::Ordered),
            ] {
                if method == Method::Ordered && class == "rect" && n > 500 {
                    continue;
                }
                let opts = Options {
                    method,
                    maximize: false,
                };
                group.bench_with_input(BenchmarkId::new(name, &label), &k, |b, k| {
                    b.iter(|| solve(black_box(&k.cost), k.rows, k.cols, &opts).unwrap())
                });
            }
            if k.rows == k.cols {
                let m = ndarray::Array2::from_shape_vec((k.rows, k.cols), k.cost.clone()).unwrap();
                group.bench_with_input(BenchmarkId::new("lapjv-crate", &label), &m, |b, m| {
                    b.iter(|| lapjv::lapjv(black_box(m)).unwrap())
                });
            }
            if n <= 1000 {
                // pathfinding needs an Ord weight: costs scaled to integers (exact for int1-100).
                let scale = if class == "int1-100" { 1.0 } else { 1e9 };
                let w: Vec<i64> = k.cost.iter().map(|&x| (x * scale).round() as i64).collect();
                let m = pathfinding::matrix::Matrix::from_vec(k.rows, k.cols, w).unwrap();
                group.bench_with_input(BenchmarkId::new("pathfinding-km", &label), &m, |b, m| {
                    b.iter(|| pathfinding::kuhn_munkres::kuhn_munkres_min(black_box(m)))
                });
            }
        }
        group.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
