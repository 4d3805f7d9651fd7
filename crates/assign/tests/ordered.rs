//! The order-preserving solver and the crossing count: known answers, bad input, and cross-checks
//! against brute force (every order-preserving map of small cases) and against the unconstrained
//! solvers where their optimum happens to keep the order.

use assign::{cyclic_crossings, solve, solve_with_threshold, AssignError, Method, Options};
use proptest::prelude::*;

const INF: f64 = f64::INFINITY;

fn ordered(maximize: bool) -> Options {
    Options {
        method: Method::Ordered,
        maximize,
    }
}

/// Whether the matches, read in row order, go at most once round the columns: the independent
/// definition of order preservation (at most one cyclic descent of the partners).
fn keeps_cyclic_order(pairs: &[(usize, usize)]) -> bool {
    let mut p = pairs.to_vec();
    p.sort();
    let descents = (0..p.len())
        .filter(|&t| p[(t + 1) % p.len()].1 < p[t].1)
        .count();
    descents <= 1
}

/// Every injective map of the `n` rows into the `m` columns (`n ≤ m`), as partner lists.
fn injective_maps(n: usize, m: usize) -> Vec<Vec<usize>> {
    fn rec(n: usize, m: usize, cur: &mut Vec<usize>, out: &mut Vec<Vec<usize>>) {
        if cur.len() == n {
            out.push(cur.clone());
            return;
        }
        for j in 0..m {
            if !cur.contains(&j) {
                cur.push(j);
                rec(n, m, cur, out);
                cur.pop();
            }
        }
    }
    let mut out = Vec::new();
    rec(n, m, &mut Vec::new(), &mut out);
    out
}

/// Cost of the partner list `f` in the `rows × cols` matrix, read transposed when `t`.
fn map_cost(c: &[f64], cols: usize, f: &[usize], t: bool) -> f64 {
    f.iter()
        .enumerate()
        .map(|(i, &j)| if t { c[j * cols + i] } else { c[i * cols + j] })
        .sum()
}

/// The best total of every order-preserving saturating map, `None` when each uses a forbidden
/// entry; by enumeration of all injective maps of the smaller side.
fn brute_force(c: &[f64], rows: usize, cols: usize, maximize: bool) -> Option<f64> {
    let t = rows > cols;
    let (n, m) = if t { (cols, rows) } else { (rows, cols) };
    let s = if maximize { -1.0 } else { 1.0 };
    injective_maps(n, m)
        .into_iter()
        .filter(|f| keeps_cyclic_order(&f.iter().copied().enumerate().collect::<Vec<_>>()))
        .map(|f| map_cost(c, cols, &f, t))
        .filter(|x| (s * x).is_finite())
        .min_by(|a, b| (s * a).total_cmp(&(s * b)))
}

/// The best `Σ (c − τ)` over the order-preserving partial one-to-one maps (the threshold
/// problem's objective up to its constant), by enumeration.
fn brute_force_threshold(c: &[f64], rows: usize, cols: usize, tau: f64) -> f64 {
    fn rec(c: &[f64], rows: usize, cols: usize, cur: &mut Vec<(usize, usize)>, tau: f64) -> f64 {
        let here = cur.iter().map(|&(a, b)| c[a * cols + b] - tau).sum::<f64>();
        let mut best = if keeps_cyclic_order(cur) { here } else { INF };
        for a in cur.last().map_or(0, |p| p.0 + 1)..rows {
            for b in 0..cols {
                if !cur.iter().any(|p| p.1 == b) && c[a * cols + b] < INF {
                    cur.push((a, b));
                    best = best.min(rec(c, rows, cols, cur, tau));
                    cur.pop();
                }
            }
        }
        best
    }
    rec(c, rows, cols, &mut Vec::new(), tau)
}

/// The crossing count by its definition: the fewest inverted pairs over every start of both
/// numberings.
fn brute_force_crossings(pairs: &[(usize, usize)], n: usize, m: usize) -> usize {
    let mut best = usize::MAX;
    for s in 0..n {
        for t in 0..m {
            let r: Vec<(usize, usize)> = pairs
                .iter()
                .map(|&(i, j)| ((i + n - s) % n, (j + m - t) % m))
                .collect();
            let mut inv = 0;
            for (p, &a) in r.iter().enumerate() {
                for &b in &r[p + 1..] {
                    if (a.0 < b.0 && a.1 > b.1) || (a.0 > b.0 && a.1 < b.1) {
                        inv += 1;
                    }
                }
            }
            best = best.min(inv);
        }
    }
    if pairs.is_empty() {
        0
    } else {
        best
    }
}

#[test]
fn names_parse_and_print() {
    assert_eq!("ordered".parse::<Method>(), Ok(Method::Ordered));
    assert_eq!(Method::Ordered.to_string(), "ordered");
    assert!(Method::NAMES.contains(&"ordered"));
}

#[test]
fn a_match_may_wrap_past_the_last_column() {
    // The cheap entries are (0,2), (1,3), (2,0): partners 2, 3, 0 go once round the columns.
    let c = [
        9.0, 9.0, 0.0, 9.0, //
        9.0, 9.0, 9.0, 0.0, //
        0.0, 9.0, 9.0, 9.0,
    ];
    let a = solve(&c, 3, 4, &ordered(false)).unwrap();
    assert_eq!(a.row_to_col, vec![Some(2), Some(3), Some(0)]);
    assert_eq!(a.cost, 0.0);
    assert_eq!(a.duals, None);
}

#[test]
fn a_reversed_sequence_is_not_matched_in_order() {
    // The unconstrained optimum (cost 0) reverses the order; the ordered solver must pay for a
    // rotation instead (any rotation of a 3-cycle costs 1 + 1 + 0 here at best).
    let c = [
        0.0, 1.0, 1.0, //
        1.0, 1.0, 0.0, //
        1.0, 0.0, 1.0,
    ];
    let free = solve(&c, 3, 3, &Options::default()).unwrap();
    assert_eq!(free.cost, 0.0);
    assert_eq!(cyclic_crossings(&free.pairs()), 1);
    let a = solve(&c, 3, 3, &ordered(false)).unwrap();
    assert_eq!(a.cost, 1.0 + 1.0 + 0.0);
    assert_eq!(cyclic_crossings(&a.pairs()), 0);
}

#[test]
fn bad_input_is_an_error() {
    let shape = solve(&[1.0; 5], 2, 3, &ordered(false));
    assert!(matches!(shape, Err(AssignError::ShapeMismatch { .. })));
    let nan = [0.0, 1.0, f64::NAN, 2.0];
    assert_eq!(
        solve(&nan, 2, 2, &ordered(false)),
        Err(AssignError::InvalidEntry { row: 1, col: 0 })
    );
    let favouring = [0.0, f64::NEG_INFINITY, 1.0, 2.0];
    assert_eq!(
        solve(&favouring, 2, 2, &ordered(false)),
        Err(AssignError::InvalidEntry { row: 0, col: 1 })
    );
    assert_eq!(
        solve(&[1.0, INF, INF, 1.0], 2, 2, &ordered(true)),
        Err(AssignError::InvalidEntry { row: 0, col: 1 })
    );
    // Allowed pairs (0,0) and (1,2), and (1,1), (2,0) … none completes an ordered map of 3 rows.
    let c = [
        0.0, INF, INF, //
        INF, INF, 0.0, //
        INF, 0.0, INF,
    ];
    assert_eq!(
        solve(&c, 3, 3, &ordered(false)),
        Err(AssignError::Infeasible)
    );
    assert!(solve(&c, 3, 3, &Options::default()).is_ok());
    let tau = solve_with_threshold(&[1.0], 1, 1, f64::NAN, &ordered(false));
    assert!(matches!(tau, Err(AssignError::InvalidThreshold { .. })));
}

#[test]
fn empty_and_single() {
    for (r, c) in [(0, 0), (0, 3), (3, 0)] {
        let a = solve(&[], r, c, &ordered(false)).unwrap();
        assert_eq!(a.cost, 0.0);
        assert!(a.pairs().is_empty());
        let t = solve_with_threshold(&[], r, c, 1.0, &ordered(false)).unwrap();
        assert!(t.pairs().is_empty());
    }
    let a = solve(&[3.0, 1.0, 2.0], 3, 1, &ordered(false)).unwrap();
    assert_eq!(a.pairs(), vec![(1, 0)]);
}

#[test]
fn crossings_known() {
    assert_eq!(cyclic_crossings(&[]), 0);
    assert_eq!(cyclic_crossings(&[(4, 1)]), 0);
    // A reversed contour: every pair of 4 matches crosses but the best start leaves 3 crossed.
    let rev: Vec<(usize, usize)> = (0..4).map(|i| (i, 3 - i)).collect();
    assert_eq!(cyclic_crossings(&rev), brute_force_crossings(&rev, 4, 4));
    assert!(cyclic_crossings(&rev) > 0);
    // Many-to-one matches in order (the excess step's) do not cross.
    assert_eq!(
        cyclic_crossings(&[(0, 5), (0, 6), (1, 7), (2, 0), (2, 1)]),
        0
    );
}

#[test]
fn larger_ordered_matches_jv_on_a_smooth_deformation() {
    // Two samplings of one closed curve, B's numbering started elsewhere: the cost (squared
    // distance of the parameters) has an order-keeping optimum, which JV finds as well.
    for (n, m, shift) in [(40, 40, 7), (40, 47, 30), (53, 60, 0), (60, 53, 11)] {
        let pos = |k: usize, len: usize| k as f64 / len as f64;
        let c: Vec<f64> = (0..n)
            .flat_map(|i| {
                (0..m).map(move |j| {
                    let d = (pos(i, n) - pos((j + shift) % m, m)).rem_euclid(1.0);
                    d.min(1.0 - d).powi(2)
                })
            })
            .collect();
        let jv = solve(&c, n, m, &Options::default()).unwrap();
        let a = solve(&c, n, m, &ordered(false)).unwrap();
        assert_eq!(cyclic_crossings(&jv.pairs()), 0);
        assert!(
            (a.cost - jv.cost).abs() <= 1e-12,
            "{} vs {}",
            a.cost,
            jv.cost
        );
        assert_eq!(cyclic_crossings(&a.pairs()), 0);
    }
}

fn matrix() -> impl Strategy<Value = (usize, usize, Vec<f64>)> {
    (0usize..=7, 0usize..=7, 0u8..4).prop_flat_map(|(r, c, kind)| {
        let entry = match kind {
            0 => (-50i32..50).prop_map(f64::from).boxed(),
            1 => (0i32..3).prop_map(f64::from).boxed(), // heavy ties
            2 => prop_oneof![4 => -1e3f64..1e3, 1 => Just(INF)].boxed(),
            _ => prop_oneof![3 => (0i32..5).prop_map(f64::from), 2 => Just(INF)].boxed(),
        };
        (Just(r), Just(c), proptest::collection::vec(entry, r * c))
    })
}

fn pair_list() -> impl Strategy<Value = (usize, usize, Vec<(usize, usize)>)> {
    (1usize..=7, 1usize..=7).prop_flat_map(|(n, m)| {
        let pairs = proptest::collection::vec((0..n, 0..m), 0..=9);
        (Just(n), Just(m), pairs)
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    #[test]
    fn ordered_matches_brute_force((r, c, cost) in matrix(), maximize in any::<bool>()) {
        let cost: Vec<f64> = if maximize {
            cost.iter().map(|&x| if x == INF { f64::NEG_INFINITY } else { x }).collect()
        } else {
            cost
        };
        let got = solve(&cost, r, c, &ordered(maximize));
        match brute_force(&cost, r, c, maximize) {
            None if r.min(c) > 0 => prop_assert_eq!(got, Err(AssignError::Infeasible)),
            None => prop_assert!(got.unwrap().pairs().is_empty()),
            Some(best) => {
                let a = got.unwrap();
                let pairs = a.pairs();
                prop_assert_eq!(pairs.len(), r.min(c));
                prop_assert!(keeps_cyclic_order(&pairs));
                prop_assert_eq!(cyclic_crossings(&pairs), 0);
                let total: f64 = pairs.iter().map(|&(i, j)| cost[i * c + j]).sum();
                prop_assert_eq!(total, a.cost);
                prop_assert!((a.cost - best).abs() <= 1e-9 * (1.0 + best.abs()), "{} vs {}", a.cost, best);
                // Never better than the unconstrained optimum, and equal to it when that keeps
                // the order.
                let jv = solve(&cost, r, c, &Options { method: Method::JonkerVolgenant, maximize }).unwrap();
                let s = if maximize { -1.0 } else { 1.0 };
                prop_assert!(s * a.cost >= s * jv.cost - 1e-9 * (1.0 + jv.cost.abs()));
                if cyclic_crossings(&jv.pairs()) == 0 {
                    prop_assert!((a.cost - jv.cost).abs() <= 1e-9 * (1.0 + jv.cost.abs()));
                }
            }
        }
    }

    #[test]
    fn ordered_threshold_matches_brute_force((r, c, cost) in matrix(), tau in -5.0f64..60.0) {
        prop_assume!(r <= 5 && c <= 5);
        let best = brute_force_threshold(&cost, r, c, tau);
        let a = solve_with_threshold(&cost, r, c, tau, &ordered(false)).unwrap();
        let pairs = a.pairs();
        prop_assert!(keeps_cyclic_order(&pairs));
        let obj = a.cost - tau * pairs.len() as f64;
        prop_assert!((obj - best).abs() <= 1e-9 * (1.0 + best.abs()), "{} vs {}", obj, best);
        for (i, j) in pairs {
            prop_assert!(cost[i * c + j] <= tau);
        }
    }

    #[test]
    fn crossings_match_brute_force((n, m, pairs) in pair_list()) {
        prop_assert_eq!(cyclic_crossings(&pairs), brute_force_crossings(&pairs, n, m));
        // Zero exactly on order-keeping one-to-one matches.
        let one_to_one = {
            let (mut a, mut b): (Vec<_>, Vec<_>) = pairs.iter().copied().unzip();
            a.sort();
            a.dedup();
            b.sort();
            b.dedup();
            a.len() == pairs.len() && b.len() == pairs.len()
        };
        if one_to_one {
            prop_assert_eq!(cyclic_crossings(&pairs) == 0, keeps_cyclic_order(&pairs));
        }
    }
}
