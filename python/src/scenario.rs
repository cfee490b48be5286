//! `slipfront.Scenario`: a validated scenario, loaded from a TOML file or a
//! shipped scene by name, with `set={...}` overrides. The TOML scenarios
//! stay the one configuration; errors are the CLI's, as ValueError.

use crate::convert;
use pyo3::exceptions::{PyFileNotFoundError, PyKeyError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use slipfront::model::scenario::{self as scene, DEFAULT_SCENARIO, DEFAULT_SCENARIO_NAME};
use slipfront::Model;
use std::path::PathBuf;

/// A validated scenario: a TOML file or a shipped scene by name, with
/// overrides (`Scenario.load("triggered_front", set={"time.end": 1e-3})`).
/// Immutable: `with_set` makes a changed copy.
#[pyclass(module = "slipfront._core", frozen, from_py_object)]
#[derive(Clone)]
pub struct Scenario {
    pub inner: scene::Scenario,
    /// Where it came from: a file, a shipped scene, or text.
    #[pyo3(get)]
    pub source: String,
}

fn invalid(e: scene::ScenarioError) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// The names of the shipped scenarios (`Scenario.load(name)`).
#[pyfunction]
pub fn built_in_names() -> Vec<&'static str> {
    scene::BUILT_IN.iter().map(|(n, _)| *n).collect()
}

#[pymethods]
impl Scenario {
    /// A scenario file, or a shipped scene by name (`"triggered_front"`);
    /// None: the built-in default scene (Table S1 stick-slip). `set`
    /// overrides keys as `--set` does: `{"loading.drive.velocity": 4e-4}`.
    #[staticmethod]
    #[pyo3(signature = (path_or_name=None, set=None))]
    fn load(path_or_name: Option<PathBuf>, set: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let overrides = convert::overrides(set)?;
        let Some(name) = path_or_name else {
            return Ok(Scenario {
                inner: scene::Scenario::parse(DEFAULT_SCENARIO, DEFAULT_SCENARIO_NAME, &overrides)
                    .map_err(invalid)?,
                source: DEFAULT_SCENARIO_NAME.into(),
            });
        };
        let path = name.as_path();
        let name = path.display().to_string();
        if path.exists() {
            return Ok(Scenario {
                inner: scene::Scenario::load(path, &overrides).map_err(invalid)?,
                source: name,
            });
        }
        match scene::built_in(&name) {
            Some(text) => {
                let source = format!("{name} (built in)");
                Ok(Scenario {
                    inner: scene::Scenario::parse(text, &source, &overrides).map_err(invalid)?,
                    source,
                })
            }
            None => Err(PyFileNotFoundError::new_err(format!(
                "no scenario file `{name}`, and no shipped scenario of that name (shipped: {})",
                built_in_names().join(", ")
            ))),
        }
    }

    /// A scenario from TOML text.
    #[staticmethod]
    #[pyo3(signature = (text, set=None, name="<text>"))]
    fn from_toml(text: &str, set: Option<&Bound<'_, PyDict>>, name: &str) -> PyResult<Self> {
        Ok(Scenario {
            inner: scene::Scenario::parse(text, name, &convert::overrides(set)?)
                .map_err(invalid)?,
            source: name.into(),
        })
    }

    /// This scenario with more keys overridden (validated again).
    fn with_set(&self, set: &Bound<'_, PyDict>) -> PyResult<Self> {
        Ok(Scenario {
            inner: scene::Scenario::parse(
                &self.inner.to_toml(),
                &self.source,
                &convert::overrides(Some(set))?,
            )
            .map_err(invalid)?,
            source: self.source.clone(),
        })
    }

    /// The canonical TOML text (what a run file stores).
    fn to_toml(&self) -> String {
        self.inner.to_toml()
    }

    /// The value of a dotted key (`"geometry.nx"`); KeyError if unset.
    fn get<'py>(&self, py: Python<'py>, key: &str) -> PyResult<Bound<'py, PyAny>> {
        let table: toml::Table = toml::from_str(&self.inner.to_toml())
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        let mut node = &toml::Value::Table(table);
        for part in key.split('.') {
            node = node
                .get(part)
                .ok_or_else(|| PyKeyError::new_err(format!("{key}: not set in this scenario")))?;
        }
        convert::from_toml(py, node)
    }

    /// The scenario's name (`name = ...` in the file).
    #[getter]
    fn name(&self) -> String {
        self.inner.name.clone()
    }

    /// Blocks along the interface and rows, (nx, nz).
    #[getter]
    fn shape(&self) -> (u32, u32) {
        (self.inner.geometry.nx, self.inner.geometry.nz)
    }

    /// The derived model: time step, steps, lattice spacing, wave speeds,
    /// mass, stiffnesses, normal force (SI units), as the engines use them.
    fn model<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let m = Model::from_scenario(&self.inner, true)
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        let d = PyDict::new(py);
        d.set_item("nx", m.nx)?;
        d.set_item("nz", m.nz)?;
        d.set_item("dt", m.dt)?;
        d.set_item("spacing", m.spacing)?;
        d.set_item("mass", m.mass)?;
        d.set_item("k", m.k)?;
        d.set_item("normal_force", m.normal_force)?;
        d.set_item("junctions_per_block", m.junctions.map_or(0, |j| j.count))?;
        d.set_item("normal_load_steps", m.prep_steps)?;
        d.set_item("drive_steps", m.drive_steps)?;
        d.set_item("total_steps", m.total_steps())?;
        d.set_item("t_end", m.time_of_step(m.total_steps()))?;
        d.set_item("shear_wave_speed", m.shear_wave_speed())?;
        d.set_item("pressure_wave_speed", m.pressure_wave_speed())?;
        d.set_item("seed", m.seed)?;
        Ok(d)
    }

    fn __repr__(&self) -> String {
        format!(
            "Scenario({:?} from {}, {} x {} blocks, t_end {:e} s)",
            self.inner.name,
            self.source,
            self.inner.geometry.nx,
            self.inner.geometry.nz,
            self.inner.time.end
        )
    }

    fn __eq__(&self, other: &Self) -> bool {
        self.inner == other.inner
    }
}
