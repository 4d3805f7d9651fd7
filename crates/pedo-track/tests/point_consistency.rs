//! Each followed point's round trip (points.csv's round_trip_sensels) against ground truth: on a
//! synthetic walk with a known motion, the points anchored registration carries come back close
//! to where they came from; the same points slid along the outline on one frame (the drift of a
//! point, which the outline alone does not see) land off their material point, and the figure of
//! that step rises for them, above every point of the clean step, while the others keep theirs.

use pedo_io::synthetic::SyntheticWalk;
use pedo_track::follow::{follow_points, step_round_trips, FollowParams};
use pedo_track::{run_sequence, RunParams, SenselAspect, SequenceResult};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The run's object on frame `k` (one object per frame on this walk).
fn object_on(r: &SequenceResult, k: usize) -> usize {
    r.objects.iter().position(|o| o.frame == k).unwrap()
}

#[test]
fn points_slid_off_their_material_point_on_one_step_have_large_round_trips() {
    let walk = SyntheticWalk {
        frames: 14,
        ..SyntheticWalk::default()
    };
    let rec = walk.recording().unwrap();
    let options = RunParams::default().to_options(&rec).unwrap();
    let run = run_sequence(&rec, &options, &|_, _, _| {}).unwrap();
    let aspect = SenselAspect::SQUARE;
    let followed = follow_points(&run, aspect, &FollowParams::default(), &[]).unwrap();
    // One lineage of outline points from frame 0: no figure on the seed frame, one on every
    // frame after (each pair has a field).
    let points = &followed.points;
    assert!(points.len() > 40, "{}", points.len());
    for p in points {
        assert_eq!(p.round_trips.len(), p.steps.len());
        assert_eq!(p.round_trips[0], None);
        assert!(p.round_trips[1..].iter().all(Option::is_some), "{p:?}");
    }

    // The step from frame 7 to 8: each point's positions on both, its figure as followed.
    let k0 = 7;
    let (a, b) = (object_on(&run, k0), object_on(&run, k0 + 1));
    let at = |p: &pedo_track::follow::FollowedPoint, o: usize| {
        let s = p.steps.iter().position(|&(q, _)| q == o)?;
        Some((s, p.steps[s].1))
    };
    let moves: Vec<([f64; 2], [f64; 2])> = (points.iter())
        .map(|p| (at(p, a).unwrap().1, at(p, b).unwrap().1))
        .collect();
    let clean = step_round_trips(&run, a, b, aspect, &moves).unwrap();
    for (p, &d) in points.iter().zip(&clean) {
        let (s, _) = at(p, b).unwrap();
        assert_eq!(
            p.round_trips[s],
            Some(d),
            "the figure followed is the step's"
        );
    }

    // The first half of the outline's points slid along the outline on frame 8, each onto its
    // second neighbour's position there (the outline points are in outline order): they keep to
    // the outline, but not to their material point.
    let n = points.len();
    let slid: Vec<([f64; 2], [f64; 2])> = (0..n)
        .map(|i| match i < n / 2 {
            true => (moves[i].0, moves[(i + 2) % n].1),
            false => moves[i],
        })
        .collect();
    let after = step_round_trips(&run, a, b, aspect, &slid).unwrap();
    let error = |q: [f64; 2], i: usize| {
        let truth = walk.true_position(k0 + 1, points[i].steps[0].1);
        (q[0] - truth[0]).hypot(q[1] - truth[1])
    };
    let (mut err_clean, mut err_slid) = (Vec::new(), Vec::new());
    for i in 0..n {
        err_clean.push(error(moves[i].1, i));
        if i < n / 2 {
            err_slid.push(error(slid[i].1, i));
        } else {
            assert_eq!(after[i], clean[i], "point {i}, not slid, keeps its figure");
        }
    }
    let clean_max = clean.iter().copied().fold(0.0, f32::max);
    let trip_slid: Vec<f32> = after[..n / 2].to_vec();
    let beyond = trip_slid.iter().filter(|&&d| d > clean_max).count();
    let m = |v: &[f32]| median(v.iter().map(|&d| f64::from(d)).collect());
    eprintln!(
        "round trip: clean median {:.3} (largest {clean_max:.3}), slid median {:.3}, {beyond} of {} beyond; \
         true error: clean median {:.3}, slid median {:.3}",
        m(&clean),
        m(&trip_slid),
        trip_slid.len(),
        median(err_clean.clone()),
        median(err_slid.clone()),
    );
    // Slid, the points are off their material point by about the slide; the clean step keeps
    // them within a fraction of a sensel, and comes back within the fields' smoothing (the
    // walk's frames are far apart: the foot turns by about a degree a frame).
    assert!(median(err_slid) > 1.0 && median(err_clean) < 0.5);
    assert!(m(&clean) < 0.8 && clean_max < 1.5, "{clean:?}");
    // Their figure rises above every point of the clean step for nearly all of them.
    assert!(
        10 * beyond >= 9 * trip_slid.len(),
        "{beyond} of {}",
        trip_slid.len()
    );
    assert!(m(&trip_slid) > 3.0 * m(&clean));
}
