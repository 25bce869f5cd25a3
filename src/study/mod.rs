//! Studies of the paper's academic examples (issue 5), each one command
//! (`signorini study NAME --out DIR`) that writes a CSV table, a plot (PNG and SVG) and
//! a verdict line per finding (`verdict.txt`, also returned).
//!
//! The studies run on the bouncing ball of eq. 7 (Ballard's example,
//! [`BouncingBall::ballard`]) and the impacting oscillator of eq. 8
//! ([`Oscillator::example`]) against their closed forms:
//! - `convergence`: errors in position and velocity in the uniform, l1 and l2 norms
//!   against h for Moreau–Jean, Schatzman–Paoli and Algorithm 1 on both examples, with
//!   fitted orders (Fig. 2);
//! - `projection-multiplier`: max |τ| against h for Algorithm 1 on both examples
//!   (Fig. 3, eq. 37: τ = O(h));
//! - `chattering`: Algorithm 1 with the explicit forecast γ = 0, 1, 2 (eq. 61) and the
//!   free forecast (eq. 62), and Algorithm 2, at h = 5e-2: contact switches after the
//!   accumulation, post-accumulation velocity amplitude, time to rest (Fig. 4); and the
//!   rocking block of eq. 9–10 with the paper's parameters under the same five cases:
//!   corner switches after t = 1 and energy at t = 2 (Fig. 9);
//! - `energy`: kinetic, potential and total energy for e = 1/2 and e = 1, without
//!   projection (Moreau–Jean) and with it (Algorithms 1 and 2) (Figs. 6, 7).
//!
//! Moreau–Jean and Algorithm 1 run with [`STUDY_FORECAST`] in the convergence,
//! projection-multiplier and energy studies.
//!
//! `energy` uses the ball.
//!
//! The impacting bar has its own studies in [`bar`]: `speed-accuracy` (error against
//! cost for every scheme, size and Courant number) and `extremes` (stability at the
//! brief's extremes, 10⁶ elements included). The slider–crank of sec. 6.3.1 has
//! `slider-crank` in [`slider_crank`] (Table 3, Figs. 21–24). `extremes` on a scene file
//! (`signorini study extremes SCENE`) is [`extremes`]: every scheme at the scene's
//! step ×1/8 … ×8, e = 0 and 1, θ = 1/2 and 1, stiffness ×1e-3 and ×1e3. `costs`
//! ([`costs`]) measures a step, a set-up and the memory per size (bars of 10³ … 10⁶
//! elements, hex8 cubes of 4³ … 16³ cells), in contact and in flight.

pub mod accuracy;
pub mod bar;
pub mod costs;
pub mod extremes;
pub mod slider_crank;
pub mod sweep;

mod chattering;
mod convergence;
mod energy;

pub use chattering::*;
pub use convergence::*;
use energy::*;

use std::fmt::Write as _;
use std::path::Path;

use crate::analytic::ball::BouncingBall;
use crate::analytic::oscillator::Oscillator;
use crate::contact::block::BlockCorners;
use crate::contact::plane::NodesOnPlane;
use crate::error::Error;
use crate::integrators::{self, Forecast, Integrator, SchemeKind, SchemeParams, StepStats};
use crate::io::write_atomic;
use crate::model::point_mass::{oscillator, point_mass, rigid_block};
use crate::plot::{Curve, lines};

/// The studies `signorini study` knows.
pub const NAMES: [&str; 9] = [
    "convergence",
    "projection-multiplier",
    "chattering",
    "energy",
    "speed-accuracy",
    "extremes",
    "slider-crank",
    "costs",
    "accuracy",
];

/// A run of the ball: per step the time at the end of the step, height, velocity,
/// impulse and projection multiplier.
#[derive(Clone, Debug, Default)]
pub struct Trajectory {
    /// `t_{k+1}` (s).
    pub t: Vec<f64>,
    /// Height `q` (m).
    pub q: Vec<f64>,
    /// Velocity `v` (m/s).
    pub v: Vec<f64>,
    /// Impulse `P` over the step (N·s).
    pub p: Vec<f64>,
    /// Projection multiplier `τ` (eq. 28).
    pub tau: Vec<f64>,
}

/// An academic example with a closed form.
#[derive(Clone, Copy, Debug)]
pub enum Example {
    /// The bouncing ball (eq. 7).
    Ball(BouncingBall),
    /// The impacting oscillator (eq. 8).
    Oscillator(Oscillator),
}

impl Example {
    /// Short name for tables and messages.
    pub fn name(&self) -> &'static str {
        match self {
            Example::Ball(_) => "ball",
            Example::Oscillator(_) => "oscillator",
        }
    }
    /// The exact state (position, right-limit velocity) at the given times.
    pub fn exact(&self, t: &[f64]) -> Vec<(f64, f64)> {
        match self {
            Example::Ball(b) => t.iter().map(|&t| b.state(t)).collect(),
            Example::Oscillator(o) => {
                let f = o.flights(t.last().copied().unwrap_or(0.0) + 1.0);
                t.iter().map(|&t| f.at(t)).collect()
            }
        }
    }
}

/// Integrates the ball `b` with `params` and step `h` up to `t_end`.
pub fn ball_run(
    b: &BouncingBall,
    params: &SchemeParams,
    h: f64,
    t_end: f64,
) -> Result<Trajectory, Error> {
    example_run(&Example::Ball(*b), params, h, t_end)
}

/// Integrates example `x` with `params` and step `h` up to `t_end`; the gap is the
/// height `q`. The ball's dof is its displacement from `q0` (reference position `q0`);
/// the oscillator's dof is `q` itself, since its spring acts on `q`.
pub fn example_run(
    x: &Example,
    params: &SchemeParams,
    h: f64,
    t_end: f64,
) -> Result<Trajectory, Error> {
    let (sys, reference, u0, v0, e) = match x {
        Example::Ball(b) => (
            point_mass(1, b.mass, &[b.force])?,
            b.q0,
            0.0,
            b.v0,
            b.restitution,
        ),
        Example::Oscillator(o) => (
            oscillator(o.mass, o.damping, o.stiffness, o.force)?,
            0.0,
            o.q0,
            o.v0,
            o.restitution,
        ),
    };
    let contact = NodesOnPlane::new(vec![vec![0]], vec![vec![reference]], vec![1.0], 0.0, e)?;
    let mut integ = integrators::build(params, sys, Box::new(contact), &[u0], &[v0], h)?;
    let steps = crate::limits::step_count(t_end, h, "t_end", "h")?;
    let mut r = Trajectory::default();
    let mut record = |integ: &dyn Integrator, _: &StepStats, _: bool| {
        let s = integ.state();
        r.t.push(s.time);
        r.q.push(reference + s.q[0]);
        r.v.push(s.v[0]);
        r.p.push(s.impulse[0]);
        r.tau.push(s.projection[0]);
        Ok(())
    };
    crate::run::drive(
        integ.as_mut(),
        steps,
        &study_checks(params),
        &mut [&mut record],
        &mut crate::run::Quiet,
    )?;
    Ok(r)
}

/// The run checks of a study's own runs: non-finite states stop them, but caps are
/// counted, not fatal (the studies measure and report them, e.g. the chattering of
/// Algorithm 1 with the explicit forecast).
fn study_checks(params: &SchemeParams) -> crate::run::RunChecks {
    crate::run::RunChecks {
        allow_caps: true,
        ..crate::run::RunChecks::new(params, 0.0)
    }
}

/// The paper's rules ([`SchemeParams::paper_rules`]): these studies reproduce its figures.
fn params(kind: SchemeKind, forecast: Forecast) -> SchemeParams {
    SchemeParams {
        kind,
        forecast,
        ..SchemeParams::default()
    }
    .paper_rules()
}

/// The activation rule of the convergence, projection-multiplier and energy studies
/// for Moreau–Jean and Algorithm 1: the explicit forecast with γ = 0 (eq. 61), i.e. a
/// contact is active when its gap at the start of the step is closed, the index set
/// the paper's consistency analysis (Prop. 1–2) assumes. With the free forecast
/// (eq. 62) the ball is caught before it penetrates, τ is zero and no energy is
/// created, so Figs. 3 and 7 would not show (measured: max |τ| = 0 at every h).
pub const STUDY_FORECAST: Forecast = Forecast::Explicit { gamma: 0.0 };

/// `name` is one of [`NAMES`], or the error that lists them.
fn known(name: &str) -> Result<(), Error> {
    if NAMES.contains(&name) {
        return Ok(());
    }
    Err(Error::invalid(
        "study",
        crate::error::excerpt(name),
        &format!("unknown study; the studies are {}", NAMES.join(", ")),
    ))
}

/// Runs study `name` into `dir` and returns its verdict lines (also written to
/// `dir/verdict.txt`).
pub fn run(name: &str, dir: &Path) -> Result<Vec<String>, Error> {
    // the name before anything is created (issue 48: an unknown name left its `--out`)
    known(name)?;
    std::fs::create_dir_all(dir).map_err(|e| Error::write(dir, e))?;
    let verdicts = match name {
        "convergence" => convergence(dir)?,
        "projection-multiplier" => projection_multiplier(dir)?,
        "chattering" => chattering(dir)?,
        "energy" => energy(dir)?,
        "speed-accuracy" => bar::speed_accuracy(dir)?,
        "extremes" => bar::extremes(dir)?,
        "slider-crank" => slider_crank::study(dir)?,
        "costs" => costs::costs(dir)?,
        "accuracy" => {
            return Err(Error::invalid(
                "study",
                name,
                "needs a scene file (`signorini study accuracy meshes/bar.toml`)",
            ));
        }
        other => {
            return Err(Error::invalid(
                "study",
                other,
                &format!("unknown study; the studies are {}", NAMES.join(", ")),
            ));
        }
    };
    write_atomic(
        &dir.join("verdict.txt"),
        (verdicts.join("\n") + "\n").as_bytes(),
    )?;
    Ok(verdicts)
}

/// `signorini study extremes SCENE`: [`extremes::scene_extremes`] on a scene file under
/// `schemes` (all when empty), with its verdicts also in `dir/verdict.txt`.
pub fn run_on_scene(
    name: &str,
    scene: &Path,
    overrides: &[String],
    schemes: &[SchemeKind],
    tols: &[f64],
    dir: &Path,
) -> Result<Vec<String>, Error> {
    known(name)?;
    if name == "accuracy" {
        let s = crate::scene::file::Scene::from_file_with(scene, overrides)?;
        let tols: Vec<f64> = if tols.is_empty() {
            accuracy::DEFAULT_TOLS.to_vec()
        } else {
            tols.to_vec()
        };
        for &t in &tols {
            if !(t > 0.0 && t < 1.0) {
                return Err(Error::invalid(
                    "--tol",
                    t,
                    "expected a relative accuracy in (0, 1)",
                ));
            }
        }
        let verdicts = accuracy::study(&s, &tols, 3, dir)?;
        write_atomic(
            &dir.join("verdict.txt"),
            (verdicts.join("\n") + "\n").as_bytes(),
        )?;
        return Ok(verdicts);
    }
    if name != "extremes" {
        return Err(Error::invalid(
            "study",
            name,
            "takes no scene file; only `extremes` and `accuracy` run on a scene \
             (`signorini study extremes SCENE`)",
        ));
    }
    let verdicts = extremes::scene_extremes(scene, overrides, schemes, dir)?;
    write_atomic(
        &dir.join("verdict.txt"),
        (verdicts.join("\n") + "\n").as_bytes(),
    )?;
    Ok(verdicts)
}
