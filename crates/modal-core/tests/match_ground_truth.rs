//! Ground truth: real foot outlines warped by known deformations, re-sampled with different point
//! counts and random starts; the fraction of nodes matched within one point spacing of their true
//! position.

mod match_common;

use match_common::*;
use modal_core::{match_shapes, MatchOptions, Shape, Topology};

fn run(sev: Severity, seeds: std::ops::Range<u64>, opts: &MatchOptions) -> (f64, Vec<f64>) {
    let outlines = outlines();
    let mut accs = Vec::new();
    for seed in seeds {
        let (_, o) = &outlines[seed as usize % outlines.len()];
        let case = contour_case(o, sev, seed);
        let a = Shape::from_points_2d(&case.a, Topology::ClosedContour).unwrap();
        let b = Shape::from_points_2d(&case.b, Topology::ClosedContour).unwrap();
        let res = match_shapes(&a, &b, opts).unwrap();
        accs.push(accuracy_2d(&res, &case.b, &case.truth, case.spacing_b));
    }
    (accs.iter().sum::<f64>() / accs.len() as f64, accs)
}

#[test]
fn contours_all_severities() {
    let opts = MatchOptions::default();
    for (sev, target) in [
        (Severity::Mild, 0.97),
        (Severity::Moderate, 0.95),
        (Severity::Severe, 0.9),
    ] {
        let (mean, accs) = run(sev, 0..18, &opts);
        eprintln!("{sev:?}: mean {mean:.4} {accs:.3?}");
        assert!(mean >= target, "{sev:?}: {mean} < {target}");
    }
}
