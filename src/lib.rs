//! slipfront: a GPU-accelerated 2D spring-block simulator of the onset of
//! frictional sliding (Trømborg et al., PNAS 2014), with a CPU reference.

pub mod analysis;
pub mod backend;
pub mod checkpoint;
pub mod compare;
pub mod cpu;
pub mod energy;
pub mod engine;
pub mod gpu;
pub mod junction;
pub mod lattice;
pub mod laws;
pub mod memory;
pub mod model;
pub mod observables;
pub mod output;
pub mod plot;
pub mod precision_probe;
pub mod precursors;
pub mod quasistatic;
pub mod real;
pub mod rng;
pub mod runner;
pub mod scenario;
pub mod single_block;
pub mod stats;
pub mod step_params;
pub mod studies;
pub mod sweep;
pub mod trigger;
pub mod verify;

pub use engine::{advance_to, Engine, EngineError, Snapshot};
pub use model::Model;
pub use scenario::Scenario;
