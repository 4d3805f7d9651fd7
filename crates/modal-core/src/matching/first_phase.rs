//! The first phase of a pair — the pre-alignment (stage 2), B's modes and A's first modes — on
//! the calling thread alone ([`Parallelism::Serial`]) or shared with one helper job on the rayon
//! pool ([`Parallelism::Pair`]).
//!
//! With a helper, this thread still does all the work itself, in an order that never waits for a
//! helper that has not started: a pool worker can take long to wake (on a VM, after a 15 ms pause,
//! two threads ran slower than one). Both threads take rotation starts from a shared counter,
//! then the survivors of the screening from another (each survivor's convergence and outline
//! fit takes about as long as fifteen starts' screening, and A's solve waits for all of them),
//! and the helper then takes B's solve if this thread has not claimed it yet. After it, the
//! helper prepares what the first pass needs besides the modes — the position term of the cost,
//! then the neighbour lists of two point sets' excess step — while this thread builds the modal
//! costs, so the pass that follows the solves is shorter. Whoever computes a result stores it in
//! its slot (a `OnceLock` for the last two: the pass computes what the helper has not begun),
//! so the outcome does not depend on the timing. This thread waits (blocked, not
//! spinning) only for work the helper has claimed and is therefore running.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex, OnceLock};

use super::features::{ModalFeatures, PositionTermAhead};
use super::prealign::Prealign;
use super::prealign::{self, Affine, RotationSearch, SearchPair, SurvivorFit};
use super::prepare::{Pair, PreparedShape};
use super::refine::Start;
use crate::error::ModalError;
use crate::model::ModelOptions;

/// How many threads one pair uses: the caller's choice, by what else it runs at the same time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Parallelism {
    /// The calling thread only. For callers that match many pairs at once, one pair per thread
    /// (a recording's pairs on the rayon pool): the pairs keep every core busy.
    Serial,
    /// The calling thread and one helper job on the rayon pool, which takes rotation starts,
    /// survivors of the screening, the second object's solve and some of the first pass's inputs
    /// when it gets a core. For one pair at a time (the `pedomatch match` command,
    /// `pymodal.match`). The result is the same as with [`Parallelism::Serial`].
    #[default]
    Pair,
}

/// A gate on A's start in B's frame: `true` stops the first phase (see [`first_phase`]).
pub(crate) type Gate<'g> = &'g dyn Fn(&[f64]) -> bool;

/// Stage 2 and the first solves: A in B's frame, B's modes and A's modes there. `None`, before
/// any modal solve, when `stop` is given and says so of A's start in B's frame (the gate of
/// [`super::Refine::Auto`]); behind a gate both solves wait for its word, then run side by side.
pub(crate) fn first_phase(
    pair: &Pair<'_>,
    parallelism: Parallelism,
    stop: Option<Gate<'_>>,
) -> Result<Option<Start>, ModalError> {
    let stops = |cur: &[f64]| stop.is_some_and(|f| f(cur));
    let (a, b) = (pair.a.get(), pair.b.get());
    let (d, ordered) = (pair.dim, pair.ordered);
    let robust = pair.opts.prealign == Prealign::Robust;
    let sensor = (pair.opts.prealign == Prealign::Sensor).then(|| pair.sensor_map());
    let renormalize = pair.opts.prealign.renormalizes(ordered);
    let search = pair.opts.rotation_search;
    let modal = pair.modal();
    match parallelism {
        Parallelism::Serial => {
            let t = robust
                .then(|| prealign::robust_prealign_serial(&a.pts, &b.pts, d, &search, ordered))
                .or(sensor);
            let (cur, to_cur) = prealign::start_in_b_frame(&a.pts, t, d, renormalize)?;
            if stops(&cur) {
                return Ok(None);
            }
            let modes_b = modal.then(|| pair.modes_b()).transpose()?;
            let modes_a = modal.then(|| pair.modes_a(&cur)).transpose()?;
            Ok(Some(Start {
                cur,
                to_cur,
                modes_b,
                modes_a,
                positions: None,
            }))
        }
        Parallelism::Pair => {
            let phase = FirstPhase::start(
                d,
                robust.then(|| {
                    let (a, b) = (pair.a.clone().into_owned(), pair.b.clone().into_owned());
                    Screening::new(a, b, search, ordered)
                }),
                // Behind a gate B's solve waits for the gate's word: a helper that began it for a
                // pair the gate then stops would take a core from the rest of the pair.
                (modal && stop.is_none()).then(|| SolveB {
                    b: pair.b.clone().into_owned(),
                    model: pair.model.clone(),
                    skip: pair.skip,
                    modes: pair.k + pair.band,
                }),
                (pair.excess() && !ordered)
                    .then(|| [pair.a.clone().into_owned(), pair.b.clone().into_owned()]),
                (modal && pair.opts.position_weight > 0.0).then(|| {
                    Arc::new(PositionTermAhead::new(
                        pair.b.clone().into_owned(),
                        pair.opts.cost_power,
                    ))
                }),
            );
            let t = phase.prealign().or(sensor);
            let (cur, to_cur) = prealign::start_in_b_frame(&a.pts, t, d, renormalize)?;
            if stops(&cur) {
                return Ok(None);
            }
            let positions = phase.publish_start(&cur);
            let (modes_a, modes_b) = if modal && stop.is_some() {
                let (ma, mb) = rayon::join(|| pair.modes_a(&cur), || pair.modes_b());
                (Some(ma?), Some(mb?))
            } else {
                (
                    modal.then(|| pair.modes_a(&cur)).transpose()?,
                    phase.b_modes()?,
                )
            };
            Ok(Some(Start {
                cur,
                to_cur,
                modes_b,
                modes_a,
                positions,
            }))
        }
    }
}

/// B's modal solve, as the helper or the calling thread runs it (cached in B).
struct SolveB {
    b: PreparedShape,
    model: ModelOptions,
    skip: usize,
    modes: usize,
}

type Features = Result<Option<Arc<ModalFeatures>>, ModalError>;

/// The rotation search's screening, as the helper or the calling thread runs it (on the two
/// objects' normalised nodes).
struct Screening {
    a: PreparedShape,
    b: PreparedShape,
    /// The nodes of A and B the screening runs on ([`prealign::screen_nodes`]).
    screen: [Vec<f64>; 2],
    search: RotationSearch,
    keep_orientation: bool,
}

/// The screening's outcome, shared by both threads: every start's screened map and chamfer, and
/// the survivors' indices with a slot for each one's fit.
struct Survivors {
    screened: Vec<(Affine, f64)>,
    order: Option<Vec<usize>>,
    fits: Vec<Slot<SurvivorFit>>,
}

impl Screening {
    fn new(a: PreparedShape, b: PreparedShape, search: RotationSearch, ordered: bool) -> Self {
        let outlines = prealign::fits_outlines(a.get().dim(), &search, ordered);
        let nodes = |s: &PreparedShape| {
            let s = s.get();
            prealign::screen_nodes(&s.pts, s.dim(), &search, outlines).into_owned()
        };
        Self {
            screen: [nodes(&a), nodes(&b)],
            a,
            b,
            search,
            keep_orientation: ordered,
        }
    }

    fn pair(&self, dim: usize) -> SearchPair<'_> {
        SearchPair {
            a: &self.a.get().pts,
            b: &self.b.get().pts,
            a_screen: &self.screen[0],
            b_screen: &self.screen[1],
            dim,
            search: &self.search,
            keep_orientation: self.keep_orientation,
        }
    }
}

/// A result one thread fills and the other may wait for, blocked.
struct Slot<T> {
    value: Mutex<Option<T>>,
    filled: Condvar,
}

impl<T: Clone> Slot<T> {
    fn new() -> Self {
        Self {
            value: Mutex::new(None),
            filled: Condvar::new(),
        }
    }

    fn set(&self, v: T) {
        *self.value.lock().expect("slot") = Some(v);
        self.filled.notify_all();
    }

    /// Blocks until the slot is filled; only called for work a running thread has claimed.
    fn wait(&self) -> T {
        let guard = self.value.lock().expect("slot");
        let guard = self
            .filled
            .wait_while(guard, |v| v.is_none())
            .expect("slot");
        guard.clone().expect("filled")
    }
}

struct Shared {
    dim: usize,
    screening: Option<Screening>,
    starts: Vec<Affine>,
    next: AtomicUsize,
    screened: Vec<Slot<(Affine, f64)>>,
    /// Set by the first thread done screening, once every start is screened.
    survivors: OnceLock<Survivors>,
    next_survivor: AtomicUsize,
    solve_b: Option<SolveB>,
    b_claimed: AtomicBool,
    b_modes: Slot<Features>,
    /// The objects whose neighbour lists the point-set excess step will read.
    neighbours: Option<[PreparedShape; 2]>,
    positions: Option<Arc<PositionTermAhead>>,
}

impl Shared {
    /// Screens starts until none is left.
    fn screen(&self) {
        let Some(s) = &self.screening else { return };
        let pair = s.pair(self.dim);
        loop {
            let i = self.next.fetch_add(1, Ordering::Relaxed);
            if i >= self.starts.len() {
                return;
            }
            // Only the thread that took index i fills slot i.
            self.screened[i].set(pair.screen(self.starts[i]));
        }
    }

    /// The screened starts and their survivors; blocks until every start is screened, so only
    /// called by a thread whose own [`Shared::screen`] has returned (the other thread's claimed
    /// starts are then running or done).
    fn survivors(&self, s: &Screening) -> &Survivors {
        self.survivors.get_or_init(|| {
            let screened: Vec<(Affine, f64)> = self.screened.iter().map(Slot::wait).collect();
            let order = prealign::survivors(&screened, &s.search);
            let fits = order.iter().flatten().map(|_| Slot::new()).collect();
            Survivors {
                screened,
                order,
                fits,
            }
        })
    }

    /// Runs survivors to convergence until none is left.
    fn converge(&self) {
        let Some(s) = &self.screening else { return };
        let survivors = self.survivors(s);
        let Some(order) = &survivors.order else {
            return;
        };
        loop {
            let i = self.next_survivor.fetch_add(1, Ordering::Relaxed);
            if i >= order.len() {
                return;
            }
            let start = survivors.screened[order[i]].0;
            survivors.fits[i].set(s.pair(self.dim).converge(start));
        }
    }

    /// Solves B unless the other thread has claimed it.
    fn solve_b(&self) {
        let Some(job) = &self.solve_b else { return };
        if self.b_claimed.swap(true, Ordering::AcqRel) {
            return;
        }
        let out = job.b.get().own_modes(&job.model, job.skip, job.modes);
        self.b_modes.set(out.map(Some));
    }

    /// Fills the objects' neighbour caches for the excess step. The cache is a `OnceLock`, so the
    /// calling thread either finds the lists, waits for the helper computing them, or computes
    /// them itself if the helper has not got there.
    fn neighbours(&self) {
        for shape in self.neighbours.iter().flatten() {
            shape.get().neighbours();
        }
    }

    /// Computes the first pass's position term if A's start is published and nobody has.
    fn positions(&self) {
        if let Some(p) = &self.positions {
            p.get();
        }
    }
}

/// The first phase under way: a helper job is on the pool from [`FirstPhase::start`] on.
struct FirstPhase {
    shared: Arc<Shared>,
}

impl FirstPhase {
    /// Puts the helper on the pool: it screens rotation starts (when `screening` is given),
    /// solves B (when `solve_b` is given) unless this thread has claimed it, then computes the
    /// first pass's position term (when `positions` is given) and fills the neighbour lists of
    /// `neighbours` while this thread runs the first pass's modal costs and assignment.
    fn start(
        dim: usize,
        screening: Option<Screening>,
        solve_b: Option<SolveB>,
        neighbours: Option<[PreparedShape; 2]>,
        positions: Option<Arc<PositionTermAhead>>,
    ) -> Self {
        let starts = screening
            .as_ref()
            .map_or_else(Vec::new, |s| s.pair(dim).starts());
        let shared = Arc::new(Shared {
            dim,
            screened: (0..starts.len()).map(|_| Slot::new()).collect(),
            starts,
            survivors: OnceLock::new(),
            next_survivor: AtomicUsize::new(0),
            screening,
            next: AtomicUsize::new(0),
            solve_b,
            b_claimed: AtomicBool::new(false),
            b_modes: Slot::new(),
            neighbours,
            positions,
        });
        let helper = Arc::clone(&shared);
        rayon::spawn(move || {
            helper.screen();
            helper.converge();
            helper.solve_b();
            helper.positions();
            helper.neighbours();
        });
        Self { shared }
    }

    /// The rotation search's result (`None` when no screening was given): the starts and
    /// survivors this thread takes, then [`SearchPair::choose`] — the same candidates and order as
    /// [`prealign::robust_prealign`], so the same map.
    fn prealign(&self) -> Option<Affine> {
        let shared = &self.shared;
        shared.screen();
        shared.converge();
        let s = shared.screening.as_ref()?;
        let survivors = shared.survivors(s);
        let fits: Option<Vec<SurvivorFit>> = survivors
            .order
            .as_ref()
            .map(|_| survivors.fits.iter().map(Slot::wait).collect());
        Some(
            s.pair(shared.dim)
                .choose(&survivors.screened, fits.as_deref()),
        )
    }

    /// Publishes A's start coordinates for the first pass's position term, and hands the
    /// term's slot to the first pass.
    fn publish_start(&self, cur: &[f64]) -> Option<Arc<PositionTermAhead>> {
        let ahead = self.shared.positions.as_ref()?;
        ahead.publish(cur);
        Some(Arc::clone(ahead))
    }

    /// B's modes (`Ok(None)` when no solve was given): solved here if the helper has not
    /// claimed them yet, else waited for.
    fn b_modes(self) -> Features {
        if self.shared.solve_b.is_none() {
            return Ok(None);
        }
        self.shared.solve_b();
        self.shared.b_modes.wait()
    }
}
