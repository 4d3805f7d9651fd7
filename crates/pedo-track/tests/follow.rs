//! Material points followed by anchored registration, against ground truth: on a synthetic walk
//! with a known motion, a point keeps to its material point over the whole walk, where node
//! tracks chained pair by pair drift.

use pedo_io::synthetic::SyntheticWalk;
use pedo_track::follow::{follow_points, FollowParams, FollowedPoints};
use pedo_track::{run_sequence, RunParams, SenselAspect, SequenceResult};
use std::sync::OnceLock;

fn run(walk: &SyntheticWalk) -> SequenceResult {
    let rec = walk.recording().unwrap();
    let options = RunParams::default().to_options(&rec).unwrap();
    run_sequence(&rec, &options, &|_, _, _| {}).unwrap()
}

/// The walk's first 60 frames and their run with the defaults, made once for the tests that
/// follow points through them.
fn walk_60() -> &'static (SyntheticWalk, SequenceResult) {
    static RUN: OnceLock<(SyntheticWalk, SequenceResult)> = OnceLock::new();
    RUN.get_or_init(|| {
        let walk = SyntheticWalk {
            frames: 60,
            ..Default::default()
        };
        let result = run(&walk);
        (walk, result)
    })
}

/// Distance (sensels) from each point's position in frame `k` to the truth (None once it ended).
fn errors_at(
    walk: &SyntheticWalk,
    run: &SequenceResult,
    followed: &FollowedPoints,
    k: usize,
) -> Vec<Option<f64>> {
    followed
        .points
        .iter()
        .map(|p| {
            let start = p.steps[0].1;
            let truth = walk.true_position(k, start);
            p.steps
                .iter()
                .find(|(o, _)| run.objects[*o].frame == k)
                .map(|(_, q)| (q[0] - truth[0]).hypot(q[1] - truth[1]))
        })
        .collect()
}

fn share_within(errors: &[Option<f64>], tolerance: f64) -> f64 {
    let ok = errors
        .iter()
        .filter(|e| e.is_some_and(|e| e <= tolerance))
        .count();
    ok as f64 / errors.len().max(1) as f64
}

#[test]
fn followed_outline_points_stay_on_their_material_points_through_the_whole_walk() {
    let walk = SyntheticWalk::default();
    let result = run(&walk);
    let followed =
        follow_points(&result, SenselAspect::SQUARE, &FollowParams::default(), &[]).unwrap();
    // One lineage (one object per frame), seeded on frame 0's outline nodes.
    assert_eq!(followed.points.len(), result.objects[0].shape.len());
    assert!(followed.points.iter().all(|p| p.seed.0 == 0));
    let spacing = RunParams::default().spacing;
    let last = walk.frames - 1;
    for k in [30, 60, last] {
        let share = share_within(&errors_at(&walk, &result, &followed, k), spacing);
        assert!(share >= 0.95, "after {k} frames: {share:.3}");
    }
    // Node tracks chained pair by pair, on the same run, for comparison: they drift.
    let chained: Vec<Option<f64>> = result
        .tracks
        .iter()
        .filter(|t| t.steps[0].0 == 0)
        .map(|t| {
            let pts = result.track_points(t);
            let truth = walk.true_position(last, [pts[0].1[0], pts[0].1[1]]);
            pts.iter()
                .find(|(f, _)| *f == last)
                .map(|(_, p)| (p[0] - truth[0]).hypot(p[1] - truth[1]))
        })
        .collect();
    let followed_last = share_within(&errors_at(&walk, &result, &followed, last), spacing);
    assert!(
        followed_last > share_within(&chained, spacing),
        "followed {followed_last:.3}"
    );
}

#[test]
fn a_seeded_interior_point_is_carried_by_the_field() {
    let (walk, result) = walk_60();
    let c = walk.centre();
    let seeds = [
        (0, c),
        (0, [c[0], c[1] - 10.0]),
        (0, [c[0] + 2.0, c[1] + 12.0]),
    ];
    let followed = follow_points(
        result,
        SenselAspect::SQUARE,
        &FollowParams::default(),
        &seeds,
    )
    .unwrap();
    assert_eq!(followed.points.len(), 3);
    for e in errors_at(walk, result, &followed, 59) {
        let e = e.expect("followed through the walk");
        assert!(e < 0.5, "{e:.3} sensels off");
    }
}

#[test]
fn a_seed_on_a_missing_object_is_an_error_naming_it() {
    let walk = SyntheticWalk {
        frames: 4,
        ..Default::default()
    };
    let result = run(&walk);
    let e = follow_points(
        &result,
        SenselAspect::SQUARE,
        &FollowParams::default(),
        &[(9, [1.0, 1.0])],
    )
    .unwrap_err();
    assert!(e.to_string().contains("object 9"), "{e}");
}

/// Mean over points and frames of how far a point's step differs from its step before (the
/// second difference of its path, sensels).
fn mean_jerk(followed: &FollowedPoints) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for p in &followed.points {
        for w in p.steps.windows(3) {
            let [a, b, c] = [w[0].1, w[1].1, w[2].1];
            sum += (c[0] - 2.0 * b[0] + a[0]).hypot(c[1] - 2.0 * b[1] + a[1]);
            n += 1;
        }
    }
    sum / n.max(1) as f64
}

#[test]
fn the_constant_velocity_prior_smooths_the_paths_and_keeps_the_points_on_the_truth() {
    let (walk, result) = walk_60();
    let without = FollowParams::default();
    assert_eq!(without.inertia, 0.0);
    let with = FollowParams {
        inertia: 0.2,
        ..without
    };
    let smooth = follow_points(result, SenselAspect::SQUARE, &with, &[]).unwrap();
    let plain = follow_points(result, SenselAspect::SQUARE, &without, &[]).unwrap();
    let (j_smooth, j_plain) = (mean_jerk(&smooth), mean_jerk(&plain));
    assert!(
        j_smooth < j_plain,
        "with the prior {j_smooth:.4}, without {j_plain:.4} sensels"
    );
    let spacing = RunParams::default().spacing;
    for k in [20, 40, 59] {
        let share = share_within(&errors_at(walk, result, &smooth, k), spacing);
        assert!(share >= 0.95, "after {k} frames: {share:.3}");
    }
}
