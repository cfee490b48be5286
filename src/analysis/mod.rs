//! The analysis layer: events and rupture fronts in an interface series
//! (`events`), precursors, the statistics of two samples, the energy
//! ledger, and the figures.

pub mod energy;
pub mod events;
pub mod plot;
pub mod precursors;
pub mod stats;
