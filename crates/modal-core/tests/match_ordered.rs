//! The order-preserving solver (`solver = ordered`) on closed contours: no crossed matches, at
//! least JV's accuracy on the ground-truth contours, the same matches whichever way a contour is
//! numbered, and a clear error on anything but two ordered closed contours. The crossing count of
//! every result.

mod match_common;

use match_common::*;
use modal_core::{match_shapes, MatchOptions, ModalError, Shape, Topology, Unsupported};

fn with(method: assign::Method) -> MatchOptions {
    MatchOptions {
        method,
        ..MatchOptions::default()
    }
}

fn contour(p: &[[f64; 2]]) -> Shape {
    Shape::from_points_2d(p, Topology::ClosedContour).unwrap()
}

#[test]
fn ordered_matches_never_cross_and_are_as_accurate_as_jv() {
    let outlines = outlines();
    for sev in [Severity::Mild, Severity::Moderate, Severity::Severe] {
        let (mut acc_jv, mut acc_ordered, mut crossed_jv) = (0.0, 0.0, 0);
        const SEEDS: u64 = 24;
        for seed in 0..SEEDS {
            let (_, o) = &outlines[seed as usize % outlines.len()];
            let case = contour_case(o, sev, seed);
            let (a, b) = (contour(&case.a), contour(&case.b));
            let jv = match_shapes(&a, &b, &with(assign::Method::JonkerVolgenant)).unwrap();
            let ordered = match_shapes(&a, &b, &with(assign::Method::Ordered)).unwrap();
            assert_eq!(ordered.crossings, Some(0), "{sev:?} seed {seed}");
            // Every node of both contours has a partner: the search's, or the excess step's for
            // a node the search left out rather than force a run of nodes a spacing off.
            let (na, nb) = (case.a.len(), case.b.len());
            assert!(ordered.one_to_one_count() <= na.min(nb));
            let covered = |side: fn(&modal_core::MatchPair) -> usize, n: usize| {
                let mut seen = vec![false; n];
                ordered.pairs.iter().for_each(|p| seen[side(p)] = true);
                seen.iter().all(|&s| s)
            };
            assert!(
                covered(|p| p.a, na) && covered(|p| p.b, nb),
                "{sev:?} seed {seed}"
            );
            crossed_jv += jv.crossings.unwrap();
            acc_jv += accuracy(&jv, &case.b, &case.truth, case.spacing_b);
            acc_ordered += accuracy(&ordered, &case.b, &case.truth, case.spacing_b);
        }
        let k = SEEDS as f64;
        let (acc_jv, acc_ordered) = (acc_jv / k, acc_ordered / k);
        eprintln!("{sev:?}: JV {acc_jv:.4} ({crossed_jv} crossed), ordered {acc_ordered:.4}");
        assert!(
            acc_ordered >= acc_jv - 1e-12,
            "{sev:?}: {acc_ordered} < {acc_jv}"
        );
    }
}

#[test]
fn a_contour_numbered_clockwise_gets_the_same_matches() {
    // modal-core orients both contours counter-clockwise before the search, so the numbering's
    // direction (and start) cannot change which nodes are matched.
    let outlines = outlines();
    let case = contour_case(&outlines[1].1, Severity::Moderate, 7);
    let reversed: Vec<[f64; 2]> = case.b.iter().rev().copied().collect();
    let m = case.b.len();
    let opts = with(assign::Method::Ordered);
    let forward = match_shapes(&contour(&case.a), &contour(&case.b), &opts).unwrap();
    let backward = match_shapes(&contour(&case.a), &contour(&reversed), &opts).unwrap();
    let pairs = |r: &modal_core::MatchResult, flip: bool| {
        let mut v: Vec<(usize, usize)> = r
            .pairs
            .iter()
            .map(|p| (p.a, if flip { m - 1 - p.b } else { p.b }))
            .collect();
        v.sort();
        v
    };
    assert_eq!(pairs(&forward, false), pairs(&backward, true));
    assert_eq!(backward.crossings, Some(0));
    // The count reads both contours counter-clockwise: a reversed numbering is not a crossing.
    let jv = with(assign::Method::JonkerVolgenant);
    let jv_forward = match_shapes(&contour(&case.a), &contour(&case.b), &jv).unwrap();
    let jv_backward = match_shapes(&contour(&case.a), &contour(&reversed), &jv).unwrap();
    assert_eq!(jv_forward.crossings, jv_backward.crossings);
}

#[test]
fn the_ordered_solver_needs_two_ordered_closed_contours() {
    let outlines = outlines();
    let case = contour_case(&outlines[0].1, Severity::Mild, 3);
    let opts = with(assign::Method::Ordered);
    let points = |p: &[[f64; 2]]| Shape::from_points_2d(p, Topology::None).unwrap();
    let needs = |e: ModalError| {
        assert!(
            matches!(
                e,
                ModalError::Unsupported(Unsupported::OrderedSolverNeedsContours)
            ),
            "{e:?}"
        );
        assert!(e.to_string().contains("closed contours"), "{e}");
    };
    needs(match_shapes(&points(&case.a), &points(&case.b), &opts).unwrap_err());
    needs(match_shapes(&contour(&case.a), &points(&case.b), &opts).unwrap_err());
    let unordered = MatchOptions {
        ordered: Some(false),
        ..opts.clone()
    };
    needs(match_shapes(&contour(&case.a), &contour(&case.b), &unordered).unwrap_err());
}

#[test]
fn crossings_are_counted_on_contours_only() {
    let outlines = outlines();
    let case = contour_case(&outlines[0].1, Severity::Severe, 11);
    let points = |p: &[[f64; 2]]| Shape::from_points_2d(p, Topology::None).unwrap();
    let opts = MatchOptions::default();
    let sets = match_shapes(&points(&case.a), &points(&case.b), &opts).unwrap();
    assert_eq!(sets.crossings, None);
    let contours = match_shapes(&contour(&case.a), &contour(&case.b), &opts).unwrap();
    // The count is that of the numbering read counter-clockwise.
    let area = |p: &[[f64; 2]]| {
        (0..p.len())
            .map(|i| {
                let (u, v) = (p[i], p[(i + 1) % p.len()]);
                u[0] * v[1] - v[0] * u[1]
            })
            .sum::<f64>()
    };
    let along = |p: &[[f64; 2]], i: usize| if area(p) >= 0.0 { i } else { p.len() - 1 - i };
    let pairs: Vec<(usize, usize)> = contours
        .pairs
        .iter()
        .map(|p| (along(&case.a, p.a), along(&case.b, p.b)))
        .collect();
    assert_eq!(contours.crossings, Some(assign::cyclic_crossings(&pairs)));
}

#[test]
fn where_jv_crosses_the_ordered_solver_does_not_and_is_as_accurate() {
    // The paper's literal setting on severe warps: JV's matches cross (746 crossed pairs
    // measured over these 40 cases, accuracy 0.552; ordered 0.557).
    let outlines = outlines();
    let (mut crossed_jv, mut acc_jv, mut acc_ordered) = (0, 0.0, 0.0);
    for seed in 0..40u64 {
        let (_, o) = &outlines[seed as usize % outlines.len()];
        let case = contour_case(o, Severity::Severe, seed);
        let (a, b) = (contour(&case.a), contour(&case.b));
        let run = |method| {
            let opts = MatchOptions {
                method,
                ..MatchOptions::paper()
            };
            match_shapes(&a, &b, &opts).unwrap()
        };
        let (jv, ordered) = (
            run(assign::Method::JonkerVolgenant),
            run(assign::Method::Ordered),
        );
        assert_eq!(ordered.crossings, Some(0), "seed {seed}");
        crossed_jv += jv.crossings.unwrap();
        acc_jv += accuracy(&jv, &case.b, &case.truth, case.spacing_b);
        acc_ordered += accuracy(&ordered, &case.b, &case.truth, case.spacing_b);
    }
    assert!(crossed_jv > 0);
    assert!(acc_ordered >= acc_jv, "{acc_ordered} < {acc_jv}");
}
