//! Choosing and building an engine: backend and precision.

use crate::cpu::CpuEngine;
use crate::engine::{Engine, EngineError};
use crate::model::Model;

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Backend {
    /// The CPU reference engine.
    Cpu,
    /// The wgpu engine (a hardware adapter, else lavapipe).
    Gpu,
    /// A hardware GPU, else lavapipe, else the CPU.
    Auto,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Precision {
    F64,
    F32,
}

/// Builds the CPU engine in the requested precision.
pub fn cpu_engine(
    model: &Model,
    precision: Precision,
    threads: usize,
) -> Result<Box<dyn Engine>, EngineError> {
    Ok(match precision {
        Precision::F64 => Box::new(CpuEngine::<f64>::new(model, threads)?),
        Precision::F32 => Box::new(CpuEngine::<f32>::new(model, threads)?),
    })
}

/// Builds the engine for `backend`.
pub fn make_engine(
    model: &Model,
    backend: Backend,
    precision: Precision,
    threads: usize,
) -> Result<Box<dyn Engine>, EngineError> {
    match backend {
        Backend::Cpu => cpu_engine(model, precision, threads),
        Backend::Gpu | Backend::Auto => Err(EngineError::Gpu(
            "the GPU engine is not built yet; use --backend cpu".into(),
        )),
    }
}
