//! 3-D point sets: brightness surfaces of a real pressure image (MUN104), and a same-sampling case.

mod match_common;

use match_common::*;
use modal_core::matching::prealign::normalize;
use modal_core::matching::prealign_normalized;
use modal_core::{match_shapes, MatchOptions, Search, Shape, Topology};

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

/// Both objects of a surface case as unordered 3-D point sets.
fn shapes(case: &SurfaceCase) -> (Shape, Shape) {
    (
        Shape::from_points_3d(&case.a, Topology::None).unwrap(),
        Shape::from_points_3d(&case.b, Topology::None).unwrap(),
    )
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
        let (sa, sb) = shapes(&case);
        let r = match_shapes(&sa, &sb, opts).unwrap();
        assert_eq!(
            r.pairs.len(),
            case.a.len().max(case.b.len()),
            "excess completes to max(n, m)"
        );
        acc.push(accuracy(&r, &case.b, &case.truth, case.spacing_b));
    }
    acc.iter().sum::<f64>() / acc.len() as f64
}

#[test]
fn the_surface_setting_beats_squared_costs_and_ties_aligned_positions() {
    let surf = MatchOptions::for_surfaces();
    let acc = |o: MatchOptions| mean_accuracy(&o, Severity::Mild, 0..8);
    let setting = acc(surf.clone());
    let positions = acc(MatchOptions {
        position_weight: 1.0,
        ..surf.clone()
    });
    let squared = acc(MatchOptions {
        cost_power: 1.0,
        ..surf.clone()
    });
    let modal_only = acc(MatchOptions {
        position_weight: 0.0,
        ..surf.clone()
    });
    let contour_setting = acc(MatchOptions::default());
    eprintln!(
        "surfaces mild: setting {setting:.3}, aligned positions {positions:.3}, squared costs \
         {squared:.3}, modal only {modal_only:.3}, contour setting {contour_setting:.3}"
    );
    // An assignment of squared distances spreads its error over all pairs: between independent
    // samplings it cannot put much more than a quarter of them within one spacing.
    assert!(
        setting > squared + 0.05,
        "powered costs {setting} vs squared {squared}"
    );
    assert!(
        setting >= positions - 0.01,
        "setting {setting} vs positions {positions}"
    );
    assert!(
        modal_only > contour_setting,
        "the surface model must improve on the contour setting: {modal_only} vs {contour_setting}"
    );
}

#[test]
fn aligned_point_sets_keep_the_frame_of_the_fit() {
    // A random sampling's centroid and RMS radius wander with the sample; normalising the
    // aligned points again would move them off B's frame by about radius / √n.
    let g = pressure_grid();
    let (mut kept, mut renormalised) = (0.0, 0.0);
    for seed in 0..8u64 {
        let case = surface_case(&g, Severity::Moderate, seed, 110, 115);
        let (sa, sb) = shapes(&case);
        let (pa, _) = prealign_normalized(&sa, &sb, &MatchOptions::for_surfaces()).unwrap();
        let flat_b: Vec<f64> = case.b.iter().flatten().copied().collect();
        let (_, c, s) = normalize(&flat_b, 3).unwrap();
        let truth: Vec<f64> = case
            .truth
            .iter()
            .flat_map(|p| (0..3).map(move |k| (p[k] - c[k]) * s))
            .collect();
        let rms = |x: &[f64]| {
            (x.iter()
                .zip(&truth)
                .map(|(u, v)| (u - v).powi(2))
                .sum::<f64>()
                / case.a.len() as f64)
                .sqrt()
        };
        kept += rms(&pa) / 8.0;
        renormalised += rms(&normalize(&pa, 3).unwrap().0) / 8.0;
    }
    eprintln!("RMS error of aligned A: kept {kept:.4}, re-normalised {renormalised:.4}");
    assert!(
        kept < 0.8 * renormalised,
        "kept {kept} vs re-normalised {renormalised}"
    );
}

#[test]
fn cost_power_reshapes_the_sum_not_the_order() {
    let g = pressure_grid();
    let case = surface_case(&g, Severity::Mild, 3, 100, 108);
    let (sa, sb) = shapes(&case);
    let with = |p: f64| MatchOptions {
        position_weight: 0.0,
        cost_power: p,
        ..MatchOptions::for_surfaces()
    };
    let squared = match_shapes(&sa, &sb, &with(1.0)).unwrap();
    let powered = match_shapes(&sa, &sb, &with(0.125)).unwrap();
    for (x, y) in squared
        .affinity
        .as_slice()
        .iter()
        .zip(powered.affinity.as_slice())
    {
        assert!((x.powf(0.125) - y).abs() < 1e-12, "{x}^0.125 vs {y}");
    }
    // Mutual-best matches depend only on each row's and column's order.
    assert_eq!(squared.local_pairs, powered.local_pairs);
    // The assignment does change: it adds the costs up.
    assert_ne!(
        squared.pairs.iter().map(|p| (p.a, p.b)).collect::<Vec<_>>(),
        powered.pairs.iter().map(|p| (p.a, p.b)).collect::<Vec<_>>()
    );
}

#[test]
fn best_search_reads_out_every_node_many_to_one() {
    let g = pressure_grid();
    let surf = MatchOptions::for_surfaces();
    let best = MatchOptions {
        search: Search::Best,
        ..surf.clone()
    };
    let (mut acc_best, mut acc_global) = (0.0, 0.0);
    for seed in 0..8u64 {
        let case = surface_case(&g, Severity::Mild, seed, 100 + seed as usize % 15, 108);
        let (sa, sb) = shapes(&case);
        let r = match_shapes(&sa, &sb, &best).unwrap();
        assert_eq!(r.pairs.len(), case.a.len(), "one pair per node of A");
        for (i, p) in r.pairs.iter().enumerate() {
            assert_eq!(p.a, i);
            assert!(!p.excess);
            let row = &r.affinity.as_slice()[i * case.b.len()..(i + 1) * case.b.len()];
            let min = row.iter().copied().fold(f64::INFINITY, f64::min);
            assert_eq!(p.cost, min, "node {i} is paired with its row minimum");
        }
        acc_best += accuracy(&r, &case.b, &case.truth, case.spacing_b) / 8.0;
        let r = match_shapes(&sa, &sb, &surf).unwrap();
        acc_global += accuracy(&r, &case.b, &case.truth, case.spacing_b) / 8.0;
    }
    eprintln!("surfaces mild: best {acc_best:.3}, global {acc_global:.3}");
    // Two independent samplings: the best one-to-one answer cannot be right for every node,
    // a many-to-one read-out can (the oracle ceilings are 0.46 and 0.55 in bench_match.py).
    assert!(
        acc_best > acc_global + 0.06,
        "best {acc_best} vs global {acc_global}"
    );
}
