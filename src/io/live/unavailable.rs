//! The live view of a build without the cargo feature `live`: starting one
//! is refused with [`LiveError::NotBuilt`], so no value of it ever exists.

use super::{LiveAddress, LiveError};
use crate::io::output::records::Record;

#[derive(Clone)]
pub enum LiveView {}

impl LiveView {
    pub fn start(_address: &LiveAddress, _largest_message: usize) -> Result<LiveView, LiveError> {
        Err(LiveError::NotBuilt)
    }
    pub fn url(&self) -> &str {
        match *self {}
    }
    pub fn wanted(&self) -> bool {
        match *self {}
    }
    pub fn wait_for_viewer(&self, _stop: &dyn Fn() -> bool) -> bool {
        match *self {}
    }
    pub fn publish(&self, _record: &Record, _bytes: &[u8]) {
        match *self {}
    }
    pub fn show_time(&self, _t: f64) {
        match *self {}
    }
    pub fn close(&self) {
        match *self {}
    }
}
