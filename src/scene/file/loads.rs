//! Loads: gravity (`[loads]`), forces on node sets (`[[forces]]`) and uniform pressures
//! on boundary faces (`[[pressures]]`, [`crate::model::pressure`]), each with a
//! piecewise-linear function of time.

use serde::{Deserialize, Serialize};

/// `[[forces]]`: a force on a node set, split evenly over its nodes, scaled by a
/// piecewise-linear function of time.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ForceSpec {
    /// Body name.
    pub body: String,
    /// A node set of the body's mesh (as for `[[contacts]]`: a set, `boundary` or `all`).
    pub nodes: String,
    /// The total force over the set (N), one component per space dimension.
    pub total: Vec<f64>,
    /// `[[t, factor], …]`: the factor multiplying `total` at time `t`, linear between the
    /// points and constant outside them (default: 1 at all times).
    #[serde(default, deserialize_with = "time_points")]
    pub time: Option<Vec<[f64; 2]>>,
}

/// `[[t, factor], …]` with exactly two numbers a point: serde's fixed-size arrays take
/// the first two of a longer list and drop the rest silently (issue 34).
pub(super) fn time_points<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<Option<Vec<[f64; 2]>>, D::Error> {
    let v: Option<Vec<Vec<f64>>> = Option::deserialize(d)?;
    v.map(|points| {
        points
            .into_iter()
            .enumerate()
            .map(|(i, p)| match p[..] {
                [t, f] => Ok([t, f]),
                _ => Err(serde::de::Error::custom(format!(
                    "time point {i} has {} number(s), expected 2: [t, factor]",
                    p.len()
                ))),
            })
            .collect()
    })
    .transpose()
}

/// `[[pressures]]`: a uniform pressure on the boundary faces of a node set (the faces
/// whose nodes all lie in it), scaled by a piecewise-linear function of time. Its
/// nodal forces are the consistent ones, `−p ∫ N_b n dΓ` over the faces in the
/// reference configuration (a dead load; [`crate::model::pressure`]).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PressureSpec {
    /// Body name (a plane, axisymmetric or solid body; not a rod).
    pub body: String,
    /// A node set of the body's mesh (a set, `boundary` or `all`): the boundary faces
    /// whose nodes all lie in it are loaded.
    pub faces: String,
    /// The pressure (Pa): positive pushes into the body, against the faces' outward
    /// normals.
    pub pressure: f64,
    /// `[[t, factor], …]`: the factor multiplying `pressure` at time `t` (default 1 at
    /// all times).
    #[serde(default, deserialize_with = "time_points")]
    pub time: Option<Vec<[f64; 2]>>,
}

/// `[loads]`.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Loads {
    /// Uniform acceleration field (m/s²), e.g. `[0, 0, -9.81]`.
    #[serde(default)]
    pub gravity: Option<Vec<f64>>,
}

impl super::Scene {
    /// Checks the `[[pressures]]`: an existing body that has faces (not a rod), a
    /// finite pressure within the load magnitude limit with its time factors, a valid
    /// time function.
    pub(super) fn validate_pressures(&self) -> Result<(), crate::error::Error> {
        use crate::error::Error;
        for (i, p) in self.pressures.iter().enumerate() {
            let at = format!("pressures[{i}]");
            let Some(b) = self.bodies.iter().find(|b| b.name == p.body) else {
                return Err(Error::invalid(
                    &format!("{at}.body"),
                    &p.body,
                    "names no body",
                ));
            };
            if matches!(b.mesh, super::MeshSpec::Rod { .. }) {
                return Err(Error::invalid(
                    &format!("{at}.body"),
                    &p.body,
                    "is a rod, which has no faces: load its end with [[forces]]",
                ));
            }
            if !p.pressure.is_finite() {
                return Err(Error::invalid(
                    &format!("{at}.pressure"),
                    p.pressure,
                    "expected a finite pressure (Pa)",
                ));
            }
            super::validate::time_function(&format!("{at}.time"), &p.time)?;
            let peak = p.pressure.abs()
                * p.time
                    .as_ref()
                    .map_or(1.0, |t| t.iter().fold(0.0f64, |m, q| m.max(q[1].abs())));
            super::validate::within_magnitude(
                &format!("{at}.pressure"),
                &[p.pressure],
                peak,
                "Pa",
            )?;
        }
        Ok(())
    }
}

/// The nodal loads of the `[[pressures]]` (after the elimination: loads on fixed dofs
/// are dropped, the supports carry them): the consistent forces of
/// [`crate::model::pressure::unit_pressure_forces`] times the pressure, summed per node.
pub(super) fn pressure_loads(
    scene: &super::Scene,
    meshes: &[crate::model::solid::Mesh],
    map: &[Option<usize>],
    offsets: &[usize],
) -> Result<Vec<crate::model::NodalLoad>, crate::error::Error> {
    use super::prefix;
    use crate::error::Error;
    let mut loads = Vec::new();
    for (pi, p) in scene.pressures.iter().enumerate() {
        let at = |e: Error| prefix(&format!("pressures[{pi}]"), e);
        let bi = scene.body_index(&p.body);
        let (mesh, body) = (&meshes[bi], &scene.bodies[bi]);
        // the set's errors name this entry's key, `faces`
        let set = super::mesh_spec::node_set_any(mesh, &p.faces).map_err(|e| match e {
            Error::InvalidParameter { value, reason, .. } => at(Error::InvalidParameter {
                field: "faces".into(),
                value,
                reason,
            }),
            e => at(e),
        })?;
        let facets = mesh.boundary_facets(&set);
        if facets.is_empty() {
            return Err(at(Error::invalid(
                "faces",
                &p.faces,
                "holds no boundary face (edge in 2-D): a face is loaded when all its nodes \
                 are in the set",
            )));
        }
        let dim = body.dim();
        let unit =
            crate::model::pressure::unit_pressure_forces(body.formulation, &facets, &mesh.points)
                .map_err(at)?;
        let mut by_dof = std::collections::BTreeMap::new();
        for (v, f) in unit {
            for (i, &fi) in f.iter().enumerate().take(dim) {
                if let Some(d) = map[offsets[bi] + v * dim + i] {
                    *by_dof.entry(d).or_insert(0.0) += p.pressure * fi;
                }
            }
        }
        let (dofs, values) = by_dof.into_iter().unzip();
        let time = super::validate::time_function(&format!("pressures[{pi}].time"), &p.time)?;
        loads.push(crate::model::NodalLoad { dofs, values, time });
    }
    Ok(loads)
}
