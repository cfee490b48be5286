//! CPU twin of the kernels' call of `block_law_friction` (the generated
//! `friction_law` shader): what an engine hands a per-block friction law
//! for one interface block, and what it gets back. The laws themselves
//! (`crate::model::friction`) know nothing of the engines.

use super::junctions::foundation_normal;
use crate::engines::step_params::{Consts, StepParams};
use crate::model::friction::{block_law_friction, BlockContact, FrictionLaw};
use crate::model::real::{Coordinate, Real};

/// (friction along x, normal force) of one interface block at `u`, `v`
/// (v(n−½)) under the other forces along x `other_force`, updating its
/// `slide` pair and its law state (`block_state_words` coordinates).
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn block_law<T: Real, C: Coordinate<T>>(
    c: &Consts<T>,
    p: &StepParams<T>,
    law: FrictionLaw,
    uz: C,
    vx: T,
    other_force: T,
    slide: &mut [i32; 2],
    state: &mut [C],
) -> [T; 2] {
    let normal = foundation_normal(c, uz.value());
    let contact = BlockContact {
        mass: c.mass,
        dt: c.dt,
        normal,
        velocity: vx,
        other_force,
        preparing: p.preparing,
    };
    [
        block_law_friction(law, &c.law, &contact, slide, state),
        normal,
    ]
}
