//! The live view: while a run goes on (or a finished run is replayed), a
//! Foxglove WebSocket server streams the run file's channels, the same
//! protobuf bytes under the same schemas, and draws the interface and the
//! bulk as images at most 30 times a second. Viewers that fall behind lose
//! messages; the run never waits for them.
//!
//! Built with the cargo feature `live` (on by default); without it the
//! commands refuse `--live` with a clear error.

mod address;
pub mod pictures;
#[cfg(feature = "live")]
mod server;
#[cfg(not(feature = "live"))]
mod unavailable;

pub use address::{LiveAddress, DEFAULT_LIVE_ADDRESS};
#[cfg(feature = "live")]
pub use server::LiveView;
#[cfg(not(feature = "live"))]
pub use unavailable::LiveView;

/// The image channels of the live view (foxglove.RawImage, rgb8).
pub const IMAGE_TOPICS: [&str; 4] = [
    "/live/stress_ratio",
    "/live/slip",
    "/live/slip_speed",
    "/live/bulk_speed",
];

/// Bytes of the largest record a run of an `nx` × `nz` lattice sends: a
/// bulk field where `bulk` output is on, else an interface row (each
/// viewer's queue is sized by it).
pub fn largest_record(nx: usize, nz: usize, bulk: bool) -> usize {
    let interface = nx * 5 * 8;
    let field = if bulk { nx * nz * 4 * 4 } else { 0 };
    interface.max(field) + 64
}

#[derive(Debug, thiserror::Error)]
pub enum LiveError {
    #[error(
        "live view at {address}: cannot listen there: {why} (pick another port, or \
         port 0 for a free one)"
    )]
    Bind { address: String, why: String },
    #[error(
        "--live: this slipfront was built without the live view; rebuild it with \
         the cargo feature `live` (on by default)"
    )]
    NotBuilt,
    #[error("live view: {0}")]
    Server(String),
}
