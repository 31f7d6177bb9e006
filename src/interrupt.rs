//! A request from outside to stop (Ctrl-C, SIGTERM, SIGHUP), one flag for everything that
//! steps: a run checkpoints and stops after the step under way, a strength-reduction
//! analysis ends its trial, a study stops the run under way. The binary's signal handlers
//! set it; a library user may set it from its own.

use std::sync::atomic::{AtomicBool, Ordering};

static REQUESTED: AtomicBool = AtomicBool::new(false);

/// Asks everything that steps to stop; returns true when a stop was asked for already (a
/// second signal while the first is being honoured).
pub fn request() -> bool {
    REQUESTED.swap(true, Ordering::SeqCst)
}

/// True once a stop was asked for.
pub fn requested() -> bool {
    REQUESTED.load(Ordering::SeqCst)
}
