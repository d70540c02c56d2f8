//! Values between Python and the harness: JSON values (summaries, details)
//! to Python objects, Python objects to TOML (scenario dicts, `replace`).

use anholonomy::scenario::keypath::toml_number;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

/// A JSON value as a Python object (objects keep their key order).
pub fn json_to_py<'py>(py: Python<'py>, v: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    use serde_json::Value;
    Ok(match v {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        Value::Number(n) => match (n.as_i64(), n.as_u64()) {
            (Some(i), _) => i.into_pyobject(py)?.into_any(),
            (None, Some(u)) => u.into_pyobject(py)?.into_any(),
            _ => PyFloat::new(py, n.as_f64().unwrap_or(f64::NAN)).into_any(),
        },
        Value::String(s) => PyString::new(py, s).into_any(),
        Value::Array(a) => {
            let items = a
                .iter()
                .map(|x| json_to_py(py, x))
                .collect::<PyResult<Vec<_>>>()?;
            PyList::new(py, items)?.into_any()
        }
        Value::Object(m) => {
            let d = PyDict::new(py);
            for (k, x) in m {
                d.set_item(k, json_to_py(py, x)?)?;
            }
            d.into_any()
        }
    })
}

/// A Python value as a TOML value: bool, int, float, str (or a path), a
/// mapping (table) or a sequence / numpy array (array). `key` names it in
/// errors.
pub fn py_to_toml(v: &Bound<'_, PyAny>, key: &str) -> PyResult<toml::Value> {
    let bad = |what: String| PyTypeError::new_err(format!("key `{key}`: {what}"));
    if v.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(v.extract()?));
    }
    if v.is_instance_of::<PyInt>() {
        return v.extract::<i64>().map(toml::Value::Integer).map_err(|_| {
            // Its size, not its hundreds of digits.
            let size = v
                .extract::<f64>()
                .map(anholonomy::numfmt::readable)
                .unwrap_or_else(|_| "an integer".into());
            bad(format!("{size} does not fit in a 64-bit integer"))
        });
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(v.extract()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(toml::Value::String(v.extract()?));
    }
    if v.hasattr("__fspath__")? {
        let s = v.call_method0("__fspath__")?;
        return Ok(toml::Value::String(
            s.extract()
                .map_err(|_| bad("a path that is not text".into()))?,
        ));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        let mut t = toml::Table::new();
        for (k, x) in d.iter() {
            let k: String = k
                .extract()
                .map_err(|_| bad(format!("table keys must be strings, not {k}")))?;
            let sub = if key.is_empty() {
                k.clone()
            } else {
                format!("{key}.{k}")
            };
            t.insert(k, py_to_toml(&x, &sub)?);
        }
        return Ok(toml::Value::Table(t));
    }
    // numpy scalars: integers have __index__, floats __float__.
    if v.hasattr("__index__")? && !v.hasattr("__len__")? {
        return Ok(toml::Value::Integer(v.extract()?));
    }
    let items: Vec<Bound<'_, PyAny>> =
        if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
            v.try_iter()?.collect::<PyResult<_>>()?
        } else if v.hasattr("tolist")? {
            // numpy arrays and scalars: their Python values.
            let l = v.call_method0("tolist")?;
            if !l.is_instance_of::<PyList>() {
                return py_to_toml(&l, key);
            }
            l.try_iter()?.collect::<PyResult<_>>()?
        } else if v.hasattr("__float__")? {
            return Ok(toml::Value::Float(v.extract()?));
        } else {
            return Err(bad(format!(
                "{} is not a TOML value (use bool, int, float, str, dict or a sequence)",
                v.get_type().name()?
            )));
        };
    let mut out = Vec::with_capacity(items.len());
    for (i, x) in items.iter().enumerate() {
        out.push(py_to_toml(x, &format!("{key}[{i}]"))?);
    }
    Ok(toml::Value::Array(out))
}

/// A TOML value as text for [`anholonomy::scenario::Scenario::replace`]:
/// numbers exactly (floats that are whole numbers as floats, so a float key
/// stays a float), the rest as TOML writes them inline.
pub fn toml_text(v: &toml::Value) -> String {
    match v {
        // `3.0`, not `3`: a float stays a float (the key's type is the caller's).
        toml::Value::Float(x) if x.fract() == 0.0 && x.abs() < 9.0e15 => {
            format!("{}.0", *x as i64)
        }
        toml::Value::Float(x) if x.is_nan() => "nan".into(),
        toml::Value::Float(x) if x.is_infinite() => if *x > 0.0 { "inf" } else { "-inf" }.into(),
        toml::Value::Float(x) => toml_number(*x),
        toml::Value::Array(a) => {
            let items: Vec<String> = a.iter().map(toml_text).collect();
            format!("[{}]", items.join(", "))
        }
        other => other.to_string(),
    }
}
