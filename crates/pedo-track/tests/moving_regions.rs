//! Anatomical regions carried through a stance by the field, against ground truth: on a
//! synthetic walk with a known motion, points followed backwards land on their material points,
//! the regions partition the contact of their reference frame, and a region carried by the field
//! weighs what the true region weighs better than the mask left in place.

use pedo_io::measures::Measures;
use pedo_io::regions::{masks_of_measures, RegionMasks, RegionRule};
use pedo_io::stances::Stance;
use pedo_io::synthetic::SyntheticWalk;
use pedo_io::{IoError, Recording};
use pedo_track::follow::{follow_both_ways, FollowParams, Seed, Seeded};
use pedo_track::moving_regions::{follow_masks, reference_frame, MovingRegion};
use pedo_track::{run_sequence, ObjectModel, RunParams, SenselAspect, SequenceOptions};

fn run(walk: &SyntheticWalk) -> (Recording, SequenceOptions, pedo_track::SequenceResult) {
    let rec = walk.recording().unwrap();
    let options = RunParams::default().to_options(&rec).unwrap();
    let result = run_sequence(&rec, &options, &|_, _, _| {}).unwrap();
    (rec, options, result)
}

fn threshold(options: &SequenceOptions) -> f64 {
    options.contour.preprocess.threshold.unwrap_or(0.0)
}

/// The coarse masks of the walk's peak image and the whole walk as one stance.
fn masks_and_stance(rec: &Recording, threshold: f64) -> (RegionMasks, Stance) {
    let n = rec.n_frames();
    let m = Measures::of_recording(rec, threshold, 0..n).unwrap();
    let cop: Vec<Option<[f64; 2]>> = rec
        .measures_of(threshold, 0..n)
        .iter()
        .map(|f| f.cop)
        .collect();
    let masks = masks_of_measures(rec, &m, Some(&cop), RegionRule::Coarse).unwrap();
    let stance = Stance {
        first: 0,
        last: n - 1,
        complete: false,
    };
    (masks, stance)
}

/// The load (sum of values at or above the threshold) of frame `t` over `cells`.
fn load(rec: &Recording, t: usize, cells: &[bool], threshold: f64) -> f64 {
    let shares: Vec<f64> = cells.iter().map(|&c| f64::from(u8::from(c))).collect();
    covered_load(rec, t, &shares, threshold)
}

/// The load of frame `t` over the sensels, each by its share.
fn covered_load(rec: &Recording, t: usize, shares: &[f64], threshold: f64) -> f64 {
    let v = rec.frame_slice(t).unwrap();
    (v.iter().zip(shares))
        .filter(|&(&x, _)| x > 0.0 && f64::from(x) >= threshold)
        .map(|(&x, &w)| w * f64::from(x))
        .sum()
}

/// The true region on frame `t` of a region whose sensels on frame `reference` are `cells`: the
/// sensels whose material point lies, on the reference frame, in one of its sensels.
fn true_cells(
    walk: &SyntheticWalk,
    rec: &Recording,
    reference: usize,
    t: usize,
    cells: &[bool],
) -> Vec<bool> {
    let (rows, cols) = (rec.rows(), rec.cols());
    (0..rows * cols)
        .map(|i| {
            let x = [(i % cols) as f64, (i / cols) as f64];
            let q = walk.true_position(reference, walk.reference_position(t, x));
            let (c, r) = (q[0].round(), q[1].round());
            (0.0..cols as f64).contains(&c)
                && (0.0..rows as f64).contains(&r)
                && cells[r as usize * cols + c as usize]
        })
        .collect()
}

#[test]
fn points_followed_backwards_land_within_a_sensel_of_their_material_points() {
    let walk = SyntheticWalk {
        frames: 60,
        ..Default::default()
    };
    let (_, _, result) = run(&walk);
    // Seeded on frame 45 (inside the contact), followed back to frame 0 and on to 59.
    let seeded = 45;
    let object = (result.objects.iter())
        .position(|o| o.frame == seeded)
        .unwrap();
    let c = walk.true_position(seeded, walk.centre());
    let places = [c, [c[0], c[1] - 10.0], [c[0] + 2.0, c[1] + 12.0]];
    let seeds: Vec<Seed> = (places.iter().enumerate())
        .map(|(k, &xy)| Seed {
            object,
            xy,
            kind: Seeded::Point(k),
        })
        .collect();
    let followed = follow_both_ways(
        &result,
        SenselAspect::SQUARE,
        &FollowParams::default(),
        &seeds,
        0,
        59,
    )
    .unwrap();
    assert_eq!(followed.points.len(), 3);
    for (p, &xy) in followed.points.iter().zip(&places) {
        // One step per frame, in frame order, the seed's own place on its frame.
        let frames: Vec<usize> = p
            .steps
            .iter()
            .map(|(o, _)| result.objects[*o].frame)
            .collect();
        assert_eq!(frames, (0..60).collect::<Vec<_>>());
        assert_eq!(p.steps[seeded].1, xy);
        let material = walk.reference_position(seeded, xy);
        for (k, &(_, q)) in p.steps.iter().enumerate() {
            let truth = walk.true_position(k, material);
            let e = (q[0] - truth[0]).hypot(q[1] - truth[1]);
            assert!(e < 1.0, "frame {k}: {e:.3} sensels off");
        }
        // Frame 0, 45 frames back: well within a sensel.
        let truth = walk.true_position(0, material);
        let q = p.steps[0].1;
        assert!((q[0] - truth[0]).hypot(q[1] - truth[1]) < 0.5);
    }
}

#[test]
fn seeds_on_two_frames_or_outside_the_frames_are_refused() {
    let walk = SyntheticWalk {
        frames: 6,
        ..Default::default()
    };
    let (_, _, result) = run(&walk);
    let seed = |object| Seed {
        object,
        xy: walk.centre(),
        kind: Seeded::Point(0),
    };
    let params = FollowParams::default();
    let e = follow_both_ways(
        &result,
        SenselAspect::SQUARE,
        &params,
        &[seed(0), seed(1)],
        0,
        5,
    )
    .unwrap_err();
    assert!(matches!(e, IoError::InvalidInput(_)), "{e}");
    assert!(e.to_string().contains("one frame"), "{e}");
    let e = follow_both_ways(&result, SenselAspect::SQUARE, &params, &[seed(3)], 0, 2).unwrap_err();
    assert!(matches!(e, IoError::InvalidInput(_)), "{e}");
}

#[test]
fn regions_partition_the_contact_of_their_reference_frame_and_follow_the_true_region() {
    let walk = SyntheticWalk {
        frames: 80,
        ..Default::default()
    };
    let (rec, options, result) = run(&walk);
    let th = threshold(&options);
    let (masks, stance) = masks_and_stance(&rec, th);
    let moving = follow_masks(&result, &options, &rec, &masks, &[stance], th, None).unwrap();
    assert_eq!(moving.len(), 4);
    let reference = reference_frame(&rec, &stance, th).unwrap();
    // The frame of largest contact: counted independently.
    let counts: Vec<usize> = (0..80)
        .map(|t| {
            let v = rec.frame_slice(t).unwrap();
            v.iter().filter(|&&x| x > 0.0 && f64::from(x) >= th).count()
        })
        .collect();
    let most = *counts.iter().max().unwrap();
    assert_eq!(reference, counts.iter().position(|&c| c == most).unwrap());
    assert!(moving.iter().all(|r| r.reference_frame == reference));
    // A partition of the reference frame's contact: every contact sensel in exactly one region.
    let (rows, cols) = (rec.rows(), rec.cols());
    let v = rec.frame_slice(reference).unwrap();
    for i in 0..rows * cols {
        let contact = v[i] > 0.0 && f64::from(v[i]) >= th;
        let held = moving.iter().filter(|r| r.reference_cells[i]).count();
        assert_eq!(held, usize::from(contact), "sensel {i}");
    }
    // On the reference frame each region's followed outlines cover exactly its sensels.
    for r in &moving {
        assert_eq!(r.parts.0, r.parts.1, "{}: every part followed", r.name);
        let shares = r.shares(reference, rows, cols).unwrap();
        let cells: Vec<f64> = (r.reference_cells.iter())
            .map(|&c| f64::from(u8::from(c)))
            .collect();
        assert_eq!(shares, cells, "{}", r.name);
    }
    // The force of each region carried by the field against the true region's, beside the
    // fixed mask's: at the worst frame of each, the carried region is closer.
    for r in moving
        .iter()
        .filter(|r| r.reference_cells.iter().any(|&c| c))
    {
        let fixed: Vec<bool> = masks.labels.iter().map(|&l| l == r.label).collect();
        let (mut worst_moving, mut worst_fixed, mut mean_moving) = (0.0f64, 0.0f64, 0.0f64);
        for t in 0..80 {
            let truth = load(
                &rec,
                t,
                &true_cells(&walk, &rec, reference, t, &r.reference_cells),
                th,
            );
            let carried = covered_load(&rec, t, &r.shares(t, rows, cols).unwrap(), th);
            let left = load(&rec, t, &fixed, th);
            worst_moving = worst_moving.max((carried - truth).abs() / truth);
            worst_fixed = worst_fixed.max((left - truth).abs() / truth);
            mean_moving += (carried - truth).abs() / truth / 80.0;
        }
        eprintln!(
            "{}: worst error carried {worst_moving:.3}, fixed {worst_fixed:.3}, mean carried {mean_moving:.3}",
            r.name
        );
        assert!(
            worst_moving < worst_fixed && mean_moving < 0.08,
            "{}: worst error carried {worst_moving:.3}, fixed {worst_fixed:.3}, mean carried {mean_moving:.3}",
            r.name
        );
    }
}

#[test]
fn regions_are_carried_on_contour_runs_of_fitting_masks_only() {
    let walk = SyntheticWalk {
        frames: 12,
        ..Default::default()
    };
    let (rec, options, result) = run(&walk);
    let th = threshold(&options);
    let (masks, stance) = masks_and_stance(&rec, th);
    let surface = SequenceOptions {
        model: ObjectModel::Surface,
        ..options.clone()
    };
    let e = follow_masks(&result, &surface, &rec, &masks, &[stance], th, None).unwrap_err();
    assert!(matches!(e, IoError::InvalidInput(_)), "{e}");
    let small = RegionMasks {
        rows: 3,
        cols: 3,
        labels: vec![1; 9],
        ..masks.clone()
    };
    let e = follow_masks(&result, &options, &rec, &small, &[stance], th, None).unwrap_err();
    assert!(e.to_string().contains("do not fit"), "{e}");
    // Every region has its sensels on every frame of its stance (none missing).
    let moved: Vec<MovingRegion> =
        follow_masks(&result, &options, &rec, &masks, &[stance], th, None).unwrap();
    for r in &moved {
        for t in 0..12 {
            assert!(
                r.shares(t, rec.rows(), rec.cols()).is_some(),
                "{} frame {t}",
                r.name
            );
        }
    }
}
