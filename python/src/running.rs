//! `slipfront.run`: a scene run to its end into a run file, as `slipfront
//! run -o FILE` does, with the GIL released while it steps.

use crate::scenario::Scenario;
use crate::watch::Watcher;
use crate::{choice, engine_error};
use pyo3::exceptions::{PyFileExistsError, PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use slipfront::app::runner::{self, ProgressMode, RunError, RunOptions, RunSummary};
use slipfront::engines::backend::{make_engine_with, Backend, Precision};
use slipfront::engines::gpu::options::run_ahead_batches;
use slipfront::engines::gpu::{GpuOptions, GpuOutput, GpuPath};
use slipfront::io::checkpoint::Checkpoint;
use slipfront::io::live::{largest_record, LiveAddress, LiveError, LiveView};
use slipfront::io::output::fnv1a;
use slipfront::io::output::lock::RunLock;
use slipfront::{Engine, Model};
use std::path::PathBuf;

/// How a run or a simulation is computed: the options of `slipfront run`
/// of the same names.
pub struct EngineChoice {
    pub backend: Backend,
    pub precision: Option<Precision>,
    pub threads: usize,
    pub gpu: GpuOptions,
}

impl EngineChoice {
    pub fn parse(
        backend: &str,
        precision: Option<&str>,
        threads: usize,
        gpu_path: &str,
        gpu_output: &str,
        gpu_arithmetic: &str,
    ) -> PyResult<Self> {
        Ok(EngineChoice {
            backend: choice("backend", backend)?,
            precision: precision.map(|p| choice("precision", p)).transpose()?,
            threads,
            gpu: GpuOptions {
                path: choice::<GpuPath>("gpu_path", gpu_path)?,
                output: choice::<GpuOutput>("gpu_output", gpu_output)?,
                arithmetic: choice("gpu_arithmetic", gpu_arithmetic)?,
                ..GpuOptions::default()
            },
        })
    }

    /// The precision asked, else the backend's default (f64 wherever it
    /// can run).
    pub fn precision(&self) -> Precision {
        self.precision
            .unwrap_or_else(|| self.backend.default_precision())
    }

    /// The engine for `model`, refused up front when the machine has not
    /// the memory for it.
    pub fn build(&self, model: &Model, precision: Precision) -> PyResult<Box<dyn Engine>> {
        precision
            .check_memory(model, "a smaller lattice, or another precision")
            .map_err(PyValueError::new_err)?;
        make_engine_with(model, self.backend, precision, self.threads, self.gpu)
            .map_err(engine_error)
    }
}

fn summary_dict<'py>(py: Python<'py>, s: &RunSummary) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("backend", &s.backend)?;
    d.set_item("steps", s.steps)?;
    d.set_item("simulated_time", s.simulated_time)?;
    d.set_item("wall_seconds", s.wall_seconds)?;
    d.set_item("block_steps_per_second", s.block_steps_per_second)?;
    if s.normal_load {
        d.set_item("peak_drive_ratio", s.peak_drive_ratio)?;
        d.set_item("final_drive_ratio", s.final_drive_ratio)?;
    }
    d.set_item("ruptures", s.ruptures)?;
    d.set_item("dispatches", s.dispatches)?;
    d.set_item("skipped_steps", s.skipped_steps)?;
    d.set_item("interrupted", s.interrupted)?;
    d.set_item("output", s.output.as_ref().map(|p| p.display().to_string()))?;
    d.set_item(
        "checkpoint",
        s.checkpoint.as_ref().map(|p| p.display().to_string()),
    )?;
    Ok(d)
}

/// Starts the run's live view at `address` and says where on Python's
/// stderr; with `wait`, returns once a viewer has subscribed (Ctrl-C
/// gives up waiting and raises KeyboardInterrupt).
fn start_live(
    py: Python<'_>,
    address: &str,
    model: &Model,
    sc: &slipfront::Scenario,
    wait: bool,
) -> PyResult<LiveView> {
    let address: LiveAddress = address
        .parse()
        .map_err(|e: String| PyValueError::new_err(format!("live: {e}")))?;
    let largest = largest_record(model.nx, model.nz, sc.output.bulk_interval > 0.0);
    let view = LiveView::start(&address, largest).map_err(|e| match e {
        LiveError::Bind { .. } => PyOSError::new_err(e.to_string()),
        e => PyRuntimeError::new_err(e.to_string()),
    })?;
    let say = format!(
        "slipfront: live view at {} (Foxglove: Open connection → Foxglove WebSocket)\n",
        view.url()
    );
    py.import("sys")?
        .getattr("stderr")?
        .call_method1("write", (say,))?;
    if wait {
        let caught = std::sync::Mutex::new(None);
        py.detach(|| {
            view.wait_for_viewer(&|| {
                Python::attach(|py| py.check_signals())
                    .map_err(|e| *caught.lock().unwrap_or_else(|p| p.into_inner()) = Some(e))
                    .is_err()
            })
        });
        if let Some(e) = caught.into_inner().unwrap_or_else(|p| p.into_inner()) {
            view.close();
            return Err(e);
        }
    }
    Ok(view)
}

/// Runs `scenario` to its end into the run file `output`. Returns the run
/// summary, and the exception that stopped the run early (Ctrl-C's
/// KeyboardInterrupt, or one raised by `progress`), if one did: the run
/// file is closed and its checkpoint written by then.
#[pyfunction]
#[pyo3(signature = (scenario, output, backend="auto", precision=None, threads=0,
                    gpu_path="auto", gpu_output="device", allow_unstable=false,
                    force=false, progress=None, live=None, live_wait=false,
                    gpu_run_ahead=None, gpu_arithmetic="leaner"))]
#[allow(clippy::too_many_arguments)]
pub fn run_scene<'py>(
    py: Python<'py>,
    scenario: &Scenario,
    output: PathBuf,
    backend: &str,
    precision: Option<&str>,
    threads: usize,
    gpu_path: &str,
    gpu_output: &str,
    allow_unstable: bool,
    force: bool,
    progress: Option<Py<PyAny>>,
    live: Option<&str>,
    live_wait: bool,
    gpu_run_ahead: Option<i64>,
    gpu_arithmetic: &str,
) -> PyResult<(Bound<'py, PyDict>, Option<PyErr>)> {
    let mut choice = EngineChoice::parse(
        backend,
        precision,
        threads,
        gpu_path,
        gpu_output,
        gpu_arithmetic,
    )?;
    if let Some(batches) = gpu_run_ahead {
        choice.gpu.run_ahead = run_ahead_batches(batches)
            .map_err(|why| PyValueError::new_err(format!("gpu_run_ahead = {why}")))?;
    }
    let sc = &scenario.inner;
    let model = Model::from_scenario(sc, allow_unstable)
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    if output.exists() && !force {
        return Err(PyFileExistsError::new_err(format!(
            "`{}` exists: pass force=True to replace it, or continue it with `slipfront run \
             --resume {}`",
            output.display(),
            output.display()
        )));
    }
    let _lock = RunLock::acquire(&output, "run").map_err(PyRuntimeError::new_err)?;
    // A previous run's checkpoints beside the file would pass for this one's.
    for stale in Checkpoint::candidates(&output) {
        let _ = std::fs::remove_file(&stale);
    }
    let precision = choice.precision();
    // The run writes its file: `auto` times the GPU's launches recording
    // its samples at its cadences, as the run will.
    if choice.gpu.output == GpuOutput::Device {
        choice.gpu.samples = Some(runner::sample_plan(&model, sc));
    }
    let mut engine = py.detach(|| choice.build(&model, precision))?;
    let history = vec![format!(
        "started from Python: scenario `{}` ({}, hash {:016x}) on {}",
        sc.name,
        scenario.source,
        fnv1a(sc.to_toml().as_bytes()),
        engine.describe()
    )];
    let live = live
        .map(|address| start_live(py, address, &model, sc, live_wait))
        .transpose()?;
    let watcher = Watcher::new(progress);
    let hook = {
        let w = watcher.clone();
        std::sync::Arc::new(move |done: u64, total: u64| w.poll(done, total))
    };
    let opts = RunOptions {
        output: Some(output),
        progress: ProgressMode::None,
        history,
        on_chunk: Some(hook),
        live: live.clone(),
        ..RunOptions::default()
    };
    let result = py.detach(|| {
        let result = runner::run_scene(engine.as_mut(), sc, &opts);
        if let Some(live) = &live {
            live.close();
        }
        result
    });
    let stopped_by = watcher.take_error();
    match result {
        Ok(summary) => {
            let d = summary_dict(py, &summary)?;
            d.set_item("live", live.as_ref().map(LiveView::url))?;
            Ok((d, stopped_by))
        }
        Err(RunError::Engine(e)) => Err(engine_error(e)),
        Err(e) => Err(PyRuntimeError::new_err(e.to_string())),
    }
}
