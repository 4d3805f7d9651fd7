//! Ctrl-C and SIGTERM: the handler that removes this process's staging output folders
//! ([`pedo_output::outdir`]) and exits with [`EXIT_INTERRUPTED`].

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
