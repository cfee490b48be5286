//! Python values to and from TOML values: the `set={...}` overrides of a
//! scenario and the points of a sweep are TOML values, as in the files.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

/// A Python value as TOML: bool, int, float, str, a list or tuple of them,
/// or a dict (an inline table).
pub fn to_toml(key: &str, value: &Bound<'_, PyAny>) -> PyResult<toml::Value> {
    // bool before int: a Python bool is an int.
    if value.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(value.extract()?));
    }
    if value.is_instance_of::<PyInt>() {
        return value
            .extract::<i64>()
            .map(toml::Value::Integer)
            .map_err(|_| {
                PyValueError::new_err(format!(
                    "{key} = {value}: an integer out of TOML's 64-bit range"
                ))
            });
    }
    if value.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(value.extract()?));
    }
    if value.is_instance_of::<PyString>() {
        return Ok(toml::Value::String(value.extract()?));
    }
    if value.is_instance_of::<PyList>() || value.is_instance_of::<PyTuple>() {
        return value
            .try_iter()?
            .map(|v| to_toml(key, &v?))
            .collect::<PyResult<Vec<_>>>()
            .map(toml::Value::Array);
    }
    if let Ok(d) = value.cast::<PyDict>() {
        let mut table = toml::Table::new();
        for (k, v) in d.iter() {
            let k: String = k.extract()?;
            let inner = to_toml(&format!("{key}.{k}"), &v)?;
            table.insert(k, inner);
        }
        return Ok(toml::Value::Table(table));
    }
    // numpy scalars and other numbers: as a float if they convert.
    if let Ok(f) = value.extract::<f64>() {
        return Ok(toml::Value::Float(f));
    }
    Err(PyValueError::new_err(format!(
        "{key} = {}: expected a bool, int, float, str, list or dict",
        value.repr().map_or("?".into(), |r| r.to_string())
    )))
}

/// `{"loading.drive.velocity": 4e-4}` as the CLI's `--set` items.
pub fn overrides(set: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<String>> {
    let Some(set) = set else {
        return Ok(Vec::new());
    };
    set.iter()
        .map(|(k, v)| {
            let key: String = k
                .extract()
                .map_err(|_| PyValueError::new_err(format!("set: the key {k} is not a string")))?;
            Ok(format!("{key}={}", to_toml(&key, &v)?))
        })
        .collect()
}

/// A TOML value as a Python value.
pub fn from_toml<'py>(py: Python<'py>, value: &toml::Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match value {
        toml::Value::String(s) => s.into_pyobject(py)?.into_any(),
        toml::Value::Integer(i) => i.into_pyobject(py)?.into_any(),
        toml::Value::Float(f) => f.into_pyobject(py)?.into_any(),
        toml::Value::Boolean(b) => b.into_pyobject(py)?.to_owned().into_any(),
        toml::Value::Datetime(d) => d.to_string().into_pyobject(py)?.into_any(),
        toml::Value::Array(a) => {
            let items = a
                .iter()
                .map(|v| from_toml(py, v))
                .collect::<PyResult<Vec<_>>>()?;
            PyList::new(py, items)?.into_any()
        }
        toml::Value::Table(t) => {
            let d = PyDict::new(py);
            for (k, v) in t {
                d.set_item(k, from_toml(py, v)?)?;
            }
            d.into_any()
        }
    })
}
