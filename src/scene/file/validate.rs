//! Checking a scene before anything is built: every key's range and cross-reference
//! (the error names the key path), the time functions, the loads' magnitudes and the
//! mesh generators' arguments. The starting gaps, checked once the meshes exist, are
//! `gaps`'; the build calls this file, never the other way.

use super::*;

impl Scene {
    /// The accuracy mode's keys: `time.accuracy` in (0, 1), `0 < time.dt_min ≤
    /// time.dt_max ≤ time.t_end`, a scheme that can vary its step; `dt_max` and `dt_min`
    /// only beside `accuracy`.
    fn validate_accuracy(&self) -> Result<(), Error> {
        let t = &self.time;
        let Some(spec) = t.accuracy_spec() else {
            for (key, v) in [("time.dt_max", t.dt_max), ("time.dt_min", t.dt_min)] {
                if let Some(v) = v {
                    return Err(Error::invalid(
                        key,
                        v,
                        "it sets the accuracy mode's ladder: set time.accuracy too",
                    ));
                }
            }
            return Ok(());
        };
        let keys = if t.dt_max.is_some() {
            ["time.accuracy", "time.dt_max", "time.dt_min"]
        } else {
            ["time.accuracy", "time.dt", "time.dt_min"]
        };
        spec.validate(keys)?;
        if spec.dt_max > t.t_end {
            return Err(Error::invalid(
                keys[1],
                spec.dt_max,
                &format!("expected at most time.t_end = {:e} s", t.t_end),
            ));
        }
        if !self.scheme.kind.capabilities().variable_step {
            return Err(Error::invalid(
                "time.accuracy",
                spec.tol,
                &format!(
                    "scheme.kind = \"{}\" is a two-step scheme that steps at one h: the \
                     accuracy mode needs a one-step scheme (moreau_jean, \
                     combined_projection, direct_projection, trapezoid)",
                    self.scheme.kind.name()
                ),
            ));
        }
        Ok(())
    }

    /// Range checks that serde cannot express.
    pub fn validate(&self) -> Result<(), Error> {
        crate::limits::step_count(self.time.t_end, self.time.dt, "time.t_end", "time.dt")?;
        self.validate_accuracy()?;
        self.scheme.validate().map_err(|e| prefix("scheme", e))?;
        self.output.validate().map_err(|e| prefix("output", e))?;
        if self.example.is_some() {
            // the examples carry their own loads (the paper's f = −2, the oscillator's
            // forcing); tables that would be silently ignored are refused, by name
            let extra = [
                (!self.bodies.is_empty(), "bodies"),
                (!self.obstacles.is_empty(), "obstacles"),
                (!self.contacts.is_empty(), "contacts"),
                (!self.forces.is_empty(), "forces"),
                (!self.pressures.is_empty(), "pressures"),
                (!self.prescribed.is_empty(), "prescribed"),
                (!self.probes.is_empty(), "probes"),
                (self.loads.gravity.is_some(), "loads"),
                (self.reference.is_some(), "reference"),
            ];
            if let Some((_, key)) = extra.iter().find(|(present, _)| *present) {
                return Err(Error::invalid(
                    key,
                    "in an [example] scene",
                    "an example scene holds only [example], [time], [scheme] and [output]: \
                     its loads are the example's own parameters (`signorini example --help`)",
                ));
            }
            return Ok(());
        }
        if self.bodies.is_empty() {
            return Err(Error::invalid(
                "bodies",
                "[]",
                "a scene needs at least one body (or an [example])",
            ));
        }
        for (i, b) in self.bodies.iter().enumerate() {
            if b.name.trim().is_empty() {
                return Err(Error::invalid(
                    &format!("bodies[{i}].name"),
                    "\"\"",
                    "a body needs a name",
                ));
            }
            if let Some(j) = self.bodies[..i].iter().position(|o| o.name == b.name) {
                return Err(Error::invalid(
                    &format!("bodies[{i}].name"),
                    &b.name,
                    &format!("bodies[{j}] has that name already; names must be unique"),
                ));
            }
            b.material
                .validate()
                .map_err(|e| prefix(&format!("bodies[{i}].material"), e))?;
            let rod = matches!(b.mesh, MeshSpec::Rod { .. });
            if b.material.model != MaterialModel::LINEAR
                && (rod
                    || matches!(
                        b.formulation,
                        Formulation::PlaneStress { .. } | Formulation::Axisymmetric
                    ))
            {
                return Err(Error::invalid(
                    &format!("bodies[{i}].material.model"),
                    b.material.model.name(),
                    "large-deformation laws take solid bodies and plane-strain bodies (any \
                     cell kind); rods, plane-stress and axisymmetric bodies are linear only \
                     (model = \"linear\")",
                ));
            }
            if let Some(r) = b.damping {
                crate::error::require_in(
                    &format!("bodies[{i}].damping.alpha"),
                    r.alpha,
                    0.0,
                    f64::MAX,
                )?;
                crate::error::require_in(
                    &format!("bodies[{i}].damping.beta"),
                    r.beta,
                    0.0,
                    f64::MAX,
                )?;
            }
        }
        let dim = self.bodies[0].dim();
        for (j, o) in self.obstacles.iter().enumerate() {
            if let Some(k) = self.obstacles[..j]
                .iter()
                .position(|p| p.name() == o.name())
            {
                return Err(Error::invalid(
                    &format!("obstacles[{j}].name"),
                    o.name(),
                    &format!("obstacles[{k}] has that name already; names must be unique"),
                ));
            }
            // say where the dimension comes from: a 3-D mesh given a 2-D formulation
            // reads as an obstacle's fault otherwise (issue 34)
            let origin = match self.bodies[0].mesh {
                MeshSpec::Rod { .. } => "bodies[0] is a rod".to_string(),
                _ => format!(
                    "bodies[0] has formulation = \"{}\"",
                    self.bodies[0].formulation.name()
                ),
            };
            let axisymmetric = matches!(self.bodies[0].formulation, Formulation::Axisymmetric)
                && !matches!(self.bodies[0].mesh, MeshSpec::Rod { .. });
            o.shape().validate(dim, axisymmetric).map_err(|e| {
                prefix(
                    &format!("obstacles[{j}]"),
                    e.context(&format!("a {dim}-D scene: {origin}")),
                )
            })?;
        }
        if let Some(g) = &self.loads.gravity
            && (g.len() != dim || g.iter().any(|x| !x.is_finite()))
        {
            return Err(Error::invalid(
                "loads.gravity",
                format!("{g:?}"),
                &format!("needs {dim} finite components (m/s²)"),
            ));
        }
        if let Some(g) = &self.loads.gravity {
            let peak = g.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            within_magnitude("loads.gravity", g, peak, "m/s²")?;
        }
        self.validate_axisymmetric()?;
        for (i, c) in self.contacts.iter().enumerate() {
            if !self.bodies.iter().any(|b| b.name == c.body) {
                return Err(Error::invalid(
                    &format!("contacts[{i}].body"),
                    &c.body,
                    "names no body",
                ));
            }
            match (&c.obstacle, &c.target) {
                (Some(o), None) => {
                    if !self.obstacles.iter().any(|x| x.name() == o) {
                        return Err(Error::invalid(
                            &format!("contacts[{i}].obstacle"),
                            o,
                            "names no obstacle",
                        ));
                    }
                }
                (None, Some(t)) => {
                    if !self.bodies.iter().any(|b| b.name == t.body) {
                        return Err(Error::invalid(
                            &format!("contacts[{i}].target.body"),
                            &t.body,
                            "names no body",
                        ));
                    }
                    if t.body == c.body {
                        return Err(Error::invalid(
                            &format!("contacts[{i}].target.body"),
                            &t.body,
                            "is the contact's own body: self-contact is not modelled",
                        ));
                    }
                    if let Some(sd) = t.search {
                        require_positive(&format!("contacts[{i}].target.search"), sd)?;
                    }
                    if let Some(k) = t.capacity
                        && !(1..=4096).contains(&k)
                    {
                        return Err(Error::invalid(
                            &format!("contacts[{i}].target.capacity"),
                            k,
                            "must lie in 1..=4096",
                        ));
                    }
                }
                (Some(_), Some(_)) => {
                    return Err(Error::invalid(
                        &format!("contacts[{i}]"),
                        "obstacle and target",
                        "give one: `obstacle` (a rigid obstacle) or `target` (another body)",
                    ));
                }
                (None, None) => {
                    return Err(Error::invalid(
                        &format!("contacts[{i}]"),
                        "neither obstacle nor target",
                        "give `obstacle = \"name\"` or `target = { body = \"name\", surface = \"set\" }`",
                    ));
                }
            }
            crate::contact::check_restitution(
                &format!("contacts[{i}].restitution"),
                c.restitution,
            )?;
            crate::contact::check_friction(&format!("contacts[{i}].friction"), c.friction)?;
        }
        for (i, p) in self.prescribed.iter().enumerate() {
            let at = format!("prescribed[{i}]");
            let b = self.driven_body(&at, &p.body, ("velocity", &p.velocity, "m/s"), &p.time)?;
            if let Some(c) = &p.components
                && (c.is_empty() || c.iter().any(|&k| k >= b.dim()))
            {
                return Err(Error::invalid(
                    &format!("prescribed[{i}].components"),
                    format!("{c:?}"),
                    &format!("expected components in 0..{}", b.dim()),
                ));
            }
        }
        for (i, f) in self.forces.iter().enumerate() {
            let at = format!("forces[{i}]");
            self.driven_body(&at, &f.body, ("total", &f.total, "N"), &f.time)?;
        }
        self.validate_pressures()?;
        self.validate_probes()
    }

    /// Checks the `[[probes]]`: unique non-empty names, existing bodies, increasing
    /// finite times within `[0, time.t_end]`, at most [`MAX_PROBE_TIMES`] each.
    pub(super) fn validate_probes(&self) -> Result<(), Error> {
        for (i, p) in self.probes.iter().enumerate() {
            let key = |k: &str| format!("probes[{i}].{k}");
            if p.name.trim().is_empty() {
                return Err(Error::invalid(&key("name"), "\"\"", "a probe needs a name"));
            }
            if let Some(j) = self.probes[..i].iter().position(|o| o.name == p.name) {
                return Err(Error::invalid(
                    &key("name"),
                    &p.name,
                    &format!("probes[{j}] has that name already; names must be unique"),
                ));
            }
            if !self.bodies.iter().any(|b| b.name == p.body) {
                return Err(Error::invalid(&key("body"), &p.body, "names no body"));
            }
            if p.times.is_empty() || p.times.len() > MAX_PROBE_TIMES {
                return Err(Error::invalid(
                    &key("times"),
                    format!("{} times", p.times.len()),
                    &format!("expected 1 to {MAX_PROBE_TIMES} times"),
                ));
            }
            for (k, &t) in p.times.iter().enumerate() {
                if !(0.0..=self.time.t_end).contains(&t) {
                    return Err(Error::invalid(
                        &format!("probes[{i}].times[{k}]"),
                        t,
                        &format!("expected a time in [0, time.t_end = {}] s", self.time.t_end),
                    ));
                }
                if k > 0 && t <= p.times[k - 1] {
                    return Err(Error::invalid(
                        &format!("probes[{i}].times[{k}]"),
                        t,
                        &format!(
                            "times must increase (times[{}] = {})",
                            k - 1,
                            p.times[k - 1]
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Checks a `[[forces]]` or `[[prescribed]]` entry at `at`: its body exists, its
    /// vector has one finite component per dimension, its time function is valid.
    pub(super) fn driven_body(
        &self,
        at: &str,
        body: &str,
        (key, v, unit): (&str, &[f64], &str),
        time: &Option<Vec<[f64; 2]>>,
    ) -> Result<&BodySpec, Error> {
        let Some(b) = self.bodies.iter().find(|b| b.name == body) else {
            return Err(Error::invalid(&format!("{at}.body"), body, "names no body"));
        };
        if v.len() != b.dim() || v.iter().any(|x| !x.is_finite()) {
            return Err(Error::invalid(
                &format!("{at}.{key}"),
                format!("{v:?}"),
                &format!("needs {} finite components ({unit})", b.dim()),
            ));
        }
        time_function(&format!("{at}.time"), time)?;
        let peak = v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
            * time
                .as_ref()
                .map_or(1.0, |t| t.iter().fold(0.0f64, |m, p| m.max(p[1].abs())));
        within_magnitude(&format!("{at}.{key}"), v, peak, unit)?;
        Ok(b)
    }

    /// An axisymmetric scene is a solid of revolution about the y axis: every body
    /// axisymmetric (a plane-strain body beside one is an extrusion, which the revolved
    /// solid cannot touch), gravity along the axis, planes normal to it and spheres
    /// centred on it (issue 34: gravity along r and a plane-strain neighbour were
    /// accepted).
    pub(super) fn validate_axisymmetric(&self) -> Result<(), Error> {
        let axi = |b: &BodySpec| matches!(b.formulation, Formulation::Axisymmetric);
        let Some(first) = self.bodies.iter().position(axi) else {
            return Ok(());
        };
        if let Some((i, b)) = self.bodies.iter().enumerate().find(|(_, b)| !axi(b)) {
            return Err(Error::invalid(
                &format!("bodies[{i}].formulation"),
                b.formulation.name(),
                &format!(
                    "must be axisymmetric like bodies[{first}] (\"{}\"): a scene is one \
                     solid of revolution, and a {} body is no part of it",
                    self.bodies[first].name,
                    b.formulation.name()
                ),
            ));
        }
        if let Some(g) = &self.loads.gravity
            && g.first().is_some_and(|&gr| gr != 0.0)
        {
            return Err(Error::invalid(
                "loads.gravity",
                format!("{g:?}"),
                "must lie along the axis of revolution (y) in an axisymmetric scene: \
                 gravity along r would pull every ring outward alike, which no body of \
                 revolution feels; give [0.0, g]",
            ));
        }
        for (j, o) in self.obstacles.iter().enumerate() {
            let Some((key, value, what)) = o.shape().axisymmetric_problem() else {
                continue;
            };
            return Err(Error::invalid(
                &format!("obstacles[{j}].{key}"),
                value,
                &format!("(obstacle \"{}\") {what}", o.name()),
            ));
        }
        Ok(())
    }
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

/// The cells the `box` generator makes.
const BOX_CELLS: &[CellKind] = &[
    CellKind::Hex8,
    CellKind::Tet4,
    CellKind::Hex20,
    CellKind::Hex27,
    CellKind::Tet10,
];

/// The cells the `rectangle` generator makes.
const RECTANGLE_CELLS: &[CellKind] = &[
    CellKind::Quad4,
    CellKind::Tri3,
    CellKind::Quad8,
    CellKind::Quad9,
    CellKind::Tri6,
];

/// Checks a generator's request before anything is generated: the cell kind is one it
/// makes, the counts are positive and their products fit the memory limit, the sizes
/// are positive and finite, the origin is finite.
pub(super) fn generator_checks(
    generator: &str,
    cell: CellKind,
    cells: &[usize],
    size: &[f64],
    origin: &[f64],
) -> Result<(), Error> {
    let (kinds, per_box): (&[CellKind], u64) = match (generator, cell) {
        ("box", CellKind::Tet4 | CellKind::Tet10) => (BOX_CELLS, 6),
        ("box", _) => (BOX_CELLS, 1),
        (_, CellKind::Tri3 | CellKind::Tri6) => (RECTANGLE_CELLS, 2),
        _ => (RECTANGLE_CELLS, 1),
    };
    if !kinds.contains(&cell) {
        return Err(Error::invalid(
            "mesh.cell",
            cell.name(),
            &format!(
                "the `{generator}` generator makes {} cells",
                kinds
                    .iter()
                    .map(|k| k.name())
                    .collect::<Vec<_>>()
                    .join(" or ")
            ),
        ));
    }
    if cells.contains(&0) {
        return Err(Error::invalid(
            "mesh.cells",
            format!("{cells:?}"),
            "needs counts of at least 1",
        ));
    }
    for (i, s) in size.iter().enumerate() {
        require_positive(&format!("mesh.size[{i}]"), *s)?;
    }
    for (i, o) in origin.iter().enumerate() {
        crate::error::require_finite(&format!("mesh.origin[{i}]"), *o)?;
    }
    // nodes on the grid of the cells (of half their spacing for quadratic cells)
    let s = cell.element().order() as u64;
    let prod = |scale: u64, extra: u64| {
        cells
            .iter()
            .try_fold(1u64, |a, &c| {
                a.checked_mul((c as u64).checked_mul(scale)? + extra)
            })
            .unwrap_or(u64::MAX)
    };
    let n_cells = prod(1, 0).saturating_mul(per_box);
    let dim = cells.len() as u64;
    crate::limits::mesh_memory(prod(s, 1), n_cells, cell.nodes() as u64, dim)
        .check("mesh.cells", format!("{cells:?}"))
}

/// The largest magnitude a load, a prescribed velocity or gravity may reach (its
/// components times the largest factor of its `time` function): the run's energy
/// balance squares them and multiplies them by displacements, and past this their
/// products overflow to infinity (issue 48: loads of 1e308 ran, and the overflow was
/// reported as a run that exploded, with "lower the time step" as the remedy).
pub const MAX_LOAD_MAGNITUDE: f64 = 1e150;

/// `values` (of key `key`, peak magnitude `peak`) within [`MAX_LOAD_MAGNITUDE`].
pub(super) fn within_magnitude(
    key: &str,
    values: &[f64],
    peak: f64,
    unit: &str,
) -> Result<(), Error> {
    if peak <= MAX_LOAD_MAGNITUDE {
        return Ok(());
    }
    Err(Error::invalid(
        key,
        format!("{values:?}"),
        &format!(
            "reaches {peak:e} {unit} (with its time factors); at most {MAX_LOAD_MAGNITUDE:e} \
             {unit}: beyond it the energy and work sums (squares, products with \
             displacements) overflow"
        ),
    ))
}
