//! A clean stop on request (SIGTERM, SIGINT in `crash-master` and `crash run`): the
//! loop finishes the current step, writes a checkpoint, the last frame and
//! summary.json marked interrupted, tells the workers to stop and returns
//! `MasterError::Interrupted`. The flag is process-wide: a signal handler sets it
//! (signal_hook::flag).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, LazyLock};

/// Exit code of a process stopped by a signal (128 + SIGINT, the shell's convention).
pub const EXIT_INTERRUPTED: u8 = 130;

static STOP: LazyLock<Arc<AtomicBool>> = LazyLock::new(|| Arc::new(AtomicBool::new(false)));

/// The flag a signal handler sets.
pub fn flag() -> Arc<AtomicBool> {
    STOP.clone()
}

/// Whether a stop was requested.
pub fn requested() -> bool {
    STOP.load(Ordering::Relaxed)
}

/// SIGTERM and SIGINT set the flag; a second one ends the process at once with
/// `EXIT_INTERRUPTED` (a run stuck in a long step can still be ended).
pub fn install_handlers() -> std::io::Result<()> {
    let stop = flag();
    for sig in [signal_hook::consts::SIGTERM, signal_hook::consts::SIGINT] {
        // registered first, so it sees the flag before this signal sets it
        signal_hook::flag::register_conditional_shutdown(
            sig,
            i32::from(EXIT_INTERRUPTED),
            stop.clone(),
        )?;
        signal_hook::flag::register(sig, stop.clone())?;
    }
    Ok(())
}
