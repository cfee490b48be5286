//! The counter-based junction RNG: reproducible draws and the mean and
//! spread of slip times within sampling error.

use super::{scene_model, CaseResult, EngineFactory, VerifyError};
use crate::engines::advance_to;
use crate::model::rng::slip_steps;

/// The engine's own draws: one dragged block with 2000 junctions that all
/// break on the same step s0. Each re-pin step minus s0 must be the
/// counter-based draw for (seed, 0, j, 1), to within one step (f32 log and
/// cos may round a draw across a step boundary); their mean and spread must
/// match ⟨t_R⟩/dt and σ_R/dt within sampling error.
fn engine_draw_cases(factory: EngineFactory<'_>) -> Result<Vec<CaseResult>, VerifyError> {
    let count = 2000u32;
    let mut s = super::junction_drag::dragged_block(count, 4.0e-2, 2.0e-4, 6.0e-5)?;
    s.time.end = 2.0e-5;
    let model = scene_model(&s)?;
    let mut engine = factory(&model)?;
    advance_to(engine.as_mut(), model.total_steps())?;
    let snap = engine.snapshot()?;
    let (mean, std) = (2.0e-4 / model.dt, 6.0e-5 / model.dt);
    let draw = |j: u32| slip_steps::<f64>(model.seed, 0, j, 1, mean, std) as i64;
    // Junctions still in their first slip (the few with draws under ~27
    // steps have re-pinned, and may have broken again, and are left out).
    let slipping: Vec<u32> = (0..count)
        .filter(|&j| {
            snap.slip_steps_left[j as usize] != crate::model::junction::PINNED
                && snap.ruptures[j as usize] == 1
        })
        .collect();
    // The step each junction will re-pin at: now plus its steps left.
    let repin_step = |j: u32| snap.step as i64 + snap.slip_steps_left[j as usize] as i64;
    let j0 = *slipping.first().unwrap_or(&0);
    let first = repin_step(j0) - draw(j0);
    let durations: Vec<f64> = slipping
        .iter()
        .map(|&j| (repin_step(j) - first) as f64)
        .collect();
    let matching = slipping
        .iter()
        .zip(&durations)
        .filter(|(&j, &d)| (d as i64 - draw(j)).abs() <= 1)
        .count();
    let n = slipping.len() as f64;
    let m = durations.iter().sum::<f64>() / n;
    let sd = (durations.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    Ok(vec![
        CaseResult::new(
            "rng_engine_draws_match_counter",
            matching as f64,
            n,
            0.0,
            "junctions",
        ),
        CaseResult::at_most(
            "rng_engine_junctions_repinned_early",
            count as f64 - n,
            10.0,
            "junctions",
        ),
        CaseResult::new(
            "rng_engine_slip_time_mean",
            m,
            mean,
            4.0 * std / n.sqrt(),
            "steps",
        ),
        CaseResult::new(
            "rng_engine_slip_time_std",
            sd,
            std,
            4.0 * std / (2.0 * n).sqrt(),
            "steps",
        ),
    ])
}

pub fn rng_cases(factory: EngineFactory<'_>) -> Result<Vec<CaseResult>, VerifyError> {
    let mut out = rng_function_cases()?;
    out.extend(engine_draw_cases(factory)?);
    Ok(out)
}

fn rng_function_cases() -> Result<Vec<CaseResult>, VerifyError> {
    let (mean, std) = (2000.0f64, 200.0f64);
    let n = 200_000u32;
    let draw = |i: u32| slip_steps::<f64>(1, i % 57, (i / 57) % 100, i / 5700 + 1, mean, std);
    let repeats = (0..1000).filter(|&i| draw(i) == draw(i)).count();
    let samples: Vec<f64> = (0..n).map(|i| draw(i) as f64).collect();
    let m = samples.iter().sum::<f64>() / n as f64;
    let var = samples.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1) as f64;
    let sd = var.sqrt();
    let nf = n as f64;
    // Four standard errors; rounding to whole steps adds 1/12 step² of variance.
    Ok(vec![
        CaseResult::new(
            "rng_same_counter_same_draw",
            repeats as f64,
            1000.0,
            0.0,
            "draws",
        ),
        CaseResult::new(
            "rng_slip_time_mean",
            m,
            mean,
            4.0 * std / nf.sqrt(),
            "steps",
        ),
        CaseResult::new(
            "rng_slip_time_std",
            sd,
            (std * std + 1.0 / 12.0).sqrt(),
            4.0 * std / (2.0 * nf).sqrt(),
            "steps",
        ),
    ])
}
