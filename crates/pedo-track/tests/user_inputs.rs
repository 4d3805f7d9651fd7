//! The points and regions a user gives (`RunInputs`), followed through a synthetic walk with a
//! known motion: a point keeps to its material point, a region's force to the true region's,
//! and bad inputs are typed errors naming what is wrong.

use modal_core::PathOrRows;
use pedo_io::synthetic::SyntheticWalk;
use pedo_io::{IoError, Recording};
use pedo_track::follow::{follow_seeded, run_points, FollowParams, FollowedPoints, Seed, Seeded};
use pedo_track::{run_sequence, RunInputs, RunParams, SequenceOptions, SequenceResult};

fn run(rec: &Recording, inputs: RunInputs) -> pedo_io::Result<(SequenceOptions, SequenceResult)> {
    let params = RunParams {
        inputs,
        ..RunParams::default()
    };
    let options = params.to_options(rec)?;
    let result = run_sequence(rec, &options, &|_, _, _| {})?;
    Ok((options, result))
}

fn followed(
    rec: &Recording,
    inputs: RunInputs,
) -> pedo_io::Result<(SequenceResult, FollowedPoints, SequenceOptions)> {
    let (options, result) = run(rec, inputs)?;
    let points = run_points(&result, &options)?.expect("a contour run");
    Ok((result, points, options))
}

/// The forefoot third of frame `t`'s contact region: the loaded sensels in the top third of
/// its rows (the toes are at row 0).
fn forefoot_third(rec: &Recording, t: usize, threshold: f64) -> Vec<Vec<f64>> {
    let g = rec.frame(t).unwrap();
    let loaded = |r: usize, c: usize| g.get(r, c) >= threshold && g.get(r, c) > 0.0;
    let rows: Vec<usize> = (0..rec.rows())
        .filter(|&r| (0..rec.cols()).any(|c| loaded(r, c)))
        .collect();
    let (top, bottom) = (rows[0], *rows.last().unwrap());
    let cut = top + (bottom - top + 1) / 3;
    (0..rec.rows())
        .map(|r| {
            (0..rec.cols())
                .map(|c| f64::from(u8::from(r < cut && loaded(r, c))))
                .collect()
        })
        .collect()
}

#[test]
fn a_given_interior_point_stays_within_a_sensel_of_its_material_point() {
    let walk = SyntheticWalk {
        frames: 60,
        ..Default::default()
    };
    let rec = walk.recording().unwrap();
    let c = walk.centre();
    let given = vec![vec![c[0], c[1] - 10.0], vec![c[0] + 2.0, c[1] + 12.0]];
    let (result, points, _) = followed(
        &rec,
        RunInputs {
            points: Some(PathOrRows::Rows(given.clone())),
            ..Default::default()
        },
    )
    .unwrap();
    let user: Vec<_> = (points.points.iter())
        .filter(|p| matches!(p.kind, Seeded::Point(_)))
        .collect();
    assert_eq!(user.len(), 2);
    // The outline's default points are followed beside them.
    assert!(points.points.iter().any(|p| p.kind == Seeded::Outline));
    for (p, g) in user.iter().zip(&given) {
        assert_eq!(
            result.objects[p.steps[0].0].frame, 0,
            "given on the first frame holding it"
        );
        for &(o, q) in &p.steps {
            let truth = walk.true_position(result.objects[o].frame, [g[0], g[1]]);
            let e = (q[0] - truth[0]).hypot(q[1] - truth[1]);
            assert!(
                e < 1.0,
                "frame {}: {e:.3} sensels off",
                result.objects[o].frame
            );
        }
        assert_eq!(p.steps.len(), 60);
    }
}

#[test]
fn a_point_given_in_mm_on_a_later_frame_is_carried_back_to_the_first_frame_of_its_contact() {
    let walk = SyntheticWalk {
        frames: 40,
        ..Default::default()
    };
    let rec = walk.recording().unwrap();
    let c = walk.centre();
    // Where the material point at the centre lies on frame 20, in mm (5 mm sensels).
    let q = walk.true_position(20, c);
    let dir = std::env::temp_dir().join(format!("pedomatch-points-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("points.csv");
    std::fs::write(
        &file,
        format!(
            "name,x_mm,y_mm,frame\nmid,{},{},20\n",
            q[0] * 5.0,
            q[1] * 5.0
        ),
    )
    .unwrap();
    let (result, points, options) = followed(
        &rec,
        RunInputs {
            points: Some(PathOrRows::Path(file.display().to_string())),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(options.inputs.points[0].name, "mid");
    let p = points
        .points
        .iter()
        .find(|p| p.kind == Seeded::Point(0))
        .unwrap();
    // Seeded on frame 20, its steps run from the contact's first frame to its last, in order.
    assert_eq!(result.objects[p.seed.0].frame, 20);
    let frames: Vec<usize> = p.steps.iter().map(|s| result.objects[s.0].frame).collect();
    assert_eq!(frames, (0..40).collect::<Vec<_>>());
    assert_eq!(
        p.steps[20].1, q,
        "its own frame holds it where it was given"
    );
    for &(o, xy) in &p.steps {
        let truth = walk.true_position(result.objects[o].frame, c);
        let e = (xy[0] - truth[0]).hypot(xy[1] - truth[1]);
        assert!(
            e < 1.0,
            "frame {}: {e:.3} sensels off",
            result.objects[o].frame
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn points_carried_forward_to_the_last_frame_and_back_land_near_their_start() {
    let walk = SyntheticWalk {
        frames: 30,
        ..Default::default()
    };
    let rec = walk.recording().unwrap();
    let c = walk.centre();
    let starts = [
        [c[0], c[1] - 10.0],
        [c[0] + 2.0, c[1] + 12.0],
        [c[0] - 3.0, c[1]],
    ];
    let (_, result) = run(&rec, RunInputs::default()).unwrap();
    let aspect = pedo_track::SenselAspect::SQUARE;
    let params = FollowParams::default();
    let seeds_on = |object: usize, xy: &[[f64; 2]]| -> Vec<Seed> {
        (xy.iter().enumerate())
            .map(|(k, &xy)| Seed {
                object,
                xy,
                kind: Seeded::Point(k),
            })
            .collect()
    };
    let last = result.objects.len() - 1;
    assert_eq!(result.objects[last].frame, 29);
    // Forwards from frame 0 (nothing before it), then back from where they are on frame 29.
    let there =
        follow_seeded(&result, aspect, &params, &seeds_on(0, &starts), false, true).unwrap();
    let ends: Vec<[f64; 2]> = (there.points.iter())
        .map(|p| {
            assert_eq!(p.steps.len(), 30, "frame 0 on, no backward part");
            p.steps[29].1
        })
        .collect();
    let back = follow_seeded(
        &result,
        aspect,
        &params,
        &seeds_on(last, &ends),
        false,
        true,
    )
    .unwrap();
    for (p, s) in back.points.iter().zip(&starts) {
        assert_eq!(p.steps.len(), 30, "back to frame 0");
        let (o, xy) = p.steps[0];
        assert_eq!(result.objects[o].frame, 0);
        let d = (xy[0] - s[0]).hypot(xy[1] - s[1]);
        assert!(d < 0.5, "lands {d:.3} sensels from its start");
        // And on every frame between, the backward way keeps within a sensel of the truth.
        for &(o, q) in &p.steps {
            let truth = walk.true_position(result.objects[o].frame, *s);
            let e = (q[0] - truth[0]).hypot(q[1] - truth[1]);
            assert!(e < 1.0, "{s:?} frame {}: {e:.3}", result.objects[o].frame);
        }
    }
}

#[test]
fn a_forefoot_region_carries_the_true_regions_force() {
    let walk = SyntheticWalk {
        frames: 60,
        ..Default::default()
    };
    let rec = walk.recording().unwrap();
    let threshold = rec.noise_threshold.unwrap_or(0.0);
    let mask = forefoot_third(&rec, 0, threshold);
    let (result, points, options) = followed(
        &rec,
        RunInputs {
            regions: Some(PathOrRows::Rows(mask.clone())),
            ..Default::default()
        },
    )
    .unwrap();
    let region = &options.inputs.regions[0];
    let cols = rec.cols();
    let mut worst: f64 = 0.0;
    let mut worst_fixed: f64 = 0.0;
    for t in (0..60).step_by(5) {
        let g = rec.frame(t).unwrap();
        // The true region on frame t: the sensels whose material point lay in the mask on frame 0.
        let truth: Vec<bool> = (0..rec.rows() * cols)
            .map(|i| {
                let p = walk.reference_position(t, [(i % cols) as f64, (i / cols) as f64]);
                let (c, r) = (p[0].round(), p[1].round());
                c >= 0.0
                    && r >= 0.0
                    && (c as usize) < cols
                    && (r as usize) < rec.rows()
                    && mask[r as usize][c as usize] == 1.0
            })
            .collect();
        let want = rec.cells_measures(&g, threshold, &truth).total_force;
        let outline: Vec<[f64; 2]> = (points.points.iter())
            .filter(|p| p.kind == Seeded::Region(0))
            .filter_map(|p| p.steps.iter().find(|(o, _)| result.objects[*o].frame == t))
            .map(|&(_, xy)| xy)
            .collect();
        let moving: Vec<bool> = (0..rec.rows() * cols)
            .map(|i| {
                pedo_io::contour::point_in_polygon([(i % cols) as f64, (i / cols) as f64], &outline)
            })
            .collect();
        let got = rec.cells_measures(&g, threshold, &moving).total_force;
        let fixed = rec.cells_measures(&g, threshold, &region.cells).total_force;
        worst = worst.max((got - want).abs() / want);
        worst_fixed = worst_fixed.max((fixed - want).abs() / want);
    }
    assert!(
        worst < 0.05,
        "moving region: worst force error {:.1} %",
        worst * 100.0
    );
    // The fixed mask misses the moving forefoot by far more.
    assert!(
        worst_fixed > 2.0 * worst,
        "fixed {worst_fixed:.3}, moving {worst:.3}"
    );
}

#[test]
fn bad_points_and_regions_are_typed_errors_naming_them() {
    let walk = SyntheticWalk {
        frames: 6,
        ..Default::default()
    };
    let rec = walk.recording().unwrap();
    let invalid = |r: pedo_io::Result<_>| match r {
        Err(IoError::InvalidInput(m)) => m,
        Err(e) => panic!("not InvalidInput: {e}"),
        Ok(_) => panic!("no error"),
    };
    // A point outside every object.
    let outside = RunInputs {
        points: Some(PathOrRows::Rows(vec![vec![1.0, 1.0]])),
        ..Default::default()
    };
    let m = invalid(followed(&rec, outside).map(|_| ()));
    assert!(m.contains("\"p1\"") && m.contains("no object"), "{m}");
    // NaN.
    let nan = RunInputs {
        points: Some(PathOrRows::Rows(vec![vec![f64::NAN, 1.0]])),
        ..Default::default()
    };
    let m = invalid(run(&rec, nan).map(|_| ()));
    assert!(m.contains("row 0"), "{m}");
    // A mask of the wrong shape.
    let wrong = RunInputs {
        regions: Some(PathOrRows::Rows(vec![vec![0.0, 1.0]; 3])),
        ..Default::default()
    };
    let m = invalid(run(&rec, wrong).map(|_| ()));
    assert!(m.contains("3 × 2") && m.contains("84 × 40"), "{m}");
    // A frame beyond the recording.
    let late = RunInputs {
        points: Some(PathOrRows::Rows(vec![vec![20.0, 40.0]])),
        points_frame: Some(6),
        ..Default::default()
    };
    let m = invalid(run(&rec, late).map(|_| ()));
    assert!(m.contains("frame 6"), "{m}");
    // Points for a model without contact outlines.
    let surface = RunParams {
        model: pedo_track::ObjectModel::Surface,
        inputs: RunInputs {
            points: Some(PathOrRows::Rows(vec![vec![20.0, 40.0]])),
            ..Default::default()
        },
        ..RunParams::default()
    };
    assert!(surface.to_options(&rec).is_err());
}
