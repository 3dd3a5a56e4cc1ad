//! A clean stop on request (SIGTERM, SIGINT in `crash-master`): the loop finishes the
//! current step, writes a checkpoint, the last frame and summary.json marked
//! interrupted, tells the workers to stop and returns `MasterError::Interrupted`.
//! The flag is process-wide: a signal handler sets it (signal_hook::flag).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, LazyLock};

static STOP: LazyLock<Arc<AtomicBool>> = LazyLock::new(|| Arc::new(AtomicBool::new(false)));

/// The flag a signal handler sets.
pub fn flag() -> Arc<AtomicBool> {
    STOP.clone()
}

/// Whether a stop was requested.
pub fn requested() -> bool {
    STOP.load(Ordering::Relaxed)
}
