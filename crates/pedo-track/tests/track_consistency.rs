//! Each track's round trip (the largest of its steps', sensels) against ground truth: on a
//! synthetic walk with a known motion, the tracks of the run's own matches come back close to
//! where they came from; the same tracks through a pair whose matches were shuffled among
//! neighbours (each shuffled step still within the physical step rule, so the tracks take it)
//! do not, and the ones the shuffle moved furthest from their true material point are the ones
//! the figure flags.

use pedo_io::synthetic::SyntheticWalk;
use pedo_track::consistency::PairConsistency;
use pedo_track::pairing::StepBound;
use pedo_track::{
    chain_tracks_checked, run_sequence, RunParams, SenselAspect, SequenceResult, Track,
};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The run's pair from frame `k` to `k + 1` (one object per frame on this walk).
fn pair_at(r: &SequenceResult, k: usize) -> usize {
    (r.pairs.iter())
        .position(|p| r.objects[p.a].frame == k && r.objects[p.b].frame == k + 1)
        .unwrap()
}

/// Track `t`'s node on frame `k`, if it has a step there.
fn node_on(r: &SequenceResult, t: &Track, k: usize) -> Option<usize> {
    (t.steps.iter())
        .find(|(o, _)| r.objects[*o].frame == k)
        .map(|&(_, n)| n)
}

#[test]
fn tracks_through_shuffled_matches_have_large_round_trips_and_right_ones_small() {
    let walk = SyntheticWalk {
        frames: 14,
        ..SyntheticWalk::default()
    };
    let rec = walk.recording().unwrap();
    let options = RunParams::default().to_options(&rec).unwrap();
    let run = run_sequence(&rec, &options, &|_, _, _| {}).unwrap();
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
    let (k0, i) = (7, pair_at(&run, 7));
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
                node_on(&run, t, k0)?;
                let b = ob.shape.point(node_on(&run, t, k0 + 1)?);
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
