//! The rows of contact entries that are not one node against one obstacle point: the
//! surface rule against a plane (rows at face points, or per face node on triangles,
//! [`crate::contact::surface`]), mortar rows between bodies ([`crate::contact::mortar`]),
//! and node rows on a plane for nodes with held components (symmetry planes). Each is a
//! set of constant rows ([`crate::contact::linear::LinearContacts`]).

use super::contacts::{Dofs, Sides};
use super::*;
use crate::contact::ContactLaw;
use crate::contact::linear::{LinearContact, LinearContacts};

/// A surface rule's contact set, the node each row is named by, and whether the rows
/// are per face node.
pub(super) type SurfaceSet = (Box<dyn ContactSet>, Vec<usize>, bool);

impl Sides<'_> {
    /// One constant row ([`LinearContact`]) with `law`, its gap `offset` at `q = 0` and
    /// its `terms` `(body, node, gradient, weight)`: the normal row puts `gradient` on
    /// the node's kept dofs, the tangential rows (with friction) `weight · t` for the
    /// tangents `t`; a held component is left out (its displacement enters `offset`
    /// only). A tangential row left empty by held components is dropped (the node cannot
    /// slip that way), and a row left with none is frictionless.
    fn constant_row(
        &self,
        dofs: Dofs,
        (law, offset, t): (ContactLaw, f64, &[[f64; 3]; 2]),
        terms: impl IntoIterator<Item = (usize, usize, [f64; 3], f64)>,
    ) -> LinearContact {
        let k = if law.friction > 0.0 { self.dim - 1 } else { 0 };
        let mut lc = LinearContact {
            dofs: Vec::new(),
            offset,
            normal: Vec::new(),
            tangents: vec![Vec::new(); k],
            law,
        };
        for (body, v, g, s) in terms {
            for (i, gi) in g.iter().enumerate().take(self.dim) {
                if let Some(d) = dofs.of(body, v, i) {
                    lc.dofs.push(d);
                    lc.normal.push(*gi);
                    for (row, tj) in lc.tangents.iter_mut().zip(t) {
                        row.push(s * tj[i]);
                    }
                }
            }
        }
        lc.tangents
            .retain(|row| row.iter().any(|x| x.abs() > 1e-12));
        if lc.tangents.is_empty() {
            lc.law.friction = 0.0;
        }
        lc
    }

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
        let mesh = &self.meshes[bi];
        let t = crate::contact::frame::tangents(&normal[..self.dim]);
        let k = if c.friction > 0.0 { self.dim - 1 } else { 0 };
        let law = ContactLaw {
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
            for i in 0..self.dim {
                let moved_along_slip =
                    moving.contains(&(v, i)) && t[..k].iter().any(|tj| tj[i].abs() > 1e-12);
                if dofs.of(bi, v, i).is_none() && (normal[i].abs() > 1e-12 || moved_along_slip) {
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
            }
            let x = &mesh.points[v];
            let gap = (0..self.dim).map(|i| normal[i] * x[i]).sum::<f64>() - offset;
            let n: [f64; 3] = std::array::from_fn(|i| normal.get(i).copied().unwrap_or(0.0));
            rows.push(self.constant_row(dofs, (law, gap, &t), [(bi, v, n, 1.0)]));
        }
        Ok(Box::new(LinearContacts::new(rows)?))
    }

    /// The surface rule's rows of `c` (of body `bi`) against its plane obstacle
    /// ([`crate::contact::surface`]): at the points of the boundary facets whose nodes
    /// all lie in the kept `nodes`, on the kept `dofs` (a fixed node's position only
    /// enters the offset); with the node each row is named by, and whether the rows are
    /// per face node ([`crate::contact::surface::per_node`]).
    pub(super) fn surface_set(
        &self,
        c: &ContactSpec,
        bi: usize,
        nodes: &[usize],
        dofs: Dofs,
    ) -> Result<SurfaceSet, Error> {
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
        let law = ContactLaw {
            restitution: c.restitution,
            friction: c.friction,
        };
        // the plane's frame: its tangential rows weigh the face point's velocity as its
        // normal row does
        let t = crate::contact::frame::tangents(&normal[..self.dim]);
        let n: [f64; 3] = std::array::from_fn(|i| normal.get(i).copied().unwrap_or(0.0));
        let labels = rows.iter().map(|r| r.0).collect();
        let rows = rows
            .into_iter()
            .map(|(_, row)| {
                let gap = row
                    .iter()
                    .map(|&(b, w)| {
                        let x = &mesh.points[b];
                        w * ((0..self.dim).map(|i| n[i] * x[i]).sum::<f64>() - offset)
                    })
                    .sum();
                let terms = row.into_iter().map(|(b, w)| (bi, b, n.map(|ni| w * ni), w));
                self.constant_row(dofs, (law, gap, &t), terms)
            })
            .collect();
        let per_node = facets
            .first()
            .is_some_and(|f| crate::contact::surface::per_node(self.dim, f.len()));
        Ok((Box::new(LinearContacts::new(rows)?), labels, per_node))
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
        if t.pairing != Pairing::NodeToSurface {
            return Err(Error::invalid(
                "target.pairing",
                "node-to-node",
                "pairs nodes; rule = \"surface\" integrates over the faces (leave one out)",
            ));
        }
        // the node-to-surface search's options would be ignored without a word
        if let Some((key, value)) = t
            .search
            .map(|s| ("target.search", crate::error::num(s)))
            .or(t.capacity.map(|c| ("target.capacity", c.to_string())))
        {
            return Err(Error::invalid(
                key,
                value,
                "belongs to node-to-surface rows; mortar rows (rule = \"surface\") pair the \
                 faces once at set-up and search nothing (leave it out)",
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
        let law = ContactLaw {
            restitution: c.restitution,
            friction: c.friction,
        };
        let labels = rows.iter().map(|r| r.node).collect();
        let rows = rows
            .into_iter()
            .map(|r| {
                // the row's frame: its normal the direction of its slave gradient (the
                // faces' mean inward normal under `Φ_a`), the tangents of that normal;
                // the tangential rows weigh the relative velocity as the normal row does
                let n = r
                    .slave
                    .iter()
                    .fold([0.0; 3], |n, (_, w)| std::array::from_fn(|i| n[i] + w[i]));
                let len = n.iter().map(|x| x * x).sum::<f64>().sqrt();
                let t = crate::contact::frame::tangents(&n.map(|x| x / len)[..self.dim]);
                let slave = r.slave.iter().zip(&r.slave_weights);
                let master = r.master.iter().zip(&r.master_weights);
                let terms = slave
                    .map(|((v, w), s)| (bi, *v, *w, *s))
                    .chain(master.map(|((v, w), s)| (ti, *v, *w, *s)));
                self.constant_row(dofs, (law, r.gap, &t), terms)
            })
            .collect();
        Ok((Box::new(LinearContacts::new(rows)?), labels))
    }
}
