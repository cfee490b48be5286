//! Ensembles: many scenes of one lattice shape stepped together on the GPU,
//! one dispatch for all of them (workgroup row z of a dispatch is scene z,
//! `shaders/scene.wgsl`). The scenes may differ in anything that
//! is a run constant (loads, prestress, friction, seed, stiffnesses), not
//! in the lattice, the terms compiled in or the time schedule. A scene that
//! blows up stops alone: its error is kept and the others go on. Output
//! samples of every scene are recorded on the device together.

use super::context::{self, GpuContext};
use super::precision::GpuReal;
use super::shaders::Variant;
use super::{GpuEngine, GpuOptions};
use crate::engines::{Engine, EngineError, EngineState, Sample, SamplePlan, Snapshot};
use crate::model::lattice::block_flags;
use crate::model::real::precision_name;
use crate::model::Model;

/// An ensemble computing in `T`: mixed f32 (every adapter) or f64 (an
/// adapter with SHADER_F64), from the same kernels as `GpuEngine<T>`.
pub struct GpuEnsemble<T: GpuReal = f32> {
    engine: GpuEngine<T>,
}

/// Why `models` cannot be stepped as one ensemble, or None if they can:
/// one lattice (size, junctions, block flags), the same compiled terms
/// and the same time schedule (normal-load phase and ramp).
pub fn incompatibility(models: &[Model]) -> Option<String> {
    let first = models.first()?;
    let variant = Variant::for_model(first);
    let flags = block_flags(first);
    models.iter().enumerate().skip(1).find_map(|(k, m)| {
        let differs = |what: &str| Some(format!("scene {k} differs from scene 0 in {what}"));
        if (m.nx, m.nz) != (first.nx, first.nz) {
            differs("the lattice size")
        } else if m.n_junctions() != first.n_junctions() {
            differs("the junction count")
        } else if Variant::for_model(m) != variant {
            differs("the terms its kernel compiles in")
        } else if (m.prep_steps, m.ramp_steps) != (first.prep_steps, first.ramp_steps) {
            differs("the steps of its normal-load phase")
        } else if block_flags(m) != flags {
            differs("its boundary conditions")
        } else {
            None
        }
    })
}

/// The mixed-precision ensemble (every adapter).
impl GpuEnsemble {
    /// The ensemble of `models` on the best adapter.
    pub fn new(models: &[Model], opts: GpuOptions) -> Result<GpuEnsemble, EngineError> {
        GpuEnsemble::with_context(models, context::shared()?, opts)
    }

    pub fn with_context(
        models: &[Model],
        ctx: GpuContext,
        opts: GpuOptions,
    ) -> Result<GpuEnsemble, EngineError> {
        GpuEnsemble::with_precision_and_context(models, ctx, opts)
    }
}

impl<T: GpuReal> GpuEnsemble<T> {
    /// The ensemble in precision `T` (`GpuEnsemble::<f64>::with_precision`)
    /// on the best adapter; f64 fails on an adapter without SHADER_F64.
    pub fn with_precision(
        models: &[Model],
        opts: GpuOptions,
    ) -> Result<GpuEnsemble<T>, EngineError> {
        GpuEnsemble::with_precision_and_context(models, context::shared()?, opts)
    }

    pub fn with_precision_and_context(
        models: &[Model],
        ctx: GpuContext,
        opts: GpuOptions,
    ) -> Result<GpuEnsemble<T>, EngineError> {
        if models.is_empty() {
            return Err(EngineError::Gpu(
                "an ensemble needs at least one scene".into(),
            ));
        }
        if let Some(why) = incompatibility(models) {
            return Err(EngineError::Gpu(format!(
                "these scenes cannot share one ensemble: {why}"
            )));
        }
        Ok(GpuEnsemble {
            engine: GpuEngine::build(models, ctx, opts, true)?,
        })
    }

    pub fn len(&self) -> usize {
        self.engine.scenes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.engine.scenes.is_empty()
    }

    pub fn model(&self, scene: usize) -> &Model {
        &self.engine.scenes[scene].model
    }

    /// Steps done; every scene stands at this step.
    pub fn steps_done(&self) -> u64 {
        self.engine.step
    }

    /// Advances every scene `n` steps. Fails only for the device; a scene
    /// that blows up keeps its error in [`GpuEnsemble::failure`] and is
    /// left as it was at its blow-up while the others go on.
    pub fn advance(&mut self, n: u64) -> Result<(), EngineError> {
        self.engine.advance_steps(n)
    }

    /// Scene `scene`'s output samples recorded on the device from now on
    /// (all scenes in one dispatch per sample, read back with the
    /// batches), at `plan`'s cadences; false if they cannot be (host
    /// snapshots then): an adapter without the output kernels, f64, or
    /// cadences other than those the first scene asked for.
    pub fn record_samples(&mut self, scene: usize, plan: &SamplePlan) -> Result<bool, EngineError> {
        self.engine.record_samples_of(scene, plan)
    }

    /// As `Engine::run_ahead`, for every scene.
    pub fn run_ahead(&mut self) {
        self.engine.run_ahead();
    }

    /// As `Engine::settle`, for every scene.
    pub fn settle(&mut self) -> Result<(), EngineError> {
        self.engine.settle()
    }

    /// Scene `scene`'s samples recorded since the last call.
    pub fn take_samples(&mut self, scene: usize) -> Vec<Sample> {
        self.engine.take_samples_of(scene)
    }

    /// Dispatches of the output kernels so far (each records every scene).
    pub fn output_dispatches(&self) -> u64 {
        self.engine.output_dispatches
    }

    /// The blow-up that stopped `scene`, if it blew up.
    pub fn failure(&self, scene: usize) -> Option<&EngineError> {
        self.engine.scenes[scene].failure.as_ref()
    }

    /// Scene `scene`'s whole state at the current step.
    pub fn snapshot(&mut self, scene: usize) -> Result<Snapshot, EngineError> {
        self.engine.snapshot_of(scene)
    }

    /// Scene `scene`'s phase clock sums (`GpuOptions::phase_clocks`): a
    /// workgroup stepping several scenes adds its sums to its first.
    pub fn phase_cycles(
        &mut self,
        scene: usize,
    ) -> Result<super::phase_clocks::PhaseCycles, EngineError> {
        self.engine.phase_cycles(scene)
    }

    /// Scene `scene`'s phase clock sums, each of its tiles' apart (the
    /// tiled kernel; one entry for the others).
    pub fn phase_cycles_by_tile(
        &mut self,
        scene: usize,
    ) -> Result<Vec<super::phase_clocks::PhaseCycles>, EngineError> {
        self.engine.phase_cycles_by_tile(scene)
    }

    pub fn save_state(&mut self, scene: usize) -> Result<EngineState, EngineError> {
        self.engine.save_state_of(scene)
    }

    /// Starts every scene from its state in `states` (one per scene, all of
    /// one step: the end of a shared normal-load phase); the ensemble moves
    /// to that step.
    pub fn start_from(&mut self, states: &[&EngineState]) -> Result<(), EngineError> {
        self.engine.start_scenes_from(states)
    }

    /// Replaces one scene's state by `state`, which must be of the step
    /// the ensemble stands at.
    pub fn load_state(&mut self, scene: usize, state: &EngineState) -> Result<(), EngineError> {
        if state.step != self.engine.step {
            return Err(EngineError::State(format!(
                "a state of step {} cannot join an ensemble at step {}",
                state.step, self.engine.step
            )));
        }
        self.engine.load_state_of(scene, state)
    }

    pub fn describe(&self) -> String {
        format!(
            "gpu {}, ensemble of {} scenes, {}, on {}",
            precision_name::<T, T::Coord>(),
            self.len(),
            self.engine.kernel_description(),
            self.engine.ctx.describe()
        )
    }

    /// Dispatches issued so far (each steps every scene).
    pub fn dispatches(&self) -> u64 {
        self.engine.dispatches
    }
}
