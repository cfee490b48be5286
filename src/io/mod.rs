//! The io layer: run output (MCAP files, their reader and recovery),
//! checkpoints, and the field-by-field comparison of two outputs.

pub mod checkpoint;
pub mod compare;
pub mod live;
pub mod output;
