//! `signorini study extremes SCENE`: stability at the extremes of any scene file.
//!
//! The scene runs under every scheme at its own settings and at one extreme at a time
//! (issue 33): its time step ×1/8 … ×8, every contact's restitution `e = 0` and `e = 1`,
//! `θ = 1/2` and `θ = 1`, and every body's Young's modulus ×1e-3 and ×1e3. Each cell
//! (an extreme under a scheme) gets a verdict with its figures:
//!
//! - `stable`: exit 0, no iteration cap, and the energy check's balance kept (its excess
//!   is reported: round-off on a linear structure, the θ-method's bounded error on a
//!   large-deformation body);
//! - `energy gain`: the run stopped on the energy check, or grew past 1e-6 of its
//!   energy scale where that is the check's limit;
//! - `cap`: an iteration loop stopped at its cap;
//! - `failure`: any other failed run (non-finite state, a penetration past the model's
//!   size, a solver error), with its message;
//! - `not applicable`: the scheme refuses the scene (Schatzman–Paoli and the
//!   position-level trapezoid take no friction nor prescribed velocities), or the extreme
//!   has nothing to change in it (no contact for `e`, rigid bodies for `E`:
//!   [`Extreme::apply`]), with why;
//! - `beyond the model`: a cell inverted (`det F ≤ 0`) and the same run at a quarter of
//!   the step inverts at the same time (within two of its steps or 5 %): the body is
//!   crushed flat by the load, which no step size cures (the soft ball of
//!   `ball_crush.toml` at E × 1e-3 hits the floor at 11 times its wave speed; cell 719
//!   inverts at t = 0.0130 s at h and 0.0129 s at h/4). An inversion that moves with
//!   the step stays a `failure`. A linear body that turns past `scheme.max_rotation`
//!   (`run::rotations`) is `beyond the model` too: the linear law's range, not the
//!   scheme's.
//!
//! It writes `extremes.csv` (one row per cell), `extremes-energy.png/.svg` (the energy
//! excess against the step factor, one curve per scheme) and returns one verdict line per
//! cell, the default scheme's first. The runs are the library's own ([`run_scene`]), in
//! memory, one after another.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use crate::app::run_scene;
use crate::error::Error;
use crate::integrators::{DEFAULT_MAX_ENERGY_EXCESS, SchemeKind};
use crate::io::write_atomic;
use crate::plot::{Curve, lines};
use crate::run::Quiet;
use crate::scene::file::Scene;

/// One extreme: a change of the scene's own settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Extreme {
    /// The time step times this factor.
    Step(f64),
    /// Every contact's restitution set to this.
    Restitution(f64),
    /// θ set to this.
    Theta(f64),
    /// Every body's Young's modulus times this factor.
    Stiffness(f64),
}

impl Extreme {
    /// The cells of the study, in the order of the table.
    pub const ALL: [Extreme; 13] = [
        Extreme::Step(0.125),
        Extreme::Step(0.25),
        Extreme::Step(0.5),
        Extreme::Step(1.0),
        Extreme::Step(2.0),
        Extreme::Step(4.0),
        Extreme::Step(8.0),
        Extreme::Restitution(0.0),
        Extreme::Restitution(1.0),
        Extreme::Theta(0.5),
        Extreme::Theta(1.0),
        Extreme::Stiffness(1e-3),
        Extreme::Stiffness(1e3),
    ];

    /// The cell's label (`h×4`, `e=1`, `θ=1`, `E×1e3`).
    pub fn label(self) -> String {
        match self {
            Extreme::Step(f) => format!("h×{f}"),
            Extreme::Restitution(e) => format!("e={e}"),
            Extreme::Theta(t) => format!("θ={t}"),
            Extreme::Stiffness(f) => format!("E×{f:e}"),
        }
    }

    /// `base` with this extreme applied, or why it does not apply to `base` (a scene
    /// with no contact has no restitution to set; rigid bodies have no modulus): such a
    /// cell is reported `not applicable` with the reason, never run unchanged under the
    /// extreme's label. The paper's examples take their own keys: every example's
    /// `restitution`, and the oscillator's spring `stiffness` for `E×f`.
    pub fn apply(self, base: &Scene) -> Result<Scene, String> {
        use crate::scene::example::ExampleSpec;
        let mut s = base.clone();
        match self {
            Extreme::Step(f) => s.time.dt *= f,
            Extreme::Theta(t) => s.scheme.theta = t,
            Extreme::Restitution(e) => match s.example.as_mut() {
                Some(
                    ExampleSpec::BouncingBall { restitution, .. }
                    | ExampleSpec::Oscillator { restitution, .. }
                    | ExampleSpec::RockingBlock { restitution, .. }
                    | ExampleSpec::SliderCrank { restitution, .. },
                ) => *restitution = e,
                None if s.contacts.is_empty() => {
                    return Err("the scene has no contact: no restitution to set".into());
                }
                None => s.contacts.iter_mut().for_each(|c| c.restitution = e),
            },
            Extreme::Stiffness(f) => match s.example.as_mut() {
                Some(ExampleSpec::Oscillator { stiffness, .. }) => *stiffness *= f,
                Some(_) => {
                    return Err("the example's bodies are rigid: no modulus to scale".into());
                }
                None if s.bodies.is_empty() => {
                    return Err("the scene has no deformable body: no modulus to scale".into());
                }
                None => s.bodies.iter_mut().for_each(|b| b.material.young *= f),
            },
        }
        Ok(s)
    }
}

/// A cell's verdict.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Exit 0, no cap, the energy balance kept.
    Stable,
    /// The energy grew past the check's limit.
    EnergyGain,
    /// An iteration loop stopped at its cap.
    Cap,
    /// Any other failed run.
    Failure,
    /// The scheme refuses the scene.
    NotApplicable,
    /// A cell inverts at the same time at the step and at a quarter of it: the load
    /// crushes the body, whatever the step.
    BeyondModel,
}

impl Verdict {
    /// The word of the table.
    pub fn word(self) -> &'static str {
        match self {
            Verdict::Stable => "stable",
            Verdict::EnergyGain => "energy gain",
            Verdict::Cap => "cap",
            Verdict::Failure => "failure",
            Verdict::NotApplicable => "not applicable",
            Verdict::BeyondModel => "beyond the model",
        }
    }
}

/// What one cell measured.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// The extreme.
    pub extreme: Extreme,
    /// The scheme.
    pub scheme: SchemeKind,
    /// The step it ran at (s).
    pub dt: f64,
    /// The verdict.
    pub verdict: Verdict,
    /// Largest energy excess relative to the run's energy scale (NaN: no summary).
    pub excess: f64,
    /// Largest penetration (m; NaN: no summary).
    pub violation: f64,
    /// Mean Newton iterations per step (NaN: no summary).
    pub newton: f64,
    /// Wall time of the run (s).
    pub seconds: f64,
    /// The failure's message, or empty.
    pub detail: String,
}

/// Runs one cell.
pub fn run_cell(base: &Scene, extreme: Extreme, scheme: SchemeKind) -> Outcome {
    let mut o = Outcome {
        extreme,
        scheme,
        dt: base.time.dt,
        verdict: Verdict::Stable,
        excess: f64::NAN,
        violation: f64::NAN,
        newton: f64::NAN,
        seconds: 0.0,
        detail: String::new(),
    };
    let mut s = match extreme.apply(base) {
        Ok(s) => s,
        Err(why) => {
            o.verdict = Verdict::NotApplicable;
            o.detail = why;
            return o;
        }
    };
    s.scheme.kind = scheme;
    o.dt = s.time.dt;
    let t0 = Instant::now();
    let r = run_scene(&s, None, &mut Quiet);
    o.seconds = t0.elapsed().as_secs_f64();
    match r {
        Ok(r) => {
            let sm = &r.summary;
            o.excess = sm.energy_balance.map_or(0.0, |b| b.excess_max);
            o.violation = sm.max_violation;
            o.newton = sm.iterations.newton.mean;
            let linear = s.bodies.iter().all(|b| b.material.model.is_linear());
            if sm.caps_hit > 0 {
                o.verdict = Verdict::Cap;
            } else if linear && o.excess > DEFAULT_MAX_ENERGY_EXCESS {
                o.verdict = Verdict::EnergyGain;
            }
        }
        Err(e) => {
            let msg = e.to_string();
            o.verdict = if e.exit_code() == 2 {
                Verdict::NotApplicable
            } else if msg.contains("energy grew") {
                Verdict::EnergyGain
            } else if msg.contains("at its cap") || msg.contains("stopped at its cap") {
                Verdict::Cap
            } else if msg.contains("scheme.max_rotation") {
                // a linear body turned past its law's range (`run::rotations`)
                o.detail = "the linear law turned past its rotation range; ".into();
                Verdict::BeyondModel
            } else if let Some(t) = inversion_time(&e) {
                // the same run at a quarter of the step: an inversion that stays put is
                // the load's, one that moves (or goes) is the step's
                let mut fine = s.clone();
                fine.time.dt /= 4.0;
                let again = run_scene(&fine, None, &mut Quiet)
                    .err()
                    .and_then(|e| inversion_time(&e));
                match again {
                    Some(t4) if (t4 - t).abs() <= (2.0 * s.time.dt).max(0.05 * t) => {
                        o.detail = format!("crushed: at h/4 too (t = {t4:.4e} s); ");
                        Verdict::BeyondModel
                    }
                    _ => Verdict::Failure,
                }
            } else {
                Verdict::Failure
            };
            o.detail += msg.lines().next().unwrap_or_default();
        }
    }
    o
}

/// The time of a run failure on an inverted cell (`det F ≤ 0`), if `e` is one.
fn inversion_time(e: &Error) -> Option<f64> {
    match e {
        Error::RunFailed { time, detail, .. } if detail.contains("is inverted") => Some(*time),
        _ => None,
    }
}

/// The study on the scene file `path` (with `KEY=VALUE` overrides, as `run --set`) under
/// `only` (every scheme when empty; the default scheme, Algorithm 2, first): writes
/// `extremes.csv` and the energy plot into `dir`, returns one verdict line per cell.
pub fn scene_extremes(
    path: &Path,
    overrides: &[String],
    only: &[SchemeKind],
    dir: &Path,
) -> Result<Vec<String>, Error> {
    let base = Scene::from_file_with(path, overrides)?;
    std::fs::create_dir_all(dir).map_err(|e| Error::write(dir, e))?;
    let default = crate::integrators::SchemeParams::default().kind;
    let mut schemes = vec![default];
    schemes.extend(SchemeKind::ALL.into_iter().filter(|&k| k != default));
    if !only.is_empty() {
        schemes.retain(|k| only.contains(k));
    }
    let mut outcomes = Vec::new();
    for &scheme in &schemes {
        for extreme in Extreme::ALL {
            outcomes.push(run_cell(&base, extreme, scheme));
        }
    }
    let mut csv = String::from(
        "scene,cell,scheme,dt,verdict,energy_excess,max_violation,newton_mean,seconds,detail\n",
    );
    let name = path.display().to_string();
    for o in &outcomes {
        let _ = writeln!(
            csv,
            "{name},{},{},{:e},{},{:e},{:e},{},{:.3},\"{}\"",
            o.extreme.label(),
            o.scheme.name(),
            o.dt,
            o.verdict.word(),
            o.excess,
            o.violation,
            o.newton,
            o.seconds,
            o.detail.replace('"', "'")
        );
    }
    write_atomic(&dir.join("extremes.csv"), csv.as_bytes())?;
    // the energy excess against the step factor, floored at 1e-17 to show round-off
    let curves: Vec<Curve> = schemes
        .iter()
        .map(|&k| Curve {
            name: k.name().to_string(),
            points: outcomes
                .iter()
                .filter(|o| o.scheme == k && o.excess.is_finite())
                .filter_map(|o| match o.extreme {
                    Extreme::Step(f) => Some((f, o.excess.max(1e-17))),
                    _ => None,
                })
                .collect(),
        })
        .filter(|c| !c.points.is_empty())
        .collect();
    lines(
        &dir.join("extremes-energy"),
        "energy excess (relative, floored at 1e-17) against the step factor",
        "h / scene's h",
        "largest energy excess",
        &curves,
        true,
    )?;
    let lines_out = outcomes
        .iter()
        .map(|o| {
            let figures = if o.excess.is_finite() {
                format!(
                    "energy excess {:.1e}, violation {:.1e} m, Newton {:.2}, {:.2} s",
                    o.excess, o.violation, o.newton, o.seconds
                )
            } else {
                o.detail.clone()
            };
            format!(
                "extremes {} / {} / {}: {} ({figures})",
                path.file_name()
                    .map_or(name.clone(), |f| f.to_string_lossy().into_owned()),
                o.scheme.name(),
                o.extreme.label(),
                o.verdict.word()
            )
        })
        .collect();
    Ok(lines_out)
}
