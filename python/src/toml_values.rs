//! A Python value as a TOML value (issue 48's `Scene.from_dict`, no text): each bool,
//! number, string, list and dict of a scene's tables is walked into a `toml::Value`,
//! each number checked on the way (finite, real, at most 64 bits) and named by its key
//! path; a numpy scalar, a small numpy array and a path-like are taken as their Python
//! values. Also the words of the messages every part of `from_dict` shares: `bad` (the
//! library's `invalid value for …`), `echo` (a value cut to a line), `at` / `dot` (key
//! paths) and `shape_text` (a shape as Python writes it).

use std::fmt::Display;

use numpy::{PyUntypedArray, PyUntypedArrayMethods};
use pyo3::types::{
    PyBool, PyComplex, PyDict, PyFloat, PyInt, PyList, PyMapping, PyString, PyTuple,
};

use super::*;

/// Most values of a numpy array taken as a list (`probes.times`, a force's time
/// points); the large arrays of a scene are its mesh's and fields', taken as arrays.
const MAX_LISTED: usize = 1 << 20;

/// The longest echo of a value in a message.
const MAX_ECHO: usize = 60;

/// `invalid value for `path`: value (expected)`, as the library words it.
pub(crate) fn bad(path: &str, value: impl Display, expected: &str) -> PyErr {
    BadInput::new_err(format!("invalid value for `{path}`: {value} ({expected})"))
}

/// A Python value as a message shows it: its `repr`, cut to a line.
pub(crate) fn echo(obj: &Bound<'_, PyAny>) -> String {
    let r = obj
        .repr()
        .map(|r| r.to_string())
        .unwrap_or_else(|_| "(a value without repr)".to_string());
    if r.chars().count() > MAX_ECHO {
        format!("{}…", r.chars().take(MAX_ECHO).collect::<String>())
    } else {
        r
    }
}

/// A numpy scalar (`np.int64(3)`, `np.bool_(True)`): its Python value.
pub(crate) fn numpy_scalar<'py>(obj: &Bound<'py, PyAny>) -> PyResult<Option<Bound<'py, PyAny>>> {
    let t = obj.get_type();
    let module = t.getattr("__module__")?.to_string();
    if module == "numpy" && obj.hasattr("item")? && obj.hasattr("dtype")? {
        Ok(Some(obj.call_method0("item")?))
    } else {
        Ok(None)
    }
}

/// `key[i]`.
pub(crate) fn at(path: &str, i: usize) -> String {
    format!("{path}[{i}]")
}

/// `path.key` (`key` at the top level).
pub(crate) fn dot(path: &str, key: &str) -> String {
    if path.is_empty() {
        key.to_string()
    } else {
        format!("{path}.{key}")
    }
}

/// A mapping's items, keys checked to be strings.
pub(crate) fn items<'py>(
    obj: &Bound<'py, PyAny>,
    path: &str,
) -> PyResult<Vec<(String, Bound<'py, PyAny>)>> {
    let list = if let Ok(d) = obj.cast::<PyDict>() {
        d.items()
    } else {
        obj.cast::<PyMapping>()?.items()?
    };
    let mut out = Vec::with_capacity(list.len());
    for kv in list.iter() {
        let (k, v): (Bound<'py, PyAny>, Bound<'py, PyAny>) = kv.extract()?;
        let key = k
            .cast::<PyString>()
            .map_err(|_| {
                bad(
                    &dot(path, &echo(&k)),
                    echo(&k),
                    "a key of a scene's table is a string",
                )
            })?
            .to_string();
        out.push((key, v));
    }
    Ok(out)
}

pub(crate) fn is_mapping(obj: &Bound<'_, PyAny>) -> bool {
    obj.is_instance_of::<PyDict>() || obj.cast::<PyMapping>().is_ok()
}

pub(crate) fn is_list(obj: &Bound<'_, PyAny>) -> bool {
    obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>()
}

/// A mapping's values as a TOML table: `None` values are left out (an absent key, as
/// in a scene file).
fn table(obj: &Bound<'_, PyAny>, path: &str) -> PyResult<toml::Table> {
    let mut t = toml::Table::new();
    for (k, v) in items(obj, path)? {
        if v.is_none() {
            continue;
        }
        let p = dot(path, &k);
        t.insert(k, value(&v, &p)?);
    }
    Ok(t)
}

/// A Python value as a TOML value, refused with its key path where a scene file could
/// not hold it: a non-finite or complex number, `None` in a list, an integer past 64
/// bits, another type.
pub(crate) fn value(obj: &Bound<'_, PyAny>, path: &str) -> PyResult<toml::Value> {
    if let Ok(b) = obj.cast::<PyBool>() {
        return Ok(toml::Value::Boolean(b.extract()?));
    }
    if obj.is_instance_of::<PyInt>() {
        return obj.extract::<i64>().map(toml::Value::Integer).map_err(|_| {
            bad(
                path,
                echo(obj),
                "an integer of at most 64 bits (a scene file's integers)",
            )
        });
    }
    if obj.is_instance_of::<PyFloat>() {
        let x: f64 = obj.extract()?;
        if !x.is_finite() {
            return Err(bad(path, x, "a finite number"));
        }
        return Ok(toml::Value::Float(x));
    }
    if let Ok(s) = obj.cast::<PyString>() {
        return Ok(toml::Value::String(s.to_string()));
    }
    if obj.is_instance_of::<PyComplex>() {
        return Err(bad(
            path,
            echo(obj),
            "a real number; complex numbers are not taken",
        ));
    }
    if is_mapping(obj) {
        return table(obj, path).map(toml::Value::Table);
    }
    if is_list(obj) {
        let mut a = Vec::new();
        for (i, x) in obj.try_iter()?.enumerate() {
            let x = x?;
            let p = at(path, i);
            if x.is_none() {
                return Err(bad(
                    &p,
                    "None",
                    "a value (None stands for an absent key, in a dict only)",
                ));
            }
            a.push(value(&x, &p)?);
        }
        return Ok(toml::Value::Array(a));
    }
    if let Ok(arr) = obj.cast::<PyUntypedArray>() {
        if arr.len() > MAX_LISTED {
            return Err(bad(
                path,
                format!("an array of shape {}", shape_text(arr.shape())),
                &format!(
                    "a list of at most {MAX_LISTED} values here: arrays are taken whole as a \
                     mesh's points, cells and node_sets (generator = \"arrays\") and as \
                     initial_velocity or initial_displacement"
                ),
            ));
        }
        return value(&obj.call_method0("tolist")?, path);
    }
    if let Some(x) = numpy_scalar(obj)? {
        return value(&x, path);
    }
    if obj.hasattr("__fspath__")? {
        return value(&obj.call_method0("__fspath__")?, path);
    }
    Err(bad(
        path,
        echo(obj),
        &format!(
            "a bool, number, string, list or dict, not a value of type {}",
            obj.get_type().name()?
        ),
    ))
}

/// `(3, 8)` as Python writes a shape.
pub(crate) fn shape_text(s: &[usize]) -> String {
    match s {
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            s.iter()
                .map(|x| x.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}
