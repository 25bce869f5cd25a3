//! A scene from Python data with no text (issue 48): the dict of a scene's tables is
//! walked into TOML values (`toml::Table`, each number checked on the way and named by
//! its key path), and read by the library's `Scene::from_table` as a scene file is. The
//! arrays of a mesh given as arrays (`points`, `cells`, `node_sets`) and the per-node
//! fields (`initial_velocity`, `initial_displacement`) are set aside: their shapes and
//! dtypes are checked, the memory they lead to is compared with the memory limit, and
//! only then is each copied, in one pass, into the library's flat tables (`Rows`).
//!
//! Before, the dict went dict → JSON → TOML text → parse: a 10⁷-point mesh under a
//! 256 MiB limit aborted the interpreter after 38 s at 7.2 GB in the TOML parser, the
//! limit checked only once the mesh had been parsed.

use std::collections::BTreeMap;
use std::fmt::Display;

use numpy::{
    PyArray1, PyArray2, PyArrayDescrMethods, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods,
};
use pyo3::types::{
    PyBool, PyComplex, PyDict, PyFloat, PyInt, PyList, PyMapping, PyString, PyTuple,
};
use signorini::model::solid::CellKind;
use signorini::scene::file::{MeshSpec, NodalField, Rows, arrays_memory};

use super::*;

/// Most values of a numpy array taken as a list (`probes.times`, a force's time
/// points); the large arrays of a scene are its mesh's and fields', taken as arrays.
const MAX_LISTED: usize = 1 << 20;

/// The longest echo of a value in a message.
const MAX_ECHO: usize = 60;

/// `invalid value for `path`: value (expected)`, as the library words it.
fn bad(path: &str, value: impl Display, expected: &str) -> PyErr {
    BadInput::new_err(format!("invalid value for `{path}`: {value} ({expected})"))
}

/// A Python value as a message shows it: its `repr`, cut to a line.
fn echo(obj: &Bound<'_, PyAny>) -> String {
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
fn numpy_scalar<'py>(obj: &Bound<'py, PyAny>) -> PyResult<Option<Bound<'py, PyAny>>> {
    let t = obj.get_type();
    let module = t.getattr("__module__")?.to_string();
    if module == "numpy" && obj.hasattr("item")? && obj.hasattr("dtype")? {
        Ok(Some(obj.call_method0("item")?))
    } else {
        Ok(None)
    }
}

/// `key[i]`.
fn at(path: &str, i: usize) -> String {
    format!("{path}[{i}]")
}

/// `path.key` (`key` at the top level).
fn dot(path: &str, key: &str) -> String {
    if path.is_empty() {
        key.to_string()
    } else {
        format!("{path}.{key}")
    }
}

/// A mapping's items, keys checked to be strings.
fn items<'py>(obj: &Bound<'py, PyAny>, path: &str) -> PyResult<Vec<(String, Bound<'py, PyAny>)>> {
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

fn is_mapping(obj: &Bound<'_, PyAny>) -> bool {
    obj.is_instance_of::<PyDict>() || obj.cast::<PyMapping>().is_ok()
}

fn is_list(obj: &Bound<'_, PyAny>) -> bool {
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
fn value(obj: &Bound<'_, PyAny>, path: &str) -> PyResult<toml::Value> {
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
fn shape(obj: &Bound<'_, PyAny>, path: &str, ndim: usize) -> PyResult<(usize, usize)> {
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

/// `(3, 8)` as Python writes a shape.
fn shape_text(s: &[usize]) -> String {
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
fn real_rows(obj: &Bound<'_, PyAny>, path: &str, unit: &'static str) -> PyResult<Rows<f64>> {
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
fn index_rows(obj: &Bound<'_, PyAny>, path: &str) -> PyResult<Rows<usize>> {
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
fn index_list(obj: &Bound<'_, PyAny>, path: &str) -> PyResult<Vec<usize>> {
    shape(obj, path, 1)?;
    if let Ok(a) = obj.cast::<PyUntypedArray>() {
        return index_array(obj, a, path);
    }
    obj.try_iter()?
        .enumerate()
        .map(|(i, x)| index(&x?, &at(path, i)))
        .collect()
}

/// The arrays of one body, set aside while its tables are read.
struct BodyArrays<'py> {
    body: usize,
    points: Option<Bound<'py, PyAny>>,
    cells: Vec<(String, Bound<'py, PyAny>)>,
    node_sets: Vec<(String, Bound<'py, PyAny>)>,
    /// `initial_velocity`, `initial_displacement` given as rows.
    fields: Vec<(&'static str, Bound<'py, PyAny>)>,
}

impl BodyArrays<'_> {
    /// The key paths of the arrays set aside (`bodies[0].mesh.points`).
    fn slots(&self) -> Vec<String> {
        let b = format!("bodies[{}]", self.body);
        let mut s = Vec::new();
        if self.points.is_some() {
            s.push(format!("{b}.mesh.points"));
            s.push(format!("{b}.mesh.cells"));
            s.push(format!("{b}.mesh.node_sets"));
        }
        s.extend(self.fields.iter().map(|(k, _)| format!("{b}.{k}")));
        s
    }
}

/// The per-node fields a body may give as rows, with their units.
const FIELDS: [(&str, &str); 2] = [("initial_velocity", "m/s"), ("initial_displacement", "m")];

/// A body's table, its arrays set aside (`i` its index in `bodies`).
fn body<'py>(
    obj: &Bound<'py, PyAny>,
    i: usize,
    aside: &mut Vec<BodyArrays<'py>>,
) -> PyResult<toml::Value> {
    let path = at("bodies", i);
    if !is_mapping(obj) {
        return value(obj, &path);
    }
    let mut arrays = BodyArrays {
        body: i,
        points: None,
        cells: Vec::new(),
        node_sets: Vec::new(),
        fields: Vec::new(),
    };
    let mut t = toml::Table::new();
    for (k, v) in items(obj, &path)? {
        if v.is_none() {
            continue;
        }
        let p = dot(&path, &k);
        if let Some(&(name, _)) = FIELDS.iter().find(|(f, _)| *f == k)
            && !is_mapping(&v)
        {
            // rows: set aside, an empty table in their place (the field is given)
            arrays.fields.push((name, v));
            t.insert(k, toml::Value::Array(Vec::new()));
            continue;
        }
        let arrays_mesh = k == "mesh"
            && is_mapping(&v)
            && v.get_item("generator")
                .ok()
                .and_then(|g| g.extract::<String>().ok())
                .is_some_and(|g| g == "arrays");
        if !arrays_mesh {
            t.insert(k, value(&v, &p)?);
            continue;
        }
        let mut mesh = toml::Table::new();
        for (mk, mv) in items(&v, &p)? {
            if mv.is_none() {
                continue;
            }
            let mp = dot(&p, &mk);
            match mk.as_str() {
                "points" => {
                    arrays.points = Some(mv);
                    mesh.insert(mk, toml::Value::Array(Vec::new()));
                }
                "cells" | "node_sets" => {
                    if !is_mapping(&mv) {
                        return Err(bad(
                            &mp,
                            echo(&mv),
                            if mk == "cells" {
                                "a dict of cell kind (hex8, tet4, quad4, tri3) to an array of cells"
                            } else {
                                "a dict of set name to an array of point indices"
                            },
                        ));
                    }
                    let named = items(&mv, &mp)?.into_iter().filter(|(_, a)| !a.is_none());
                    if mk == "cells" {
                        arrays.cells.extend(named);
                    } else {
                        arrays.node_sets.extend(named);
                    }
                    mesh.insert(mk, toml::Value::Table(toml::Table::new()));
                }
                _ => {
                    mesh.insert(mk, value(&mv, &mp)?);
                }
            }
        }
        t.insert(k, toml::Value::Table(mesh));
    }
    if arrays.points.is_some() || !arrays.fields.is_empty() {
        aside.push(arrays);
    }
    Ok(toml::Value::Table(t))
}

/// The scene of a dict of its tables (`Scene.from_dict`), with `--set` overrides.
pub(crate) fn scene_from_dict(
    tables: &Bound<'_, PyAny>,
    overrides: &[String],
) -> PyResult<FileScene> {
    if !is_mapping(tables) {
        return Err(bad(
            "scene",
            echo(tables),
            "a dict of a scene file's tables: {\"time\": {...}, \"bodies\": [...], ...}",
        ));
    }
    let mut aside = Vec::new();
    let mut t = toml::Table::new();
    for (k, v) in items(tables, "")? {
        if v.is_none() {
            continue;
        }
        let tv = if k == "bodies" && is_list(&v) {
            let mut bodies = Vec::new();
            for (i, b) in v.try_iter()?.enumerate() {
                bodies.push(body(&b?, i, &mut aside)?);
            }
            toml::Value::Array(bodies)
        } else {
            value(&v, &k)?
        };
        t.insert(k, tv);
    }
    // an override of a key held by an array set aside would be lost
    for o in overrides {
        let key = o.split_once('=').map_or(o.as_str(), |(k, _)| k).trim();
        let clash = |s: &String| {
            let under = |a: &str, b: &str| {
                a == b || a.starts_with(&format!("{b}.")) || a.starts_with(&format!("{b}["))
            };
            under(key, s) || under(s, key)
        };
        if let Some(s) = aside.iter().flat_map(|a| a.slots()).find(clash) {
            return Err(bad(
                "set",
                o,
                &format!("`{s}` is given as an array in the dict: change it there"),
            ));
        }
    }
    let mut scene = FileScene::from_table(t, overrides).map_err(py_err)?;
    for a in aside {
        fill(&mut scene, a)?;
    }
    scene.validate().map_err(py_err)?;
    Ok(scene)
}

/// Checks the shapes of a body's arrays and the memory they lead to against the
/// memory limit, then copies them into the scene's body.
fn fill(scene: &mut FileScene, a: BodyArrays<'_>) -> PyResult<()> {
    let b = &mut scene.bodies[a.body];
    let dim = b.dim();
    let path = at("bodies", a.body);
    // the shapes, and the memory they lead to, before anything is copied
    let mut estimate = None;
    if let Some(points) = &a.points {
        let pp = format!("{path}.mesh.points");
        let (n, width) = shape(points, &pp, 2)?;
        if points.cast::<PyUntypedArray>().is_ok() && !(width == dim || width == 3) {
            return Err(bad(
                &pp,
                format!("an array of shape {}", shape_text(&[n, width])),
                &format!(
                    "shape (N, {dim}): one row of {dim} coordinates (m) per point{}",
                    if dim == 2 {
                        ", or (N, 3) with z = 0"
                    } else {
                        ""
                    }
                ),
            ));
        }
        let mut cells = Vec::new();
        for (kind, c) in &a.cells {
            let cp = format!("{path}.mesh.cells.{kind}");
            let (count, per) = shape(c, &cp, 2)?;
            if let Ok(k) =
                serde_json::from_value::<CellKind>(serde_json::Value::String(kind.clone()))
                && c.cast::<PyUntypedArray>().is_ok()
                && per != k.nodes()
            {
                return Err(bad(
                    &cp,
                    format!("an array of shape {}", shape_text(&[count, per])),
                    &format!(
                        "shape (n, {}): a {kind} cell has {} nodes",
                        k.nodes(),
                        k.nodes()
                    ),
                ));
            }
            cells.push((count, per));
        }
        let nc: usize = cells.iter().map(|c| c.0).sum();
        estimate = Some((
            arrays_memory(n, width, &cells, dim),
            pp,
            format!("{n} points and {nc} cells"),
        ));
    }
    for (name, f) in &a.fields {
        let fp = format!("{path}.{name}");
        let (n, width) = shape(f, &fp, 2)?;
        let unit = FIELDS
            .iter()
            .find(|(k, _)| k == name)
            .map_or("", |(_, u)| u);
        if f.cast::<PyUntypedArray>().is_ok() && width != dim {
            return Err(bad(
                &fp,
                format!("an array of shape {}", shape_text(&[n, width])),
                &format!("shape (nodes, {dim}): one row of {dim} values ({unit}) per node"),
            ));
        }
        let (m, _, _) = estimate.get_or_insert_with(|| {
            (
                signorini::limits::MemoryEstimate::default(),
                fp.clone(),
                format!("{n} rows"),
            )
        });
        m.add(*name, (n as u64).saturating_mul(width as u64), 8);
    }
    if let Some((m, key, what)) = &estimate {
        m.check(key, what).map_err(py_err)?;
    }
    // the copies, one pass each
    if let Some(points) = &a.points {
        let MeshSpec::Arrays {
            points: p,
            cells,
            node_sets,
        } = &mut b.mesh
        else {
            return Err(bad(
                &format!("{path}.mesh.generator"),
                "changed by `set`",
                "\"arrays\": the dict gives the mesh as arrays",
            ));
        };
        *p = real_rows(points, &format!("{path}.mesh.points"), "m")?;
        let mut by_kind = BTreeMap::new();
        for (kind, c) in &a.cells {
            by_kind.insert(
                kind.clone(),
                index_rows(c, &format!("{path}.mesh.cells.{kind}"))?,
            );
        }
        *cells = by_kind;
        let mut sets = BTreeMap::new();
        for (name, s) in &a.node_sets {
            sets.insert(
                name.clone(),
                index_list(s, &format!("{path}.mesh.node_sets.{name}"))?,
            );
        }
        *node_sets = sets;
    }
    for (name, f) in &a.fields {
        let unit = FIELDS
            .iter()
            .find(|(k, _)| k == name)
            .map_or("", |(_, u)| u);
        let rows = NodalField::Rows(real_rows(f, &format!("{path}.{name}"), unit)?);
        match *name {
            "initial_velocity" => b.initial_velocity = Some(rows),
            _ => b.initial_displacement = Some(rows),
        }
    }
    Ok(())
}
