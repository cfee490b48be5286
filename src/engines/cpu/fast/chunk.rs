//! One step over a band of rows, as a single pass over memory: each row is
//! advanced (leapfrog) just before the bonds that need it, then its forces
//! are gathered, then — on the interface row — its friction. A band reads
//! the step's start state (`Shared::now`) and writes only its own rows of
//! the next state, so bands run on any threads with the same bits; the row
//! below and above a band are advanced again into scratch (a halo) instead
//! of waiting for the band that owns them.

use super::interface::{interface_row, JunctionScratch};
use super::rows::{gather_row, horizontal_bonds, upward_bonds, BondRow};
use super::rows::{RowView, UpwardBonds};
use super::step::{Advance, Interface, Shared};
use super::Kinematics;
use crate::engines::kernels::bulk_forces::external_loads;
use crate::engines::kernels::verlet;
use crate::model::real::{Coordinate, Real};
use crate::model::scenario::FrictionLaw;
use std::ops::Range;

/// A band's rows of the next state.
pub struct Band<'a, T, C> {
    pub rows: Range<usize>,
    pub ux: &'a mut [C],
    pub uz: &'a mut [C],
    pub vx: &'a mut [T],
    pub vz: &'a mut [T],
    pub fx: &'a mut [T],
    pub fz: &'a mut [T],
    pub interface: Option<Interface<'a, T, C>>,
}

/// A band's working rows, kept between steps.
pub struct Scratch<T: Real, C: Coordinate<T>> {
    below: Kinematics<T, C>,
    above: Kinematics<T, C>,
    horizontal: BondRow<T>,
    up: UpwardBonds<T>,
    down: UpwardBonds<T>,
    /// A row's bond-force sums (`ForceSum`), before the external
    /// loads join them (`bulk_forces::external_loads` says why).
    sum_x: Vec<C::Sum>,
    sum_z: Vec<C::Sum>,
    junctions: JunctionScratch<T, C::Sum, C>,
}

impl<T: Real, C: Coordinate<T>> Scratch<T, C> {
    pub fn new(nx: usize) -> Self {
        Scratch {
            below: Kinematics::new(nx),
            above: Kinematics::new(nx),
            horizontal: BondRow::new(nx),
            up: UpwardBonds::new(nx),
            down: UpwardBonds::new(nx),
            sum_x: vec![Default::default(); nx],
            sum_z: vec![Default::default(); nx],
            junctions: JunctionScratch::default(),
        }
    }

    /// Drops the interface row's kept junction sums
    /// (`JunctionScratch::forget_junction_sums`).
    pub fn forget_junction_sums(&mut self) {
        self.junctions.forget_junction_sums();
    }

    /// Interface blocks whose junction sums are kept now.
    pub fn kept_junction_blocks(&self) -> usize {
        self.junctions.kept_blocks()
    }
}

fn view<'a, T, C>(
    ux: &'a [C],
    uz: &'a [C],
    vx: &'a [T],
    vz: &'a [T],
    r: Range<usize>,
) -> RowView<'a, T, C> {
    RowView {
        ux: &ux[r.clone()],
        uz: &uz[r.clone()],
        vx: &vx[r.clone()],
        vz: &vz[r],
    }
}

/// Advances row `z` of the start state into the given row slices; returns
/// the column of the first block that blew up.
#[inline(always)]
fn advance_row<T: Real, C: Coordinate<T>>(
    s: &Shared<'_, T, C>,
    z: usize,
    ux: &mut [C],
    uz: &mut [C],
    vx: &mut [T],
    vz: &mut [T],
) -> Option<usize> {
    let nx = s.c.nx;
    let first = z * nx;
    let now = s.now;
    if s.advance == Advance::Copy {
        ux.copy_from_slice(&now.ux[first..first + nx]);
        uz.copy_from_slice(&now.uz[first..first + nx]);
        vx.copy_from_slice(&now.vx[first..first + nx]);
        vz.copy_from_slice(&now.vz[first..first + nx]);
        return None;
    }
    let has_friction = z == 0 && s.law != FrictionLaw::None;
    let row = first..first + nx;
    // Straight slices of one length, and the blow-up check folded into one
    // flag, so that the loop vectorises; the rare bad row is searched after.
    let (now_ux, now_uz) = (&now.ux[row.clone()], &now.uz[row.clone()]);
    let (now_vx, now_vz) = (&now.vx[row.clone()], &now.vz[row.clone()]);
    let (fx, fz) = (&s.now_force[0][row.clone()], &s.now_force[1][row.clone()]);
    let flags = &s.flags[row];
    let (ux, uz, vx, vz) = (&mut ux[..nx], &mut uz[..nx], &mut vx[..nx], &mut vz[..nx]);
    let contact = &s.now_contact[..if has_friction { nx } else { 0 }];
    let mut all_ok = true;
    for ix in 0..nx {
        let mut u = [now_ux[ix], now_uz[ix]];
        let mut v = [now_vx[ix], now_vz[ix]];
        let friction = if has_friction {
            contact[ix][0]
        } else {
            T::zero()
        };
        all_ok &= verlet::verlet(
            s.c,
            &s.before,
            flags[ix],
            [fx[ix], fz[ix]],
            friction,
            &mut u,
            &mut v,
            s.speed_limit,
        );
        [ux[ix], uz[ix]] = u;
        [vx[ix], vz[ix]] = v;
    }
    if all_ok {
        return None;
    }
    (0..nx).find(|&ix| !verlet::sane([ux[ix], uz[ix]], [vx[ix], vz[ix]], s.speed_limit))
}

/// Advances row `z` of a band starting at row `a` in place; notes the
/// first block that blew up in `bad`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn advance_own<T: Real, C: Coordinate<T>>(
    s: &Shared<'_, T, C>,
    a: usize,
    z: usize,
    ux: &mut [C],
    uz: &mut [C],
    vx: &mut [T],
    vz: &mut [T],
    bad: &mut Option<usize>,
) {
    let nx = s.c.nx;
    let r = (z - a) * nx..(z - a + 1) * nx;
    let row_bad = advance_row(
        s,
        z,
        &mut ux[r.clone()],
        &mut uz[r.clone()],
        &mut vx[r.clone()],
        &mut vz[r],
    );
    if bad.is_none() {
        *bad = row_bad.map(|ix| z * nx + ix);
    }
}

/// The instruction set the band sweep is compiled for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Isa {
    /// The build's baseline (SSE2 on x86-64).
    Baseline,
    /// 256-bit vectors (x86-64 with AVX2), chosen at run time.
    Avx2,
}

impl Isa {
    /// The widest this CPU runs. The results are the same bits either way:
    /// no operation is fused or reordered, only done several at a time.
    pub fn detect() -> Isa {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            return Isa::Avx2;
        }
        Isa::Baseline
    }
}

/// Takes one step over `band` with the instruction set `isa` (which must
/// have come from `Isa::detect`); returns the index of the first block of
/// the band that blew up.
pub fn sweep_band<T: Real, C: Coordinate<T>>(
    isa: Isa,
    s: &Shared<'_, T, C>,
    band: Band<'_, T, C>,
    scratch: &mut Scratch<T, C>,
) -> Option<usize> {
    match isa {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `Isa::Avx2` only comes from `Isa::detect` on a CPU with AVX2.
        Isa::Avx2 => unsafe { sweep_band_avx2(s, band, scratch) },
        _ => sweep_band_body(s, band, scratch),
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn sweep_band_avx2<T: Real, C: Coordinate<T>>(
    s: &Shared<'_, T, C>,
    band: Band<'_, T, C>,
    scratch: &mut Scratch<T, C>,
) -> Option<usize> {
    sweep_band_body(s, band, scratch)
}

#[inline(always)]
fn sweep_band_body<T: Real, C: Coordinate<T>>(
    s: &Shared<'_, T, C>,
    band: Band<'_, T, C>,
    scratch: &mut Scratch<T, C>,
) -> Option<usize> {
    let (nx, nz) = (s.c.nx, s.c.nz);
    let Band {
        rows,
        ux,
        uz,
        vx,
        vz,
        fx,
        fz,
        mut interface,
    } = band;
    let (a, b) = (rows.start, rows.end);
    let own = |z: usize| (z - a) * nx..(z - a + 1) * nx;
    let mut bad = None;
    if !s.forces {
        for z in a..b {
            advance_own(s, a, z, ux, uz, vx, vz, &mut bad);
        }
        return bad;
    }
    let Scratch {
        below,
        above,
        horizontal,
        up,
        down,
        sum_x,
        sum_z,
        junctions,
    } = scratch;
    // Halo rows (a blow-up there is reported by the band owning them).
    if a > 0 {
        advance_row(
            s,
            a - 1,
            &mut below.ux,
            &mut below.uz,
            &mut below.vx,
            &mut below.vz,
        );
    }
    if b < nz {
        advance_row(
            s,
            b,
            &mut above.ux,
            &mut above.uz,
            &mut above.vx,
            &mut above.vz,
        );
    }
    advance_own(s, a, a, ux, uz, vx, vz, &mut bad);
    if a > 0 {
        let first = view(ux, uz, vx, vz, own(a));
        upward_bonds(
            s.bonds,
            s.c.eta,
            s.c.bond_damping,
            below.view(),
            first,
            down,
        );
        down.hold_forces(s.c.f32_probe);
    } else {
        down.clear();
    }
    let drive_target = s.drive_target;
    for z in a..b {
        if z + 1 < b {
            advance_own(s, a, z + 1, ux, uz, vx, vz, &mut bad);
        }
        let row = view(ux, uz, vx, vz, own(z));
        horizontal_bonds(s.bonds, s.c.eta, s.c.bond_damping, row, horizontal);
        if z + 1 < b {
            let next = view(ux, uz, vx, vz, own(z + 1));
            upward_bonds(s.bonds, s.c.eta, s.c.bond_damping, row, next, up);
        } else if z + 1 < nz {
            upward_bonds(s.bonds, s.c.eta, s.c.bond_damping, row, above.view(), up);
        } else {
            up.clear();
        }
        if s.c.f32_probe != 0 {
            horizontal.hold_forces(s.c.f32_probe);
            up.hold_forces(s.c.f32_probe);
        }
        let r = own(z);
        let (fx_row, fz_row) = (&mut fx[r.clone()], &mut fz[r]);
        gather_row(horizontal, up, down, sum_x, sum_z);
        for ix in 0..nx {
            let i = z * nx + ix;
            [fx_row[ix], fz_row[ix]] = external_loads(
                s.c,
                &s.after,
                drive_target,
                s.flags[i],
                ix,
                [row.ux[ix], row.uz[ix]],
                [row.vx[ix], row.vz[ix]],
                [sum_x[ix], sum_z[ix]],
            );
        }
        if z == 0 {
            if let Some(out) = interface.as_mut() {
                interface_row(s, row, fx_row, out, junctions);
            }
        }
        std::mem::swap(up, down);
    }
    bad
}
