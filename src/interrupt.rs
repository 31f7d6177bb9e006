//! A request from outside to stop (Ctrl-C, SIGTERM, SIGHUP): a run checkpoints and stops
//! after the step under way, a strength-reduction analysis ends its trial, a study stops
//! the run under way.
//!
//! The process has one flag, set by the signal handlers [`catch_signals`] installs (the
//! binary calls it; a library user may call it, or [`request`] from its own handler). A
//! [`StopSignal`] is what a run polls: the process's flag, or a private one that a caller
//! (a test, an embedding program) sets for one run alone and that the process's flag also
//! trips.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Once};

static REQUESTED: AtomicBool = AtomicBool::new(false);

/// Exit code of a process stopped by a signal (128 + SIGINT, as shells report it).
pub const INTERRUPTED_EXIT: u8 = 130;

/// Asks everything that steps to stop; returns true when a stop was asked for already (a
/// second signal while the first is being honoured).
pub fn request() -> bool {
    REQUESTED.swap(true, Ordering::SeqCst)
}

/// True once a stop was asked for.
pub fn requested() -> bool {
    REQUESTED.load(Ordering::SeqCst)
}

/// Installs the handler of Ctrl-C, SIGTERM and SIGHUP, once per process: the first signal
/// sets the process's stop flag; a second one while the first is being honoured ends the
/// process at once with exit code 130 (every file is written whole or not at all, so
/// nothing torn is left). A process that cannot install it (another handler is installed)
/// keeps that handler. On Unix SIGUSR1 also sets the flag, and never ends the process:
/// the signal a batch system sends ahead of a job's time limit (Slurm's `--signal`), and
/// one that `mpirun` passes on to every rank.
pub fn catch_signals() {
    static INSTALL: Once = Once::new();
    INSTALL.call_once(|| {
        let _ = ctrlc::set_handler(|| {
            if request() {
                std::process::exit(INTERRUPTED_EXIT.into());
            }
        });
        #[cfg(unix)]
        {
            extern "C" fn on_usr1(_: libc::c_int) {
                // Async-signal-safe: one atomic store.
                REQUESTED.store(true, Ordering::SeqCst);
            }
            // SAFETY: `on_usr1` only stores to an atomic, which is async-signal-safe, and the
            // disposition of SIGUSR1 is not otherwise used by this process.
            unsafe {
                libc::signal(libc::SIGUSR1, on_usr1 as *const () as libc::sighandler_t);
            }
        }
    });
}

/// What a run polls to know it should stop: the process's flag, plus for a private signal
/// its own.
#[derive(Clone, Debug, Default)]
pub struct StopSignal(Option<Arc<AtomicBool>>);

impl StopSignal {
    /// The process's flag alone (what [`catch_signals`] sets).
    pub fn process() -> StopSignal {
        StopSignal(None)
    }

    /// A flag of its own, for one run (or a group of runs sharing clones of it); the
    /// process's flag still trips it.
    pub fn private() -> StopSignal {
        StopSignal(Some(Arc::new(AtomicBool::new(false))))
    }

    /// Asks the runs polling this signal to stop (the process's flag for
    /// [`StopSignal::process`]); returns true when a stop was asked for already.
    pub fn request(&self) -> bool {
        match &self.0 {
            Some(own) => own.swap(true, Ordering::SeqCst),
            None => request(),
        }
    }

    /// True once a stop was asked for, of this signal or of the process.
    pub fn requested(&self) -> bool {
        requested() || self.0.as_ref().is_some_and(|own| own.load(Ordering::SeqCst))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_private_signal_stops_only_the_runs_that_poll_it() {
        let a = StopSignal::private();
        let b = StopSignal::private();
        assert!(!a.requested());
        assert!(!a.request());
        assert!(a.request(), "the second request reports the first");
        assert!(a.clone().requested());
        assert!(!b.requested());
    }
}
