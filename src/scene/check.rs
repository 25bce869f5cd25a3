//! What `signorini check` reports about a scene, as data ([`CheckReport`]): the model it
//! builds, the physics it includes (and the solvers it will therefore run), the time
//! stepping, whether the Newton loop will iterate, the planned linear-algebra path and
//! the memory ledger. The CLI prints it; the Python package returns it as a dict.

use serde::Serialize;

use super::Model;
use super::bar::BarScene;
use super::file::{ModelReport, Scene};
use crate::error::Error;
use crate::integrators::SchemeParams;

/// One `[[probes]]` entry as built.
#[derive(Clone, Debug, Serialize)]
pub struct ProbeCheck {
    /// The probe's name.
    pub name: String,
    /// Its body.
    pub body: String,
    /// Its node set.
    pub nodes: String,
    /// Nodes in the set.
    pub node_count: usize,
    /// Recording times (s).
    pub times: Vec<f64>,
}

/// What a scene builds and how it will run ([`Scene::check`]).
#[derive(Debug, Serialize)]
pub struct CheckReport {
    /// Bodies in the scene.
    pub bodies: usize,
    /// Cells over all bodies.
    pub cells: usize,
    /// The cell kinds and their counts, in the registry's order (`line` for rods).
    pub cell_kinds: Vec<(String, usize)>,
    /// Degrees of freedom after Dirichlet elimination.
    pub dofs: usize,
    /// Dofs removed by `fixed` node sets.
    pub fixed_dofs: usize,
    /// Candidate contacts.
    pub contacts: usize,
    /// Whether Rayleigh damping is present.
    pub damping: bool,
    /// Whether a body force is applied.
    pub gravity: bool,
    /// Largest friction coefficient (0: frictionless, no friction solver).
    pub max_friction: f64,
    /// The friction solver's description (`None` when no contact has friction).
    pub friction_solver: Option<String>,
    /// One line per contact between bodies and per obstacle contact on the surface rule.
    pub interfaces: Vec<String>,
    /// The probes.
    pub probes: Vec<ProbeCheck>,
    /// Steps of the run.
    pub steps: usize,
    /// Time step (s).
    pub dt: f64,
    /// The accuracy mode's ladder of steps, largest first (s; empty: every step `dt`).
    pub ladder: Vec<f64>,
    /// The accuracy asked (`time.accuracy`).
    pub accuracy: Option<f64>,
    /// The scheme's name.
    pub scheme: String,
    /// θ of the θ-method.
    pub theta: f64,
    /// Whether the structure is linear.
    pub linear_structure: bool,
    /// Whether every gap is linear in q.
    pub linear_contacts: bool,
    /// What the Newton loop will do.
    pub newton: String,
    /// The planned linear-algebra path.
    pub path: String,
    /// Planned memory (bytes), with the history's rows.
    pub memory_planned: u64,
    /// The memory limit (bytes).
    pub memory_limit: u64,
    /// The ledger's nonzero parts (what, bytes).
    pub memory_parts: Vec<(String, u64)>,
    /// Whether the planned memory fits the limit ([`CheckReport::memory_error`] says
    /// why not).
    pub memory_fits: bool,
    /// The run's refusal when it would not fit (the error a run of the scene returns).
    #[serde(skip)]
    pub memory_error: Option<Error>,
}

impl Scene {
    /// Builds the model and plans the run without factoring anything: what `signorini
    /// check` prints. Errors are those of [`Scene::build`]; a run that would not fit the
    /// memory limit is reported in the result (`memory_fits`, `memory_error`).
    pub fn check(&self) -> Result<CheckReport, Error> {
        let (mut model, report) = self.build()?;
        CheckReport::new(
            &mut model,
            &report,
            self.bodies.len(),
            &self.scheme,
            (self.time.dt, self.steps(), self.time.accuracy_spec()),
            self.output.hdf5(),
        )
    }
}

impl BarScene {
    /// [`Scene::check`] for the built-in bar: one rod, one contact, linear (history in
    /// CSV only, as the bar writes it).
    pub fn check(&self) -> Result<CheckReport, Error> {
        let mut model = self.build()?;
        let report = ModelReport {
            dofs: model.problem.q0.len(),
            cells: self.elements,
            contacts: model.problem.contacts.len(),
            linear_contacts: true,
            max_friction: 0.0,
            damping: false,
            gravity: false,
            fixed_dofs: 0,
            linear_structure: true,
            interfaces: Vec::new(),
        };
        CheckReport::new(
            &mut model,
            &report,
            1,
            &self.scheme,
            (self.dt, self.steps(), self.accuracy_spec()),
            false,
        )
    }
}

impl CheckReport {
    /// The report of a built `model` (its build `report`) run with `params` at `dt` for
    /// `steps` steps, in the accuracy mode when `accuracy` is given; `hdf5`: whether the
    /// history is also written to HDF5 (the ledger).
    fn new(
        model: &mut Model,
        report: &ModelReport,
        bodies: usize,
        params: &SchemeParams,
        (dt, steps, accuracy): (f64, usize, Option<crate::run::accuracy::AccuracySpec>),
        hdf5: bool,
    ) -> Result<CheckReport, Error> {
        let mut plan = model.plan_only(params, dt)?;
        let (m, rows) = (model.problem.contacts.len(), model.problem.contacts.rows());
        plan.add_history(report.dofs, m, (rows - m) / m.max(1), hdf5);
        if accuracy.is_some() {
            plan.add_accuracy(report.linear_structure, report.dofs, rows);
        }
        let newton = match (report.linear_structure, report.linear_contacts) {
            (true, true) => {
                "not needed for the dynamics (linear structure, constant G): factor once, never refactor"
            }
            (true, false) => {
                "needed: G(q) changes with q (curved obstacle or contact between bodies), \
                 re-linearized every iteration (M̂ still factored once)"
            }
            (false, _) if params.newton.modified => {
                "nonlinear structure: modified Newton (M̂ⁿ formed at each step's first iterate, \
                 re-formed when the iterates stop contracting)"
            }
            (false, _) => "nonlinear structure: full Newton (M̂ⁿ refactored at every iterate)",
        };
        let friction_solver = (report.max_friction > 0.0).then(|| {
            format!(
                "{} on the velocity problem of each step: De Saxcé's cone complementarity, \
                 eq. 15; tol {:e}, cap {} sweeps",
                params.friction.solver.describe(),
                params.friction.tol,
                params.friction.max_iterations
            )
        });
        let fits = plan.ledger.check(
            "scene",
            format!("{} dofs, {} contacts", report.dofs, report.contacts),
        );
        Ok(CheckReport {
            bodies,
            cells: report.cells,
            cell_kinds: {
                use crate::model::element::CellKind;
                use crate::model::geometry::GeomCell;
                // one count per kind (slot 0: rods' lines), in the registry's order
                let mut counts = vec![0usize; CellKind::ALL.len() + 1];
                for (cell, _, _) in &model.geometry.cells {
                    counts[match cell {
                        GeomCell::Line => 0,
                        GeomCell::Solid(k) => {
                            1 + CellKind::ALL.iter().position(|a| a == k).unwrap_or(0)
                        }
                    }] += 1;
                }
                std::iter::once("line")
                    .chain(CellKind::ALL.iter().map(|k| k.name()))
                    .zip(counts)
                    .filter(|&(_, n)| n > 0)
                    .map(|(k, n)| (k.to_string(), n))
                    .collect()
            },
            dofs: report.dofs,
            fixed_dofs: report.fixed_dofs,
            contacts: report.contacts,
            damping: report.damping,
            gravity: report.gravity,
            max_friction: report.max_friction,
            friction_solver,
            interfaces: report.interfaces.clone(),
            probes: model
                .probes
                .iter()
                .map(|p| ProbeCheck {
                    name: p.name.clone(),
                    body: p.body.clone(),
                    nodes: p.nodes.clone(),
                    node_count: p.points.len(),
                    times: p.times.clone(),
                })
                .collect(),
            steps,
            dt,
            ladder: accuracy.map_or_else(Vec::new, |a| a.ladder()),
            accuracy: accuracy.map(|a| a.tol),
            scheme: params.kind.name().to_string(),
            theta: params.theta,
            linear_structure: report.linear_structure,
            linear_contacts: report.linear_contacts,
            newton: newton.to_string(),
            path: plan.describe(),
            memory_planned: plan.ledger.total(),
            memory_limit: crate::limits::memory_limit(),
            memory_parts: plan
                .ledger
                .parts()
                .iter()
                .filter(|(_, b)| *b > 0)
                .cloned()
                .collect(),
            memory_fits: fits.is_ok(),
            memory_error: fits.err(),
        })
    }
}
