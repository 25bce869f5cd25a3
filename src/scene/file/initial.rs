//! A body's initial state: the rigid motion of its `velocity`, `angular_velocity` and
//! `rotation_center`, or its per-node `initial_velocity` field, and its per-node
//! `initial_displacement` (inline rows or a text file), each checked against the body's
//! kind, mesh and fixed components.

use super::*;
use crate::model::solid::{HEX8_CORNERS, QUAD4_CORNERS};

/// The rows of a body's field `key` (`initial_velocity` in m/s, `initial_displacement`
/// in m): `nodes` rows of `dim` finite values, inline or from its file (read within
/// [`crate::limits::MAX_TEXT_BYTES`]), flattened node after node.
pub(super) fn nodal_field(
    key: &str,
    unit: &str,
    field: &super::NodalField,
    base_dir: &std::path::Path,
    nodes: usize,
    dim: usize,
) -> Result<Vec<f64>, Error> {
    let expected = format!(
        "one row per node of the body's mesh ({nodes}), {dim} finite value{} each ({unit})",
        if dim == 1 { "" } else { "s" }
    );
    let mut out = Vec::with_capacity(nodes.saturating_mul(dim).min(1 << 24));
    match field {
        super::NodalField::Rows(rows) => {
            if rows.len() != nodes {
                return Err(Error::invalid(
                    key,
                    format!("{} rows", rows.len()),
                    &expected,
                ));
            }
            for (r, row) in rows.iter().enumerate() {
                if row.len() != dim || row.iter().any(|x| !x.is_finite()) {
                    return Err(Error::invalid(
                        &format!("{key}[{r}]"),
                        format!("{row:?}"),
                        &expected,
                    ));
                }
                out.extend_from_slice(row);
            }
        }
        super::NodalField::File { file } => {
            let path = base_dir.join(file);
            let text = crate::limits::read_text(&path, key, crate::limits::MAX_TEXT_BYTES)
                .map_err(|e| prefix(&format!("{key}.file"), e))?;
            let mut rows = 0;
            for (l, raw) in text.lines().enumerate() {
                let content = raw.split('#').next().unwrap_or("");
                if content.trim().is_empty() {
                    continue;
                }
                let bad = |what: String| Error::bad_file(&path, format!("line {}", l + 1), what);
                if rows == nodes {
                    return Err(bad(format!("a row past the {nodes} expected: {expected}")));
                }
                // values separated by commas or white space; between two commas (or
                // after the last) a value is required: `1.0,,0.0` read as (1, 0) and
                // shifted the next values into the empty cell's place
                let commas = content.contains(',');
                let mut count = 0;
                let mut start = 0;
                for cell in content.split(',') {
                    let column = start + 1;
                    start += cell.len() + 1;
                    if commas && cell.trim().is_empty() {
                        return Err(Error::bad_file(
                            &path,
                            format!("line {}, column {column}", l + 1),
                            format!(
                                "an empty cell in `{}`: every component is written (0 as 0): {expected}",
                                crate::error::excerpt(content.trim())
                            ),
                        ));
                    }
                    for tok in cell.split_whitespace() {
                        let x: f64 = tok
                            .parse()
                            .ok()
                            .filter(|x: &f64| x.is_finite())
                            .ok_or_else(|| {
                                bad(format!(
                                    "`{}` is not a finite number",
                                    crate::error::excerpt(tok)
                                ))
                            })?;
                        count += 1;
                        if count <= dim {
                            out.push(x);
                        }
                    }
                }
                if count != dim {
                    return Err(bad(format!("{count} values: {expected}")));
                }
                rows += 1;
            }
            if rows != nodes {
                return Err(Error::bad_file(
                    &path,
                    "rows",
                    format!("{rows} rows: {expected}"),
                ));
            }
        }
    }
    Ok(out)
}

/// The initial velocity of `b`'s dofs in the rigid motion its `velocity`,
/// `angular_velocity` and `rotation_center` give (`omega` `None`: no rotation, a
/// centre alone is then meaningless and refused), checked against the body's kind.
pub(super) fn rigid_motion(
    b: &BodySpec,
    mesh: &crate::model::solid::Mesh,
    sys: &crate::model::LinearSystem,
    dim: usize,
    vel: &[f64],
    omega: Option<&[f64]>,
) -> Result<Vec<f64>, Error> {
    let Some(omega) = omega else {
        return Err(Error::invalid(
            "rotation_center",
            format!("{:?}", b.rotation_center.as_deref().unwrap_or_default()),
            "is the point the initial rotation turns about: give angular_velocity with it",
        ));
    };
    let cannot_turn = matches!(b.mesh, MeshSpec::Rod { .. })
        || matches!(
            b.formulation,
            crate::model::solid::Formulation::Axisymmetric
        );
    if cannot_turn {
        return Err(Error::invalid(
            "angular_velocity",
            format!("{omega:?}"),
            "needs a 3-D solid or a plane body (a rod or an axisymmetric body cannot \
             turn rigidly in its own model)",
        ));
    }
    let n_omega = if dim == 3 { 3 } else { 1 };
    if omega.len() != n_omega || omega.iter().any(|x| !x.is_finite()) {
        return Err(Error::invalid(
            "angular_velocity",
            format!("{omega:?}"),
            &format!(
                "needs {n_omega} finite value{} (rad/s{})",
                if n_omega == 1 { "" } else { "s" },
                if n_omega == 1 { ", about z" } else { "" }
            ),
        ));
    }
    let centre = match &b.rotation_center {
        Some(c) => {
            if c.len() != dim || c.iter().any(|x| !x.is_finite()) {
                return Err(Error::invalid(
                    "rotation_center",
                    format!("{c:?}"),
                    &format!("needs {dim} finite values (m)"),
                ));
            }
            std::array::from_fn(|d| c.get(d).copied().unwrap_or(0.0))
        }
        None => {
            crate::model::centre_of_mass(sys.mass.as_ref(), &mesh.points, dim).ok_or_else(|| {
                Error::invalid(
                    "angular_velocity",
                    format!("{omega:?}"),
                    "turns about the body's centre of mass, but the body has no mass: give \
                     rotation_center",
                )
            })?
        }
    };
    Ok(crate::model::rigid_velocity(
        &mesh.points,
        dim,
        vel,
        omega,
        centre,
    ))
}

/// A per-node initial velocity replaces the rigid motion: both given is refused.
pub(super) fn one_initial_motion(b: &BodySpec) -> Result<(), Error> {
    if b.initial_velocity.is_some()
        && (b.velocity.is_some() || b.angular_velocity.is_some() || b.rotation_center.is_some())
    {
        return Err(Error::invalid(
            "initial_velocity",
            "given with velocity, angular_velocity or rotation_center",
            "one initial motion per body: the field, or the rigid motion",
        ));
    }
    Ok(())
}

/// The key that gave body `b`'s initial velocity: `initial_velocity`,
/// `angular_velocity` (a rigid motion that turns) or `velocity`.
pub(super) fn motion_key(b: &BodySpec) -> &'static str {
    if b.initial_velocity.is_some() {
        "initial_velocity"
    } else if b.angular_velocity.is_some() || b.rotation_center.is_some() {
        "angular_velocity"
    } else {
        "velocity"
    }
}

/// A field's value on a component `fixed` holds would be dropped by the elimination:
/// refused rather than lost (`values` and `fixed` over the body's dofs, node-major).
/// `key` is the input that gave the values: a field, or the rigid motion of
/// `velocity` / `angular_velocity`, which must then vanish on the fixed components.
pub(super) fn zero_where_fixed(
    key: &str,
    values: &[f64],
    fixed: &[bool],
    dim: usize,
) -> Result<(), Error> {
    match (0..values.len()).find(|&i| fixed[i] && values[i] != 0.0) {
        Some(i) => Err(Error::invalid(
            key,
            format!(
                "{} at node {} component {}",
                crate::error::num(values[i]),
                i / dim,
                i % dim
            ),
            if key == "velocity" || key == "angular_velocity" {
                "gives a node that `fixed` holds a velocity: the rigid motion must be 0 on \
                 every fixed component (a held node neither translates nor turns), else \
                 the hold would drop it there; give the motion as initial_velocity (0 on \
                 the fixed nodes), or drop the fixed set"
            } else {
                "is 0 where `fixed` holds the node"
            },
        )),
        None => Ok(()),
    }
}

/// An initial velocity or displacement past [`super::validate::MAX_LOAD_MAGNITUDE`]
/// (`values` over the body's dofs, node-major; `unit` for the message): the energy and
/// work sums square it and overflow (issue 48: a velocity of 1e308 ran and was reported
/// as a run that broke down, "lower the time step").
pub(super) fn within_bound(key: &str, values: &[f64], dim: usize, unit: &str) -> Result<(), Error> {
    let max = super::validate::MAX_LOAD_MAGNITUDE;
    match values.iter().position(|v| v.abs() > max) {
        Some(i) => Err(Error::invalid(
            key,
            format!(
                "{:e} {unit} at node {} component {}",
                values[i],
                i / dim,
                i % dim
            ),
            &format!(
                "at most {max:e} {unit} in magnitude: beyond it the energy sums (squares) overflow"
            ),
        )),
        None => Ok(()),
    }
}

/// An initial value on a component a `[[prescribed]]` entry (`prescribed[entry]`)
/// drives: it must equal the prescribed motion's start (`expected`: the velocity at
/// t = 0, or displacement 0), since the elimination replaces it by that.
pub(super) fn as_prescribed(
    key: &str,
    value: f64,
    expected: f64,
    node: &str,
    component: usize,
    entry: usize,
) -> Result<(), Error> {
    if value == expected {
        return Ok(());
    }
    Err(Error::invalid(
        key,
        format!(
            "{} at {node} component {component}",
            crate::error::num(value)
        ),
        &format!(
            "prescribed[{entry}] drives that component, which starts at {} (its prescribed \
             {} at t = 0); a different value would be dropped: write {} there, or leave \
             the node out of the [[prescribed]] set",
            crate::error::num(expected),
            if key == "initial_displacement" {
                "displacement"
            } else {
                "velocity"
            },
            crate::error::num(expected),
        ),
    ))
}

/// The Jacobian determinant (up to a positive factor) of a cell with corner positions
/// `x` at each corner, and the scale of its edges there (the product of their lengths)
/// to compare it with. A simplex has one value (its Jacobian is constant).
fn corner_dets(kind: CellKind, x: &[[f64; 3]]) -> Vec<(f64, f64)> {
    let sub = |a: usize, b: usize| -> [f64; 3] { std::array::from_fn(|i| x[a][i] - x[b][i]) };
    let norm = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let det2 = |a: [f64; 3], b: [f64; 3]| a[0] * b[1] - a[1] * b[0];
    let det3 = |a: [f64; 3], b: [f64; 3], c: [f64; 3]| {
        a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
            + a[2] * (b[0] * c[1] - b[1] * c[0])
    };
    match kind {
        CellKind::Tri3 => {
            let (a, b) = (sub(1, 0), sub(2, 0));
            vec![(det2(a, b), norm(a) * norm(b))]
        }
        CellKind::Tet4 => {
            let (a, b, c) = (sub(1, 0), sub(2, 0), sub(3, 0));
            vec![(det3(a, b, c), norm(a) * norm(b) * norm(c))]
        }
        CellKind::Quad4 => (0..4)
            .map(|k| {
                let s = QUAD4_CORNERS[k];
                let along = |d: usize| {
                    let mut t = s;
                    t[d] = -t[d];
                    let n = QUAD4_CORNERS
                        .iter()
                        .position(|c| *c == t)
                        .expect("a corner");
                    let e = sub(k, n);
                    e.map(|v| v * s[d])
                };
                let (a, b) = (along(0), along(1));
                (det2(a, b), norm(a) * norm(b))
            })
            .collect(),
        CellKind::Hex8 => (0..8)
            .map(|k| {
                let s = HEX8_CORNERS[k];
                let along = |d: usize| {
                    let mut t = s;
                    t[d] = -t[d];
                    let n = HEX8_CORNERS.iter().position(|c| *c == t).expect("a corner");
                    let e = sub(k, n);
                    e.map(|v| v * s[d])
                };
                let (a, b, c) = (along(0), along(1), along(2));
                (det3(a, b, c), norm(a) * norm(b) * norm(c))
            })
            .collect(),
        // a curved (quadratic) cell: det J at every node, from the shape functions
        _ => kind
            .element()
            .reference_nodes()
            .iter()
            .map(|&xi| {
                let [a, b, c] = crate::model::element::jacobian_columns(kind, x, xi);
                if kind.dim() == 2 {
                    (det2(a, b), norm(a) * norm(b))
                } else {
                    (det3(a, b, c), norm(a) * norm(b) * norm(c))
                }
            })
            .collect(),
    }
}

/// Every cell of body `b`'s `mesh` positively oriented at each corner (a tangled cell
/// can have det J < 0 at a corner while its Gauss points, which the assembly checks,
/// have det J > 0; a mirrored body is inverted everywhere), and, when the body starts
/// displaced by `u` (node-major, `dim` per node), det F > 0 at each corner of the
/// displaced cell: a body inverted at its start is bad input, not a time step that is
/// too large.
pub(super) fn check_orientation(
    mesh: &crate::model::solid::Mesh,
    b: &BodySpec,
    u: Option<&[f64]>,
) -> Result<(), Error> {
    let dim = b.dim();
    // below this relative size a corner's determinant is round-off of a degenerate
    // (collapsed) corner, not an inversion
    const TOL: f64 = 1e-10;
    for (id, (kind, nodes)) in mesh.cells.iter().enumerate() {
        let cell = match mesh.cell_ids.get(id) {
            Some(tag) => format!("cell {tag} (file tag, {})", kind.name()),
            None => format!("cell {id} ({})", kind.name()),
        };
        let x: Vec<[f64; 3]> = nodes.iter().map(|&v| mesh.points[v]).collect();
        let corner = |k: usize, n: usize| {
            if n == 1 {
                "every corner".to_string()
            } else {
                let at = if k < kind.element().corners() {
                    "corner"
                } else {
                    "node"
                };
                format!("{at} {k} ({})", mesh.node_label(nodes[k]))
            }
        };
        let reference = corner_dets(*kind, &x);
        let n = reference.len();
        if let Some(k) = reference.iter().position(|&(d, s)| d < -TOL * s) {
            let what = format!(
                "{}: Jacobian determinant det J = {:.3e} (relative to its edges)",
                corner(k, n),
                reference[k].0 / reference[k].1
            );
            let why = "is inverted there: reorder the cell's nodes (VTK/Gmsh order: \
                       positive orientation), or untangle the cell";
            return Err(match &mesh.source {
                // a cell of a mesh file: the file and the file's own element id
                Some(file) => Error::bad_file(
                    file,
                    format!(
                        "element {}",
                        mesh.cell_ids.get(id).copied().unwrap_or(id as u64)
                    ),
                    format!("{cell}, {what}: {why}"),
                ),
                None => Error::invalid("mesh", format!("{cell}, {what}"), why),
            });
        }
        let Some(u) = u else { continue };
        let y: Vec<[f64; 3]> = nodes
            .iter()
            .map(|&v| {
                std::array::from_fn(|i| {
                    mesh.points[v][i] + if i < dim { u[v * dim + i] } else { 0.0 }
                })
            })
            .collect();
        for (k, ((dx, _), (dref, sref))) in corner_dets(*kind, &y)
            .into_iter()
            .zip(reference)
            .enumerate()
        {
            if dref <= TOL * sref {
                continue;
            }
            let det_f = dx / dref;
            if det_f.is_nan() || det_f <= 0.0 {
                return Err(Error::invalid(
                    "initial_displacement",
                    format!("{cell}, {}: det F = {:.3e}", corner(k, n), det_f),
                    "inverts the cell at the start (det F ≤ 0): no body starts turned inside \
                     out; check the displacement's sign and its rows' node order",
                ));
            }
        }
    }
    Ok(())
}
