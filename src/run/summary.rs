//! What a run reports: the [`Summary`] written to `summary.json` (iterations, caps,
//! friction, contact measurement against the analytic reference, energy balance). The
//! first-contact-interval measurement behind its [`ContactSummary`] is in
//! `run/contact.rs`.

use std::path::Path;

use serde::Serialize;

use crate::error::Error;
use crate::integrators::Forecast;
use crate::io::write_atomic;

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

/// The matrix-free one-step solves of a run ([`crate::solvers::global`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct MatrixFreeSummary {
    /// Problems solved matrix-free (`StepStats::global_solves`).
    pub solves: usize,
    /// Products with the Delassus operator they took (`StepStats::global_products`).
    pub products: usize,
    /// Products per solve.
    pub products_per_solve: f64,
}

/// The Newton loop of a nonlinear structure over a run ([`Summary::nonlinear`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct NonlinearSummary {
    /// Factorizations of `M̂ⁿ` over the run.
    pub factorizations: usize,
    /// Factorizations per step.
    pub factorizations_per_step: f64,
    /// Seconds spent evaluating `F`, `Kⁿ` and forming `M̂ⁿ` (element kernels and assembly;
    /// the steps run in this session).
    pub assembly_seconds: f64,
    /// Seconds spent refactoring `M̂ⁿ` (this session's steps).
    pub factorization_seconds: f64,
}

/// A run's energy balance ([`Summary::energy_balance`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct EnergyBalance {
    /// Work supplied by the time-dependent loads and the prescribed motion (J).
    pub supplied_work: f64,
    /// Largest `(E − E₀ − W) / scale` met at the checks (0 when it never was positive); above
    /// `scheme.max_energy_excess` the run fails.
    pub excess_max: f64,
    /// The floor of the energy scale from the scene's own magnitudes (J;
    /// [`crate::model::energy::EnergyFloor`]).
    pub scale_floor: f64,
}

/// The rotation check's figures ([`Summary::rotation`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RotationSummary {
    /// `scheme.max_rotation` (rad).
    pub limit: f64,
    /// The largest rotation of a linear body's cell at the last step (rad).
    pub final_largest: f64,
    /// Its body and cell (index within the body).
    pub body: usize,
    /// The cell.
    pub cell: usize,
}

/// One body's measures at the start and the end of a run (`summary.json`'s `bodies`).
#[derive(Clone, Debug, Serialize)]
pub struct BodySummary {
    /// The scene's body name.
    pub name: String,
    /// At the initial state.
    pub initial: crate::model::BodyState,
    /// After the last step.
    #[serde(rename = "final")]
    pub last: crate::model::BodyState,
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
    /// The memory ledger's total, checked before the run (bytes; an upper bound: it
    /// counts zeroed buffers the run may never touch).
    pub memory_planned_bytes: u64,
    /// Peak resident memory of the process (bytes; Linux `VmHWM`, absent elsewhere).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub peak_memory_bytes: Option<u64>,
    /// One-step problems solved matrix-free because their active rows exceeded the
    /// dense workspaces (absent when none was).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub matrix_free: Option<MatrixFreeSummary>,
    /// The nonlinear structure's Newton loop (absent for a linear structure).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub nonlinear: Option<NonlinearSummary>,
    /// Largest LCP complementarity residual met.
    pub max_lcp_residual: f64,
    /// Energy (kinetic + potential) at the start and at the end (J).
    pub energy: [f64; 2],
    /// The energy balance (`model::energy`): work supplied by loads and prescribed
    /// motion, and the largest excess met relative to the run's energy scale (`None` for
    /// Schatzman–Paoli, whose discrete energy is not the θ-method's).
    pub energy_balance: Option<EnergyBalance>,
    /// The rotation check of linear bodies (`run::rotations`; absent where no body is
    /// measured): its limit and the largest cell rotation at the end of the run.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rotation: Option<RotationSummary>,
    /// Whether the history rows were formed on a thread of their own
    /// (`run::history_thread`: from 4096 dofs on more than one core).
    pub history_thread: bool,
    /// The arithmetic of the chain solves: `fused` (fused multiply-add, this CPU's bits)
    /// or `portable` (`--portable-arithmetic`, or a CPU without FMA: the same bits on
    /// every CPU); see [`crate::linalg::Arithmetic`].
    pub arithmetic: String,
    /// What the run's threads did with subnormal numbers: `flushed` to zero (the
    /// default) or `ieee` (`--ieee-subnormals`, or a CPU without the control); see
    /// [`crate::linalg::subnormals`](mod@crate::linalg::subnormals).
    pub subnormals: String,
    /// The displacement probes (a scene's `[[probes]]`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub probes: Vec<super::probes::ProbeSummary>,
    /// Each body's mass, centre of mass, linear and angular momentum at the start and
    /// at the end of the run ([`crate::model::BodyMeasures`]; scenes with meshes).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub bodies: Vec<BodySummary>,
    /// Linear-algebra path taken.
    pub path: String,
    /// Seconds to build the model (mesh, parallel assembly of `M` and `K`, contacts).
    pub model_seconds: f64,
    /// Seconds to build the integrator (factorization of `M̂`, Delassus data).
    pub integrator_seconds: f64,
    /// The scene parameters as run.
    pub parameters: serde_json::Value,
    /// The accuracy mode (`time.accuracy`): what was asked, what the run estimates, the
    /// steps it chose ([`super::accuracy`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub accuracy: Option<super::accuracy::AccuracySummary>,
}

/// What [`run_bar`](crate::app::run_bar) returns: the summary and the per-step contact force.
pub struct RunResult {
    /// The run summary.
    pub summary: Summary,
    /// Total contact force `Σ P / h` at each step (N); empty for runs that write
    /// checkpoints (a checkpoint does not grow with the run) and beyond
    /// [`FORCE_TRACE_MAX_STEPS`](super::FORCE_TRACE_MAX_STEPS).
    pub force: Vec<f64>,
    /// The step of each entry of `force` (s) when the step varied during the run (the
    /// accuracy mode); empty when every step was the summary's `dt`.
    pub dt: Vec<f64>,
    /// The state after the last step (one copy, made once at the end: the Python
    /// package's `sim.q`, `sim.v`, … after `run()`).
    pub state: crate::integrators::State,
}

/// Writes `summary.json` into `dir` atomically.
pub fn write_summary(summary: &Summary, dir: &Path) -> Result<(), Error> {
    let json = serde_json::to_string_pretty(summary).expect("summary serializes");
    write_atomic(&dir.join("summary.json"), json.as_bytes())
}

/// The forecast as a short string for printing.
pub fn forecast_name(f: Forecast) -> String {
    match f {
        Forecast::Explicit { gamma } => format!("explicit (γ = {gamma})"),
        Forecast::Free => "free".to_string(),
    }
}
