//! CPU twin of `shaders/junctions.wgsl`: the Ns micro-junctions of one
//! interface block pin, break at μs·f_N, slip for a drawn time at μd·f_N and
//! re-pin with zero stretch. The law's table, parameters, break threshold
//! and at-rest rule are in `crate::model::friction::junctions`. The lanes
//! sum the pinned junctions' forces and count the slipping ones; the
//! slipping junctions then act together (`junction_friction`), so that they
//! can hold a block at rest. A slipping junction counts down the steps left
//! of its slip, so nothing here depends on the global step count (runs of
//! any length, and fast-forward, never wrap it).
//!
//! Opening: junctions only attach where the block touches the track. While
//! a block is lifted off (f_N = 0), its pinned junctions break as soon as
//! they carry any force (their threshold μs·f_N is 0) and a junction whose
//! slip time is over waits; it re-pins at the first step the block is
//! pressed back, with the stiffness of the normal force at that step.
//! (Before, it re-pinned at f_N = 0 with k_j = √(c·0) = 0 and stayed pinned
//! with no force for ever.)

use crate::engines::precision_probe::{hold, DRAWS, JUNCTIONS};
use crate::engines::step_params::{Consts, StepParams};
use crate::model::friction::junctions::{break_threshold, slipping_friction};
use crate::model::real::{Coordinate, ForceSum, Real};
use crate::model::rng::slip_steps;

pub use crate::model::junction::{JunctionSpring, JUNCTION_LANES, PINNED};

/// The junction arrays of one interface block (length Ns each), laid out
/// as the GPU's `junction_spring` and `junction_state` buffers.
pub struct JunctionSlots<'a, T, C> {
    pub spring: &'a mut [JunctionSpring<C, T>],
    /// (slip steps left or PINNED, rupture count) per junction.
    pub state: &'a mut [[u32; 2]],
}

/// Normal force the foundation carries under interface block with u_z.
#[inline]
pub fn foundation_normal<T: Real>(c: &Consts<T>, uz: T) -> T {
    crate::model::laws::foundation_normal(c.k_foundation, uz)
}

/// Advances the junctions of interface block `ix` by one step and returns
/// (friction force on the block along x, normal force p); `other` is the
/// block's other force along x (bulk springs, dashpots, loads), which the
/// slipping junctions may hold (`junction_friction`).
#[allow(clippy::too_many_arguments)]
pub fn junctions<T: Real, C: Coordinate<T>>(
    c: &Consts<T>,
    p: &StepParams<T>,
    ix: usize,
    u: [C; 2],
    v: [T; 2],
    other: T,
    slots: JunctionSlots<'_, T, C>,
) -> (T, T) {
    let mut jb = junction_block(c, u);
    jb.reference = junction_reference(c, p, &jb, slots.state[0], &slots.spring[0]);
    let mut lane_sums = [LaneSum::<T, C::Sum>::default(); JUNCTION_LANES];
    let lanes = JUNCTION_LANES.min(c.junction_count);
    for (lane, sum) in lane_sums[..lanes].iter_mut().enumerate() {
        let slots = JunctionSlots {
            spring: &mut *slots.spring,
            state: &mut *slots.state,
        };
        *sum = junction_lane(c, p, ix, lane, &jb, slots);
    }
    let total = merge_lanes(&lane_sums[..lanes]);
    let pinned = pinned_friction(c, jb.ux, jb.reference, &total);
    (
        junction_friction(c, jb.slipping_force, pinned, total.slipping, other, v[0]),
        foundation_normal(c, u[1].value()),
    )
}

/// Twin of the WGSL `junction_reference`: the coordinate r the block's
/// pinned forces are summed about this step, junction 0's anchor if that
/// junction is pinned after the step (pinned now and not breaking), else
/// u_x. A pure function of the state, so a kernel that keeps the sums of
/// an unchanged block (the GPU's `junction_cache`) gets the bits of one
/// that sums them again. Every pinned junction is within μs·f_N/k_j of
/// u_x, so about r too: the sums about r are of the size of the forces.
pub fn junction_reference<T: Real, C: Coordinate<T>>(
    c: &Consts<T>,
    p: &StepParams<T>,
    jb: &JunctionBlock<T, C>,
    state: [u32; 2],
    spring: &JunctionSpring<C, T>,
) -> C {
    if state[0] != PINNED {
        return jb.ux;
    }
    let f = hold(
        c.f32_probe,
        JUNCTIONS,
        -spring.stiffness * jb.ux.diff(spring.anchor),
    );
    if !p.preparing && f.abs() > jb.threshold {
        return jb.ux;
    }
    spring.anchor
}

/// What every junction of one interface block needs this step (twin of the
/// WGSL `JunctionBlock`): the block's u_x, the normal force per junction,
/// the break threshold μs·f_N and one slipping junction's force μd·f_N.
pub struct JunctionBlock<T, C> {
    pub ux: C,
    /// The reference r of the pinned sums (`junction_reference`; u_x
    /// until it is set).
    pub reference: C,
    pub f_n: T,
    pub threshold: T,
    pub slipping_force: T,
}

/// Twin of the WGSL `junction_block`.
pub fn junction_block<T: Real, C: Coordinate<T>>(c: &Consts<T>, u: [C; 2]) -> JunctionBlock<T, C> {
    let probe = c.f32_probe;
    let f_n = hold(
        probe,
        JUNCTIONS,
        foundation_normal(c, u[1].value()) / T::from_f64(c.junction_count as f64),
    );
    JunctionBlock {
        ux: u[0],
        reference: u[0],
        f_n,
        threshold: hold(probe, JUNCTIONS, break_threshold(c.mu_s, f_n)),
        slipping_force: hold(probe, JUNCTIONS, c.mu_d * f_n),
    }
}

/// What the junction lanes of a block hand back (twin of the WGSL
/// `LaneSum`, laid out as `GpuLaneSum`), over the junctions pinned after
/// the step: Σ k_j·(a_j − r) (`anchored`) and Σ k_j (`stiffness`) in the
/// precision's `ForceSum`, the count of slipping junctions, and the
/// largest |k_j·(a_j − r)| and k_j (`stretch_max`, `stiffness_max`: what a
/// kernel needs to know that no junction can break while u_x stays near r).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LaneSum<T, S> {
    pub anchored: S,
    pub stiffness: S,
    pub slipping: u32,
    pub stretch_max: T,
    pub stiffness_max: T,
}

impl<T: Real, S: ForceSum<T>> LaneSum<T, S> {
    /// Twin of the WGSL `lane_sum_merge`.
    #[inline]
    pub fn merge(self, other: LaneSum<T, S>) -> LaneSum<T, S> {
        LaneSum {
            anchored: self.anchored.merge(other.anchored),
            stiffness: self.stiffness.merge(other.stiffness),
            slipping: self.slipping + other.slipping,
            stretch_max: self.stretch_max.max(other.stretch_max),
            stiffness_max: self.stiffness_max.max(other.stiffness_max),
        }
    }

    /// Twin of the WGSL `lane_sum_add`: a junction pinned after the step,
    /// its stiffness k_j and term k_j·(a_j − r).
    #[inline(always)]
    pub fn add_pinned(mut self, stiffness: T, term: T) -> LaneSum<T, S> {
        self.anchored = self.anchored.add(term);
        self.stiffness = self.stiffness.add(stiffness);
        self.stretch_max = self.stretch_max.max(term.abs());
        self.stiffness_max = self.stiffness_max.max(stiffness);
        self
    }
}

/// A block's lane sums merged as a complete binary tree over the
/// `JUNCTION_LANES` lane slots: lanes (0, 1), (2, 3), ... first, then pairs
/// of those, six levels. Slots past `lanes.len()` (fewer junctions than
/// lanes) hold the zero sum, which a merge leaves as it is. A tree, not a
/// running sum in lane order: on a GPU the thread that merges a block's 64
/// lane sums then waits on a chain of six merges, not sixty-four, and the
/// merges of each level are independent. Twin of the WGSL
/// `lane_tree8` as the kernels use it (eight subtrees of eight lanes).
pub fn merge_lanes<T: Real, S: ForceSum<T>>(lanes: &[LaneSum<T, S>]) -> LaneSum<T, S> {
    fn subtree<T: Real, S: ForceSum<T>>(
        lanes: &[LaneSum<T, S>],
        first: usize,
        width: usize,
    ) -> LaneSum<T, S> {
        // A subtree wholly past the junctions merges zero sums into the
        // zero sum: its value without the merges (most of the tree where
        // Ns is well under the lane count). A level-by-level loop over a
        // 64-slot array was no faster (2026-12-03).
        if first >= lanes.len() {
            return LaneSum::default();
        }
        if width == 1 {
            return lanes[first];
        }
        let half = width / 2;
        subtree(lanes, first, half).merge(subtree(lanes, first + half, half))
    }
    debug_assert!(lanes.len() <= JUNCTION_LANES);
    subtree(lanes, 0, JUNCTION_LANES)
}

// The kernels merge eight subtrees of eight lanes (lane_tree8).
const _: () = assert!(JUNCTION_LANES == 64);

/// How far under the threshold a block's kept bound must stay (twin of
/// the WGSL `KEPT_MARGIN`): it covers the rounding of the bound and of
/// each junction's force, a few ulps.
pub const KEPT_MARGIN: f64 = 1.0 + 1.0 / 65536.0;

/// The sums of an interface block whose junctions are all pinned, kept
/// from the step that made them (twin of the WGSL `JunctionCache`). While
/// no junction changes, they are what the lanes would sum again; the
/// reference engine sums anew every step, the sweep engine keeps them.
/// Empty where `stiffness_max` is 0.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct KeptSums<T, S, C> {
    pub anchored: S,
    pub reference: C,
    pub stiffness: T,
    pub stretch_max: T,
    pub stiffness_max: T,
}

impl<T: Real, C: Coordinate<T>> KeptSums<T, C::Sum, C> {
    /// The sums to keep after a step of the block summed about
    /// `reference` (empty if a junction slips).
    pub fn of(reference: C, total: &LaneSum<T, C::Sum>) -> Self {
        if total.slipping != 0 {
            return Self::default();
        }
        KeptSums {
            anchored: total.anchored,
            reference,
            stiffness: total.stiffness.value(),
            stretch_max: total.stretch_max,
            stiffness_max: total.stiffness_max,
        }
    }

    /// Twin of the test in the WGSL `junction_block`: whether no junction
    /// of the block can change this step. Each junction's force is at most
    /// k_max·|u_x − r| + max|k_j·(a_j − r)|; under the threshold (and the
    /// margin), none breaks, and none slips.
    pub fn hold(&self, jb: &JunctionBlock<T, C>) -> bool {
        let reach = self.stiffness_max * jb.ux.diff(self.reference).abs() + self.stretch_max;
        jb.f_n > T::zero()
            && self.stiffness_max > T::zero()
            && reach * T::from_f64(KEPT_MARGIN) <= jb.threshold
    }

    /// The lane sums these stand for (as the WGSL `junction_friction`).
    pub fn lane_sum(&self) -> LaneSum<T, C::Sum> {
        LaneSum {
            anchored: self.anchored,
            stiffness: C::Sum::default().add(self.stiffness),
            ..LaneSum::default()
        }
    }
}

/// Twin of the WGSL `pinned_friction`: the pinned junctions' force on the
/// block, Σ k_j·(a_j − r) − (Σ k_j)·(u_x − r). Where r is u_x (junction 0
/// not pinned) the second term is 0 and this is Σ −k_j·(u_x − a_j) term
/// by term.
#[inline]
pub fn pinned_friction<T: Real, C: Coordinate<T>>(
    c: &Consts<T>,
    ux: C,
    reference: C,
    total: &LaneSum<T, C::Sum>,
) -> T {
    let moved = hold(
        c.f32_probe,
        JUNCTIONS,
        total.stiffness.value() * ux.diff(reference),
    );
    total.anchored.add(-moved).value()
}

/// Twin of the WGSL `junction_friction`: the friction on a block from its
/// pinned junctions' force `pinned`, the count of its slipping junctions,
/// one slipping junction's force `slipping_force` (μd·f_N), its other
/// force along x `other` and its velocity `vx` (v(n−½)). The slipping
/// junctions add n_slipping·μd·f_N under the scenario's at-rest rule
/// (`model::friction::junctions::SlipAtRest`): `hold` stops the block this
/// step when that bound allows, `sign` pushes against v.
#[inline]
pub fn junction_friction<T: Real>(
    c: &Consts<T>,
    slipping_force: T,
    pinned: T,
    slipping: u32,
    other: T,
    vx: T,
) -> T {
    if slipping == 0 {
        return pinned;
    }
    let capacity = T::from_f64(slipping as f64) * slipping_force;
    // The friction that brings the block to rest this step.
    let stop = -(other + pinned) - c.mass * vx / c.dt;
    pinned + slipping_friction(c.law[0] != T::zero(), capacity, stop, vx)
}

/// Twin of the WGSL `junction_lane`: advances junctions `lane`,
/// `lane + JUNCTION_LANES`, ... of block `ix` by one step and returns
/// the sum of the pinned ones' forces on the block along x and the count
/// of the slipping ones.
///
/// The sum is the precision's `ForceSum`: compensated in mixed f32. A
/// block's Ns junction forces are alike in size, and an f32 running sum of
/// them rounded the friction coherently across the interface; it moved the
/// default scene's first full event 0.18 ms late against f64 in 21 of 32
/// perturbed runs (results/precision_ensembles.md, the third cause).
pub fn junction_lane<T: Real, C: Coordinate<T>>(
    c: &Consts<T>,
    p: &StepParams<T>,
    ix: usize,
    lane: usize,
    jb: &JunctionBlock<T, C>,
    slots: JunctionSlots<'_, T, C>,
) -> LaneSum<T, C::Sum> {
    let mut total = LaneSum::<T, C::Sum>::default();
    for j in (lane..c.junction_count).step_by(JUNCTION_LANES) {
        let state = &mut slots.state[j];
        let spring = &mut slots.spring[j];
        match junction(c, p, ix, j, jb, spring, state) {
            Some(_) => {
                let term = anchored_term(c, jb, spring);
                total = total.add_pinned(spring.stiffness, term);
            }
            None => total.slipping += 1,
        }
    }
    total
}

/// Twin of the WGSL `anchored_term`: a pinned junction's k_j·(a_j − r).
#[inline(always)]
pub fn anchored_term<T: Real, C: Coordinate<T>>(
    c: &Consts<T>,
    jb: &JunctionBlock<T, C>,
    spring: &JunctionSpring<C, T>,
) -> T {
    hold(
        c.f32_probe,
        JUNCTIONS,
        spring.stiffness * spring.anchor.diff(jb.reference),
    )
}

/// One junction `j` of block `ix` advanced by one step; returns its force
/// on the block along x if it is pinned after the step, None if it slips
/// (the block's slipping junctions act together, `junction_friction`).
/// Every junction is independent of the others (its
/// slip time is drawn from its own key), so the sweep engine calls this in
/// any order and gets the same bits.
#[inline(always)]
pub fn junction<T: Real, C: Coordinate<T>>(
    c: &Consts<T>,
    p: &StepParams<T>,
    ix: usize,
    j: usize,
    jb: &JunctionBlock<T, C>,
    spring: &mut JunctionSpring<C, T>,
    state: &mut [u32; 2],
) -> Option<T> {
    let (f_n, threshold) = (jb.f_n, jb.threshold);
    if state[0] != PINNED {
        state[0] = state[0].saturating_sub(1);
        if state[0] == 0 && f_n > T::zero() {
            *spring = JunctionSpring {
                anchor: jb.ux,
                stiffness: hold(c.f32_probe, JUNCTIONS, c.junction_stiffness(f_n)),
            };
            state[0] = PINNED;
        }
    }
    if state[0] != PINNED {
        return None;
    }
    if p.preparing {
        // While the normal load is applied, attachment is continuous.
        spring.stiffness = hold(c.f32_probe, JUNCTIONS, c.junction_stiffness(f_n));
    }
    let f = hold(
        c.f32_probe,
        JUNCTIONS,
        -spring.stiffness * jb.ux.diff(spring.anchor),
    );
    if !p.preparing && f.abs() > threshold {
        let count = state[1].wrapping_add(1);
        state[1] = count;
        let n = if c.f32_probe & DRAWS != 0 {
            slip_steps(
                c.seed,
                ix as u32,
                j as u32,
                count,
                c.slip_mean_steps.as_f64() as f32,
                c.slip_std_steps.as_f64() as f32,
            )
        } else {
            slip_steps(
                c.seed,
                ix as u32,
                j as u32,
                count,
                c.slip_mean_steps,
                c.slip_std_steps,
            )
        };
        // PINNED − 1 at most: a countdown never reads as pinned.
        state[0] = n.min(PINNED - 1);
        return None;
    }
    Some(f)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engines::step_params::step_params;
    use crate::model::scenario::{Scenario, DEFAULT_SCENARIO};

    type Springs = Vec<JunctionSpring<f64, f64>>;

    /// `merge_lanes` as its definition: the complete tree over all
    /// `JUNCTION_LANES` slots, every merge made, zero sums past the lanes.
    fn full_tree<T: Real, S: ForceSum<T>>(lanes: &[LaneSum<T, S>]) -> LaneSum<T, S> {
        fn subtree<T: Real, S: ForceSum<T>>(
            lanes: &[LaneSum<T, S>],
            first: usize,
            width: usize,
        ) -> LaneSum<T, S> {
            if width == 1 {
                return lanes.get(first).copied().unwrap_or_default();
            }
            let half = width / 2;
            subtree(lanes, first, half).merge(subtree(lanes, first + half, half))
        }
        subtree(lanes, 0, JUNCTION_LANES)
    }

    /// Lane sums with the values where skipping a merge would show: −0
    /// (which a merge with +0 turns to +0), NaN, infinities, and terms
    /// whose compensated sums carry an error.
    fn awkward_lanes<S: ForceSum<f32>>(
        n: usize,
        seed: u64,
        sum: impl Fn(f32, f32) -> S,
    ) -> Vec<LaneSum<f32, S>> {
        struct Draws(u64);
        impl Draws {
            fn next(&mut self) -> u64 {
                self.0 = self.0.wrapping_mul(6364136223846793005);
                self.0 = self.0.wrapping_add(1442695040888963407);
                self.0 >> 33
            }
            fn value(&mut self) -> f32 {
                let special = [-0.0f32, 0.0, f32::NAN, f32::INFINITY, 1.0e-30, -3.0e7];
                let r = self.next();
                if r.is_multiple_of(4) {
                    special[(r / 4) as usize % special.len()]
                } else {
                    (r as f32 / 2.0f32.powi(31) - 0.5) * 1.0e3
                }
            }
        }
        let mut d = Draws(seed);
        (0..n)
            .map(|_| LaneSum {
                anchored: sum(d.value(), d.value() * 1.0e-8),
                stiffness: sum(d.value().abs(), 0.0),
                slipping: (d.next() % 3) as u32,
                stretch_max: d.value().abs(),
                stiffness_max: d.value().abs(),
            })
            .collect()
    }

    fn same_bits<S: ForceSum<f32>>(a: &LaneSum<f32, S>, b: &LaneSum<f32, S>) -> bool {
        format!("{a:?}") == format!("{b:?}")
            && a.stretch_max.to_bits() == b.stretch_max.to_bits()
            && a.stiffness_max.to_bits() == b.stiffness_max.to_bits()
    }

    /// The tree that skips the subtrees past the lanes gives the full
    /// tree's bits for every lane count, −0, NaN and compensated
    /// error terms included; a tree that skips a merge with a zero sum
    /// (the control) is caught.
    #[test]
    fn merge_lanes_gives_the_full_trees_bits_for_every_lane_count() {
        use crate::model::real::CompensatedSum;
        let compensated = |sum: f32, err: f32| CompensatedSum { sum, err };
        for seed in 0..40u64 {
            for n in 0..=JUNCTION_LANES {
                let plain = awkward_lanes(n, seed, |sum: f32, _| sum);
                assert!(
                    same_bits(&merge_lanes(&plain), &full_tree(&plain)),
                    "f32, {n} lanes"
                );
                let comp = awkward_lanes(n, seed, compensated);
                assert!(
                    same_bits(&merge_lanes(&comp), &full_tree(&comp)),
                    "compensated, {n} lanes"
                );
            }
        }
        // The control: one lane of −0 merged with nothing keeps its sign,
        // where the full tree's merges with the zero sum make it +0.
        let lone = [LaneSum::<f32, f32> {
            anchored: -0.0,
            ..LaneSum::default()
        }];
        assert!(!same_bits(&lone[0], &full_tree(&lone)));
        assert!(same_bits(&merge_lanes(&lone), &full_tree(&lone)));
    }

    /// The Table S1 model and one interface block's junctions, all pinned
    /// at 0 with k_j = 1e5 N/m.
    fn pinned_block() -> (crate::Model, Consts<f64>, Springs, Vec<[u32; 2]>) {
        let s = Scenario::parse(DEFAULT_SCENARIO, "test", &[]).unwrap();
        let m = crate::Model::from_scenario(&s, false).unwrap();
        let c = Consts::<f64>::new(&m);
        let spring = JunctionSpring {
            anchor: 0.0,
            stiffness: 1.0e5,
        };
        let ns = c.junction_count;
        (m, c, vec![spring; ns], vec![[PINNED, 0u32]; ns])
    }

    /// Junctions that break just before step 2³² re-pin after their drawn
    /// slip time: the countdown does not see the global step, which used to
    /// be cast to u32 (re-pin steps past 2³² saturated or wrapped).
    #[test]
    fn junctions_broken_near_step_2_pow_32_re_pin_after_their_slip_time() {
        let (_, c, mut spring, mut state) = pinned_block();
        let ns = c.junction_count;
        // Compressed and stretched far past μs·f_N: every junction breaks.
        let u = [1.0e-3, -1.0e-6];
        let start = (1u64 << 32) - 3;
        let mut pinned_at = vec![None; ns];
        for step in start..start + 4 * c.slip_mean_steps as u64 {
            let p = step_params(&c, step);
            assert!(!p.preparing);
            // After the first step the block sits at the anchors' position,
            // so re-pinned junctions stay pinned.
            let ux = if step == start { u[0] } else { 0.0 };
            let slots = JunctionSlots {
                spring: &mut spring,
                state: &mut state,
            };
            junctions(&c, &p, 0, [ux, u[1]], [0.0; 2], 0.0, slots);
            for (j, s) in state.iter().enumerate() {
                if s[0] == PINNED && pinned_at[j].is_none() {
                    pinned_at[j] = Some(step);
                }
            }
        }
        for (j, at) in pinned_at.iter().enumerate() {
            let n = slip_steps(c.seed, 0, j as u32, 1, c.slip_mean_steps, c.slip_std_steps);
            assert_eq!(*at, Some(start + n as u64), "junction {j}");
            assert_eq!(state[j][1], 1, "junction {j} broke once");
        }
    }

    /// A block lifted off the track while its junctions slip: none re-pins
    /// while it is open (and none with zero stiffness); pressed back, all
    /// re-pin at once with the stiffness of the new normal force and carry
    /// force again.
    #[test]
    fn junctions_wait_while_the_block_is_lifted_and_re_pin_when_pressed_back() {
        let (m, c, mut spring, mut state) = pinned_block();
        let ns = c.junction_count;
        let step0 = m.prep_steps + 10;
        let pressed = -1.0e-6;
        let run = |step: u64,
                   ux: f64,
                   uz: f64,
                   spring: &mut [JunctionSpring<f64, f64>],
                   state: &mut [[u32; 2]]| {
            let slots = JunctionSlots { spring, state };
            junctions(
                &c,
                &step_params(&c, step),
                0,
                [ux, uz],
                [0.0; 2],
                0.0,
                slots,
            )
        };
        // Break them all, then lift the block for longer than any slip.
        run(step0, 1.0e-3, pressed, &mut spring, &mut state);
        assert!(state.iter().all(|s| s[0] != PINNED));
        let lifted = 1.0e-6;
        let wait = 4 * c.slip_mean_steps as u64;
        for step in step0 + 1..step0 + wait {
            let (friction, normal) = run(step, 0.0, lifted, &mut spring, &mut state);
            assert_eq!((friction, normal), (0.0, 0.0));
            assert!(state.iter().all(|s| s[0] != PINNED), "none re-pins lifted");
        }
        assert!(state.iter().all(|s| s[0] == 0), "all waiting");
        // Pressed back: every junction re-pins with k_j = sqrt(c f_N) > 0.
        let back = step0 + wait;
        run(back, 0.0, pressed, &mut spring, &mut state);
        let f_n = c.k_foundation * 1.0e-6 / ns as f64;
        let k = c.junction_stiffness(f_n);
        assert!(k > 0.0);
        assert!(state.iter().all(|s| s[0] == PINNED));
        assert!(spring.iter().all(|s| s.stiffness == k && s.anchor == 0.0));
        // And they hold: a small displacement meets −Ns·k_j·du.
        let (friction, _) = run(back + 1, 1.0e-9, pressed, &mut spring, &mut state);
        assert!((friction + ns as f64 * k * 1.0e-9).abs() < 1e-12 * ns as f64 * k);
    }
}
