//! The friction problem's data: contact blocks, the solver kinds and their parameters
//! with documented defaults, the statistics a solve returns, and the problem
//! `u = W r + q` itself (DESIGN.md §8; eq. 11–15 of the paper).

use serde::{Deserialize, Serialize};

use super::super::operator::DelassusOperator;

/// One contact block of a friction problem.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Block {
    /// First row of the block in `r`, `u`, `q` and the operator.
    pub offset: usize,
    /// Rows: 1 (frictionless), 2 (2-D: normal, tangent) or 3 (3-D: normal, two tangents).
    pub dim: usize,
    /// Friction coefficient μ ≥ 0.
    pub mu: f64,
}

/// Which friction solver runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum FrictionSolverKind {
    /// NSGS first, then the robust methods on what it leaves (default): in one-step
    /// problems the proximal Newton method for [`AUTO_NEWTON_FIRST`] iterations, the plain
    /// one, and the proximal one again; in the step loop the plain and then the proximal
    /// method on a dense workspace sized at set-up, up to
    /// [`super::newton::STEP_NEWTON_ROWS`] rows (PROX above).
    /// [`FrictionInfo::solver`] says which one finished.
    #[cfg_attr(
        feature = "cli",
        value(
            help = "NSGS first, then the robust methods on what it leaves (default): the \
                    global Newton methods, proximal and plain (in the step loop up to 1024 \
                    contact rows; PROX above); the output names the one that finished"
        )
    )]
    #[default]
    Auto,
    /// Nonsmooth Gauss–Seidel with exact local solves.
    Nsgs,
    /// Proximal point with NSGS inside (rank-deficient `W`).
    Prox,
    /// Global semismooth Newton on Alart–Curnier, no regularization (Siconos' NSN_AC;
    /// [`super::newton`]; allocates, so not in the step loop).
    #[cfg_attr(
        feature = "cli",
        value(help = "Global semismooth Newton on Alart–Curnier, no regularization \
                    (Siconos' NSN_AC; one-step problems only)")
    )]
    Nsn,
    /// Proximal point with the global Newton inside (Siconos' PROX with its Newton inner
    /// solver; [`super::newton`]; allocates, so not in the step loop).
    #[cfg_attr(
        feature = "cli",
        value(
            help = "Proximal point with the global Newton inside (Siconos' PROX with its \
                    Newton inner solver; one-step problems only)"
        )
    )]
    Newton,
}

impl FrictionSolverKind {
    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            FrictionSolverKind::Auto => "auto",
            FrictionSolverKind::Nsgs => "nsgs",
            FrictionSolverKind::Prox => "prox",
            FrictionSolverKind::Nsn => "nsn",
            FrictionSolverKind::Newton => "newton",
        }
    }

    /// One phrase for `signorini check`.
    pub fn describe(self) -> &'static str {
        match self {
            FrictionSolverKind::Auto => {
                "NSGS, falling back to the global Newton methods (dense, up to 1024 rows) or \
                 to proximal point over NSGS"
            }
            FrictionSolverKind::Nsgs => "NSGS with exact local solves",
            FrictionSolverKind::Prox => "proximal point over NSGS",
            FrictionSolverKind::Nsn => "global Alart–Curnier Newton",
            FrictionSolverKind::Newton => "proximal point over a global Alart–Curnier Newton",
        }
    }

    /// True for the solvers that allocate per iteration (one-step problems only).
    pub fn allocates(self) -> bool {
        matches!(self, FrictionSolverKind::Nsn | FrictionSolverKind::Newton)
    }
}

/// NSGS sweeps `auto` gives NSGS before it falls back, in one-step problems (measured
/// on the FCLIB files: NSGS converges within 40 sweeps where it is the fastest solver).
pub const AUTO_NSGS_ONE_STEP: usize = 100;
/// NSGS sweeps `auto` gives NSGS in the step loop before PROX takes over (warm-started
/// NSGS needs a few sweeps per step on every shipped scene).
pub const AUTO_NSGS_STEP: usize = 1000;
/// Iterations `auto` gives the plain Newton method in one-step problems.
pub const AUTO_NSN: usize = 200;
/// Iterations `auto` gives the proximal Newton method first, in one-step problems, after
/// NSGS and before the plain method. Measured on the FCLIB files
/// (`benches/fclib_siconos.py`): the proximal method converged within 39 iterations on
/// every file it finishes quickly (BoxesStack1 19 → 6.6 ms, local_problem_test 11 →
/// 1.6 ms, OneObject 1.26 → 0.56 ms, the capsules 2×), spheres-in-a-box needs 950 and
/// goes on to the plain method (0.39 → 0.55 s, Siconos' best 1.29 s); 30 iterations
/// missed BoxesStack1's 39.
pub const AUTO_NEWTON_FIRST: usize = 50;

/// Largest friction tolerance the schemes accept ([`FrictionParams::validate`]).
pub const MAX_STEP_TOL: f64 = 1e-4;

/// Controls of the friction solvers, with the defaults the schemes use.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FrictionParams {
    /// Which solver (default `auto`).
    pub solver: FrictionSolverKind,
    /// Stop when the residual (module doc) is at most this (default 1e-12: the schemes
    /// need the impulses to near round-off for gaps of 1e-12 m and stick of 1e-9 m).
    pub tol: f64,
    /// Cap on NSGS sweeps (in total over the proximal iterations for PROX; default 10 000).
    pub max_iterations: usize,
    /// Cap on the local Newton iterations of a 3-D block (default 50).
    pub local_max_iterations: usize,
}

impl Default for FrictionParams {
    fn default() -> Self {
        FrictionParams {
            solver: FrictionSolverKind::Auto,
            tol: 1e-12,
            max_iterations: 10_000,
            local_max_iterations: 50,
        }
    }
}

impl FrictionParams {
    /// Checks the ranges; errors name the field under `prefix`.
    pub fn validate(&self, prefix: &str) -> Result<(), crate::Error> {
        // In the step loop the tolerance also sets the Newton loop's floor and the
        // position dead band (`integrators::core`): above 1e-4 the impulses are too rough
        // for either (tol = 0.5 let a block sink 0.6 mm and gain energy ×2, exit 0).
        if self.tol.is_nan() || self.tol <= 0.0 || self.tol > MAX_STEP_TOL {
            return Err(crate::Error::invalid(
                &format!("{prefix}tol"),
                crate::error::num(self.tol),
                &format!(
                    "must be in (0, {MAX_STEP_TOL:e}] for the schemes: it is the friction \
                     solve's relative accuracy, and the step's gaps and Newton loop follow it"
                ),
            ));
        }
        self.validate_ranges(prefix)?;
        if self.solver.allocates() {
            return Err(crate::Error::invalid(
                &format!("{prefix}solver"),
                self.solver.name(),
                "is for one-step problems (signorini fclib): it forms and factors a Jacobian \
                 per iteration, and the step loop does not allocate; use auto, nsgs or prox",
            ));
        }
        Ok(())
    }

    /// Checks the ranges only (any solver; one-step problems).
    pub fn validate_ranges(&self, prefix: &str) -> Result<(), crate::Error> {
        crate::error::require_in(&format!("{prefix}tol"), self.tol, 0.0, 1.0)?;
        if self.max_iterations == 0 {
            return Err(crate::Error::invalid(
                &format!("{prefix}max_iterations"),
                0,
                "must be at least 1",
            ));
        }
        if self.local_max_iterations == 0 {
            return Err(crate::Error::invalid(
                &format!("{prefix}local_max_iterations"),
                0,
                "must be at least 1",
            ));
        }
        Ok(())
    }
}

/// What a friction solve reports.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct FrictionInfo {
    /// NSGS sweeps (summed over the proximal iterations for PROX).
    pub iterations: usize,
    /// Final residual (module doc).
    pub residual: f64,
    /// Proximal iterations (0 for NSGS).
    pub prox_iterations: usize,
    /// The residual reached the tolerance (false: the cap was hit; `r` is the last
    /// iterate, or the best one for the Newton methods).
    pub converged: bool,
    /// The solver that produced `r` (for `auto`: the stage that finished).
    pub solver: FrictionSolverKind,
    /// The Newton methods factored a sparse Jacobian (the block pattern of `W`).
    pub sparse_jacobian: bool,
    /// Local 2-D solves for which no case of the law was consistent (the least
    /// inconsistent one was kept): 0 unless a `W_αα` is not positive definite or a sign
    /// sits at round-off.
    pub inconsistent_local_solves: usize,
    /// The tolerance the solve stopped on: the caller's, raised to the round-off floor
    /// `μ_max ε` where the friction coefficient is that large ([`FrictionSolver::solve`](super::FrictionSolver::solve)).
    pub tolerance: f64,
}

/// A friction problem `u = W r + q` over `blocks` (rows `0..k` of `w` and `q`).
pub struct FrictionProblem<'a, W: DelassusOperator + ?Sized> {
    /// The operator (its rows `0..k` in the order of `blocks`).
    pub w: &'a W,
    /// The constant term.
    pub q: &'a [f64],
    /// The contact blocks, contiguous from row 0.
    pub blocks: &'a [Block],
}

impl<W: DelassusOperator + ?Sized> Clone for FrictionProblem<'_, W> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<W: DelassusOperator + ?Sized> Copy for FrictionProblem<'_, W> {}
