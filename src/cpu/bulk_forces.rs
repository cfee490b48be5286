//! CPU twin of `shaders/bulk_forces.wgsl`: springs, dashpots, foundation and
//! external loads on each block. Gather form (each block sums its own bonds),
//! so blocks are independent and the result does not depend on threading.

use crate::lattice::{FLAG_DRIVEN, FLAG_INTERFACE, FLAG_TOP, STENCIL};
use crate::precision_probe::{hold, FORCES};
use crate::real::{Coordinate, Real};
use crate::step_params::{Consts, StepParams};

/// Per-bond constants in the engine's precision, built once.
#[derive(Debug, Clone, Copy)]
pub struct BondConsts<T> {
    pub dx: i32,
    pub dz: i32,
    pub r0: [T; 2],
    pub rest: T,
    pub k: T,
}

pub fn bond_consts<T: Real>(c: &Consts<T>) -> [BondConsts<T>; 8] {
    STENCIL.map(|b| BondConsts {
        dx: b.dx,
        dz: b.dz,
        r0: [
            T::from_f64(b.dx as f64) * c.spacing,
            T::from_f64(b.dz as f64) * c.spacing,
        ],
        rest: T::from_f64(b.length_factor) * c.spacing,
        k: T::from_f64(b.stiffness_factor) * c.k,
    })
}

/// Read-only block state the force kernels see.
pub struct Blocks<'a, T, C> {
    pub disp: &'a [[C; 2]],
    pub vel: &'a [[T; 2]],
    pub flags: &'a [u32],
}

impl<T, C> Clone for Blocks<'_, T, C> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<T, C> Copy for Blocks<'_, T, C> {}

/// Force on block `i` from everything but friction. `drive_target` is where
/// the side spring's far end is (drive origin + V·t), as a coordinate.
#[inline]
pub fn bulk_force<T: Real, C: Coordinate<T>>(
    c: &Consts<T>,
    bonds: &[BondConsts<T>; 8],
    p: &StepParams<T>,
    drive_target: C,
    b: Blocks<'_, T, C>,
    i: usize,
) -> [T; 2] {
    let (ix, iz) = ((i % c.nx) as i32, (i / c.nx) as i32);
    let ui = b.disp[i];
    let vi = b.vel[i];
    let mut fx = T::zero();
    let mut fz = T::zero();
    for bond in bonds {
        let jx = ix + bond.dx;
        let jz = iz + bond.dz;
        if jx < 0 || jz < 0 || jx >= c.nx as i32 || jz >= c.nz as i32 {
            continue;
        }
        let j = jz as usize * c.nx + jx as usize;
        let du = [b.disp[j][0].diff(ui[0]), b.disp[j][1].diff(ui[1])];
        let r = [bond.r0[0] + du[0], bond.r0[1] + du[1]];
        let len = (r[0] * r[0] + r[1] * r[1]).sqrt();
        // Elongation without cancellation: (|r|² − l²)/(|r| + l).
        let two = T::one() + T::one();
        let stretch = (two * (bond.r0[0] * du[0] + bond.r0[1] * du[1])
            + (du[0] * du[0] + du[1] * du[1]))
            / (len + bond.rest);
        let inv_len = T::one() / len;
        let n = [r[0] * inv_len, r[1] * inv_len];
        let spring = bond.k * stretch;
        // (The probe rounds each bond's terms as the sweep engine's rows do.)
        let held = |x: T| hold(c.f32_probe, FORCES, x);
        fx = fx + held(spring * n[0]);
        fz = fz + held(spring * n[1]);
        let dv = [b.vel[j][0] - vi[0], b.vel[j][1] - vi[1]];
        if c.bond_damping {
            let along = c.eta * (dv[0] * n[0] + dv[1] * n[1]);
            fx = fx + held(along * n[0]);
            fz = fz + held(along * n[1]);
        } else {
            fx = fx + held(c.eta * dv[0]);
            fz = fz + held(c.eta * dv[1]);
        }
    }
    external_loads(
        c,
        p,
        drive_target,
        b.flags[i],
        ix as usize,
        ui,
        vi,
        [fx, fz],
    )
}

/// Adds to the bond forces `f` of a block at column `ix` the loads that do
/// not come from bonds: foundation and interface prestress, top load, side spring and the
/// absolute damping (in this order, which the fast
/// engine keeps too).
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn external_loads<T: Real, C: Coordinate<T>>(
    c: &Consts<T>,
    p: &StepParams<T>,
    drive_target: C,
    flags: u32,
    ix: usize,
    ui: [C; 2],
    vi: [T; 2],
    f: [T; 2],
) -> [T; 2] {
    let [mut fx, mut fz] = f;
    if flags & FLAG_INTERFACE != 0 {
        fz = fz + crate::laws::foundation_normal(c.k_foundation, ui[1].value());
        let total = if ix < c.strip_blocks {
            p.strip_shear_total
        } else {
            p.interface_shear_total
        };
        let share = crate::laws::top_share::<T>(c.nx, c.nz, ix)
            * crate::laws::normal_profile(c.normal_slope, c.nx, ix);
        fx = fx + total * share;
    }
    if flags & FLAG_TOP != 0 {
        let share = crate::laws::top_share::<T>(c.nx, c.nz, ix);
        let profile = crate::laws::normal_profile(c.normal_slope, c.nx, ix);
        fz = fz - p.normal_total * (share * profile);
        fx = fx + p.top_tangential_total * share;
    }
    if flags & FLAG_DRIVEN != 0 && !p.preparing {
        fx = fx + c.drive_stiffness * drive_target.diff(ui[0]);
    }
    fx = fx - p.absolute_eta * vi[0];
    fz = fz - p.absolute_eta * vi[1];
    [hold(c.f32_probe, FORCES, fx), hold(c.f32_probe, FORCES, fz)]
}

/// Twin of the `bulk_forces` entry point: fills `force` for the blocks
/// starting at `first`.
#[allow(clippy::too_many_arguments)]
pub fn bulk_forces<T: Real, C: Coordinate<T>>(
    c: &Consts<T>,
    bonds: &[BondConsts<T>; 8],
    p: &StepParams<T>,
    drive_target: C,
    b: Blocks<'_, T, C>,
    force: &mut [[T; 2]],
    first: usize,
) {
    for (k, f) in force.iter_mut().enumerate() {
        *f = bulk_force(c, bonds, p, drive_target, b, first + k);
    }
}
