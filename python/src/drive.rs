//! A long job (a run, a face build) on a thread of its own while the calling Python thread
//! waits with the GIL released, waking every [`POLL`] to hand the job's progress to a Python
//! callable and to look for a signal (`check_signals`: Ctrl-C's `KeyboardInterrupt`). A
//! Python exception from either cancels the job's token; the job then stops at its next
//! check (a run between two steps, with its frames complete) and the exception is handed
//! back with the job's result.

use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::time::Duration;
use sticky_lips::control::{CancelToken, OnProgress, ProgressUpdate};

/// How long the calling thread waits between two looks at the job, its progress and the
/// signals: the delay of a Ctrl-C, before the job's own (a run looks at its token every
/// `driver::INTERRUPT_CHECK_STEPS` steps).
const POLL: Duration = Duration::from_millis(50);

/// What came of a job: its result, and the first Python exception raised while it ran (by
/// a signal handler or the callback), which cancelled it.
pub struct Outcome<T> {
    pub result: T,
    pub raised: Option<PyErr>,
}

/// A progress update as the dict the callback gets (`sticky_lips.Progress`'s fields).
fn update_dict<'py>(py: Python<'py>, u: &ProgressUpdate) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("step", u.step)?;
    d.set_item("steps", u.steps)?;
    d.set_item("time", u.time)?;
    d.set_item("end_time", u.end_time)?;
    d.set_item("frames", u.frames)?;
    d.set_item("elapsed", u.elapsed)?;
    d.set_item("seconds_left", u.seconds_left)?;
    Ok(d)
}

/// Runs `job` on a new thread, giving it a progress callback that queues the updates for
/// `progress` (called on this thread, in order, the last one before this returns), and
/// cancelling `cancel` at the first Python exception (`progress` raising, or a signal
/// handler such as Ctrl-C's). A panic of the job is resumed here (PyO3 raises it as
/// `PanicException`).
pub fn drive<T: Send>(
    py: Python<'_>,
    cancel: &CancelToken,
    progress: Option<&Bound<'_, PyAny>>,
    job: impl FnOnce(OnProgress) -> T + Send,
) -> Outcome<T> {
    let (tx, rx) = mpsc::channel::<ProgressUpdate>();
    let on_progress = OnProgress::new(move |u: &ProgressUpdate| {
        // the receiver lives until the job has returned: a send cannot fail before
        let _ = tx.send(*u);
    });
    std::thread::scope(|s| {
        let handle = s.spawn(move || job(on_progress));
        let mut raised: Option<PyErr> = None;
        let mut rx: Receiver<ProgressUpdate> = rx;
        loop {
            // wait for an update or the end, without the GIL
            let (back, updates, finished) = py.detach(move || {
                let mut updates = Vec::new();
                let finished = match rx.recv_timeout(POLL) {
                    Ok(u) => {
                        updates.push(u);
                        updates.extend(rx.try_iter());
                        false
                    }
                    Err(RecvTimeoutError::Timeout) => false,
                    // every sender dropped: the job has returned, its updates all received
                    Err(RecvTimeoutError::Disconnected) => true,
                };
                (rx, updates, finished)
            });
            rx = back;
            if raised.is_none() {
                let looked = look(py, progress, &updates);
                if let Err(e) = looked {
                    cancel.cancel();
                    raised = Some(e);
                }
            }
            if finished {
                break;
            }
        }
        // the job's thread has dropped its sender: it is returning
        let result = py.detach(|| handle.join());
        match result {
            Ok(result) => Outcome { result, raised },
            Err(panic) => std::panic::resume_unwind(panic),
        }
    })
}

/// Hands `updates` to `progress`, then runs the pending signal handlers.
fn look(
    py: Python<'_>,
    progress: Option<&Bound<'_, PyAny>>,
    updates: &[ProgressUpdate],
) -> PyResult<()> {
    if let Some(cb) = progress {
        for u in updates {
            cb.call1((update_dict(py, u)?,))?;
        }
    }
    py.check_signals()
}
