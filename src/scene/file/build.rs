//! Building a scene: meshes, materials and fixed dofs to the assembled structure, the
//! contact sets, loads, probes and the initial state, handed down as one
//! [`crate::integrators::Problem`] inside a [`Model`].
//!
//! [`Scene::build`] runs these phases in order, each a function of this file (the
//! first four are `meshes`', the contacts' two `contacts`'); every error names the key path it comes from:
//! 1. `Scene::meshes`: every body's mesh (all first: a contact between bodies needs
//!    both sides' meshes), checked against its formulation;
//! 2. `Scene::initial_displacements`: each body's `initial_displacement`, before the
//!    contacts (`within` is measured at the starting positions);
//! 3. `Scene::probes`: the probes' node sets (a misspelt set is refused at once);
//! 4. `Scene::target_surfaces`: the master surface of each contact between bodies;
//! 5. `Build::assemble_bodies`: body by body, its contact nodes
//!    (`contacts::Sides::body_contact_nodes`), its assembly, its initial motion, its
//!    fixed components and its part of the geometry;
//! 6. `Build::prescribe`: the prescribed velocities on the block-diagonal structure;
//! 7. `Build::eliminate`: the fixed and prescribed dofs eliminated, the
//!    large-deformation bodies' internal forces on the kept ones;
//! 8. `Build::forces`: the forces on node sets;
//! 9. `contacts::Sides::contact_sets`: the contact sets, their starting gaps checked by
//!    the scene's rule (`gaps`);
//! 10. `Build::finish`: the obstacles' outlines, the report (built once, as an
//!     example scene's is), the dof ordering, the model.

use super::contacts::{Dofs, Sides};
use super::meshes::{Surface, at_body};
use super::*;

impl Scene {
    /// Meshes and assembles every body, eliminates fixed dofs, and builds the contacts.
    pub fn build(&self) -> Result<(Model, ModelReport), Error> {
        if let Some(x) = &self.example {
            return example_model(x);
        }
        self.validate()?;
        let dim = self.bodies[0].dim();
        let meshes = self.meshes(dim)?;
        let u_of = self.initial_displacements(&meshes)?;
        let point_base = starts(meshes.iter().map(|m| m.points.len()));
        let probes = self.probes(&meshes, &point_base)?;
        let (facets_of, axis_facets) = self.target_surfaces(&meshes)?;
        let mut b = Build {
            scene: self,
            dim,
            meshes,
            u_of,
            point_base,
            facets_of,
            axis_facets,
            geometry: Geometry {
                dim,
                ..Geometry::default()
            },
        };
        // each contact's nodes, found once with its body's mesh: they take no mass under
        // the redistributed mass, then become the contact set below
        let mut nodes_of: Vec<Vec<usize>> = vec![Vec::new(); self.contacts.len()];
        let mut bodies = b.assemble_bodies(&mut nodes_of)?;
        let offsets = starts(bodies.systems.iter().map(LinearSystem::ndof));
        let full = LinearSystem::block_diagonal(std::mem::take(&mut bodies.systems))?;
        let fixed_dofs = bodies.fixed.iter().filter(|&&f| f).count();
        let prescribed = b.prescribe(&offsets, &bodies, full.ndof())?;
        let (mut system, map) = b.eliminate(full, &bodies.fixed, prescribed, &offsets)?;
        let kept = |x: &[f64]| -> Vec<f64> {
            x.iter()
                .zip(&map)
                .filter(|(_, m)| m.is_some())
                .map(|(v, _)| *v)
                .collect()
        };
        let (v0, q0) = (kept(&bodies.v0), kept(&bodies.q0));
        b.forces(&mut system, &map, &offsets)?;
        let dofs = Dofs {
            map: &map,
            offsets: &offsets,
            dim,
        };
        let mut points = Vec::new();
        let sets = b.sides().contact_sets(nodes_of, dofs, &q0, &mut points)?;
        b.geometry.contacts = points;
        let counts = (bodies.cells, fixed_dofs);
        b.finish(
            Problem::new(system, sets.0, q0, v0),
            (sets.1, sets.2),
            counts,
            probes,
        )
    }
}

/// An `[example]` scene's model, with its report.
fn example_model(x: &crate::scene::example::ExampleSpec) -> Result<(Model, ModelReport), Error> {
    let model = x.build()?;
    let gravity = model.problem.system.force.iter().any(|&f| f != 0.0)
        || matches!(x, crate::scene::example::ExampleSpec::SliderCrank { mechanism, .. }
            if mechanism.gravity > 0.0);
    let report = ModelReport::of(&model.problem, (0, 0), gravity, Vec::new());
    Ok((model, report))
}

impl ModelReport {
    /// The report of `problem`, with what the problem does not hold: the cells and the
    /// fixed dofs (`counts`), whether a body force applies, the interfaces' lines.
    fn of(
        problem: &Problem,
        (cells, fixed_dofs): (usize, usize),
        gravity: bool,
        interfaces: Vec<String>,
    ) -> ModelReport {
        ModelReport {
            dofs: problem.system.ndof(),
            cells,
            contacts: problem.contacts.len(),
            linear_contacts: problem.contacts.is_linear(),
            max_friction: problem
                .contacts
                .laws()
                .iter()
                .map(|l| l.friction)
                .fold(0.0, f64::max),
            damping: problem.system.damping.is_some(),
            gravity,
            fixed_dofs,
            linear_structure: problem.system.nonlinear.is_empty(),
            interfaces,
        }
    }
}

/// What the phases of [`Scene::build`] hand on (module doc): the meshes and what was
/// found on them, and the geometry the bodies fill in as they are assembled.
struct Build<'a> {
    scene: &'a Scene,
    dim: usize,
    /// Every body's mesh (phase 1).
    meshes: Vec<Mesh>,
    /// Each body's `initial_displacement` (phase 2).
    u_of: Vec<Option<Vec<f64>>>,
    /// Each body's first point in the geometry.
    point_base: Vec<usize>,
    /// The master surface of each contact between bodies (phase 4).
    facets_of: Vec<Surface>,
    /// The facets of each master surface left out on the axis r = 0 (phase 4).
    axis_facets: Vec<usize>,
    /// Points, cells, dof map and contacts for the field output.
    geometry: Geometry,
}

/// The bodies assembled one by one (phase 5), before the elimination: their blocks,
/// initial motion and displacement, fixed components (all over the full dofs) and cells.
#[derive(Default)]
struct Bodies {
    systems: Vec<LinearSystem>,
    v0: Vec<f64>,
    q0: Vec<f64>,
    fixed: Vec<bool>,
    cells: usize,
}

/// The prescribed velocities (phase 6): for each full dof, its velocity and time
/// function when prescribed; the time functions.
type Prescribed = (Vec<Option<(f64, usize)>>, Vec<crate::model::TimeFunction>);

impl Build<'_> {
    /// The bodies as the contacts see them.
    fn sides(&self) -> Sides<'_> {
        Sides {
            scene: self.scene,
            dim: self.dim,
            meshes: &self.meshes,
            displacements: &self.u_of,
            facets_of: &self.facets_of,
            axis_facets: &self.axis_facets,
            point_base: &self.point_base,
        }
    }

    /// Phase 5: body by body, its contact nodes (into `nodes_of`), its assembly, its
    /// initial motion and displacement (zero where fixed), its fixed components and its
    /// part of the geometry.
    fn assemble_bodies(&mut self, nodes_of: &mut [Vec<usize>]) -> Result<Bodies, Error> {
        let (scene, mut out) = (self.scene, Bodies::default());
        for (bi, b) in scene.bodies.iter().enumerate() {
            let at = at_body(bi, b);
            let mesh = &self.meshes[bi];
            out.cells += mesh.cells.len().max(match b.mesh {
                MeshSpec::Rod { elements, .. } => elements,
                _ => 0,
            });
            let contact_nodes = self.sides().body_contact_nodes(bi, nodes_of)?;
            let sys = self.assemble_body(bi, &contact_nodes)?;
            let v0 = self.initial_velocity(bi, &sys)?;
            let fx = self.fixed_components(bi, sys.ndof())?;
            let (dim, key) = (self.dim, super::initial::motion_key(b));
            // every initial motion, the rigid one included: the elimination would drop
            // its values on fixed components (a spin given by angular_velocity stopped
            // at the fixed nodes, silently)
            super::initial::zero_where_fixed(key, &v0, &fx, dim).map_err(&at)?;
            super::initial::within_bound(key, &v0, dim, "m/s").map_err(&at)?;
            match &self.u_of[bi] {
                Some(u) => {
                    super::initial::zero_where_fixed("initial_displacement", u, &fx, dim)
                        .map_err(at)?;
                    out.q0.extend_from_slice(u);
                }
                None => out.q0.extend(std::iter::repeat_n(0.0, sys.ndof())),
            }
            out.v0.extend(v0);
            out.fixed.extend(fx);
            self.add_to_geometry(bi);
            out.systems.push(sys);
        }
        Ok(out)
    }

    /// Body `bi`'s structure (a rod's or a mesh's, with `contact_nodes` massless under
    /// the redistributed mass), its damping and the scene's gravity.
    fn assemble_body(&self, bi: usize, contact_nodes: &[usize]) -> Result<LinearSystem, Error> {
        let b = &self.scene.bodies[bi];
        let at = at_body(bi, b);
        let mesh = &self.meshes[bi];
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
            .map_err(&at)?,
            _ => assemble_with_contacts(mesh, &b.material, b.formulation, b.mass, contact_nodes)
                .map_err(&at)?,
        };
        if let Some(r) = b.damping {
            sys = sys.with_rayleigh(r.alpha, r.beta).map_err(at)?;
        }
        if let Some(g) = &self.scene.loads.gravity {
            sys.add_gravity(g).map_err(|e| prefix("loads", e))?;
        }
        Ok(sys)
    }

    /// Body `bi`'s initial velocity on the dofs of `sys`: its `initial_velocity` field,
    /// its uniform `velocity`, or the rigid motion with `angular_velocity`.
    fn initial_velocity(&self, bi: usize, sys: &LinearSystem) -> Result<Vec<f64>, Error> {
        let (b, dim) = (&self.scene.bodies[bi], self.dim);
        let at = at_body(bi, b);
        let n = sys.ndof();
        let vel = b.velocity.clone().unwrap_or_else(|| vec![0.0; dim]);
        if vel.len() != dim || vel.iter().any(|x| !x.is_finite()) {
            return Err(at(Error::invalid(
                "velocity",
                format!("{vel:?}"),
                &format!("needs {dim} finite values"),
            )));
        }
        super::initial::one_initial_motion(b).map_err(&at)?;
        Ok(match (&b.initial_velocity, &b.angular_velocity) {
            (Some(field), _) => super::initial::nodal_field(
                "initial_velocity",
                "m/s",
                field,
                &self.scene.base_dir,
                n / dim,
                dim,
            )
            .map_err(at)?,
            (None, None) if b.rotation_center.is_none() => (0..n).map(|i| vel[i % dim]).collect(),
            (None, omega) => {
                let mesh = &self.meshes[bi];
                super::initial::rigid_motion(b, mesh, sys, dim, &vel, omega.as_deref())
                    .map_err(at)?
            }
        })
    }

    /// Body `bi`'s components held by its `fixed` node sets, over its `n` dofs.
    fn fixed_components(&self, bi: usize, n: usize) -> Result<Vec<bool>, Error> {
        let b = &self.scene.bodies[bi];
        let at = at_body(bi, b);
        let mut fx = vec![false; n];
        for name in &b.fixed {
            let set = node_set(&self.meshes[bi], name).map_err(|e| at(prefix("fixed", e)))?;
            for &v in &set {
                for i in 0..self.dim {
                    fx[v * self.dim + i] = true;
                }
            }
        }
        Ok(fx)
    }

    /// Body `bi`'s cells (a rod's lines), node ids, points and material in the geometry.
    fn add_to_geometry(&mut self, bi: usize) {
        let (b, mesh, geometry) = (&self.scene.bodies[bi], &self.meshes[bi], &mut self.geometry);
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
    }

    /// Phase 6: the prescribed velocities over the `ndof` full dofs (eliminated with
    /// their coupling blocks in phase 7); a component fixed or prescribed twice is
    /// refused, and each starts at its prescribed motion.
    fn prescribe(
        &self,
        offsets: &[usize],
        start: &Bodies,
        ndof: usize,
    ) -> Result<Prescribed, Error> {
        let mut prescribed = vec![None; ndof];
        let mut functions = Vec::new();
        for (pi, p) in self.scene.prescribed.iter().enumerate() {
            let at = |e: Error| prefix(&format!("prescribed[{pi}]"), e);
            let bi = self.scene.body_index(&p.body);
            let dim = self.scene.bodies[bi].dim();
            let nodes = node_set(&self.meshes[bi], &p.nodes).map_err(at)?;
            let comps: Vec<usize> = p.components.clone().unwrap_or_else(|| (0..dim).collect());
            functions.push(time_function(&format!("prescribed[{pi}].time"), &p.time)?);
            for &v in &nodes {
                for &c in &comps {
                    let d = offsets[bi] + v * dim + c;
                    if start.fixed[d] || prescribed[d].is_some() {
                        return Err(at(Error::invalid(
                            "nodes",
                            format!("{} component {c}", self.meshes[bi].node_label(v)),
                            "is already fixed or prescribed",
                        )));
                    }
                    prescribed[d] = Some((p.velocity[c], functions.len() - 1));
                    let w0 = p.velocity[c] * functions[functions.len() - 1].eval(0.0);
                    self.starts_as_prescribed((pi, bi, v, c), (start.v0[d], start.q0[d]), w0)?;
                }
            }
        }
        Ok((prescribed, functions))
    }

    /// A prescribed component (`[[prescribed]]` entry `pi`, body `bi`, node `v`,
    /// component `c`) starts at its prescribed motion `w0`: a different initial velocity
    /// or displacement (`start`) there would be dropped by the elimination.
    fn starts_as_prescribed(
        &self,
        (pi, bi, v, c): (usize, usize, usize, usize),
        (v0, q0): (f64, f64),
        w0: f64,
    ) -> Result<(), Error> {
        let b = &self.scene.bodies[bi];
        let body = at_body(bi, b);
        let node = self.meshes[bi].node_label(v);
        if b.initial_velocity.is_some() || b.velocity.is_some() || b.angular_velocity.is_some() {
            let key = super::initial::motion_key(b);
            super::initial::as_prescribed(key, v0, w0, &node, c, pi).map_err(&body)?;
        }
        if b.initial_displacement.is_some() {
            super::initial::as_prescribed("initial_displacement", q0, 0.0, &node, c, pi)
                .map_err(body)?;
        }
        Ok(())
    }

    /// Phase 7: the `fixed` and prescribed dofs of `full` eliminated (the geometry keeps
    /// the prescribed ones and the dof map), and the large-deformation bodies' internal
    /// forces on the kept dofs. Returns the structure and the map full → kept dof.
    fn eliminate(
        &mut self,
        full: LinearSystem,
        fixed: &[bool],
        (prescribed, functions): Prescribed,
        offsets: &[usize],
    ) -> Result<(LinearSystem, Vec<Option<usize>>), Error> {
        self.geometry.prescribed = (0..full.ndof())
            .filter_map(|d| match prescribed[d] {
                Some((w, f)) if !fixed[d] => Some((d, w, f)),
                _ => None,
            })
            .collect();
        self.geometry.prescribed_functions = functions.clone();
        let (mut system, map) = full.restrict_prescribed(fixed, &prescribed, functions);
        for bi in 0..self.scene.bodies.len() {
            if let Some(part) = self.hyperelastic_part(bi, &map, &prescribed, offsets)? {
                system.add_nonlinear_part(std::sync::Arc::new(part));
            }
        }
        self.geometry.dof_of = map.clone();
        Ok((system, map))
    }

    /// Body `bi`'s internal forces on the kept dofs (`map`) when its material is a
    /// large-deformation law; `None` for a linear body. A prescribed node, or a cell the
    /// initial displacement inverts at a quadrature point, is refused.
    fn hyperelastic_part(
        &self,
        bi: usize,
        map: &[Option<usize>],
        prescribed: &[Option<(f64, usize)>],
        offsets: &[usize],
    ) -> Result<Option<HyperelasticPart>, Error> {
        let b = &self.scene.bodies[bi];
        let Some(law) = b.material.model.hyperelastic(&b.material) else {
            return Ok(None);
        };
        let at = at_body(bi, b);
        let mesh = &self.meshes[bi];
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
        if let Some(Err(c)) = self.u_of[bi].as_deref().map(|u| body.strain_energy(u)) {
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
        let part = HyperelasticPart::new(&b.name, body, dofs, mesh.cell_ids.clone()).map_err(at)?;
        Ok(Some(part))
    }

    /// Phase 8: the forces on node sets, split over their nodes, and the pressures on
    /// boundary faces (after the elimination:
    /// loads on fixed dofs are dropped, the supports carry them).
    fn forces(
        &self,
        system: &mut LinearSystem,
        map: &[Option<usize>],
        offsets: &[usize],
    ) -> Result<(), Error> {
        for (fi, f) in self.scene.forces.iter().enumerate() {
            let at = |e: Error| prefix(&format!("forces[{fi}]"), e);
            let bi = self.scene.body_index(&f.body);
            let nodes = node_set(&self.meshes[bi], &f.nodes).map_err(at)?;
            if nodes.is_empty() {
                return Err(at(Error::invalid(
                    "nodes",
                    &f.nodes,
                    "the node set is empty",
                )));
            }
            let dim = self.scene.bodies[bi].dim();
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
        let pressures = super::loads::pressure_loads(self.scene, &self.meshes, map, offsets)?;
        system.loads.extend(pressures);
        Ok(())
    }

    /// Phase 10: the obstacles' outlines in the geometry, the report (the `counts` of
    /// cells and fixed dofs, the `contacts`' interface lines), the dof ordering; the
    /// model, keeping the scene's starting-gap rule (`contacts`').
    fn finish(
        mut self,
        mut problem: Problem,
        (interfaces, starting_gaps): (Vec<String>, StartingGaps),
        counts: (usize, usize),
        probes: Vec<Probe>,
    ) -> Result<(Model, ModelReport), Error> {
        let (scene, dim) = (self.scene, self.dim);
        let mut geometry = std::mem::take(&mut self.geometry);
        geometry.outlines = scene
            .obstacles
            .iter()
            .map(|o| outline(o, &geometry.points, dim))
            .collect();
        let report = ModelReport::of(&problem, counts, scene.loads.gravity.is_some(), interfaces);
        let n = problem.system.ndof();
        if crate::model::ordering::worth_ordering(&geometry) {
            problem.system.ordering =
                crate::model::ordering::candidate(scene.scheme.ordering, &geometry, n).map_err(
                    |e| Error::invalid("scheme.ordering", scene.scheme.ordering.name(), &e),
                )?;
        }
        let model = Model {
            problem,
            geometry,
            probes,
            starting_gaps,
        };
        Ok((model, report))
    }
}

/// Where each of consecutive blocks of `sizes` starts (the exclusive prefix sums): the
/// bodies' first point and first dof.
fn starts(sizes: impl Iterator<Item = usize>) -> Vec<usize> {
    sizes
        .scan(0, |acc, n| {
            let start = *acc;
            *acc += n;
            Some(start)
        })
        .collect()
}
