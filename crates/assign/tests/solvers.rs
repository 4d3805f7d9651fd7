//! Known answers, edge cases and cross-checks of the three solvers against each other and
//! against brute force.

use assign::{solve, solve_with_threshold, AssignError, Assignment, Method, Options};
use proptest::prelude::*;

const METHODS: [Method; 3] = [
    Method::JonkerVolgenant,
    Method::Hungarian,
    Method::NetworkSimplex,
];
const INF: f64 = f64::INFINITY;

fn opts(method: Method, maximize: bool) -> Options {
    Options { method, maximize }
}

/// Minimum (or maximum) total over all assignments of `min(rows, cols)` pairs, `None` if none
/// avoids the forbidden entries.
fn brute_force(c: &[f64], rows: usize, cols: usize, maximize: bool) -> Option<f64> {
    #[allow(clippy::too_many_arguments)]
    fn rec(
        c: &[f64],
        rows: usize,
        cols: usize,
        i: usize,
        used: &mut Vec<bool>,
        acc: f64,
        best: &mut Option<f64>,
        maximize: bool,
        transposed: bool,
    ) {
        let (n, m) = if transposed {
            (cols, rows)
        } else {
            (rows, cols)
        };
        if i == n {
            let better = match best {
                None => true,
                Some(b) => {
                    if maximize {
                        acc > *b
                    } else {
                        acc < *b
                    }
                }
            };
            if better {
                *best = Some(acc);
            }
            return;
        }
        for j in 0..m {
            if used[j] {
                continue;
            }
            let x = if transposed {
                c[j * cols + i]
            } else {
                c[i * cols + j]
            };
            let forbidden = if maximize { x == -INF } else { x == INF };
            if forbidden {
                continue;
            }
            used[j] = true;
            rec(
                c,
                rows,
                cols,
                i + 1,
                used,
                acc + x,
                best,
                maximize,
                transposed,
            );
            used[j] = false;
        }
    }
    let transposed = rows > cols;
    let m = rows.max(cols);
    let mut best = None;
    rec(
        c,
        rows,
        cols,
        0,
        &mut vec![false; m],
        0.0,
        &mut best,
        maximize,
        transposed,
    );
    best
}

/// Best value of the threshold objective: Σ over matched (c - τ), any matching, by brute force.
fn brute_force_threshold(c: &[f64], rows: usize, cols: usize, tau: f64) -> f64 {
    fn rec(
        c: &[f64],
        rows: usize,
        cols: usize,
        i: usize,
        used: &mut Vec<bool>,
        acc: f64,
        tau: f64,
    ) -> f64 {
        if i == rows {
            return acc;
        }
        // Row i unmatched.
        let mut best = rec(c, rows, cols, i + 1, used, acc, tau);
        for j in 0..cols {
            if used[j] || c[i * cols + j] == INF {
                continue;
            }
            used[j] = true;
            best = best.min(rec(
                c,
                rows,
                cols,
                i + 1,
                used,
                acc + c[i * cols + j] - tau,
                tau,
            ));
            used[j] = false;
        }
        best
    }
    rec(c, rows, cols, 0, &mut vec![false; cols], 0.0, tau)
}

fn check_consistent(a: &Assignment, c: &[f64], rows: usize, cols: usize) {
    assert_eq!(a.row_to_col.len(), rows);
    assert_eq!(a.col_to_row.len(), cols);
    let mut total = 0.0;
    let mut count = 0;
    for (i, j) in a.row_to_col.iter().enumerate() {
        if let Some(j) = *j {
            assert_eq!(a.col_to_row[j], Some(i));
            total += c[i * cols + j];
            count += 1;
        }
    }
    assert_eq!(a.col_to_row.iter().filter(|x| x.is_some()).count(), count);
    assert_eq!(total, a.cost);
}

/// Checks the documented dual certificate.
fn check_duals(a: &Assignment, c: &[f64], rows: usize, cols: usize, maximize: bool) {
    let (u, v) = a.duals.as_ref().expect("solve reports duals");
    let s = if maximize { -1.0 } else { 1.0 };
    let scale = c
        .iter()
        .filter(|x| x.is_finite())
        .fold(1.0f64, |m, x| m.max(x.abs()));
    let tol = 1e-9 * scale * (rows + cols) as f64;
    for i in 0..rows {
        for j in 0..cols {
            let x = c[i * cols + j];
            if x.is_finite() {
                assert!(
                    s * (u[i] + v[j]) <= s * x + tol,
                    "dual infeasible at ({i},{j})"
                );
            }
        }
        if let Some(j) = a.row_to_col[i] {
            assert!(
                (u[i] + v[j] - c[i * cols + j]).abs() <= tol,
                "not tight at ({i},{j})"
            );
        }
    }
    let (long, long_assigned): (&Vec<f64>, Vec<bool>) = if rows <= cols {
        (v, a.col_to_row.iter().map(|x| x.is_some()).collect())
    } else {
        (u, a.row_to_col.iter().map(|x| x.is_some()).collect())
    };
    if rows != cols {
        for (k, &d) in long.iter().enumerate() {
            assert!(s * d <= tol);
            if !long_assigned[k] {
                assert!(d.abs() <= tol);
            }
        }
    }
    let dual_obj: f64 = u.iter().sum::<f64>() + v.iter().sum::<f64>();
    assert!(
        (dual_obj - a.cost).abs() <= tol,
        "dual objective {dual_obj} != {}",
        a.cost
    );
}

#[test]
fn known_square() {
    let c = [4.0, 1.0, 3.0, 2.0, 0.0, 5.0, 3.0, 2.0, 2.0];
    for m in METHODS {
        let a = solve(&c, 3, 3, &opts(m, false)).unwrap();
        assert_eq!(a.row_to_col, vec![Some(1), Some(0), Some(2)], "{m:?}");
        assert_eq!(a.cost, 5.0);
        check_duals(&a, &c, 3, 3, false);
        let a = solve(&c, 3, 3, &opts(m, true)).unwrap();
        // 4 + 5 + 2 = 11 is the maximum.
        assert_eq!(a.cost, 11.0, "{m:?}");
        assert_eq!(a.row_to_col, vec![Some(0), Some(2), Some(1)]);
        check_duals(&a, &c, 3, 3, true);
    }
}

#[test]
fn known_rectangular_both_ways() {
    // scipy's docs example, wide and tall.
    let c = [4.0, 1.0, 3.0, 2.0, 2.0, 5.0];
    for m in METHODS {
        let a = solve(&c, 2, 3, &opts(m, false)).unwrap();
        assert_eq!(a.cost, 3.0, "{m:?}");
        assert_eq!(a.row_to_col, vec![Some(1), Some(0)]);
        assert_eq!(a.col_to_row, vec![Some(1), Some(0), None]);
        check_duals(&a, &c, 2, 3, false);
        let t = [4.0, 2.0, 1.0, 2.0, 3.0, 5.0];
        let a = solve(&t, 3, 2, &opts(m, false)).unwrap();
        assert_eq!(a.cost, 3.0);
        assert_eq!(a.row_to_col, vec![Some(1), Some(0), None]);
        check_duals(&a, &t, 3, 2, false);
        let a = solve(&t, 3, 2, &opts(m, true)).unwrap();
        assert_eq!(a.cost, 9.0);
        check_duals(&a, &t, 3, 2, true);
    }
}

#[test]
fn ties_all_equal() {
    let n = 7;
    let c = vec![3.0; n * n];
    for m in METHODS {
        let a = solve(&c, n, n, &opts(m, false)).unwrap();
        check_consistent(&a, &c, n, n);
        assert_eq!(a.cost, 21.0);
        assert!(a.row_to_col.iter().all(|x| x.is_some()));
    }
}

#[test]
fn inf_entries_and_infeasible() {
    let c = [INF, 1.0, 2.0, INF];
    let bad = [INF, 1.0, INF, 2.0];
    for m in METHODS {
        let a = solve(&c, 2, 2, &opts(m, false)).unwrap();
        assert_eq!(a.cost, 3.0);
        assert_eq!(a.row_to_col, vec![Some(1), Some(0)]);
        assert_eq!(
            solve(&bad, 2, 2, &opts(m, false)),
            Err(AssignError::Infeasible),
            "{m:?}"
        );
        assert_eq!(
            solve(&[INF; 6], 2, 3, &opts(m, false)),
            Err(AssignError::Infeasible)
        );
        assert_eq!(
            solve(&[INF; 6], 3, 2, &opts(m, false)),
            Err(AssignError::Infeasible)
        );
        // Maximising: -inf is the forbidden value, +inf is an error.
        let neg = [f64::NEG_INFINITY, 1.0, 2.0, f64::NEG_INFINITY];
        assert_eq!(solve(&neg, 2, 2, &opts(m, true)).unwrap().cost, 3.0);
        assert_eq!(
            solve(&c, 2, 2, &opts(m, true)),
            Err(AssignError::InvalidEntry { row: 0, col: 0 })
        );
    }
}

/// JV checks the entries during its own first pass on wide minimisations; the error must be the
/// one of a separate full check: the first bad entry in row-major order, taking precedence over
/// infeasibility, wherever it sits (early, late, in a row no heuristic phase reads).
#[test]
fn invalid_entries_found_anywhere() {
    let mut state = 2024u64;
    let mut rnd = move |k: u64| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state % k
    };
    for (rows, cols) in [(1, 1), (3, 3), (9, 9), (40, 40), (5, 12), (30, 70), (12, 5)] {
        for trial in 0..60 {
            let mut c: Vec<f64> = (0..rows * cols)
                .map(|_| {
                    if trial % 3 == 0 {
                        rnd(4) as f64
                    } else {
                        rnd(1000) as f64 / 7.0
                    }
                })
                .collect();
            if trial % 4 == 1 {
                // A row with no allowed pair: infeasible as well as invalid.
                let i = rnd(rows as u64) as usize;
                c[i * cols..(i + 1) * cols].fill(INF);
            }
            let bad = if trial % 2 == 0 {
                f64::NAN
            } else {
                f64::NEG_INFINITY
            };
            let nbad = 1 + rnd(3) as usize;
            let mut first = usize::MAX;
            for _ in 0..nbad {
                let k = rnd((rows * cols) as u64) as usize;
                c[k] = bad;
                first = first.min(k);
            }
            let want = Err(AssignError::InvalidEntry {
                row: first / cols,
                col: first % cols,
            });
            for m in METHODS {
                assert_eq!(solve(&c, rows, cols, &opts(m, false)), want, "{m:?}");
                assert_eq!(
                    solve_with_threshold(&c, rows, cols, 3.0, &opts(m, false)),
                    want,
                    "{m:?}"
                );
            }
            // Maximising: NaN and +inf are the invalid ones.
            let flipped: Vec<f64> = c.iter().map(|&x| -x).collect();
            for m in METHODS {
                assert_eq!(solve(&flipped, rows, cols, &opts(m, true)), want, "{m:?}");
            }
        }
    }
}

#[test]
fn invalid_entries() {
    for m in METHODS {
        let o = opts(m, false);
        assert_eq!(
            solve(&[1.0, f64::NAN], 1, 2, &o),
            Err(AssignError::InvalidEntry { row: 0, col: 1 })
        );
        assert_eq!(
            solve(&[1.0, 2.0, f64::NEG_INFINITY, 0.0], 2, 2, &o),
            Err(AssignError::InvalidEntry { row: 1, col: 0 })
        );
        assert!(matches!(
            solve(&[1.0; 5], 2, 3, &o),
            Err(AssignError::ShapeMismatch { .. })
        ));
        assert!(matches!(
            solve_with_threshold(&[1.0], 1, 1, f64::NAN, &o),
            Err(AssignError::InvalidThreshold { .. })
        ));
    }
}

#[test]
fn empty() {
    for m in METHODS {
        for (r, c) in [(0, 0), (0, 3), (4, 0)] {
            let a = solve(&[], r, c, &opts(m, false)).unwrap();
            assert_eq!(a.cost, 0.0);
            assert_eq!(a.row_to_col, vec![None; r]);
            assert_eq!(a.col_to_row, vec![None; c]);
            let a = solve_with_threshold(&[], r, c, 1.0, &opts(m, false)).unwrap();
            assert_eq!(a.cost, 0.0);
        }
    }
}

#[test]
fn single_entries() {
    for m in METHODS {
        let a = solve(&[-2.5], 1, 1, &opts(m, false)).unwrap();
        assert_eq!((a.row_to_col.clone(), a.cost), (vec![Some(0)], -2.5));
        let a = solve(&[5.0, INF, 1.0], 1, 3, &opts(m, false)).unwrap();
        assert_eq!(a.row_to_col, vec![Some(2)]);
        let a = solve(&[5.0, INF, 1.0], 3, 1, &opts(m, false)).unwrap();
        assert_eq!(a.col_to_row, vec![Some(2)]);
    }
}

#[test]
fn threshold_known() {
    // Row 0 matches column 0 at 1 (< τ = 3); row 1's only affordable column is taken, and
    // its other pairs exceed τ, so it stays unassigned.
    let c = [1.0, 9.0, 2.0, 8.0];
    for m in METHODS {
        let a = solve_with_threshold(&c, 2, 2, 3.0, &opts(m, false)).unwrap();
        assert_eq!(a.row_to_col, vec![Some(0), None], "{m:?}");
        assert_eq!(a.col_to_row, vec![Some(0), None]);
        assert_eq!(a.cost, 1.0);
        assert!(a.duals.is_none());
        // A large τ gives the plain assignment.
        let a = solve_with_threshold(&c, 2, 2, 100.0, &opts(m, false)).unwrap();
        assert_eq!(a.cost, 9.0);
        // Maximising: keep pairs worth more than τ.
        let a = solve_with_threshold(&c, 2, 2, 8.5, &opts(m, true)).unwrap();
        assert_eq!(a.row_to_col, vec![Some(1), None]);
        // Tall matrix.
        let t = [1.0, 2.0, 9.0, 8.0];
        let a = solve_with_threshold(&t, 2, 2, 3.0, &opts(m, false)).unwrap();
        assert_eq!(a.row_to_col, vec![Some(0), None]);
    }
}

#[test]
fn larger_random_agree() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand::rngs::StdRng::seed_from_u64(7);
    for &(r, c, ints) in &[
        (60, 60, false),
        (60, 60, true),
        (40, 90, false),
        (90, 40, true),
        (150, 150, false),
    ] {
        for _ in 0..3 {
            let cost: Vec<f64> = (0..r * c)
                .map(|_| {
                    if ints {
                        rng.random_range(1..=10) as f64
                    } else {
                        rng.random::<f64>()
                    }
                })
                .collect();
            let sols: Vec<Assignment> = METHODS
                .iter()
                .map(|&m| solve(&cost, r, c, &opts(m, false)).unwrap())
                .collect();
            for a in &sols {
                check_consistent(a, &cost, r, c);
                check_duals(a, &cost, r, c, false);
                assert!(
                    (a.cost - sols[0].cost).abs() <= 1e-9 * r as f64,
                    "{} vs {}",
                    a.cost,
                    sols[0].cost
                );
            }
        }
    }
}

fn matrix() -> impl Strategy<Value = (usize, usize, Vec<f64>)> {
    (0usize..=6, 0usize..=6, 0u8..4).prop_flat_map(|(r, c, kind)| {
        let entry = match kind {
            0 => (-50i32..50).prop_map(f64::from).boxed(),
            1 => (0i32..3).prop_map(f64::from).boxed(), // heavy ties
            2 => prop_oneof![4 => -1e3f64..1e3, 1 => Just(INF)].boxed(),
            _ => prop_oneof![3 => (0i32..5).prop_map(f64::from), 2 => Just(INF)].boxed(),
        };
        (Just(r), Just(c), proptest::collection::vec(entry, r * c))
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(600))]

    #[test]
    fn methods_match_brute_force((r, c, cost) in matrix(), maximize in any::<bool>()) {
        let cost: Vec<f64> = if maximize {
            cost.iter().map(|&x| if x == INF { f64::NEG_INFINITY } else { x }).collect()
        } else {
            cost
        };
        let expected = brute_force(&cost, r, c, maximize);
        for m in METHODS {
            let got = solve(&cost, r, c, &opts(m, maximize));
            match expected {
                None => prop_assert_eq!(got, Err(AssignError::Infeasible), "{:?}", m),
                Some(best) => {
                    let a = got.unwrap();
                    check_consistent(&a, &cost, r, c);
                    prop_assert_eq!(a.row_to_col.iter().filter(|x| x.is_some()).count(), r.min(c));
                    prop_assert!((a.cost - best).abs() <= 1e-9 * (1.0 + best.abs()), "{:?}: {} vs {}", m, a.cost, best);
                    check_duals(&a, &cost, r, c, maximize);
                }
            }
        }
    }

    #[test]
    fn threshold_matches_brute_force((r, c, cost) in matrix(), tau in -5.0f64..60.0) {
        let best = brute_force_threshold(&cost, r, c, tau);
        for m in METHODS {
            let a = solve_with_threshold(&cost, r, c, tau, &opts(m, false)).unwrap();
            check_consistent(&a, &cost, r, c);
            let k = a.row_to_col.iter().filter(|x| x.is_some()).count() as f64;
            let obj = a.cost - tau * k;
            prop_assert!((obj - best).abs() <= 1e-9 * (1.0 + best.abs()), "{:?}: {} vs {}", m, obj, best);
            for (i, j) in a.pairs() {
                prop_assert!(cost[i * c + j] <= tau);
            }
        }
    }
}
