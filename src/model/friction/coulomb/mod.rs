//! Amontons–Coulomb friction per interface block (CPU twin of
//! `shaders/laws/coulomb.wgsl`). Stuck: friction cancels the other forces
//! and the velocity (exact static friction) while that takes at most μs·p.
//! Sliding: μd·p against the sliding direction until the velocity reaches
//! zero or changes sign; then static friction holds again at once ("static
//! friction is renewed immediately when the block comes to rest", the
//! thesis's rule). Each stick → slip transition after the normal-load phase
//! counts as one rupture of the block, as a junction break does.
//!
//! Constants: (μs, μd), the scenario's `friction.static_coefficient` and
//! `friction.dynamic_coefficient`. State: only the `slide` pair.

use super::{BlockContact, Law, LAW_CONSTANTS};
use crate::model::real::Real;

pub const LAW: Law = Law {
    name: "coulomb",
    kernel: 2,
    kernel_constant: "LAW_COULOMB",
    block_state_words: 0,
    block_shader: Some((
        "coulomb",
        include_str!(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/shaders/laws/coulomb.wgsl"
        )),
        "coulomb",
    )),
    block_loop_iterations: 0,
};

/// (μs, μd).
pub fn constants(mu_s: f64, mu_d: f64) -> [f64; 2] {
    [mu_s, mu_d]
}

/// Returns the friction along x and updates the block's `slide` state:
/// (direction: 0 stuck, ±1 sliding; stick → slip count).
#[inline]
pub fn coulomb<T: Real>(
    constants: &[T; LAW_CONSTANTS],
    b: &BlockContact<T>,
    slide: &mut [i32; 2],
) -> T {
    let (mu_s, mu_d) = (constants[0], constants[1]);
    let dir = &mut slide[0];
    if *dir != 0 && b.velocity * T::from_f64(*dir as f64) <= T::zero() {
        *dir = 0;
    }
    if *dir == 0 {
        // Friction that brings the block to rest this step.
        let hold = -b.other_force - b.mass * b.velocity / b.dt;
        if b.preparing || hold.abs() <= mu_s * b.normal {
            return hold;
        }
        *dir = if b.other_force > T::zero() { 1 } else { -1 };
        slide[1] = slide[1].wrapping_add(1);
    }
    -mu_d * b.normal * T::from_f64(slide[0] as f64)
}
