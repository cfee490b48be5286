//! Ctrl-C and progress for runs started from Python. The run goes on with
//! the GIL released; between chunks the watcher takes the GIL back for a
//! moment, lets Python run its signal handlers (Ctrl-C raises
//! KeyboardInterrupt there) and calls the progress callback. An exception
//! from either asks the run to stop: it writes its checkpoint, closes its
//! file, and the exception is raised once it has.

use pyo3::prelude::*;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

pub struct Watcher {
    progress: Option<Py<PyAny>>,
    error: Mutex<Option<PyErr>>,
    /// When Python was last called: runs that write output stop every few
    /// steps, and taking the GIL at each stop would make a run wait on the
    /// Python threads (up to the 5 ms switch interval each time).
    last: Mutex<Option<Instant>>,
}

/// Wall time between two calls into Python at least (but the last).
const POLL_INTERVAL: Duration = Duration::from_millis(100);

impl Watcher {
    pub fn new(progress: Option<Py<PyAny>>) -> Arc<Watcher> {
        // A stop asked of an earlier run of this process is forgotten.
        slipfront::app::runner::clear_stop();
        Arc::new(Watcher {
            progress,
            error: Mutex::new(None),
            last: Mutex::new(None),
        })
    }

    /// Checks Python's signals and reports `done` of `total`; called with
    /// the GIL released.
    pub fn poll(&self, done: u64, total: u64) {
        {
            let mut last = self.last.lock().expect("watcher");
            if done < total && last.is_some_and(|t| t.elapsed() < POLL_INTERVAL) {
                return;
            }
            *last = Some(Instant::now());
        }
        Python::attach(|py| {
            let result = py.check_signals().and_then(|()| match &self.progress {
                Some(callback) => callback.call1(py, (done, total)).map(drop),
                None => Ok(()),
            });
            if let Err(e) = result {
                let mut slot = self.error.lock().expect("watcher");
                slot.get_or_insert(e);
                slipfront::app::runner::request_stop();
            }
        });
    }

    /// The exception that stopped the run, if one did; the stop request is
    /// cleared for the next run.
    pub fn take_error(&self) -> Option<PyErr> {
        slipfront::app::runner::clear_stop();
        self.error.lock().expect("watcher").take()
    }
}
