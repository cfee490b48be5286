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

/// What one bond adds to a block's force sums (twin of WGSL `BondTerms`):
/// q·r0 (mixed f32's split bonds only), then the spring and dashpot terms
/// along x and along z. Each is an odd function of the bond's offset and
/// its displacement and velocity differences, and rounding to nearest is
/// symmetric, so the bond seen from its far end adds exactly these terms
/// negated (`negated`): `bulk_force_patch` computes a bond once.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BondTerms<T> {
    pub axial: [T; 2],
    pub along_x: [T; 2],
    pub along_z: [T; 2],
}

impl<T: Real> BondTerms<T> {
    /// The same bond seen from its far end.
    pub fn negated(self) -> Self {
        let neg = |[a, b]: [T; 2]| [-a, -b];
        BondTerms {
            axial: neg(self.axial),
            along_x: neg(self.along_x),
            along_z: neg(self.along_z),
        }
    }

    /// These terms added to a block's sums, in the order every engine adds
    /// a bond's.
    #[inline(always)]
    fn add_to<S: ForceSum<T>>(self, [fx, fz]: [S; 2]) -> [S; 2] {
        if S::SPLITS_BONDS {
            return [
                fx.add(self.axial[0])
                    .add_bond(self.along_x[0], self.along_x[1]),
                fz.add(self.axial[1])
                    .add_bond(self.along_z[0], self.along_z[1]),
            ];
        }
        [
            fx.add_bond(self.along_x[0], self.along_x[1]),
            fz.add_bond(self.along_z[0], self.along_z[1]),
        ]
    }
}

/// The terms of `bond` from a block with displacement `ui` and velocity
/// `vi` to its neighbour (`uj`, `vj`) (twin of WGSL `bond_terms`).
#[inline(always)]
fn bond_terms<T: Real, C: Coordinate<T>>(
    c: &Consts<T>,
    bond: &BondConsts<T>,
    (ui, vi): ([C; 2], [T; 2]),
    (uj, vj): ([C; 2], [T; 2]),
) -> BondTerms<T> {
    let du = [uj[0].diff(ui[0]), uj[1].diff(ui[1])];
    let r = [bond.r0[0] + du[0], bond.r0[1] + du[1]];
    let len = (r[0] * r[0] + r[1] * r[1]).sqrt();
    // Elongation without cancellation: stretch = (|r|² − l²)/(|r| + l) =
    // num/(|r| + l). Each force below divides once by a denominator that
    // folds this division in (one division a bond, not two).
    let two = T::one() + T::one();
    let num = two * (bond.r0[0] * du[0] + bond.r0[1] * du[1]) + (du[0] * du[0] + du[1] * du[1]);
    let over = len + bond.rest;
    let held = |x: T| hold(c.f32_probe, FORCES, x);
    let dv = [vj[0] - vi[0], vj[1] - vi[1]];
    if C::Sum::SPLITS_BONDS {
        // Mixed f32: r = r0 + du rounds du to ulp(r0) ≈ 2e-10 m, about
        // two steps of creep, so the bond's direction would move in
        // stairs, step after step alike, and bias the lattice. Instead
        // the force q·r (q = k·stretch/|r|, |r| = rest + stretch) is
        // summed as q·r0 + q·du, each exact to f32's relative precision.
        // With stretch = num/over, |r| = (rest·over + num)/over, so
        // q = k·num/(rest·over + num).
        let len_times_over = bond.rest * over + num;
        let q = bond.k * num / len_times_over;
        let (dx, dz) = if c.bond_damping {
            // n = r0/|r| + du/|r|, kept as its two parts alike.
            let inv = over / len_times_over;
            let n0 = [bond.r0[0] * inv, bond.r0[1] * inv];
            let n1 = [du[0] * inv, du[1] * inv];
            let along = c.eta * ((dv[0] * n0[0] + dv[1] * n0[1]) + (dv[0] * n1[0] + dv[1] * n1[1]));
            (along * n0[0] + along * n1[0], along * n0[1] + along * n1[1])
        } else {
            (c.eta * dv[0], c.eta * dv[1])
        };
        return BondTerms {
            axial: [q * bond.r0[0], q * bond.r0[1]],
            along_x: [q * du[0], dx],
            along_z: [q * du[1], dz],
        };
    }
    // The spring force k·stretch·r/|r| = (k·num/(over·|r|))·r.
    let spring_per_length = bond.k * num / (over * len);
    // (The probe rounds each bond's terms as the sweep engine's rows do.)
    let (sx, sz) = (
        held(spring_per_length * r[0]),
        held(spring_per_length * r[1]),
    );
    let (dx, dz) = if c.bond_damping {
        let inv_len = T::one() / len;
        let n = [r[0] * inv_len, r[1] * inv_len];
        let along = c.eta * (dv[0] * n[0] + dv[1] * n[1]);
        (held(along * n[0]), held(along * n[1]))
    } else {
        (held(c.eta * dv[0]), held(c.eta * dv[1]))
    };
    BondTerms {
        axial: [T::zero(); 2],
        along_x: [sx, dx],
        along_z: [sz, dz],
    }
}

/// The block at column `ix`, row `iz` (index `i = iz·nx + ix`), if it is in
/// the lattice.
fn block_at(c: &Consts<impl Real>, ix: i32, iz: i32) -> Option<usize> {
    let inside = ix >= 0 && iz >= 0 && ix < c.nx as i32 && iz < c.nz as i32;
    inside.then(|| iz as usize * c.nx + ix as usize)
}

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
    let own = (b.disp[i], b.vel[i]);
    force_with(c, bonds, p, drive_target, b, i, |bond, j| {
        bond_terms(c, bond, own, (b.disp[j], b.vel[j]))
    })
}

/// Block `i`'s force from everything but friction, its bonds' terms from
/// `terms_of(bond, j)` for each stencil bond to a block j of the lattice,
/// added in stencil order, then the external loads.
#[inline(always)]
fn force_with<T: Real, C: Coordinate<T>>(
    c: &Consts<T>,
    bonds: &[BondConsts<T>; 8],
    p: &StepParams<T>,
    drive_target: C,
    b: Blocks<'_, T, C>,
    i: usize,
    mut terms_of: impl FnMut(&BondConsts<T>, usize) -> BondTerms<T>,
) -> [T; 2] {
    let (ix, iz) = ((i % c.nx) as i32, (i / c.nx) as i32);
    // Summed as the precision's `ForceSum` (`crate::model::real` says why).
    let mut f = [C::Sum::default(); 2];
    for bond in bonds {
        if let Some(j) = block_at(c, ix + bond.dx, iz + bond.dz) {
            f = terms_of(bond, j).add_to(f);
        }
    }
    external_loads(
        c,
        p,
        drive_target,
        b.flags[i],
        ix as usize,
        b.disp[i],
        b.vel[i],
        f,
    )
}

/// The forces on the 2×2 patch of blocks whose first is at column `x0`,
/// row `z0` (twin of WGSL `bulk_force_patch`): blocks (x0, z0),
/// (x0 + 1, z0), (x0, z0 + 1), (x0 + 1, z0 + 1), None where outside the
/// lattice. Each bond between two of them is computed once, by the first
/// in that order, and added negated by the second; every block adds its
/// bonds in stencil order, so each force has `bulk_force`'s bits.
#[inline]
pub fn bulk_force_patch<T: Real, C: Coordinate<T>>(
    c: &Consts<T>,
    bonds: &[BondConsts<T>; 8],
    p: &StepParams<T>,
    drive_target: C,
    b: Blocks<'_, T, C>,
    (x0, z0): (usize, usize),
) -> [Option<[T; 2]>; 4] {
    const CORNERS: [(i32, i32); 4] = [(0, 0), (1, 0), (0, 1), (1, 1)];
    let corner_of = |dx: i32, dz: i32| CORNERS.iter().position(|&o| o == (dx, dz));
    // The inner bonds' terms as computed, by (first, second) corner.
    let mut inner: [[Option<BondTerms<T>>; 4]; 4] = [[None; 4]; 4];
    let mut out = [None; 4];
    for (k, &(ox, oz)) in CORNERS.iter().enumerate() {
        let Some(i) = block_at(c, x0 as i32 + ox, z0 as i32 + oz) else {
            continue;
        };
        let own = (b.disp[i], b.vel[i]);
        out[k] = Some(force_with(c, bonds, p, drive_target, b, i, |bond, j| {
            let computed = || bond_terms(c, bond, own, (b.disp[j], b.vel[j]));
            match corner_of(ox + bond.dx, oz + bond.dz) {
                Some(m) if m < k => inner[m][k].expect("computed by its first corner").negated(),
                Some(m) => *inner[k][m].insert(computed()),
                None => computed(),
            }
        }));
    }
    out
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

    /// A snapshot's displacements and velocities in precision (T, C).
    #[allow(clippy::type_complexity)]
    fn state_in<T: Real, C: Coordinate<T>>(snap: &crate::Snapshot) -> (Vec<[C; 2]>, Vec<[T; 2]>) {
        let disp = snap
            .disp
            .iter()
            .map(|u| [C::from_f64(u[0]), C::from_f64(u[1])])
            .collect();
        let vel = snap
            .vel_half
            .iter()
            .map(|v| [T::from_f64(v[0]), T::from_f64(v[1])])
            .collect();
        (disp, vel)
    }

    /// Bond forces alone (no block carries a flag, so no external load) on
    /// every block of a snapshot, in precision (T, C).
    fn bond_forces<T: Real, C: Coordinate<T>>(m: &Model, snap: &crate::Snapshot) -> Vec<[f64; 2]> {
        let c = Consts::<T>::new(m);
        let bonds = bond_consts(&c);
        let p = step_params(&c, snap.step);
        let (disp, vel) = state_in::<T, C>(snap);
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

    /// The blocks whose force from `bulk_force_patch` (over every patch of
    /// the snapshot's lattice) has other bits than `bulk_force` on the same
    /// block, in precision (T, C), and the blocks compared. `nudged`: a
    /// block whose u_x the patches see 1e-9 m further (a control). With a
    /// drive target (the side spring) and the model's flags, so the
    /// external loads are in the sums too.
    fn patch_mismatches<T: Real, C: Coordinate<T>>(
        m: &Model,
        snap: &crate::Snapshot,
        nudged: Option<usize>,
    ) -> (Vec<usize>, usize) {
        let c = Consts::<T>::new(m);
        let bonds = bond_consts(&c);
        let p = step_params(&c, snap.step);
        let (disp, vel) = state_in::<T, C>(snap);
        let mut seen = disp.clone();
        if let Some(i) = nudged {
            seen[i][0] = C::from_f64(snap.disp[i][0] + 1e-9);
        }
        let flags = crate::model::lattice::block_flags(m);
        let blocks = |disp| Blocks {
            disp,
            vel: &vel,
            flags: &flags,
        };
        let target = C::from_f64(1e-6);
        let (mut mismatched, mut compared) = (Vec::new(), 0);
        for z0 in (0..m.nz).step_by(2) {
            for x0 in (0..m.nx).step_by(2) {
                let patch = bulk_force_patch(&c, &bonds, &p, target, blocks(&seen), (x0, z0));
                for (k, (ox, oz)) in [(0, 0), (1, 0), (0, 1), (1, 1)].into_iter().enumerate() {
                    let (ix, iz) = (x0 + ox, z0 + oz);
                    if ix >= m.nx || iz >= m.nz {
                        assert!(patch[k].is_none(), "({ix}, {iz}) is outside the lattice");
                        continue;
                    }
                    let i = iz * m.nx + ix;
                    let alone = bulk_force(&c, &bonds, &p, target, blocks(&disp), i);
                    let bits = |f: [T; 2]| f.map(|x| x.as_f64().to_bits());
                    if bits(patch[k].expect("a block of the lattice")) != bits(alone) {
                        mismatched.push(i);
                    }
                    compared += 1;
                }
            }
        }
        (mismatched, compared)
    }

    /// The patch twin computes each inner bond once and adds it negated at
    /// its far end; each force keeps `bulk_force`'s bits, in f64, mixed f32
    /// and plain f32, with either damping form, on an odd lattice (partial
    /// patches on the last column and row) that a front has disturbed.
    /// Control: a block nudged by 1e-9 m is flagged, with its neighbours.
    #[test]
    fn bond_patches_give_each_block_the_bits_of_its_own_sum() {
        for form in ["full", "bond"] {
            let s = crate::app::verify::small_triggered_scene(&[
                "geometry.nz=15",
                "geometry.height=0.035",
                &format!("damping.form=\"{form}\""),
            ])
            .unwrap();
            let m = Model::from_scenario(&s, false).unwrap();
            assert!(m.nx % 2 == 1 && m.nz % 2 == 1);
            let mut e = SweepEngine::<f64, f64>::new(&m, 1).unwrap();
            e.advance(m.prep_steps + 300).unwrap();
            let snap = e.snapshot().unwrap();
            assert!(snap.vel_half.iter().any(|v| v[0] != 0.0 && v[1] != 0.0));
            let all = (Vec::new(), m.nx * m.nz);
            assert_eq!(patch_mismatches::<f64, f64>(&m, &snap, None), all);
            assert_eq!(patch_mismatches::<f32, DoubleSingle>(&m, &snap, None), all);
            assert_eq!(patch_mismatches::<f32, f32>(&m, &snap, None), all);
            // Control: block (5, 3) nudged; it and its 8 neighbours differ.
            let nudged = 3 * m.nx + 5;
            let (flagged, _) = patch_mismatches::<f32, DoubleSingle>(&m, &snap, Some(nudged));
            assert!(
                flagged.contains(&nudged) && flagged.len() == 9,
                "{flagged:?}"
            );
        }
    }

    /// The order of the stencil that `shaders/bulk_patch.wgsl` is written
    /// out for: which entries of each corner are inner bonds follows from
    /// it.
    #[test]
    fn the_bond_patch_shader_assumes_the_stencils_order() {
        let order: Vec<(i32, i32)> = STENCIL.iter().map(|b| (b.dx, b.dz)).collect();
        assert_eq!(
            order,
            [
                (1, 0),
                (-1, 0),
                (0, 1),
                (0, -1),
                (1, 1),
                (-1, 1),
                (1, -1),
                (-1, -1)
            ]
        );
        let shader = include_str!(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/shaders/bulk_patch.wgsl"
        ));
        assert!(shader.contains("(1,0), (−1,0), (0,1), (0,−1),\n// (1,1), (−1,1), (1,−1), (−1,−1)"));
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
