//! Building a scene: meshes, materials and fixed dofs to the assembled structure, the
//! contact sets, loads, probes and the initial state, handed down as one
//! [`crate::integrators::Problem`] inside a [`Model`].

use super::*;

impl Scene {
    /// Meshes and assembles every body, eliminates fixed dofs, and builds the contacts.
    pub fn build(&self) -> Result<(Model, ModelReport), Error> {
        if let Some(x) = &self.example {
            let model = x.build()?;
            let report = ModelReport {
                dofs: model.problem.system.ndof(),
                cells: 0,
                contacts: model.problem.contacts.len(),
                linear_contacts: model.problem.contacts.is_linear(),
                max_friction: model
                    .problem
                    .contacts
                    .laws()
                    .iter()
                    .map(|l| l.friction)
                    .fold(0.0, f64::max),
                damping: model.problem.system.damping.is_some(),
                gravity: model.problem.system.force.iter().any(|&f| f != 0.0)
                    || matches!(x, super::super::example::ExampleSpec::SliderCrank { mechanism, .. }
                        if mechanism.gravity > 0.0),
                fixed_dofs: 0,
                linear_structure: model.problem.system.nonlinear.is_empty(),
                interfaces: Vec::new(),
            };
            return Ok((model, report));
        }
        self.validate()?;
        let mut systems = Vec::new();
        let mut v0 = Vec::new();
        let mut q0 = Vec::new();
        let mut fixed = Vec::new();
        let mut cells = 0;
        let dim = self.bodies[0].dim();
        let mut geometry = Geometry {
            dim,
            ..Geometry::default()
        };
        // each contact's nodes, found once with its body's mesh: they take no mass under
        // the redistributed mass, then become the contact set below
        let mut nodes_of: Vec<Vec<usize>> = vec![Vec::new(); self.contacts.len()];
        // every mesh first: a contact between bodies needs both sides' meshes
        let mut all_meshes = Vec::with_capacity(self.bodies.len());
        for (bi, b) in self.bodies.iter().enumerate() {
            let at = |e: Error| prefix(&format!("bodies[{bi}] ({})", b.name), e);
            if b.dim() != dim {
                return Err(at(Error::invalid(
                    "formulation",
                    b.dim(),
                    "all bodies need one dimension",
                )));
            }
            let mesh = b.mesh(&self.base_dir).map_err(at)?;
            // the mesh against the formulation before anything reads its cells as such
            if !matches!(b.mesh, MeshSpec::Rod { .. }) {
                crate::model::solid::check_mesh(&mesh, b.formulation).map_err(at)?;
            }
            all_meshes.push(mesh);
        }
        // each body's initial displacement (node-major, `dim` per node), before the
        // contacts: `within` is measured at the starting positions
        let mut u_of: Vec<Option<Vec<f64>>> = Vec::with_capacity(self.bodies.len());
        for (bi, b) in self.bodies.iter().enumerate() {
            let at = |e: Error| prefix(&format!("bodies[{bi}] ({})", b.name), e);
            u_of.push(match &b.initial_displacement {
                Some(field) => Some(
                    super::initial::nodal_field(
                        "initial_displacement",
                        "m",
                        field,
                        &self.base_dir,
                        all_meshes[bi].points.len(),
                        b.dim(),
                    )
                    .map_err(at)?,
                ),
                None => None,
            });
            if let Some(u) = &u_of[bi] {
                super::initial::within_bound("initial_displacement", u, b.dim(), "m")
                    .map_err(at)?;
            }
            // a cell inverted at the start, in the mesh or by the displacement
            if !matches!(b.mesh, MeshSpec::Rod { .. }) {
                super::initial::check_orientation(&all_meshes[bi], b, u_of[bi].as_deref())
                    .map_err(at)?;
            }
        }
        // the probes' node sets, before any assembly: a misspelt set is refused at once
        let point_base = starts(all_meshes.iter().map(|m| m.points.len()));
        let probes = self.probes(&all_meshes, &point_base)?;
        // the master surface of each contact between bodies (facets over its body's
        // node numbers, outward)
        let mut facets_of: Vec<Vec<Vec<usize>>> = vec![Vec::new(); self.contacts.len()];
        let mut axis_facets = vec![0; self.contacts.len()];
        for (ci, c) in self.contacts.iter().enumerate() {
            if let Some(t) = &c.target {
                let ti = self.body_index(&t.body);
                (facets_of[ci], axis_facets[ci]) =
                    target_facets(&all_meshes[ti], &self.bodies[ti], t)
                        .map_err(|e| prefix(&format!("contacts[{ci}].target"), e))?;
            }
        }
        for (bi, b) in self.bodies.iter().enumerate() {
            let at = |e: Error| prefix(&format!("bodies[{bi}] ({})", b.name), e);
            let mesh = &all_meshes[bi];
            cells += mesh.cells.len().max(match b.mesh {
                MeshSpec::Rod { elements, .. } => elements,
                _ => 0,
            });
            // contact nodes of this body (for the redistributed mass): the same nodes
            // as the contacts below, `boundary`, `all` and `within` included
            let mut contact_nodes = Vec::new();
            // (obstacle, node) → the contact that first listed it
            let mut first_of = std::collections::HashMap::new();
            for (ci, c) in self
                .contacts
                .iter()
                .enumerate()
                .filter(|(_, c)| c.body == b.name)
            {
                nodes_of[ci] = self
                    .contact_nodes(mesh, c, dim, &facets_of[ci], &all_meshes, &u_of)
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
            // the master surfaces on this body take no mass either (both sides of an
            // interface, as Khenous–Laborde–Renard redistribute it)
            for (ci, c) in self.contacts.iter().enumerate() {
                if c.target.as_ref().is_some_and(|t| t.body == b.name) {
                    contact_nodes.extend(facets_of[ci].iter().flatten().copied());
                }
            }
            contact_nodes.sort_unstable();
            contact_nodes.dedup();
            let mut sys = match &b.mesh {
                MeshSpec::Rod {
                    elements,
                    length,
                    area,
                    ..
                } => Rod {
                    length: *length,
                    area: *area,
                    young: b.material.young,
                    density: b.material.density,
                    elements: *elements,
                    mass: b.mass,
                }
                .assemble()
                .map_err(at)?,
                _ => {
                    assemble_with_contacts(mesh, &b.material, b.formulation, b.mass, &contact_nodes)
                        .map_err(at)?
                }
            };
            if let Some(r) = b.damping {
                sys = sys.with_rayleigh(r.alpha, r.beta).map_err(at)?;
            }
            if let Some(g) = &self.loads.gravity {
                sys.add_gravity(g).map_err(|e| prefix("loads", e))?;
            }
            let n = sys.ndof();
            let vel = b.velocity.clone().unwrap_or_else(|| vec![0.0; dim]);
            if vel.len() != dim || vel.iter().any(|x| !x.is_finite()) {
                return Err(at(Error::invalid(
                    "velocity",
                    format!("{vel:?}"),
                    &format!("needs {dim} finite values"),
                )));
            }
            let first = v0.len();
            super::initial::one_initial_motion(b).map_err(at)?;
            match (&b.initial_velocity, &b.angular_velocity) {
                (Some(field), _) => v0.extend(
                    super::initial::nodal_field(
                        "initial_velocity",
                        "m/s",
                        field,
                        &self.base_dir,
                        n / dim,
                        dim,
                    )
                    .map_err(at)?,
                ),
                (None, None) if b.rotation_center.is_none() => {
                    v0.extend((0..n).map(|i| vel[i % dim]))
                }
                (None, omega) => v0.extend(
                    super::initial::rigid_motion(b, mesh, &sys, dim, &vel, omega.as_deref())
                        .map_err(at)?,
                ),
            }
            let mut fx = vec![false; n];
            for name in &b.fixed {
                let set = node_set(mesh, name).map_err(|e| at(prefix("fixed", e)))?;
                for &v in &set {
                    for i in 0..dim {
                        fx[v * dim + i] = true;
                    }
                }
            }
            // every initial motion, the rigid one included: the elimination would drop
            // its values on fixed components (a spin given by angular_velocity stopped
            // at the fixed nodes, silently)
            super::initial::zero_where_fixed(super::initial::motion_key(b), &v0[first..], &fx, dim)
                .map_err(at)?;
            super::initial::within_bound(super::initial::motion_key(b), &v0[first..], dim, "m/s")
                .map_err(at)?;
            match &u_of[bi] {
                Some(u) => {
                    super::initial::zero_where_fixed("initial_displacement", u, &fx, dim)
                        .map_err(at)?;
                    q0.extend_from_slice(u);
                }
                None => q0.extend(std::iter::repeat_n(0.0, n)),
            }
            fixed.extend(fx);
            let base = geometry.points.len();
            match &b.mesh {
                MeshSpec::Rod { elements, .. } => {
                    geometry.cells.extend(
                        (0..*elements).map(|e| (GeomCell::Line, vec![base + e, base + e + 1], bi)),
                    );
                }
                _ => geometry.cells.extend(mesh.cells.iter().map(|(k, c)| {
                    (
                        GeomCell::Solid(*k),
                        c.iter().map(|v| base + v).collect(),
                        bi,
                    )
                })),
            }
            geometry.node_ids.extend(
                (0..mesh.points.len()).map(|k| mesh.node_ids.get(k).copied().unwrap_or(k as u64)),
            );
            geometry.points.extend_from_slice(&mesh.points);
            geometry.bodies.push((b.material, b.formulation));
            systems.push(sys);
        }
        let meshes = all_meshes;
        let offsets = starts(systems.iter().map(LinearSystem::ndof));
        let full = LinearSystem::block_diagonal(systems)?;
        let fixed_dofs = fixed.iter().filter(|&&f| f).count();
        // prescribed velocities: eliminated with their coupling blocks
        let mut prescribed = vec![None; full.ndof()];
        let mut functions = Vec::new();
        for (pi, p) in self.prescribed.iter().enumerate() {
            let at = |e: Error| prefix(&format!("prescribed[{pi}]"), e);
            let bi = self
                .bodies
                .iter()
                .position(|b| b.name == p.body)
                .expect("validated");
            let dim = self.bodies[bi].dim();
            let nodes = node_set(&meshes[bi], &p.nodes).map_err(at)?;
            let comps: Vec<usize> = p.components.clone().unwrap_or_else(|| (0..dim).collect());
            functions.push(time_function(&format!("prescribed[{pi}].time"), &p.time)?);
            for &v in &nodes {
                for &c in &comps {
                    let d = offsets[bi] + v * dim + c;
                    if fixed[d] || prescribed[d].is_some() {
                        return Err(at(Error::invalid(
                            "nodes",
                            format!("{} component {c}", meshes[bi].node_label(v)),
                            "is already fixed or prescribed",
                        )));
                    }
                    prescribed[d] = Some((p.velocity[c], functions.len() - 1));
                    // a prescribed component starts at its prescribed motion: a
                    // different initial value there would be dropped by the elimination
                    let b = &self.bodies[bi];
                    let w0 = p.velocity[c] * functions[functions.len() - 1].eval(0.0);
                    let body = |e: Error| prefix(&format!("bodies[{bi}] ({})", b.name), e);
                    if b.initial_velocity.is_some()
                        || b.velocity.is_some()
                        || b.angular_velocity.is_some()
                    {
                        super::initial::as_prescribed(
                            super::initial::motion_key(b),
                            v0[d],
                            w0,
                            &meshes[bi].node_label(v),
                            c,
                            pi,
                        )
                        .map_err(body)?;
                    }
                    if b.initial_displacement.is_some() {
                        super::initial::as_prescribed(
                            "initial_displacement",
                            q0[d],
                            0.0,
                            &meshes[bi].node_label(v),
                            c,
                            pi,
                        )
                        .map_err(body)?;
                    }
                }
            }
        }
        geometry.prescribed = (0..full.ndof())
            .filter_map(|d| match prescribed[d] {
                Some((w, f)) if !fixed[d] => Some((d, w, f)),
                _ => None,
            })
            .collect();
        geometry.prescribed_functions = functions.clone();
        let (mut system, map) = full.restrict_prescribed(&fixed, &prescribed, functions);
        // large-deformation bodies: their internal forces on the kept dofs
        for (bi, b) in self.bodies.iter().enumerate() {
            let Some(law) = b.material.model.hyperelastic(&b.material) else {
                continue;
            };
            let at = |e: Error| prefix(&format!("bodies[{bi}] ({})", b.name), e);
            let mesh = &meshes[bi];
            let n = b.dim() * mesh.points.len();
            let dofs: Vec<Option<usize>> = (0..n).map(|i| map[offsets[bi] + i]).collect();
            if let Some(i) = (0..n).find(|&i| prescribed[offsets[bi] + i].is_some()) {
                return Err(at(Error::invalid(
                    "material.model",
                    b.material.model.name(),
                    &format!(
                        "takes no prescribed velocities yet (node {} is in a [[prescribed]] \
                         set); hold it with `fixed`, or use model = \"linear\"",
                        i / b.dim()
                    ),
                )));
            }
            let body = HyperBody::new(mesh, law).map_err(|e| at(prefix("mesh", e)))?;
            // inverted at a quadrature point by the initial displacement (the corners
            // were checked with the mesh): bad input, not a step that is too large
            if let Some(Err(c)) = u_of[bi].as_deref().map(|u| body.strain_energy(u)) {
                let cell = match mesh.cell_ids.get(c.cell) {
                    Some(tag) => format!("cell {tag} (file tag)"),
                    None => format!("cell {}", c.cell),
                };
                return Err(at(Error::invalid(
                    "initial_displacement",
                    format!("{cell}: det F = {:.3e} at a quadrature point", c.det),
                    "inverts the cell at the start (det F ≤ 0): no body starts turned \
                     inside out; check the displacement's sign and its rows' node order",
                )));
            }
            let part =
                HyperelasticPart::new(&b.name, body, dofs, mesh.cell_ids.clone()).map_err(at)?;
            system.add_nonlinear_part(std::sync::Arc::new(part));
        }
        geometry.dof_of = map.clone();
        let kept = |x: Vec<f64>| -> Vec<f64> {
            x.iter()
                .zip(&map)
                .filter(|(_, m)| m.is_some())
                .map(|(v, _)| *v)
                .collect()
        };
        let (v0, q0) = (kept(v0), kept(q0));
        // forces on node sets (after the elimination: loads on fixed dofs are dropped,
        // the supports carry them)
        for (fi, f) in self.forces.iter().enumerate() {
            let at = |e: Error| prefix(&format!("forces[{fi}]"), e);
            let bi = self
                .bodies
                .iter()
                .position(|b| b.name == f.body)
                .expect("validated");
            let mesh = &meshes[bi];
            let nodes = node_set(mesh, &f.nodes).map_err(at)?;
            if nodes.is_empty() {
                return Err(at(Error::invalid(
                    "nodes",
                    &f.nodes,
                    "the node set is empty",
                )));
            }
            let dim = self.bodies[bi].dim();
            let share = 1.0 / nodes.len() as f64;
            let (mut dofs, mut values) = (Vec::new(), Vec::new());
            for &v in &nodes {
                for (i, &t) in f.total.iter().enumerate() {
                    if let Some(d) = map[offsets[bi] + v * dim + i] {
                        dofs.push(d);
                        values.push(t * share);
                    }
                }
            }
            let time = time_function(&format!("forces[{fi}].time"), &f.time)?;
            system
                .loads
                .push(crate::model::NodalLoad { dofs, values, time });
        }
        // contacts
        let mut sets: Vec<Box<dyn ContactSet>> = Vec::new();
        let mut interfaces = Vec::new();
        for (ci, c) in self.contacts.iter().enumerate() {
            let at = |e: Error| prefix(&format!("contacts[{ci}]"), e);
            let bi = self
                .bodies
                .iter()
                .position(|b| b.name == c.body)
                .expect("validated");
            let mesh = &meshes[bi];
            let nodes = std::mem::take(&mut nodes_of[ci]);
            // the entry's contacts, one per node in order (as both kinds of set make them)
            let record = |out: &mut Vec<crate::model::geometry::ContactPoint>, target: &str| {
                out.extend(nodes.iter().map(|&v| crate::model::geometry::ContactPoint {
                    point: point_base[bi] + v,
                    body: bi,
                    target: target.to_string(),
                    entry: ci,
                }))
            };
            if let Some(t) = &c.target {
                let ti = self.body_index(&t.body);
                let node_dofs = |body: usize, v: usize| -> [Option<usize>; 3] {
                    let mut d = [None; 3];
                    for (i, di) in d.iter_mut().enumerate().take(dim) {
                        *di = map[offsets[body] + v * dim + i];
                    }
                    d
                };
                let set = crate::contact::bodies::build(
                    crate::contact::bodies::Interface {
                        dim,
                        slave: &nodes,
                        slave_points: &mesh.points,
                        slave_dofs: &|v| node_dofs(bi, v),
                        facets: &facets_of[ci],
                        master_points: &meshes[ti].points,
                        master_dofs: &|v| node_dofs(ti, v),
                        names: Some((&c.body, &t.body, &|v| mesh.node_label(v))),
                    },
                    t.pairing == Pairing::NodeToNode,
                    (c.restitution, c.friction),
                    t.search,
                    t.capacity
                        .unwrap_or(crate::contact::bodies::DEFAULT_CAPACITY),
                )
                .map_err(at)?;
                check_starting_gaps(
                    set.0.as_ref(),
                    &q0,
                    c,
                    mesh,
                    &nodes,
                    &format!("body \"{}\" (surface `{}`)", t.body, t.surface),
                )
                .map_err(at)?;
                interfaces.push(format!(
                    "contacts[{ci}]: {} nodes of \"{}\" against {}{}",
                    set.0.len(),
                    c.body,
                    set.1,
                    match axis_facets[ci] {
                        0 => String::new(),
                        k => format!(
                            " ({k} facet(s) of \"{}\" on the axis r = 0 left out: not \
                             surfaces of the revolved solid)",
                            t.body
                        ),
                    }
                ));
                sets.push(set.0);
                record(&mut geometry.contacts, &t.body);
                continue;
            }
            let obstacle = self.obstacle(c);
            let mut dofs = Vec::new();
            let mut refs = Vec::new();
            for &v in &nodes {
                let d: Option<Vec<usize>> =
                    (0..dim).map(|i| map[offsets[bi] + v * dim + i]).collect();
                let Some(d) = d else {
                    return Err(at(Error::invalid(
                        "nodes",
                        mesh.node_label(v),
                        "is fixed and cannot be a contact node",
                    )));
                };
                dofs.push(d);
                refs.push(mesh.points[v][..dim].to_vec());
            }
            let set = obstacle
                .shape()
                .contact_set(dofs, refs, c.restitution, c.friction)
                .map_err(at)?;
            check_starting_gaps(
                set.as_ref(),
                &q0,
                c,
                mesh,
                &nodes,
                &format!("obstacle \"{}\"", obstacle.name()),
            )
            .map_err(at)?;
            sets.push(set);
            record(&mut geometry.contacts, obstacle.name());
        }
        geometry.outlines = self
            .obstacles
            .iter()
            .map(|o| outline(o, &geometry.points, dim))
            .collect();
        let contacts: Box<dyn ContactSet> = if sets.len() == 1 {
            sets.pop().expect("one set")
        } else {
            Box::new(Composite::new(sets))
        };
        let report = ModelReport {
            dofs: system.ndof(),
            cells,
            contacts: contacts.len(),
            linear_contacts: contacts.is_linear(),
            max_friction: contacts
                .laws()
                .iter()
                .map(|l| l.friction)
                .fold(0.0, f64::max),
            damping: system.damping.is_some(),
            gravity: self.loads.gravity.is_some(),
            fixed_dofs,
            linear_structure: system.nonlinear.is_empty(),
            interfaces,
        };
        let n = system.ndof();
        if crate::model::ordering::worth_ordering(&geometry) {
            system.ordering = crate::model::ordering::candidate(self.scheme.ordering, &geometry, n)
                .map_err(|e| Error::invalid("scheme.ordering", self.scheme.ordering.name(), &e))?;
        }
        Ok((
            Model {
                problem: Problem::new(system, contacts, q0, v0),
                geometry,
                probes,
            },
            report,
        ))
    }

    /// The `[[probes]]` on the built meshes: each set's points in the geometry, and a
    /// rod's abscissae from its end of smallest `x`.
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

    /// The nodes of contact `c` on `mesh`: its node set (`boundary` and `all`
    /// included), kept where the gap to the obstacle (or the distance to the target
    /// surface) at the starting positions — reference plus each body's
    /// `initial_displacement` — is at most `within`.
    pub(super) fn contact_nodes(
        &self,
        mesh: &Mesh,
        c: &ContactSpec,
        dim: usize,
        facets: &[Vec<usize>],
        meshes: &[Mesh],
        displacements: &[Option<Vec<f64>>],
    ) -> Result<Vec<usize>, Error> {
        let nodes = node_set(mesh, &c.nodes)?;
        let Some(d) = c.within else {
            return Ok(nodes);
        };
        require_positive("within", d)?;
        let bi = self.body_index(&c.body);
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
            let ti = self.body_index(&t.body);
            let master: Vec<[f64; 3]> =
                (0..meshes[ti].points.len()).map(|v| start(ti, v)).collect();
            let dist = crate::contact::bodies::box_distances(
                nodes.iter().map(|&v| start(bi, v)),
                facets,
                &master,
            );
            return keep_within(&nodes, &dist, d, &c.nodes, "the target surface");
        }
        let obstacle = self.obstacle(c);
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

    /// The index of the body named `name` (validated to exist).
    pub(super) fn body_index(&self, name: &str) -> usize {
        self.bodies
            .iter()
            .position(|b| b.name == name)
            .expect("validated body name")
    }
}

/// Where each of consecutive blocks of `sizes` starts (the exclusive prefix sums): the
/// bodies' first point and first dof.
pub(super) fn starts(sizes: impl Iterator<Item = usize>) -> Vec<usize> {
    sizes
        .scan(0, |acc, n| {
            let start = *acc;
            *acc += n;
            Some(start)
        })
        .collect()
}

/// The time function of a `[[forces]]` / `[[prescribed]]` entry (1 when absent).
pub(super) fn time_function(
    field: &str,
    t: &Option<Vec<[f64; 2]>>,
) -> Result<crate::model::TimeFunction, Error> {
    match t {
        Some(t) => crate::model::TimeFunction::new(field, t.iter().map(|p| (p[0], p[1])).collect()),
        None => Ok(crate::model::TimeFunction::one()),
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
