//! Tracks that stay on the material at merges and splits: on frames of the F-Scan walk where the
//! heel and forefoot outlines join into the whole foot and part again, a part paired with the
//! whole is matched to its own portion of the whole, and no track step is longer than the
//! boundary's own motion allows.

use modal_core::{match_shapes, MatchParams, Prealign, Shape};
use pedo_io::read_recording;
use pedo_track::pairing::step_allowed;
use pedo_track::{run_sequence, FrameRange, RunParams, SequenceResult};

/// Frames 42..48 of the walk: regions merge into the whole-foot outline (43 → 44, 44 → 45) and
/// the whole splits again (45 → 46).
fn merge_and_split() -> (RunParams, SequenceResult) {
    let rec = read_recording(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../pedo-io/tests/data/FrasP01L.asf"
    ))
    .unwrap();
    let params = RunParams {
        frames: Some(FrameRange {
            start: 42,
            end: Some(48),
        }),
        ..Default::default()
    };
    let options = params.to_options(&rec).unwrap();
    let run = run_sequence(&rec, &options, &|_, _, _| {}).unwrap();
    (params, run)
}

/// Distance (sensels) from `p` to the nearest node of `s`.
fn to_nodes(p: &[f64], s: &Shape) -> f64 {
    (0..s.len())
        .map(|k| (s.point(k)[0] - p[0]).hypot(s.point(k)[1] - p[1]))
        .fold(f64::INFINITY, f64::min)
}

/// `(part, whole)` object indices of every matched pair that joins a part and a whole.
fn part_whole_pairs(run: &SequenceResult) -> Vec<(usize, usize, usize)> {
    run.pairs
        .iter()
        .enumerate()
        .filter_map(|(k, p)| {
            let merged = run
                .merges
                .iter()
                .any(|(is, j)| *j == p.b && is.contains(&p.a));
            let split = run
                .splits
                .iter()
                .any(|(i, js)| *i == p.a && js.contains(&p.b));
            match (merged, split) {
                (true, _) => Some((k, p.a, p.b)),
                (false, true) => Some((k, p.b, p.a)),
                _ => None,
            }
        })
        .collect()
}

#[test]
fn a_part_is_matched_to_its_own_portion_of_the_whole() {
    let (params, run) = merge_and_split();
    let parts = part_whole_pairs(&run);
    // The foot's outline as it merges with the toes' (109 → 118 nodes) and the whole foot
    // parting into the forefoot (148 → 90 nodes): the part at least a third smaller.
    let size = |o: usize| run.objects[o].shape.len();
    assert!(
        parts
            .iter()
            .any(|&(_, part, whole)| 2 * size(whole) >= 3 * size(part)),
        "frames 42..48 have a part paired with a whole"
    );
    let mut spread_reach = 0.0f64;
    for (k, part, whole) in parts {
        let p = &run.pairs[k];
        let (sp, sw) = (&run.objects[part].shape, &run.objects[whole].shape);
        let whole_node = |a: usize, b: usize| if whole == p.b { b } else { a };
        let part_node = |a: usize, b: usize| if whole == p.b { a } else { b };
        let one_to_one: Vec<_> = p.result.pairs.iter().filter(|m| !m.excess).collect();
        assert!(one_to_one.len() >= sp.len() / 2, "the part is matched");
        // Every match lands on the whole's nodes near the part (its portion: within 5 node
        // spacings, about 5 sensels), and few are long.
        let mut far = 0;
        for m in &one_to_one {
            let on_whole = sw.point(whole_node(m.a, m.b));
            assert!(
                to_nodes(on_whole, sp) <= 5.5,
                "{on_whole:?} is off the part"
            );
            let on_part = sp.point(part_node(m.a, m.b));
            let step = (on_whole[0] - on_part[0]).hypot(on_whole[1] - on_part[1]);
            far += usize::from(step > 5.0);
        }
        // Where the part's outline moved beyond the whole's (the forefoot, 90 nodes, spreads
        // outwards as it parts from the whole foot, 148 nodes, between frames 45 and 46), its
        // new nodes have no partner near them and their matches are long (17 of 90); the step
        // bound keeps such matches out of the tracks (the next test).
        assert!(far * 5 <= one_to_one.len(), "{far} long matches");
        // Normalised onto the whole (the robust pre-alignment of two unrelated shapes), a part is
        // spread over it: its matches reach nodes of the whole far from the part.
        let opts = MatchParams {
            prealign: Some(Prealign::Robust),
            ..params.matching.clone()
        }
        .to_match_options(2, true)
        .unwrap();
        if 2 * sw.len() < 3 * sp.len() {
            continue;
        }
        let (a, b) = (&run.objects[p.a].shape, &run.objects[p.b].shape);
        let spread = match_shapes(a, b, &opts).unwrap();
        let reach = spread
            .pairs
            .iter()
            .filter(|m| !m.excess)
            .map(|m| to_nodes(sw.point(whole_node(m.a, m.b)), sp))
            .fold(0.0, f64::max);
        spread_reach = spread_reach.max(reach);
    }
    // Twice the portion's reach (5.5 sensels, above): 14 sensels for the forefoot parting from
    // the whole foot.
    assert!(
        spread_reach > 11.0,
        "normalised onto the whole, a part reaches {spread_reach} sensels away"
    );
}

#[test]
fn no_track_step_is_longer_than_the_boundary_moved() {
    let (_, run) = merge_and_split();
    let mut steps = 0;
    for t in &run.tracks {
        for w in t.steps.windows(2) {
            let ((oa, na), (ob, nb)) = (w[0], w[1]);
            let (a, b) = (&run.objects[oa], &run.objects[ob]);
            assert_eq!(a.frame + 1, b.frame);
            assert!(
                step_allowed(a.shape.point(na), b.shape.point(nb), &b.shape),
                "track step from frame {} node {na} to node {nb}",
                a.frame
            );
            steps += 1;
        }
    }
    // The bound ends the dishonest steps only: most one-to-one matches still extend a track.
    let matches: usize = run.pairs.iter().map(|p| p.result.one_to_one_count()).sum();
    assert!(
        steps * 10 >= matches * 8,
        "{steps} steps for {matches} matches"
    );
}
