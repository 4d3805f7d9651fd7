//! The first phase of a pair — the rotation search, B's modes and A's first modes — for a caller
//! outside the rayon pool.
//!
//! Such a caller (Python, one CLI pair) would hand every parallel section to the pool and sleep
//! until it is done, and between calls the pool's workers fall asleep: a section then waits on
//! waking one, which on a VM can take longer than the section saves (after 15 ms pauses two
//! threads ran slower than one). So this thread does all the work itself, in an order that never
//! waits for a helper, and one helper job on the pool takes what is left when it wakes: rotation
//! starts from a shared counter, then B's solve if this thread has not claimed it yet. Whoever
//! computes a result stores it in its slot, so the outcome does not depend on the timing; a late
//! helper finds nothing left to do.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, OnceLock};

use super::features_of;
use crate::align::{self, Affine, RotationSearch};
use crate::{ModalError, ModalFeatures, ModelOptions, Topology};

/// B's modal solve, as the helper or the calling thread runs it.
pub(super) struct SolveB {
    pub pts: Vec<f64>,
    pub topology: Topology,
    pub model: ModelOptions,
    pub skip: usize,
    pub modes: usize,
}

type Features = Result<Option<ModalFeatures>, ModalError>;

/// The rotation search's screening, as the helper or the calling thread runs it.
pub(super) struct Screening {
    pub a: Vec<f64>,
    pub b: Vec<f64>,
    pub search: RotationSearch,
    pub keep_orientation: bool,
}

struct Shared {
    dim: usize,
    screening: Option<Screening>,
    starts: Vec<Affine>,
    next: AtomicUsize,
    screened: Vec<OnceLock<(Affine, f64)>>,
    solve_b: Option<SolveB>,
    b_claimed: AtomicBool,
    b_modes: OnceLock<Features>,
}

impl Shared {
    /// Screens starts until none is left.
    fn screen(&self) {
        let Some(s) = &self.screening else { return };
        let iters = s.search.screening_iterations();
        loop {
            let i = self.next.fetch_add(1, Ordering::Relaxed);
            if i >= self.starts.len() {
                return;
            }
            let r = align::icp_affine(
                &s.a,
                &s.b,
                self.dim,
                self.starts[i],
                iters,
                s.keep_orientation,
            );
            // Only the thread that took index i writes slot i.
            let _ = self.screened[i].set(r);
        }
    }

    /// Solves B unless the other thread has claimed it.
    fn solve_b(&self) {
        let Some(job) = &self.solve_b else { return };
        if self.b_claimed.swap(true, Ordering::AcqRel) {
            return;
        }
        let out = features_of(
            &job.pts,
            self.dim,
            &job.topology,
            &job.model,
            job.skip,
            job.modes,
        );
        let _ = self.b_modes.set(out.map(Some));
    }
}

/// Waits for a slot the other thread is filling (it has claimed the work, so it is running).
fn wait<T>(slot: &OnceLock<T>) -> &T {
    loop {
        if let Some(v) = slot.get() {
            return v;
        }
        std::thread::yield_now();
    }
}

/// The first phase under way: a helper job is on the pool from [`FirstPhase::start`] on.
pub(super) struct FirstPhase {
    shared: Arc<Shared>,
}

impl FirstPhase {
    /// Puts the helper on the pool: it screens rotation starts (when `screening` is given) and
    /// then solves B (when `solve_b` is given) unless this thread has claimed it.
    pub(super) fn start(dim: usize, screening: Option<Screening>, solve_b: Option<SolveB>) -> Self {
        let starts = screening.as_ref().map_or_else(Vec::new, |s| {
            align::rotation_candidates(&s.a, &s.b, dim, s.search.turns)
        });
        let shared = Arc::new(Shared {
            dim,
            screened: (0..starts.len()).map(|_| OnceLock::new()).collect(),
            starts,
            screening,
            next: AtomicUsize::new(0),
            solve_b,
            b_claimed: AtomicBool::new(false),
            b_modes: OnceLock::new(),
        });
        let helper = Arc::clone(&shared);
        rayon::spawn(move || {
            helper.screen();
            helper.solve_b();
        });
        Self { shared }
    }

    /// The rotation search's result (`None` when no screening was given): the starts this
    /// thread screens, then [`align::finish_search`] on this thread — the same candidates and
    /// order as [`align::robust_prealign`], so the same map.
    pub(super) fn prealign(&self) -> Option<Affine> {
        let shared = &self.shared;
        shared.screen();
        let s = shared.screening.as_ref()?;
        let screened: Vec<(Affine, f64)> = shared.screened.iter().map(|r| *wait(r)).collect();
        Some(align::finish_search(
            &s.a,
            &s.b,
            shared.dim,
            &s.search,
            s.keep_orientation,
            &screened,
            false,
        ))
    }

    /// B's modes (`Ok(None)` when no solve was given): solved here if the helper has not
    /// claimed them yet, else waited for.
    pub(super) fn b_modes(self) -> Features {
        if self.shared.solve_b.is_none() {
            return Ok(None);
        }
        self.shared.solve_b();
        wait(&self.shared.b_modes).clone()
    }
}
