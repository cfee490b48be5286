//! Ctrl-C and progress for runs started from Python. The run goes on with
//! the GIL released; between chunks the watcher takes the GIL back for a
//! moment, lets Python run its signal handlers (Ctrl-C raises
//! KeyboardInterrupt there) and calls the progress callback. An exception
//! from either asks the run to stop: it writes its checkpoint, closes its
//! file, and the exception is raised once it has.

use pyo3::prelude::*;
use std::sync::{Arc, Mutex};

pub struct Watcher {
    progress: Option<Py<PyAny>>,
    error: Mutex<Option<PyErr>>,
}

impl Watcher {
    pub fn new(progress: Option<Py<PyAny>>) -> Arc<Watcher> {
        // A stop asked of an earlier run of this process is forgotten.
        slipfront::app::runner::clear_stop();
        Arc::new(Watcher {
            progress,
            error: Mutex::new(None),
        })
    }

    /// Checks Python's signals and reports `done` of `total`; called with
    /// the GIL released.
    pub fn poll(&self, done: u64, total: u64) {
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
