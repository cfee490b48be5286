//! The model layer, below every engine: the scenario file (`scenario`), the
//! model's parameters and derived quantities in SI units (`parameters`,
//! re-exported here: `model::Model`), the lattice, the force laws, the
//! junction record, the random numbers and the number types.

pub mod friction;
pub mod junction;
pub mod lattice;
pub mod laws;
mod parameters;
pub mod real;
pub mod rng;
pub mod scenario;

pub use parameters::*;
