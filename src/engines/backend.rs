//! Choosing and building an engine: backend and precision.

use crate::engines::backend_choice::{self, AutoChoice};
use crate::engines::cpu::{CpuEngine, SweepEngine};
use crate::engines::gpu::context::GpuContext;
use crate::engines::gpu::kernel_choice::ChoiceCache;
use crate::engines::gpu::precision::GpuReal;
use crate::engines::gpu::{GpuEngine, GpuOptions};
use crate::engines::{Engine, EngineError};
use crate::model::Model;

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Backend {
    /// The CPU engine (the sweep engine: each bond once, vectorised,
    /// bitwise the reference engine's results).
    Cpu,
    /// The CPU reference engine, the WGSL kernels' twin, phase by phase
    /// (about 3× slower than `cpu`, the same bits): for cross-checks.
    CpuReference,
    /// The wgpu engine (a hardware adapter, else lavapipe).
    Gpu,
    /// On a hardware GPU, the faster of the GPU and the CPU engine, both
    /// timed on the scene (once: the figures are cached per adapter,
    /// lattice and CPU); else the CPU. A software adapter (lavapipe) is
    /// never chosen: on this model it runs several times slower than one
    /// CPU thread (BENCHMARKS.md); ask for it with `--backend gpu`.
    Auto,
}

impl Backend {
    /// The precision when none is asked: f64 everywhere it can run. Mixed
    /// f32 is a choice, never a default where f64 exists (issue 31: whether
    /// it gives f64's outcome distribution is a measured claim,
    /// results/precision_ensembles.md). `--backend gpu` on an adapter
    /// without SHADER_F64 is the one place it defaults to mixed f32, and it
    /// says so.
    pub fn default_precision(self) -> Precision {
        match self {
            Backend::Cpu | Backend::CpuReference | Backend::Auto => Precision::F64,
            Backend::Gpu => gpu_default_precision(),
        }
    }
}

/// f64 when the GPU adapter has SHADER_F64, else mixed f32 (saying why).
/// Without an adapter, f64: building the engine then reports the missing
/// adapter.
fn gpu_default_precision() -> Precision {
    match crate::engines::gpu::context::shared() {
        Ok(ctx) if ctx.check_precision::<f64>().is_err() => {
            eprintln!(
                "slipfront: {} has no SHADER_F64: the GPU runs in mixed f32 \
                 (--backend cpu for f64)",
                ctx.info.name
            );
            Precision::F32
        }
        _ => Precision::F64,
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Precision {
    /// f64 throughout: the CPU engines, and the GPU where the adapter has
    /// f64 shaders (SHADER_F64).
    F64,
    /// Mixed: f32 forces and velocities, double-single (f32 + f32)
    /// displacements, junction anchors and drive position, compensated
    /// force sums. Every adapter has it.
    F32,
    /// Plain f32 displacements (CPU only): loses creep below one f32 ulp of
    /// u and changes long runs. Kept as the negative control of the
    /// precision tests.
    F32Plain,
}

/// Refuses a precision the backend cannot compute in (the GPU computes in
/// mixed f32, or in f64 where the adapter has it: checked when the engine
/// is built), naming the flag to change.
pub fn check_precision(backend: Backend, precision: Precision) -> Result<(), String> {
    if backend == Backend::Gpu && precision == Precision::F32Plain {
        return Err(
            "--precision f32-plain: the GPU engine computes in mixed f32 or in f64: use \
             --precision f32 or f64 (or --backend cpu for f32-plain)"
                .into(),
        );
    }
    Ok(())
}

impl Precision {
    /// Bytes of engine state for `model` in this precision
    /// (`Model::memory_bytes`: 8 and 8 bytes per float and accumulated
    /// coordinate in f64, 4 and 8 in mixed f32, 4 and 4 in plain f32).
    pub fn memory_bytes(self, model: &crate::model::Model) -> u64 {
        let (real, coord) = match self {
            Precision::F64 => (8, 8),
            Precision::F32 => (4, 8),
            Precision::F32Plain => (4, 4),
        };
        model.memory_bytes(real, coord) as u64
    }

    /// Refuses, naming the lattice and the precision, an engine for `model`
    /// that needs more memory than the machine has available now;
    /// `override_hint` says what to do instead.
    pub fn check_memory(
        self,
        model: &crate::model::Model,
        override_hint: &str,
    ) -> Result<(), String> {
        crate::engines::memory::check(
            self.memory_bytes(model),
            crate::engines::memory::available_bytes(),
            &format!("a {} × {} lattice in {self:?}", model.nx, model.nz),
            override_hint,
        )
    }

    /// The precision of a saved state (`EngineState::precision`).
    pub fn of_state(name: &str) -> Option<Precision> {
        use crate::model::real::precision_name;
        use crate::model::real::DoubleSingle;
        [
            (precision_name::<f64, f64>(), Precision::F64),
            (precision_name::<f32, DoubleSingle>(), Precision::F32),
            (precision_name::<f32, f32>(), Precision::F32Plain),
        ]
        .into_iter()
        .find_map(|(n, p)| (n == name).then_some(p))
    }
}

/// Refuses a malformed `SLIPFRONT_F32_PROBE` and says when the precision
/// study's instrument is on (an f64 engine with quantities held in f32).
fn check_probe(precision: Precision) -> Result<(), EngineError> {
    let mask = crate::engines::precision_probe::from_environment().map_err(EngineError::State)?;
    if mask != 0 && precision == Precision::F64 {
        eprintln!(
            "slipfront: {}={}: f64 engine with these quantities held in f32 (the precision \
             study's instrument, not an ordinary run)",
            crate::engines::precision_probe::VARIABLE,
            crate::engines::precision_probe::describe(mask)
        );
    }
    Ok(())
}

/// Builds the CPU engine (the sweep engine) in the requested precision.
pub fn cpu_engine(
    model: &Model,
    precision: Precision,
    threads: usize,
) -> Result<Box<dyn Engine>, EngineError> {
    check_probe(precision)?;
    Ok(match precision {
        Precision::F64 => Box::new(SweepEngine::<f64>::new(model, threads)?),
        Precision::F32 => Box::new(SweepEngine::<f32>::new(model, threads)?),
        Precision::F32Plain => Box::new(SweepEngine::<f32, f32>::new(model, threads)?),
    })
}

/// Builds the CPU reference engine (the kernels' twin) in the requested
/// precision.
pub fn cpu_reference_engine(
    model: &Model,
    precision: Precision,
    threads: usize,
) -> Result<Box<dyn Engine>, EngineError> {
    check_probe(precision)?;
    Ok(match precision {
        Precision::F64 => Box::new(CpuEngine::<f64>::new(model, threads)?),
        Precision::F32 => Box::new(CpuEngine::<f32>::new(model, threads)?),
        Precision::F32Plain => Box::new(CpuEngine::<f32, f32>::new(model, threads)?),
    })
}

/// Builds the engine for `backend` (the GPU with its default kernel choice).
pub fn make_engine(
    model: &Model,
    backend: Backend,
    precision: Precision,
    threads: usize,
) -> Result<Box<dyn Engine>, EngineError> {
    make_engine_with(model, backend, precision, threads, GpuOptions::default())
}

/// Builds the engine for `backend`, the GPU one with `gpu` options.
pub fn make_engine_with(
    model: &Model,
    backend: Backend,
    precision: Precision,
    threads: usize,
    gpu: GpuOptions,
) -> Result<Box<dyn Engine>, EngineError> {
    match backend {
        Backend::Cpu => cpu_engine(model, precision, threads),
        Backend::CpuReference => cpu_reference_engine(model, precision, threads),
        Backend::Gpu => {
            check_precision(backend, precision).map_err(EngineError::Gpu)?;
            if precision == Precision::F64 {
                return Ok(Box::new(GpuEngine::<f64>::with_precision(model, gpu)?));
            }
            Ok(Box::new(GpuEngine::with_options(model, gpu)?))
        }
        Backend::Auto => match crate::engines::gpu::context::shared() {
            Ok(ctx) if ctx.is_software() => {
                eprintln!(
                    "slipfront: only a software GPU adapter ({}); running on the CPU, \
                     which is faster (--backend gpu to use it anyway)",
                    ctx.info.name
                );
                cpu_engine(model, precision, threads)
            }
            Ok(ctx) if precision == Precision::F32 => {
                auto_on_hardware::<f32>(model, ctx, gpu, precision, threads)
            }
            Ok(ctx) if precision == Precision::F64 && ctx.check_precision::<f64>().is_ok() => {
                auto_on_hardware::<f64>(model, ctx, gpu, precision, threads)
            }
            Ok(ctx) => {
                if precision == Precision::F64 {
                    eprintln!(
                        "slipfront: {} has no SHADER_F64; running f64 on the CPU \
                         (--precision f32 for the GPU's mixed precision)",
                        ctx.info.name
                    );
                }
                cpu_engine(model, precision, threads)
            }
            Err(e) => {
                eprintln!("slipfront: no usable GPU adapter ({e}); running on the CPU");
                cpu_engine(model, precision, threads)
            }
        },
    }
}

/// `auto` on a hardware adapter: the GPU engine, or the CPU engine where
/// it steps this scene faster (`backend_choice`: both timed, or the
/// figures cached in `cache`; a CPU engine that would not fit in half the
/// memory available is not built, and a timing that fails leaves the GPU),
/// and what decided it.
pub fn faster_of_gpu_and_cpu<T: GpuReal>(
    model: &Model,
    ctx: GpuContext,
    gpu: GpuOptions,
    precision: Precision,
    threads: usize,
    cache: &ChoiceCache,
) -> Result<(Box<dyn Engine>, AutoChoice), EngineError>
where
    GpuEngine<T>: Engine,
{
    let engine = GpuEngine::<T>::with_precision_and_context(model, ctx.clone(), gpu)?;
    let needed = precision.memory_bytes(model);
    if let Err(not_timed) =
        backend_choice::cpu_fits(needed, crate::engines::memory::available_bytes())
    {
        return Ok((Box::new(engine), not_timed));
    }
    let choice = match backend_choice::resolve(model, &ctx, gpu, &engine, threads, cache) {
        Ok(choice) => choice,
        Err(e) => return Ok((Box::new(engine), AutoChoice::NotCompared(e.to_string()))),
    };
    if choice.cpu_is_faster() {
        drop(engine);
        return Ok((
            cpu_engine(model, precision, threads)?,
            AutoChoice::Timed(choice),
        ));
    }
    Ok((Box::new(engine), AutoChoice::Timed(choice)))
}

/// `faster_of_gpu_and_cpu` with the machine's cache, saying which and why.
fn auto_on_hardware<T: GpuReal>(
    model: &Model,
    ctx: GpuContext,
    gpu: GpuOptions,
    precision: Precision,
    threads: usize,
) -> Result<Box<dyn Engine>, EngineError>
where
    GpuEngine<T>: Engine,
{
    let cache = ChoiceCache::default_location();
    let (engine, choice) = faster_of_gpu_and_cpu::<T>(model, ctx, gpu, precision, threads, &cache)?;
    eprintln!("slipfront: --backend auto: {}", choice.describe());
    Ok(engine)
}

/// What `auto` means for a sweep or an ensemble: the GPU when a hardware
/// adapter computes in `precision`, else the CPU's threads (one scene per
/// core). Returns the backend and a line saying why.
pub fn resolve_auto(precision: Precision) -> (Backend, String) {
    match crate::engines::gpu::context::shared() {
        Ok(ctx) if ctx.is_software() => (
            Backend::Cpu,
            format!(
                "only a software GPU adapter ({}): scenes run on the CPU's threads",
                ctx.info.name
            ),
        ),
        // Mixed f32 on any adapter; f64 (ensembles too) where it has f64 shaders.
        Ok(ctx)
            if precision == Precision::F32
                || (precision == Precision::F64 && ctx.check_precision::<f64>().is_ok()) =>
        {
            (Backend::Gpu, format!("GPU on {}", ctx.info.name))
        }
        Ok(ctx) => (
            Backend::Cpu,
            format!(
                "the GPU ({}) does not compute in this precision: scenes run on the CPU's threads",
                ctx.info.name
            ),
        ),
        Err(e) => (
            Backend::Cpu,
            format!("no usable GPU adapter ({e}): scenes run on the CPU's threads"),
        ),
    }
}

/// Steps per second of `engine` on its scene, measured for about `seconds`
/// of wall time from the step it is at (after a short warm-up that also
/// absorbs a GPU's pipeline compilation).
pub fn measure_steps_per_second(engine: &mut dyn Engine, seconds: f64) -> Result<f64, EngineError> {
    // One untimed step: pipelines built, first dispatch made.
    engine.advance(1)?;
    let started = std::time::Instant::now();
    let mut steps = 0u64;
    let mut chunk = 1u64;
    loop {
        engine.advance(chunk)?;
        steps += chunk;
        let elapsed = started.elapsed().as_secs_f64();
        if elapsed >= seconds {
            return Ok(steps as f64 / elapsed);
        }
        // Growing calls, so that a GPU's per-call round trip is amortised
        // as in a run (which advances up to 20 000 steps a call), but never
        // past the time left at the rate so far: a large lattice is timed
        // over a few steps, not hung on a long call.
        let left = ((seconds - elapsed) * steps as f64 / elapsed.max(1e-9)) as u64;
        chunk = (chunk * 2).min(8192).min(left.max(1));
    }
}
