//! The tables of numbers of a scene given as arrays (`Scene.from_dict`'s mesh
//! `points`, `cells` and `node_sets`, a body's `initial_velocity` and
//! `initial_displacement`): their shapes and dtypes checked, and each copied in one pass
//! into the library's flat `Rows`, from a numpy array or a list of rows, every value
//! checked (a finite real number, or a point index ≥ 0) and named `path[r][c]` otherwise.

use std::fmt::Display;

use numpy::{
    PyArray1, PyArray2, PyArrayDescrMethods, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods,
};
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt};
use signorini::scene::file::Rows;

use super::*;
use crate::toml_values::{at, bad, echo, is_list, numpy_scalar, shape_text};

/// What a table of numbers holds, for the checks and messages.
#[derive(Clone, Copy)]
enum Values {
    /// Finite real numbers, in this unit.
    Real(&'static str),
    /// Point indices (0-based, into `mesh.points`).
    Index,
}

impl Values {
    fn expected(self) -> String {
        match self {
            Values::Real(unit) => format!("a finite real number ({unit})"),
            Values::Index => "a point index: an integer ≥ 0 (0-based, into mesh.points)".into(),
        }
    }
}

/// A number of a table from a Python object (`path` names it).
fn real(obj: &Bound<'_, PyAny>, path: &str, unit: &'static str) -> PyResult<f64> {
    let expected = Values::Real(unit).expected();
    if obj.is_instance_of::<PyBool>() {
        return Err(bad(path, echo(obj), &format!("{expected}, not a bool")));
    }
    if obj.is_instance_of::<PyFloat>() || obj.is_instance_of::<PyInt>() {
        let x: f64 = obj.extract().map_err(|_| bad(path, echo(obj), &expected))?;
        if x.is_finite() {
            return Ok(x);
        }
        return Err(bad(path, x, &expected));
    } else if let Some(x) = numpy_scalar(obj)? {
        return real(&x, path, unit);
    }
    Err(bad(path, echo(obj), &expected))
}

/// A point index from a Python object (`path` names it).
fn index(obj: &Bound<'_, PyAny>, path: &str) -> PyResult<usize> {
    let expected = Values::Index.expected();
    if obj.is_instance_of::<PyBool>() {
        return Err(bad(path, echo(obj), &format!("{expected}, not a bool")));
    }
    if obj.is_instance_of::<PyInt>() {
        if let Ok(i) = obj.extract::<usize>() {
            return Ok(i);
        }
    } else if let Some(x) = numpy_scalar(obj)? {
        return index(&x, path);
    }
    Err(bad(path, echo(obj), &expected))
}

/// The items of a list, a tuple or a 1-D array given as a row (`path` names it).
fn row_items<'py>(obj: &Bound<'py, PyAny>, path: &str) -> PyResult<Vec<Bound<'py, PyAny>>> {
    let obj = if obj.cast::<PyUntypedArray>().is_ok() {
        obj.call_method0("tolist")?
    } else {
        obj.clone()
    };
    if !is_list(&obj) {
        return Err(bad(path, echo(&obj), "a row: a list of numbers"));
    }
    obj.try_iter()?.collect()
}

/// The shape of a table given as a numpy array or a list of rows: rows, and the
/// length of the first row (the memory estimate's; the rows are checked one by one
/// when copied).
pub(crate) fn shape(obj: &Bound<'_, PyAny>, path: &str, ndim: usize) -> PyResult<(usize, usize)> {
    if let Ok(a) = obj.cast::<PyUntypedArray>() {
        let s = a.shape();
        if s.len() != ndim || (ndim == 2 && s[1] == 0 && s[0] > 0) {
            return Err(bad(
                path,
                format!("an array of shape {}", shape_text(s)),
                if ndim == 2 {
                    "a 2-D array, one row per point, node or cell"
                } else {
                    "a 1-D array of point indices"
                },
            ));
        }
        return Ok((s[0], if ndim == 2 { s[1] } else { 1 }));
    }
    if !is_list(obj) {
        return Err(bad(
            path,
            echo(obj),
            if ndim == 2 {
                "a numpy array or a list of rows"
            } else {
                "a numpy array or a list of point indices"
            },
        ));
    }
    let n = obj.len()?;
    let width = if ndim == 2 && n > 0 {
        obj.get_item(0)?.len().unwrap_or(0)
    } else {
        1
    };
    Ok((n, width))
}

/// A numpy array's dtype refused for what a table holds.
fn bad_dtype(path: &str, a: &Bound<'_, PyUntypedArray>, what: Values) -> PyErr {
    bad(
        path,
        format!("an array of dtype {}", a.dtype()),
        &match what {
            Values::Real(unit) => format!("real numbers ({unit}): a float or integer dtype"),
            Values::Index => "point indices: an integer dtype such as int64".to_string(),
        },
    )
}

/// A numpy array (2-D, or 1-D for `ndim` 1) as `f64` values row after row and its
/// width, each value checked finite; its `path[r][c]` named otherwise.
fn real_array(
    obj: &Bound<'_, PyAny>,
    a: &Bound<'_, PyUntypedArray>,
    path: &str,
    unit: &'static str,
) -> PyResult<Rows<f64>> {
    let width = a.shape()[1];
    let typed = match a.dtype().kind() {
        b'f' | b'i' | b'u' => {
            if a.dtype().is_equiv_to(&numpy::dtype::<f64>(obj.py())) {
                obj.clone()
            } else {
                obj.call_method1("astype", ("float64",))?
            }
        }
        _ => return Err(bad_dtype(path, a, Values::Real(unit))),
    };
    let arr = typed.cast::<PyArray2<f64>>()?.readonly();
    let view = arr.as_array();
    // row after row: one copy of a C-ordered array, a walk in logical order of any
    // other (numpy's `as_slice` would give a Fortran-ordered array in its memory order)
    let data: Vec<f64> = match view.as_slice() {
        Some(s) => s.to_vec(),
        None => view.iter().copied().collect(),
    };
    if let Some(k) = data.iter().position(|x| !x.is_finite()) {
        return Err(bad(
            &format!("{path}[{}][{}]", k / width, k % width),
            data[k],
            &Values::Real(unit).expected(),
        ));
    }
    Rows::from_flat(data, width).map_err(py_err)
}

/// A numpy integer array of any dimension as point indices row after row, each checked
/// ≥ 0 and named `path[r][c]` (`path[r]` in 1-D) otherwise.
fn index_array(
    obj: &Bound<'_, PyAny>,
    a: &Bound<'_, PyUntypedArray>,
    path: &str,
) -> PyResult<Vec<usize>> {
    let width = if a.ndim() == 2 { a.shape()[1] } else { 1 };
    let name = |k: usize| {
        if a.ndim() == 2 {
            format!("{path}[{}][{}]", k / width, k % width)
        } else {
            at(path, k)
        }
    };
    let flat = obj.call_method0("ravel")?;
    // no copy of an array that has the dtype already
    let no_copy = PyDict::new(obj.py());
    no_copy.set_item("copy", false)?;
    // signed and unsigned arrays alike: each value checked into a point index
    fn indices<T>(
        flat: &Bound<'_, PyAny>,
        dtype: &str,
        no_copy: &Bound<'_, PyDict>,
        name: impl Fn(usize) -> String,
    ) -> PyResult<Vec<usize>>
    where
        T: numpy::Element + Copy + Display,
        usize: TryFrom<T>,
    {
        let typed = flat.call_method("astype", (dtype,), Some(no_copy))?;
        let arr = typed.cast::<PyArray1<T>>()?.readonly();
        let view = arr.as_array();
        let mut out = Vec::with_capacity(view.len());
        for (k, &v) in view.iter().enumerate() {
            out.push(usize::try_from(v).map_err(|_| bad(&name(k), v, &Values::Index.expected()))?);
        }
        Ok(out)
    }
    match a.dtype().kind() {
        b'i' => indices::<i64>(&flat, "int64", &no_copy, name),
        b'u' => indices::<u64>(&flat, "uint64", &no_copy, name),
        _ => Err(bad_dtype(path, a, Values::Index)),
    }
}

/// A table of real numbers (`unit`) from a numpy array or a list of rows.
pub(crate) fn real_rows(
    obj: &Bound<'_, PyAny>,
    path: &str,
    unit: &'static str,
) -> PyResult<Rows<f64>> {
    shape(obj, path, 2)?;
    if let Ok(a) = obj.cast::<PyUntypedArray>() {
        return real_array(obj, a, path, unit);
    }
    let mut rows = Vec::new();
    for (r, row) in obj.try_iter()?.enumerate() {
        let p = at(path, r);
        let row = row_items(&row?, &p)?;
        rows.push(
            row.iter()
                .enumerate()
                .map(|(c, x)| real(x, &at(&p, c), unit))
                .collect::<PyResult<Vec<f64>>>()?,
        );
    }
    Ok(Rows::from_rows(rows))
}

/// A table of point indices (cells) from a numpy array or a list of rows.
pub(crate) fn index_rows(obj: &Bound<'_, PyAny>, path: &str) -> PyResult<Rows<usize>> {
    let (_, width) = shape(obj, path, 2)?;
    if let Ok(a) = obj.cast::<PyUntypedArray>() {
        return Rows::from_flat(index_array(obj, a, path)?, width).map_err(py_err);
    }
    let mut rows = Vec::new();
    for (r, row) in obj.try_iter()?.enumerate() {
        let p = at(path, r);
        let row = row_items(&row?, &p)?;
        rows.push(
            row.iter()
                .enumerate()
                .map(|(c, x)| index(x, &at(&p, c)))
                .collect::<PyResult<Vec<usize>>>()?,
        );
    }
    Ok(Rows::from_rows(rows))
}

/// A list of point indices (a node set) from a 1-D numpy array or a list.
pub(crate) fn index_list(obj: &Bound<'_, PyAny>, path: &str) -> PyResult<Vec<usize>> {
    shape(obj, path, 1)?;
    if let Ok(a) = obj.cast::<PyUntypedArray>() {
        return index_array(obj, a, path);
    }
    obj.try_iter()?
        .enumerate()
        .map(|(i, x)| index(&x?, &at(path, i)))
        .collect()
}
