//! The analysis layer: events and rupture fronts in an interface series
//! (`events`) and their table (`event_table`), precursors, the statistics of two samples, the energy
//! ledger, and the figures.

pub mod energy;
pub mod event_table;
pub mod events;
pub mod plot;
pub mod precursors;
pub mod stats;
