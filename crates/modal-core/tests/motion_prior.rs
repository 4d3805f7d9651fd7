//! The motion prior of the robust pre-alignment: among rotation candidates that fit nearly as
//! well, the smallest turn wins, and `max_rotation` bounds the turn. Round, elliptic and
//! mirror-symmetric outlines under small turns must never flip to a far turn, and a real, nearly
//! round heel outline under a moderate warp must match well.

mod match_common;

use match_common::*;
use modal_core::{match_shapes, MatchOptions, MatchResult, Shape, Topology};

/// The signed turn in degrees of the rotation part of a planar map (polar decomposition).
fn turn_deg(r: &MatchResult) -> f64 {
    let m = &r.transform.m;
    (m[1][0] - m[0][1]).atan2(m[0][0] + m[1][1]).to_degrees()
}

/// A closed outline of `n` points, `radius(t)` in polar form, stretched by `sx` along x.
fn polar(n: usize, sx: f64, radius: impl Fn(f64) -> f64) -> Vec<[f64; 2]> {
    (0..n)
        .map(|i| {
            let t = i as f64 / n as f64 * std::f64::consts::TAU;
            let r = radius(t);
            [10.0 + sx * r * t.cos(), 20.0 + r * t.sin()]
        })
        .collect()
}

/// `pts` turned by `deg` about their centroid, scaled by `(sx, sy)` first, and shifted.
fn moved(pts: &[[f64; 2]], deg: f64, sx: f64, sy: f64) -> Vec<[f64; 2]> {
    let n = pts.len() as f64;
    let c = [
        pts.iter().map(|p| p[0]).sum::<f64>() / n,
        pts.iter().map(|p| p[1]).sum::<f64>() / n,
    ];
    let (s, co) = deg.to_radians().sin_cos();
    pts.iter()
        .map(|p| {
            let (x, y) = (sx * (p[0] - c[0]), sy * (p[1] - c[1]));
            [c[0] + 1.5 + co * x - s * y, c[1] - 0.7 + s * x + co * y]
        })
        .collect()
}

fn shape(p: &[[f64; 2]]) -> Shape {
    Shape::from_points_2d(p, Topology::ClosedContour).unwrap()
}

/// Fraction of A's nodes matched to B's node of the same index, or one of its neighbours (B is A
/// moved, node for node).
fn index_accuracy(r: &MatchResult, n: usize) -> f64 {
    let mut ok = vec![false; n];
    for p in r.pairs.iter().filter(|p| !p.excess) {
        let d = (p.a as i64 - p.b as i64).rem_euclid(n as i64);
        ok[p.a] |= d <= 1 || d == n as i64 - 1;
    }
    ok.iter().filter(|&&k| k).count() as f64 / n as f64
}

#[test]
fn round_elliptic_and_mirror_symmetric_outlines_keep_small_turns() {
    let shapes: [(&str, Vec<[f64; 2]>); 3] = [
        // Principal-axis ratio 1.0: every turn fits about as well.
        ("round", polar(60, 1.0, |t| 8.0 + 0.25 * (3.0 * t).cos())),
        // Two mirror axes: the outline fits itself turned by 180°.
        ("elliptic", polar(60, 1.6, |_| 8.0)),
        // One mirror axis (the x axis), egg-shaped like a heel.
        ("mirror", polar(60, 1.15, |t| 8.0 * (1.0 + 0.12 * t.cos()))),
    ];
    let opts = MatchOptions::default();
    for (name, a) in &shapes {
        for deg in [-15.0, -8.0, -3.0, 3.0, 8.0, 15.0] {
            for (sx, sy) in [(1.0, 1.0), (1.06, 0.95)] {
                let b = moved(a, deg, sx, sy);
                let r = match_shapes(&shape(a), &shape(&b), &opts).unwrap();
                let found = turn_deg(&r);
                // The fitted affine map of a stretched turn has a slightly different polar turn; a
                // round outline's turn is only defined up to a nearby minimum, but never far.
                let slack = if *name == "round" { 10.0 } else { 6.0 };
                assert!(
                    (found - deg).abs() < slack,
                    "{name} turned by {deg}° (scale {sx}, {sy}): found {found:.1}°"
                );
                if *name != "round" {
                    let acc = index_accuracy(&r, a.len());
                    assert!(acc >= 0.95, "{name} {deg}° ({sx}, {sy}): accuracy {acc}");
                }
            }
        }
    }
}

#[test]
fn max_rotation_bounds_the_turn() {
    let a = polar(60, 1.3, |t| 8.0 * (1.0 + 0.12 * t.cos()));
    let b = moved(&a, 60.0, 1.0, 1.0);
    let free = match_shapes(&shape(&a), &shape(&b), &MatchOptions::default()).unwrap();
    assert!((turn_deg(&free) - 60.0).abs() < 3.0, "{}", turn_deg(&free));
    let mut bounded = MatchOptions::default();
    bounded.rotation_search.max_rotation = Some(20.0);
    let r = match_shapes(&shape(&a), &shape(&b), &bounded).unwrap();
    assert!(turn_deg(&r).abs() <= 20.0 + 1e-9, "{}", turn_deg(&r));
}

/// Mean accuracy and the worst case of real heel-strike outlines under moderate warps.
fn heel_accuracy(opts: &MatchOptions, seeds: std::ops::Range<u64>) -> (f64, f64) {
    let heels = heel_strikes();
    let accs: Vec<f64> = seeds
        .map(|seed| {
            let (_, o) = &heels[seed as usize % heels.len()];
            let case = contour_case(o, Severity::Moderate, seed);
            let (a, b) = (shape(&case.a), shape(&case.b));
            let r = match_shapes(&a, &b, opts).unwrap();
            accuracy(&r, &case.b, &case.truth, case.spacing_b)
        })
        .collect();
    let mean = accs.iter().sum::<f64>() / accs.len() as f64;
    (mean, accs.iter().copied().fold(1.0, f64::min))
}

#[test]
fn nearly_round_heel_outlines_match_under_moderate_warps() {
    // The case: heel outlines of the first loaded frames (principal-axis ratio 1.09-1.17)
    // under moderate warps (≤ 15° turns). Measured on these 40 cases: mean 0.995, worst 0.825,
    // with and without the bound; the bound must not lose anything.
    let (mean, worst) = heel_accuracy(&MatchOptions::default(), 0..40);
    let mut bounded = MatchOptions::default();
    bounded.rotation_search.max_rotation = Some(modal_core::options::RUN_MAX_ROTATION);
    let (b_mean, b_worst) = heel_accuracy(&bounded, 0..40);
    eprintln!(
        "heels, moderate: mean {mean:.4} worst {worst:.3}; bounded {b_mean:.4} worst {b_worst:.3}"
    );
    assert!(mean >= 0.98 && worst >= 0.8, "mean {mean}, worst {worst}");
    assert!(
        b_mean >= mean - 1e-9 && b_worst >= worst - 1e-9,
        "bounded {b_mean} {b_worst}"
    );
}

/// `prealign = "sensor"`: the coordinates as given are the prior. A small outline lying at one end
/// of a large one (a heel beside the whole foot) starts where it lies; normalised onto the large
/// outline (the robust search) it starts centred on it. (The re-fits then follow the pairs, and
/// modes compare whole shapes, so which nodes of the whole a part may match is the caller's
/// choice: a recording run matches it to its own portion of the whole.) And two consecutive
/// frames a small shift apart match node for node.
#[test]
fn the_sensor_prior_keeps_a_part_where_it_lies() {
    use modal_core::Prealign;
    // The whole: an ellipse 40 × 12 centred at (20, 0); the part: a circle of radius 6 at its
    // left end, centred at (6.5, 0), as a heel region before it merges.
    let whole: Vec<[f64; 2]> = (0..120)
        .map(|i| {
            let t = i as f64 / 120.0 * std::f64::consts::TAU;
            [20.0 + 20.0 * t.cos(), 6.0 * t.sin()]
        })
        .collect();
    let part: Vec<[f64; 2]> = (0..30)
        .map(|i| {
            let t = i as f64 / 30.0 * std::f64::consts::TAU + 0.05;
            [6.5 + 6.3 * t.cos(), 5.8 * t.sin()]
        })
        .collect();
    let shape = |p: &[[f64; 2]]| Shape::from_points_2d(p, Topology::ClosedContour).unwrap();
    let placed_at = |prealign| {
        let opts = MatchOptions {
            prealign,
            refits: 0,
            ..MatchOptions::default()
        };
        let r = match_shapes(&shape(&part), &shape(&whole), &opts).unwrap();
        let n = part.len() as f64;
        r.aligned_a.chunks_exact(2).map(|p| p[0]).sum::<f64>() / n
    };
    let sensor = placed_at(Prealign::Sensor);
    assert!(
        (sensor - 6.5).abs() < 2.0,
        "sensor: centred at x = {sensor}"
    );
    let robust = placed_at(Prealign::Robust);
    assert!(
        (robust - 20.0).abs() < 2.0,
        "robust: centred at x = {robust}"
    );
    let shifted: Vec<[f64; 2]> = whole.iter().map(|p| [p[0] + 0.4, p[1] - 0.2]).collect();
    let opts = MatchOptions {
        prealign: Prealign::Sensor,
        ..MatchOptions::default()
    };
    let r = match_shapes(&shape(&whole), &shape(&shifted), &opts).unwrap();
    let right = r.pairs.iter().filter(|m| !m.excess && m.a == m.b).count();
    assert_eq!(right, whole.len());
}

#[test]
fn severe_heel_strikes_are_ranked_by_the_fitted_outlines() {
    // Nearly round heel outlines turned by up to 35°: the survivors of the rotation search are
    // ranked by the distance between the fitted outlines, not by the chamfer of their nodes
    // (which a far turn can win: two samplings of one curve keep their nodes apart even at the
    // true map). Measured on these 120 cases: ranked by the node chamfer, mean 0.955 with cases 45
    // and 107 below 0.5 (turned the wrong way round); ranked by the outlines, mean 0.971, none.
    let heels = heel_strikes();
    let accs: Vec<f64> = (0..120u64)
        .map(|seed| {
            let (_, o) = &heels[seed as usize % heels.len()];
            let case = contour_case(o, Severity::Severe, seed);
            let (a, b) = (shape(&case.a), shape(&case.b));
            let r = match_shapes(&a, &b, &MatchOptions::default()).unwrap();
            accuracy(&r, &case.b, &case.truth, case.spacing_b)
        })
        .collect();
    let mean = accs.iter().sum::<f64>() / accs.len() as f64;
    let lost: Vec<usize> = (0..accs.len()).filter(|&k| accs[k] < 0.5).collect();
    eprintln!("severe heels: mean {mean:.4}, below 0.5: {lost:?} {accs:.2?}");
    assert!(lost.is_empty(), "cases below 0.5: {lost:?}");
    assert!(mean >= 0.965, "mean {mean}");
}
