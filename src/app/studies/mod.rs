//! The thesis's other models as studies: each runs a grid of scenes from
//! one scenario file and writes its table, figure and notes to `results/`.

pub mod coulomb_precursors;
pub mod front_1d;
pub mod junction_laws;
pub mod slow_slip;
