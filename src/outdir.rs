//! The CLI's side of the library's atomic output folders ([`pedo_output::outdir`]): the Ctrl-C
//! handler, and the folder type with the subcommands' `String` errors.

use std::path::Path;

/// Exit code of a run stopped by SIGINT or SIGTERM (128 + SIGINT, the shell convention).
pub const EXIT_INTERRUPTED: u8 = 130;

/// Installs the Ctrl-C (and SIGTERM) handler: it removes this process's staging folders and exits
/// with [`EXIT_INTERRUPTED`] at once, without waiting for the work in progress.
pub fn install_interrupt_handler() {
    // Failing to install (another handler exists) only loses the clean-up; the next run sweeps
    // stale staging folders anyway.
    let _ = ctrlc::set_handler(|| {
        pedo_output::outdir::interrupt();
        eprintln!("pedomatch: interrupted");
        std::process::exit(EXIT_INTERRUPTED as i32);
    });
}

/// Whether Ctrl-C (or SIGTERM) arrived. The handler then owns the exit: a caller that sees an
/// error caused by the interruption must not exit on its own before the clean-up is done, so it
/// calls [`wait_for_interrupt_exit`].
pub fn interrupted() -> bool {
    pedo_output::outdir::interrupted()
}

/// Blocks until the interrupt handler ends the process with [`EXIT_INTERRUPTED`].
pub fn wait_for_interrupt_exit() -> ! {
    loop {
        std::thread::park();
    }
}

/// An output folder being written (see [`pedo_output::outdir`]), with `String` errors.
pub struct OutDir(pub pedo_output::outdir::OutDir);

impl OutDir {
    /// Starts an output into `root`. Fails if `root` is a file, or a non-empty folder that is not
    /// a pedomatch output.
    pub fn create(root: &Path) -> Result<Self, String> {
        pedo_output::outdir::OutDir::create(root)
            .map(Self)
            .map_err(|e| e.to_string())
    }

    /// Writes `rel` (which may include sub-folders) into the staging folder.
    pub fn write(&self, rel: &str, contents: &[u8]) -> Result<(), String> {
        self.0.write(rel, contents).map_err(|e| e.to_string())
    }

    /// Puts the complete folder in place of the previous one in one step.
    pub fn commit(self) -> Result<(), String> {
        self.0.commit().map_err(|e| e.to_string())
    }
}
