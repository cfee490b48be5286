//! `slipfront._core`: the compiled half of the Python package. The Python
//! layer (`python/slipfront/`) builds `run`, `open`, `Run`, `Simulation`
//! and `sweep` on these functions; the `.pyi` stub beside it documents
//! each for a type checker.

mod convert;
mod reading;
mod running;
mod scenario;
mod simulation;
mod sweeping;
mod watch;

use pyo3::create_exception;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;

create_exception!(
    _core,
    BlowUp,
    PyRuntimeError,
    "A run blew up: the message names the step, the time and the block."
);

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // Ctrl-C stays Python's: runs check Python's signals between chunks
    // (`watch`) instead of installing handlers of their own.
    slipfront::app::runner::leave_signals_to_host();
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("BlowUp", m.py().get_type::<BlowUp>())?;
    m.add_class::<scenario::Scenario>()?;
    m.add_class::<simulation::Simulation>()?;
    m.add_function(wrap_pyfunction!(scenario::built_in_names, m)?)?;
    m.add_function(wrap_pyfunction!(reading::read_run, m)?)?;
    m.add_function(wrap_pyfunction!(reading::event_table, m)?)?;
    m.add_function(wrap_pyfunction!(running::run_scene, m)?)?;
    m.add_function(wrap_pyfunction!(sweeping::run_sweep, m)?)?;
    Ok(())
}

/// A value of one of slipfront's option enums from its CLI spelling
/// (`backend="cpu-reference"`), or a ValueError naming the choices.
pub(crate) fn choice<T: clap::ValueEnum>(field: &str, value: &str) -> PyResult<T> {
    T::from_str(value, true).map_err(|_| {
        let names: Vec<String> = T::value_variants()
            .iter()
            .filter_map(|v| v.to_possible_value())
            .map(|p| p.get_name().to_string())
            .collect();
        PyValueError::new_err(format!(
            "{field} = {value:?}: expected one of {}",
            names.join(", ")
        ))
    })
}

/// An engine error as Python sees it: a blow-up is [`BlowUp`], bad input
/// a ValueError, anything else a RuntimeError.
pub(crate) fn engine_error(e: slipfront::EngineError) -> PyErr {
    use slipfront::EngineError;
    match e {
        EngineError::BlowUp { .. } => BlowUp::new_err(e.to_string()),
        EngineError::State(_) => PyValueError::new_err(e.to_string()),
        _ => PyRuntimeError::new_err(e.to_string()),
    }
}
