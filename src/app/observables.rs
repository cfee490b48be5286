//! Observables of a stick-slip run that a time-step study compares: the
//! first full sliding event (the front reaches the leading edge), the peak
//! of the loading curve before it and the force drop it causes.

use crate::app::runner::global_sample;
use crate::engines::{advance_to, Engine, EngineError};
use crate::model::Driver;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FirstEvent {
    /// Time (s after driving starts) when the leading-edge block first has
    /// fewer than half of its junctions pinned.
    pub time: f64,
    /// Peak F/F_N up to the event.
    pub peak_ratio: f64,
    /// Drop of F/F_N from the peak to its minimum within `after` s of the event.
    pub drop: f64,
}

/// Runs `engine` (from its current step) until the first full sliding event
/// and `after` seconds beyond, sampling every `sample` seconds. None if no
/// full sliding happens before `t_max`.
pub fn first_full_sliding(
    engine: &mut dyn Engine,
    t_max: f64,
    sample: f64,
    after: f64,
) -> Result<Option<FirstEvent>, EngineError> {
    let m = engine.model().clone();
    advance_to(engine, m.prep_steps)?;
    let origin = match m.driver {
        Driver::SideSpring { row, .. } => engine.snapshot()?.disp[row * m.nx][0],
        _ => 0.0,
    };
    let stride = ((sample / m.dt).round() as u64).max(1);
    let (mut peak, mut event, mut low): (f64, Option<f64>, f64) = (f64::MIN, None, f64::MAX);
    let mut step = m.prep_steps;
    loop {
        step += stride;
        advance_to(engine, step)?;
        let snap = engine.snapshot()?;
        let g = global_sample(&m, &snap, origin);
        match event {
            None => {
                peak = peak.max(g.drive_ratio);
                if snap.pinned_fraction(m.nx)[m.nx - 1] < 0.5 {
                    event = Some(snap.time);
                    low = g.drive_ratio;
                } else if snap.time > t_max {
                    return Ok(None);
                }
            }
            Some(t) => {
                low = low.min(g.drive_ratio);
                if snap.time > t + after {
                    return Ok(Some(FirstEvent {
                        time: t,
                        peak_ratio: peak,
                        drop: peak - low,
                    }));
                }
            }
        }
    }
}
