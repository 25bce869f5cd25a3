//! The build's first four phases (`build`'s module doc), on the bodies' meshes before
//! anything is assembled: every body's mesh checked against its formulation, each
//! body's `initial_displacement` (no cell inverted at the start), the probes' node sets
//! and the master surface of each contact between bodies. `build` calls them.

use super::*;

/// A master surface: its facets, over its body's node numbers, outward.
pub(super) type Surface = Vec<Vec<usize>>;

impl Scene {
    /// Phase 1: every body's mesh (all first: a contact between bodies needs both sides'
    /// meshes), in dimension `dim`, checked against its formulation.
    pub(super) fn meshes(&self, dim: usize) -> Result<Vec<Mesh>, Error> {
        let mut all_meshes = Vec::with_capacity(self.bodies.len());
        for (bi, b) in self.bodies.iter().enumerate() {
            let at = at_body(bi, b);
            if b.dim() != dim {
                return Err(at(Error::invalid(
                    "formulation",
                    b.dim(),
                    "all bodies need one dimension",
                )));
            }
            let mesh = b.mesh(&self.base_dir).map_err(&at)?;
            // the mesh against the formulation before anything reads its cells as such
            if !matches!(b.mesh, MeshSpec::Rod { .. }) {
                crate::model::solid::check_mesh(&mesh, b.formulation).map_err(at)?;
            }
            all_meshes.push(mesh);
        }
        Ok(all_meshes)
    }

    /// Phase 2: each body's initial displacement (node-major, `dim` per node), before
    /// the contacts: `within` is measured at the starting positions. A cell it inverts
    /// (or the mesh inverts) is refused.
    pub(super) fn initial_displacements(
        &self,
        meshes: &[Mesh],
    ) -> Result<Vec<Option<Vec<f64>>>, Error> {
        let mut u_of: Vec<Option<Vec<f64>>> = Vec::with_capacity(self.bodies.len());
        for (bi, b) in self.bodies.iter().enumerate() {
            let at = at_body(bi, b);
            u_of.push(match &b.initial_displacement {
                Some(field) => Some(
                    super::initial::nodal_field(
                        "initial_displacement",
                        "m",
                        field,
                        &self.base_dir,
                        meshes[bi].points.len(),
                        b.dim(),
                    )
                    .map_err(&at)?,
                ),
                None => None,
            });
            if let Some(u) = &u_of[bi] {
                super::initial::within_bound("initial_displacement", u, b.dim(), "m")
                    .map_err(&at)?;
            }
            // a cell inverted at the start, in the mesh or by the displacement
            if !matches!(b.mesh, MeshSpec::Rod { .. }) {
                super::initial::check_orientation(&meshes[bi], b, u_of[bi].as_deref())
                    .map_err(at)?;
            }
        }
        Ok(u_of)
    }

    /// Phase 4: the master surface of each contact between bodies (facets over its
    /// body's node numbers, outward; none for a contact with an obstacle), and how many
    /// of its facets on the axis r = 0 were left out.
    pub(super) fn target_surfaces(
        &self,
        meshes: &[Mesh],
    ) -> Result<(Vec<Surface>, Vec<usize>), Error> {
        let mut facets_of: Vec<Surface> = vec![Vec::new(); self.contacts.len()];
        let mut axis_facets = vec![0; self.contacts.len()];
        for (ci, c) in self.contacts.iter().enumerate() {
            if let Some(t) = &c.target {
                let ti = self.body_index(&t.body);
                (facets_of[ci], axis_facets[ci]) =
                    target_facets(&meshes[ti], &self.bodies[ti], t, c.rule)
                        .map_err(|e| prefix(&format!("contacts[{ci}].target"), e))?;
            }
        }
        Ok((facets_of, axis_facets))
    }

    /// Phase 3: the `[[probes]]` on the built meshes: each set's points in the geometry,
    /// and a rod's abscissae from its end of smallest `x`.
    pub(super) fn probes(
        &self,
        meshes: &[Mesh],
        point_base: &[usize],
    ) -> Result<Vec<Probe>, Error> {
        let mut out = Vec::with_capacity(self.probes.len());
        for (i, p) in self.probes.iter().enumerate() {
            let bi = self.body_index(&p.body);
            let mesh = &meshes[bi];
            let nodes = node_set(mesh, &p.nodes).map_err(|e| prefix(&format!("probes[{i}]"), e))?;
            if nodes.is_empty() {
                return Err(Error::invalid(
                    &format!("probes[{i}].nodes"),
                    &p.nodes,
                    "the node set is empty",
                ));
            }
            let rod_abscissa = matches!(self.bodies[bi].mesh, MeshSpec::Rod { .. }).then(|| {
                let x0 = mesh
                    .points
                    .iter()
                    .map(|x| x[0])
                    .fold(f64::INFINITY, f64::min);
                nodes.iter().map(|&v| mesh.points[v][0] - x0).collect()
            });
            out.push(Probe {
                name: p.name.clone(),
                body: p.body.clone(),
                nodes: p.nodes.clone(),
                points: nodes.iter().map(|&v| point_base[bi] + v).collect(),
                times: p.times.clone(),
                rod_abscissa,
            });
        }
        Ok(out)
    }
}

/// Prefixes an error with the key of body `bi`: `bodies[i] (name)`.
pub(super) fn at_body(bi: usize, b: &BodySpec) -> impl Fn(Error) -> Error + '_ {
    move |e| prefix(&format!("bodies[{bi}] ({})", b.name), e)
}
