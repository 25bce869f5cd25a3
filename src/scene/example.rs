//! The paper's academic examples as scenes (`[example]` in a scene file): the bouncing
//! ball (eq. 7), the impacting linear oscillator (eq. 8), the rocking block
//! (eq. 9–10) and the slider–crank of sec. 6.3.1 (Table 2). Every parameter defaults to
//! the value the paper (or Ballard's example) uses, so `[example] kind = "rocking-block"`
//! alone reproduces Fig. 9's set-up.

use crate::integrators::Problem;
use serde::{Deserialize, Serialize};

use crate::contact::block::BlockCorners;
use crate::contact::plane::NodesOnPlane;
use crate::contact::slider::SliderCorners;
use crate::error::Error;
use crate::io::frames::Geometry;
use crate::model::multibody::SliderCrankParams;
use crate::model::point_mass::{oscillator, point_mass, rigid_block};
use crate::scene::Model;

/// `[example]`: one of the paper's academic examples.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum ExampleSpec {
    /// The bouncing ball (eq. 7); defaults: Ballard's f = −2, m = 1, e = 1/2, q0 = 1.
    BouncingBall {
        /// Constant force `f` (N).
        #[serde(default = "ball_force")]
        force: f64,
        /// Mass (kg).
        #[serde(default = "one")]
        mass: f64,
        /// Restitution.
        #[serde(default = "half")]
        restitution: f64,
        /// Initial height (m).
        #[serde(default = "one")]
        q0: f64,
        /// Initial velocity (m/s).
        #[serde(default)]
        v0: f64,
    },
    /// The impacting oscillator (eq. 8); defaults: m = 1, k = 4π², c = 0.2, f = 0,
    /// e = 1/2, q0 = 1.
    Oscillator {
        /// Mass (kg).
        #[serde(default = "one")]
        mass: f64,
        /// Damping (N·s/m).
        #[serde(default = "osc_damping")]
        damping: f64,
        /// Stiffness (N/m).
        #[serde(default = "osc_stiffness")]
        stiffness: f64,
        /// Constant force (N).
        #[serde(default)]
        force: f64,
        /// Restitution.
        #[serde(default = "half")]
        restitution: f64,
        /// Initial position (m).
        #[serde(default = "one")]
        q0: f64,
        /// Initial velocity (m/s).
        #[serde(default)]
        v0: f64,
    },
    /// The rocking block (eq. 9–10); defaults: the paper's l = 1.5, L = 1, m = 1,
    /// e = 1/2, y0 = 1, θ0 = 0.2, ω0 = 0.2, g = 9.81.
    RockingBlock {
        /// Length `L` (m), the bottom edge.
        #[serde(default = "one")]
        length: f64,
        /// Thickness `l` (m).
        #[serde(default = "block_thickness")]
        thickness: f64,
        /// Mass (kg).
        #[serde(default = "one")]
        mass: f64,
        /// Restitution.
        #[serde(default = "half")]
        restitution: f64,
        /// Gravity (m/s²).
        #[serde(default = "gravity")]
        gravity: f64,
        /// Initial `[x, y, θ]`.
        #[serde(default = "block_q0")]
        q0: [f64; 3],
        /// Initial `[ẋ, ẏ, θ̇]`.
        #[serde(default = "block_v0")]
        v0: [f64; 3],
    },
    /// The slider–crank of sec. 6.3.1 ([`crate::model::multibody`]); defaults: the
    /// paper's Table 2 (J₂ = 8.9e-4; Siconos' example uses 5.9e-4), e = 0.4, μ = 0.01,
    /// q₀ = 0, crank 150 rad/s and rod −75 rad/s.
    SliderCrank {
        /// Restitution of the slider's corners on the guides.
        #[serde(default = "crank_restitution")]
        restitution: f64,
        /// Coulomb friction of the corners.
        #[serde(default = "crank_friction")]
        friction: f64,
        /// Initial angles `[θ₁, θ₂, θ₃]` (rad).
        #[serde(default)]
        q0: [f64; 3],
        /// Initial rates `[θ̇₁, θ̇₂, θ̇₃]` (rad/s).
        #[serde(default = "crank_v0")]
        v0: [f64; 3],
        /// Geometry and inertia (`[example.mechanism]`).
        #[serde(default)]
        mechanism: SliderCrankParams,
    },
}

fn crank_restitution() -> f64 {
    0.4
}
fn crank_friction() -> f64 {
    0.01
}
fn crank_v0() -> [f64; 3] {
    [150.0, -75.0, 0.0]
}

fn one() -> f64 {
    1.0
}
fn half() -> f64 {
    0.5
}
fn ball_force() -> f64 {
    -2.0
}
fn osc_damping() -> f64 {
    0.2
}
fn osc_stiffness() -> f64 {
    4.0 * std::f64::consts::PI * std::f64::consts::PI
}
fn block_thickness() -> f64 {
    1.5
}
fn gravity() -> f64 {
    9.81
}
fn block_q0() -> [f64; 3] {
    [0.0, 1.0, 0.2]
}
fn block_v0() -> [f64; 3] {
    [0.0, 0.0, 0.2]
}

impl ExampleSpec {
    /// The built-in example of that name with the paper's parameters:
    /// `bouncing-ball`, `oscillator`, `rocking-block` or `slider-crank`.
    pub fn named(name: &str) -> Result<Self, Error> {
        // the name is a value, never TOML text: a name holding quotes or newlines must
        // not add keys to the spec
        let mut table = toml::Table::new();
        table.insert("kind".into(), toml::Value::String(name.to_string()));
        toml::Value::Table(table).try_into().map_err(|_| {
            Error::invalid(
                "example",
                name,
                "unknown example; the examples are bouncing-ball, oscillator, rocking-block, \
                 slider-crank",
            )
        })
    }

    /// The model: system, contacts and initial state (no field geometry: the examples
    /// write their history, summary and plots).
    pub fn build(&self) -> Result<Model, Error> {
        let prefix = |e: Error| match e {
            Error::InvalidParameter {
                field,
                value,
                reason,
            } => Error::InvalidParameter {
                field: format!("example.{field}"),
                value,
                reason,
            },
            e => e,
        };
        let build = || -> Result<Model, Error> {
            Ok(match *self {
                ExampleSpec::BouncingBall {
                    force,
                    mass,
                    restitution,
                    q0,
                    v0,
                } => on_the_line(point_mass(1, mass, &[force])?, q0, v0, restitution)?,
                ExampleSpec::Oscillator {
                    mass,
                    damping,
                    stiffness,
                    force,
                    restitution,
                    q0,
                    v0,
                } => on_the_line(
                    oscillator(mass, damping, stiffness, force)?,
                    q0,
                    v0,
                    restitution,
                )?,
                ExampleSpec::RockingBlock {
                    length,
                    thickness,
                    mass,
                    restitution,
                    gravity,
                    q0,
                    v0,
                } => Model {
                    problem: Problem::new(
                        rigid_block(mass, length, thickness, gravity)?,
                        Box::new(BlockCorners::new(length, thickness, restitution)?),
                        q0.to_vec(),
                        v0.to_vec(),
                    ),
                    geometry: Geometry::default(),
                    probes: Vec::new(),
                    starting_gaps: Default::default(),
                },
                ExampleSpec::SliderCrank {
                    restitution,
                    friction,
                    q0,
                    v0,
                    mechanism,
                } => {
                    mechanism.validate("mechanism.")?;
                    for (name, x) in [("q0", q0), ("v0", v0)] {
                        for (i, &xi) in x.iter().enumerate() {
                            crate::error::require_in(&format!("{name}[{i}]"), xi, -1e6, 1e6)?;
                        }
                    }
                    let corners = SliderCorners::new(&mechanism, restitution, friction)?;
                    Model {
                        problem: Problem::new(
                            mechanism.system()?,
                            Box::new(corners),
                            q0.to_vec(),
                            v0.to_vec(),
                        ),
                        geometry: Geometry::default(),
                        probes: Vec::new(),
                        starting_gaps: Default::default(),
                    }
                }
            })
        };
        let model = build().map_err(prefix)?;
        check_start(&model).map_err(prefix)?;
        Ok(model)
    }
}

/// Refuses a starting state that no run can make sense of (issue 34): a contact that
/// starts inside its obstacle (the slider 5 cm inside its guides stopped at step 64 on
/// "energy grew 15 %"), or an initial kinetic energy that is not finite (the bouncing
/// ball at v0 = 1e308 wrote a non-finite history and exited 0). The examples are in
/// metres of order one: 1e-9 m of overlap is round-off of their set-up.
fn check_start(model: &Model) -> Result<(), Error> {
    let mut gap = vec![0.0; model.problem.contacts.len()];
    model
        .problem
        .contacts
        .starting_gaps(&model.problem.q0, &mut gap);
    if let Some((k, &g)) = gap
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(b.1))
        .filter(|(_, g)| **g < -1e-9 || g.is_nan())
    {
        return Err(Error::invalid(
            "q0",
            format!("{:?}", model.problem.q0),
            &format!(
                "contact {k} starts {:.3e} m inside its obstacle (gap {g:.3e} m): give a \
                 starting position with every gap ≥ 0",
                -g
            ),
        ));
    }
    let energy = model
        .problem
        .system
        .kinetic_energy(&model.problem.q0, &model.problem.v0);
    if !energy.is_finite() {
        return Err(Error::invalid(
            "v0",
            format!("{:?}", model.problem.v0),
            &format!("gives an initial kinetic energy of {energy:e} J: expected a finite one"),
        ));
    }
    Ok(())
}

/// A one-dof system whose coordinate `q` is the gap to the line `q = 0`.
fn on_the_line(
    system: crate::model::LinearSystem,
    q0: f64,
    v0: f64,
    restitution: f64,
) -> Result<Model, Error> {
    crate::error::require_in("q0", q0, 0.0, f64::MAX)?;
    let contact = NodesOnPlane::new(vec![vec![0]], vec![vec![0.0]], vec![1.0], 0.0, restitution)?;
    Ok(Model {
        problem: Problem::new(system, Box::new(contact), vec![q0], vec![v0]),
        geometry: Geometry::default(),
        probes: Vec::new(),
        starting_gaps: Default::default(),
    })
}
