//! CPU twin of `shaders/bulk_forces.wgsl`: springs, dashpots, foundation and
//! external loads on each block. Gather form (each block sums its own bonds),
//! so blocks are independent and the result does not depend on threading.

use crate::engines::precision_probe::{hold, FORCES};
use crate::engines::step_params::{Consts, StepParams};
use crate::model::lattice::{FLAG_DRIVEN, FLAG_INTERFACE, FLAG_TOP, STENCIL};
use crate::model::real::{Coordinate, ForceSum, Real};

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
    // Summed as the precision's `ForceSum` (`crate::model::real` says why).
    let mut fx = C::Sum::default();
    let mut fz = C::Sum::default();
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
        let held = |x: T| hold(c.f32_probe, FORCES, x);
        let dv = [b.vel[j][0] - vi[0], b.vel[j][1] - vi[1]];
        if C::Sum::SPLITS_BONDS {
            // Mixed f32: r = r0 + du rounds du to ulp(r0) ≈ 2e-10 m, about
            // two steps of creep, so the bond's direction would move in
            // stairs, step after step alike, and bias the lattice. Instead
            // the force q·r (q = k·stretch/|r|, |r| = rest + stretch) is
            // summed as q·r0 + q·du, each exact to f32's relative precision.
            let q = bond.k * stretch / (bond.rest + stretch);
            let rot = [q * du[0], q * du[1]];
            let (dx, dz) = if c.bond_damping {
                // n = r0/|r| + du/|r|, kept as its two parts alike.
                let inv = T::one() / (bond.rest + stretch);
                let n0 = [bond.r0[0] * inv, bond.r0[1] * inv];
                let n1 = [du[0] * inv, du[1] * inv];
                let along =
                    c.eta * ((dv[0] * n0[0] + dv[1] * n0[1]) + (dv[0] * n1[0] + dv[1] * n1[1]));
                (along * n0[0] + along * n1[0], along * n0[1] + along * n1[1])
            } else {
                (c.eta * dv[0], c.eta * dv[1])
            };
            fx = fx.add(q * bond.r0[0]).add_bond(rot[0], dx);
            fz = fz.add(q * bond.r0[1]).add_bond(rot[1], dz);
            continue;
        }
        let inv_len = T::one() / len;
        let n = [r[0] * inv_len, r[1] * inv_len];
        let spring = bond.k * stretch;
        // (The probe rounds each bond's terms as the sweep engine's rows do.)
        let (sx, sz) = (held(spring * n[0]), held(spring * n[1]));
        let (dx, dz) = if c.bond_damping {
            let along = c.eta * (dv[0] * n[0] + dv[1] * n[1]);
            (held(along * n[0]), held(along * n[1]))
        } else {
            (held(c.eta * dv[0]), held(c.eta * dv[1]))
        };
        fx = fx.add_bond(sx, dx);
        fz = fz.add_bond(sz, dz);
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
/// engine keeps too), and returns the total rounded to `T` once (the sum
/// is the precision's `ForceSum`: compensated in mixed f32).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn external_loads<T: Real, C: Coordinate<T>>(
    c: &Consts<T>,
    p: &StepParams<T>,
    drive_target: C,
    flags: u32,
    ix: usize,
    ui: [C; 2],
    vi: [T; 2],
    f: [C::Sum; 2],
) -> [T; 2] {
    let [mut fx, mut fz] = f;
    if flags & FLAG_INTERFACE != 0 {
        fz = fz.add(crate::model::laws::foundation_normal(
            c.k_foundation,
            ui[1].value(),
        ));
        let total = if ix < c.strip_blocks {
            p.strip_shear_total
        } else {
            p.interface_shear_total
        };
        let share = crate::model::laws::top_share::<T>(c.nx, c.nz, ix)
            * crate::model::laws::normal_profile(c.normal_slope, c.nx, ix);
        fx = fx.add(total * share);
    }
    if flags & FLAG_TOP != 0 {
        let share = crate::model::laws::top_share::<T>(c.nx, c.nz, ix);
        let profile = crate::model::laws::normal_profile(c.normal_slope, c.nx, ix);
        fz = fz.add(-(p.normal_total * (share * profile)));
        fx = fx.add(p.top_tangential_total * share);
    }
    if flags & FLAG_DRIVEN != 0 && !p.preparing {
        fx = fx.add(c.drive_stiffness * drive_target.diff(ui[0]));
    }
    fx = fx.add(-(p.absolute_eta * vi[0]));
    fz = fz.add(-(p.absolute_eta * vi[1]));
    [
        hold(c.f32_probe, FORCES, fx.value()),
        hold(c.f32_probe, FORCES, fz.value()),
    ]
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engines::cpu::SweepEngine;
    use crate::engines::step_params::step_params;
    use crate::model::real::DoubleSingle;
    use crate::{Engine, Model};

    /// Mixed f32 as it was before its sums were compensated: double-single
    /// coordinates, an f32 running sum.
    #[derive(Debug, Clone, Copy, Default, PartialEq)]
    struct RunningF32Sum(DoubleSingle);

    impl Coordinate<f32> for RunningF32Sum {
        const NAME: &'static str = "f32+f32 with f32 sums";
        type Sum = f32;
        fn from_f64(v: f64) -> Self {
            RunningF32Sum(DoubleSingle::from_f64(v))
        }
        fn as_f64(self) -> f64 {
            self.0.as_f64()
        }
        fn add(self, d: f32) -> Self {
            RunningF32Sum(self.0.ds_add(d))
        }
        fn diff(self, other: Self) -> f32 {
            self.0.ds_diff(other.0)
        }
        fn value(self) -> f32 {
            self.0.hi
        }
    }

    /// Bond forces alone (no block carries a flag, so no external load) on
    /// every block of a snapshot, in precision (T, C).
    fn bond_forces<T: Real, C: Coordinate<T>>(m: &Model, snap: &crate::Snapshot) -> Vec<[f64; 2]> {
        let c = Consts::<T>::new(m);
        let bonds = bond_consts(&c);
        let p = step_params(&c, snap.step);
        let disp: Vec<[C; 2]> = snap
            .disp
            .iter()
            .map(|u| [C::from_f64(u[0]), C::from_f64(u[1])])
            .collect();
        let vel: Vec<[T; 2]> = snap
            .vel_half
            .iter()
            .map(|v| [T::from_f64(v[0]), T::from_f64(v[1])])
            .collect();
        let flags = vec![0; disp.len()];
        let blocks = Blocks {
            disp: &disp,
            vel: &vel,
            flags: &flags,
        };
        let target = C::from_f64(0.0);
        (0..disp.len())
            .map(|i| {
                let f = bulk_force(&c, &bonds, &p, target, blocks, i);
                [f[0].as_f64(), f[1].as_f64()]
            })
            .collect()
    }

    /// Action equals reaction: a bond's force on its far end is the exact
    /// negation of its force on its near end, so the bond forces of the
    /// whole lattice sum to zero, and with each block's sum rounded once
    /// (compensated sums) to within Σ ulp(F_i)/2. An f32 running sum
    /// rounds each block at its largest partial sum, and in a nearly
    /// uniform strain every block rounds the same numbers alike: a net
    /// spurious force on the lattice, the mechanism of mixed f32's old bias
    /// (results/precision_ensembles.md). The loaded Table S1 lattice.
    #[test]
    fn mixed_bond_forces_keep_action_equal_to_reaction() {
        let s = crate::model::scenario::Scenario::parse(
            include_str!(concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/scenarios/tromborg2014_precursors.toml"
            )),
            "precursors",
            &[],
        )
        .unwrap();
        let m = Model::from_scenario(&s, false).unwrap();
        let mut e = SweepEngine::<f64, f64>::new(&m, 1).unwrap();
        e.advance(m.prep_steps + 500).unwrap();
        let snap = e.snapshot().unwrap();
        let net = |f: &[[f64; 2]], k: usize| f.iter().map(|b| b[k]).sum::<f64>();
        let exact = bond_forces::<f64, f64>(&m, &snap);
        let mixed = bond_forces::<f32, DoubleSingle>(&m, &snap);
        let running = bond_forces::<f32, RunningF32Sum>(&m, &snap);
        for k in 0..2 {
            // Each block's f32 force is within half an ulp of its exact sum.
            let bound: f64 = mixed
                .iter()
                .map(|b| 0.5 * f32::EPSILON as f64 * b[k].abs())
                .sum();
            let largest: f64 = exact.iter().map(|b| b[k].abs()).fold(0.0, f64::max);
            assert!(net(&exact, k).abs() < 1e-12 * largest * exact.len() as f64);
            assert!(
                net(&mixed, k).abs() <= bound,
                "component {k}: mixed net bond force {:e} N above {bound:e} N",
                net(&mixed, k)
            );
            // The negative control: f32 running sums break it, by far.
            assert!(
                net(&running, k).abs() > 10.0 * net(&mixed, k).abs(),
                "component {k}: running f32 sums' net {:e} N within 10 × mixed's",
                net(&running, k)
            );
        }
    }
}
