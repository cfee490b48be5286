//! The exact state of an engine between two steps, in a form every engine
//! reads and writes: what a checkpoint stores. Coordinates are kept as
//! (hi, lo) parts (`Coordinate::parts`) and forces and velocities as f64,
//! so a state saved and loaded by engines of the same precision comes back
//! bit for bit, and one loaded by another precision is rounded once.

use super::{EngineError, FrictionState};
use crate::model::junction::JunctionSpring;
use crate::model::real::{Coordinate, Real};
use crate::model::Model;

#[derive(Debug, Clone, PartialEq)]
pub struct EngineState {
    /// The saving engine's precision, as `real::precision_name` writes it.
    pub precision: String,
    /// Global step count of the state.
    pub step: u64,
    /// Where the side spring's far end started (coordinate parts).
    pub drive_origin: [f64; 2],
    /// Per block: u_x and u_z as coordinate parts.
    pub disp: Vec<[[f64; 2]; 2]>,
    /// Per block: the leapfrog's v(n − ½).
    pub vel: Vec<[f64; 2]>,
    /// Per block: the force at u(n) from everything but friction.
    pub force: Vec<[f64; 2]>,
    /// Per interface block: (friction along x, normal force) at u(n).
    pub contact: Vec<[f64; 2]>,
    /// Per junction (ix·Ns + j): anchor parts.
    pub anchor: Vec<[f64; 2]>,
    pub junction_stiffness: Vec<f64>,
    /// Per junction: (slip steps left or PINNED, rupture count).
    pub junction_state: Vec<[u32; 2]>,
    /// Per interface block: (sliding direction, stick → slip count).
    pub slide: Vec<[i32; 2]>,
    /// The friction law's state, `block_state_words` per interface block,
    /// as coordinate parts.
    pub law_state: Vec<[f64; 2]>,
}

/// An engine's arrays, borrowed in its own number types: the input of
/// [`EngineState::capture`].
pub struct StateArrays<'a, T, C> {
    pub step: u64,
    pub drive_origin: C,
    pub disp: &'a [[C; 2]],
    pub vel: &'a [[T; 2]],
    pub force: &'a [[T; 2]],
    pub contact: &'a [[T; 2]],
    pub friction: &'a FrictionState<T, C>,
}

fn reals<T: Real>(v: &[[T; 2]]) -> Vec<[f64; 2]> {
    v.iter().map(|x| x.map(T::as_f64)).collect()
}

impl EngineState {
    pub fn capture<T: Real, C: Coordinate<T>>(a: StateArrays<'_, T, C>) -> EngineState {
        EngineState {
            precision: crate::model::real::precision_name::<T, C>(),
            step: a.step,
            drive_origin: a.drive_origin.parts(),
            disp: a.disp.iter().map(|u| u.map(C::parts)).collect(),
            vel: reals(a.vel),
            force: reals(a.force),
            contact: reals(a.contact),
            anchor: a
                .friction
                .junction_spring
                .iter()
                .map(|s| s.anchor.parts())
                .collect(),
            junction_stiffness: a
                .friction
                .junction_spring
                .iter()
                .map(|s| s.stiffness.as_f64())
                .collect(),
            junction_state: a.friction.junction_state.clone(),
            slide: a.friction.slide.clone(),
            law_state: a.friction.law_state.iter().map(|v| v.parts()).collect(),
        }
    }

    /// Refuses a state whose array sizes do not fit `model`'s lattice.
    pub fn check_fits(&self, model: &Model) -> Result<(), EngineError> {
        let (n, nx, nj) = (model.n_blocks(), model.nx, model.n_junctions());
        let sizes = [
            ("block displacements", self.disp.len(), n),
            ("block velocities", self.vel.len(), n),
            ("block forces", self.force.len(), n),
            ("interface contact forces", self.contact.len(), nx),
            ("junction anchors", self.anchor.len(), nj),
            ("junction stiffnesses", self.junction_stiffness.len(), nj),
            ("junction states", self.junction_state.len(), nj),
            ("interface slide states", self.slide.len(), nx),
            (
                "interface law states",
                self.law_state.len(),
                nx * model.law.declaration().block_state_words,
            ),
        ];
        for (what, got, want) in sizes {
            if got != want {
                return Err(EngineError::State(format!(
                    "the saved state has {got} {what}, the model needs {want} \
                     ({} × {} blocks, {} junctions): it is of another lattice",
                    model.nx, model.nz, nj
                )));
            }
        }
        Ok(())
    }

    /// Displacements in an engine's coordinates.
    pub fn disp_as<T: Real, C: Coordinate<T>>(&self) -> Vec<[C; 2]> {
        self.disp.iter().map(|u| u.map(C::from_parts)).collect()
    }

    /// Velocities in an engine's reals.
    pub fn vel_as<T: Real>(&self) -> Vec<[T; 2]> {
        as_reals(&self.vel)
    }

    pub fn force_as<T: Real>(&self) -> Vec<[T; 2]> {
        as_reals(&self.force)
    }

    pub fn contact_as<T: Real>(&self) -> Vec<[T; 2]> {
        as_reals(&self.contact)
    }

    pub fn junction_springs_as<T: Real, C: Coordinate<T>>(&self) -> Vec<JunctionSpring<C, T>> {
        self.anchor
            .iter()
            .zip(&self.junction_stiffness)
            .map(|(a, k)| JunctionSpring {
                anchor: C::from_parts(*a),
                stiffness: T::from_f64(*k),
            })
            .collect()
    }

    pub fn drive_origin_as<T: Real, C: Coordinate<T>>(&self) -> C {
        C::from_parts(self.drive_origin)
    }

    /// The side spring's far-end origin as one number (m).
    pub fn drive_origin_value(&self) -> f64 {
        self.drive_origin[0] + self.drive_origin[1]
    }
}

fn as_reals<T: Real>(v: &[[f64; 2]]) -> Vec<[T; 2]> {
    v.iter().map(|x| x.map(T::from_f64)).collect()
}
