//! CPU twin of `shaders/coulomb.wgsl`: Amontons–Coulomb friction per
//! interface block. Stuck: friction cancels the other forces and the
//! velocity (exact static friction) while that takes at most μs·p. Sliding:
//! μd·p against the sliding direction until the velocity reaches zero or
//! changes sign; then static friction holds again at once ("static friction
//! is renewed immediately when the block comes to rest", the thesis's rule).
//! Each stick → slip transition after the normal-load phase counts as one
//! rupture of the block, as a junction break does.

use super::junctions::foundation_normal;
use crate::engines::step_params::{Consts, StepParams};
use crate::model::real::{Coordinate, Real};

/// Returns (friction along x, normal force p) and updates the block's
/// `slide` state: (direction: 0 stuck, ±1 sliding; stick → slip count).
pub fn coulomb<T: Real, C: Coordinate<T>>(
    c: &Consts<T>,
    p: &StepParams<T>,
    u: [C; 2],
    v: [T; 2],
    other_force_x: T,
    slide: &mut [i32; 2],
) -> (T, T) {
    let dir = &mut slide[0];
    let normal = foundation_normal(c, u[1].value());
    if *dir != 0 && v[0] * T::from_f64(*dir as f64) <= T::zero() {
        *dir = 0;
    }
    if *dir == 0 {
        // Friction that brings the block to rest this step.
        let hold = -other_force_x - c.mass * v[0] / c.dt;
        if p.preparing || hold.abs() <= c.mu_s * normal {
            return (hold, normal);
        }
        *dir = if other_force_x > T::zero() { 1 } else { -1 };
        slide[1] = slide[1].wrapping_add(1);
    }
    (-c.mu_d * normal * T::from_f64(slide[0] as f64), normal)
}
