//! A Python dict as the scene file's TOML: the same loader then reads it, so a dict
//! and a file give the same scene and the same one-line errors naming the key path.

use crate::errors::SceneError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

/// `value` (dicts, lists or tuples, numpy arrays, str, bool, int, float) as a TOML
/// value; `at` is its key path, for the message when a value has no TOML form.
pub fn to_toml(value: &Bound<'_, PyAny>, at: &str) -> PyResult<toml::Value> {
    // bool before int: Python's bool is an int.
    if let Ok(b) = value.cast::<PyBool>() {
        return Ok(toml::Value::Boolean(b.is_true()));
    }
    if value.is_instance_of::<PyInt>() {
        return match value.extract::<i64>() {
            Ok(i) => Ok(toml::Value::Integer(i)),
            Err(_) => Err(not_toml(at, "integer out of TOML's 64-bit range")),
        };
    }
    if let Ok(f) = value.cast::<PyFloat>() {
        return Ok(toml::Value::Float(f.value()));
    }
    if let Ok(s) = value.cast::<PyString>() {
        return Ok(toml::Value::String(s.extract::<String>()?));
    }
    if let Ok(d) = value.cast::<PyDict>() {
        return table(d, at).map(toml::Value::Table);
    }
    if value.is_instance_of::<PyList>() || value.is_instance_of::<PyTuple>() {
        let items = value.try_iter()?;
        let mut array = Vec::new();
        for (i, item) in items.enumerate() {
            array.push(to_toml(&item?, &format!("{at}[{i}]"))?);
        }
        return Ok(toml::Value::Array(array));
    }
    // numpy arrays and scalars: as their Python lists and numbers.
    if value.hasattr("__array__")? && value.hasattr("tolist")? {
        let plain = value.call_method0("tolist")?;
        if !plain.hasattr("__array__")? {
            return to_toml(&plain, at);
        }
    }
    // Other integers by `__index__`, the rest by what float() accepts.
    if let Ok(i) = value.extract::<i64>() {
        return Ok(toml::Value::Integer(i));
    }
    if let Ok(f) = value.extract::<f64>() {
        return Ok(toml::Value::Float(f));
    }
    let kind = value.get_type().name()?.to_string();
    Err(not_toml(at, &format!("a {kind} has no TOML form")))
}

/// A dict with string keys as a TOML table.
pub fn table(d: &Bound<'_, PyDict>, at: &str) -> PyResult<toml::Table> {
    let mut t = toml::Table::new();
    for (k, v) in d.iter() {
        let Ok(key) = k.extract::<String>() else {
            return Err(not_toml(at, "keys must be strings"));
        };
        let path = if at.is_empty() {
            key.clone()
        } else {
            format!("{at}.{key}")
        };
        t.insert(key, to_toml(&v, &path)?);
    }
    Ok(t)
}

fn not_toml(at: &str, why: &str) -> PyErr {
    let at = if at.is_empty() { "scene" } else { at };
    SceneError::new_err(format!("{at}: {why}"))
}

/// One step of a key path as messages write it: `lights[0].flux_lm` is
/// `Key("lights")`, `Index(0)`, `Key("flux_lm")`.
#[derive(Debug, PartialEq)]
pub enum Step {
    Key(String),
    Index(usize),
}

/// `materials.wall.reflectance`, `lights[1].flux_lm` into steps; `None` if malformed.
pub fn parse_path(path: &str) -> Option<Vec<Step>> {
    let mut steps = Vec::new();
    for part in path.split('.') {
        let (key, mut rest) = part.split_once('[').map_or((part, ""), |(k, r)| (k, r));
        if key.is_empty() {
            return None;
        }
        steps.push(Step::Key(key.to_string()));
        while !rest.is_empty() {
            let (index, after) = rest.split_once(']')?;
            steps.push(Step::Index(index.parse().ok()?));
            rest = after.strip_prefix('[').unwrap_or(after);
            if !after.is_empty() && !after.starts_with('[') {
                return None;
            }
        }
    }
    Some(steps)
}

/// Replaces (or adds) the value at `steps` in `doc`; false when the path's parent does
/// not exist (a table or array entry of the scene file).
pub fn set_at(doc: &mut toml::Table, steps: &[Step], new: toml::Value) -> bool {
    let Some((last, parents)) = steps.split_last() else {
        return false;
    };
    let Some((Step::Key(first), rest)) = parents.split_first() else {
        return false;
    };
    let Some(mut value) = doc.get_mut(first) else {
        return false;
    };
    for step in rest {
        let next = match step {
            Step::Key(k) => value.as_table_mut().and_then(|t| t.get_mut(k)),
            Step::Index(i) => value.as_array_mut().and_then(|a| a.get_mut(*i)),
        };
        let Some(next) = next else {
            return false;
        };
        value = next;
    }
    match (last, value) {
        (Step::Key(k), toml::Value::Table(t)) => {
            t.insert(k.clone(), new);
            true
        }
        (Step::Index(i), toml::Value::Array(a)) if *i < a.len() => {
            a[*i] = new;
            true
        }
        _ => false,
    }
}
