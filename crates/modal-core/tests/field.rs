//! The correspondence field: exact at the matches, exact on affine maps for every λ, close to a
//! known bend inside a foot outline fitted to its outline nodes only, a way back by its inverse,
//! and a clear error for every degenerate input.

use modal_core::{CorrespondenceField, ErrorKind, MatchPair, ModalError, Shape, Side, Topology};
use proptest::prelude::*;

fn shape(p: &[[f64; 2]]) -> Shape {
    Shape::from_points_2d(p, Topology::None).unwrap()
}

/// A foot-like outline in mm, 240 long and up to ~100 wide (wider at the forefoot, x > 0),
/// `n` nodes counter-clockwise, scaled by `s` about its centre (`s < 1`: inside it).
fn foot(n: usize, s: f64) -> Vec<[f64; 2]> {
    (0..n)
        .map(|i| {
            let t = i as f64 / n as f64 * std::f64::consts::TAU;
            [
                s * 120.0 * t.cos(),
                s * 45.0 * t.sin() * (1.0 + 0.15 * t.cos()),
            ]
        })
        .collect()
}

/// Points inside the foot outline: 9 scaled copies of it, from its centre to 0.9 of its size.
fn interior() -> Vec<[f64; 2]> {
    (0..9).flat_map(|k| foot(60, k as f64 / 10.0)).collect()
}

/// The bend of a foot rolling over a curved surface: the sole wrapped onto a circle of radius
/// `radius` mm (arc length along x kept, so its ends turn by ±120/radius rad), then moved by
/// (5, −3) mm.
fn bend(radius: f64) -> impl Fn([f64; 2]) -> [f64; 2] {
    move |p| {
        let theta = p[0] / radius;
        [
            (radius - p[1]) * theta.sin() + 5.0,
            radius - (radius - p[1]) * theta.cos() - 3.0,
        ]
    }
}

/// A strong bend (±0.4 rad at the ends), more than a whole stance's.
const STRONG: f64 = 300.0;
/// A bend of ±0.04 rad, as between two frames.
const MILD: f64 = 3000.0;

fn affine(p: [f64; 2]) -> [f64; 2] {
    [
        1.1 * p[0] + 0.2 * p[1] + 12.0,
        -0.15 * p[0] + 0.9 * p[1] - 7.0,
    ]
}

fn dist(p: [f64; 2], q: [f64; 2]) -> f64 {
    (p[0] - q[0]).hypot(p[1] - q[1])
}

/// The field fitted to `map` sampled at the foot's 150 outline nodes.
fn fitted(map: impl Fn([f64; 2]) -> [f64; 2], smoothing: f64) -> CorrespondenceField {
    let a = foot(150, 1.0);
    let b: Vec<[f64; 2]> = a.iter().map(|&p| map(p)).collect();
    CorrespondenceField::fit(
        &shape(&a),
        &shape(&b),
        &MatchPair::each_to_itself(150),
        smoothing,
    )
    .unwrap()
}

/// Largest and RMS distance between `got` and `want`.
fn errors(got: &[[f64; 2]], want: &[[f64; 2]]) -> (f64, f64) {
    let d: Vec<f64> = got.iter().zip(want).map(|(g, w)| dist(*g, *w)).collect();
    let rms = (d.iter().map(|e| e * e).sum::<f64>() / d.len() as f64).sqrt();
    (d.iter().fold(0.0, |m: f64, &e| m.max(e)), rms)
}

#[test]
fn interpolates_the_matches_exactly_without_smoothing() {
    let field = fitted(bend(STRONG), 0.0);
    let r = field.residuals();
    assert_eq!(r.len(), 150);
    // Coordinates of ~100 mm: rounding is ~1e-14 of them.
    assert!(
        r.iter().all(|&e| e < 1e-9),
        "largest residual {:e}",
        r.iter().fold(0.0f64, |m, &e| m.max(e))
    );
    assert_eq!(field.pairs()[7], [7, 7]);
}

#[test]
fn smoothing_trades_residuals_for_smoothness() {
    // The bend is not affine: λ > 0 leaves residuals, more the larger λ.
    let largest = |l: f64| {
        fitted(bend(STRONG), l)
            .residuals()
            .into_iter()
            .fold(0.0, f64::max)
    };
    let (small, large) = (largest(1e2), largest(1e5));
    assert!(small > 1e-6 && small < large, "{small:e} {large:e}");
}

#[test]
fn reproduces_any_affine_map_exactly_for_every_smoothing() {
    let inside = interior();
    // Outside the outline too: an affine field has no bend to extrapolate.
    let outside = foot(40, 2.0);
    for smoothing in [0.0, 0.5, 10.0, 1e3, 1e6] {
        let field = fitted(affine, smoothing);
        for pts in [&inside, &outside] {
            let want: Vec<[f64; 2]> = pts.iter().map(|&p| affine(p)).collect();
            let (max, _) = errors(&field.apply(pts), &want);
            assert!(max < 1e-9, "λ = {smoothing}: {max:e}");
        }
        assert!(
            field.residuals().iter().all(|&r| r < 1e-9),
            "λ = {smoothing}"
        );
    }
}

#[test]
fn carries_interior_points_through_a_bend_fitted_to_the_outline() {
    // Only the outline nodes are matched (as with the contour model); the field decides the
    // inside, and the error there comes from that, not from the node spacing (~3.7 mm; 50 or
    // 400 nodes give the same figures): the thin-plate spline's inside is the least bent
    // continuation of the outline's motion, the arc's is not. Measured: strong bend, max 1.009
    // mm, RMS 0.722 mm where the affine part alone is off by up to 12.6 mm; mild bend, max 0.103
    // mm, RMS 0.073 mm (affine alone 1.21 mm). scipy's RBFInterpolator gives the same figures.
    for (radius, max_tol, rms_tol) in [(STRONG, 1.1, 0.75), (MILD, 0.11, 0.08)] {
        let inside = interior();
        let want: Vec<[f64; 2]> = inside.iter().map(|&p| bend(radius)(p)).collect();
        let (max, rms) = errors(&fitted(bend(radius), 0.0).apply(&inside), &want);
        // The best affine map (the spline's affine part alone, λ → ∞) for comparison.
        let (affine_max, _) = errors(&fitted(bend(radius), 1e12).apply(&inside), &want);
        eprintln!("bend radius {radius}: field max {max:.4} mm, RMS {rms:.4} mm; affine {affine_max:.3} mm");
        assert!(
            max < max_tol && rms < rms_tol,
            "radius {radius}: max {max} RMS {rms}"
        );
        assert!(
            affine_max > 10.0 * max,
            "radius {radius}: affine {affine_max}, field {max}"
        );
    }
}

#[test]
fn the_inverse_brings_points_back() {
    // Round trip inside the outline, measured: strong bend max 0.750 mm, RMS 0.327 mm; mild bend
    // (one frame to the next) max 0.0075 mm, RMS 0.0032 mm: the errors of the two fits cancel to
    // first order, so what is left grows with the bend squared.
    for (radius, max_tol, rms_tol) in [(STRONG, 0.8, 0.35), (MILD, 0.01, 0.004)] {
        let field = fitted(bend(radius), 0.0);
        let back = field.inverse().unwrap();
        let inside = interior();
        let (max, rms) = errors(&back.apply(&field.apply(&inside)), &inside);
        eprintln!("bend radius {radius}: round trip max {max:.5} mm, RMS {rms:.5} mm");
        assert!(
            max < max_tol && rms < rms_tol,
            "radius {radius}: max {max} RMS {rms}"
        );
        // At the matched nodes the round trip is exact to rounding.
        assert!(back.residuals().iter().all(|&r| r < 1e-9));
        let nodes = foot(150, 1.0);
        assert!(errors(&back.apply(&field.apply(&nodes)), &nodes).0 < 1e-9);
        // The inverse of the inverse is the field again, bit for bit.
        assert_eq!(back.inverse().unwrap(), field);
    }
    let back = fitted(bend(STRONG), 2.0).inverse().unwrap();
    assert_eq!((back.pairs()[3], back.smoothing()), ([3, 3], 2.0));
}

#[test]
fn excess_pairs_are_left_out() {
    let a = foot(40, 1.0);
    let b: Vec<[f64; 2]> = a.iter().map(|&p| bend(STRONG)(p)).collect();
    let mut with_excess = MatchPair::each_to_itself(40);
    // An excess pair sending node 0 somewhere else entirely: ignored.
    with_excess.push(MatchPair {
        a: 0,
        b: 20,
        cost: 0.5,
        excess: true,
    });
    let (sa, sb) = (shape(&a), shape(&b));
    let field = CorrespondenceField::fit(&sa, &sb, &with_excess, 0.0).unwrap();
    assert_eq!(
        field,
        CorrespondenceField::fit(&sa, &sb, &MatchPair::each_to_itself(40), 0.0).unwrap()
    );
    assert_eq!(field.pairs().len(), 40);
}

#[test]
fn stored_parts_give_the_same_field() {
    let field = fitted(bend(STRONG), 3.0);
    let again = CorrespondenceField::from_parts(field.parts().clone()).unwrap();
    assert_eq!(again, field);
    let inside = interior();
    assert_eq!(again.apply(&inside), field.apply(&inside));
    let mut bad = field.parts().clone();
    bad.weights.pop();
    let e = CorrespondenceField::from_parts(bad).unwrap_err();
    assert!(
        matches!(
            e,
            ModalError::SizeMismatch {
                what: "field weights",
                expected: 150,
                found: 149
            }
        ),
        "{e}"
    );
    let mut bad = field.parts().clone();
    bad.affine[1][2] = f64::NAN;
    assert!(matches!(
        CorrespondenceField::from_parts(bad),
        Err(ModalError::NonFiniteResult { .. })
    ));
    let mut bad = field.parts().clone();
    bad.radius = 0.0;
    assert!(CorrespondenceField::from_parts(bad).is_err());
}

#[test]
fn a_point_that_is_not_finite_maps_to_nan_without_panicking() {
    let out = fitted(bend(STRONG), 0.0).apply(&[[f64::NAN, 0.0], [0.0, f64::INFINITY], [1.0, 2.0]]);
    assert!(out[0].iter().all(|v| v.is_nan()));
    assert!(out[1].iter().any(|v| !v.is_finite()));
    assert!(out[2].iter().all(|v| v.is_finite()));
    assert!(fitted(bend(STRONG), 0.0).apply(&[]).is_empty());
}

fn fit_err(a: &[[f64; 2]], b: &[[f64; 2]], p: &[MatchPair], smoothing: f64) -> ModalError {
    CorrespondenceField::fit(&shape(a), &shape(b), p, smoothing).unwrap_err()
}

#[test]
fn degenerate_inputs_are_rejected_with_reasons() {
    let a = foot(20, 1.0);
    let b: Vec<[f64; 2]> = a.iter().map(|&p| bend(STRONG)(p)).collect();
    // Too few matches, excess pairs not counted.
    let mut two = MatchPair::each_to_itself(2);
    two.extend(
        MatchPair::each_to_itself(10)
            .into_iter()
            .skip(2)
            .map(|p| MatchPair { excess: true, ..p }),
    );
    let e = fit_err(&a, &b, &two, 0.0);
    assert_eq!(e, ModalError::TooFewMatches { matches: 2, min: 3 });
    assert_eq!(
        e.to_string(),
        "2 one-to-one matches; a correspondence field needs at least 3"
    );
    assert_eq!(e.kind(), ErrorKind::Shape);
    assert_eq!(
        fit_err(&a, &b, &[], 0.0),
        ModalError::TooFewMatches { matches: 0, min: 3 }
    );
    // Collinear matched nodes, in A then in B.
    let line: Vec<[f64; 2]> = (0..20).map(|i| [i as f64, 2.0 * i as f64 + 1.0]).collect();
    let e = fit_err(&line, &b, &MatchPair::each_to_itself(20), 0.0);
    assert_eq!(e, ModalError::CollinearMatches { side: Side::A });
    assert!(
        e.to_string()
            .starts_with("object A: the matched nodes are collinear"),
        "{e}"
    );
    assert_eq!(
        fit_err(&a, &line, &MatchPair::each_to_itself(20), 1.0),
        ModalError::CollinearMatches { side: Side::B }
    );
    // A node in two matches (many-to-one), and two nodes at one place.
    let mut twice = MatchPair::each_to_itself(20);
    twice[5].b = 4;
    let e = fit_err(&a, &b, &twice, 0.0);
    assert_eq!(
        e,
        ModalError::CoincidentMatches {
            side: Side::B,
            first: 4,
            second: 4
        }
    );
    assert_eq!(
        e.to_string(),
        "object B: node 4 is in two matches; a field sends each point to one place"
    );
    let mut dup = a.clone();
    dup[9] = dup[3];
    let e = fit_err(&dup, &b, &MatchPair::each_to_itself(20), 0.0);
    assert_eq!(
        e,
        ModalError::CoincidentMatches {
            side: Side::A,
            first: 3,
            second: 9
        }
    );
    assert!(
        e.to_string().contains("matched nodes 3 and 9 coincide"),
        "{e}"
    );
    // All matched nodes at one place.
    let e = fit_err(&[[1.0, 1.0]; 20], &b, &MatchPair::each_to_itself(20), 0.0);
    assert!(
        matches!(e, ModalError::CoincidentMatches { side: Side::A, .. }),
        "{e}"
    );
    // A node that does not exist.
    let mut out = MatchPair::each_to_itself(20);
    out[6].a = 20;
    let e = fit_err(&a, &b, &out, 0.0);
    assert_eq!(
        e,
        ModalError::MatchOutOfRange {
            pair: 6,
            side: Side::A,
            node: 20,
            nodes: 20
        }
    );
    assert_eq!(
        e.to_string(),
        "match 6 names node 20 of object A, which has 20 nodes"
    );
    assert_eq!(e.kind(), ErrorKind::Input);
    // The smoothing weight.
    for bad in [-1.0, f64::NAN, f64::INFINITY] {
        match fit_err(&a, &b, &MatchPair::each_to_itself(20), bad) {
            ModalError::Option(o) => assert_eq!(o.option, "smoothing"),
            other => panic!("expected an option error, got {other}"),
        }
    }
    // 3-D objects.
    let lift = |p: &[[f64; 2]]| -> Shape {
        Shape::from_points_3d(
            &p.iter().map(|q| [q[0], q[1], 0.0]).collect::<Vec<_>>(),
            Topology::None,
        )
        .unwrap()
    };
    let e = CorrespondenceField::fit(&lift(&a), &lift(&b), &MatchPair::each_to_itself(20), 0.0)
        .unwrap_err();
    assert_eq!(e, ModalError::FieldDimension { dim: 3 });
    assert!(
        e.to_string().contains("maps the plane: got 3-D objects"),
        "{e}"
    );
}

/// Jittered grids: `rows × cols` nodes one apart, each moved by up to 0.25, so nodes are at least
/// 0.5 apart and span an area; targets moved from them by up to 0.2 (still distinct).
fn grid_and_targets() -> impl Strategy<Value = (Vec<[f64; 2]>, Vec<[f64; 2]>)> {
    (2usize..7, 2usize..7)
        .prop_filter("at least 3 nodes", |(r, c)| r * c >= 3)
        .prop_flat_map(|(rows, cols)| {
            let n = rows * cols;
            let jitter = prop::collection::vec((-0.25..0.25f64, -0.25..0.25f64), n);
            let moves = prop::collection::vec((-0.2..0.2f64, -0.2..0.2f64), n);
            (jitter, moves).prop_map(move |(jitter, moves)| {
                let a: Vec<[f64; 2]> = (0..n)
                    .map(|k| {
                        [
                            (k % cols) as f64 + jitter[k].0,
                            (k / cols) as f64 + jitter[k].1,
                        ]
                    })
                    .collect();
                let b = a
                    .iter()
                    .zip(&moves)
                    .map(|(p, m)| [p[0] + m.0, p[1] + m.1])
                    .collect();
                (a, b)
            })
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn interpolates_and_reproduces_affine_maps((a, b) in grid_and_targets(),
                                               m in prop::array::uniform4(-1.0..1.0f64),
                                               t in prop::array::uniform2(-50.0..50.0f64),
                                               smoothing in prop_oneof![Just(0.0), 0.0..100.0f64]) {
        let n = a.len();
        let field = CorrespondenceField::fit(&shape(&a), &shape(&b), &MatchPair::each_to_itself(n), 0.0).unwrap();
        prop_assert!(field.residuals().iter().all(|&r| r < 1e-9), "{:?}", field.residuals());
        // A well-conditioned linear part: the identity plus a perturbation of norm < 0.8.
        let lin = [[1.0 + 0.4 * m[0], 0.4 * m[1]], [0.4 * m[2], 1.0 + 0.4 * m[3]]];
        let map = |p: &[f64; 2]| [0, 1].map(|r| lin[r][0] * p[0] + lin[r][1] * p[1] + t[r]);
        let mapped: Vec<[f64; 2]> = a.iter().map(map).collect();
        let field = CorrespondenceField::fit(&shape(&a), &shape(&mapped), &MatchPair::each_to_itself(n), smoothing).unwrap();
        // Anywhere, not only at the nodes: the grid's box and beyond.
        let probe: Vec<[f64; 2]> = (0..50).map(|k| [k as f64 * 0.17 - 1.0, (k * 7 % 50) as f64 * 0.15 - 1.0]).collect();
        for (got, p) in field.apply(&probe).iter().zip(&probe) {
            prop_assert!(dist(*got, map(p)) < 1e-9, "λ = {smoothing}: {got:?} vs {:?}", map(p));
        }
    }
}

/// The factored spline is the fitted field of the same centres: one factorisation, many fits.
#[test]
fn a_factored_spline_gives_the_fitted_field_for_every_set_of_values() {
    let a = foot(80, 1.0);
    let inside = interior();
    for (map, smoothing) in [
        (bend(300.0), 0.0),
        (bend(300.0), 50.0),
        (bend(150.0), 1000.0),
    ] {
        let spline = modal_core::FactoredSpline::new(&a, smoothing).unwrap();
        let basis = spline.basis(&inside);
        let b: Vec<[f64; 2]> = a.iter().map(|&p| map(p)).collect();
        let field = CorrespondenceField::fit(
            &shape(&a),
            &shape(&b),
            &MatchPair::each_to_itself(a.len()),
            smoothing,
        )
        .unwrap();
        let got = basis.apply(&spline.fit(&b).unwrap());
        let (worst, _) = errors(&got, &field.apply(&inside));
        assert!(worst < 1e-9, "λ {smoothing}: {worst:e} mm apart");
    }
}

#[test]
fn a_factored_spline_names_what_it_cannot_take() {
    let a = foot(20, 1.0);
    let line: Vec<[f64; 2]> = (0..10).map(|i| [i as f64, 2.0 * i as f64]).collect();
    let e = modal_core::FactoredSpline::new(&line, 0.0).unwrap_err();
    assert!(matches!(e, ModalError::CollinearMatches { .. }), "{e}");
    let e = modal_core::FactoredSpline::new(&a[..2], 0.0).unwrap_err();
    assert!(matches!(e, ModalError::TooFewMatches { .. }), "{e}");
    assert!(modal_core::FactoredSpline::new(&a, f64::NAN).is_err());
    let spline = modal_core::FactoredSpline::new(&a, 1.0).unwrap();
    let e = spline.fit(&a[..5]).unwrap_err();
    assert!(matches!(e, ModalError::SizeMismatch { .. }), "{e}");
    let mut bad = a.clone();
    bad[3][0] = f64::INFINITY;
    assert!(spline.fit(&bad).is_err());
}
