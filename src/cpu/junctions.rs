//! CPU twin of `shaders/junctions.wgsl`: the Ns micro-junctions of one
//! interface block pin, break at μs·f_N, slip for a drawn time at μd·f_N and
//! re-pin with zero stretch.

use crate::real::Real;
use crate::rng::slip_steps;
use crate::step_params::{Consts, StepParams};

/// `repin_step` value of a pinned junction.
pub const PINNED: u32 = u32::MAX;

/// The junction arrays of one interface block (length Ns each), laid out
/// as the GPU's `junction_spring` and `junction_state` buffers.
pub struct JunctionSlots<'a, T> {
    /// (anchor a_ij, stiffness k_j) per junction.
    pub spring: &'a mut [[T; 2]],
    /// (re-pin step or PINNED, rupture count) per junction.
    pub state: &'a mut [[u32; 2]],
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
    for (j, (spring, state)) in slots
        .spring
        .iter_mut()
        .zip(slots.state.iter_mut())
        .enumerate()
    {
        if state[0] != PINNED && step >= state[0] {
            *spring = [u[0], c.junction_stiffness(f_n)];
            state[0] = PINNED;
        }
        let mut f = sliding;
        if state[0] == PINNED {
            if p.preparing {
                // While the normal load is applied, attachment is continuous.
                spring[1] = c.junction_stiffness(f_n);
            }
            f = -spring[1] * (u[0] - spring[0]);
            if !p.preparing && f.abs() > threshold {
                let count = state[1].wrapping_add(1);
                state[1] = count;
                let n = slip_steps(
                    c.seed,
                    ix as u32,
                    j as u32,
                    count,
                    c.slip_mean_steps,
                    c.slip_std_steps,
                );
                state[0] = step.saturating_add(n);
                f = sliding;
            }
        }
        total = total + f;
    }
    (total, normal)
}
