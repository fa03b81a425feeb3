//! How a caller steers a long job: a [`CancelToken`] to stop it between two steps (or at the
//! next check of a face build or an export), and a progress callback ([`OnProgress`]) that a
//! run calls as it goes. The library owns no process-wide state: the command line connects
//! SIGINT/SIGTERM to a token and draws its bar from the callback, the Python package connects
//! `KeyboardInterrupt` and a Python function.

use crate::error::{Error, Result};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// A request to stop, shared between a job and whoever may cancel it (clones share one flag).
/// Safe to set from a signal-handling thread. A run that sees it stops between two steps,
/// writes its summary marked interrupted and returns [`Error::Interrupted`]; the other jobs
/// return [`Error::Cancelled`] having removed what they had not finished.
#[derive(Clone, Debug, Default)]
pub struct CancelToken(Arc<AtomicBool>);

impl CancelToken {
    /// A token nobody has cancelled yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Asks every job holding this token (or a clone) to stop at its next check.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::SeqCst);
    }

    /// Whether [`cancel`](Self::cancel) was called.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::SeqCst)
    }

    /// For the jobs that are not a run's stepping: [`Error::Cancelled`] saying `what` (e.g.
    /// "face stopped before writing anything") once the token is cancelled.
    pub fn check(&self, what: impl FnOnce() -> String) -> Result<()> {
        if self.is_cancelled() {
            Err(Error::Cancelled(what()))
        } else {
            Ok(())
        }
    }
}

/// Where a run is: handed to the progress callback once before the first step, after every
/// piece of stepping (at most [`crate::driver::INTERRUPT_CHECK_STEPS`] steps) and at the end.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ProgressUpdate {
    /// Steps taken (a restarted run counts from the beginning).
    pub step: usize,
    /// Steps of the whole run.
    pub steps: usize,
    /// Simulated time reached (s).
    pub time: f64,
    /// Simulated time at the end of the run (s).
    pub end_time: f64,
    /// Frames handed to the writer so far.
    pub frames: usize,
    /// Wall time of this process's stepping so far (s).
    pub elapsed: f64,
    /// Estimated wall time to the end (s): this process's stepping rate applied to the steps
    /// left; `None` before the first piece of stepping.
    pub seconds_left: Option<f64>,
}

impl ProgressUpdate {
    /// `step / steps`, 1 for a run with no steps.
    pub fn fraction(&self) -> f64 {
        if self.steps == 0 {
            1.0
        } else {
            self.step as f64 / self.steps as f64
        }
    }
}

/// A progress callback (called on the thread that runs the job; keep it short).
#[derive(Clone)]
pub struct OnProgress(pub Arc<dyn Fn(&ProgressUpdate) + Send + Sync>);

impl OnProgress {
    pub fn new(f: impl Fn(&ProgressUpdate) + Send + Sync + 'static) -> Self {
        OnProgress(Arc::new(f))
    }

    pub fn call(&self, u: &ProgressUpdate) {
        (self.0)(u)
    }
}

impl std::fmt::Debug for OnProgress {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("OnProgress(..)")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clones_share_one_flag() {
        let a = CancelToken::new();
        let b = a.clone();
        assert!(!b.is_cancelled());
        assert!(a.check(|| "x".into()).is_ok());
        a.cancel();
        assert!(b.is_cancelled());
        match b.check(|| "stopped here".into()) {
            Err(Error::Cancelled(s)) => assert_eq!(s, "stopped here"),
            other => panic!("{other:?}"),
        }
        // an unrelated token is not cancelled
        assert!(!CancelToken::new().is_cancelled());
    }

    #[test]
    fn fraction() {
        let mut u = ProgressUpdate {
            step: 25,
            steps: 100,
            time: 0.0,
            end_time: 1.0,
            frames: 0,
            elapsed: 0.0,
            seconds_left: None,
        };
        assert_eq!(u.fraction(), 0.25);
        u.steps = 0;
        assert_eq!(u.fraction(), 1.0);
    }
}
