//! Degenerate input gives clear errors, never panics or NaN.

use modal_core::{match_shapes, ErrorKind, MatchOptions, ModalError, Shape, Side, Topology};

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

fn err(a: &Shape, b: &Shape, o: &MatchOptions) -> ModalError {
    match match_shapes(a, b, o) {
        Err(e) => e,
        Ok(_) => panic!("expected an error"),
    }
}

/// The option an `OptionError` names, or a panic naming the error.
fn option_of(e: &ModalError) -> &'static str {
    match e {
        ModalError::Option(o) => o.option,
        other => panic!("expected an option error, got {other}"),
    }
}

#[test]
fn degenerate_inputs_are_rejected_with_reasons() {
    let good = shape(&square(20));
    let o = MatchOptions::default();
    let e = err(&shape(&[[0.0, 0.0], [1.0, 0.0]]), &good, &o);
    assert!(e.to_string().contains("at least 3"), "{e}");
    let too_few = ModalError::TooFewNodes { nodes: 2, min: 3 };
    assert_eq!(e, too_few.clone().of(Side::A));
    assert_eq!(e.kind(), ErrorKind::Shape);
    let mut dup = square(20);
    dup[5] = dup[4];
    let e = err(&shape(&dup), &good, &o);
    assert!(e.to_string().contains("coincide"), "{e}");
    assert_eq!(
        e,
        ModalError::CoincidentNodes {
            first: 4,
            second: 5
        }
        .of(Side::A)
    );
    let line: Vec<[f64; 2]> = (0..10).map(|i| [i as f64, 2.0 * i as f64]).collect();
    let e = err(&good, &shape(&line), &o);
    assert!(e.to_string().contains("collinear"), "{e}");
    assert_eq!(e, ModalError::Collinear.of(Side::B));
    let same = vec![[1.0, 1.0]; 5];
    let e = err(&shape(&same), &good, &o);
    assert_eq!(e.kind(), ErrorKind::Shape, "{e}");
    assert!(!e.to_string().is_empty());
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
    let e = err(&good, &three, &o);
    assert!(e.to_string().contains("dimension"), "{e}");
    assert_eq!(e, ModalError::DimensionMismatch { a: 2, b: 3 });
    assert!(matches!(
        Shape::from_points_2d(&[[0.0, f64::NAN]], Topology::None),
        Err(ModalError::NonFiniteCoordinate {
            node: 0,
            axis: 1,
            ..
        })
    ));
    for bad in [0.0, -0.1, 1.5, f64::NAN] {
        let o = MatchOptions {
            mode_fraction: bad,
            ..MatchOptions::default()
        };
        assert_eq!(option_of(&err(&good, &good, &o)), "modes");
    }
    for t in [-1.0, 1.5, f64::NAN] {
        let o = MatchOptions {
            threshold: Some(t),
            ..MatchOptions::default()
        };
        assert_eq!(option_of(&err(&good, &good, &o)), "threshold");
    }
    let o = MatchOptions {
        position_weight: 2.0,
        ..MatchOptions::default()
    };
    assert_eq!(option_of(&err(&good, &good, &o)), "position_weight");
    for t in [-0.1, f64::NAN, f64::INFINITY] {
        let o = MatchOptions {
            refit_tolerance: t,
            ..MatchOptions::default()
        };
        assert_eq!(option_of(&err(&good, &good, &o)), "refit_tolerance");
    }
    for p in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let o = MatchOptions {
            cost_power: p,
            ..MatchOptions::default()
        };
        let e = err(&good, &good, &o);
        assert_eq!(option_of(&e), "cost_power");
        assert!(e.to_string().starts_with("cost_power = "), "{e}");
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

#[test]
fn an_object_beyond_the_node_limit_is_refused_before_its_model_is_built() {
    // 20,000 nodes: a model of 1.6 × 10⁹ values a matrix. Refused at once, naming the option.
    let big = shape(&square(20_000));
    let small = shape(&square(40));
    let o = MatchOptions::default();
    let t = std::time::Instant::now();
    let e = err(&big, &small, &o);
    assert_eq!(
        e,
        ModalError::TooManyNodes {
            nodes: 20_000,
            max: modal_core::MAX_NODES
        }
        .of(Side::A)
    );
    assert!(e.to_string().contains("--max-nodes"), "{e}");
    assert!(t.elapsed() < std::time::Duration::from_secs(10));
    // Raised, the limit lets a larger object through (here 50 nodes under a limit of 60,
    // refused under 45).
    let a = shape(&square(50));
    let tight = MatchOptions {
        max_nodes: 45,
        ..MatchOptions::default()
    };
    assert!(matches!(err(&a, &small, &tight), ModalError::Object { .. }));
    let roomy = MatchOptions {
        max_nodes: 60,
        ..MatchOptions::default()
    };
    assert!(match_shapes(&a, &small, &roomy).is_ok());
}

#[test]
fn coordinates_near_the_largest_finite_numbers_match_as_at_unit_scale() {
    // A contour and its turned, stretched copy, matched at unit scale and at 1e300 (every
    // coordinate finite): the same matches, not "all nodes coincide".
    let a = square(40);
    let b: Vec<[f64; 2]> = square(40)
        .iter()
        .map(|p| [1.1 * p[0] - 0.2 * p[1] + 0.3, 0.2 * p[0] + 1.1 * p[1]])
        .collect();
    let o = MatchOptions::default();
    let unit = match_shapes(&shape(&a), &shape(&b), &o).unwrap();
    for scale in [1e300, 1e-300] {
        let big = |p: &[[f64; 2]]| -> Vec<[f64; 2]> {
            p.iter().map(|q| [q[0] * scale, q[1] * scale]).collect()
        };
        let scaled = match_shapes(&shape(&big(&a)), &shape(&big(&b)), &o)
            .unwrap_or_else(|e| panic!("scale {scale}: {e}"));
        let pairs = |r: &modal_core::MatchResult| -> Vec<(usize, usize)> {
            r.pairs.iter().map(|p| (p.a, p.b)).collect()
        };
        assert_eq!(pairs(&scaled), pairs(&unit), "scale {scale}");
    }
}
