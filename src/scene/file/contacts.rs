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
    pub(super) fn of(&self, body: usize, v: usize, i: usize) -> Option<usize> {
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
                    let (set, rows, per_node) =
                        self.surface_set(c, bi, &nodes, dofs).map_err(at)?;
                    interfaces.push(format!(
                        "contacts[{ci}]: {} rows of \"{}\" {} (rule = \"surface\", {} face nodes) \
                         against obstacle \"{name}\"",
                        rows.len(),
                        c.body,
                        if per_node {
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
