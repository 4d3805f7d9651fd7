//! Matches chained into node tracks: a track follows one node from object to object through
//! the pairs, as long as each step is an honest one ([`PairMatch::trackable`]).

use crate::*;
use pedo_io::Result;
use std::collections::HashMap;

/// Chains pair matches into tracks ([`chain_tracks`]), fed all at once (a whole run) or a
/// window at a time ([`stream_sequence`]); only the open tracks are held.
#[derive(Default)]
pub(crate) struct Chainer {
    /// The number of the front pending track.
    first: usize,
    /// The tracks not handed over yet.
    pending: std::collections::VecDeque<Open>,
    /// The track of each node of the objects a pair may still leave (`NO_TRACK`: none).
    rows: std::collections::BTreeMap<usize, Vec<u32>>,
    /// The last object a known pair leaves each object of `rows` for.
    last_use: HashMap<usize, usize>,
}

const NO_TRACK: u32 = u32::MAX;

/// A track not handed over yet.
struct Open {
    track: Track,
    /// Whether it can grow no more.
    ended: bool,
    /// The largest round trip of its steps so far ([`PairMatch::step_round_trips`]); `None`
    /// once a step has none (a pair without a field: surfaces).
    worst: Option<f64>,
}

/// Where [`Chainer`] hands each track: its number, the track and its round trip (sensels, the
/// largest of its steps'; `None` when a step has none, and for a track of one step).
pub(crate) type EmitTrack<'a> = dyn FnMut(usize, Track, Option<f64>) -> Result<()> + 'a;

impl Chainer {
    /// The first object of the front open track (all objects before it are done with).
    pub(crate) fn first_object(&self) -> Option<usize> {
        self.pending
            .front()
            .and_then(|o| o.track.steps.first())
            .map(|s| s.0)
    }

    /// Ends the tracks of `row` whose last step is on object `x`.
    fn end_at(&mut self, x: usize, row: &[u32]) {
        for &t in row {
            let t = t as usize;
            if t >= self.first
                && let Some(open) = self.pending.get_mut(t - self.first)
                && open.track.steps.last().map(|s| s.0) == Some(x)
            {
                open.ended = true;
            }
        }
    }

    /// Chains the objects `new` through `pairs` (those that end on them, in order). Every pair
    /// leaving an object before `settled` is among those given so far.
    pub(crate) fn chain(
        &mut self,
        objects: &(impl ObjectsById + ?Sized),
        new: std::ops::Range<usize>,
        pairs: &[PairMatch],
        settled: usize,
        emit: &mut EmitTrack<'_>,
    ) -> Result<()> {
        let mut incoming: Vec<Vec<&PairMatch>> = vec![Vec::new(); new.len()];
        for p in pairs {
            // Objects are in sequence order and every pair goes forward, so visiting the
            // objects in order sees each predecessor before its successors.
            p.check_forward(new.clone())?;
            incoming[p.b - new.start].push(p);
            let u = self.last_use.entry(p.a).or_insert(0);
            *u = (*u).max(p.b);
        }
        // Objects of earlier windows that no pair leaves end their tracks.
        let idle: Vec<usize> = self
            .rows
            .keys()
            .copied()
            .filter(|x| *x < new.start && !self.last_use.contains_key(x))
            .collect();
        for x in idle {
            if let Some(row) = self.rows.remove(&x) {
                self.end_at(x, &row);
            }
        }
        for o in new.clone() {
            let row = self.continue_tracks(objects, o, &incoming[o - new.start])?;
            // A predecessor whose last pair this was ends the tracks still ending on it; so
            // does this object when no pair leaves it.
            for p in &incoming[o - new.start] {
                if self.last_use.get(&p.a) == Some(&o) {
                    self.last_use.remove(&p.a);
                    if let Some(done) = self.rows.remove(&p.a) {
                        self.end_at(p.a, &done);
                    }
                }
            }
            if o >= settled || self.last_use.get(&o).is_some_and(|&u| u > o) {
                self.rows.insert(o, row);
            } else {
                self.end_at(o, &row);
            }
            self.emit_ended(emit)?;
        }
        Ok(())
    }

    /// The track of each node of object `o`: the track its one-to-one partner in a predecessor
    /// (`incoming`, in order) is on, or a new one.
    fn continue_tracks(
        &mut self,
        objects: &(impl ObjectsById + ?Sized),
        o: usize,
        incoming: &[&PairMatch],
    ) -> Result<Vec<u32>> {
        let id = |t: usize| u32::try_from(t).unwrap_or(NO_TRACK - 1);
        let ob = objects.object(o)?;
        let mut row = vec![NO_TRACK; ob.shape.len()];
        for p in incoming {
            let Some(from) = self.rows.get(&p.a) else {
                continue;
            };
            for (k, mp) in p
                .result
                .pairs
                .iter()
                .enumerate()
                .filter(|(_, mp)| !mp.excess)
            {
                let (Some(&t), Some(&slot)) = (from.get(mp.a), row.get(mp.b)) else {
                    return Err(p.beyond_nodes(mp, from.len(), row.len()));
                };
                if slot != NO_TRACK || !p.trackable.get(k).copied().unwrap_or(false) {
                    continue;
                }
                let t = t as usize;
                // A track can pass through one node per object only: a split keeps the first
                // continuation. (A track already handed over has ended elsewhere.)
                if t >= self.first
                    && let Some(open) = self.pending.get_mut(t - self.first)
                    && open.track.steps.last().map(|s| s.0) == Some(p.a)
                {
                    open.track.steps.push((o, mp.b));
                    let trip = p.step_round_trips.get(k).map(|&d| f64::from(d));
                    open.worst = match (open.worst, trip) {
                        (Some(w), Some(d)) if d.is_finite() => Some(w.max(d)),
                        _ => None,
                    };
                    row[mp.b] = id(t);
                }
            }
        }
        for (node, slot) in row.iter_mut().enumerate() {
            if *slot == NO_TRACK {
                *slot = id(self.first + self.pending.len());
                self.pending.push_back(Open {
                    track: Track {
                        steps: vec![(o, node)],
                    },
                    ended: false,
                    worst: Some(0.0),
                });
            }
        }
        Ok(row)
    }

    /// Hands over the front tracks that have ended.
    fn emit_ended(&mut self, emit: &mut EmitTrack<'_>) -> Result<()> {
        while self.pending.front().is_some_and(|o| o.ended) {
            if let Some(Open {
                mut track, worst, ..
            }) = self.pending.pop_front()
            {
                track.steps.shrink_to_fit();
                self.first += 1;
                let trip = worst.filter(|_| track.steps.len() > 1);
                emit(self.first - 1, track, trip)?;
            }
        }
        Ok(())
    }

    /// Hands over every track left.
    pub(crate) fn finish(&mut self, emit: &mut EmitTrack<'_>) -> Result<()> {
        for open in &mut self.pending {
            open.ended = true;
        }
        self.rows.clear();
        self.last_use.clear();
        self.emit_ended(emit)
    }
}

/// Chains matches into tracks. A node continues the track of the node it is matched to one-to-one
/// in the previous object; excess (one-to-many) matches never extend a track, since a track must
/// stay a single path, and neither does a match that moves further than the pair's
/// [`crate::pairing::StepBound`] allows ([`PairMatch::trackable`]). Nodes with no such predecessor start a new track.
/// Every pair must lead forward (`a < b`) between the `objects` and name nodes they have.
pub fn chain_tracks(objects: &[SequenceObject], pairs: &[PairMatch]) -> Result<Vec<Track>> {
    let mut tracks = Vec::new();
    chain_tracks_with(objects, pairs, &mut |t| {
        tracks.push(t);
        Ok(())
    })?;
    Ok(tracks)
}

/// [`chain_tracks`], handing the tracks to `emit` one by one in order (track 0 first), each as
/// soon as it can grow no more and every track before it has gone: only the open tracks are
/// held (those through the last frames chained), not every track of the run.
pub fn chain_tracks_with(
    objects: &[SequenceObject],
    pairs: &[PairMatch],
    emit: &mut dyn FnMut(Track) -> Result<()>,
) -> Result<()> {
    chain_tracks_checked_with(objects, pairs, &mut |track, _| emit(track))
}

/// [`chain_tracks`], with each track's **round trip** (sensels): the largest of its steps'
/// round trips ([`PairMatch::step_round_trips`]), how far the backward field of a pair it steps
/// through carries its node from where the track came. A track every step of which agrees with
/// the smooth map its pair's matches define has a small one; a track that takes a match
/// crossing or swapping with its neighbours has a large one. `None` for a track of one step
/// and for one that steps through a pair without a field (surfaces).
pub fn chain_tracks_checked(
    objects: &[SequenceObject],
    pairs: &[PairMatch],
) -> Result<Vec<(Track, Option<f64>)>> {
    let mut tracks = Vec::new();
    chain_tracks_checked_with(objects, pairs, &mut |t, trip| {
        tracks.push((t, trip));
        Ok(())
    })?;
    Ok(tracks)
}

/// [`chain_tracks_checked`], handing the tracks to `emit` one by one as
/// [`chain_tracks_with`] does.
pub fn chain_tracks_checked_with(
    objects: &[SequenceObject],
    pairs: &[PairMatch],
    emit: &mut dyn FnMut(Track, Option<f64>) -> Result<()>,
) -> Result<()> {
    let mut chain = Chainer::default();
    let mut emit = |_, track, trip| emit(track, trip);
    chain.chain(objects, 0..objects.len(), pairs, objects.len(), &mut emit)?;
    chain.finish(&mut emit)
}
