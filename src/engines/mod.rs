//! The engines layer: what every engine offers, the state it reports and
//! the stepping driver shared by all of them (phase change at the start of
//! driving), and the engines themselves: the CPU reference (`cpu`) and its
//! fast twin (`cpu::fast`), the WGSL engine (`gpu`), the quasi-static
//! solver (`quasistatic`), the single-block model (`single_block`), and
//! the choice among them (`backend`). Engines import the model layer and
//! this module, never one another, except that the GPU's shader constants
//! and the fast CPU engine mirror the CPU reference twin by twin.

pub mod backend;
pub mod backend_choice;
pub mod cpu;
mod friction_state;
pub mod gpu;
pub mod kernels;
pub mod memory;
pub mod precision_probe;
pub mod quasistatic;
pub mod single_block;
pub mod step_params;
pub mod step_timing;
pub mod trigger;

mod sample;
mod state;

pub use friction_state::FrictionState;
pub use sample::{
    record_sample, BulkField, Due, InterfaceRow, PlannedAndComputed, Sample, SamplePlan, SampleSums,
};
pub use state::{EngineState, StateArrays};

use crate::model::real::{Coordinate, Real};
use crate::model::Model;

/// Full engine state, converted to f64 for analysis and output.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Snapshot {
    /// Global step count (0 at the start of the normal-load phase).
    pub step: u64,
    /// Time since driving started (s); negative in the normal-load phase.
    pub time: f64,
    /// Displacement u(n) of each block (m).
    pub disp: Vec<[f64; 2]>,
    /// Velocity at the same instant, v(n) = v(n−½) + (dt/2)·a(n), with the
    /// constraints applied (m/s).
    pub vel: Vec<[f64; 2]>,
    /// The leapfrog's own velocity v(n−½), over the step that led here: the
    /// engine state, and what the energy ledger integrates with (m/s).
    pub vel_half: Vec<[f64; 2]>,
    /// Force on each block from everything but friction at u(n) (N).
    pub force: Vec<[f64; 2]>,
    /// Friction force along x on each interface block (N).
    pub friction: Vec<f64>,
    /// Normal force p on each interface block (N).
    pub normal: Vec<f64>,
    /// Junction arrays, index `ix * Ns + j`.
    pub anchor: Vec<f64>,
    pub junction_stiffness: Vec<f64>,
    /// Steps each junction has left to slip, or `PINNED`.
    pub slip_steps_left: Vec<u32>,
    pub ruptures: Vec<u32>,
    /// Amontons–Coulomb sliding direction per interface block.
    pub slide_dir: Vec<i32>,
    /// Amontons–Coulomb stick → slip transitions per interface block.
    pub slips: Vec<u32>,
    /// The friction law's state per interface block
    /// (`block_state_words` each, block-major): θ (s) of rate-and-state.
    pub law_state: Vec<f64>,
}

impl Snapshot {
    /// Converts engine buffers (the layout shared by the CPU twins and the
    /// WGSL kernels) to a snapshot.
    pub fn from_buffers<T: Real, C: Coordinate<T>>(
        model: &Model,
        step: u64,
        disp: &[[C; 2]],
        vel: &[[T; 2]],
        force: &[[T; 2]],
        contact: &[[T; 2]],
        friction_state: &FrictionState<T, C>,
    ) -> Snapshot {
        let FrictionState {
            junction_spring,
            junction_state,
            slide,
            law_state,
        } = friction_state;
        let f2 = |v: &[[T; 2]]| v.iter().map(|x| x.map(|y| y.as_f64())).collect::<Vec<_>>();
        let col = |v: &[[T; 2]], k: usize| v.iter().map(|x| x[k].as_f64()).collect::<Vec<_>>();
        let vel_half = f2(vel);
        let force = f2(force);
        let friction = col(contact, 0);
        Snapshot {
            step,
            time: model.time_of_step(step),
            disp: disp.iter().map(|u| u.map(C::as_f64)).collect(),
            vel: synchronised_velocity(model, step, &vel_half, &force, &friction),
            vel_half,
            force,
            friction,
            normal: col(contact, 1),
            anchor: junction_spring.iter().map(|s| s.anchor.as_f64()).collect(),
            junction_stiffness: junction_spring
                .iter()
                .map(|s| s.stiffness.as_f64())
                .collect(),
            slip_steps_left: junction_state.iter().map(|s| s[0]).collect(),
            ruptures: junction_state.iter().map(|s| s[1]).collect(),
            slide_dir: slide.iter().map(|s| s[0]).collect(),
            slips: slide.iter().map(|s| s[1] as u32).collect(),
            law_state: law_state.iter().map(|v| v.as_f64()).collect(),
        }
    }

    /// Fraction of pinned junctions on each interface block.
    pub fn pinned_fraction(&self, nx: usize) -> Vec<f64> {
        if self.slip_steps_left.is_empty() {
            return self
                .slide_dir
                .iter()
                .map(|&d| (d == 0) as u8 as f64)
                .collect();
        }
        let ns = self.slip_steps_left.len() / nx;
        self.slip_steps_left
            .chunks(ns)
            .map(|c| {
                c.iter()
                    .filter(|&&r| r == crate::model::junction::PINNED)
                    .count() as f64
                    / ns as f64
            })
            .collect()
    }

    pub fn total_friction(&self) -> f64 {
        self.friction.iter().sum()
    }

    /// Junction ruptures, or Amontons–Coulomb stick → slip transitions.
    pub fn total_ruptures(&self) -> u64 {
        self.ruptures
            .iter()
            .chain(&self.slips)
            .map(|&r| r as u64)
            .sum()
    }

    /// Kinetic energy at the snapshot's instant (from `vel`).
    pub fn kinetic_energy(&self, mass: f64) -> f64 {
        kinetic(&self.vel, mass)
    }

    /// Kinetic energy of the half-step velocities (the energy ledger's).
    pub fn kinetic_energy_half(&self, mass: f64) -> f64 {
        kinetic(&self.vel_half, mass)
    }
}

fn kinetic(vel: &[[f64; 2]], mass: f64) -> f64 {
    0.5 * mass * vel.iter().map(|v| v[0] * v[0] + v[1] * v[1]).sum::<f64>()
}

/// v(n) = v(n−½) + (dt/2)·(F(n) + friction(n))/m, the velocity at the
/// instant of u(n), with fixed components 0 and the prescribed top row at
/// its prescribed velocity.
pub fn synchronised_velocity(
    model: &Model,
    step: u64,
    vel_half: &[[f64; 2]],
    force: &[[f64; 2]],
    friction: &[f64],
) -> Vec<[f64; 2]> {
    use crate::model::lattice::{block_flags, FLAG_FIX_X, FLAG_FIX_Z, FLAG_PRESCRIBED_X};
    let half_dt_over_m = 0.5 * model.dt / model.mass;
    let top_velocity = match model.driver {
        crate::model::Driver::TopVelocity { velocity } if step >= model.prep_steps => velocity,
        _ => 0.0,
    };
    block_flags(model)
        .iter()
        .enumerate()
        .map(|(i, &flags)| {
            let fr = friction.get(i).copied().unwrap_or(0.0);
            let mut v = [
                vel_half[i][0] + half_dt_over_m * (force[i][0] + fr),
                vel_half[i][1] + half_dt_over_m * force[i][1],
            ];
            if flags & FLAG_FIX_X != 0 {
                v[0] = 0.0;
            }
            if flags & FLAG_FIX_Z != 0 {
                v[1] = 0.0;
            }
            if flags & FLAG_PRESCRIBED_X != 0 {
                v[0] = top_velocity;
            }
            v
        })
        .collect()
}

#[derive(Debug, thiserror::Error)]
pub enum EngineError {
    #[error(
        "the run blew up at step {step} (t = {time:.6e} s): block (ix = {ix}, iz = {iz}) has \
         u = ({ux:.3e}, {uz:.3e}) m, v = ({vx:.3e}, {vz:.3e}) m/s (non-finite or faster than \
         the P-wave speed); reduce time.dt or check the loads"
    )]
    BlowUp {
        step: u64,
        time: f64,
        ix: usize,
        iz: usize,
        ux: f64,
        uz: f64,
        vx: f64,
        vz: f64,
    },
    #[error("GPU: {0}")]
    Gpu(String),
    #[error("saved state: {0}")]
    State(String),
}

/// A simulation engine over one model.
pub trait Engine: Send {
    fn model(&self) -> &Model;
    /// Steps done so far.
    fn steps_done(&self) -> u64;
    /// Advances `n` steps. Each step ends with the forces, friction and
    /// junction states of its new displacements, so a snapshot describes
    /// one instant; when the step count reaches the end of the normal-load
    /// phase the engine fixes the driver origin and applies the trigger's
    /// junction forces before those forces.
    fn advance(&mut self, n: u64) -> Result<(), EngineError>;
    /// Reads the whole state back.
    fn snapshot(&mut self) -> Result<Snapshot, EngineError>;
    /// Backend, adapter and precision, for logs and metadata.
    fn describe(&self) -> String;
    /// Moves the engine to step `step` with displacements `disp` and
    /// velocities `vel` (the leapfrog's v(n−½)), junction and slide arrays
    /// unchanged, and recomputes the forces of that state: the end of a
    /// quasi-static jump. Only in the driving phase.
    fn set_kinematics(
        &mut self,
        step: u64,
        disp: &[[f64; 2]],
        vel: &[[f64; 2]],
    ) -> Result<(), EngineError>;
    /// Replaces the junction arrays (anchors, stiffnesses, slip countdowns,
    /// rupture counts) by those of `snap`: the junction events of a
    /// quasi-static jump. Forces are recomputed by the next
    /// `set_kinematics` or step.
    fn set_junctions(&mut self, snap: &Snapshot) -> Result<(), EngineError>;
    /// The whole state, exactly (a checkpoint's content): the engine can be
    /// rebuilt from it with [`Engine::load_state`] and steps on with the
    /// same bits.
    fn save_state(&mut self) -> Result<EngineState, EngineError>;
    /// Replaces the whole state by `state` (saved by this engine or by
    /// another: a state of another precision is rounded to this one's).
    fn load_state(&mut self, state: &EngineState) -> Result<(), EngineError>;
    /// GPU dispatches issued so far (None: not a GPU engine).
    fn dispatches(&self) -> Option<u64> {
        None
    }
    /// GPU dispatches of output kernels so far (apart from `dispatches`).
    fn output_dispatches(&self) -> Option<u64> {
        None
    }
    /// Output samples planned on the device so far and those it computed
    /// (None: it records none).
    fn device_samples(&self) -> Option<PlannedAndComputed> {
        None
    }
    /// Asks the engine to record the output samples `plan` makes due on
    /// the device while it advances (the GPU engine's one-step kernels):
    /// true if it will, and then `take_samples` hands them over after each
    /// `advance`. Called again after anything the host emitted itself (a
    /// quasi-static jump) to pass on the fast cadence's state. An error is
    /// the device's (a step failed while the queue was drained).
    fn record_samples(&mut self, _plan: &SamplePlan) -> Result<bool, EngineError> {
        Ok(false)
    }
    /// The samples recorded on the device since the last call, in step
    /// order (each step after the last sample the host saw, up to and
    /// including the engine's current step).
    fn take_samples(&mut self) -> Vec<Sample> {
        Vec::new()
    }
    /// Steps a runner should ask for in each `advance`, where the engine
    /// wants a fixed chunk rather than one sized by its wall time: a scene
    /// of a lockstep ensemble waits in `advance` for every other scene, so
    /// its wall time says nothing of its own speed (sizing by it shrank the
    /// chunks to a step each on a 256-scene ensemble).
    fn fixed_chunk(&self) -> Option<u64> {
        None
    }
    /// Lets `advance` return before its last steps have run where that
    /// keeps a device busy while the caller writes the samples it has (the
    /// GPU engine's batches). Their samples come with a later
    /// `take_samples`, a blow-up among them with a later call; every call
    /// that reads or writes the state waits for them first. A no-op where
    /// `advance` cannot run ahead.
    fn run_ahead(&mut self) {}
    /// Waits for steps still running after `advance` (`run_ahead`), so that
    /// `take_samples` then holds every sample up to `steps_done`.
    fn settle(&mut self) -> Result<(), EngineError> {
        Ok(())
    }
}

/// Advances `engine` to global step `target` (no-op if it is there or past).
pub fn advance_to(engine: &mut dyn Engine, target: u64) -> Result<(), EngineError> {
    let s = engine.steps_done();
    if target > s {
        engine.advance(target - s)?;
    }
    Ok(())
}

/// `set_kinematics` moves an engine within the driving phase only (the
/// normal-load phase's loads and the driver origin are set by stepping).
pub fn assert_driving_phase(model: &Model, current: u64, target: u64) {
    assert!(
        current >= model.prep_steps && target >= model.prep_steps,
        "set_kinematics is for the driving phase (steps {current} → {target}, driving from {})",
        model.prep_steps
    );
}

/// Builds the blow-up error for block `i` of a state.
pub fn blow_up(model: &Model, step: u64, i: usize, u: [f64; 2], v: [f64; 2]) -> EngineError {
    EngineError::BlowUp {
        step,
        time: model.time_of_step(step),
        ix: i % model.nx,
        iz: i / model.nx,
        ux: u[0],
        uz: u[1],
        vx: v[0],
        vz: v[1],
    }
}
