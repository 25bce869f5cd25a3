//! Running a scene: steps the integrator, streams the history, measures the contact
//! response against the analytic reference and assembles the [`Summary`].
//!
//! Every run goes through one step loop, [`drive`]: it checks each state
//! ([`RunChecks`]) and hands it to observers (statistics, the contact measurement,
//! history and frames, checkpoints). The loop reserves nothing per step: the integrator
//! works in its own buffers, the contact measurement keeps the first contact interval
//! only (and the per-step force up to [`FORCE_TRACE_MAX_STEPS`], reserved once).

pub mod checkpoint;

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use crate::analytic::ImpactingBar;
use crate::error::Error;
use crate::integrators::saved::{Bits, Floats};
use crate::integrators::{Forecast, Integrator, StepStats};
use crate::io::frames::{FrameStream, FrameWriter, Geometry};
use crate::io::{HistoryWriter, OutputOptions, write_atomic};
use crate::scene::bar::BarScene;
use checkpoint::{Checkpoint, RunSource, RunState};

/// Snapshots in flight between the run and the frame writer thread: two lets the
/// writer encode one frame while the run fills the next.
const FRAME_POOL: usize = 2;

/// Receives progress; the CLI prints it, the library stays silent.
pub trait Progress {
    /// Called after `step` of `total` steps.
    fn update(&mut self, step: usize, total: usize);
    /// Called when a set-up phase starts (building the model, factoring `M̂` and
    /// condensing the Delassus data, which take tens of seconds on 10⁵–10⁶ dofs).
    fn phase(&mut self, _what: &str) {}
    /// Called once right before the first step, with the number of steps (rates and
    /// ETAs count from here, not from the set-up).
    fn start(&mut self, _total: usize) {}
}

/// Announces the integrator build of `model` (dofs and contacts) to `progress`.
fn announce_integrator(model: &crate::scene::Model, progress: &mut dyn Progress) {
    progress.phase(&format!(
        "building the integrator: factoring M̂ ({} dofs) and the Delassus data of {} contact(s)",
        model.q0.len(),
        model.contacts.len()
    ));
}

/// A progress sink that prints nothing.
pub struct Quiet;

impl Progress for Quiet {
    fn update(&mut self, _: usize, _: usize) {}
}

/// Mean and maximum of a per-step count.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct MeanMax {
    /// Mean over the steps.
    pub mean: f64,
    /// Maximum over the steps.
    pub max: usize,
}

/// Iteration statistics over the run (the paper's Table 3 columns).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Iterations {
    /// Newton iterations per step.
    pub newton: MeanMax,
    /// Projection iterations per step.
    pub projection: MeanMax,
    /// Index-set rounds per step (Algorithm 2).
    pub index_set: MeanMax,
    /// LCP pivots or sweeps per step.
    pub lcp: MeanMax,
}

/// Friction solver statistics over the run (frictional scenes only).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct FrictionSummary {
    /// Friction problems solved (over all steps, Newton iterations and index-set rounds).
    pub solves: usize,
    /// NSGS sweeps per solve: mean and maximum.
    pub sweeps_mean: f64,
    /// Largest sweeps of one step.
    pub sweeps_max_per_step: usize,
    /// Mean over the steps with a friction solve of the step's largest final residual.
    pub residual_mean: f64,
    /// Largest final residual (the velocity residual of `solvers::friction`).
    pub residual_max: f64,
    /// Solves that hit the sweep cap (counted in `caps_hit` too).
    pub caps_hit: usize,
    /// Solves NSGS did not finish (finished by `auto`'s Newton or PROX fallback).
    pub fallbacks: usize,
}

/// Measured contact response with its analytic counterpart.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct ContactSummary {
    /// Mean force over the middle 80 % of the first contact interval (N).
    pub plateau_force: f64,
    /// Standard deviation of the force over the same window (N).
    pub plateau_std: f64,
    /// `E S |v0| / c0` (N).
    pub analytic_force: f64,
    /// Width of the first contact interval at half the plateau force (s).
    pub duration: f64,
    /// Whole length of the first closed interval, first to last positive impulse (s).
    pub closed_duration: f64,
    /// `2 L / c0` (s).
    pub analytic_duration: f64,
    /// Start of the first step with a positive impulse (s).
    pub first_contact_time: f64,
    /// Centre-of-mass velocity at the end of the run (m/s).
    pub release_velocity: f64,
    /// `−v0` (m/s).
    pub analytic_release_velocity: f64,
    /// Sum of all contact impulses over the run (N·s).
    pub total_impulse: f64,
    /// `2 ρ S L |v0|` (N·s).
    pub analytic_total_impulse: f64,
}

/// How the Newton loops of a run ended, beyond convergence at the tolerance
/// (`StepStats::coupled_solves`, `newton_stalls`, `held_rows`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct NewtonLoops {
    /// Coupled position solves (eq. 52–55) taken where the decoupled loop crawled.
    pub coupled_solves: usize,
    /// Loops ended by stagnation within √tol (counted as converged).
    pub stalls: usize,
    /// Steps that ended with a row held at g = 0 with P = 0 and τ < 0.
    pub steps_with_held_rows: usize,
    /// Algorithm 2: index-set rounds redone with Algorithm 1's position rule because
    /// the combined rule capped or held rows (`StepStats::complementarity_fallbacks`).
    pub complementarity_fallbacks: usize,
}

/// A run's energy balance ([`Summary::energy_balance`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct EnergyBalance {
    /// Work supplied by the time-dependent loads and the prescribed motion (J).
    pub supplied_work: f64,
    /// Largest `(E − E₀ − W) / scale` met at the checks (0 when it never was positive); above
    /// `scheme.max_energy_excess` the run fails.
    pub excess_max: f64,
}

/// Everything a run reports (`summary.json`).
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    /// Scheme name.
    pub scheme: String,
    /// Number of elements (cells).
    pub elements: usize,
    /// Degrees of freedom integrated.
    pub dofs: usize,
    /// Time step (s).
    pub dt: f64,
    /// θ.
    pub theta: f64,
    /// Steps run.
    pub steps: usize,
    /// Final time (s).
    pub t_end: f64,
    /// Wall-clock time of the step loop including output (s).
    pub wall_seconds: f64,
    /// `wall_seconds / steps`.
    pub seconds_per_step: f64,
    /// Seconds the step loop spent on output (included in `wall_seconds`): history rows
    /// with their energies, copying states for the frame writer, waiting for it when
    /// its snapshots were all in flight, and waiting at the end for the last frames.
    pub output_seconds: f64,
    /// Seconds the background frame writer spent computing, encoding and writing
    /// frames (overlapped with the steps; not part of `output_seconds`).
    pub frame_seconds: f64,
    /// Part of `output_seconds` spent waiting for a free snapshot (the writer fell
    /// behind: raise `stride` to write fewer frames).
    pub frame_wait_seconds: f64,
    /// Field frames written (`fields.pvd`).
    pub frames: usize,
    /// Largest penetration over the run (m, ≥ 0).
    pub max_violation: f64,
    /// Contact response vs analytic (bar scenes).
    pub contact: Option<ContactSummary>,
    /// Iteration statistics.
    pub iterations: Iterations,
    /// Total iteration caps hit.
    pub caps_hit: usize,
    /// How the Newton loops of the projection schemes ended
    /// ([`crate::integrators::core`]).
    pub newton_loops: NewtonLoops,
    /// Friction solver statistics (absent in a frictionless scene).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub friction: Option<FrictionSummary>,
    /// Largest LCP complementarity residual met.
    pub max_lcp_residual: f64,
    /// Energy (kinetic + potential) at the start and at the end (J).
    pub energy: [f64; 2],
    /// The energy balance (`model::energy`): work supplied by loads and prescribed
    /// motion, and the largest excess met relative to the run's energy scale (`None` for
    /// Schatzman–Paoli, whose discrete energy is not the θ-method's).
    pub energy_balance: Option<EnergyBalance>,
    /// Linear-algebra path taken.
    pub path: String,
    /// Seconds to build the model (mesh, parallel assembly of `M` and `K`, contacts).
    pub model_seconds: f64,
    /// Seconds to build the integrator (factorization of `M̂`, Delassus data).
    pub integrator_seconds: f64,
    /// The scene parameters as run.
    pub parameters: serde_json::Value,
}

/// What [`run_bar`] returns: the summary and the per-step contact force.
pub struct RunResult {
    /// The run summary.
    pub summary: Summary,
    /// Total contact force `Σ P / h` at each step (N); empty for runs that write
    /// checkpoints (a checkpoint does not grow with the run) and beyond
    /// [`FORCE_TRACE_MAX_STEPS`].
    pub force: Vec<f64>,
}

#[derive(Default)]
struct Acc {
    sum: [usize; 4],
    max: [usize; 4],
    caps: usize,
    lcp_res: f64,
    violation: f64,
    fr_solves: usize,
    fr_sweeps: usize,
    fr_sweeps_max: usize,
    fr_res_sum: f64,
    fr_res_max: f64,
    fr_steps: usize,
    fr_caps: usize,
    fr_fallbacks: usize,
    /// Coupled position solves, stagnated Newton loops, steps with held rows.
    loops: [usize; 4],
    /// Largest relative energy excess met ([`EnergyCheck`]).
    energy_excess: f64,
}

impl Acc {
    fn add(&mut self, s: &StepStats) {
        let v = [
            s.newton_iterations,
            s.projection_iterations,
            s.index_set_iterations,
            s.lcp_iterations,
        ];
        for i in 0..4 {
            self.sum[i] += v[i];
            self.max[i] = self.max[i].max(v[i]);
        }
        self.caps += s.caps_hit;
        self.loops[0] += s.coupled_solves;
        self.loops[1] += s.newton_stalls;
        self.loops[2] += usize::from(s.held_rows > 0);
        self.loops[3] += s.complementarity_fallbacks;
        if s.friction_solves > 0 {
            self.fr_solves += s.friction_solves;
            self.fr_sweeps += s.friction_iterations;
            self.fr_sweeps_max = self.fr_sweeps_max.max(s.friction_iterations);
            self.fr_res_sum += s.friction_residual;
            self.fr_res_max = self.fr_res_max.max(s.friction_residual);
            self.fr_steps += 1;
            self.fr_caps += s.friction_caps;
            self.fr_fallbacks += s.friction_fallbacks;
        }
        self.lcp_res = self.lcp_res.max(s.lcp_residual);
        self.violation = self.violation.max(s.max_violation);
    }
    fn friction(&self, frictional: bool) -> Option<FrictionSummary> {
        frictional.then(|| FrictionSummary {
            solves: self.fr_solves,
            sweeps_mean: self.fr_sweeps as f64 / self.fr_solves.max(1) as f64,
            sweeps_max_per_step: self.fr_sweeps_max,
            residual_mean: self.fr_res_sum / self.fr_steps.max(1) as f64,
            residual_max: self.fr_res_max,
            caps_hit: self.fr_caps,
            fallbacks: self.fr_fallbacks,
        })
    }
    fn iterations(&self, steps: usize) -> Iterations {
        let mm = |i: usize| MeanMax {
            mean: self.sum[i] as f64 / steps.max(1) as f64,
            max: self.max[i],
        };
        Iterations {
            newton: mm(0),
            projection: mm(1),
            index_set: mm(2),
            lcp: mm(3),
        }
    }
}

/// Where and what a run writes.
#[derive(Clone, Copy, Debug)]
pub struct Output<'a> {
    /// Output directory.
    pub dir: &'a Path,
    /// Strides, formats.
    pub options: &'a OutputOptions,
}

/// Runs the bar scene; writes `history.csv`, `summary.json` and the field frames
/// (`fields.pvd`, `fields/*.vtu`) into `out.dir` if given.
pub fn run_bar(
    scene: &BarScene,
    out: Option<Output>,
    progress: &mut dyn Progress,
) -> Result<RunResult, Error> {
    run_bar_from(scene, out, progress, None)
}

fn run_bar_from(
    scene: &BarScene,
    out: Option<Output>,
    progress: &mut dyn Progress,
    resume: Option<&Checkpoint>,
) -> Result<RunResult, Error> {
    let t0 = Instant::now();
    progress.phase("building the model");
    let mut model = scene.build()?;
    let geometry = std::mem::take(&mut model.geometry);
    announce_integrator(&model, progress);
    let t1 = Instant::now();
    let mut integ = model.into_integrator(&scene.scheme, scene.dt)?;
    let setup = [(t1 - t0).as_secs_f64(), t1.elapsed().as_secs_f64()];
    let parameters = serde_json::to_value(scene).expect("scene serializes");
    let checks = RunChecks::new(&scene.scheme, geometry.size());
    let ckpt =
        (resume.is_some() || out.is_some_and(|o| o.options.checkpoint_every > 0)).then(|| {
            Checkpointing {
                source: RunSource::Bar {
                    scene: scene.clone(),
                },
                resume,
            }
        });
    run_checkpointed(
        integ.as_mut(),
        scene.steps(),
        scene.elements,
        scene.scheme.theta,
        &checks,
        scene.analytic(),
        parameters,
        out.map(|o| (o, geometry)),
        progress,
        ckpt,
    )
    .and_then(|r| finish(r, setup, out))
}

/// Runs a scene file; writes into `out.dir` if given. Errors raised while building name
/// the scene's key paths; [`Scene::from_file`](crate::scene::file::Scene::from_file)
/// adds the file.
pub fn run_scene(
    scene: &crate::scene::file::Scene,
    out: Option<Output>,
    progress: &mut dyn Progress,
) -> Result<RunResult, Error> {
    run_scene_from(scene, out, progress, None)
}

fn run_scene_from(
    scene: &crate::scene::file::Scene,
    out: Option<Output>,
    progress: &mut dyn Progress,
    resume: Option<&Checkpoint>,
) -> Result<RunResult, Error> {
    let t0 = Instant::now();
    progress.phase("building the model (mesh, assembly, contacts)");
    let (mut model, report) = scene.build()?;
    let geometry = std::mem::take(&mut model.geometry);
    announce_integrator(&model, progress);
    let t1 = Instant::now();
    let mut integ = model.into_integrator(&scene.scheme, scene.time.dt)?;
    let setup = [(t1 - t0).as_secs_f64(), t1.elapsed().as_secs_f64()];
    let parameters = serde_json::to_value(scene).expect("scene serializes");
    let checks = RunChecks::new(&scene.scheme, geometry.size());
    // what a checkpoint rebuilds from: only formed when the run writes checkpoints
    let ckpt = match resume {
        Some(c) => Some(Checkpointing {
            source: c.source.clone(),
            resume,
        }),
        None if out.is_some_and(|o| o.options.checkpoint_every > 0) => Some(Checkpointing {
            source: RunSource::Scene {
                file: scene.file.clone().unwrap_or_default(),
                toml: toml::to_string(scene).map_err(|e| {
                    Error::Numerical(format!(
                        "the scene does not serialize for a checkpoint: {e}"
                    ))
                })?,
                base_dir: std::path::absolute(&scene.base_dir).unwrap_or(scene.base_dir.clone()),
            },
            resume: None,
        }),
        None => None,
    };
    run_checkpointed(
        integ.as_mut(),
        scene.steps(),
        report.cells,
        scene.scheme.theta,
        &checks,
        scene.reference.map(|r| r.impacting_bar),
        parameters,
        out.map(|o| (o, geometry)),
        progress,
        ckpt,
    )
    .and_then(|r| finish(r, setup, out))
}

/// Finishes the killed run in `dir` from its `checkpoint.json` (see
/// [`crate::run::checkpoint`]): rebuilds the model from the scene the checkpoint holds,
/// restores the state and the outputs' cursors, and steps to the end, writing the same
/// files an uninterrupted run writes.
pub fn resume(dir: &Path, progress: &mut dyn Progress) -> Result<RunResult, Error> {
    let c = Checkpoint::read(dir)?;
    c.verify(dir)?;
    let out = Output {
        dir,
        options: &c.output,
    };
    let file = dir.join(checkpoint::FILE);
    match &c.source {
        RunSource::Bar { scene } => {
            scene.validate().map_err(|e| e.in_file(&file))?;
            run_bar_from(scene, Some(out), progress, Some(&c))
        }
        RunSource::Scene {
            file: scene_file,
            toml,
            base_dir,
        } => {
            let mut scene =
                crate::scene::file::Scene::from_toml(toml).map_err(|e| e.in_file(&file))?;
            scene.base_dir = base_dir.clone();
            scene.file = Some(scene_file.clone());
            run_scene_from(&scene, Some(out), progress, Some(&c))
        }
    }
}

/// What the driver checks after every step (DESIGN.md §9): a state that turned
/// non-finite, a penetration that exploded, an iteration cap hit. Each stops the run with
/// [`Error::RunFailed`] (exit code 1) naming the step, the time and the contact.
#[derive(Clone, Copy, Debug)]
pub struct RunChecks {
    /// Count iteration caps in the statistics instead of failing the run
    /// (`scheme.allow_caps`, `--allow-caps`).
    pub allow_caps: bool,
    /// A penetration deeper than this (m) fails the run: no scheme of the paper lets a
    /// node sink through a body's own size, so the solution has exploded.
    pub max_violation: f64,
    /// The Newton / projection cap (`scheme.newton.max_iterations`), for the message.
    pub newton_cap: usize,
    /// The friction sweep cap (`scheme.friction.max_iterations`), for the message.
    pub friction_cap: usize,
    /// The friction solver (`scheme.friction.solver`), for the message: it advises
    /// only what the run has not tried.
    pub friction_solver: crate::solvers::friction::FrictionSolverKind,
    /// Largest relative energy excess (`scheme.max_energy_excess`).
    pub max_energy_excess: f64,
}

impl RunChecks {
    /// The checks of a run with `params`, on a model whose bounding box has diagonal
    /// `size` (m; 0 or non-finite when the model has no geometry: no violation limit).
    pub fn new(params: &crate::integrators::SchemeParams, size: f64) -> Self {
        RunChecks {
            allow_caps: params.allow_caps,
            max_violation: if size.is_finite() && size > 0.0 {
                size
            } else {
                f64::INFINITY
            },
            newton_cap: params.newton.max_iterations,
            friction_cap: params.friction.max_iterations,
            friction_solver: params.friction.solver,
            max_energy_excess: params.max_energy_excess,
        }
    }

    /// Checks the state after a step; the error names the step, time and contact.
    pub fn check(&self, integ: &dyn Integrator, st: &StepStats) -> Result<(), Error> {
        let s = integ.state();
        let fail = |contact: Option<usize>, detail: String| Error::RunFailed {
            step: s.step,
            time: s.time,
            contact,
            detail,
        };
        let deepest = || {
            s.gap
                .iter()
                .enumerate()
                .min_by(|a, b| a.1.total_cmp(b.1))
                .map(|(c, _)| c)
        };
        for (name, v, per_contact) in [
            ("displacement", &s.q, false),
            ("velocity", &s.v, false),
            ("impulse", &s.impulse, true),
            ("gap", &s.gap, true),
        ] {
            if all_finite(v) {
                continue;
            }
            let i = v.iter().position(|x| !x.is_finite()).unwrap_or(0);
            let (contact, at) = if per_contact {
                (Some(i), String::new())
            } else {
                (None, format!(" of dof {i}"))
            };
            return Err(fail(
                contact,
                format!(
                    "the {name}{at} is {}: the solution broke down (lower the time step, \
                     check the material and loads)",
                    v[i]
                ),
            ));
        }
        if st.max_violation > self.max_violation {
            return Err(fail(
                deepest(),
                format!(
                    "penetration {:.3e} m exceeds the model's size {:.3e} m: the solution \
                     exploded (lower the time step)",
                    st.max_violation, self.max_violation
                ),
            ));
        }
        if st.caps_hit > 0 && !self.allow_caps {
            let detail = if st.friction_caps > 0 {
                use crate::solvers::friction::FrictionSolverKind as K;
                // `auto` already ran everything it has: switching the solver cannot
                // help it, only the budget or the step can; `nsgs` and `prox` lack
                // the Newton methods `auto` adds
                let switch = match self.friction_solver {
                    K::Nsgs | K::Prox => {
                        ", try scheme.friction.solver = \"auto\" (the Newton methods after \
                         NSGS, PROX beyond 1024 contact rows)"
                    }
                    _ => "",
                };
                format!(
                    "the {} friction solver stopped at its cap of {} sweeps with residual \
                     {:.3e} (raise scheme.friction.max_iterations{switch}, lower the time \
                     step, or set scheme.allow_caps = true to count caps instead)",
                    self.friction_solver.name(),
                    self.friction_cap,
                    st.friction_residual
                )
            } else {
                format!(
                    "an iteration loop stopped at its cap (Newton/projection cap {}, residual \
                     {:.3e}; LCP residual {:.3e}): raise scheme.newton.max_iterations or lower \
                     the time step, or set scheme.allow_caps = true (--allow-caps) to count caps \
                     instead",
                    self.newton_cap, st.newton_residual, st.lcp_residual
                )
            };
            return Err(fail(deepest(), detail));
        }
        Ok(())
    }
}

/// Whether every value is finite, in eight independent lanes (`0 · x` is NaN exactly for
/// an infinite or NaN `x`), so the check vectorizes: about 0.1 µs for the bar's 2 × 1001
/// values, where a scan with an early exit costs microseconds.
fn all_finite(x: &[f64]) -> bool {
    let mut acc = [0.0f64; 8];
    let mut chunks = x.chunks_exact(8);
    for c in &mut chunks {
        for i in 0..8 {
            acc[i] += c[i] * 0.0;
        }
    }
    let tail: f64 = chunks.remainder().iter().map(|v| v * 0.0).sum();
    (acc.iter().sum::<f64>() + tail) == 0.0
}

/// Something that looks at the run after every step: the history and frame writers,
/// the contact measurement, a study's trajectory. Called in order after the checks.
pub trait Observer {
    /// The step just taken (`integ.state()` is the state after it); `last` on the final
    /// step of the run.
    fn observe(
        &mut self,
        integ: &dyn Integrator,
        stats: &StepStats,
        last: bool,
    ) -> Result<(), Error>;
}

impl<F> Observer for F
where
    F: FnMut(&dyn Integrator, &StepStats, bool) -> Result<(), Error>,
{
    fn observe(
        &mut self,
        integ: &dyn Integrator,
        stats: &StepStats,
        last: bool,
    ) -> Result<(), Error> {
        self(integ, stats, last)
    }
}

/// The one step loop every run goes through (scenes, the bar, the examples, the
/// studies): steps `integ` from its current step up to `steps`, checks each state
/// ([`RunChecks`]), hands it to the observers in order, and reports progress.
pub fn drive(
    integ: &mut dyn Integrator,
    steps: usize,
    checks: &RunChecks,
    observers: &mut [&mut dyn Observer],
    progress: &mut dyn Progress,
) -> Result<(), Error> {
    let report_every = (steps / 1000).max(1);
    let first = integ.state().step;
    progress.start(steps);
    for k in first..steps {
        let st = integ.step()?;
        checks.check(integ, &st)?;
        let last = k + 1 == steps;
        for o in observers.iter_mut() {
            o.observe(integ, &st, last)?;
        }
        if (k + 1) % report_every == 0 || last {
            progress.update(k + 1, steps);
        }
    }
    Ok(())
}

/// The per-step contact force `Σ P / h` is kept in [`RunResult::force`] for runs of at
/// most this many steps (32 MiB); longer runs keep only the first contact interval,
/// which the contact measurement needs.
pub const FORCE_TRACE_MAX_STEPS: usize = 1 << 22;

/// Measures the contact as the run goes: the total impulse, and the samples of the
/// first contact interval (from the first positive impulse to one step after the last
/// closed step), which is all [`contact_summary`] reads.
///
/// What grows with the run is kept only where something reads it, so that a checkpoint
/// (which saves the tracker) does not grow with the run (issue 16 §4: each held the
/// whole force trace, and the bytes written grew quadratically with the run's length):
/// the per-step trace only for runs that do not checkpoint (library callers read it in
/// [`RunResult::force`]), the first interval only for scenes with the impacting-bar
/// reference (whose interval ends after `2L/c0`).
#[derive(Default)]
struct ContactTracker {
    trace: Option<Vec<f64>>,
    interval: bool,
    first: Option<usize>,
    force: Vec<f64>,
    min_gap: Vec<f64>,
    done: bool,
    total_force: f64,
}

impl ContactTracker {
    fn new(steps: usize, trace: bool, interval: bool) -> Self {
        ContactTracker {
            trace: (trace && steps <= FORCE_TRACE_MAX_STEPS).then(|| Vec::with_capacity(steps)),
            interval,
            ..ContactTracker::default()
        }
    }

    fn push(&mut self, k: usize, f: f64, min_gap: f64) {
        if let Some(t) = self.trace.as_mut() {
            t.push(f);
        }
        self.total_force += f;
        if self.done || !self.interval {
            return;
        }
        if self.first.is_none() && f > 0.0 {
            self.first = Some(k);
        }
        if self.first.is_some() {
            self.force.push(f);
            self.min_gap.push(min_gap);
            // the interval ended at the previous sample: this one is the sample after it
            if !(f > 0.0 || min_gap <= 0.0) {
                self.done = true;
            }
        }
    }
}

/// Where the run's output goes and what it costs: the history and frame observers.
struct Writers {
    history: Option<HistoryWriter>,
    frames: Option<FrameStream>,
    frame_stride: usize,
    history_stride: usize,
    closed_before: bool,
    /// Frames pushed (for checkpoints).
    frame_count: usize,
    seconds: f64,
    /// Scratch of the prescribed dofs' energy.
    scratch: Vec<f64>,
}

impl Writers {
    fn observe(&mut self, integ: &dyn Integrator, st: &StepStats, last: bool) -> Result<(), Error> {
        if self.history.is_none() {
            return Ok(());
        }
        let t0 = Instant::now();
        let s = integ.state();
        let k = s.step;
        if let Some(w) = self
            .history
            .as_mut()
            .filter(|_| k.is_multiple_of(self.history_stride) || last)
        {
            let (ke, pe) = integ
                .system()
                .energies(s.time, &s.q, &s.v, &mut self.scratch);
            w.row(s, st, ke, pe)?;
        }
        let closed = s.impulse.iter().any(|&p| p > 0.0);
        let switch = closed != self.closed_before;
        self.closed_before = closed;
        if let Some(w) = self
            .frames
            .as_mut()
            .filter(|_| k.is_multiple_of(self.frame_stride) || last || switch)
        {
            if let Some(hw) = self.history.as_mut() {
                hw.flush()?;
            }
            w.push(s, integ.jacobian(), integ.dt())?;
            self.frame_count += 1;
        }
        self.seconds += t0.elapsed().as_secs_f64();
        Ok(())
    }
}

/// When and where a run writes its checkpoints.
struct CheckpointPlan {
    every: usize,
    dir: PathBuf,
    source: RunSource,
    output: OutputOptions,
    steps: usize,
    energy0: f64,
    /// The run's input files at its start, and its directory (canonical), for
    /// [`Checkpoint::verify`].
    inputs: Vec<checkpoint::InputFile>,
    out_dir: PathBuf,
    /// Test hook (`SIGNORINI_ABORT_AFTER_STEP`): abort the process right after this
    /// step's checkpoint and output, as a SIGKILL would, to test `resume`.
    abort_after: Option<usize>,
}

/// The run's own observer: statistics, energy balance, contact measurement, output,
/// checkpoints.
struct RunObserver {
    acc: Acc,
    tracker: ContactTracker,
    writers: Writers,
    h: f64,
    plan: Option<CheckpointPlan>,
    energy: Option<EnergyCheck>,
}

/// Steps between two checks of the energy balance (each costs the two quadratic forms
/// of the energy; the work is summed every step).
pub const ENERGY_CHECK_STRIDE: usize = 64;

/// The energy-balance check of a θ-method run (module doc of [`crate::model::energy`]).
struct EnergyCheck {
    audit: crate::model::energy::EnergyAudit,
    theta: f64,
    /// `scheme.max_energy_excess`.
    max: f64,
    /// `scheme.allow_caps`: capped steps may be what added the energy.
    caps_allowed: bool,
}

impl EnergyCheck {
    /// Sums the step's work; every [`ENERGY_CHECK_STRIDE`] steps and at the last one,
    /// checks the balance (the largest relative excess goes to `worst`).
    fn observe(
        &mut self,
        integ: &dyn Integrator,
        last: bool,
        worst: &mut f64,
    ) -> Result<(), Error> {
        let (s, sys, h) = (integ.state(), integ.system(), integ.dt());
        self.audit.advance(sys, s.time - h, h, self.theta, &s.q);
        if !(last || s.step.is_multiple_of(ENERGY_CHECK_STRIDE)) {
            return Ok(());
        }
        let x = self.audit.excess(sys, s.time, &s.q, &s.v);
        let (rel, abs) = (x.relative, x.joules);
        *worst = worst.max(rel);
        if rel > self.max {
            return Err(Error::RunFailed {
                step: s.step,
                time: s.time,
                contact: None,
                detail: format!(
                    "the energy grew by {abs:.3e} J ({:.1} % of the run's energy scale) beyond \
                     the {:.3e} J supplied by loads and prescribed motion, more than \
                     scheme.max_energy_excess = {}: the solution is not the scheme's (lower \
                     the time step or the tolerances{}, or raise scheme.max_energy_excess \
                     (--max-energy-excess) to accept it)",
                    100.0 * rel,
                    self.audit.work(),
                    self.max,
                    if self.caps_allowed {
                        ", do not allow caps (capped steps are not the scheme's solution)"
                    } else {
                        ""
                    }
                ),
            });
        }
        Ok(())
    }
}

impl Observer for RunObserver {
    fn observe(&mut self, integ: &dyn Integrator, st: &StepStats, last: bool) -> Result<(), Error> {
        self.acc.add(st);
        if let Some(e) = self.energy.as_mut() {
            e.observe(integ, last, &mut self.acc.energy_excess)?;
        }
        let s = integ.state();
        let f = s.impulse.iter().sum::<f64>() / self.h;
        let g = s.gap.iter().copied().fold(f64::INFINITY, f64::min);
        self.tracker.push(s.step - 1, f, g);
        self.writers.observe(integ, st, last)?;
        if let Some((every, abort_after)) = self.plan.as_ref().map(|p| (p.every, p.abort_after)) {
            if !last && s.step.is_multiple_of(every) {
                let t0 = Instant::now();
                self.checkpoint(integ)?;
                self.writers.seconds += t0.elapsed().as_secs_f64();
            }
            if abort_after == Some(s.step) {
                if let Some(h) = self.writers.history.as_mut() {
                    h.flush()?;
                }
                std::process::abort();
            }
        }
        Ok(())
    }
}

impl RunObserver {
    /// Flushes the history, waits for the queued frames and writes the checkpoint.
    fn checkpoint(&mut self, integ: &dyn Integrator) -> Result<(), Error> {
        let Some(p) = &self.plan else {
            return Ok(());
        };
        if let Some(h) = self.writers.history.as_mut() {
            h.flush()?;
        }
        if let Some(f) = self.writers.frames.as_mut() {
            f.sync()?;
        }
        let a = &self.acc;
        let t = &self.tracker;
        let run = RunState {
            sum: a.sum,
            max: a.max,
            caps: a.caps,
            lcp_res: Bits(a.lcp_res),
            violation: Bits(a.violation),
            friction_counts: [
                a.fr_solves,
                a.fr_sweeps,
                a.fr_sweeps_max,
                a.fr_steps,
                a.fr_caps,
                a.fr_fallbacks,
            ],
            friction_residual: [Bits(a.fr_res_sum), Bits(a.fr_res_max)],
            newton_loops: a.loops,
            energy_audit: self
                .energy
                .as_ref()
                .map_or([0.0; 6], |e| e.audit.save())
                .map(Bits),
            energy_excess: Bits(a.energy_excess),
            trace: t.trace.clone().map(Floats),
            first_contact: t.first,
            contact_force: Floats(t.force.clone()),
            contact_min_gap: Floats(t.min_gap.clone()),
            contact_done: t.done,
            total_force: Bits(t.total_force),
            energy0: Bits(p.energy0),
            history_bytes: self.writers.history.as_ref().map_or(0, |h| h.bytes()),
            history_rows: self.writers.history.as_ref().map_or(0, |h| h.rows()),
            frames: self.writers.frame_count,
            closed_before: self.writers.closed_before,
        };
        Checkpoint {
            format: checkpoint::FORMAT.to_string(),
            version: checkpoint::VERSION,
            source: p.source.clone(),
            output: p.output.clone(),
            every: p.every,
            steps: p.steps,
            integrator: integ.save(),
            run,
            build: checkpoint::build_id(),
            out_dir: p.out_dir.clone(),
            inputs: p.inputs.clone(),
        }
        .write(&p.dir)
    }

    /// The accumulators of a checkpoint.
    fn restore(&mut self, r: &RunState) {
        let a = &mut self.acc;
        (a.sum, a.max, a.caps) = (r.sum, r.max, r.caps);
        (a.lcp_res, a.violation) = (r.lcp_res.0, r.violation.0);
        [
            a.fr_solves,
            a.fr_sweeps,
            a.fr_sweeps_max,
            a.fr_steps,
            a.fr_caps,
            a.fr_fallbacks,
        ] = r.friction_counts;
        (a.fr_res_sum, a.fr_res_max) = (r.friction_residual[0].0, r.friction_residual[1].0);
        a.loops = r.newton_loops;
        a.energy_excess = r.energy_excess.0;
        let t = &mut self.tracker;
        t.trace = r.trace.as_ref().map(|f| f.0.clone());
        t.first = r.first_contact;
        t.force = r.contact_force.0.clone();
        t.min_gap = r.contact_min_gap.0.clone();
        t.done = r.contact_done;
        t.total_force = r.total_force.0;
        self.writers.closed_before = r.closed_before;
        self.writers.frame_count = r.frames;
    }
}

/// What [`run`] needs to checkpoint a run or to resume one.
pub struct Checkpointing<'a> {
    /// What to rebuild on resume.
    pub source: RunSource,
    /// The checkpoint to resume from (`None`: a new run).
    pub resume: Option<&'a Checkpoint>,
}

/// Steps `integ` `steps` times through [`drive`], streaming the history and the field
/// frames (when `out` is given) and measuring the contact; the caller writes the
/// summary ([`write_summary`]).
///
/// Frames are saved at the start, every `frame_stride` steps, at each contact onset and
/// release and at the last step; history rows every `history_stride` steps and at the
/// last step. The time spent writing (including the energies and fields computed only
/// for output) is measured and reported as `output_seconds`.
#[allow(clippy::too_many_arguments)]
pub fn run(
    integ: &mut dyn Integrator,
    steps: usize,
    elements: usize,
    theta: f64,
    checks: &RunChecks,
    reference: Option<ImpactingBar>,
    parameters: serde_json::Value,
    out: Option<(Output, Geometry)>,
    progress: &mut dyn Progress,
) -> Result<RunResult, Error> {
    run_checkpointed(
        integ, steps, elements, theta, checks, reference, parameters, out, progress, None,
    )
}

/// [`run`], writing checkpoints when `out.options.checkpoint_every > 0` (then `ckpt`
/// says what to rebuild), or resuming from `ckpt.resume`.
#[allow(clippy::too_many_arguments)]
pub fn run_checkpointed(
    integ: &mut dyn Integrator,
    steps: usize,
    elements: usize,
    theta: f64,
    checks: &RunChecks,
    reference: Option<ImpactingBar>,
    parameters: serde_json::Value,
    out: Option<(Output, Geometry)>,
    progress: &mut dyn Progress,
    ckpt: Option<Checkpointing>,
) -> Result<RunResult, Error> {
    let h = integ.dt();
    let m = integ.state().gap.len();
    let resume = ckpt.as_ref().and_then(|c| c.resume);
    if let Some(c) = resume {
        if c.steps != steps || c.integrator.step >= steps {
            return Err(Error::invalid(
                "checkpoint steps",
                format!("{} (at step {})", c.steps, c.integrator.step),
                &format!("the scene makes {steps} steps"),
            ));
        }
        integ.restore(&c.integrator)?;
    }
    let t0 = Instant::now();
    let mut writers = Writers {
        history: None,
        frames: None,
        frame_stride: usize::MAX,
        history_stride: usize::MAX,
        closed_before: false,
        frame_count: 0,
        seconds: 0.0,
        scratch: vec![0.0; 2 * integ.system().prescribed_dofs()],
    };
    let mut plan = None;
    let energy0 = match resume {
        Some(c) => c.run.energy0.0,
        None => {
            let s = integ.state();
            integ.system().total_energy(s.time, &s.q, &s.v)
        }
    };
    // held until the run returns: a second run into the same directory is refused
    let mut _lock = None;
    if let Some((o, geom)) = out {
        o.options.validate()?;
        _lock = Some(crate::io::RunLock::acquire(o.dir)?);
        let geom_outlines = geom.outlines.clone();
        let hist_path = o.dir.join("history.csv");
        let hist = match resume {
            Some(c) => HistoryWriter::resume(&hist_path, c.run.history_bytes, c.run.history_rows)?,
            None => {
                crate::io::prepare_run_dir(o.dir)?;
                HistoryWriter::create(&hist_path, m, integ.state().tangent_dim)?
            }
        };
        #[cfg(feature = "hdf5")]
        let h5 = match (o.options.hdf5(), resume) {
            (false, _) => None,
            (true, None) => Some(crate::io::h5::RunFile::create(o.dir)?),
            (true, Some(_)) => Some(crate::io::h5::RunFile::open(o.dir)?),
        };
        #[cfg(feature = "hdf5")]
        let hist = match &h5 {
            Some(f) => hist.with_hdf5(crate::io::h5::History::create(
                f,
                m,
                integ.state().tangent_dim,
                integ.name(),
                h,
                theta,
                &parameters,
                resume.map(|c| c.run.history_rows as usize),
            )?),
            None => hist,
        };
        // a model without field geometry (the academic examples) writes no frames
        if o.options.fields && !geom.points.is_empty() {
            let w = match resume {
                Some(c) => FrameWriter::resume(
                    o.dir,
                    "fields",
                    geom,
                    integ.jacobian(),
                    o.options.encoding,
                    c.run.frames,
                )?,
                None => FrameWriter::create(
                    o.dir,
                    "fields",
                    geom,
                    integ.jacobian(),
                    o.options.encoding,
                )?,
            };
            if !geom_outlines.is_empty() {
                crate::io::frames::write_outlines(&o.dir.join("obstacles.vtu"), &geom_outlines)?;
            }
            #[cfg(feature = "hdf5")]
            let w = match &h5 {
                Some(f) => w.with_hdf5(f, resume.map(|c| c.run.frames))?,
                None => w,
            };
            let s = integ.state();
            let mut w =
                FrameStream::spawn_with_statuses(w, s.q.len(), m, s.status.len(), FRAME_POOL);
            if resume.is_none() {
                w.push(s, integ.jacobian(), h)?;
                writers.frame_count += 1;
            }
            writers.frames = Some(w);
        }
        writers.history = Some(hist);
        writers.frame_stride = o.options.frame_stride(steps);
        writers.history_stride = o.options.history_stride;
        let every = resume.map_or(o.options.checkpoint_every, |c| c.every);
        if let Some(c) = ckpt.as_ref().filter(|_| every > 0) {
            let (inputs, out_dir) = match resume {
                Some(r) => (r.inputs.clone(), r.out_dir.clone()),
                None => (
                    c.source.input_files()?,
                    std::fs::canonicalize(o.dir).map_err(|e| Error::io(o.dir, e))?,
                ),
            };
            plan = Some(CheckpointPlan {
                every,
                dir: o.dir.to_path_buf(),
                source: c.source.clone(),
                output: o.options.clone(),
                steps,
                energy0,
                inputs,
                out_dir,
                abort_after: std::env::var("SIGNORINI_ABORT_AFTER_STEP")
                    .ok()
                    .and_then(|v| v.parse().ok()),
            });
        }
    }
    let mut output_seconds = t0.elapsed().as_secs_f64();
    let mut obs = RunObserver {
        acc: Acc::default(),
        tracker: ContactTracker::new(steps, plan.is_none(), reference.is_some()),
        writers,
        h,
        plan,
        // Schatzman–Paoli's velocity is a central difference: its discrete energy is
        // not the θ-method's, whose balance the check reads
        energy: (integ.name() != "schatzman-paoli").then(|| {
            let s = integ.state();
            EnergyCheck {
                audit: crate::model::energy::EnergyAudit::new(integ.system(), s.time, &s.q, &s.v),
                theta,
                max: checks.max_energy_excess,
                caps_allowed: checks.allow_caps,
            }
        }),
    };
    if let Some(c) = resume {
        obs.restore(&c.run);
        if let Some(e) = obs.energy.as_mut() {
            e.audit
                .restore(c.run.energy_audit.map(|b| b.0), &integ.state().q);
        }
    }
    let start = Instant::now();
    drive(integ, steps, checks, &mut [&mut obs], progress)?;
    let t_fin = Instant::now();
    let RunObserver {
        acc,
        tracker,
        mut writers,
        plan,
        energy,
        ..
    } = obs;
    let energy_balance = energy.map(|e| EnergyBalance {
        supplied_work: e.audit.work(),
        excess_max: acc.energy_excess,
    });
    output_seconds += writers.seconds;
    if let Some(w) = writers.history.take() {
        w.finish()?;
    }
    let (frame_count, frame_seconds, frame_wait) = match writers.frames.take() {
        Some(f) => {
            let wait = f.waited_seconds();
            let w = f.finish()?;
            (w.frames().len(), w.busy_seconds(), wait)
        }
        None => (0, 0.0, 0.0),
    };
    // the run is complete: its checkpoint would only resume a finished run
    if let Some(p) = plan {
        let path = p.dir.join(checkpoint::FILE);
        if path.exists() {
            std::fs::remove_file(&path).map_err(|e| Error::write(&path, e))?;
        }
    }
    output_seconds += t_fin.elapsed().as_secs_f64();
    let wall = start.elapsed().as_secs_f64();
    let s = integ.state();
    let sys = integ.system();
    let energy1 = sys.total_energy(s.time, &s.q, &s.v);
    let contact = reference.map(|r| contact_summary(&tracker, h, sys, &s.v, r));
    let summary = Summary {
        scheme: integ.name().to_string(),
        elements,
        dofs: s.q.len(),
        dt: h,
        theta,
        steps,
        t_end: s.time,
        wall_seconds: wall,
        seconds_per_step: wall / steps.max(1) as f64,
        output_seconds,
        frames: frame_count,
        frame_seconds,
        frame_wait_seconds: frame_wait,
        max_violation: acc.violation,
        contact,
        iterations: acc.iterations(steps),
        caps_hit: acc.caps,
        newton_loops: NewtonLoops {
            coupled_solves: acc.loops[0],
            stalls: acc.loops[1],
            steps_with_held_rows: acc.loops[2],
            complementarity_fallbacks: acc.loops[3],
        },
        friction: acc.friction(s.tangent_dim > 0),
        max_lcp_residual: acc.lcp_res,
        energy: [energy0, energy1],
        energy_balance,
        path: integ.path(),
        model_seconds: 0.0,
        integrator_seconds: 0.0,
        parameters,
    };
    Ok(RunResult {
        summary,
        force: tracker.trace.unwrap_or_default(),
    })
}

/// Completes a run: records the set-up times, writes `summary.json` and the plots.
fn finish(mut r: RunResult, setup: [f64; 2], out: Option<Output>) -> Result<RunResult, Error> {
    [r.summary.model_seconds, r.summary.integrator_seconds] = setup;
    if let Some(o) = out {
        write_summary(&r.summary, o.dir)?;
        if o.options.plots {
            crate::plot::plot_run(o.dir)?;
        }
    }
    Ok(r)
}

/// Writes `summary.json` into `dir` atomically.
pub fn write_summary(summary: &Summary, dir: &Path) -> Result<(), Error> {
    let json = serde_json::to_string_pretty(summary).expect("summary serializes");
    write_atomic(&dir.join("summary.json"), json.as_bytes())
}

/// Measures the first contact interval.
///
/// The interval is the first run of steps that are closed (positive impulse, or
/// gap ≤ 0) and contain a positive impulse. Sample `k` (0-based) is the mean force
/// over `[k h, (k+1) h]`, placed at its midpoint. The plateau is the mean over the
/// middle 80 % of the interval's steps. The duration is measured between the
/// half-plateau crossings (linear interpolation between samples, zero force before
/// the first sample): the release front of a space-discretized bar is smeared over a
/// few steps by dispersion, and the half-height width is the time its centre takes,
/// independent of how far the tails reach. `closed_duration` counts the whole run.
fn contact_summary(
    tracker: &ContactTracker,
    h: f64,
    sys: &crate::model::LinearSystem,
    v: &[f64],
    r: ImpactingBar,
) -> ContactSummary {
    let (force, min_gap) = (&tracker.force, &tracker.min_gap);
    let mut c = ContactSummary {
        analytic_force: r.contact_force(),
        analytic_duration: r.contact_duration(),
        first_contact_time: f64::NAN,
        release_velocity: sys.momentum(v) / sys.total_mass(),
        analytic_release_velocity: r.release_velocity(),
        total_impulse: tracker.total_force * h,
        analytic_total_impulse: r.total_impulse(),
        ..ContactSummary::default()
    };
    // the tracker's window starts at the first positive impulse, step `first`
    let (Some(first), Some(i0)) = (tracker.first, force.iter().position(|&f| f > 0.0)) else {
        return c;
    };
    let mut last = i0;
    let mut k = i0;
    while k < force.len() && (force[k] > 0.0 || min_gap[k] <= 0.0) {
        if force[k] > 0.0 {
            last = k;
        }
        k += 1;
    }
    let len = last + 1 - i0;
    let lo = i0 + len / 10;
    let hi = (last + 1 - len / 10).max(lo + 1);
    let win = &force[lo..hi];
    let plateau = win.iter().sum::<f64>() / win.len() as f64;
    c.plateau_force = plateau;
    c.plateau_std =
        (win.iter().map(|f| (f - plateau).powi(2)).sum::<f64>() / win.len() as f64).sqrt();
    c.closed_duration = len as f64 * h;
    c.first_contact_time = (first + i0) as f64 * h;
    let half = 0.5 * plateau;
    let at = |j: usize| if j < force.len() { force[j] } else { 0.0 };
    // rising crossing: first sample ≥ half, interpolated from the previous one
    let up = (i0..=last).find(|&j| force[j] >= half).unwrap_or(i0);
    let prev = if up > 0 { force[up - 1] } else { 0.0 };
    let t_up = (up as f64 - 0.5) * h + h * (half - prev) / (force[up] - prev);
    // falling crossing: last sample ≥ half, interpolated to the next one
    let down = (i0..=last)
        .rev()
        .find(|&j| force[j] >= half)
        .unwrap_or(last);
    let next = at(down + 1);
    let t_down = (down as f64 + 0.5) * h + h * (force[down] - half) / (force[down] - next);
    c.duration = t_down - t_up;
    c
}

/// The forecast as a short string for printing.
pub fn forecast_name(f: Forecast) -> String {
    match f {
        Forecast::Explicit { gamma } => format!("explicit (γ = {gamma})"),
        Forecast::Free => "free".to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::all_finite;

    #[test]
    fn finiteness_is_checked_in_every_lane_and_the_tail() {
        let mut x = vec![1e300; 21];
        assert!(all_finite(&x));
        for i in [0, 7, 8, 15, 16, 20] {
            for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                x[i] = bad;
                assert!(!all_finite(&x), "{bad} at {i}");
                x[i] = -1e300;
            }
        }
        assert!(all_finite(&[]));
    }
}
