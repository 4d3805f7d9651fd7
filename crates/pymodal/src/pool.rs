//! Where the heavy work runs: with the GIL released, on a rayon pool of pymodal's own, made
//! anew in a forked child; the long runs ([`detach_cancellable`]) stop on Ctrl-C.
//!
//! rayon's global pool cannot be used: a child forked after the parent started it (Python's
//! `multiprocessing` and `ProcessPoolExecutor` fork by default on Linux) inherits the pool as
//! data but none of its threads (a fork copies only the calling thread), so its first parallel
//! work would wait forever for them. pymodal's pool records the process id it was made in, and a
//! child makes its own at its first call.

use pedo_io::cancel::Cancel;
use pyo3::prelude::*;
use std::sync::mpsc::RecvTimeoutError;
use std::sync::{Arc, Mutex};

use crate::errors::internal;

/// The pool and the process it belongs to. Only locked with the GIL held (every entry point holds
/// it when it asks for the pool), so that no other thread holds the lock when Python forks (the
/// forking thread holds the GIL): a child never inherits it locked.
static POOL: Mutex<Option<(u32, Arc<rayon::ThreadPool>)>> = Mutex::new(None);

/// This process's pool, made at its first use (`None` if no thread can be started).
pub fn pool(_py: Python<'_>) -> Option<Arc<rayon::ThreadPool>> {
    let pid = std::process::id();
    let mut owned = POOL.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((owner, pool)) = owned.as_ref()
        && *owner == pid
    {
        return Some(pool.clone());
    }
    let pool = Arc::new(
        rayon::ThreadPoolBuilder::new()
            .thread_name(|i| format!("pymodal-{i}"))
            .build()
            .ok()?,
    );
    // A pool inherited through a fork is never dropped: dropping it would signal threads that
    // this process does not have.
    if let Some(inherited) = owned.replace((pid, pool.clone())) {
        std::mem::forget(inherited);
    }
    Some(pool)
}

/// Runs `f` with the GIL released, on this process's pool (on this thread if it has none).
pub fn detach<T: Send>(py: Python<'_>, f: impl FnOnce() -> T + Send) -> T {
    match pool(py) {
        Some(pool) => py.detach(|| pool.install(f)),
        None => py.detach(f),
    }
}

/// How often a cancellable call looks for a signal while its work runs.
const POLL: std::time::Duration = std::time::Duration::from_millis(50);

/// Runs `f` as [`detach`] does, while this thread looks for signals every 50 ms
/// (`Python::check_signals`, which runs Python's signal handlers: Ctrl-C raises
/// `KeyboardInterrupt`). When a handler raises, `cancel` is cancelled (the library stops `f`'s run
/// at its next progress step, see [`pedo_io::cancel`]), and once `f` has returned, the handler's
/// exception is returned instead of `f`'s result. Without that, a signal would wait for the whole
/// run, and its exception would surface only afterwards.
pub fn detach_cancellable<T: Send>(
    py: Python<'_>,
    cancel: &Cancel,
    f: impl FnOnce() -> T + Send,
) -> PyResult<T> {
    let Some(pool) = pool(py) else {
        return Ok(py.detach(f));
    };
    let (tx, mut rx) = std::sync::mpsc::channel();
    pool.in_place_scope(|scope| {
        scope.spawn(move |_| {
            let _ = tx.send(f());
        });
        let mut raised: Option<PyErr> = None;
        loop {
            // The receiver goes to the thread without the GIL and back (it is not `Sync`).
            let (back, got) = py.detach(move || {
                let got = rx.recv_timeout(POLL);
                (rx, got)
            });
            rx = back;
            match got {
                // A signal that came since the last look is raised by this call too, not
                // left pending for whichever line of the caller runs next.
                Ok(out) => return raised.map_or_else(|| py.check_signals().map(|()| out), Err),
                Err(RecvTimeoutError::Timeout) => {
                    if raised.is_none()
                        && let Err(e) = py.check_signals()
                    {
                        cancel.cancel();
                        raised = Some(e);
                    }
                }
                // `f` panicked: the scope resumes its panic when this returns.
                Err(RecvTimeoutError::Disconnected) => {
                    return Err(
                        raised.unwrap_or_else(|| internal("the work ended without a result"))
                    );
                }
            }
        }
    })
}
