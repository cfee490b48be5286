//! Rate-and-state friction through a whole engine: one block pulled by a
//! stiff spring over the Dieterich–Ruina law (aging).
//!
//! - Steady sliding at four drive speeds over three decades: the friction
//!   level is μ_ss = μ0 + (a − b)·ln(V/V0), and the fitted slope is a − b.
//! - A velocity step V1 → 10·V1 (the spring's far end changes speed, from
//!   where it is): friction jumps by a·ln 10 (the direct effect), then
//!   decays to the new steady state; with the aging law and V constant the
//!   excess is b·ln(1 + 9·e^(−δ/Dc)) over slip δ, so ln(e^(excess/b) − 1)
//!   falls with slope −1/Dc: the fitted length is the evolution distance.

use super::{scene_model, spring_block, CaseResult, EngineFactory, VerifyError};
use crate::engines::step_params::{step_params, Consts};
use crate::engines::{advance_to, Engine};
use crate::model::scenario::{FrictionLaw, RateStateTable, StateEvolution};
use crate::model::Model;

const NORMAL_FORCE: f64 = 10.0;
/// N/m: far above the critical stiffness p·(b − a)/Dc = 5e4 N/m, so steady
/// sliding is stable, and stiff enough that after a velocity step the block
/// reaches the new speed within a few hundredths of Dc of slip (a near-ideal
/// step: the direct effect is not smeared by the evolution).
const DRIVE_STIFFNESS: f64 = 1.0e8;
const A: f64 = 0.01;
const B: f64 = 0.015;
const MU0: f64 = 0.6;
const V0: f64 = 1.0e-6;
const DC: f64 = 1.0e-6;
/// Drive speeds of the steady-state case (m/s): three decades.
pub const STEADY_SPEEDS: [f64; 4] = [1e-3, 1e-2, 1e-1, 1.0];
/// The velocity step: V1 → 10·V1.
const STEP_FROM: f64 = 1e-3;
const STEP_RATIO: f64 = 10.0;

/// The law of the cases; `perturb` scales b (the negative control).
pub fn law(perturb: f64) -> RateStateTable {
    RateStateTable {
        direct_effect: A,
        evolution_effect: B * perturb,
        reference_coefficient: MU0,
        reference_velocity: V0,
        characteristic_slip: DC,
        state_evolution: StateEvolution::Aging,
        initial_state: DC / STEP_FROM,
        slip_velocity: 1e-4,
    }
}

/// The block at drive speed `speed` for `end` s of driving, starting at
/// the state of steady sliding at that speed.
fn block_scene(table: &RateStateTable, speed: f64, end: f64) -> Result<Model, VerifyError> {
    let mut s = spring_block(
        "rate_state_block",
        NORMAL_FORCE,
        DRIVE_STIFFNESS,
        speed,
        |s| {
            s.friction.law = FrictionLaw::RateState;
            s.friction.static_coefficient = MU0;
            s.friction.dynamic_coefficient = MU0;
            s.friction.rate_state = Some(RateStateTable {
                initial_state: DC / speed,
                ..table.clone()
            });
            // A dashpot against the track damps the block's ringing on the
            // spring about critically (its force is not friction; the cases
            // read friction itself).
            s.damping.absolute_ratio = 5.0;
        },
    )?;
    s.time.end = end;
    scene_model(&s)
}

/// Driving time to reach steady sliding at `speed` and hold it: the
/// spring's loading, 20·Dc of slip, and the ringing's decay.
fn steady_time(speed: f64) -> f64 {
    3.0 * MU0 * NORMAL_FORCE / (DRIVE_STIFFNESS * speed) + 20.0 * DC / speed + 1e-4
}

/// μ = −friction/p of the block now.
fn coefficient(e: &mut dyn Engine) -> Result<(f64, f64), VerifyError> {
    let s = e.snapshot()?;
    Ok((-s.friction[0] / s.normal[0], s.disp[0][0]))
}

/// Mean μ over the last quarter of a steady run at `speed`.
pub fn steady_coefficient(
    factory: EngineFactory<'_>,
    table: &RateStateTable,
    speed: f64,
) -> Result<f64, VerifyError> {
    let model = block_scene(table, speed, steady_time(speed))?;
    let mut e = factory(&model)?;
    let first = model.prep_steps + model.drive_steps * 3 / 4;
    let samples = 50;
    let stride = ((model.total_steps() - first) / samples).max(1);
    let mut sum = 0.0;
    let mut n = 0.0;
    let mut step = first;
    while step <= model.total_steps() {
        advance_to(e.as_mut(), step)?;
        sum += coefficient(e.as_mut())?.0;
        n += 1.0;
        step += stride;
    }
    Ok(sum / n)
}

/// The friction after a velocity step V1 → 10·V1 at steady sliding:
/// (μ_ss at V1, the peak μ, the evolution distance fitted, μ at the end).
pub fn velocity_step(
    factory: EngineFactory<'_>,
    table: &RateStateTable,
) -> Result<(f64, f64, f64, f64), VerifyError> {
    let (v1, v2) = (STEP_FROM, STEP_FROM * STEP_RATIO);
    let before = block_scene(table, v1, steady_time(v1))?;
    let mut e = factory(&before)?;
    advance_to(e.as_mut(), before.total_steps())?;
    let mu_1 = coefficient(e.as_mut())?.0;
    let mut state = e.save_state()?;
    // After the step, 12·Dc of slip at V2.
    let after = block_scene(table, v2, steady_time(v1) + 12.0 * DC / v2)?;
    // The spring's far end goes on from where it is, at V2.
    let at = |m: &Model| step_params(&Consts::<f64>::new(m), state.step).drive_offset;
    let shift = at(&before) - at(&after);
    state.drive_origin[0] += shift;
    let mut e = factory(&after)?;
    e.load_state(&state)?;
    let (mut peak, mut x_start) = (f64::MIN, None);
    // (slip, excess over μ_ss at V2 in the law's exact form).
    let mu_ss2 = MU0 + (A - B) * (v2 / V0).ln();
    let b = table.evolution_effect;
    let mut curve = Vec::new();
    let mut last = mu_1;
    let mut step = state.step;
    while step < after.total_steps() {
        step += 1;
        advance_to(e.as_mut(), step)?;
        let (mu, x) = coefficient(e.as_mut())?;
        let x0 = *x_start.get_or_insert(x);
        peak = peak.max(mu);
        let u = ((mu - mu_ss2) / b).exp() - 1.0;
        if (1e-3..3e-2).contains(&u) {
            curve.push((x - x0, u.ln()));
        }
        last = mu;
    }
    let slope = fit_slope(&curve);
    Ok((mu_1, peak, -1.0 / slope, last))
}

/// Least-squares slope of y against x (NaN for fewer than 3 points).
fn fit_slope(points: &[(f64, f64)]) -> f64 {
    if points.len() < 3 {
        return f64::NAN;
    }
    let n = points.len() as f64;
    let mx = points.iter().map(|p| p.0).sum::<f64>() / n;
    let my = points.iter().map(|p| p.1).sum::<f64>() / n;
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    sxy / sxx
}

/// The cases of a law scaled by `perturb` in b (1: the law itself).
pub fn rate_state_cases_of(
    factory: EngineFactory<'_>,
    perturb: f64,
) -> Result<Vec<CaseResult>, VerifyError> {
    let table = law(perturb);
    let expected = law(1.0);
    let mut worst: f64 = 0.0;
    let mut points = Vec::new();
    for v in STEADY_SPEEDS {
        let mu = steady_coefficient(factory, &table, v)?;
        let want = expected.steady_state_coefficient(v);
        worst = worst.max(((mu - want) / want).abs());
        points.push(((v / V0).ln(), mu));
    }
    let slope = fit_slope(&points);
    let (mu_1, peak, evolution, _) = velocity_step(factory, &table)?;
    let direct = (peak - mu_1) / STEP_RATIO.ln();
    Ok(vec![
        CaseResult::at_most("rate_state_steady_friction_rel_error", worst, 0.01, "1"),
        CaseResult::new(
            "rate_state_steady_slope_a_minus_b",
            slope,
            A - B,
            0.02 * (A - B).abs(),
            "1",
        ),
        CaseResult::new("rate_state_direct_effect_a", direct, A, 0.05 * A, "1"),
        CaseResult::new(
            "rate_state_evolution_distance_dc",
            evolution,
            DC,
            0.05 * DC,
            "m",
        ),
    ])
}

pub fn rate_state_cases(factory: EngineFactory<'_>) -> Result<Vec<CaseResult>, VerifyError> {
    rate_state_cases_of(factory, 1.0)
}
