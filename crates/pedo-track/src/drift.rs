//! Drift correction of node tracks: each object is matched against a reference object as well as
//! against its predecessor.
//!
//! Chaining frame-to-frame matches accumulates an error at every step: a node can only go to a
//! node, so each link rounds the true position to the nearest node of the next outline (up to
//! half a node spacing), and these roundings add up like a random walk (about two spacings after
//! 50 frames). With a reference interval `K`, frames `start, start + K, start + 2K, …` are
//! reference frames: every object is also matched directly against its ancestor on the last
//! reference frame before it (a reference frame's object against the previous reference frame),
//! and a track continues through that match first. The error then grows with the number of
//! reference links (one per `K` frames), not with the number of frames.
//!
//! An object's ancestor is followed through one-to-one continuations only (a region that splits or
//! merges has none), so a part is never matched against a whole. A reference match moves a track
//! only to a node near the track's last node (within [`JUMP_LIMIT`] node spacings), so a wrong
//! reference match cannot make a track jump; the predecessor's match serves those nodes instead.

use crate::{PairMatch, SequenceObject, Track};

/// A reference match may carry a track to a node at most this many node spacings (the object's
/// median distance between neighbouring nodes) from the track's last node.
pub const JUMP_LIMIT: f64 = 3.0;

/// The unique one-to-one predecessor of every object: `a` is the parent of `b` when `(a, b)` is
/// the only candidate pair into `b` and the only one out of `a`.
fn parents(n_objects: usize, candidates: &[(usize, usize)]) -> Vec<Option<usize>> {
    let mut outgoing = vec![0usize; n_objects];
    let mut incoming = vec![0usize; n_objects];
    for &(a, b) in candidates {
        outgoing[a] += 1;
        incoming[b] += 1;
    }
    let mut parent = vec![None; n_objects];
    for &(a, b) in candidates {
        if outgoing[a] == 1 && incoming[b] == 1 {
            parent[b] = Some(a);
        }
    }
    parent
}

/// The reference pairs `(ancestor, object)` for reference frames every `interval` frames from
/// `start`: an object of frame `t` is paired with its ancestor on the last reference frame before
/// `t` (a reference frame's object with its ancestor on the previous reference frame). Pairs that
/// would repeat a candidate pair (ancestor one frame back) are left out, and so are objects whose
/// chain of one-to-one continuations breaks before the reference frame.
pub fn reference_pairs(
    objects: &[SequenceObject],
    candidates: &[(usize, usize)],
    start: usize,
    interval: usize,
) -> Vec<(usize, usize)> {
    reference_pairs_every(objects, candidates, start, interval, 1)
}

/// [`reference_pairs`] of a run that keeps every `step`-th frame from `start` (`interval` a
/// multiple of `step`): an object continues the one `step` frames before it, and a reference
/// pair spans at least two kept frames.
pub fn reference_pairs_every(
    objects: &[SequenceObject],
    candidates: &[(usize, usize)],
    start: usize,
    interval: usize,
    step: usize,
) -> Vec<(usize, usize)> {
    let step = step.max(1);
    if interval < 2 {
        return Vec::new();
    }
    let parent = parents(objects.len(), candidates);
    let mut out = Vec::new();
    for (o, obj) in objects.iter().enumerate() {
        let t = obj.frame;
        if t < start {
            continue;
        }
        let mut reference = start + (t - start) / interval * interval;
        if reference == t {
            match t.checked_sub(interval) {
                Some(r) if r >= start => reference = r,
                _ => continue,
            }
        }
        let mut ancestor = o;
        while objects[ancestor].frame > reference {
            match parent[ancestor] {
                Some(p) if objects[p].frame + step == objects[ancestor].frame => ancestor = p,
                _ => break,
            }
        }
        if objects[ancestor].frame == reference && t - reference >= 2 * step {
            out.push((ancestor, o));
        }
    }
    out
}

/// Median distance between neighbouring nodes of an object (its node spacing).
fn node_spacing(obj: &SequenceObject) -> f64 {
    let n = obj.shape.len();
    let mut d: Vec<f64> = (0..n)
        .map(|i| dist(obj.shape.point(i), obj.shape.point((i + 1) % n)))
        .filter(|d| d.is_finite() && *d > 0.0)
        .collect();
    if d.is_empty() {
        return 1.0;
    }
    d.sort_by(f64::total_cmp);
    d[d.len() / 2]
}

fn dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt()
}

/// Chains matches into tracks like [`crate::chain_tracks`], with the reference
/// matches (pairs `(ancestor, object)`) taking precedence: a node matched one-to-one to a node of
/// its object's reference continues that node's track, when the track's last step is on one of
/// the object's predecessors and lies within [`JUMP_LIMIT`] spacings. The remaining nodes follow
/// their predecessor's matches where the pair's [`crate::pairing::StepBound`] allows the step
/// ([`PairMatch::trackable`]), and nodes
/// with neither start new tracks.
///
/// # Errors
/// A pair (of either list) that does not lead forward (`a < b`) between the `objects`, or that
/// names a node beyond its objects' nodes: [`IoError::InvalidInput`](pedo_io::IoError), as
/// [`crate::chain_tracks`] reports it.
pub fn anchored_tracks(
    objects: &[SequenceObject],
    pairs: &[PairMatch],
    reference: &[PairMatch],
) -> pedo_io::Result<Vec<Track>> {
    for p in pairs.iter().chain(reference) {
        check_pair(objects, p)?;
    }
    let mut track_of: Vec<Vec<Option<usize>>> =
        objects.iter().map(|o| vec![None; o.shape.len()]).collect();
    let mut tracks: Vec<Track> = Vec::new();
    let mut incoming: Vec<Vec<&PairMatch>> = vec![Vec::new(); objects.len()];
    for p in pairs {
        incoming[p.b].push(p);
    }
    let mut anchors: Vec<Vec<&PairMatch>> = vec![Vec::new(); objects.len()];
    for p in reference {
        anchors[p.b].push(p);
    }
    for o in 0..objects.len() {
        let limit = JUMP_LIMIT * node_spacing(&objects[o]);
        let predecessors: Vec<usize> = incoming[o].iter().map(|p| p.a).collect();
        for p in &anchors[o] {
            for mp in p.result.pairs.iter().filter(|mp| !mp.excess) {
                if track_of[o][mp.b].is_some() {
                    continue;
                }
                let Some(t) = track_of[p.a][mp.a] else {
                    continue;
                };
                let Some(&(last_o, last_n)) = tracks[t].steps.last() else {
                    continue;
                };
                let near = dist(
                    objects[last_o].shape.point(last_n),
                    objects[o].shape.point(mp.b),
                ) <= limit;
                if predecessors.contains(&last_o) && near {
                    tracks[t].steps.push((o, mp.b));
                    track_of[o][mp.b] = Some(t);
                }
            }
        }
        for p in &incoming[o] {
            for (k, mp) in p
                .result
                .pairs
                .iter()
                .enumerate()
                .filter(|(_, mp)| !mp.excess)
            {
                let trackable = p.trackable.get(k).copied().unwrap_or(false);
                if track_of[o][mp.b].is_some() || !trackable {
                    continue;
                }
                if let Some(t) = track_of[p.a][mp.a]
                    && tracks[t].steps.last().map(|s| s.0) == Some(p.a)
                {
                    tracks[t].steps.push((o, mp.b));
                    track_of[o][mp.b] = Some(t);
                }
            }
        }
        for (node, slot) in track_of[o].iter_mut().enumerate() {
            if slot.is_none() {
                *slot = Some(tracks.len());
                tracks.push(Track {
                    steps: vec![(o, node)],
                });
            }
        }
    }
    Ok(tracks)
}

/// A pair fit to chain: forward between the objects, its matches on nodes they have (the
/// checks and messages of the streaming chaining).
fn check_pair(objects: &[SequenceObject], p: &PairMatch) -> pedo_io::Result<()> {
    p.check_forward(0..objects.len())?;
    let (na, nb) = (objects[p.a].shape.len(), objects[p.b].shape.len());
    match p.result.pairs.iter().find(|m| m.a >= na || m.b >= nb) {
        Some(m) => Err(p.beyond_nodes(m, na, nb)),
        None => Ok(()),
    }
}
