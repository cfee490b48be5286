//! One interface block with Ns junctions dragged at constant speed v: the
//! steady friction coefficient against the renewal formula
//! μ(v) = [(μs/2)·t_a + μd·⟨t_R⟩]/(t_a + ⟨t_R⟩), t_a = μs·f_N/(k_j·v).

use super::{bare_scene, scene_model, CaseResult, EngineFactory, VerifyError};
use crate::engines::advance_to;
use crate::model::scenario::{
    Drive, DriveMode, FrictionLaw, JunctionStiffness, Junctions, Scenario,
};

/// The renewal prediction of the steady friction coefficient.
pub fn renewal_friction_coefficient(mu_s: f64, mu_d: f64, pinned_time: f64, slip_time: f64) -> f64 {
    (0.5 * mu_s * pinned_time + mu_d * slip_time) / (pinned_time + slip_time)
}

const NS: u32 = 100;
const NORMAL: f64 = 10.0;
const SLIP_MEAN: f64 = 0.2e-3;
const SLIP_STD: f64 = 0.06e-3;
const STIFFNESS: f64 = 5.0e4;

/// One heavy interface block (72 g) with `count` junctions of constant
/// stiffness, normal load NORMAL, its top dragged at `speed`. The foundation
/// period (0.65 ms) is long against the time step, so one step resolves the
/// junction cycles. The time step is ⟨t_R⟩/300.
pub(super) fn dragged_block(
    count: u32,
    speed: f64,
    slip_mean: f64,
    slip_std: f64,
) -> Result<Scenario, VerifyError> {
    let mut s = bare_scene("junction_drag");
    s.geometry.nx = 1;
    s.geometry.nz = 1;
    s.geometry.length = 0.1;
    s.geometry.height = 0.1;
    s.foundation.stiffness_ratio = 0.5;
    s.friction.law = FrictionLaw::Junctions;
    s.friction.junctions = Some(Junctions {
        count,
        stiffness: JunctionStiffness::Constant,
        stiffness_coefficient: 39.2e9,
        constant_stiffness: STIFFNESS,
        stiffness_ratio: None,
        slip_time_mean: slip_mean,
        slip_time_std: slip_std,
        at_rest: Default::default(),
    });
    s.loading.normal.force = NORMAL;
    // Ramp and relax over many periods of the block on its foundation.
    let probe = scene_model(&s)?;
    let foundation_time = (probe.mass / probe.k_foundation).sqrt();
    s.loading.normal.ramp_time = 10.0 * foundation_time;
    s.loading.normal.relax_time = 40.0 * foundation_time;
    s.loading.normal.relax_damping_ratio = 0.5f64.sqrt();
    s.loading.drive = Drive {
        mode: DriveMode::TopVelocity,
        stiffness: None,
        height: None,
        velocity: Some(speed),
        force_rate: None,
    };
    s.time.dt_fraction = None;
    s.time.dt = Some(slip_mean / 300.0);
    Ok(s)
}

/// Measured mean friction coefficient when dragged at `speed`, and the
/// pinned time t_a of the renewal argument.
fn drag(factory: EngineFactory<'_>, speed: f64) -> Result<(f64, f64), VerifyError> {
    let mut s = dragged_block(NS, speed, SLIP_MEAN, SLIP_STD)?;
    let f_n = NORMAL / NS as f64;
    let pinned_time = s.friction.static_coefficient * f_n / (STIFFNESS * speed);
    let cycle = pinned_time + SLIP_MEAN;
    // Skip two cycles of start-up; average over 60 more.
    let skip = 2.0 * cycle;
    s.time.end = skip + 60.0 * cycle;
    let model = scene_model(&s)?;
    let mut engine = factory(&model)?;
    let first = model.prep_steps + (skip / model.dt) as u64;
    advance_to(engine.as_mut(), first)?;
    let stride = 7u64;
    let (mut sum, mut n) = (0.0, 0.0);
    let mut step = first;
    while step + stride <= model.total_steps() {
        step += stride;
        advance_to(engine.as_mut(), step)?;
        let snap = engine.snapshot()?;
        sum += -snap.friction[0] / snap.normal[0];
        n += 1.0;
    }
    Ok((sum / n, pinned_time))
}

pub fn junction_drag_cases(factory: EngineFactory<'_>) -> Result<Vec<CaseResult>, VerifyError> {
    let (mu_s, mu_d) = (0.4, 0.17);
    let f_n = NORMAL / NS as f64;
    // Speeds with t_a = 10, 1 and 0.1 ⟨t_R⟩: across the weakening range.
    let mut out = Vec::new();
    for ratio in [10.0, 1.0, 0.1] {
        let speed = mu_s * f_n / (STIFFNESS * ratio * SLIP_MEAN);
        let (measured, pinned_time) = drag(factory, speed)?;
        let expected = renewal_friction_coefficient(mu_s, mu_d, pinned_time, SLIP_MEAN);
        out.push(CaseResult::new(
            &format!("junction_drag_friction_v{speed:.2e}"),
            measured,
            expected,
            0.02 * expected,
            "1",
        ));
    }
    Ok(out)
}
