//! 3-D point sets: brightness surfaces of a real pressure image (MUN104), and a same-sampling case.

mod match_common;

use match_common::*;
use modal_core::{match_shapes, MatchOptions, Shape, Topology};

#[test]
fn same_sampling_3d_is_recovered_exactly() {
    // B = A rotated by 25° about z, scaled anisotropically, shuffled: a correspondence problem
    // with an exact answer.
    let g = pressure_grid();
    let case = surface_case(&g, Severity::Mild, 7, 90, 90);
    let n = case.a.len();
    let perm: Vec<usize> = (0..n).map(|i| (i * 37 + 11) % n).collect(); // 37 coprime to 90
    let (c, s) = (25f64.to_radians().cos(), 25f64.to_radians().sin());
    let b: Vec<[f64; 3]> = perm
        .iter()
        .map(|&i| {
            let p = case.a[i];
            [
                1.1 * (c * p[0] - s * p[1]) + 4.0,
                0.95 * (s * p[0] + c * p[1]) - 2.0,
                1.05 * p[2],
            ]
        })
        .collect();
    let sa = Shape::from_points_3d(&case.a, Topology::None).unwrap();
    let sb = Shape::from_points_3d(&b, Topology::None).unwrap();
    for opts in [MatchOptions::default(), MatchOptions::for_surfaces()] {
        let r = match_shapes(&sa, &sb, &opts).unwrap();
        let correct = r.pairs.iter().filter(|p| perm[p.b] == p.a).count();
        assert!(correct as f64 >= 0.97 * n as f64, "{correct}/{n}");
    }
}

fn mean_accuracy(opts: &MatchOptions, sev: Severity, seeds: std::ops::Range<u64>) -> f64 {
    let g = pressure_grid();
    let mut acc = Vec::new();
    for seed in seeds {
        let case = surface_case(
            &g,
            sev,
            seed,
            100 + (seed as usize % 15),
            108 + (seed as usize % 7),
        );
        let sa = Shape::from_points_3d(&case.a, Topology::None).unwrap();
        let sb = Shape::from_points_3d(&case.b, Topology::None).unwrap();
        let r = match_shapes(&sa, &sb, opts).unwrap();
        assert_eq!(
            r.pairs.len(),
            case.a.len().max(case.b.len()),
            "excess completes to max(n, m)"
        );
        acc.push(accuracy_3d(&r, &case.b, &case.truth, case.spacing_b));
    }
    acc.iter().sum::<f64>() / acc.len() as f64
}

#[test]
fn independent_samplings_beat_aligned_positions() {
    let modal = mean_accuracy(&MatchOptions::for_surfaces(), Severity::Mild, 0..8);
    let positions = mean_accuracy(
        &MatchOptions {
            position_weight: 1.0,
            ..MatchOptions::for_surfaces()
        },
        Severity::Mild,
        0..8,
    );
    let contour_setting = mean_accuracy(&MatchOptions::default(), Severity::Mild, 0..8);
    eprintln!("surfaces mild: modal {modal:.3}, aligned positions {positions:.3}, contour setting {contour_setting:.3}");
    assert!(
        modal > contour_setting,
        "the surface setting must improve on the contour setting"
    );
    assert!(
        modal >= positions - 0.01,
        "modal {modal} vs positions {positions}"
    );
}
