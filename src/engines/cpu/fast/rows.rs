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

use crate::engines::kernels::bulk_forces::BondConsts;
use crate::model::real::{Coordinate, ForceSum, Real};

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
    /// The spring's rotation term q·du where bonds are split (mixed f32,
    /// `ForceSum::SPLITS_BONDS`; spring_x/z then hold q·r0); unused else.
    pub rotation_x: Vec<T>,
    pub rotation_z: Vec<T>,
    pub damper_x: Vec<T>,
    pub damper_z: Vec<T>,
}

impl<T: Real> BondRow<T> {
    pub fn new(nx: usize) -> Self {
        let zeros = vec![T::zero(); nx + 2];
        BondRow {
            spring_x: zeros.clone(),
            spring_z: zeros.clone(),
            rotation_x: zeros.clone(),
            rotation_z: zeros.clone(),
            damper_x: zeros.clone(),
            damper_z: zeros,
        }
    }

    /// Every bond force rounded to f32 when the precision probe holds
    /// forces (`crate::engines::precision_probe`), as the reference engine rounds
    /// each bond's terms.
    pub fn hold_forces(&mut self, probe: u32) {
        use crate::engines::precision_probe::{hold_all, FORCES};
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
            &mut self.rotation_x,
            &mut self.rotation_z,
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
        [
            &mut out.spring_x[at..at + n],
            &mut out.spring_z[at..at + n],
            &mut out.rotation_x[at..at + n],
            &mut out.rotation_z[at..at + n],
            &mut out.damper_x[at..at + n],
            &mut out.damper_z[at..at + n],
        ],
    );
}

/// The bond loop proper: one straight loop over equal-length slices, in a
/// function of its own so that the compiler knows the outputs alias
/// nothing and vectorises it (sqrt and divides included). Inlined into the
/// band sweep so that it takes that function's instruction set.
#[inline(always)]
fn bond_kernel<T: Real, C: Coordinate<T>, const BOND_DAMPING: bool>(
    b: &BondConsts<T>,
    eta: T,
    u: [&[C]; 4],
    v: [&[T]; 4],
    out: [&mut [T]; 6],
) {
    let [sx, sz, rx, rz, dx, dz] = out;
    let n = sx.len();
    let (sz, rx, rz, dx, dz) = (
        &mut sz[..n],
        &mut rx[..n],
        &mut rz[..n],
        &mut dx[..n],
        &mut dz[..n],
    );
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
        let num = two * (r00 * du0 + r01 * du1) + (du0 * du0 + du1 * du1);
        let over = len + rest;
        let dv0 = vxj[i] - vxi[i];
        let dv1 = vzj[i] - vzi[i];
        if <C::Sum as ForceSum<T>>::SPLITS_BONDS {
            let len_times_over = rest * over + num;
            let q = k * num / len_times_over;
            sx[i] = q * r00;
            sz[i] = q * r01;
            rx[i] = q * du0;
            rz[i] = q * du1;
            if BOND_DAMPING {
                let inv = over / len_times_over;
                let (n00, n01) = (r00 * inv, r01 * inv);
                let (n10, n11) = (du0 * inv, du1 * inv);
                let along = eta * ((dv0 * n00 + dv1 * n01) + (dv0 * n10 + dv1 * n11));
                dx[i] = along * n00 + along * n10;
                dz[i] = along * n01 + along * n11;
            } else {
                dx[i] = eta * dv0;
                dz[i] = eta * dv1;
            }
            continue;
        }
        let spring_per_length = k * num / (over * len);
        sx[i] = spring_per_length * r0;
        sz[i] = spring_per_length * r1;
        if BOND_DAMPING {
            let inv_len = T::one() / len;
            let n0 = r0 * inv_len;
            let n1 = r1 * inv_len;
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
    fn x<T>(b: &BondRow<T>) -> [&[T]; 3] {
        [&b.spring_x, &b.rotation_x, &b.damper_x]
    }
    fn z<T>(b: &BondRow<T>) -> [&[T]; 3] {
        [&b.spring_z, &b.rotation_z, &b.damper_z]
    }
    for (part, out) in [(x::<T> as fn(&BondRow<T>) -> [&[T]; 3], fx), (z::<T>, fz)] {
        gather_component(
            [
                part(horizontal),
                part(&up.vertical),
                part(&down.vertical),
                part(&up.diagonal),
                part(&up.anti_diagonal),
                part(&down.anti_diagonal),
                part(&down.diagonal),
            ],
            out,
        );
    }
}

/// One force component of `gather_row`. `rows` (spring, rotation, damper)
/// in the order: horizontal, up vertical, down vertical, up diagonal, up
/// anti-diagonal, down anti-diagonal, down diagonal.
#[inline(always)]
fn gather_component<T: Real, S: ForceSum<T>>(rows: [[&[T]; 3]; 7], out: &mut [S]) {
    let n = out.len();
    // Padded index of the bond on each side: a block at column ix is the
    // near end of the bonds at ix + 1 and the far end of the horizontal
    // one at ix, the anti-diagonal below at ix + 2 and the diagonal below
    // at ix. Far ends take the negated terms (exact).
    const SHIFT: [usize; 7] = [1, 1, 1, 1, 1, 2, 0];
    const FAR: [bool; 7] = [false, false, true, false, false, true, true];
    let at = |b: usize, part: usize| &rows[b][part][SHIFT[b]..SHIFT[b] + n];
    let terms: [[&[T]; 3]; 7] = std::array::from_fn(|b| [at(b, 0), at(b, 1), at(b, 2)]);
    // The horizontal bond's far end (the bond at ix, shift 0).
    let hb = [&rows[0][0][..n], &rows[0][1][..n], &rows[0][2][..n]];
    for k in 0..n {
        let mut f = S::default();
        let mut add = |s: T, r: T, d: T| {
            f = if S::SPLITS_BONDS {
                f.add(s).add_bond(r, d)
            } else {
                f.add_bond(s, d)
            };
        };
        // The reference's `lattice::STENCIL` order: (1,0), (−1,0), (0,1),
        // (0,−1), (1,1), (−1,1), (1,−1), (−1,−1).
        add(terms[0][0][k], terms[0][1][k], terms[0][2][k]);
        add(-hb[0][k], -hb[1][k], -hb[2][k]);
        for b in 1..7 {
            let [s, r, d] = [terms[b][0][k], terms[b][1][k], terms[b][2][k]];
            if FAR[b] {
                add(-s, -r, -d);
            } else {
                add(s, r, d);
            }
        }
        out[k] = f;
    }
}
