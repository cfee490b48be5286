//! Row kernels of the sweep engine: a lattice row's bonds computed once
//! each into padded structure-of-arrays rows, and the gather that adds them
//! to both ends in the reference engine's order.
//!
//! Why the result is bitwise the reference's: the force a bond puts on its
//! far end is exactly the negation of the force on its near end (IEEE
//! subtraction is antisymmetric, and every later operation either squares
//! the sign away or carries it through a product), and the gather adds the
//! two terms of each bond (spring, then dashpot) in the order of
//! `lattice::STENCIL`, adding the negation where the reference adds the reversed
//! bond. Missing bonds (edges) are +0.0 in the padding: a sum that starts at
//! +0.0 never becomes −0.0, so adding +0.0 changes no bit.

use crate::cpu::bulk_forces::BondConsts;
use crate::real::{Coordinate, ForceSum, Real};

/// One row of blocks, read-only: displacements and velocities.
#[derive(Clone, Copy)]
pub struct RowView<'a, T, C> {
    pub ux: &'a [C],
    pub uz: &'a [C],
    pub vx: &'a [T],
    pub vz: &'a [T],
}

impl<'a, T, C> RowView<'a, T, C> {
    /// Blocks `from..from + n` of the row.
    #[inline]
    fn span(&self, from: usize, n: usize) -> RowView<'a, T, C> {
        RowView {
            ux: &self.ux[from..from + n],
            uz: &self.uz[from..from + n],
            vx: &self.vx[from..from + n],
            vz: &self.vz[from..from + n],
        }
    }
}

/// The forces one bond direction puts on the near end of each bond of a
/// row: spring (x, z) and dashpot (x, z). Padded: entry `ix + 1` is the
/// bond starting at column `ix`; entries 0 and nx + 1 (and those of missing
/// bonds) stay +0.0.
#[derive(Debug, Clone, Default)]
pub struct BondRow<T> {
    pub spring_x: Vec<T>,
    pub spring_z: Vec<T>,
    pub damper_x: Vec<T>,
    pub damper_z: Vec<T>,
}

impl<T: Real> BondRow<T> {
    pub fn new(nx: usize) -> Self {
        let zeros = vec![T::zero(); nx + 2];
        BondRow {
            spring_x: zeros.clone(),
            spring_z: zeros.clone(),
            damper_x: zeros.clone(),
            damper_z: zeros,
        }
    }

    /// Every bond force rounded to f32 when the precision probe holds
    /// forces (`crate::precision_probe`), as the reference engine rounds
    /// each bond's terms.
    pub fn hold_forces(&mut self, probe: u32) {
        use crate::precision_probe::{hold_all, FORCES};
        for v in [
            &mut self.spring_x,
            &mut self.spring_z,
            &mut self.damper_x,
            &mut self.damper_z,
        ] {
            hold_all(probe, FORCES, v);
        }
    }

    fn clear(&mut self) {
        for v in [
            &mut self.spring_x,
            &mut self.spring_z,
            &mut self.damper_x,
            &mut self.damper_z,
        ] {
            v.fill(T::zero());
        }
    }
}

/// The bonds from a row to the row above it: vertical, diagonal (+1, +1)
/// and anti-diagonal (−1, +1), the forward bonds of `lattice::STENCIL`
/// besides the horizontal one.
#[derive(Debug, Clone, Default)]
pub struct UpwardBonds<T> {
    pub vertical: BondRow<T>,
    pub diagonal: BondRow<T>,
    pub anti_diagonal: BondRow<T>,
}

impl<T: Real> UpwardBonds<T> {
    pub fn new(nx: usize) -> Self {
        UpwardBonds {
            vertical: BondRow::new(nx),
            diagonal: BondRow::new(nx),
            anti_diagonal: BondRow::new(nx),
        }
    }

    /// See `BondRow::hold_forces`.
    pub fn hold_forces(&mut self, probe: u32) {
        self.vertical.hold_forces(probe);
        self.diagonal.hold_forces(probe);
        self.anti_diagonal.hold_forces(probe);
    }

    /// No row above (the top row): no bonds.
    pub fn clear(&mut self) {
        self.vertical.clear();
        self.diagonal.clear();
        self.anti_diagonal.clear();
    }
}

/// Constants of the four forward bond directions.
#[derive(Debug, Clone, Copy)]
pub struct ForwardBonds<T> {
    pub horizontal: BondConsts<T>,
    pub vertical: BondConsts<T>,
    pub diagonal: BondConsts<T>,
    pub anti_diagonal: BondConsts<T>,
}

impl<T: Real> ForwardBonds<T> {
    /// Picks the forward directions out of the reference engine's stencil
    /// constants (same values, so the same bits).
    pub fn from_stencil(bonds: &[BondConsts<T>; 8]) -> Self {
        let find = |dx: i32, dz: i32| {
            *bonds
                .iter()
                .find(|b| b.dx == dx && b.dz == dz)
                .expect("the stencil holds every forward direction")
        };
        ForwardBonds {
            horizontal: find(1, 0),
            vertical: find(0, 1),
            diagonal: find(1, 1),
            anti_diagonal: find(-1, 1),
        }
    }
}

/// Forces of bonds `near[k] → far[k]` on their near ends, into `out` at
/// `at..at + n` (n = near's length).
#[inline(always)]
fn bond_span<T: Real, C: Coordinate<T>, const BOND_DAMPING: bool>(
    b: &BondConsts<T>,
    eta: T,
    near: RowView<'_, T, C>,
    far: RowView<'_, T, C>,
    out: &mut BondRow<T>,
    at: usize,
) {
    let n = near.ux.len();
    bond_kernel::<T, C, BOND_DAMPING>(
        b,
        eta,
        [near.ux, near.uz, far.ux, far.uz],
        [near.vx, near.vz, far.vx, far.vz],
        &mut out.spring_x[at..at + n],
        &mut out.spring_z[at..at + n],
        &mut out.damper_x[at..at + n],
        &mut out.damper_z[at..at + n],
    );
}

/// The bond loop proper: one straight loop over equal-length slices, in a
/// function of its own so that the compiler knows the outputs alias
/// nothing and vectorises it (sqrt and divides included). Inlined into the
/// band sweep so that it takes that function's instruction set.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn bond_kernel<T: Real, C: Coordinate<T>, const BOND_DAMPING: bool>(
    b: &BondConsts<T>,
    eta: T,
    u: [&[C]; 4],
    v: [&[T]; 4],
    sx: &mut [T],
    sz: &mut [T],
    dx: &mut [T],
    dz: &mut [T],
) {
    let n = sx.len();
    let (sz, dx, dz) = (&mut sz[..n], &mut dx[..n], &mut dz[..n]);
    let (uxi, uzi, uxj, uzj) = (&u[0][..n], &u[1][..n], &u[2][..n], &u[3][..n]);
    let (vxi, vzi, vxj, vzj) = (&v[0][..n], &v[1][..n], &v[2][..n], &v[3][..n]);
    let two = T::one() + T::one();
    let (r00, r01, rest, k) = (b.r0[0], b.r0[1], b.rest, b.k);
    for i in 0..n {
        // The reference's `bulk_force`, operation for operation.
        let du0 = uxj[i].diff(uxi[i]);
        let du1 = uzj[i].diff(uzi[i]);
        let r0 = r00 + du0;
        let r1 = r01 + du1;
        let len = (r0 * r0 + r1 * r1).sqrt();
        let stretch = (two * (r00 * du0 + r01 * du1) + (du0 * du0 + du1 * du1)) / (len + rest);
        let inv_len = T::one() / len;
        let n0 = r0 * inv_len;
        let n1 = r1 * inv_len;
        let spring = k * stretch;
        sx[i] = spring * n0;
        sz[i] = spring * n1;
        let dv0 = vxj[i] - vxi[i];
        let dv1 = vzj[i] - vzi[i];
        if BOND_DAMPING {
            let along = eta * (dv0 * n0 + dv1 * n1);
            dx[i] = along * n0;
            dz[i] = along * n1;
        } else {
            dx[i] = eta * dv0;
            dz[i] = eta * dv1;
        }
    }
}

/// `bond_span` with the damping form chosen once per span.
#[inline(always)]
fn bonds<T: Real, C: Coordinate<T>>(
    b: &BondConsts<T>,
    eta: T,
    bond_damping: bool,
    near: RowView<'_, T, C>,
    far: RowView<'_, T, C>,
    out: &mut BondRow<T>,
    at: usize,
) {
    if bond_damping {
        bond_span::<T, C, true>(b, eta, near, far, out, at)
    } else {
        bond_span::<T, C, false>(b, eta, near, far, out, at)
    }
}

/// Horizontal bonds of a row: column ix to ix + 1.
#[inline(always)]
pub fn horizontal_bonds<T: Real, C: Coordinate<T>>(
    fb: &ForwardBonds<T>,
    eta: T,
    bond_damping: bool,
    row: RowView<'_, T, C>,
    out: &mut BondRow<T>,
) {
    let nx = row.ux.len();
    if nx > 1 {
        let (near, far) = (row.span(0, nx - 1), row.span(1, nx - 1));
        bonds(&fb.horizontal, eta, bond_damping, near, far, out, 1);
    }
}

/// Bonds from `row` to the row `above` it.
#[inline(always)]
pub fn upward_bonds<T: Real, C: Coordinate<T>>(
    fb: &ForwardBonds<T>,
    eta: T,
    bond_damping: bool,
    row: RowView<'_, T, C>,
    above: RowView<'_, T, C>,
    out: &mut UpwardBonds<T>,
) {
    let nx = row.ux.len();
    bonds(
        &fb.vertical,
        eta,
        bond_damping,
        row,
        above,
        &mut out.vertical,
        1,
    );
    if nx > 1 {
        // Column ix to ix + 1 above, and column ix + 1 to ix above.
        let (left, right) = (row.span(0, nx - 1), row.span(1, nx - 1));
        let (above_left, above_right) = (above.span(0, nx - 1), above.span(1, nx - 1));
        bonds(
            &fb.diagonal,
            eta,
            bond_damping,
            left,
            above_right,
            &mut out.diagonal,
            1,
        );
        bonds(
            &fb.anti_diagonal,
            eta,
            bond_damping,
            right,
            above_left,
            &mut out.anti_diagonal,
            2,
        );
    }
}

/// Sum of the bond forces on each block of a row, in the order of
/// `lattice::STENCIL`: (1,0), (−1,0), (0,1), (0,−1), (1,1), (−1,1), (1,−1),
/// (−1,−1); `up` are this row's upward bonds, `down` the row below's.
/// The sums are the precision's `ForceSum`, as in the reference's
/// `bulk_force`.
#[inline(always)]
pub fn gather_row<T: Real, S: ForceSum<T>>(
    horizontal: &BondRow<T>,
    up: &UpwardBonds<T>,
    down: &UpwardBonds<T>,
    fx: &mut [S],
    fz: &mut [S],
) {
    gather_component(
        [
            &horizontal.spring_x,
            &horizontal.damper_x,
            &up.vertical.spring_x,
            &up.vertical.damper_x,
            &down.vertical.spring_x,
            &down.vertical.damper_x,
            &up.diagonal.spring_x,
            &up.diagonal.damper_x,
            &up.anti_diagonal.spring_x,
            &up.anti_diagonal.damper_x,
            &down.anti_diagonal.spring_x,
            &down.anti_diagonal.damper_x,
            &down.diagonal.spring_x,
            &down.diagonal.damper_x,
        ],
        fx,
    );
    gather_component(
        [
            &horizontal.spring_z,
            &horizontal.damper_z,
            &up.vertical.spring_z,
            &up.vertical.damper_z,
            &down.vertical.spring_z,
            &down.vertical.damper_z,
            &up.diagonal.spring_z,
            &up.diagonal.damper_z,
            &up.anti_diagonal.spring_z,
            &up.anti_diagonal.damper_z,
            &down.anti_diagonal.spring_z,
            &down.anti_diagonal.damper_z,
            &down.diagonal.spring_z,
            &down.diagonal.damper_z,
        ],
        fz,
    );
}

/// One force component of `gather_row`. `rows` in the order: horizontal
/// (spring, damper), up vertical, down vertical, up diagonal, up
/// anti-diagonal, down anti-diagonal, down diagonal.
#[inline(always)]
fn gather_component<T: Real, S: ForceSum<T>>(rows: [&Vec<T>; 14], out: &mut [S]) {
    let n = out.len();
    fn at<T>(r: &[T], shift: usize, n: usize) -> &[T] {
        &r[shift..shift + n]
    }
    // Padded index of the bond on each side: a block at column ix is the
    // near end of the bonds at ix + 1 and the far end of the horizontal
    // one at ix, the anti-diagonal below at ix + 2 and the diagonal below
    // at ix.
    let (h_s, h_d) = (at(rows[0], 1, n), at(rows[1], 1, n));
    let (hb_s, hb_d) = (at(rows[0], 0, n), at(rows[1], 0, n));
    let (v_s, v_d) = (at(rows[2], 1, n), at(rows[3], 1, n));
    let (vb_s, vb_d) = (at(rows[4], 1, n), at(rows[5], 1, n));
    let (d_s, d_d) = (at(rows[6], 1, n), at(rows[7], 1, n));
    let (a_s, a_d) = (at(rows[8], 1, n), at(rows[9], 1, n));
    let (ab_s, ab_d) = (at(rows[10], 2, n), at(rows[11], 2, n));
    let (db_s, db_d) = (at(rows[12], 0, n), at(rows[13], 0, n));
    for k in 0..n {
        // Subtracting a far-end term is adding its negation (exact).
        let mut f = S::default();
        f = f.add_bond(h_s[k], h_d[k]);
        f = f.add_bond(-hb_s[k], -hb_d[k]);
        f = f.add_bond(v_s[k], v_d[k]);
        f = f.add_bond(-vb_s[k], -vb_d[k]);
        f = f.add_bond(d_s[k], d_d[k]);
        f = f.add_bond(a_s[k], a_d[k]);
        f = f.add_bond(-ab_s[k], -ab_d[k]);
        f = f.add_bond(-db_s[k], -db_d[k]);
        out[k] = f;
    }
}
