//! What every band of one step reads: the run's fixed data (constants,
//! bonds, flags), the step's loads, the start state; and the interface
//! arrays the band holding row 0 updates.

use super::rows::{ForwardBonds, RowView};
use crate::engines::cpu::JunctionSpring;
use crate::engines::step_params::{drive_target, step_params, Consts, StepParams};
use crate::model::real::{Coordinate, Real};
use crate::model::scenario::FrictionLaw;

/// How rows reach the next state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Advance {
    /// One leapfrog step from the start state's forces and friction.
    Leapfrog,
    /// Unchanged: the forces of the start state itself.
    Copy,
}

/// What a run does not change: constants, bonds, block flags.
pub struct Fixed<T: Real> {
    pub consts: Consts<T>,
    pub bonds: ForwardBonds<T>,
    pub flags: Vec<u32>,
    pub law: FrictionLaw,
    /// Speed above which a block counts as blown up.
    pub speed_limit: T,
}

/// A whole state, read-only: kinematics, bulk forces, (friction, normal)
/// per interface block.
#[derive(Clone, Copy)]
pub struct StateView<'a, T, C> {
    pub kin: RowView<'a, T, C>,
    pub force: [&'a [T]; 2],
    pub contact: &'a [[T; 2]],
}

/// What every band reads during one step.
pub struct Shared<'a, T: Real, C: Coordinate<T>> {
    pub c: &'a Consts<T>,
    pub bonds: &'a ForwardBonds<T>,
    pub flags: &'a [u32],
    pub law: FrictionLaw,
    /// Loads of the step being taken (the leapfrog's).
    pub before: StepParams<T>,
    /// Loads at the new state (the forces').
    pub after: StepParams<T>,
    /// Where the side spring's far end is at the new state.
    pub drive_target: C,
    pub speed_limit: T,
    /// The start state.
    pub now: RowView<'a, T, C>,
    pub now_force: [&'a [T]; 2],
    pub now_contact: &'a [[T; 2]],
    pub advance: Advance,
    /// False: only advance the rows (forces follow in a second pass, at the
    /// step where driving starts).
    pub forces: bool,
}

impl<'a, T: Real, C: Coordinate<T>> Shared<'a, T, C> {
    /// The step from global step `step` (or, with `Advance::Copy`, the
    /// forces at it), the side spring's far end at `drive_origin` + V·t.
    pub fn new(
        fixed: &'a Fixed<T>,
        drive_origin: C,
        step: u64,
        now: StateView<'a, T, C>,
        advance: Advance,
        forces: bool,
    ) -> Self {
        let c = &fixed.consts;
        let after_step = match advance {
            Advance::Leapfrog => step + 1,
            Advance::Copy => step,
        };
        let after = step_params(c, after_step);
        Shared {
            c,
            bonds: &fixed.bonds,
            flags: &fixed.flags,
            law: fixed.law,
            before: step_params(c, step),
            after,
            drive_target: drive_target(c, drive_origin, after_step),
            speed_limit: fixed.speed_limit,
            now: now.kin,
            now_force: now.force,
            now_contact: now.contact,
            advance,
            forces,
        }
    }
}

/// The junction, slide and law-state arrays the band holding row 0
/// updates in place (they are not double-buffered: only that band touches
/// them).
pub type InterfaceArrays<'a, T, C> = (
    &'a mut [JunctionSpring<C, T>],
    &'a mut [[u32; 2]],
    &'a mut [[i32; 2]],
    &'a mut [C],
);

/// The interface arrays, owned by the band holding row 0.
pub struct Interface<'a, T, C> {
    pub contact: &'a mut [[T; 2]],
    pub spring: &'a mut [JunctionSpring<C, T>],
    pub state: &'a mut [[u32; 2]],
    pub slide: &'a mut [[i32; 2]],
    pub law_state: &'a mut [C],
}

impl<'a, T, C> Interface<'a, T, C> {
    /// The next state's `contact` with the arrays updated in place.
    pub fn new(contact: &'a mut [[T; 2]], arrays: InterfaceArrays<'a, T, C>) -> Self {
        let (spring, state, slide, law_state) = arrays;
        Interface {
            contact,
            spring,
            state,
            slide,
            law_state,
        }
    }
}
