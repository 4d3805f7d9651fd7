//! Quick timing of the solvers on the benchmark cost classes, for tuning without criterion.
//!
//! `cargo run --release -p assign --example timing -- [n ...]`

use assign::{solve, Method, Options};
use rand::{Rng, SeedableRng};

#[repr(C)]
struct Timespec {
    sec: i64,
    nsec: i64,
}
// SAFETY: the C library's `clock_gettime(clockid_t, struct timespec *)`, with `Timespec` laid out
// as the 64-bit Linux `struct timespec`.
unsafe extern "C" {
    fn clock_gettime(clk: i32, tp: *mut Timespec) -> i32;
}

/// Thread CPU time in seconds: wall time is meaningless on the shared, overloaded machine.
fn cpu_now() -> f64 {
    let mut t = Timespec { sec: 0, nsec: 0 };
    // CLOCK_THREAD_CPUTIME_ID = 3 on Linux.
    // SAFETY: `t` is a valid, writable `Timespec` for the duration of the call.
    unsafe { clock_gettime(3, &mut t) };
    t.sec as f64 + t.nsec as f64 * 1e-9
}

fn matrix(kind: &str, n: usize, seed: u64) -> (Vec<f64>, usize, usize) {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    match kind {
        "uniform" => ((0..n * n).map(|_| rng.random::<f64>()).collect(), n, n),
        "euclidean" => {
            let p: Vec<(f64, f64)> = (0..2 * n).map(|_| (rng.random(), rng.random())).collect();
            let mut c = vec![0.0; n * n];
            for i in 0..n {
                for j in 0..n {
                    let (a, b) = (p[i], p[n + j]);
                    c[i * n + j] = ((a.0 - b.0).powi(2) + (a.1 - b.1).powi(2)).sqrt();
                }
            }
            (c, n, n)
        }
        "int" => (
            (0..n * n)
                .map(|_| rng.random_range(1..=100) as f64)
                .collect(),
            n,
            n,
        ),
        "rect" => (
            (0..2 * n * n).map(|_| rng.random::<f64>()).collect(),
            n,
            2 * n,
        ),
        "rectT" => (
            (0..2 * n * n).map(|_| rng.random::<f64>()).collect(),
            2 * n,
            n,
        ),
        _ => panic!("unknown class"),
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let methods: Vec<Method> = match std::env::var("METHODS").as_deref() {
        Ok("jv") => vec![Method::JonkerVolgenant],
        Ok("hu") => vec![Method::Hungarian],
        Ok("ns") => vec![Method::NetworkSimplex],
        _ => vec![
            Method::JonkerVolgenant,
            Method::Hungarian,
            Method::NetworkSimplex,
        ],
    };
    let classes: Vec<String> = std::env::var("CLASSES")
        .map(|s| s.split(',').map(String::from).collect())
        .unwrap_or_else(|_| {
            vec![
                "uniform".into(),
                "euclidean".into(),
                "int".into(),
                "rect".into(),
            ]
        });
    let sizes: Vec<usize> = if args.is_empty() {
        vec![1000, 2000]
    } else {
        args.iter().map(|a| a.parse().unwrap()).collect()
    };
    let reps: usize = std::env::var("REPS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(3);
    for kind in &classes {
        for &n in &sizes {
            let (c, r, k) = matrix(kind, n, 42);
            for &m in &methods {
                let mut best = f64::INFINITY;
                let mut cost = 0.0;
                for _ in 0..reps {
                    let t = cpu_now();
                    let a = solve(
                        &c,
                        r,
                        k,
                        &Options {
                            method: m,
                            maximize: false,
                        },
                    )
                    .unwrap();
                    best = best.min(cpu_now() - t);
                    cost = a.cost;
                }
                println!(
                    "{kind:10} {r:5}x{k:<5} {m:?}: {:9.2} ms  cost {cost:.6}",
                    best * 1e3
                );
            }
        }
    }
}
