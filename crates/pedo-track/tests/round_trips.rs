//! Round trips against ground truth, on a synthetic walk with a known motion (one run of it
//! with the defaults serves both tests):
//! - each **track's** round trip (the largest of its steps', sensels): the tracks of the run's
//!   own matches come back close to where they came from; the same tracks through a pair whose
//!   matches were shuffled among neighbours (each shuffled step still within the physical step
//!   rule, so the tracks take it) do not, and the ones the shuffle moved furthest from their
//!   true material point are the ones the figure flags;
//! - each **followed point's** round trip (points.csv's round_trip_sensels): the points anchored
//!   registration carries come back close to where they came from; the same points slid along
//!   the outline on one frame (the drift of a point, which the outline alone does not see) land
//!   off their material point, and the figure of that step rises for them, above every point of
//!   the clean step, while the others keep theirs.

use pedo_io::synthetic::SyntheticWalk;
use pedo_track::consistency::PairConsistency;
use pedo_track::follow::{follow_points, step_round_trips, FollowParams};
use pedo_track::pairing::StepBound;
use pedo_track::{
    chain_tracks_checked, run_sequence, RunParams, SenselAspect, SequenceResult, Track,
};
use std::sync::OnceLock;

/// The walk (14 frames, one object each) and its run with the defaults, made once.
fn walk_run() -> &'static (SyntheticWalk, SequenceResult) {
    static RUN: OnceLock<(SyntheticWalk, SequenceResult)> = OnceLock::new();
    RUN.get_or_init(|| {
        let walk = SyntheticWalk {
            frames: 14,
            ..SyntheticWalk::default()
        };
        let rec = walk.recording().unwrap();
        let options = RunParams::default().to_options(&rec).unwrap();
        let run = run_sequence(&rec, &options, &|_, _, _| {}).unwrap();
        (walk, run)
    })
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The run's pair from frame `k` to `k + 1`.
fn pair_at(r: &SequenceResult, k: usize) -> usize {
    (r.pairs.iter())
        .position(|p| r.objects[p.a].frame == k && r.objects[p.b].frame == k + 1)
        .unwrap()
}

/// The run's object on frame `k`.
fn object_on(r: &SequenceResult, k: usize) -> usize {
    r.objects.iter().position(|o| o.frame == k).unwrap()
}

/// Track `t`'s node on frame `k`, if it has a step there.
fn node_on(r: &SequenceResult, t: &Track, k: usize) -> Option<usize> {
    (t.steps.iter())
        .find(|(o, _)| r.objects[*o].frame == k)
        .map(|&(_, n)| n)
}

#[test]
fn tracks_through_shuffled_matches_have_large_round_trips_and_right_ones_small() {
    let (_, run) = walk_run();
    // The run's tracks carry the figures chain_tracks_checked gives.
    let clean = chain_tracks_checked(&run.objects, &run.pairs).unwrap();
    assert_eq!(clean.len(), run.tracks.len());
    for (k, (t, trip)) in clean.iter().enumerate() {
        assert_eq!(t, &run.tracks[k]);
        assert_eq!(*trip, run.track_round_trip(k));
        assert_eq!(trip.is_none(), t.steps.len() < 2, "track {k}");
    }

    // The pair from frame 7 to 8, half its matches shuffled: in the first half of its
    // one-to-one matches, the partners of each run of four consecutive matches turned round (a
    // node takes a neighbour's partner up to 3 nodes away); each step kept if the physical step
    // rule allows it, as the run judges it, so the tracks take the shuffled steps it lets by.
    let (k0, i) = (7, pair_at(run, 7));
    let mut pairs = run.pairs.clone();
    let p = &mut pairs[i];
    let (oa, ob) = (&run.objects[p.a], &run.objects[p.b]);
    let one: Vec<usize> = (0..p.result.pairs.len())
        .filter(|&m| !p.result.pairs[m].excess)
        .collect();
    let partners: Vec<usize> = one.iter().map(|&m| p.result.pairs[m].b).collect();
    for (block, ms) in one[..one.len() / 2].chunks(4).enumerate() {
        for (j, &m) in ms.iter().enumerate() {
            p.result.pairs[m].b = partners[block * 4 + ms.len() - 1 - j];
        }
    }
    let bound = StepBound::new(oa, ob, SenselAspect::SQUARE);
    p.trackable = (p.result.pairs.iter())
        .map(|m| !m.excess && bound.allows(oa.shape.point(m.a), ob.shape.point(m.b)))
        .collect();
    let (_, steps) =
        PairConsistency::with_steps(&oa.shape, &ob.shape, &p.result.pairs, SenselAspect::SQUARE)
            .unwrap();
    p.step_round_trips = steps;
    let shuffled = chain_tracks_checked(&run.objects, &pairs).unwrap();

    // The tracks from frame 0 through frames 7 and 8, by the node they start on: the figure
    // and where the track is on frame 8.
    type Through = std::collections::BTreeMap<usize, (f64, [f64; 2])>;
    let through = |tracks: &[(Track, Option<f64>)]| -> Through {
        (tracks.iter())
            .filter(|(t, _)| run.objects[t.steps[0].0].frame == 0)
            .filter_map(|(t, trip)| {
                node_on(run, t, k0)?;
                let b = ob.shape.point(node_on(run, t, k0 + 1)?);
                Some((t.steps[0].1, (trip.unwrap(), [b[0], b[1]])))
            })
            .collect()
    };
    let (before, after) = (through(&clean), through(&shuffled));
    // Without the shuffle every track comes back within a sensel.
    assert!(before.len() > 40, "{}", before.len());
    assert!(before.values().all(|x| x.0 < 1.0), "{before:?}");
    // After it, a track is right where it steps where the run's own matches took it, and wrong
    // where the shuffle put it a node or more away.
    let (mut right, mut wrong) = (Vec::new(), Vec::new());
    for (start, (trip, at)) in &after {
        let Some((_, was)) = before.get(start) else {
            continue;
        };
        match (at[0] - was[0]).hypot(at[1] - was[1]) {
            d if d < 1e-9 => right.push(*trip),
            d if d > 0.5 => wrong.push(*trip),
            _ => {}
        }
    }
    assert!(
        right.len() >= 20 && wrong.len() >= 10,
        "{} {}",
        right.len(),
        wrong.len()
    );
    let clean_max = before.values().map(|x| x.0).fold(0.0, f64::max);
    let beyond = wrong.iter().filter(|&&d| d > clean_max).count();
    let (m_clean, m_right, m_wrong) = (
        median(before.values().map(|x| x.0).collect()),
        median(right),
        median(wrong.clone()),
    );
    eprintln!("median round trip: clean {m_clean:.3}, right {m_right:.3}, wrong {m_wrong:.3}; {beyond} of {} wrong beyond the clean run's largest {clean_max:.3}", wrong.len());
    // Right tracks come back well within a sensel; those with a wrong step by twice as far or
    // more, and most of them further than any track of the clean run (so no constant figure
    // passes).
    assert!(m_clean < 0.6 && m_right < 0.6, "{m_clean} {m_right}");
    assert!(
        m_wrong > 1.8 * m_right.max(m_clean),
        "{m_wrong} vs {m_right}"
    );
    assert!(2 * beyond > wrong.len(), "{beyond} of {}", wrong.len());
}

#[test]
fn points_slid_off_their_material_point_on_one_step_have_large_round_trips() {
    let (walk, run) = walk_run();
    let aspect = SenselAspect::SQUARE;
    let followed = follow_points(run, aspect, &FollowParams::default(), &[]).unwrap();
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
    let (a, b) = (object_on(run, k0), object_on(run, k0 + 1));
    let at = |p: &pedo_track::follow::FollowedPoint, o: usize| {
        let s = p.steps.iter().position(|&(q, _)| q == o)?;
        Some((s, p.steps[s].1))
    };
    let moves: Vec<([f64; 2], [f64; 2])> = (points.iter())
        .map(|p| (at(p, a).unwrap().1, at(p, b).unwrap().1))
        .collect();
    let clean = step_round_trips(run, a, b, aspect, &moves).unwrap();
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
    let after = step_round_trips(run, a, b, aspect, &slid).unwrap();
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

#[test]
fn the_prior_along_the_outline_is_off_on_frames_far_apart() {
    // The walk's frames are far apart (the foot turns about a degree a frame): its points move
    // more than `prior_none` a frame, so the default points are those without the prior.
    let (_, run) = walk_run();
    let aspect = SenselAspect::SQUARE;
    let defaults = FollowParams::default();
    assert!(defaults.inertia_along > 0.0);
    let without = FollowParams {
        inertia_along: 0.0,
        ..defaults
    };
    let with = follow_points(run, aspect, &defaults, &[]).unwrap();
    let plain = follow_points(run, aspect, &without, &[]).unwrap();
    assert_eq!(with, plain);
}
