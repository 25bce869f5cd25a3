//! The contacts of a scene, two phases of [`Scene::build`]: each `[[contacts]]`
//! entry's nodes (its node set, kept `within` a distance at the starting positions, each
//! node once per obstacle or body), found body by body before the mass is assembled
//! (they take none under the redistributed mass); and, after the elimination, each
//! entry's contact set against a rigid obstacle or another body's surface, its starting
//! gaps checked by the scene's rule (`gaps`) as it is made.

use std::sync::Arc;

use super::*;

/// The bodies as the contacts see them, from the build's earlier phases: the meshes,
/// the starting displacements, the master surfaces and where each body's points start.
pub(super) struct Sides<'a> {
    /// The scene being built.
    pub(super) scene: &'a Scene,
    /// The scene's dimension.
    pub(super) dim: usize,
    /// Every body's mesh.
    pub(super) meshes: &'a [Mesh],
    /// Each body's `initial_displacement` (node-major, `dim` per node).
    pub(super) displacements: &'a [Option<Vec<f64>>],
    /// The master surface of each contact between bodies (facets over its body's node
    /// numbers, outward; empty for a contact with an obstacle).
    pub(super) facets_of: &'a [Vec<Vec<usize>>],
    /// The facets of each master surface left out on the axis r = 0.
    pub(super) axis_facets: &'a [usize],
    /// Each body's first point in the geometry.
    pub(super) point_base: &'a [usize],
}

/// Where a body's nodal dofs went in the elimination: `map` (full dof → kept dof, `None`
/// where fixed or prescribed) and each body's first full dof.
#[derive(Clone, Copy)]
pub(super) struct Dofs<'a> {
    /// Full dof → kept dof.
    pub(super) map: &'a [Option<usize>],
    /// Each body's first full dof.
    pub(super) offsets: &'a [usize],
    /// Components per node.
    pub(super) dim: usize,
}

impl Dofs<'_> {
    /// The kept dof of component `i` of node `v` of body `body`.
    fn of(&self, body: usize, v: usize, i: usize) -> Option<usize> {
        self.map[self.offsets[body] + v * self.dim + i]
    }
}

/// The contact sets of a scene (composed when more than one), a line per contact between
/// bodies for the report, and the scene's starting-gap rule.
pub(super) type ContactSets = (Box<dyn ContactSet>, Vec<String>, StartingGaps);

impl Sides<'_> {
    /// Body `bi`'s contact nodes, which take no mass under the redistributed mass: the
    /// nodes of each of its entries (stored in `nodes_of`, `boundary`, `all` and
    /// `within` included; the same node twice against one obstacle or body refused),
    /// and the master surfaces on it (both sides of an interface, as Khenous–Laborde–
    /// Renard redistribute it); sorted, once each.
    pub(super) fn body_contact_nodes(
        &self,
        bi: usize,
        nodes_of: &mut [Vec<usize>],
    ) -> Result<Vec<usize>, Error> {
        let b = &self.scene.bodies[bi];
        let mesh = &self.meshes[bi];
        let mut contact_nodes = Vec::new();
        // (obstacle, node) → the contact that first listed it
        let mut first_of = std::collections::HashMap::new();
        let own = self.scene.contacts.iter().enumerate();
        for (ci, c) in own.filter(|(_, c)| c.body == b.name) {
            nodes_of[ci] = self
                .contact_nodes(mesh, c, &self.facets_of[ci])
                .map_err(|e| prefix(&format!("contacts[{ci}]"), e))?;
            let other = match (&c.obstacle, &c.target) {
                (Some(o), _) => format!("obstacle \"{o}\""),
                (_, Some(t)) => format!("body \"{}\"", t.body),
                _ => unreachable!("validated"),
            };
            for &v in &nodes_of[ci] {
                // the same constraint twice makes two equal rows of G: a singular
                // contact problem that the solvers report only as a breakdown
                if let Some(first) = first_of.insert((other.clone(), v), ci) {
                    return Err(prefix(
                        &format!("contacts[{ci}]"),
                        Error::invalid(
                            "nodes",
                            mesh.node_label(v),
                            &format!(
                                "already meets {other} through contacts[{first}]; \
                                 list each node once per obstacle or body",
                            ),
                        ),
                    ));
                }
            }
            contact_nodes.extend_from_slice(&nodes_of[ci]);
        }
        for (ci, c) in self.scene.contacts.iter().enumerate() {
            if c.target.as_ref().is_some_and(|t| t.body == b.name) {
                contact_nodes.extend(self.facets_of[ci].iter().flatten().copied());
            }
        }
        contact_nodes.sort_unstable();
        contact_nodes.dedup();
        Ok(contact_nodes)
    }

    /// The nodes of contact `c` on `mesh`: its node set (`boundary` and `all`
    /// included), kept where the gap to the obstacle (or the distance to the target
    /// surface `facets`) at the starting positions — reference plus each body's
    /// `initial_displacement` — is at most `within`.
    fn contact_nodes(
        &self,
        mesh: &Mesh,
        c: &ContactSpec,
        facets: &[Vec<usize>],
    ) -> Result<Vec<usize>, Error> {
        let (dim, meshes, displacements) = (self.dim, self.meshes, self.displacements);
        let nodes = node_set(mesh, &c.nodes)?;
        let Some(d) = c.within else {
            return Ok(nodes);
        };
        require_positive("within", d)?;
        let bi = self.scene.body_index(&c.body);
        // a node's starting position: its reference position plus the body's
        // `initial_displacement` (a body lifted 0.5 mm above its floor had no node
        // "within" 1 mm when measured at the reference)
        let start = |body: usize, v: usize| -> [f64; 3] {
            let mut x = meshes[body].points[v];
            if let Some(u) = &displacements[body] {
                for (i, xi) in x.iter_mut().enumerate().take(dim) {
                    *xi += u[v * dim + i];
                }
            }
            x
        };
        if let Some(t) = &c.target {
            // the distance to the nearest facet's box (a lower bound of the distance to
            // the surface: keeps every node within `d`, and a few more)
            let ti = self.scene.body_index(&t.body);
            let master: Vec<[f64; 3]> =
                (0..meshes[ti].points.len()).map(|v| start(ti, v)).collect();
            let dist = crate::contact::bodies::box_distances(
                nodes.iter().map(|&v| start(bi, v)),
                facets,
                &master,
            );
            return keep_within(&nodes, &dist, d, &c.nodes, "the target surface");
        }
        let obstacle = self.scene.obstacle(c);
        // the gaps at the starting positions, through the obstacle's own gap function
        // (node-local dofs: q is the initial displacement there)
        let dofs: Vec<Vec<usize>> = (0..nodes.len())
            .map(|k| (0..dim).map(|i| k * dim + i).collect())
            .collect();
        let refs: Vec<Vec<f64>> = nodes
            .iter()
            .map(|&v| mesh.points[v][..dim].to_vec())
            .collect();
        let set = obstacle
            .shape()
            .contact_set(dofs, refs, c.restitution, c.friction)?;
        let mut jac = crate::contact::ContactJacobian::for_set(set.as_ref());
        let mut gap = vec![0.0; set.len()];
        let q: Vec<f64> = match &displacements[bi] {
            Some(u) => nodes
                .iter()
                .flat_map(|&v| (0..dim).map(move |i| u[v * dim + i]))
                .collect(),
            None => vec![0.0; nodes.len() * dim],
        };
        set.evaluate(&q, &mut gap, &mut jac);
        keep_within(&nodes, &gap, d, &c.nodes, "the obstacle")
    }

    /// Every entry's contact set on the kept `dofs`, from its nodes (`nodes_of`), each
    /// refused when a node starts (at `q0`) deeper inside than its `overlap_tolerance`;
    /// the entries' contacts are recorded in `points`, one per node in order (as both
    /// kinds of set make them).
    pub(super) fn contact_sets(
        &self,
        mut nodes_of: Vec<Vec<usize>>,
        dofs: Dofs,
        q0: &[f64],
        points: &mut Vec<crate::model::geometry::ContactPoint>,
    ) -> Result<ContactSets, Error> {
        let mut sets: Vec<Box<dyn ContactSet>> = Vec::new();
        let (mut interfaces, mut gaps) = (Vec::new(), StartingGaps::default());
        let labels: Vec<Arc<Mesh>> = self.meshes.iter().map(label_mesh).collect();
        for (ci, c) in self.scene.contacts.iter().enumerate() {
            let at = |e: Error| prefix(&format!("contacts[{ci}]"), e);
            let bi = self.scene.body_index(&c.body);
            let mut nodes = std::mem::take(&mut nodes_of[ci]);
            let (set, against, target) = match &c.target {
                Some(t) if c.rule == ContactRule::Surface => {
                    let (set, rows) = self.mortar_set((ci, c), t, &nodes, dofs).map_err(at)?;
                    interfaces.push(format!(
                        "contacts[{ci}]: {} mortar rows of \"{}\" (rule = \"surface\", small \
                         sliding: weights of the reference configuration, {} face nodes) \
                         against body \"{}\" (surface `{}`)",
                        rows.len(),
                        c.body,
                        nodes.len(),
                        t.body,
                        t.surface
                    ));
                    nodes = rows;
                    let against = format!("body \"{}\" (surface `{}`)", t.body, t.surface);
                    (set, against, t.body.clone())
                }
                Some(t) => {
                    let (set, line) = self.interface((ci, c), t, &nodes, dofs).map_err(at)?;
                    interfaces.push(line);
                    let against = format!("body \"{}\" (surface `{}`)", t.body, t.surface);
                    (set, against, t.body.clone())
                }
                None if c.rule == ContactRule::Surface => {
                    let name = self.scene.obstacle(c).name().to_string();
                    let (set, rows) = self.surface_set(c, bi, &nodes, dofs).map_err(at)?;
                    // triangle faces take rows per face node (contact::surface)
                    let triangles = self.meshes[bi].cells.first().is_some_and(|(k, _)| {
                        matches!(
                            k,
                            crate::model::element::CellKind::Tet4
                                | crate::model::element::CellKind::Tet10
                        )
                    });
                    interfaces.push(format!(
                        "contacts[{ci}]: {} rows of \"{}\" {} (rule = \"surface\", {} face nodes) \
                         against obstacle \"{name}\"",
                        rows.len(),
                        c.body,
                        if triangles {
                            "at its face nodes, weighted over its faces"
                        } else {
                            "at points of its faces"
                        },
                        nodes.len(),
                    ));
                    // the outputs name each row by its nearest face node
                    nodes = rows;
                    (set, format!("obstacle \"{name}\" (surface rule)"), name)
                }
                None => {
                    let name = self.scene.obstacle(c).name().to_string();
                    let set = self.obstacle_set(c, bi, &nodes, dofs).map_err(at)?;
                    (set, format!("obstacle \"{name}\""), name)
                }
            };
            let first = points.len();
            let rule = EntryGaps::new(
                (ci, c),
                first,
                &self.meshes[bi],
                labels[bi].clone(),
                &nodes,
                against,
            )
            .map_err(at)?;
            let mut gap = vec![0.0; set.len()];
            set.starting_gaps(q0, &mut gap);
            rule.check(&gap).map_err(at)?;
            gaps.push(rule);
            sets.push(set);
            points.extend(nodes.iter().map(|&v| crate::model::geometry::ContactPoint {
                point: self.point_base[bi] + v,
                body: bi,
                target: target.clone(),
                entry: ci,
            }));
        }
        let contacts: Box<dyn ContactSet> = if sets.len() == 1 {
            sets.pop().expect("one set")
        } else {
            Box::new(Composite::new(sets))
        };
        Ok((contacts, interfaces, gaps))
    }

    /// The contact set of entry `ci` (`c`) between bodies: its `nodes` against the
    /// target `t`'s surface, on the kept `dofs`; and its line in the report.
    fn interface(
        &self,
        (ci, c): (usize, &ContactSpec),
        t: &TargetSpec,
        nodes: &[usize],
        dofs: Dofs,
    ) -> Result<(Box<dyn ContactSet>, String), Error> {
        let (bi, ti) = (
            self.scene.body_index(&c.body),
            self.scene.body_index(&t.body),
        );
        let mesh = &self.meshes[bi];
        let node_dofs = |body: usize, v: usize| -> [Option<usize>; 3] {
            let mut d = [None; 3];
            for (i, di) in d.iter_mut().enumerate().take(self.dim) {
                *di = dofs.of(body, v, i);
            }
            d
        };
        let set = crate::contact::bodies::build(
            crate::contact::bodies::Interface {
                dim: self.dim,
                slave: nodes,
                slave_points: &mesh.points,
                slave_dofs: &|v| node_dofs(bi, v),
                facets: &self.facets_of[ci],
                master_points: &self.meshes[ti].points,
                master_dofs: &|v| node_dofs(ti, v),
                names: Some((&c.body, &t.body, &|v| mesh.node_label(v))),
            },
            t.pairing == Pairing::NodeToNode,
            (c.restitution, c.friction),
            t.search,
            t.capacity
                .unwrap_or(crate::contact::bodies::DEFAULT_CAPACITY),
        )?;
        let line = format!(
            "contacts[{ci}]: {} nodes of \"{}\" against {}{}",
            set.0.len(),
            c.body,
            set.1,
            match self.axis_facets[ci] {
                0 => String::new(),
                k => format!(
                    " ({k} facet(s) of \"{}\" on the axis r = 0 left out: not \
                     surfaces of the revolved solid)",
                    t.body
                ),
            }
        );
        Ok((set.0, line))
    }

    /// The contact set of `c`'s `nodes` (of body `bi`) against its obstacle, on the kept
    /// `dofs`; a fixed node is refused.
    fn obstacle_set(
        &self,
        c: &ContactSpec,
        bi: usize,
        nodes: &[usize],
        dofs: Dofs,
    ) -> Result<Box<dyn ContactSet>, Error> {
        let obstacle = self.scene.obstacle(c);
        let mesh = &self.meshes[bi];
        let held = |v: usize| (0..self.dim).any(|i| dofs.of(bi, v, i).is_none());
        if let (true, Some((normal, offset))) =
            (nodes.iter().any(|&v| held(v)), obstacle.shape().plane())
        {
            return self.held_nodes_on_plane(c, bi, nodes, dofs, (&normal, offset));
        }
        let mut node_dofs = Vec::new();
        let mut refs = Vec::new();
        for &v in nodes {
            let d: Option<Vec<usize>> = (0..self.dim).map(|i| dofs.of(bi, v, i)).collect();
            let Some(d) = d else {
                return Err(Error::invalid(
                    "nodes",
                    mesh.node_label(v),
                    "is fixed and cannot be a contact node",
                ));
            };
            node_dofs.push(d);
            refs.push(mesh.points[v][..self.dim].to_vec());
        }
        obstacle
            .shape()
            .contact_set(node_dofs, refs, c.restitution, c.friction)
    }
}

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
    fn held_nodes_on_plane(
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
            if lc.dofs.is_empty() {
                return Err(Error::invalid(
                    "nodes",
                    mesh.node_label(v),
                    "is fixed and cannot be a contact node",
                ));
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
    fn surface_set(
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
    fn mortar_set(
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

/// The `nodes` whose initial distance `dist` to `what` is at most `within = d`; an error
/// naming the node set and the nearest distance when none is.
fn keep_within(
    nodes: &[usize],
    dist: &[f64],
    d: f64,
    set: &str,
    what: &str,
) -> Result<Vec<usize>, Error> {
    let kept: Vec<usize> = nodes
        .iter()
        .zip(dist)
        .filter(|(_, x)| **x <= d)
        .map(|(&v, _)| v)
        .collect();
    if kept.is_empty() {
        return Err(Error::invalid(
            "within",
            crate::error::num(d),
            &format!(
                "no node of `{set}` lies that close to {what} (the nearest is {:.3e} m away)",
                dist.iter().copied().fold(f64::INFINITY, f64::min)
            ),
        ));
    }
    Ok(kept)
}
