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
//!
//! Here the walk of the dict's top level and its bodies, the arrays set aside, the
//! overrides checked against them, and the arrays measured and copied into the scene:
//! the walk of other values is `toml_values`'s, the checks and copies of the tables of
//! numbers `table_rows`'s.

use std::collections::BTreeMap;

use numpy::PyUntypedArray;
use signorini::model::solid::CellKind;
use signorini::scene::file::{MeshSpec, NodalField, arrays_memory};

use super::*;
use crate::table_rows::{index_list, index_rows, real_rows, shape};
use crate::toml_values::{at, bad, dot, echo, is_list, is_mapping, items, shape_text, value};

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
                            &if mk == "cells" {
                                format!(
                                    "a dict of cell kind ({}) to an array of cells",
                                    CellKind::names(None)
                                )
                            } else {
                                "a dict of set name to an array of point indices".to_string()
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
