//! Scenes: what the user asks for (bodies, obstacles, laws, scheme, time), validated
//! and turned into a model plus an integrator.
//!
//! [`bar`] is the built-in reference scene: the paper's impacting elastic bar.
//! TOML scene files and meshes come with the solid-mesh work.

pub mod bar;
pub mod check;
pub mod example;
pub mod file;
pub mod solid_bar;
pub mod sweep;

use crate::error::Error;
use crate::integrators::{self, Integrator, Problem, SchemeParams};

/// A built scene: the problem the integrator is built for (the assembled structure, its
/// contacts and its initial state) and what the outputs need besides.
pub struct Model {
    /// The structure, contacts and initial state.
    pub problem: Problem,
    /// Points, cells and dof map for the field output.
    pub geometry: crate::io::frames::Geometry,
    /// Displacement probes (a scene's `[[probes]]`).
    pub probes: Vec<crate::model::geometry::Probe>,
    /// The scene's starting-gap rule, which a state set after the build must pass
    /// ([`Model::set_state`], [`crate::app::Session::set_state`]); empty for the bar and
    /// the examples.
    pub starting_gaps: file::StartingGaps,
}

impl Model {
    /// Replaces the initial state before the run opens: the displacements `q` (their
    /// starting gaps checked by the scene's rule, [`file::StartingGaps::check`], as the
    /// scene's own start is) and/or the velocities `v`, one finite value per dof each.
    /// Refused, the state is left as it was.
    pub fn set_state(&mut self, q: Option<Vec<f64>>, v: Option<Vec<f64>>) -> Result<(), Error> {
        let p = &mut self.problem;
        check_state(&q, &v, p.q0.len())?;
        if let Some(q) = &q {
            let mut gap = vec![0.0; p.contacts.len()];
            p.contacts.starting_gaps(q, &mut gap);
            self.starting_gaps.check(&gap)?;
        }
        if let Some(q) = q {
            p.q0 = q;
        }
        if let Some(v) = v {
            p.v0 = v;
        }
        Ok(())
    }

    /// Builds the integrator of `params` with step `dt` for this model.
    pub fn into_integrator(
        self,
        params: &SchemeParams,
        dt: f64,
    ) -> Result<Box<dyn Integrator>, Error> {
        integrators::build_problem(params, self.problem, dt)
    }

    /// Validates the run of `params` at step `dt` as [`Model::into_integrator`] would and
    /// plans it ([`integrators::plan::plan`]: paths and memory ledger) without building
    /// it, keeping the validation and the step matrix for [`Model::into_integrator`]
    /// ([`integrators::Problem::plan`]).
    pub fn plan(
        &mut self,
        params: &SchemeParams,
        dt: f64,
    ) -> Result<integrators::plan::Plan, Error> {
        self.problem.plan(params, dt)
    }

    /// [`Model::plan`] for a model that will not be built (what `signorini check`
    /// costs): nothing is kept.
    pub fn plan_only(
        &mut self,
        params: &SchemeParams,
        dt: f64,
    ) -> Result<integrators::plan::Plan, Error> {
        self.problem.plan_only(params, dt)
    }
}

/// Refuses a state `q`, `v` (either may be absent) whose vectors do not hold `n` finite
/// values, one per dof: what [`Model::set_state`] and
/// [`crate::app::Session::set_state`] check before the starting gaps.
pub fn check_state(q: &Option<Vec<f64>>, v: &Option<Vec<f64>>, n: usize) -> Result<(), Error> {
    for (name, x) in [("q", q), ("v", v)] {
        let Some(x) = x else { continue };
        if x.len() != n {
            return Err(Error::invalid(
                name,
                format!("{} values", x.len()),
                &format!("expected one per dof ({n})"),
            ));
        }
        if let Some(i) = x.iter().position(|x| !x.is_finite()) {
            return Err(Error::invalid(
                &format!("{name}[{i}]"),
                x[i],
                "a state is finite",
            ));
        }
    }
    Ok(())
}

/// The built-in example scene `name` (`bouncing-ball`, `oscillator`, `rocking-block`,
/// `slider-crank`): the same as `meshes/<name>.toml` (Algorithm 2, the paper's
/// parameters; h = 1e-3 s to T = 5 s, 1e-3 s to 3 s, 1e-2 s to 2 s, and 1e-4 s to
/// 0.2 s, Siconos' span of the slider–crank), built as data (`name` is a value, never
/// scene text).
pub fn builtin_scene(name: &str) -> Result<file::Scene, Error> {
    let spec = example::ExampleSpec::named(name)?;
    let (dt, t_end) = match spec {
        example::ExampleSpec::BouncingBall { .. } => (1e-3, 5.0),
        example::ExampleSpec::Oscillator { .. } => (1e-3, 3.0),
        example::ExampleSpec::RockingBlock { .. } => (1e-2, 2.0),
        example::ExampleSpec::SliderCrank { .. } => (1e-4, 0.2),
    };
    let scene = file::Scene {
        time: file::TimeSpec::fixed(dt, t_end),
        scheme: SchemeParams::default(),
        bodies: Vec::new(),
        example: Some(spec),
        obstacles: Vec::new(),
        contacts: Vec::new(),
        loads: file::Loads::default(),
        forces: Vec::new(),
        pressures: Vec::new(),
        prescribed: Vec::new(),
        probes: Vec::new(),
        output: crate::io::OutputOptions::default(),
        base_dir: std::path::PathBuf::new(),
        file: None,
        reference: None,
        sweep: None,
    };
    scene.validate()?;
    Ok(scene)
}
