//! `slipfront.Simulation`: a scene stepped by hand. Steps run with the GIL
//! released, in chunks of about a quarter second of wall time; Python's
//! signals are checked between chunks, so Ctrl-C stops `advance` at a
//! chunk's end with the simulation whole and usable.

use crate::engine_error;
use crate::running::EngineChoice;
use crate::scenario::Scenario;
use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use slipfront::app::runner::{drive_origin, global_sample};
use slipfront::io::checkpoint::{Checkpoint, RunnerState};
use slipfront::{Engine, Model};
use std::path::PathBuf;
use std::sync::Mutex;
use std::time::Instant;

struct State {
    engine: Box<dyn Engine>,
    scenario: slipfront::Scenario,
    /// The side spring's far-end origin, fixed when driving starts.
    origin: f64,
    history: Vec<String>,
}

/// A scene stepped by hand (the `slipfront.Simulation` wrapper takes file
/// names and shipped names too).
#[pyclass(module = "slipfront._core")]
pub struct Simulation {
    state: Mutex<State>,
}

/// Wall time one chunk of steps takes at most, so that Ctrl-C is answered
/// within about this.
const CHUNK_SECONDS: f64 = 0.25;

impl State {
    fn model(&self) -> &Model {
        self.engine.model()
    }

    /// Steps to `target` (a global step count), chunk by chunk, stopping at
    /// the start of driving to fix the drive's origin.
    fn advance_to(&mut self, py: Python<'_>, target: u64) -> PyResult<()> {
        let prep = self.model().prep_steps;
        let mut chunk: u64 = 64;
        while self.engine.steps_done() < target {
            let s = self.engine.steps_done();
            let mut to = (s + chunk).min(target);
            if s < prep {
                to = to.min(prep);
            }
            let started = Instant::now();
            let engine = &mut self.engine;
            py.detach(|| engine.advance(to - s)).map_err(engine_error)?;
            if self.engine.steps_done() == prep {
                let snap = self.engine.snapshot().map_err(engine_error)?;
                if let Some(o) = drive_origin(self.engine.model(), &snap) {
                    self.origin = o;
                }
            }
            let took = started.elapsed().as_secs_f64();
            if to - s == chunk {
                let fit = (chunk as f64 * CHUNK_SECONDS / took.max(1e-9)) as u64;
                chunk = fit.clamp(1, 1 << 20).min(chunk * 2);
            }
            py.check_signals()?;
        }
        Ok(())
    }
}

impl Simulation {
    /// The state, or an error when another Python thread is stepping it
    /// (waiting would hold the GIL that thread needs between chunks).
    fn lock(&self) -> PyResult<std::sync::MutexGuard<'_, State>> {
        self.state
            .try_lock()
            .map_err(|_| PyRuntimeError::new_err("this Simulation is busy in another thread"))
    }
}

fn flat2(v: &[[f64; 2]]) -> Vec<f64> {
    v.iter().flatten().copied().collect()
}

/// A simulation's engine choice: the options of `slipfront run` that a
/// `Simulation` takes (it writes no run file, so the output's is the default).
fn simulation_choice(
    backend: &str,
    precision: Option<&str>,
    threads: usize,
    gpu_path: &str,
    gpu_arithmetic: &str,
) -> PyResult<EngineChoice> {
    EngineChoice::parse(
        backend,
        precision,
        threads,
        gpu_path,
        "device",
        gpu_arithmetic,
    )
}

#[pymethods]
impl Simulation {
    /// A simulation of `scenario` at step 0 (the start of the normal-load
    /// phase).
    #[new]
    #[pyo3(signature = (scenario, backend="auto", precision=None, threads=0,
                        gpu_path="auto", allow_unstable=false, gpu_arithmetic="leaner"))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        scenario: &Scenario,
        backend: &str,
        precision: Option<&str>,
        threads: usize,
        gpu_path: &str,
        allow_unstable: bool,
        gpu_arithmetic: &str,
    ) -> PyResult<Self> {
        let choice = simulation_choice(backend, precision, threads, gpu_path, gpu_arithmetic)?;
        let model = Model::from_scenario(&scenario.inner, allow_unstable)
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        let precision = choice.precision();
        let engine = py.detach(|| choice.build(&model, precision))?;
        let history = vec![format!(
            "started from Python (Simulation): scenario `{}` ({}) on {}",
            scenario.inner.name,
            scenario.source,
            engine.describe()
        )];
        Ok(Simulation {
            state: Mutex::new(State {
                engine,
                scenario: scenario.inner.clone(),
                origin: 0.0,
                history,
            }),
        })
    }

    /// A simulation continued from a checkpoint: a run's (`RUN.mcap.ckpt`)
    /// or one [`checkpoint`] wrote.
    #[staticmethod]
    #[pyo3(signature = (path, backend="auto", precision=None, threads=0, gpu_path="auto",
                        gpu_arithmetic="leaner"))]
    fn from_checkpoint(
        py: Python<'_>,
        path: PathBuf,
        backend: &str,
        precision: Option<&str>,
        threads: usize,
        gpu_path: &str,
        gpu_arithmetic: &str,
    ) -> PyResult<Self> {
        let choice = simulation_choice(backend, precision, threads, gpu_path, gpu_arithmetic)?;
        let ckpt = Checkpoint::read(&path).map_err(|e| {
            PyValueError::new_err(format!("cannot read checkpoint `{}`: {e}", path.display()))
        })?;
        let scenario =
            slipfront::Scenario::parse(&ckpt.header.scenario, "the checkpoint's scenario", &[])
                .map_err(|e| PyValueError::new_err(e.to_string()))?;
        // The run passed the stability check when it started.
        let model = Model::from_scenario(&scenario, true)
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        let precision = match choice.precision {
            Some(p) => p,
            None => slipfront::engines::backend::Precision::of_state(&ckpt.header.precision)
                .ok_or_else(|| {
                    PyValueError::new_err(format!(
                        "the checkpoint's precision `{}` is unknown: choose one with precision=",
                        ckpt.header.precision
                    ))
                })?,
        };
        let mut engine = py.detach(|| choice.build(&model, precision))?;
        engine.load_state(&ckpt.engine).map_err(engine_error)?;
        let mut history = ckpt.header.history.clone();
        history.push(format!(
            "continued from Python at step {} (t = {:.6e} s) from `{}`; on {}",
            ckpt.header.step,
            ckpt.header.time,
            path.display(),
            engine.describe()
        ));
        Ok(Simulation {
            state: Mutex::new(State {
                engine,
                scenario,
                origin: ckpt.header.runner.origin,
                history,
            }),
        })
    }

    /// Advances to time `t` (s since driving started; negative times lie in
    /// the normal-load phase), to the nearest step at or after it.
    fn advance(&self, py: Python<'_>, t: f64) -> PyResult<()> {
        let mut s = self.lock()?;
        let m = s.model();
        if !t.is_finite() {
            return Err(PyValueError::new_err(format!(
                "t = {t}: expected a finite time"
            )));
        }
        let target = ((t / m.dt).ceil() + m.prep_steps as f64).max(0.0) as u64;
        let now = s.engine.steps_done();
        if target < now {
            return Err(PyValueError::new_err(format!(
                "t = {t:e} s: the simulation is already at t = {:e} s (it only goes forward)",
                m.time_of_step(now)
            )));
        }
        s.advance_to(py, target)
    }

    /// Advances `n` steps.
    fn advance_steps(&self, py: Python<'_>, n: u64) -> PyResult<()> {
        let mut s = self.lock()?;
        let target = s.engine.steps_done().saturating_add(n);
        s.advance_to(py, target)
    }

    /// Runs to the scenario's end (`time.end`).
    fn run_to_end(&self, py: Python<'_>) -> PyResult<()> {
        let mut s = self.lock()?;
        let end = s.model().total_steps().max(s.engine.steps_done());
        s.advance_to(py, end)
    }

    /// Steps done (0 at the start of the normal-load phase).
    #[getter]
    fn step(&self) -> PyResult<u64> {
        Ok(self.lock()?.engine.steps_done())
    }

    /// Time since driving started (s).
    #[getter]
    fn time(&self) -> PyResult<f64> {
        let s = self.lock()?;
        Ok(s.model().time_of_step(s.engine.steps_done()))
    }

    /// Time step (s).
    #[getter]
    fn dt(&self) -> PyResult<f64> {
        Ok(self.lock()?.model().dt)
    }

    /// Steps to the scenario's end.
    #[getter]
    fn total_steps(&self) -> PyResult<u64> {
        Ok(self.lock()?.model().total_steps())
    }

    /// The engine, as a run header names it.
    #[getter]
    fn engine(&self) -> PyResult<String> {
        Ok(self.lock()?.engine.describe())
    }

    /// The state now, as numpy copies: displacements and velocities
    /// (nz × nx × 2, m and m/s), the non-friction force on each block
    /// (nz × nx × 2, N), friction and normal force per interface block
    /// (nx, N), and the junctions (nx × Ns): anchors (m), stiffnesses
    /// (N/m), pinned (bool), steps left to slip, ruptures.
    fn state<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let mut s = self.lock()?;
        let snap = s.engine.snapshot().map_err(engine_error)?;
        let m = s.model();
        let (nx, nz) = (m.nx, m.nz);
        let ns = m.junctions.map_or(0, |j| j.count);
        let d = PyDict::new(py);
        d.set_item("step", snap.step)?;
        d.set_item("time", snap.time)?;
        let field = |v: &[[f64; 2]]| PyArray1::from_vec(py, flat2(v)).reshape([nz, nx, 2]);
        d.set_item("disp", field(&snap.disp)?)?;
        d.set_item("vel", field(&snap.vel)?)?;
        d.set_item("force", field(&snap.force)?)?;
        d.set_item("friction", PyArray1::from_vec(py, snap.friction))?;
        d.set_item("normal", PyArray1::from_vec(py, snap.normal))?;
        let pinned: Vec<bool> = snap
            .slip_steps_left
            .iter()
            .map(|&r| r == slipfront::model::junction::PINNED)
            .collect();
        let junctions = |v| PyArray1::from_vec(py, v).reshape([nx, ns]);
        d.set_item("anchor", junctions(snap.anchor)?)?;
        d.set_item("junction_stiffness", junctions(snap.junction_stiffness)?)?;
        d.set_item("pinned", PyArray1::from_vec(py, pinned).reshape([nx, ns])?)?;
        d.set_item(
            "slip_steps_left",
            PyArray1::from_vec(py, snap.slip_steps_left).reshape([nx, ns])?,
        )?;
        d.set_item(
            "ruptures",
            PyArray1::from_vec(py, snap.ruptures).reshape([nx, ns])?,
        )?;
        Ok(d)
    }

    /// The global series now, as `/global` records it: time, step, drive
    /// force (N), F/F_N, friction force (N), pinned fraction, kinetic
    /// energy (J), ruptures.
    fn sample<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let mut s = self.lock()?;
        let snap = s.engine.snapshot().map_err(engine_error)?;
        let g = global_sample(s.model(), &snap, s.origin);
        let d = PyDict::new(py);
        d.set_item("time", g.time)?;
        d.set_item("step", g.step)?;
        d.set_item("drive_force", g.drive_force)?;
        d.set_item("drive_ratio", g.drive_ratio)?;
        d.set_item("friction_force", g.friction_force)?;
        d.set_item("pinned_fraction", g.pinned_fraction)?;
        d.set_item("kinetic_energy", g.kinetic_energy)?;
        d.set_item("ruptures", g.ruptures)?;
        Ok(d)
    }

    /// Saves the state to `path` (the checkpoint format of runs: `slipfront
    /// run --from PATH` branches from it, `from_checkpoint` continues it).
    fn checkpoint(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let mut s = self.lock()?;
        let runner = RunnerState {
            origin: s.origin,
            ..RunnerState::default()
        };
        let (scenario, history) = (s.scenario.to_toml(), s.history.clone());
        let engine = &mut s.engine;
        py.detach(|| {
            Checkpoint::of_engine(engine.as_mut(), scenario, runner, None, history)
                .map_err(engine_error)?
                .write(&path)
                .map_err(|e| PyRuntimeError::new_err(e.to_string()))
        })
    }

    fn __repr__(&self) -> PyResult<String> {
        let s = self.lock()?;
        Ok(format!(
            "Simulation({:?} at step {} of {}, t = {:e} s, on {})",
            s.scenario.name,
            s.engine.steps_done(),
            s.model().total_steps(),
            s.model().time_of_step(s.engine.steps_done()),
            s.engine.describe()
        ))
    }
}
