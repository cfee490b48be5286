//! CPU twin of `shaders/laws/rate_state.wgsl`: rate-and-state friction of
//! one interface block over one leapfrog step, implicit in the velocity.
//!
//! Why implicit: dμ/dV = a/V is huge for a block near rest, so friction
//! evaluated at the old velocity would need dt ≪ m·V/(a·p) — no time step
//! would do. Instead the step's new velocity V' = v(n+½) and its friction
//! level μ solve together
//!     V' = X − κ·μ,  μ = μ(V', θ),  X = |v(n−½) + dt·other/m|,  κ = dt·p/m,
//! (the friction opposes the free motion, so V' keeps X's sign). With
//! V(μ) = V0·(e^((μ−ψ)/a) − e^(−(μ+ψ)/a)), the inverse of the regularised
//! law, that is one root of k(μ) = V(μ) − X + κμ on [0, X/κ]: increasing
//! and convex, so a bracketed Newton iteration finds it from above. Then
//! θ evolves over the step at the new speed |V'| (exactly, for a constant
//! speed over the step).

use super::{AGING, CONSTANTS};
use crate::model::friction::{BlockContact, LAW_CONSTANTS};
use crate::model::real::{Coordinate, Real};

/// The largest number of Newton/bisection iterations of one solve; a
/// solve converges in a few (bisection only while e^((μ−ψ)/a) overflows).
pub const MAX_ITERATIONS: u32 = 200;

/// The law's constants by name.
#[derive(Debug, Clone, Copy)]
struct Constants<T> {
    a: T,
    b: T,
    mu0: T,
    v0: T,
    dc: T,
    aging: bool,
    slip_velocity: T,
}

impl<T: Real> Constants<T> {
    fn of(k: &[T; LAW_CONSTANTS]) -> Self {
        const { assert!(CONSTANTS <= LAW_CONSTANTS) };
        Constants {
            a: k[0],
            b: k[1],
            mu0: k[2],
            v0: k[3],
            dc: k[4],
            aging: k[5] == T::from_f64(AGING),
            slip_velocity: k[6],
        }
    }
}

/// μ(V, θ) = a·asinh(V/(2V0)·e^(ψ/a)), ψ = μ0 + b·ln(V0·θ/Dc), for
/// V ≥ 0 (analysis and tests; the step solves for μ directly).
pub fn friction_coefficient(k: &[f64; LAW_CONSTANTS], velocity: f64, theta: f64) -> f64 {
    let c = Constants::of(k);
    let psi = c.mu0 + c.b * (c.v0 * theta / c.dc).ln();
    // asinh(z) with z = e^L can overflow z itself: use ln(2z) once z ≫ 1.
    let l = (velocity / (2.0 * c.v0)).ln() + psi / c.a;
    if l > 20.0 {
        c.a * (l + std::f64::consts::LN_2)
    } else {
        c.a * l.exp().asinh()
    }
}

/// φ(z) = (1 − e^(−z))/z, by its series where the difference would
/// cancel (|z| < 0.01: the next term is below 2e-16).
#[inline]
fn phi<T: Real>(z: T) -> T {
    let one = T::one();
    if z.abs() < T::from_f64(1e-2) {
        // 1 − z/2 + z²/6 − z³/24 + z⁴/120 − z⁵/720.
        let mut p = -one / T::from_f64(720.0);
        p = p * z + one / T::from_f64(120.0);
        p = p * z - one / T::from_f64(24.0);
        p = p * z + one / T::from_f64(6.0);
        p = p * z - one / T::from_f64(2.0);
        p * z + one
    } else {
        (one - (-z).exp()) / z
    }
}

/// The change of θ over `dt` at constant slip speed `speed` ≥ 0, from
/// `theta`: exact for either evolution law, and written as an increment so
/// that a tiny one (aging at rest adds dt) is not lost when added to a
/// large θ (`Coordinate::add`). With x = V·dt/Dc:
/// - aging, θ' = θ·e^(−x) + (Dc/V)(1 − e^(−x)): Δθ = dt·φ(x)·(1 − θV/Dc);
/// - slip, ln θ' = ln θ − (1 − e^(−x))·ln(θV/Dc): Δθ = θ·(e^y − 1) with
///   y = −x·φ(x)·ln(θV/Dc), e^y − 1 = y·φ(−y); none at rest.
#[inline]
pub fn state_increment<T: Real>(k: &[T; LAW_CONSTANTS], theta: T, speed: T, dt: T) -> T {
    let c = Constants::of(k);
    let x = speed * dt / c.dc;
    if c.aging {
        dt * phi(x) * (T::one() - theta * speed / c.dc)
    } else if speed > T::zero() {
        let y = -(x * phi(x)) * (theta * speed / c.dc).ln();
        theta * (y * phi(-y))
    } else {
        T::zero()
    }
}

/// θ after `dt` at constant slip speed `speed` (`state_increment` added).
pub fn evolve_state<T: Real>(k: &[T; LAW_CONSTANTS], theta: T, speed: T, dt: T) -> T {
    theta + state_increment(k, theta, speed, dt)
}

/// The friction level μ ≥ 0 of a step: the root of
/// k(μ) = V0·(e^((μ−ψ)/a) − e^(−(μ+ψ)/a)) − X + κμ for X > 0, κ > 0.
#[inline]
pub fn solve_friction_level<T: Real>(a: T, v0: T, psi: T, x: T, kappa: T) -> T {
    // e^z held in [−80, 80]: no overflow in f32, and the solve only needs
    // the sign of k far from its root.
    let (lo_z, hi_z) = (T::from_f64(-80.0), T::from_f64(80.0));
    let exp = |z: T| z.max(lo_z).min(hi_z).exp();
    let k = |mu: T| v0 * (exp((mu - psi) / a) - exp(-(mu + psi) / a)) - x + kappa * mu;
    let two = T::from_f64(2.0);
    let mut hi = x / kappa;
    // Where V(μ) ≈ 2X: usually far below X/κ, and an upper bound when k ≥ 0.
    let guess = psi + a * (two * x / v0 + T::one()).ln();
    if guess > T::zero() && guess < hi && k(guess) >= T::zero() {
        hi = guess;
    }
    let mut lo = T::zero();
    let mut mu = hi;
    let tol = T::epsilon() * T::from_f64(8.0);
    for _ in 0..MAX_ITERATIONS {
        let kv = k(mu);
        if kv == T::zero() {
            break;
        }
        if kv > T::zero() {
            hi = mu;
        } else {
            lo = mu;
        }
        let slope = v0 / a * (exp((mu - psi) / a) + exp(-(mu + psi) / a)) + kappa;
        let mut next = mu - kv / slope;
        // Outside the bracket (far from the root, where e^z is held):
        // bisect.
        if !(next > lo && next < hi) {
            next = (lo + hi) / two;
        }
        let done = (next - mu).abs() <= tol * (mu.abs() + a);
        mu = next;
        if done || hi - lo <= tol * (hi + a) {
            break;
        }
    }
    mu
}

/// The friction along x on one interface block over one step, updating
/// its θ (`state[0]`) and `slide` pair (direction 0/±1 while |V'| is at
/// least the slip velocity; count of stick → slip transitions).
#[inline]
pub fn rate_state<T: Real, C: Coordinate<T>>(
    k: &[T; LAW_CONSTANTS],
    b: &BlockContact<T>,
    slide: &mut [i32; 2],
    state: &mut [C],
) -> T {
    let c = Constants::of(k);
    let theta = state[0].value();
    if b.preparing {
        // The interface holds while the normal load is applied (as the
        // other laws' do), and its contacts age at rest.
        state[0] = state[0].add(state_increment(k, theta, T::zero(), b.dt));
        slide[0] = 0;
        return -b.other_force - b.mass * b.velocity / b.dt;
    }
    let free = b.velocity + b.dt * b.other_force / b.mass;
    let x = free.abs();
    let kappa = b.dt * b.normal / b.mass;
    let (mu, speed) = if x == T::zero() || kappa <= T::zero() {
        (T::zero(), x)
    } else {
        let psi = c.mu0 + c.b * (c.v0 * theta / c.dc).ln();
        let mu = solve_friction_level(c.a, c.v0, psi, x, kappa);
        (mu, (x - kappa * mu).max(T::zero()))
    };
    state[0] = state[0].add(state_increment(k, theta, speed, b.dt));
    let dir = if speed >= c.slip_velocity {
        if free > T::zero() {
            1
        } else {
            -1
        }
    } else {
        0
    };
    if slide[0] == 0 && dir != 0 {
        slide[1] = slide[1].wrapping_add(1);
    }
    slide[0] = dir;
    let sign = if free > T::zero() {
        T::one()
    } else {
        -T::one()
    };
    -sign * b.normal.max(T::zero()) * mu
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::friction::rate_state::{RateStateTable, StateEvolution};

    fn table(evolution: StateEvolution) -> RateStateTable {
        RateStateTable {
            state_evolution: evolution,
            ..crate::model::friction::rate_state::tests::table()
        }
    }

    fn constants(t: &RateStateTable) -> [f64; LAW_CONSTANTS] {
        let mut k = [0.0; LAW_CONSTANTS];
        k[..CONSTANTS].copy_from_slice(&t.constants());
        k
    }

    /// The solve returns the root: V' = X − κμ and V' = V(μ), the law's
    /// inverse, from creep at 1e-12 m/s (a block held, V' ≈ 0) to fast
    /// slip; where V' is resolved, μ = μ(V', θ) too. Both precisions.
    #[test]
    fn the_implicit_step_is_consistent_with_the_law() {
        let t = table(StateEvolution::Aging);
        let k = constants(&t);
        let (a, v0) = (0.01, 1e-6);
        for theta in [1e-3, 10.0, 1e4] {
            let psi = 0.6 + 0.015 * (v0 * theta / 1e-5f64).ln();
            for (x, kappa) in [
                (1e-12, 1e-3),
                (1e-6, 1e-4),
                (1e-3, 1e-2),
                (1.0, 1e-1),
                (5.0, 1.0),
            ] {
                let mu = solve_friction_level(a, v0, psi, x, kappa);
                let v = x - kappa * mu;
                assert!(v >= 0.0 && mu >= 0.0, "θ {theta} X {x}: μ {mu}, V {v}");
                let law_v = 2.0 * v0 * (-psi / a).exp() * (mu / a).sinh();
                assert!(
                    (law_v - v).abs() <= 1e-12 * x,
                    "θ {theta} X {x}: {law_v} vs {v}"
                );
                if v > 1e-6 * x {
                    let back = friction_coefficient(&k, v, theta);
                    assert!((back - mu).abs() < 1e-9, "θ {theta} X {x}: {mu} vs {back}");
                }
                let mu32 =
                    solve_friction_level(a as f32, v0 as f32, psi as f32, x as f32, kappa as f32);
                assert!(
                    (mu32 as f64 - mu).abs() < 1e-4 * mu.max(1.0),
                    "f32 {mu32} vs {mu}"
                );
            }
        }
    }

    /// Both evolution laws relax to θ = Dc/V at constant V, over a few Dc
    /// of slip; the aging law heals at rest (θ grows by dt), the slip law
    /// does not.
    #[test]
    fn the_state_relaxes_to_dc_over_v() {
        for evolution in [StateEvolution::Aging, StateEvolution::Slip] {
            let k = constants(&table(evolution));
            let (v, dt) = (1e-3, 1e-4);
            let mut theta = 10.0;
            for _ in 0..4000 {
                theta = evolve_state(&k, theta, v, dt);
            }
            // 40 Dc of slip.
            assert!(
                (theta / (1e-5 / v) - 1.0).abs() < 1e-6,
                "{evolution:?}: {theta}"
            );
            // One big step equals many small ones (exact at constant V).
            let one = evolve_state(&k, 1.0, v, 1e-2);
            let mut many = 1.0;
            for _ in 0..1000 {
                many = evolve_state(&k, many, v, 1e-5);
            }
            assert!(
                (one / many - 1.0).abs() < 1e-9,
                "{evolution:?}: {one} vs {many}"
            );
        }
        let aging = constants(&table(StateEvolution::Aging));
        assert_eq!(evolve_state(&aging, 2.0, 0.0, 0.5), 2.5);
        let slip = constants(&table(StateEvolution::Slip));
        assert_eq!(evolve_state(&slip, 2.0, 0.0, 0.5), 2.0);
    }

    /// Aging at rest adds dt a step: kept as a coordinate, θ = 100 s gains
    /// 1e-7 s a step in mixed precision too, where a plain f32 (ulp 7.6e-6
    /// at 100) would not move at all (the control).
    #[test]
    fn aging_at_rest_is_kept_in_mixed_precision() {
        use crate::model::real::DoubleSingle;
        let k64 = constants(&table(StateEvolution::Aging));
        let k: [f32; LAW_CONSTANTS] = k64.map(|v| v as f32);
        let dt = 1e-7f32;
        let mut mixed = DoubleSingle::from_f64(100.0);
        let mut plain = 100.0f32;
        for _ in 0..10_000 {
            mixed = mixed.add(state_increment(&k, mixed.value(), 0.0, dt));
            plain = plain.add(state_increment(&k, plain, 0.0, dt));
        }
        assert!(
            (mixed.as_f64() - 100.001).abs() < 1e-9,
            "{}",
            mixed.as_f64()
        );
        assert_eq!(plain, 100.0);
    }

    /// At steady state the regularised law is μ0 + (a − b) ln(V/V0).
    #[test]
    fn steady_state_friction_is_the_logarithmic_law() {
        let t = table(StateEvolution::Aging);
        let k = constants(&t);
        for v in [1e-4, 1e-2, 1.0] {
            let mu = friction_coefficient(&k, v, 1e-5 / v);
            assert!(
                (mu - t.steady_state_coefficient(v)).abs() < 1e-12,
                "{v}: {mu}"
            );
        }
    }
}
