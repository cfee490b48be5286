//! The application layer, on top of the others: the runner (a run from a
//! scenario to its output), parameter sweeps and perturbation ensembles
//! (`sweeps`), the thesis's studies, the verification cases, and the
//! observables a run reports.

pub mod observables;
pub mod runner;
pub mod studies;
pub mod sweeps;
pub mod verify;
