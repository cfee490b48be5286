//! Figures of a run, on plotters (PNG or SVG, font embedded): space–time
//! maps, the loading curve, fronts, slip and precursors; and the figures of
//! tables (sweeps, the work–precision benchmark). Each figure is a struct
//! holding its data that implements [`Figure`]; [`write`] renders it.

pub mod colour;
mod figure;
pub mod fronts;
pub mod loading;
pub mod maps;
pub mod precursors;
pub mod scatter;
pub mod slip;

pub use figure::{
    extent, log_tick, render, tick, write, Drawn, Figure, FigureOptions, Format, Style, DPI_RANGE,
    SIZE_RANGE,
};
