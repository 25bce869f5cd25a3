//! The impacting elastic bar (sec. 6.2, Table 1, eq. 71), with the cross-section
//! corrected to `S = π·10⁻⁴ m²` (DESIGN.md §7).
//!
//! Geometry: node 0 at `x = 0` is the contact node; the rigid wall is the plane
//! `x = −gap`; the whole bar moves with `velocity` (negative: towards the wall), so
//! `g(q) = u_0 + gap`.

use crate::integrators::Problem;
use serde::{Deserialize, Serialize};

use crate::analytic::ImpactingBar;
use crate::contact::check_restitution;
use crate::contact::plane::NodesOnPlane;
use crate::error::{Error, require_finite, require_in, require_positive};
use crate::integrators::SchemeParams;
use crate::io::frames::{Geometry, Outline};
use crate::model::MassKind;
use crate::model::rod::Rod;
use crate::scene::Model;

/// Every parameter of the bar scene, defaulting to the reference run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BarScene {
    /// Number of rod elements `N` (default 1000).
    pub elements: usize,
    /// Time step `h` (s, default 2e-7).
    pub dt: f64,
    /// End time (s, default 1e-3).
    pub t_end: f64,
    /// Length `L` (m, default 1).
    pub length: f64,
    /// Cross-section `S` (m², default π·10⁻⁴).
    pub area: f64,
    /// Young's modulus `E` (Pa, default 210e9).
    pub young: f64,
    /// Density `ρ` (kg/m³, default 7800).
    pub density: f64,
    /// Initial velocity of the whole bar (m/s, default −0.1).
    pub velocity: f64,
    /// Initial gap between the tip and the wall (m, default 0).
    pub gap: f64,
    /// Restitution coefficient at the tip (default 0).
    pub restitution: f64,
    /// Mass matrix kind (default consistent, eq. 71).
    pub mass: MassKind,
    /// Scheme and its parameters (default Algorithm 2, θ = 1/2, `M̂⁻¹` metric).
    pub scheme: SchemeParams,
    /// The accuracy mode ([`crate::run::accuracy`]): the relative accuracy asked
    /// (`--accuracy`); `dt` is then the largest step. `None`: every step is `dt`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub accuracy: Option<f64>,
    /// The accuracy mode's smallest step (s, `--dt-min`; default `dt / 2¹⁰`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dt_min: Option<f64>,
}

impl Default for BarScene {
    fn default() -> Self {
        BarScene {
            elements: 1000,
            dt: 2e-7,
            t_end: 1e-3,
            length: 1.0,
            area: std::f64::consts::PI * 1e-4,
            young: 210e9,
            density: 7800.0,
            velocity: -0.1,
            gap: 0.0,
            restitution: 0.0,
            mass: MassKind::Consistent,
            scheme: SchemeParams::default(),
            accuracy: None,
            dt_min: None,
        }
    }
}

impl BarScene {
    /// The rod of this scene.
    pub fn rod(&self) -> Rod {
        Rod {
            length: self.length,
            area: self.area,
            young: self.young,
            density: self.density,
            elements: self.elements,
            mass: self.mass,
        }
    }

    /// The accuracy mode's request, when `accuracy` is set.
    pub fn accuracy_spec(&self) -> Option<crate::run::accuracy::AccuracySpec> {
        crate::scene::file::TimeSpec {
            accuracy: self.accuracy,
            dt_min: self.dt_min,
            ..crate::scene::file::TimeSpec::fixed(self.dt, self.t_end)
        }
        .accuracy_spec()
    }

    /// Number of steps `round(t_end / dt)` (of an accuracy run: at the largest step).
    pub fn steps(&self) -> usize {
        crate::limits::step_count(self.t_end, self.dt, "t-end", "dt").unwrap_or(0)
    }

    /// The memory the run needs at least: the process itself, the rod's dofs
    /// (tridiagonal matrices, two neighbours a node) and their frame geometry.
    pub fn memory(&self) -> crate::limits::MemoryEstimate {
        let mut m = crate::limits::MemoryEstimate::default();
        // the process itself, as every run's ledger counts it (issue 34: `bar` let a
        // 1 MiB limit pass, its model alone being 0.5 MiB)
        m.add(
            "the process (binary, libraries, threads)",
            1,
            crate::limits::PROCESS_BYTES,
        );
        let n = self.elements as u64 + 1;
        m.add("dofs", n, crate::limits::bytes_per_dof(3, 1));
        m.add("frame geometry", n, 64);
        if self.accuracy_spec().is_some() {
            // per step of the ladder: the tridiagonal factor (2 × n) and the Delassus
            // data (Â⁻¹G and its scratch, 4 × n), for the cached steps and the one being
            // formed, with its M̂ (3 diagonals, values and indices); then the snapshots,
            // the companion and the comparison vectors, and the energy forms
            // (`Plan::add_accuracy`; measured: 410 bytes per dof above the run at one step)
            let rungs = crate::integrators::core::STEP_CACHE_ENTRIES as u64 + 1;
            m.add(
                "accuracy mode: factors and Delassus data of other steps",
                n,
                rungs * 6 * 8,
            );
            m.add("accuracy mode: a new step's M̂", n, 3 * 16);
            m.add(
                "accuracy mode: snapshots, the companion, comparison vectors, energy forms",
                n,
                (crate::integrators::plan::ACCURACY_VECTORS + 6) * 8,
            );
        }
        m
    }

    /// Checks every field; the error names it.
    pub fn validate(&self) -> Result<(), Error> {
        self.rod().validate()?;
        require_positive("dt", self.dt)?;
        require_positive("t-end", self.t_end)?;
        require_finite("velocity", self.velocity)?;
        require_in("gap", self.gap, 0.0, f64::MAX)?;
        check_restitution("restitution", self.restitution)?;
        self.scheme.validate()?;
        crate::limits::step_count(self.t_end, self.dt, "t-end", "dt")?;
        if let Some(a) = self.accuracy_spec() {
            a.validate(["accuracy", "dt", "dt-min"])?;
            if !self.scheme.kind.capabilities().variable_step {
                return Err(Error::invalid(
                    "accuracy",
                    a.tol,
                    "schatzman-paoli steps at one h: the accuracy mode needs a one-step scheme",
                ));
            }
        } else if let Some(d) = self.dt_min {
            return Err(Error::invalid(
                "dt-min",
                d,
                "it sets the accuracy mode's smallest step: give --accuracy too",
            ));
        }
        self.memory().check("elements", self.elements)?;
        Ok(())
    }

    /// Assembles the rod and the tip contact.
    pub fn build(&self) -> Result<Model, Error> {
        self.validate()?;
        let system = self.rod().assemble()?;
        let n = system.ndof();
        let contacts = NodesOnPlane::new(
            vec![vec![0]],
            vec![vec![0.0]],
            vec![1.0],
            -self.gap,
            self.restitution,
        )?;
        Ok(Model {
            problem: Problem::new(
                system,
                Box::new(contacts),
                vec![0.0; n],
                vec![self.velocity; n],
            ),
            geometry: Geometry {
                outlines: vec![wall(-self.gap, 0.2 * self.length)],
                // the one contact: the end x = 0 against the wall
                contacts: vec![crate::model::geometry::ContactPoint {
                    point: 0,
                    body: 0,
                    target: "wall".to_string(),
                    entry: 0,
                }],
                ..Geometry::rod(self.length, self.elements, self.young, self.density)
            },
            probes: Vec::new(),
            starting_gaps: Default::default(),
        })
    }

    /// The analytic reference, when the bar moves towards the wall.
    pub fn analytic(&self) -> Option<ImpactingBar> {
        (self.velocity < 0.0).then_some(ImpactingBar {
            length: self.length,
            area: self.area,
            young: self.young,
            density: self.density,
            velocity: self.velocity,
        })
    }
}

/// The wall `x = x0` drawn as a square of side `side` in the y–z plane.
fn wall(x0: f64, side: f64) -> Outline {
    let mut o = Outline {
        name: "wall".into(),
        ..Outline::default()
    };
    let h = 0.5 * side;
    let c = [[-h, -h], [h, -h], [h, h], [-h, h]];
    for k in 0..4 {
        let (p, q) = (c[k], c[(k + 1) % 4]);
        o.segment([x0, p[0], p[1]], [x0, q[0], q[1]]);
    }
    o
}
