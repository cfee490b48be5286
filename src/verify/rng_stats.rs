//! The counter-based junction RNG: reproducible draws and the mean and
//! spread of slip times within sampling error.

use super::{CaseResult, EngineFactory, VerifyError};
use crate::rng::slip_steps;

pub fn rng_cases(_factory: EngineFactory<'_>) -> Result<Vec<CaseResult>, VerifyError> {
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
