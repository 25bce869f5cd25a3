//! The model and the run as Python receives them: the mesh and dof map of a built
//! model, the bodies' measures (of a state, or of a finished run's summary) and the
//! history's columns, as tuples of owned numpy arrays (lib.rs: copies, not views).

use super::*;

/// History columns handed to Python: `(name, array)` in the CSV's order.
pub(crate) type NamedArrays = Vec<(String, Py<PyArray1<f64>>)>;

/// The arrays of [`PySimulation::mesh`]: points `(N, 3)`, node ids `(N,)`, the body of
/// each point `(N,)` (−1 for a point no cell uses), cells as `(kind, body, nodes)`, the
/// displacement components per point and the dof map `(N, dim)` (−1: fixed or
/// prescribed), the bodies' names, and the contacts as `(point, body, target, entry)`.
pub(crate) type MeshArrays = (
    Py<numpy::PyArray2<f64>>,
    Py<PyArray1<u64>>,
    Py<PyArray1<i64>>,
    Vec<(String, usize, Vec<usize>)>,
    usize,
    Py<numpy::PyArray2<i64>>,
    Vec<String>,
    Vec<(usize, usize, String, usize)>,
);

/// One body's mass, centre, momentum and angular momentum (`_Simulation.bodies`).
pub(crate) type BodyRow = (f64, [f64; 3], [f64; 3], [f64; 3]);

/// The mesh of `geo` and where each nodal displacement component is in `q` (module doc
/// of the Python `Mesh`), the bodies named `names`.
pub(crate) fn mesh_arrays(
    py: Python<'_>,
    geo: &signorini::model::geometry::Geometry,
    names: Vec<String>,
) -> PyResult<MeshArrays> {
    let n = geo.points.len();
    let dim = geo.dim;
    let points: Vec<f64> = geo.points.iter().flatten().copied().collect();
    let ids: Vec<u64> = if geo.node_ids.len() == n {
        geo.node_ids.clone()
    } else {
        (0..n as u64).collect()
    };
    let mut body = vec![-1_i64; n];
    let mut cells = Vec::with_capacity(geo.cells.len());
    for (kind, nodes, b) in &geo.cells {
        for &p in nodes {
            body[p] = *b as i64;
        }
        let name = match kind {
            signorini::model::geometry::GeomCell::Line => "line".to_string(),
            signorini::model::geometry::GeomCell::Solid(k) => k.name().to_string(),
        };
        cells.push((name, *b, nodes.clone()));
    }
    let dofs: Vec<i64> = (0..n * dim)
        .map(|i| {
            geo.dof_of
                .get(i)
                .copied()
                .flatten()
                .map_or(-1, |d| d as i64)
        })
        .collect();
    let to2 = |v: Vec<f64>, cols: usize| {
        numpy::PyArray1::from_vec(py, v)
            .reshape([n, cols])
            .map(|a| a.unbind())
    };
    let points = to2(points, 3)?;
    let dof_map = numpy::PyArray1::from_vec(py, dofs)
        .reshape([n, dim])?
        .unbind();
    Ok((
        points,
        ids.into_pyarray(py).unbind(),
        body.into_pyarray(py).unbind(),
        cells,
        dim,
        dof_map,
        names,
        geo.contacts
            .iter()
            .map(|c| (c.point, c.body, c.target.clone(), c.entry))
            .collect(),
    ))
}

/// A body's measures as a row: mass, centre, momentum, angular momentum.
fn row(s: &signorini::model::BodyState) -> BodyRow {
    (s.mass, s.centre, s.momentum, s.angular_momentum)
}

/// Each body's final measures, from the JSON `summary` of a finished run.
pub(crate) fn final_bodies(summary: &str) -> PyResult<Vec<BodyRow>> {
    let v: serde_json::Value = serde_json::from_str(summary).unwrap_or_default();
    let parse = |b: &serde_json::Value| -> Option<BodyRow> {
        let s: signorini::model::BodyState =
            serde_json::from_value(b.get("final")?.clone()).ok()?;
        Some(row(&s))
    };
    v.get("bodies")
        .and_then(|b| b.as_array())
        .map(|b| b.iter().filter_map(parse).collect())
        .ok_or_else(|| PyRuntimeError::new_err("the finished run recorded no bodies"))
}

/// Each body of `geo`'s measures at the state `q`, `v` with the mass matrix `mass`
/// ([`signorini::model::BodyMeasures`]; none where the geometry has no bodies).
pub(crate) fn measure_bodies(
    geo: &signorini::model::geometry::Geometry,
    mass: &signorini::linalg::SparseMatrix,
    q: &[f64],
    v: &[f64],
) -> Vec<BodyRow> {
    let Some(mut bm) = signorini::model::BodyMeasures::new(geo, q.len()) else {
        return Vec::new();
    };
    let mut out = vec![signorini::model::BodyState::default(); bm.bodies()];
    bm.measure(mass, q, v, &mut out);
    out.iter().map(row).collect()
}

/// The history's columns as `(name, array)`, in the file's order.
pub(crate) fn named_arrays(py: Python<'_>, h: &[(String, Vec<f64>)]) -> NamedArrays {
    h.iter()
        .map(|(name, v)| (name.clone(), v.clone().into_pyarray(py).unbind()))
        .collect()
}
