//! Where the heavy work runs: with the GIL released, on a rayon pool of pymodal's own, made
//! anew in a forked child.
//!
//! rayon's global pool cannot be used: a child forked after the parent started it (Python's
//! `multiprocessing` and `ProcessPoolExecutor` fork by default on Linux) inherits the pool as
//! data but none of its threads (a fork copies only the calling thread), so its first parallel
//! work would wait forever for them. pymodal's pool records the process id it was made in, and a
//! child makes its own at its first call.

use pyo3::prelude::*;
use std::sync::{Arc, Mutex};

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
