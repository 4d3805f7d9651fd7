//! Degenerate input gives clear errors, never panics or NaN.

use modal_core::{match_shapes, MatchOptions, ModalError, Shape, Topology};

fn square(n: usize) -> Vec<[f64; 2]> {
    (0..n)
        .map(|i| {
            let t = i as f64 / n as f64 * std::f64::consts::TAU;
            [t.cos() * (1.0 + 0.2 * (3.0 * t).sin()), 0.7 * t.sin()]
        })
        .collect()
}

fn shape(p: &[[f64; 2]]) -> Shape {
    Shape::from_points_2d(p, Topology::ClosedContour).unwrap()
}

fn err_text(a: &Shape, b: &Shape, o: &MatchOptions) -> String {
    match match_shapes(a, b, o) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("expected an error"),
    }
}

#[test]
fn degenerate_inputs_are_rejected_with_reasons() {
    let good = shape(&square(20));
    let o = MatchOptions::default();
    assert!(err_text(&shape(&[[0.0, 0.0], [1.0, 0.0]]), &good, &o).contains("at least 3"));
    let mut dup = square(20);
    dup[5] = dup[4];
    assert!(err_text(&shape(&dup), &good, &o).contains("coincide"));
    let line: Vec<[f64; 2]> = (0..10).map(|i| [i as f64, 2.0 * i as f64]).collect();
    assert!(err_text(&good, &shape(&line), &o).contains("collinear"));
    let same = vec![[1.0, 1.0]; 5];
    assert!(!err_text(&shape(&same), &good, &o).is_empty());
    let three = Shape::from_points_3d(
        &[
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ],
        Topology::None,
    )
    .unwrap();
    assert!(err_text(&good, &three, &o).contains("dimension"));
    assert!(matches!(
        Shape::from_points_2d(&[[0.0, f64::NAN]], Topology::None),
        Err(ModalError::InvalidShape(_))
    ));
    for bad in [0.0, -0.1, 1.5, f64::NAN] {
        let o = MatchOptions {
            mode_fraction: bad,
            ..MatchOptions::default()
        };
        assert!(err_text(&good, &good, &o).contains("mode fraction"));
    }
    let o = MatchOptions {
        threshold: Some(-1.0),
        ..MatchOptions::default()
    };
    assert!(err_text(&good, &good, &o).contains("threshold"));
    let o = MatchOptions {
        position_weight: 2.0,
        ..MatchOptions::default()
    };
    assert!(err_text(&good, &good, &o).contains("position weight"));
    for t in [-0.1, f64::NAN, f64::INFINITY] {
        let o = MatchOptions {
            refit_tolerance: t,
            ..MatchOptions::default()
        };
        assert!(err_text(&good, &good, &o).contains("refit tolerance"));
    }
    for p in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let o = MatchOptions {
            cost_power: p,
            ..MatchOptions::default()
        };
        assert!(err_text(&good, &good, &o).contains("cost power"));
    }
}

#[test]
fn identical_objects_match_themselves() {
    let a = shape(&square(40));
    for o in [MatchOptions::default(), MatchOptions::paper()] {
        let r = match_shapes(&a, &a, &o).unwrap();
        assert_eq!(r.pairs.len(), 40);
        assert!(r.pairs.iter().all(|p| p.a == p.b), "{o:?}");
        assert!(r.affinity.as_slice().iter().all(|v| v.is_finite()));
        // Reversed node order (clockwise) is handled by the internal re-orientation.
        let rev: Vec<[f64; 2]> = square(40).into_iter().rev().collect();
        let r = match_shapes(&a, &shape(&rev), &o).unwrap();
        assert!(r.pairs.iter().all(|p| p.b == 39 - p.a));
    }
}
