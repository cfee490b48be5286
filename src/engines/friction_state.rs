//! What the friction laws keep between steps, in an engine's number types:
//! each junction's spring (anchor, stiffness) and state (slip steps left or
//! pinned, rupture count), and each interface block's Amontons–Coulomb
//! sliding state (direction, stick → slip count). One struct for every
//! engine, so that a snapshot, a saved state and a loaded one name these
//! arrays once, and a law that keeps more state adds it here.

use super::{EngineState, Snapshot};
use crate::model::junction::{JunctionSpring, PINNED};
use crate::model::real::{Coordinate, Real};
use crate::model::Model;

#[derive(Debug, Clone, PartialEq)]
pub struct FrictionState<T, C> {
    /// Per junction (ix·Ns + j): anchor and stiffness.
    pub junction_spring: Vec<JunctionSpring<C, T>>,
    /// Per junction: (slip steps left or `PINNED`, rupture count).
    pub junction_state: Vec<[u32; 2]>,
    /// Per interface block: (sliding direction, stick → slip count).
    pub slide: Vec<[i32; 2]>,
    /// The law's own state, `block_state_words` per interface block,
    /// block-major (`model::friction::Law`): θ of rate-and-state. Kept as
    /// coordinates, as displacements are: a state that grows by tiny steps
    /// (θ aging by dt at rest) keeps them in mixed precision.
    pub law_state: Vec<C>,
}

impl<T: Real, C: Coordinate<T>> FrictionState<T, C> {
    /// At t = 0: every junction pinned where its block starts
    /// (`lattice::initial_anchors`), stiffness set by the normal-load
    /// phase; every block stuck.
    pub fn initial(model: &Model) -> Self {
        FrictionState {
            junction_spring: crate::model::lattice::initial_anchors(model)
                .into_iter()
                .map(|a| JunctionSpring {
                    anchor: C::from_f64(a),
                    stiffness: T::zero(),
                })
                .collect(),
            junction_state: vec![[PINNED, 0]; model.n_junctions()],
            slide: vec![[0; 2]; model.nx],
            law_state: initial_law_state(model),
        }
    }

    /// The arrays of a saved state (checked to fit by the caller).
    pub fn from_state(state: &EngineState) -> Self {
        FrictionState {
            junction_spring: state.junction_springs_as(),
            junction_state: state.junction_state.clone(),
            slide: state.slide.clone(),
            law_state: state.law_state.iter().map(|&v| C::from_parts(v)).collect(),
        }
    }

    /// The junction arrays of a snapshot.
    pub fn load_junctions(&mut self, snap: &Snapshot) {
        let anchors = snap.anchor.iter().zip(&snap.junction_stiffness);
        for (s, (a, k)) in self.junction_spring.iter_mut().zip(anchors) {
            *s = JunctionSpring {
                anchor: C::from_f64(*a),
                stiffness: T::from_f64(*k),
            };
        }
        let states = snap.slip_steps_left.iter().zip(&snap.ruptures);
        for (s, (left, count)) in self.junction_state.iter_mut().zip(states) {
            *s = [*left, *count];
        }
    }

    /// The per-block laws' state of a snapshot: sliding state and law
    /// state.
    pub fn load_slide(&mut self, snap: &Snapshot) {
        let slides = snap.slide_dir.iter().zip(&snap.slips);
        for (s, (d, n)) in self.slide.iter_mut().zip(slides) {
            *s = [*d, *n as i32];
        }
        for (s, v) in self.law_state.iter_mut().zip(&snap.law_state) {
            *s = C::from_f64(*v);
        }
    }

    /// Moves each junction's anchor to `anchors` (ix·Ns + j).
    pub fn set_anchors(&mut self, anchors: impl IntoIterator<Item = f64>) {
        for (spring, a) in self.junction_spring.iter_mut().zip(anchors) {
            spring.anchor = C::from_f64(a);
        }
    }
}

/// The law state of every interface block at t = 0: the law's initial
/// values repeated, block-major.
pub fn initial_law_state<T: Real, C: Coordinate<T>>(model: &Model) -> Vec<C> {
    let one = model.law_initial_state();
    (0..model.nx)
        .flat_map(|_| one.iter().map(|&v| C::from_f64(v)))
        .collect()
}
