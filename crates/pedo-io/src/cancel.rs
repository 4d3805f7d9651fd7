//! Stopping a run early from another thread.
//!
//! A [`Cancel`] is a shared flag: the caller sets it ([`Cancel::cancel`]) and the run, given it in
//! `pedo_track::SequenceOptions::cancel` or `pedo_study::StudyOptions::cancel`, checks it at its
//! progress steps
//! (a frame built, a pair matched, a figure drawn, before an output folder is committed) and then
//! fails with [`IoError::Cancelled`]: the frames and pairs not started are not processed and no
//! output folder of the run is committed. Unlike `pedo_output::outdir::interrupt` (a process-wide
//! latch for a program that exits), it concerns only the runs it is given, so a program can go on
//! and run again (the Python bindings cancel a run on Ctrl-C this way).

use crate::error::{IoError, Result};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// A request to stop a run, shared by its clones; see the module docs.
#[derive(Debug, Clone, Default)]
pub struct Cancel(Arc<AtomicBool>);

impl Cancel {
    /// A request not (yet) made.
    pub fn new() -> Self {
        Self::default()
    }

    /// Asks every run given this request (or a clone) to stop at its next progress step.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::SeqCst);
    }

    /// Whether [`Cancel::cancel`] was called.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::SeqCst)
    }
}

/// Whether `cancel` is given and was cancelled.
pub fn cancelled(cancel: Option<&Cancel>) -> bool {
    cancel.is_some_and(Cancel::is_cancelled)
}

/// [`IoError::Cancelled`] if `cancel` is given and was cancelled.
pub fn check(cancel: Option<&Cancel>) -> Result<()> {
    if cancelled(cancel) {
        Err(IoError::Cancelled)
    } else {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_clone_sees_the_request() {
        let c = Cancel::new();
        let seen = c.clone();
        assert!(check(Some(&seen)).is_ok() && check(None).is_ok());
        c.cancel();
        assert!(seen.is_cancelled());
        assert!(matches!(check(Some(&seen)), Err(IoError::Cancelled)));
        assert!(check(None).is_ok());
    }
}
