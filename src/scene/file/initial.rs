//! A body's initial state: the rigid motion of its `velocity`, `angular_velocity` and
//! `rotation_center`, or its per-node `initial_velocity` field, and its per-node
//! `initial_displacement` (inline rows or a text file), each checked against the body's
//! kind, mesh and fixed components.

use super::*;

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
            for (l, line) in text.lines().enumerate() {
                let line = line.split('#').next().unwrap_or("").trim();
                if line.is_empty() {
                    continue;
                }
                let bad = |what: String| Error::bad_file(&path, format!("line {}", l + 1), what);
                if rows == nodes {
                    return Err(bad(format!("a row past the {nodes} expected: {expected}")));
                }
                let mut count = 0;
                for tok in line.split(|c: char| c == ',' || c.is_whitespace()) {
                    if tok.is_empty() {
                        continue;
                    }
                    let x: f64 = tok
                        .parse()
                        .ok()
                        .filter(|x: &f64| x.is_finite())
                        .ok_or_else(|| bad(format!("`{tok}` is not a finite number")))?;
                    count += 1;
                    if count > dim {
                        break;
                    }
                    out.push(x);
                }
                if count != dim {
                    return Err(bad(format!(
                        "{count}{} values: {expected}",
                        if count > dim { " or more" } else { "" }
                    )));
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

/// A field's value on a component `fixed` holds would be dropped by the elimination:
/// refused rather than lost (`values` and `fixed` over the body's dofs, node-major).
pub(super) fn zero_where_fixed(
    key: &str,
    values: &[f64],
    fixed: &[bool],
    dim: usize,
) -> Result<(), Error> {
    match (0..values.len()).find(|&i| fixed[i] && values[i] != 0.0) {
        Some(i) => Err(Error::invalid(
            key,
            format!("{} at node {} component {}", values[i], i / dim, i % dim),
            "is 0 where `fixed` holds the node",
        )),
        None => Ok(()),
    }
}
