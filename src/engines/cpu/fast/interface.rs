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
use crate::engines::kernels::junctions::{self, JunctionBlock, KeptSums, LaneSum, JUNCTION_LANES};
use crate::engines::precision_probe::JUNCTIONS;
use crate::model::real::{Coordinate, ForceSum, Real};
use crate::model::scenario::FrictionLaw;

/// Working arrays of the junction pass, kept between steps.
#[derive(Debug, Clone, Default)]
pub struct JunctionScratch<T, S, C> {
    /// Forces of one block's junctions (their break test).
    force: Vec<T>,
    /// Per junction of one block, pinned after the step: k_j·(a_j − r)
    /// and k_j (0 and 0 where it slips: neutral in the lane sums).
    term: Vec<T>,
    stiffness: Vec<T>,
    /// Lane sums, block-major: `lanes[ix * JUNCTION_LANES + lane]`.
    lanes: Vec<LaneSum<T, S>>,
    /// Per block: slipping junctions, one slipping junction's force and
    /// the reference r of its sums.
    slipping: Vec<(u32, T, C)>,
    /// Junctions of one block left to the reference's `junction`.
    rare: Vec<bool>,
    /// Per block, the sums kept while none of its junctions changes
    /// (`junctions::KeptSums`), and whether they stood for this step's.
    kept: Vec<KeptSums<T, S, C>>,
    kept_now: Vec<bool>,
}

impl<T: Real, C: Coordinate<T>> JunctionScratch<T, C::Sum, C> {
    /// Drops the kept sums: the engine calls this wherever junctions are
    /// written other than by stepping (loaded states, the trigger's
    /// anchors), so no sums of springs no longer there are used.
    pub fn forget_junction_sums(&mut self) {
        self.kept.clear();
    }

    /// Blocks whose sums are kept now.
    pub fn kept_blocks(&self) -> usize {
        self.kept
            .iter()
            .filter(|k| k.stiffness_max > T::zero())
            .count()
    }
}

/// Friction and normal force of the interface row from the row's new state
/// and bulk forces `fx`.
#[inline(always)]
pub fn interface_row<T: Real, C: Coordinate<T>>(
    s: &Shared<'_, T, C>,
    row: RowView<'_, T, C>,
    fx: &[T],
    out: &mut Interface<'_, T, C>,
    scratch: &mut JunctionScratch<T, C::Sum, C>,
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
    scratch: &mut JunctionScratch<T, C::Sum, C>,
) {
    let c = s.c;
    let (nx, ns) = (c.nx, c.junction_count);
    let lanes_used = JUNCTION_LANES.min(ns);
    scratch.force.resize(ns, T::zero());
    scratch.term.resize(ns, T::zero());
    scratch.stiffness.resize(ns, T::zero());
    scratch
        .lanes
        .resize(nx * JUNCTION_LANES, LaneSum::default());
    scratch.slipping.resize(nx, (0, T::zero(), C::default()));
    scratch.rare.resize(ns, false);
    scratch.kept.resize(nx, KeptSums::default());
    scratch.kept_now.resize(nx, false);
    let JunctionScratch {
        force,
        term,
        stiffness,
        lanes,
        slipping,
        rare,
        kept,
        kept_now,
    } = scratch;
    // While the normal load is applied every pinned junction's stiffness
    // follows it, and the precision probe rounds junction values: the
    // reference's path for all, and nothing kept.
    let reference_path = s.after.preparing || c.f32_probe & JUNCTIONS != 0;
    for ix in 0..nx {
        let u = [row.ux[ix], row.uz[ix]];
        let mut jb = junctions::junction_block(c, u);
        kept_now[ix] = !reference_path && kept[ix].hold(&jb);
        if kept_now[ix] {
            // No junction can change: the kept sums are this step's.
            slipping[ix] = (0, jb.slipping_force, kept[ix].reference);
            continue;
        }
        let spring = &mut out.spring[ix * ns..(ix + 1) * ns];
        let state = &mut out.state[ix * ns..(ix + 1) * ns];
        jb.reference = junctions::junction_reference(c, &s.after, &jb, state[0], &spring[0]);
        let lane_sums = &mut lanes[ix * JUNCTION_LANES..ix * JUNCTION_LANES + lanes_used];
        if reference_path {
            let each = spring.iter_mut().zip(&mut *state);
            for (j, (spring, state)) in each.enumerate() {
                junctions::junction(c, &s.after, ix, j, &jb, spring, state);
            }
        }
        let all_pinned = !reference_path && pinned_forces(&jb, spring, state, force);
        if !reference_path && !all_pinned && common_junctions(&jb, spring, state, force, rare) {
            let each = spring.iter_mut().zip(&mut *state).zip(&*rare);
            for (j, ((spring, state), _)) in each.enumerate().filter(|(_, x)| *x.1) {
                junctions::junction(c, &s.after, ix, j, &jb, spring, state);
            }
        }
        pinned_terms(c, &jb, spring, state, term, stiffness);
        let count = if all_pinned { 0 } else { count_slipping(state) };
        slipping[ix] = (count, jb.slipping_force, jb.reference);
        sum_lanes(term, stiffness, lane_sums);
    }
    // The reference's final sum, the lanes' tree (merge_lanes), every block at once.
    for (ix, contact) in out.contact.iter_mut().enumerate() {
        let (count, slipping_force, reference) = slipping[ix];
        let total = if kept_now[ix] {
            kept[ix].lane_sum()
        } else {
            let lane_sums = &lanes[ix * JUNCTION_LANES..ix * JUNCTION_LANES + lanes_used];
            let mut total = junctions::merge_lanes(lane_sums);
            // The lanes here add 0 for a slipping junction; the count is
            // made apart.
            total.slipping = count;
            kept[ix] = if reference_path {
                KeptSums::default()
            } else {
                KeptSums::of(reference, &total)
            };
            total
        };
        let pinned = junctions::pinned_friction(c, row.ux[ix], reference, &total);
        *contact = [
            junctions::junction_friction(c, slipping_force, pinned, count, fx[ix], row.vx[ix]),
            junctions::foundation_normal(c, row.uz[ix].value()),
        ];
    }
}

/// Each junction's terms of the lane sums after the step: k_j·(a_j − r)
/// and k_j where it is pinned, 0 and 0 where it slips (adding 0 leaves the
/// reference's sums and maxima unchanged).
#[inline(always)]
fn pinned_terms<T: Real, C: Coordinate<T>>(
    c: &crate::engines::step_params::Consts<T>,
    jb: &JunctionBlock<T, C>,
    spring: &[JunctionSpring<C, T>],
    state: &[[u32; 2]],
    term: &mut [T],
    stiffness: &mut [T],
) {
    let n = term.len();
    let each = term
        .iter_mut()
        .zip(&mut stiffness[..n])
        .zip(&spring[..n])
        .zip(&state[..n]);
    for (((t, k), spring), state) in each {
        let pinned = state[0] == PINNED;
        let anchored = junctions::anchored_term(c, jb, spring);
        *t = if pinned { anchored } else { T::zero() };
        *k = if pinned { spring.stiffness } else { T::zero() };
    }
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

/// Lane sums of one block's junction terms in the reference's order:
/// lane l holds the terms of junctions l, l + LANES, ... added in turn.
#[inline(always)]
fn sum_lanes<T: Real, S: ForceSum<T>>(
    term: &[T],
    stiffness: &[T],
    lane_sums: &mut [LaneSum<T, S>],
) {
    let lanes = lane_sums.len();
    for (sum, (t, k)) in lane_sums
        .iter_mut()
        .zip(term[..lanes].iter().zip(&stiffness[..lanes]))
    {
        *sum = LaneSum::default().add_pinned(*k, *t);
    }
    let rest = term[lanes..]
        .chunks(lanes)
        .zip(stiffness[lanes..].chunks(lanes));
    for (terms, ks) in rest {
        for (sum, (t, k)) in lane_sums.iter_mut().zip(terms.iter().zip(ks)) {
            *sum = sum.add_pinned(*k, *t);
        }
    }
}
