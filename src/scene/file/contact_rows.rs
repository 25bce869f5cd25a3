//! The rows of contact entries that are not one node against one obstacle point: the
//! surface rule against a plane (rows at face points, or per face node on triangles,
//! [`crate::contact::surface`]), mortar rows between bodies ([`crate::contact::mortar`]),
//! and node rows on a plane for nodes with held components (symmetry planes). Each is a
//! set of constant rows ([`crate::contact::linear::LinearContacts`]).

use super::contacts::{Dofs, Sides};
use super::*;

impl Sides<'_> {
    /// The node rule's rows of `c`'s `nodes` (of body `bi`) against a plane when some
    /// of them have a held component (a node on a symmetry plane: `fixed` or
    /// `[[prescribed]]` components): one row per node on its free dofs, its gap the
    /// node's distance to the plane, as [`crate::contact::plane::NodesOnPlane`]'s; the
    /// tangential rows leave the held components out (their velocity is the held one,
    /// zero on a symmetry plane). A held component along which the plane's normal has a
    /// part, or one that `[[prescribed]]` moves along a tangent of a frictional contact,
    /// would move the gap or the slip with a motion these rows do not follow: refused,
    /// naming the node.
    pub(super) fn held_nodes_on_plane(
        &self,
        c: &ContactSpec,
        bi: usize,
        nodes: &[usize],
        dofs: Dofs,
        (normal, offset): (&[f64], f64),
    ) -> Result<Box<dyn ContactSet>, Error> {
        use crate::contact::linear::{LinearContact, LinearContacts};
        let mesh = &self.meshes[bi];
        let t = crate::contact::frame::tangents(&normal[..self.dim]);
        let k = if c.friction > 0.0 { self.dim - 1 } else { 0 };
        let law = crate::contact::ContactLaw {
            restitution: c.restitution,
            friction: c.friction,
        };
        // the components of this body's nodes that a `[[prescribed]]` entry moves
        let mut moving = std::collections::BTreeSet::new();
        for p in &self.scene.prescribed {
            if self.scene.body_index(&p.body) != bi || p.velocity.iter().all(|&x| x == 0.0) {
                continue;
            }
            let comps: Vec<usize> = p.components.clone().unwrap_or((0..self.dim).collect());
            for w in node_set(mesh, &p.nodes)? {
                moving.extend(
                    comps
                        .iter()
                        .filter(|&&i| p.velocity[i] != 0.0)
                        .map(|&i| (w, i)),
                );
            }
        }
        let mut rows = Vec::with_capacity(nodes.len());
        for &v in nodes {
            if (0..self.dim).all(|i| dofs.of(bi, v, i).is_none()) {
                return Err(Error::invalid(
                    "nodes",
                    mesh.node_label(v),
                    "is fixed and cannot be a contact node",
                ));
            }
            let x = &mesh.points[v];
            let mut lc = LinearContact {
                dofs: Vec::new(),
                offset: (0..self.dim).map(|i| normal[i] * x[i]).sum::<f64>() - offset,
                normal: Vec::new(),
                tangents: vec![Vec::new(); k],
                law,
            };
            for i in 0..self.dim {
                match dofs.of(bi, v, i) {
                    Some(d) => {
                        lc.dofs.push(d);
                        lc.normal.push(normal[i]);
                        for (row, tj) in lc.tangents.iter_mut().zip(&t) {
                            row.push(tj[i]);
                        }
                    }
                    None if normal[i].abs() > 1e-12
                        || (moving.contains(&(v, i))
                            && t[..k].iter().any(|tj| tj[i].abs() > 1e-12)) =>
                    {
                        return Err(Error::invalid(
                            "nodes",
                            mesh.node_label(v),
                            &format!(
                                "holds component {i}, along which the obstacle's normal (or, \
                                 moved by [[prescribed]], a tangent) has a part: a held contact \
                                 node must be free across the plane (a symmetry plane normal to \
                                 it is)"
                            ),
                        ));
                    }
                    None => {}
                }
            }
            // a tangent along held components only has no row: the node cannot slip that
            // way (the symmetry plane's own reaction holds it); with no tangent left the
            // node's block is frictionless
            lc.tangents
                .retain(|row| row.iter().any(|x| x.abs() > 1e-12));
            if lc.tangents.is_empty() {
                lc.law.friction = 0.0;
            }
            rows.push(lc);
        }
        Ok(Box::new(LinearContacts::new(rows)?))
    }

    /// The surface rule's rows of `c` (of body `bi`) against its plane obstacle
    /// ([`crate::contact::surface`]): at the points of the boundary facets whose nodes
    /// all lie in the kept `nodes`, on the kept `dofs` (a fixed node's position only
    /// enters the offset); with the node each row is named by.
    pub(super) fn surface_set(
        &self,
        c: &ContactSpec,
        bi: usize,
        nodes: &[usize],
        dofs: Dofs,
    ) -> Result<(Box<dyn ContactSet>, Vec<usize>), Error> {
        use crate::contact::linear::{LinearContact, LinearContacts};
        let obstacle = self.scene.obstacle(c);
        let Some((normal, offset)) = obstacle.shape().plane() else {
            return Err(Error::invalid(
                "rule",
                "surface",
                "takes a plane obstacle for now (curved obstacles: rule = \"nodes\")",
            ));
        };
        let mesh = &self.meshes[bi];
        let facets = mesh.boundary_facets(nodes);
        let rows = crate::contact::surface::collocation_rows(self.dim, &facets, &mesh.points)?;
        let law = crate::contact::ContactLaw {
            restitution: c.restitution,
            friction: c.friction,
        };
        // the plane's frame: its tangential rows weigh the face point's velocity as its
        // normal row does
        let t = crate::contact::frame::tangents(&normal[..self.dim]);
        let k = if law.friction > 0.0 { self.dim - 1 } else { 0 };
        let labels = rows.iter().map(|r| r.0).collect();
        let rows = rows
            .into_iter()
            .map(|(_, row)| {
                let mut lc = LinearContact {
                    dofs: Vec::new(),
                    offset: 0.0,
                    normal: Vec::new(),
                    tangents: vec![Vec::new(); k],
                    law,
                };
                for (b, w) in row {
                    let x = &mesh.points[b];
                    lc.offset +=
                        w * ((0..self.dim).map(|i| normal[i] * x[i]).sum::<f64>() - offset);
                    for (i, ni) in normal.iter().enumerate() {
                        if let Some(d) = dofs.of(bi, b, i) {
                            lc.dofs.push(d);
                            lc.normal.push(w * ni);
                            for (row, tj) in lc.tangents.iter_mut().zip(&t) {
                                row.push(w * tj[i]);
                            }
                        }
                    }
                }
                lc
            })
            .collect();
        Ok((Box::new(LinearContacts::new(rows)?), labels))
    }
}

impl Sides<'_> {
    /// The surface rule's mortar rows of entry `ci` (`c`) between bodies
    /// ([`crate::contact::mortar`]): the boundary facets of `c`'s body whose nodes all
    /// lie in the kept `nodes` against the target's surface, on the kept `dofs`
    /// (a fixed node's position enters the gap only); with the node each row is named
    /// by.
    pub(super) fn mortar_set(
        &self,
        (ci, c): (usize, &ContactSpec),
        t: &TargetSpec,
        nodes: &[usize],
        dofs: Dofs,
    ) -> Result<(Box<dyn ContactSet>, Vec<usize>), Error> {
        use crate::contact::linear::{LinearContact, LinearContacts};
        if t.pairing != Pairing::NodeToSurface {
            return Err(Error::invalid(
                "target.pairing",
                "node-to-node",
                "pairs nodes; rule = \"surface\" integrates over the faces (leave one out)",
            ));
        }
        let (bi, ti) = (
            self.scene.body_index(&c.body),
            self.scene.body_index(&t.body),
        );
        let (mesh, target) = (&self.meshes[bi], &self.meshes[ti]);
        let facets = mesh.boundary_facets(nodes);
        let rows = crate::contact::mortar::mortar_rows(
            self.scene.bodies[bi].formulation,
            (&facets, &mesh.points),
            (&self.facets_of[ci], &target.points),
        )?;
        if rows.is_empty() {
            return Err(Error::invalid(
                "rule",
                "surface",
                &format!(
                    "no face of `{}` has a face of body \"{}\" (surface `{}`) facing it",
                    c.nodes, t.body, t.surface
                ),
            ));
        }
        let law = crate::contact::ContactLaw {
            restitution: c.restitution,
            friction: c.friction,
        };
        let labels = rows.iter().map(|r| r.node).collect();
        let dim = self.dim;
        let rows = rows
            .into_iter()
            .map(|r| {
                // the row's frame: its normal the direction of its slave gradient (the
                // faces' mean inward normal under `Φ_a`), the tangents of that normal;
                // the tangential rows weigh the relative velocity as the normal row does
                let mut n = [0.0; 3];
                for (_, w) in &r.slave {
                    for i in 0..3 {
                        n[i] += w[i];
                    }
                }
                let len = n.iter().map(|x| x * x).sum::<f64>().sqrt();
                let t = crate::contact::frame::tangents(&n.map(|x| x / len)[..dim]);
                let k = if law.friction > 0.0 { dim - 1 } else { 0 };
                let mut lc = LinearContact {
                    dofs: Vec::new(),
                    offset: r.gap,
                    normal: Vec::new(),
                    tangents: vec![Vec::new(); k],
                    law,
                };
                for (body, terms, weights) in [
                    (bi, &r.slave, &r.slave_weights),
                    (ti, &r.master, &r.master_weights),
                ] {
                    for ((v, w), s) in terms.iter().zip(weights) {
                        for (i, wi) in w.iter().enumerate().take(dim) {
                            if let Some(d) = dofs.of(body, *v, i) {
                                lc.dofs.push(d);
                                lc.normal.push(*wi);
                                for (row, tj) in lc.tangents.iter_mut().zip(&t) {
                                    row.push(s * tj[i]);
                                }
                            }
                        }
                    }
                }
                lc
            })
            .collect();
        Ok((Box::new(LinearContacts::new(rows)?), labels))
    }
}
