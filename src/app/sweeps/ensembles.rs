//! Sweep points on the GPU as ensembles: points of one lattice shape and
//! time schedule are stepped together, one dispatch for all, each on its
//! own thread running the ordinary runner (`gpu::lockstep`).

use super::kernels::{ensemble_limit, SweepKernels};
use super::{run_point, EngineSource, Loading, Point, Recorder, SweepOptions};
use crate::engines::backend::Precision;
use crate::engines::gpu::ensemble::{incompatibility, GpuEnsemble};
use crate::engines::gpu::lockstep::Lockstep;
use crate::engines::gpu::precision::GpuReal;
use crate::engines::gpu::GpuOptions;
use crate::engines::EngineState;
use crate::engines::{Engine, EngineError};
use crate::model::Model;
use std::time::Instant;

/// Which points run together (indices into the sweep's to-do list).
pub struct Plan {
    /// Groups of two or more points, each one ensemble.
    pub ensembles: Vec<Vec<usize>>,
    /// Points that run alone: fast-forward runs (a jump moves one scene
    /// off the others' step), invalid ones, and points that match no other.
    pub alone: Vec<usize>,
}

/// Groups `todo` greedily into ensembles of at most `max` points (fewer
/// where the adapter holds fewer, `ensemble_limit`) that share a lattice
/// shape, compiled terms and time schedule, and that all start at step 0
/// or all from a shared normal-load phase.
pub fn plan(
    todo: &[&Point],
    loading_of: &[Option<usize>],
    max: usize,
    precision: Precision,
) -> Plan {
    struct Open {
        first: Model,
        loaded: bool,
        limit: usize,
        members: Vec<usize>,
    }
    let mut open: Vec<Open> = Vec::new();
    let mut alone = Vec::new();
    for (k, p) in todo.iter().enumerate() {
        let model = match Model::from_scenario(&p.scenario, false) {
            Ok(m) if !p.scenario.time.fast_forward => m,
            _ => {
                alone.push(k);
                continue;
            }
        };
        let loaded = loading_of[k].is_some();
        let fits = |g: &Open| {
            g.loaded == loaded
                && g.members.len() < g.limit
                && incompatibility(&[g.first.clone(), model.clone()]).is_none()
        };
        match open.iter_mut().find(|g| fits(g)) {
            Some(g) => g.members.push(k),
            None => open.push(Open {
                limit: ensemble_limit(&model, max, precision),
                first: model,
                loaded,
                members: vec![k],
            }),
        }
    }
    let mut ensembles = Vec::new();
    for g in open {
        if g.members.len() >= 2 {
            ensembles.push(g.members);
        } else {
            alone.extend(g.members);
        }
    }
    alone.sort_unstable();
    Plan { ensembles, alone }
}

/// Runs the shared normal-load phases themselves as ensembles (groups of
/// at most `max` compatible leaders, one dispatch for all) and stores each
/// loaded state where the points will look for it. A loading that cannot
/// join one, or whose scene blew up, is left to be made alone on first
/// use, with its own error. Returns the loadings made here.
pub fn prepare_loadings(
    loadings: &[Loading],
    opts: &SweepOptions,
    kernels: &SweepKernels,
) -> usize {
    let (max, precision) = (opts.ensemble, opts.precision);
    let mut models: Vec<(usize, Model)> = loadings
        .iter()
        .enumerate()
        .filter_map(|(g, l)| {
            Model::from_scenario(&l.leader.scenario, false)
                .ok()
                .map(|m| (g, m))
        })
        .collect();
    let mut made = 0;
    while !models.is_empty() {
        let mut batch = vec![models.remove(0)];
        let first = batch[0].1.clone();
        let limit = ensemble_limit(&first, max, precision);
        let mut k = 0;
        while k < models.len() && batch.len() < limit {
            if incompatibility(&[first.clone(), models[k].1.clone()]).is_none() {
                batch.push(models.remove(k));
            } else {
                k += 1;
            }
        }
        if batch.len() < 2 {
            continue;
        }
        let scenes: Vec<Model> = batch.iter().map(|(_, m)| m.clone()).collect();
        let gpu = kernels.options(&first, opts.gpu);
        // As `Loading::state`: one step before driving starts.
        let Ok(states) = (match precision {
            Precision::F64 => loaded_states::<f64>(&scenes, first.prep_steps - 1, gpu),
            _ => loaded_states::<f32>(&scenes, first.prep_steps - 1, gpu),
        }) else {
            continue;
        };
        for (state, &(g, _)) in states.into_iter().zip(&batch) {
            if let Some(state) = state {
                if loadings[g].state.set(Ok(state)).is_ok() {
                    made += 1;
                }
            }
        }
    }
    made
}

/// Each scene's state after `steps` as one ensemble in precision `T`
/// (None for a scene that blew up or whose state cannot be read).
fn loaded_states<T: GpuReal>(
    scenes: &[Model],
    steps: u64,
    gpu: GpuOptions,
) -> Result<Vec<Option<EngineState>>, EngineError> {
    let mut ensemble = GpuEnsemble::<T>::with_precision(scenes, gpu)?;
    ensemble.advance(steps)?;
    Ok((0..scenes.len())
        .map(|scene| {
            if ensemble.failure(scene).is_some() {
                None
            } else {
                ensemble.save_state(scene).ok()
            }
        })
        .collect())
}

/// The scenes of an ensemble of `models` in precision `T`, each its own
/// engine, started from `states` when given.
fn lockstep_engines<T: GpuReal>(
    models: &[Model],
    states: Option<&[&EngineState]>,
    gpu: GpuOptions,
) -> Result<Vec<Box<dyn Engine + Send>>, String> {
    let mut ensemble = GpuEnsemble::<T>::with_precision(models, gpu)
        .map_err(|e| format!("no ensemble of {} points: {e}", models.len()))?;
    if let Some(states) = states {
        ensemble.start_from(states).map_err(|e| e.to_string())?;
    }
    Ok(Lockstep::split(ensemble)
        .into_iter()
        .map(|e| Box::new(e) as Box<dyn Engine + Send>)
        .collect())
}

/// What running an ensemble needs from the sweep.
pub struct Run<'a> {
    pub todo: &'a [&'a Point],
    pub loadings: &'a [Loading<'a>],
    pub group_of: &'a [Option<usize>],
    pub opts: &'a SweepOptions,
    pub kernels: &'a SweepKernels,
    pub header_len: usize,
    pub recorder: &'a Recorder,
}

impl Run<'_> {
    /// Runs the points `members` as one ensemble, each point's row recorded
    /// as it finishes. Fails, before anything ran, if the ensemble cannot
    /// be built (the caller then runs the points alone).
    pub fn run(&self, members: &[usize]) -> Result<(), String> {
        let models = members
            .iter()
            .map(|&k| Model::from_scenario(&self.todo[k].scenario, false))
            .collect::<Result<Vec<Model>, _>>()
            .map_err(|e| e.to_string())?;
        let loaded = self.group_of[members[0]].is_some();
        let states = if loaded {
            Some(
                members
                    .iter()
                    .map(|&k| {
                        let g = self.group_of[k].expect("members all start loaded");
                        self.loadings[g].state(self.opts, self.kernels)
                    })
                    .collect::<Result<Vec<&EngineState>, String>>()?,
            )
        } else {
            None
        };
        let gpu = self.kernels.options(&models[0], self.opts.gpu);
        let engines = match self.opts.precision {
            Precision::F64 => lockstep_engines::<f64>(&models, states.as_deref(), gpu)?,
            _ => lockstep_engines::<f32>(&models, states.as_deref(), gpu)?,
        };
        std::thread::scope(|s| {
            for (engine, &k) in engines.into_iter().zip(members) {
                s.spawn(move || {
                    let p = self.todo[k];
                    let started = Instant::now();
                    // A stopped sweep drops the engine: the others go on to
                    // their own checks.
                    if self.recorder.stopped() {
                        return;
                    }
                    let source = EngineSource::Ensemble { engine, loaded };
                    let row = run_point(p, self.opts, self.kernels, self.header_len, source);
                    self.recorder.record(p, row, started);
                });
            }
        });
        Ok(())
    }
}
