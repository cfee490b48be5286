//! CPU twin of `shaders/junctions.wgsl`: the Ns micro-junctions of one
//! interface block pin, break at μs·f_N, slip for a drawn time at μd·f_N and
//! re-pin with zero stretch.

use crate::real::Real;
use crate::rng::slip_steps;
use crate::step_params::{Consts, StepParams};

/// `repin_step` value of a pinned junction.
pub const PINNED: u32 = u32::MAX;

/// The junction arrays of one interface block (length Ns each).
pub struct JunctionSlots<'a, T> {
    pub anchor: &'a mut [T],
    pub stiffness: &'a mut [T],
    pub repin_step: &'a mut [u32],
    pub ruptures: &'a mut [u32],
}

/// Normal force the foundation carries under interface block with u_z.
#[inline]
pub fn foundation_normal<T: Real>(c: &Consts<T>, uz: T) -> T {
    c.k_foundation * (-uz).max(T::zero())
}

/// Sign of the block velocity, 0 when it is exactly zero.
#[inline]
pub fn velocity_sign<T: Real>(v: T) -> T {
    if v > T::zero() {
        T::one()
    } else if v < T::zero() {
        -T::one()
    } else {
        T::zero()
    }
}

/// Advances the junctions of interface block `ix` by one step and returns
/// (friction force on the block along x, normal force p).
pub fn junctions<T: Real>(
    c: &Consts<T>,
    p: &StepParams<T>,
    ix: usize,
    u: [T; 2],
    v: [T; 2],
    slots: JunctionSlots<'_, T>,
) -> (T, T) {
    let normal = foundation_normal(c, u[1]);
    let f_n = normal / T::from_f64(c.junction_count as f64);
    let threshold = c.mu_s * f_n;
    let sliding = -c.mu_d * f_n * velocity_sign(v[0]);
    let step = p.step as u32;
    let mut total = T::zero();
    for j in 0..slots.anchor.len() {
        if slots.repin_step[j] != PINNED && step >= slots.repin_step[j] {
            slots.anchor[j] = u[0];
            slots.stiffness[j] = c.junction_stiffness(f_n);
            slots.repin_step[j] = PINNED;
        }
        let mut f = sliding;
        if slots.repin_step[j] == PINNED {
            if p.preparing {
                // While the normal load is applied, attachment is continuous.
                slots.stiffness[j] = c.junction_stiffness(f_n);
            }
            f = -slots.stiffness[j] * (u[0] - slots.anchor[j]);
            if !p.preparing && f.abs() > threshold {
                let count = slots.ruptures[j].wrapping_add(1);
                slots.ruptures[j] = count;
                let n = slip_steps(
                    c.seed,
                    ix as u32,
                    j as u32,
                    count,
                    c.slip_mean_steps,
                    c.slip_std_steps,
                );
                slots.repin_step[j] = step.saturating_add(n);
                f = sliding;
            }
        }
        total = total + f;
    }
    (total, normal)
}
