//! Tracks against ground truth: on a synthetic walk with a known motion, the tracks that start on
//! frame 0 must stay on their material points.

use pedo_io::synthetic::SyntheticWalk;
use pedo_track::{run_sequence, FrameRange, RunParams, SequenceResult};

/// For every track that starts on frame 0, the distance (sensels) from its node in frame `k` to
/// the true position of its starting point; `None` when the track has ended before `k`.
fn errors_at(walk: &SyntheticWalk, run: &SequenceResult, k: usize) -> Vec<Option<f64>> {
    run.tracks
        .iter()
        .filter_map(|t| {
            let pts = run.track_points(t);
            (pts[0].0 == 0).then(|| {
                let p0 = [pts[0].1[0], pts[0].1[1]];
                let truth = walk.true_position(k, p0);
                pts.iter()
                    .find(|(f, _)| *f == k)
                    .map(|(_, p)| (p[0] - truth[0]).hypot(p[1] - truth[1]))
            })
        })
        .collect()
}

/// Share of the tracks from frame 0 whose node is within `tolerance` of the truth (ended tracks
/// count as lost).
fn share_within(errors: &[Option<f64>], tolerance: f64) -> f64 {
    let ok = errors
        .iter()
        .filter(|e| e.is_some_and(|e| e <= tolerance))
        .count();
    ok as f64 / errors.len().max(1) as f64
}

fn run(walk: &SyntheticWalk, params: &RunParams) -> SequenceResult {
    let rec = walk.recording().unwrap();
    let options = params.to_options(&rec).unwrap();
    run_sequence(&rec, &options, &|_, _, _| {}).unwrap()
}

/// The first 41 frames of the default walk (its speed: 0.08 sensels and 0.1° per frame, the
/// forefoot widening 0.13 % per frame).
fn short_walk_params(drift_reference: usize) -> RunParams {
    RunParams {
        frames: Some(FrameRange {
            start: 0,
            end: Some(41),
        }),
        drift_reference,
        ..Default::default()
    }
}

#[test]
fn with_drift_correction_tracks_stay_within_a_spacing_of_their_material_points() {
    let walk = SyntheticWalk::default();
    let params = short_walk_params(20);
    let result = run(&walk, &params);
    // Frame 20 is matched directly against frame 0 (one reference link), frame 40 through frame
    // 20 (two links).
    let after_20 = share_within(&errors_at(&walk, &result, 20), params.spacing);
    let after_40 = share_within(&errors_at(&walk, &result, 40), params.spacing);
    assert!(after_20 >= 0.95, "after 20 frames: {after_20:.3}");
    assert!(after_40 >= 0.9, "after 40 frames: {after_40:.3}");
}

#[test]
fn the_reference_pairs_follow_one_to_one_continuations_back_to_the_reference_frame() {
    let walk = SyntheticWalk {
        frames: 12,
        ..Default::default()
    };
    let result = run(&walk, &RunParams::default());
    // One object per frame, so object o is frame o and its candidate pairs are (o, o + 1).
    assert_eq!(result.objects.len(), 12);
    let candidates: Vec<(usize, usize)> = (0..11).map(|o| (o, o + 1)).collect();
    let refs = pedo_track::drift::reference_pairs(&result.objects, &candidates, 0, 5);
    // Frames 2..=5 against 0, 7..=10 against 5, 11 has its reference one frame back (left out).
    let expected: Vec<(usize, usize)> = [
        (0, 2),
        (0, 3),
        (0, 4),
        (0, 5),
        (5, 7),
        (5, 8),
        (5, 9),
        (5, 10),
    ]
    .to_vec();
    assert_eq!(refs, expected);
    // A second pair into object 4 (as at a merge) breaks the chain there: frames 4 and 5 get no
    // reference, the others keep theirs.
    let mut broken = candidates.clone();
    broken.push((3, 4));
    let refs = pedo_track::drift::reference_pairs(&result.objects, &broken, 0, 5);
    let expected: Vec<(usize, usize)> = [(0, 2), (0, 3), (5, 7), (5, 8), (5, 9), (5, 10)].to_vec();
    assert_eq!(refs, expected);
}
