//! A single block pulled through a spring over Amontons–Coulomb friction,
//! against the exact piecewise solution (thesis Appendix A, Fig. A.3): the
//! leapfrog error in position is O(dt).

use super::{scene_model, spring_block, CaseResult, EngineFactory, VerifyError};
use crate::engines::advance_to;
use crate::model::scenario::FrictionLaw;

/// Parameters of the exact solution.
#[derive(Debug, Clone, Copy)]
pub struct CoulombExact {
    pub mass: f64,
    pub stiffness: f64,
    pub velocity: f64,
    pub normal: f64,
    pub mu_s: f64,
    pub mu_d: f64,
}

/// Exact position at time `t` of a block at rest at x = 0 at t = 0, pulled
/// by a spring whose far end moves at V, with static μs and dynamic μd:
/// stick until K·(V t − x) = μs·N, slide (ξ'' = −ω²ξ about the sliding
/// equilibrium) until the velocity vanishes, stick again, and so on.
pub fn coulomb_exact_position(p: &CoulombExact, t: f64) -> f64 {
    let omega = (p.stiffness / p.mass).sqrt();
    let drop = (p.mu_s - p.mu_d) * p.normal / p.stiffness;
    let c = drop * omega;
    // Slip duration: V(1 − cos θ) + c sin θ = 0 at θ = 2π − 2 atan(c/V).
    let theta = 2.0 * std::f64::consts::PI - 2.0 * (c / p.velocity).atan();
    let slip_time = theta / omega;
    let mut x = 0.0;
    loop {
        // Stuck at x from t0: slips when K(V t − x) reaches μs N.
        let onset = (p.mu_s * p.normal / p.stiffness + x) / p.velocity;
        if t <= onset {
            return x;
        }
        let tau = t - onset;
        let slide = |tau: f64| {
            // x(τ) = x_on + Vτ + ξ(τ) − ξ(0), ξ = A cos ωτ + B sin ωτ.
            let a = -drop;
            let b = -p.velocity / omega;
            x + p.velocity * tau + a * (omega * tau).cos() + b * (omega * tau).sin() - a
        };
        if tau <= slip_time {
            return slide(tau);
        }
        x = slide(slip_time);
    }
}

const DRIVE_STIFFNESS: f64 = 4.0e6;
const NORMAL_FORCE: f64 = 10.0;
/// Runs per time step, at driving speeds 10% apart: each puts the slip
/// onset at another phase of the step grid, and their mean error shows the
/// O(dt) envelope rather than one fortuitous phase (thesis Fig. A.3).
const SPEEDS: usize = 8;

/// Mean |x_num − x_exact| over one run at time step `fraction`·T, driven at
/// `speed_factor` times the speed that makes the stick phase last five slip
/// durations.
fn coulomb_error(
    factory: EngineFactory<'_>,
    fraction: f64,
    speed_factor: f64,
) -> Result<f64, VerifyError> {
    let mut s = spring_block("coulomb_block", NORMAL_FORCE, DRIVE_STIFFNESS, 0.0, |s| {
        s.friction.law = FrictionLaw::Coulomb;
        s.time.dt_fraction = Some(fraction);
    })?;
    let probe = scene_model(&s)?;
    // Times scale with the block: slip lasts π√(m/K).
    let slip_time = std::f64::consts::PI * (probe.mass / DRIVE_STIFFNESS).sqrt();
    let mu_s = s.friction.static_coefficient;
    let speed = speed_factor * mu_s * NORMAL_FORCE / (DRIVE_STIFFNESS * 5.0 * slip_time);
    s.loading.drive.velocity = Some(speed);
    s.time.end = 9.0 * slip_time;
    let model = scene_model(&s)?;
    let mut engine = factory(&model)?;
    advance_to(engine.as_mut(), model.prep_steps)?;
    let start = engine.snapshot()?;
    let exact = CoulombExact {
        mass: model.mass,
        stiffness: DRIVE_STIFFNESS,
        velocity: speed,
        normal: start.normal[0],
        mu_s: model.mu_s,
        mu_d: model.mu_d,
    };
    let x0 = start.disp[0][0];
    let samples = 90u64;
    let stride = (model.drive_steps / samples).max(1);
    let (mut sum, mut n) = (0.0, 0.0);
    let mut step = model.prep_steps;
    while step + stride <= model.total_steps() {
        step += stride;
        advance_to(engine.as_mut(), step)?;
        let snap = engine.snapshot()?;
        sum += (snap.disp[0][0] - x0 - coulomb_exact_position(&exact, snap.time)).abs();
        n += 1.0;
    }
    Ok(sum / n)
}

/// Mean error (m) over the ensemble of driving speeds, at dt = `fraction`·T.
pub fn coulomb_ensemble_error(
    factory: EngineFactory<'_>,
    fraction: f64,
) -> Result<f64, VerifyError> {
    let mut total = 0.0;
    for i in 0..SPEEDS {
        total += coulomb_error(factory, fraction, 1.0 + 0.1 * i as f64)?;
    }
    Ok(total / SPEEDS as f64)
}

pub fn coulomb_block_cases(factory: EngineFactory<'_>) -> Result<Vec<CaseResult>, VerifyError> {
    let fractions = [1.0 / 50.0, 1.0 / 100.0, 1.0 / 200.0, 1.0 / 400.0];
    let mut errors = Vec::new();
    for f in fractions {
        errors.push(coulomb_ensemble_error(factory, f)?);
    }
    let lx: Vec<f64> = fractions.iter().map(|f| f.ln()).collect();
    let ly: Vec<f64> = errors.iter().map(|e| e.ln()).collect();
    let order = super::waves::least_squares_slope(&lx, &ly);
    // Slip amplitude 2(μs − μd)N/K = 1.15 µm: the error at T/50 must stay
    // under 1% of it, and fall with dt (T/400: an eighth of that bound).
    Ok(vec![
        CaseResult::at_most("coulomb_block_error_dt_T50", errors[0], 1.0e-8, "m"),
        CaseResult::at_most("coulomb_block_error_dt_T400", errors[3], 1.25e-9, "m"),
        CaseResult::new("coulomb_block_convergence_order", order, 1.0, 0.25, "1"),
    ])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_solution_sticks_then_slips_by_twice_the_drop() {
        let p = CoulombExact {
            mass: 1e-4,
            stiffness: 4e6,
            velocity: 1e-3,
            normal: 10.0,
            mu_s: 0.4,
            mu_d: 0.17,
        };
        let onset = p.mu_s * p.normal / p.stiffness / p.velocity;
        assert_eq!(coulomb_exact_position(&p, 0.5 * onset), 0.0);
        // Slow driving: one slip moves the block by ≈ 2(μs − μd)N/K.
        let slip = 2.0 * (p.mu_s - p.mu_d) * p.normal / p.stiffness;
        let after = coulomb_exact_position(&p, onset + 1e-4);
        assert!((after - slip).abs() < 0.05 * slip, "{after} vs {slip}");
    }
}
