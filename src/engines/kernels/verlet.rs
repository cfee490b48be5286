//! CPU twin of `shaders/verlet.wgsl`: the leapfrog update
//! v ← v + dt·F/m, u ← u + dt·v, with constraints and prescribed motion.
//! The displacement is a coordinate: the increment dt·v is added without
//! losing its low bits (double-single in mixed precision).

use crate::engines::precision_probe::{hold, hold_coordinate, VELOCITIES};
use crate::engines::step_params::{Consts, StepParams};
use crate::model::lattice::{FLAG_FIX_X, FLAG_FIX_Z, FLAG_PRESCRIBED_X};
use crate::model::real::{Coordinate, Real};

/// Updates one block; returns false if the result is not finite or faster
/// than `speed_limit` (a blow-up).
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn verlet<T: Real, C: Coordinate<T>>(
    c: &Consts<T>,
    p: &StepParams<T>,
    flags: u32,
    force: [T; 2],
    friction: T,
    u: &mut [C; 2],
    v: &mut [T; 2],
    speed_limit: T,
) -> bool {
    let mut vx = v[0] + c.dt * ((force[0] + friction) * c.inv_mass);
    let mut vz = v[1] + c.dt * (force[1] * c.inv_mass);
    if flags & FLAG_FIX_X != 0 {
        vx = T::zero();
    }
    if flags & FLAG_FIX_Z != 0 {
        vz = T::zero();
    }
    if flags & FLAG_PRESCRIBED_X != 0 {
        vx = p.top_velocity;
    }
    let probe = c.f32_probe;
    let (vx, vz) = (hold(probe, VELOCITIES, vx), hold(probe, VELOCITIES, vz));
    v[0] = vx;
    v[1] = vz;
    u[0] = hold_coordinate(probe, u[0].add(c.dt * vx));
    u[1] = hold_coordinate(probe, u[1].add(c.dt * vz));
    sane(*u, *v, speed_limit)
}

/// False for a blown-up block: a non-finite displacement or a speed above
/// `speed_limit`.
#[inline]
pub fn sane<T: Real, C: Coordinate<T>>(u: [C; 2], v: [T; 2], speed_limit: T) -> bool {
    // NaN fails every comparison, so this also catches non-finite values.
    v[0].abs() <= speed_limit
        && v[1].abs() <= speed_limit
        && u[0].value().is_finite()
        && u[1].value().is_finite()
}
