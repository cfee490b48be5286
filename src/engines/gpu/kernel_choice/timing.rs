//! Timing the launches on the scene: from the end of its normal-load
//! phase where that is reached within a budget, a warm-up, then the
//! fastest of a few repeats.

use super::{launches, ChoiceSource, KernelChoice, Launch, TimedPhase};
use crate::engines::gpu::context::GpuContext;
use crate::engines::gpu::options::GpuOptions;
use crate::engines::gpu::precision::GpuReal;
use crate::engines::gpu::GpuEngine;
use crate::engines::{EngineError, EngineState};
use crate::model::Model;
use std::time::Instant;

/// Steps run before timing: the pipeline is compiled and warm.
const WARM_UP_STEPS: u64 = 32;
/// Timed repeats per kernel; the fastest counts (others share the GPU).
const REPEATS: usize = 3;
/// Steps per timed repeat at most, and the wall time one repeat aims at
/// (a large lattice is timed over fewer steps).
const MAX_TIMED_STEPS: u64 = 256;
const TARGET_REPEAT_SECONDS: f64 = 0.05;
/// The most wall time spent stepping the normal-load phase before timing
/// (once for all candidates). A lattice whose load phase takes longer (a
/// large one: more blocks, a shorter time step, more steps) is timed from
/// its initial state, and the choice says so.
pub const PREPARE_BUDGET_SECONDS: f64 = 3.0;
/// Steps timed after the warm-up to estimate the load phase's wall time.
const ESTIMATE_STEPS: u64 = 32;

/// Wall time per step of `launch` on the scenes `models` (one, or an
/// ensemble stepped in one dispatch), from `start` (one state per scene)
/// or else from their initial state: a warm-up, then the fastest of a few
/// repeats (each an `advance`, which returns when its steps have run on
/// the device).
pub fn time_kernel<T: GpuReal>(
    models: &[Model],
    ctx: &GpuContext,
    opts: GpuOptions,
    launch: Launch,
    start: Option<&[EngineState]>,
) -> Result<f64, EngineError> {
    let opts = launch.options(opts);
    let mut engine = GpuEngine::<T>::build(models, ctx.clone(), opts, models.len() > 1)?;
    if let Some(states) = start {
        engine.start_scenes_from(&states.iter().collect::<Vec<_>>())?;
    }
    let started = Instant::now();
    engine.advance_steps(WARM_UP_STEPS)?;
    let rough = started.elapsed().as_secs_f64() / WARM_UP_STEPS as f64;
    let steps = ((TARGET_REPEAT_SECONDS / rough.max(1e-9)) as u64).clamp(8, MAX_TIMED_STEPS);
    let mut best = f64::INFINITY;
    for _ in 0..REPEATS {
        let t = Instant::now();
        engine.advance_steps(steps)?;
        best = best.min(t.elapsed().as_secs_f64() / steps as f64);
    }
    Ok(best)
}

/// The states the candidates are timed from: the scenes stepped by
/// `launch` to the last step of their normal-load phase, if that takes at
/// most `budget` seconds (estimated from a few steps after a warm-up);
/// else none, and why.
pub fn driving_start<T: GpuReal>(
    models: &[Model],
    ctx: &GpuContext,
    opts: GpuOptions,
    launch: Launch,
    budget: f64,
) -> (Option<Vec<EngineState>>, TimedPhase) {
    let end = models[0].prep_steps.saturating_sub(1);
    if models.iter().any(|m| m.prep_steps != models[0].prep_steps) {
        let why = "the scenes' normal-load phases differ in length".to_string();
        return (None, TimedPhase::NormalLoad { why });
    }
    if end == 0 {
        return (None, TimedPhase::Driving { from_step: 0 });
    }
    let stepped = || -> Result<Result<Vec<EngineState>, String>, EngineError> {
        let mut engine =
            GpuEngine::<T>::build(models, ctx.clone(), launch.options(opts), models.len() > 1)?;
        engine.advance_steps(WARM_UP_STEPS.min(end))?;
        let estimate = ESTIMATE_STEPS.min(end - engine.step);
        let t = Instant::now();
        engine.advance_steps(estimate)?;
        let per_step = t.elapsed().as_secs_f64() / estimate.max(1) as f64;
        let left = end - engine.step;
        let reach = per_step * left as f64;
        if reach > budget {
            return Ok(Err(format!(
                "reaching driving would take {reach:.1} s ({left} steps at {:.1} µs/step on {}), \
                 over the {budget} s budget",
                per_step * 1e6,
                launch.name()
            )));
        }
        engine.advance_steps(left)?;
        (0..models.len())
            .map(|k| engine.save_state_of(k))
            .collect::<Result<Vec<_>, _>>()
            .map(Ok)
    };
    match stepped() {
        Ok(Ok(states)) => (Some(states), TimedPhase::Driving { from_step: end }),
        Ok(Err(why)) => (None, TimedPhase::NormalLoad { why }),
        Err(e) => {
            let why = format!(
                "{} could not step the normal-load phase: {e}",
                launch.name()
            );
            (None, TimedPhase::NormalLoad { why })
        }
    }
}

/// Times every launch (`launches`) on the scenes `models` (one, or an
/// ensemble of one lattice shape) from the start of driving
/// (`driving_start`, within `PREPARE_BUDGET_SECONDS`) and takes the
/// fastest. A launch that cannot be built (a buffer too large, a lattice
/// beyond workgroup memory, a device error) is skipped with its reason; if
/// none can, the first error is returned.
pub fn measure<T: GpuReal>(
    models: &[Model],
    ctx: &GpuContext,
    opts: GpuOptions,
) -> Result<KernelChoice, EngineError> {
    measure_within::<T>(models, ctx, opts, PREPARE_BUDGET_SECONDS)
}

/// `measure` with `budget` seconds to step the normal-load phase.
pub fn measure_within<T: GpuReal>(
    models: &[Model],
    ctx: &GpuContext,
    opts: GpuOptions,
    budget: f64,
) -> Result<KernelChoice, EngineError> {
    let mut timings = Vec::new();
    let mut skipped = Vec::new();
    let mut first_error = None;
    let launches = launches(&models[0], models.len(), opts, &ctx.limits);
    // One-step (always a candidate, first) steps the load phase.
    let (start, phase) = driving_start::<T>(models, ctx, opts, launches[0], budget);
    for launch in launches {
        match time_kernel::<T>(models, ctx, opts, launch, start.as_deref()) {
            Ok(s) => timings.push((launch, s)),
            Err(e) => {
                skipped.push((launch, e.to_string()));
                first_error.get_or_insert(e);
            }
        }
    }
    let Some(&(launch, _)) = timings.iter().min_by(|a, b| a.1.total_cmp(&b.1)) else {
        return Err(first_error.expect("at least one candidate (one-step always is)"));
    };
    Ok(KernelChoice {
        launch,
        timings,
        source: ChoiceSource::Measured,
        skipped,
        scenes: models.len(),
        phase,
    })
}
