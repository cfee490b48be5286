//! The scenes of a GPU ensemble as separate engines, one per thread, so
//! that each runs the ordinary runner (outputs, analysis, checkpoints)
//! while the device steps them all in one dispatch. The scenes move in
//! lockstep: the ensemble advances only when every running scene has asked
//! to, by the smallest of their requests, so a scene that is not waiting
//! always finds the ensemble at its own step. A scene whose run ends
//! (its engine dropped) no longer holds the others back. Output samples
//! are recorded on the device for all scenes at once, so the runners ask
//! for long advances, not one per output step; the ensemble runs ahead
//! (`Engine::run_ahead`), so the device steps the end of one advance while
//! the runners write the samples of the rest.

use super::ensemble::GpuEnsemble;
use super::precision::GpuReal;
use crate::engines::{Engine, EngineError, EngineState, Sample, SamplePlan, Snapshot};
use crate::model::Model;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};

/// Steps a lockstep scene's runner asks for per advance: a few batches of
/// the one-step kernels, long enough to amortise a round of requests, short
/// enough for progress and interrupts.
pub const LOCKSTEP_CHUNK: u64 = 8 * super::batch_sizes::ONE_STEP_BATCH;

struct Shared<T: GpuReal> {
    ensemble: GpuEnsemble<T>,
    /// Steps each scene still waits for (None: not waiting).
    wants: Vec<Option<u64>>,
    /// Scenes whose engine is still in use.
    running: Vec<bool>,
    /// A device error ends every scene.
    device_error: Option<String>,
}

pub struct Lockstep<T: GpuReal> {
    shared: Mutex<Shared<T>>,
    moved: Condvar,
}

/// One scene of a lockstep ensemble, as an [`Engine`].
pub struct LockstepScene<T: GpuReal = f32> {
    lockstep: Arc<Lockstep<T>>,
    scene: usize,
    model: Model,
    description: String,
}

impl<T: GpuReal> Lockstep<T> {
    /// One engine per scene of `ensemble`, in scene order.
    pub fn split(ensemble: GpuEnsemble<T>) -> Vec<LockstepScene<T>> {
        let n = ensemble.len();
        let models: Vec<Model> = (0..n).map(|k| ensemble.model(k).clone()).collect();
        let description = ensemble.describe();
        let lockstep = Arc::new(Lockstep {
            shared: Mutex::new(Shared {
                ensemble,
                wants: vec![None; n],
                running: vec![true; n],
                device_error: None,
            }),
            moved: Condvar::new(),
        });
        models
            .into_iter()
            .enumerate()
            .map(|(scene, model)| LockstepScene {
                lockstep: lockstep.clone(),
                scene,
                model,
                description: format!("scene {scene} of the {description}"),
            })
            .collect()
    }

    fn lock(&self) -> MutexGuard<'_, Shared<T>> {
        // A thread that panicked holding the lock leaves the state as it
        // was between two ensemble steps: still usable.
        self.shared.lock().unwrap_or_else(|p| p.into_inner())
    }
}

impl<T: GpuReal> Shared<T> {
    /// Advances the ensemble while every running scene is waiting, by the
    /// smallest request each time; true if it moved.
    fn step_while_all_wait(&mut self) -> bool {
        let mut moved = false;
        loop {
            let waiting = self
                .running
                .iter()
                .zip(&self.wants)
                .filter(|(r, _)| **r)
                .map(|(_, w)| *w);
            let mut least = None::<u64>;
            for w in waiting {
                match w {
                    None => return moved,
                    Some(n) => least = Some(least.map_or(n, |l| l.min(n))),
                }
            }
            let Some(n) = least else {
                return moved;
            };
            if self.device_error.is_some() {
                return moved;
            }
            if let Err(e) = self.ensemble.advance(n) {
                self.device_error = Some(e.to_string());
            }
            moved = true;
            for (k, want) in self.wants.iter_mut().enumerate() {
                let Some(left) = want else { continue };
                *left -= n;
                // A scene that blew up returns at once with its error.
                if *left == 0 || self.ensemble.failure(k).is_some() {
                    *want = None;
                }
            }
        }
    }

    fn check(&self, scene: usize) -> Result<(), EngineError> {
        if let Some(e) = &self.device_error {
            return Err(EngineError::Gpu(e.clone()));
        }
        match self.ensemble.failure(scene) {
            Some(EngineError::BlowUp {
                step,
                time,
                ix,
                iz,
                ux,
                uz,
                vx,
                vz,
            }) => Err(EngineError::BlowUp {
                step: *step,
                time: *time,
                ix: *ix,
                iz: *iz,
                ux: *ux,
                uz: *uz,
                vx: *vx,
                vz: *vz,
            }),
            Some(other) => Err(EngineError::Gpu(other.to_string())),
            None => Ok(()),
        }
    }
}

impl<T: GpuReal> LockstepScene<T> {
    fn no_jumps(&self) -> EngineError {
        EngineError::Gpu(
            "a scene of a GPU ensemble cannot jump (quasi-static fast-forward): run it alone"
                .into(),
        )
    }
}

impl<T: GpuReal> Engine for LockstepScene<T> {
    fn model(&self) -> &Model {
        &self.model
    }

    fn steps_done(&self) -> u64 {
        self.lockstep.lock().ensemble.steps_done()
    }

    fn advance(&mut self, n: u64) -> Result<(), EngineError> {
        let mut shared = self.lockstep.lock();
        shared.check(self.scene)?;
        if n == 0 {
            return Ok(());
        }
        shared.wants[self.scene] = Some(n);
        loop {
            if shared.step_while_all_wait() {
                self.lockstep.moved.notify_all();
            }
            if shared.wants[self.scene].is_none() || shared.device_error.is_some() {
                shared.wants[self.scene] = None;
                return shared.check(self.scene);
            }
            shared = self
                .lockstep
                .moved
                .wait(shared)
                .unwrap_or_else(|p| p.into_inner());
        }
    }

    fn snapshot(&mut self) -> Result<Snapshot, EngineError> {
        let mut shared = self.lockstep.lock();
        shared.check(self.scene)?;
        shared.ensemble.snapshot(self.scene)
    }

    fn describe(&self) -> String {
        self.description.clone()
    }

    fn set_kinematics(
        &mut self,
        _: u64,
        _: &[[f64; 2]],
        _: &[[f64; 2]],
    ) -> Result<(), EngineError> {
        Err(self.no_jumps())
    }

    fn set_junctions(&mut self, _: &Snapshot) -> Result<(), EngineError> {
        Err(self.no_jumps())
    }

    fn save_state(&mut self) -> Result<EngineState, EngineError> {
        let mut shared = self.lockstep.lock();
        shared.check(self.scene)?;
        shared.ensemble.save_state(self.scene)
    }

    fn load_state(&mut self, state: &EngineState) -> Result<(), EngineError> {
        self.lockstep.lock().ensemble.load_state(self.scene, state)
    }

    fn dispatches(&self) -> Option<u64> {
        Some(self.lockstep.lock().ensemble.dispatches())
    }

    fn output_dispatches(&self) -> Option<u64> {
        Some(self.lockstep.lock().ensemble.output_dispatches())
    }

    /// The ensemble records this scene's samples on the device with every
    /// other scene's: the runner then advances in long chunks instead of
    /// stopping the whole ensemble at each output step for a snapshot.
    fn record_samples(&mut self, plan: &SamplePlan) -> Result<bool, EngineError> {
        let mut shared = self.lockstep.lock();
        shared.check(self.scene)?;
        shared.ensemble.record_samples(self.scene, plan)
    }

    fn take_samples(&mut self) -> Vec<Sample> {
        self.lockstep.lock().ensemble.take_samples(self.scene)
    }

    /// Every scene asks for the same long chunks (its runner's stops, such
    /// as output steps taken as snapshots, still cut them), so that a round
    /// of requests is one long advance of the whole ensemble.
    fn fixed_chunk(&self) -> Option<u64> {
        Some(LOCKSTEP_CHUNK)
    }

    /// The whole ensemble runs ahead: while the runners write the samples
    /// of a chunk, the device steps the last batches of it.
    fn run_ahead(&mut self) {
        self.lockstep.lock().ensemble.run_ahead();
    }

    fn settle(&mut self) -> Result<(), EngineError> {
        let mut shared = self.lockstep.lock();
        shared.check(self.scene)?;
        if let Err(e) = shared.ensemble.settle() {
            shared.device_error = Some(e.to_string());
        }
        shared.check(self.scene)
    }
}

impl<T: GpuReal> Drop for LockstepScene<T> {
    fn drop(&mut self) {
        let mut shared = self.lockstep.lock();
        shared.running[self.scene] = false;
        shared.wants[self.scene] = None;
        // The others may all be waiting for this one.
        if shared.step_while_all_wait() {
            self.lockstep.moved.notify_all();
        }
    }
}
