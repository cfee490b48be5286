//! slipfront: a GPU-accelerated 2D spring-block simulator of the onset of
//! frictional sliding (Trømborg et al., PNAS 2014), with a CPU reference.
//!
//! `src/` in layers, each importing only the ones below it:
//! - `model`: the scenario, the model's parameters, lattice, laws, numbers;
//! - `engines`: the engine interface and the CPU, GPU, quasi-static and
//!   single-block engines;
//! - `analysis`: events, fronts, precursors, statistics, figures;
//! - `io`: output files and checkpoints;
//! - `app`: runs, sweeps, studies, verification (the `slipfront` commands
//!   in `src/commands` sit on top).

pub mod analysis;
pub mod app;
pub mod engines;
pub mod io;
pub mod model;

pub use engines::{advance_to, Engine, EngineError, Snapshot};
pub use model::scenario::Scenario;
pub use model::Model;
