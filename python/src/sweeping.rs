//! `slipfront.sweep`: a sweep built from Python values (a base scenario and
//! a list of points), run by slipfront's sweep runner (GPU ensembles where
//! a GPU is, the CPU's threads otherwise) into a folder with its
//! `summary.csv`, as `slipfront sweep` does.

use crate::choice;
use crate::convert::to_toml;
use crate::scenario::Scenario;
use crate::watch::Watcher;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use slipfront::app::sweeps::plan::{Perturb, Seeds};
use slipfront::app::sweeps::{self, KeepMcap, Sweep, SweepFile, SweepOptions};
use slipfront::engines::backend::{resolve_auto, Backend, Precision};
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Duration;

/// The sweep file these arguments stand for: the points zipped (the i-th
/// value of every key together), every point with the same keys.
fn sweep_file(
    points: Option<&Bound<'_, PyList>>,
    seeds: Option<&Bound<'_, PyAny>>,
    perturb: Option<&Bound<'_, PyDict>>,
) -> PyResult<SweepFile> {
    let mut table = toml::Table::new();
    table.insert("base".into(), toml::Value::String("base.toml".into()));
    table.insert("combine".into(), toml::Value::String("zip".into()));
    let mut axes: toml::Table = toml::Table::new();
    if let Some(points) = points {
        let mut keys: Option<Vec<String>> = None;
        for (k, point) in points.iter().enumerate() {
            let point = point.cast::<PyDict>().map_err(|_| {
                PyValueError::new_err(format!("points[{k}]: expected a dict of key: value"))
            })?;
            let mut these: Vec<String> = point
                .keys()
                .iter()
                .map(|key| key.extract::<String>())
                .collect::<PyResult<_>>()?;
            these.sort();
            match &keys {
                Some(first) if *first != these => {
                    return Err(PyValueError::new_err(format!(
                        "points[{k}] sets {these:?}, points[0] sets {first:?}: every point \
                         sets the same keys (put a key every point shares in the base \
                         scenario)"
                    )))
                }
                _ => keys = Some(these),
            }
            for (key, value) in point.iter() {
                let key: String = key.extract()?;
                let value = to_toml(&format!("points[{k}][{key:?}]"), &value)?;
                match axes
                    .entry(key)
                    .or_insert_with(|| toml::Value::Array(Vec::new()))
                {
                    toml::Value::Array(a) => a.push(value),
                    _ => unreachable!("axes hold arrays"),
                }
            }
        }
    }
    table.insert("axes".into(), toml::Value::Table(axes));
    // Each checked alone first, so that an error names it.
    let mut put =
        |name: &str, value: toml::Value, check: fn(toml::Value) -> Result<(), toml::de::Error>| {
            check(value.clone())
                .map_err(|e| PyValueError::new_err(format!("{name} = {value}: {}", e.message())))?;
            table.insert(name.into(), value);
            PyResult::Ok(())
        };
    if let Some(seeds) = seeds {
        put("seeds", to_toml("seeds", seeds)?, |v| {
            v.try_into::<Seeds>().map(drop)
        })?;
    }
    if let Some(perturb) = perturb {
        put("perturb", to_toml("perturb", perturb.as_any())?, |v| {
            v.try_into::<Perturb>().map(drop)
        })?;
    }
    toml::Value::Table(table)
        .try_into::<SweepFile>()
        .map_err(|e| PyValueError::new_err(format!("sweep: {}", e.message())))
}

/// Runs the sweep into `out_dir` (created; a rerun skips the points its
/// table already holds). Returns the report (table path, points run, not
/// ok, wall time, how the points ran) and the exception that stopped it
/// early, if one did.
#[pyfunction]
#[pyo3(signature = (base, out_dir, points=None, seeds=None, perturb=None, backend="auto",
                    precision=None, threads=0, ensemble=sweeps::DEFAULT_ENSEMBLE,
                    keep_runs=false, progress=None))]
#[allow(clippy::too_many_arguments)]
pub fn run_sweep<'py>(
    py: Python<'py>,
    base: &Scenario,
    out_dir: PathBuf,
    points: Option<&Bound<'py, PyList>>,
    seeds: Option<&Bound<'py, PyAny>>,
    perturb: Option<&Bound<'py, PyDict>>,
    backend: &str,
    precision: Option<&str>,
    threads: usize,
    ensemble: usize,
    keep_runs: bool,
    progress: Option<Py<PyAny>>,
) -> PyResult<(Bound<'py, PyDict>, Option<PyErr>)> {
    let backend: Backend = choice("backend", backend)?;
    let precision: Precision = match precision {
        Some(p) => choice("precision", p)?,
        None => backend.default_precision(),
    };
    if ensemble == 0 {
        return Err(PyValueError::new_err(
            "ensemble = 0: expected 1 (points one at a time) or more",
        ));
    }
    let file = sweep_file(points, seeds, perturb)?;
    std::fs::create_dir_all(&out_dir).map_err(|e| {
        PyRuntimeError::new_err(format!("cannot create `{}`: {e}", out_dir.display()))
    })?;
    let base_path = out_dir.join("base.toml");
    std::fs::write(&base_path, base.inner.to_toml()).map_err(|e| {
        PyRuntimeError::new_err(format!("cannot write `{}`: {e}", base_path.display()))
    })?;
    let sweep = Sweep::build(file, &out_dir).map_err(|problems| {
        PyValueError::new_err(format!("invalid sweep:\n  - {}", problems.join("\n  - ")))
    })?;
    let (backend, how) = match backend {
        Backend::Auto => resolve_auto(precision),
        b => (b, String::new()),
    };
    let done = Arc::new(AtomicUsize::new(0));
    let total = Arc::new(AtomicUsize::new(sweep.points.len()));
    let opts = SweepOptions {
        out_dir: out_dir.clone(),
        backend,
        precision,
        threads,
        shard: None,
        keep_mcap: if keep_runs {
            KeepMcap::All
        } else {
            KeepMcap::None
        },
        progress: false,
        share_loading: true,
        ensemble,
        gpu: sweeps::default_gpu(),
        on_point: Some({
            let (done, total) = (done.clone(), total.clone());
            Arc::new(move |d, t| {
                done.store(d, Ordering::SeqCst);
                total.store(t, Ordering::SeqCst);
            })
        }),
    };
    let watcher = Watcher::new(progress);
    // The sweep runs on its own threads; this one keeps Python's Ctrl-C
    // and the progress bar alive until it ends.
    let report = py.detach(|| {
        std::thread::scope(|scope| {
            let worker = scope.spawn(|| sweeps::run_sweep(&sweep, &opts));
            while !worker.is_finished() {
                std::thread::sleep(Duration::from_millis(50));
                watcher.poll(
                    done.load(Ordering::SeqCst) as u64,
                    total.load(Ordering::SeqCst) as u64,
                );
            }
            worker.join().expect("the sweep thread panicked")
        })
    });
    let stopped_by = watcher.take_error();
    let report = report.map_err(PyRuntimeError::new_err)?;
    let d = PyDict::new(py);
    d.set_item("table", report.table.display().to_string())?;
    d.set_item("points", report.points)?;
    d.set_item("ran", report.ran)?;
    d.set_item("skipped", report.skipped)?;
    d.set_item("not_ok", report.not_ok)?;
    d.set_item("interrupted", report.interrupted)?;
    d.set_item("wall_seconds", report.wall_seconds)?;
    d.set_item("ensembles", report.ensembles)?;
    d.set_item("backend", format!("{backend:?}"))?;
    d.set_item("how", how)?;
    Ok((d, stopped_by))
}
