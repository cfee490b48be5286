//! The interface row's friction in the sweep engine: the reference
//! engine's junction pass with a vectorised path for the common case, a
//! block whose junctions are all pinned and under threshold. Such a block's
//! junction forces are one straight loop; any other block (a junction
//! slipping, one crossing its threshold, the normal-load phase) runs the
//! reference's `junctions::junction` on each junction in turn. Lane sums and the final
//! sums follow the reference's order (`junctions::JUNCTION_LANES`), the
//! final sums for all blocks of the row at once so that the 64 dependent
//! additions of one block overlap with the other blocks'.

use super::rows::RowView;
use super::step::{Interface, Shared};
use crate::engines::cpu::{JunctionSpring, PINNED};
use crate::engines::kernels::block_laws::block_law;
use crate::engines::kernels::junctions::{self, JunctionBlock, LaneSum, JUNCTION_LANES};
use crate::engines::precision_probe::JUNCTIONS;
use crate::model::real::{Coordinate, ForceSum, Real};
use crate::model::scenario::FrictionLaw;

/// Working arrays of the junction pass, kept between steps.
#[derive(Debug, Clone, Default)]
pub struct JunctionScratch<T, S> {
    /// Forces of one block's junctions.
    force: Vec<T>,
    /// Lane sums (the precision's `ForceSum`), block-major:
    /// `lanes[ix * JUNCTION_LANES + lane]`.
    lanes: Vec<S>,
    total: Vec<S>,
    /// Per block: slipping junctions and one slipping junction's force.
    slipping: Vec<(u32, T)>,
    /// Junctions of one block left to the reference's `junction`.
    rare: Vec<bool>,
}

/// Friction and normal force of the interface row from the row's new state
/// and bulk forces `fx`.
#[inline(always)]
pub fn interface_row<T: Real, C: Coordinate<T>>(
    s: &Shared<'_, T, C>,
    row: RowView<'_, T, C>,
    fx: &[T],
    out: &mut Interface<'_, T, C>,
    scratch: &mut JunctionScratch<T, C::Sum>,
) {
    let c = s.c;
    match s.law {
        FrictionLaw::None => {}
        law if law.is_per_block() => {
            let words = law.declaration().block_state_words;
            let blocks = out.contact.iter_mut().zip(&mut *out.slide);
            for (ix, (contact, slide)) in blocks.enumerate() {
                let state = &mut out.law_state[ix * words..(ix + 1) * words];
                *contact = block_law(
                    c, &s.after, law, row.uz[ix], row.vx[ix], fx[ix], slide, state,
                );
            }
        }
        FrictionLaw::Junctions | FrictionLaw::SingleJunction => {
            junction_row(s, row, fx, out, scratch);
        }
        // Every law is per-block or a junction law (`model::friction::Law`).
        law => unreachable!("{law:?} has no engine path"),
    }
}

#[inline(always)]
fn junction_row<T: Real, C: Coordinate<T>>(
    s: &Shared<'_, T, C>,
    row: RowView<'_, T, C>,
    fx: &[T],
    out: &mut Interface<'_, T, C>,
    scratch: &mut JunctionScratch<T, C::Sum>,
) {
    let c = s.c;
    let (nx, ns) = (c.nx, c.junction_count);
    let lanes_used = JUNCTION_LANES.min(ns);
    scratch.force.resize(ns, T::zero());
    scratch.lanes.resize(nx * JUNCTION_LANES, C::Sum::default());
    scratch.total.resize(nx, C::Sum::default());
    scratch.slipping.resize(nx, (0, T::zero()));
    scratch.rare.resize(ns, false);
    let JunctionScratch {
        force,
        lanes,
        total,
        slipping,
        rare,
    } = scratch;
    for ix in 0..nx {
        let u = [row.ux[ix], row.uz[ix]];
        let jb = junctions::junction_block(c, u);
        let spring = &mut out.spring[ix * ns..(ix + 1) * ns];
        let state = &mut out.state[ix * ns..(ix + 1) * ns];
        let lane_sums = &mut lanes[ix * JUNCTION_LANES..ix * JUNCTION_LANES + lanes_used];
        let reference_path = s.after.preparing || c.f32_probe & JUNCTIONS != 0;
        if reference_path {
            // While the normal load is applied every pinned junction's
            // stiffness follows it, and the precision probe rounds junction
            // values: the reference's path for all.
            let each = force.iter_mut().zip(&mut *spring).zip(&mut *state);
            for (j, ((f, spring), state)) in each.enumerate() {
                *f = pinned_force(junctions::junction(c, &s.after, ix, j, &jb, spring, state));
            }
        }
        let all_pinned = !reference_path && pinned_forces(&jb, spring, state, force);
        if !reference_path && !all_pinned && common_junctions(&jb, spring, state, force, rare) {
            let each = force
                .iter_mut()
                .zip(&mut *spring)
                .zip(&mut *state)
                .zip(&*rare);
            for (j, (((f, spring), state), _)) in each.enumerate().filter(|(_, x)| *x.1) {
                *f = pinned_force(junctions::junction(c, &s.after, ix, j, &jb, spring, state));
            }
        }
        let count = if all_pinned { 0 } else { count_slipping(state) };
        slipping[ix] = (count, jb.slipping_force);
        sum_lanes(force, lane_sums);
    }
    // The reference's final sum, lane by lane, every block at once.
    total.fill(C::Sum::default());
    for lane in 0..lanes_used {
        for (ix, t) in total.iter_mut().enumerate() {
            *t = t.merge(lanes[ix * JUNCTION_LANES + lane]);
        }
    }
    for (ix, contact) in out.contact.iter_mut().enumerate() {
        let (count, slipping_force) = slipping[ix];
        let sums = LaneSum {
            pinned: total[ix],
            slipping: count,
        };
        *contact = [
            junctions::junction_friction(c, slipping_force, sums, fx[ix], row.vx[ix]),
            junctions::foundation_normal(c, row.uz[ix].value()),
        ];
    }
}

/// A junction's term of its lane's pinned sum: its force if pinned, 0 if
/// it slips (adding 0 leaves the reference's sum unchanged).
#[inline(always)]
fn pinned_force<T: Real>(force: Option<T>) -> T {
    force.unwrap_or(T::zero())
}

/// Junctions of one block slipping after its step.
#[inline(always)]
fn count_slipping(state: &[[u32; 2]]) -> u32 {
    state.iter().map(|s| (s[0] != PINNED) as u32).sum()
}

/// The forces of a block's junctions if every one is pinned and none
/// exceeds the threshold (then nothing changes state: true); false leaves
/// the block to the reference pass.
#[inline(always)]
fn pinned_forces<T: Real, C: Coordinate<T>>(
    jb: &JunctionBlock<T, C>,
    spring: &[JunctionSpring<C, T>],
    state: &[[u32; 2]],
    force: &mut [T],
) -> bool {
    let n = force.len();
    let (spring, state) = (&spring[..n], &state[..n]);
    let mut all_pinned = true;
    for s in state {
        all_pinned &= s[0] == PINNED;
    }
    if !all_pinned {
        return false;
    }
    let mut over = false;
    for (f, s) in force.iter_mut().zip(spring) {
        // As the reference: f = −k_j (u_x − anchor).
        *f = -s.stiffness * jb.ux.diff(s.anchor);
        over |= f.abs() > jb.threshold;
    }
    !over
}

/// The junctions of a block in the common cases, vectorised: pinned under
/// threshold (force −k_j (u_x − anchor), no change) and slipping with
/// steps left after this one (countdown, 0 in the pinned sum). Marks in `rare`
/// the others — a pinned junction over threshold breaks, a countdown that
/// ends re-pins or waits — and leaves them untouched for the reference's
/// `junction`; returns whether there are any.
#[inline(always)]
fn common_junctions<T: Real, C: Coordinate<T>>(
    jb: &JunctionBlock<T, C>,
    spring: &[JunctionSpring<C, T>],
    state: &mut [[u32; 2]],
    force: &mut [T],
    rare: &mut [bool],
) -> bool {
    let n = force.len();
    let (spring, state, rare) = (&spring[..n], &mut state[..n], &mut rare[..n]);
    let mut any = false;
    for j in 0..n {
        let left = state[j][0];
        let pinned = left == PINNED;
        let held = -spring[j].stiffness * jb.ux.diff(spring[j].anchor);
        let next_left = left.saturating_sub(1);
        let is_rare = if pinned {
            held.abs() > jb.threshold
        } else {
            next_left == 0
        };
        rare[j] = is_rare;
        any |= is_rare;
        force[j] = if pinned { held } else { T::zero() };
        state[j][0] = if pinned || is_rare { left } else { next_left };
    }
    any
}

/// Lane sums of one block's junction forces in the reference's order:
/// lane l holds 0 + f_l + f_(l+LANES) + ..., in the precision's `ForceSum`.
#[inline(always)]
fn sum_lanes<T: Real, S: ForceSum<T>>(force: &[T], lane_sums: &mut [S]) {
    let lanes = lane_sums.len();
    for (sum, f) in lane_sums.iter_mut().zip(&force[..lanes]) {
        *sum = S::default().add(*f);
    }
    for chunk in force[lanes..].chunks(lanes) {
        for (sum, f) in lane_sums.iter_mut().zip(chunk) {
            *sum = sum.add(*f);
        }
    }
}
