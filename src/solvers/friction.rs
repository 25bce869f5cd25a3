//! One-step Coulomb friction problems (eq. 11–15): find `r` and `u = W r + q` with
//! `C* ∋ û ⊥ r ∈ C`, `û = u + μ‖u_T‖ e_N` (De Saxcé's modified velocity, eq. 13), block
//! by block in the local frames (normal first, then one or two tangents). Newton's
//! impact law enters through `q`: the integrators put `U_free + e U_k` in its normal
//! rows, so `u_N` is `U_{k+1} + e U_k` (eq. 18d with friction).
//!
//! Two solvers, as Siconos' fc2d/fc3d and LMGC90's NLGS offer them:
//!
//! * [`FrictionSolverKind::Nsgs`]: nonsmooth Gauss–Seidel over the contacts (Jean–Moreau
//!   NLGS), each block solved exactly with the others frozen: `r_N = max(0, −q_N/W_NN)`
//!   for a frictionless block; the closed form of the 2-D law (open, stick, slip left,
//!   slip right: the one consistent case of the four); in 3-D the exact stick solution
//!   `W r = −q` when it lies in the cone (every block sticks at large μ), else a
//!   semismooth Newton on the Alart–Curnier function with an Armijo line search, and
//!   the projected fixed point `r ← P_C(r − ρ û)` as fallback. Warm started by the caller's `r`.
//!   The method of choice for the few contacts per step of the schemes, and for full-rank
//!   finite-element problems.
//! * [`FrictionSolverKind::Prox`]: the proximal-point method: NSGS on the regularized
//!   problems `(W + σI, q − σ r_j)` until `r_{j+1} = r_j`. Every regularized block is
//!   positive definite even when `W` is rank deficient (rigid multibody problems), which
//!   is where plain NSGS stalls (FCLIB's `local_problem_test`, Siconos' NSGS included).
//!
//! * [`FrictionSolverKind::Newton`]: the same proximal loop around a global semismooth
//!   Newton method on the Alart–Curnier function `Φ(r) = 0` of all blocks at once
//!   (generalized Jacobian `J = A + B (W + σI)` with `A`, `B` block diagonal, Armijo
//!   line search on `½‖Φ‖²`), as Siconos' PROX with its inner Newton: quadratic
//!   convergence where NSGS crawls; [`FrictionSolverKind::Nsn`] is the plain Newton
//!   method. One-step problems factor `J` sparse where `W` is; in the step loop they are
//!   `auto`'s fallback on a dense `J` whose buffers are sized once (contact spaces up to
//!   [`super::newton::STEP_NEWTON_ROWS`] rows), and are refused by name (their sparse
//!   form allocates).
//!
//! Two residuals ([`Measure`]), each relative and with `u` recomputed from scratch as
//! `W r + q`:
//!
//! * Siconos' (`fc3d_compute_error`, one-step problems, so that figures compare):
//!   `‖r − P_C(r − û)‖ / max(‖q‖, ‖r‖, ‖u‖)` ([`residual`], with the take-off check of
//!   [`checked_residual`]). It adds impulses to velocities, and through `û` it weighs
//!   the round-off of `u_T` by μ.
//! * The velocity residual (the step loop): Alart–Curnier's map of each block at
//!   `ρ = 1/W_NN`, scaled back to m/s, over `max(‖q‖, ‖u‖, ‖D r‖)`
//!   ([`velocity_residual`]): one tolerance means the same for a heavy body and a light
//!   node, and μ does not amplify it. The step loop also reads [`velocity_error`], its
//!   largest block term in m/s, to derive its own tolerances (`integrators::core`).
//!
//! In slip the law pins `r_T = μ r_N` while `u_N` is known to the round-off of `u`, so
//! no residual falls below about `μ ε`: a solve's tolerance is raised to `μ_max ε` where
//! that is larger ([`FrictionInfo::tolerance`]).
//! Tolerance, iteration caps, the iterations and the residual are data
//! ([`FrictionParams`], [`FrictionInfo`]); a cap hit is flagged in
//! [`FrictionInfo::converged`] with the residual reached, never a silent stop.
//!
//! All buffers are sized once ([`FrictionSolver::with_capacity`]); solving does not
//! allocate. The operator is any [`DelassusOperator`]: the solvers never see an
//! integrator. Written here rather than taken from a crate: no Rust crate offers
//! Coulomb-cone complementarity solvers (checked on crates.io and docs.rs, 2026-12).

use serde::{Deserialize, Serialize};

use super::SolveError;
use super::newton::NewtonMode;
use super::operator::DelassusOperator;

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
    /// `μ_max ε` where the friction coefficient is that large ([`FrictionSolver::solve`]).
    pub tolerance: f64,
}

/// Projection of `x = (x_N, x_T)` on the cone `‖x_T‖ ≤ μ x_N` (in place).
pub fn project_on_cone(x: &mut [f64], mu: f64) {
    let xn = x[0];
    if x.len() == 1 || mu == 0.0 {
        x[0] = xn.max(0.0);
        x[1..].iter_mut().for_each(|t| *t = 0.0);
        return;
    }
    let nt = norm(&x[1..]);
    if nt <= mu * xn {
        return;
    }
    if mu * nt <= -xn {
        x.iter_mut().for_each(|t| *t = 0.0);
        return;
    }
    let rn = (mu * nt + xn) / (1.0 + mu * mu);
    let s = mu * rn / nt;
    x[0] = rn;
    x[1..].iter_mut().for_each(|t| *t *= s);
}

pub(super) fn norm(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum::<f64>().sqrt()
}

/// Squared natural-map error of one block: `‖r − P_C(r − û)‖²`, `û = u + μ‖u_T‖ e_N`.
fn block_error2(r: &[f64], u: &[f64], mu: f64) -> f64 {
    let d = r.len();
    let mut x = [0.0; 3];
    let ut = norm(&u[1..d]);
    x[0] = r[0] - (u[0] + mu * ut);
    for i in 1..d {
        x[i] = r[i] - u[i];
    }
    project_on_cone(&mut x[..d], mu);
    (0..d).map(|i| (r[i] - x[i]).powi(2)).sum()
}

/// Siconos' residual `‖r − P_C(r − û)‖ / max(‖q‖, ‖r‖, ‖u‖)` for `u` already equal to
/// `W r + q`.
pub fn residual(blocks: &[Block], q: &[f64], r: &[f64], u: &[f64]) -> f64 {
    let e2: f64 = blocks
        .iter()
        .map(|b| {
            let s = b.offset..b.offset + b.dim;
            block_error2(&r[s.clone()], &u[s], b.mu)
        })
        .sum();
    relative(e2.sqrt(), blocks, q, r, u)
}

/// `e / max(‖q‖, ‖r‖, ‖u‖)` over the rows of `blocks` (no division when that maximum is
/// at most machine epsilon), the scale of Siconos' residual.
fn relative(e: f64, blocks: &[Block], q: &[f64], r: &[f64], u: &[f64]) -> f64 {
    let k = blocks.last().map_or(0, |b| b.offset + b.dim);
    let scale = norm(&q[..k]).max(norm(&r[..k])).max(norm(&u[..k]));
    if scale <= f64::EPSILON { e } else { e / scale }
}

/// Where [`residual`] is at most `tol`, raises it to the take-off error
/// `max |u_N| / max(‖q‖, ‖r‖, ‖u‖)` over the blocks with `r_N ≤ 0` and `u_N < 0`.
/// De Saxcé's complementarity accepts `r = 0` with `u_N < 0` when `μ‖u_T‖` is large
/// (`û ∈ C*` as soon as `u_N ≥ ‖u_T‖ (1/μ − μ)`): Siconos' residual then reads 0 at
/// `r = 0` (μ = 1e300 reported "converged, residual 0" with `u_N = −1`), while
/// Coulomb's law with Signorini's condition requires `u_N ≥ 0` on an open contact.
pub fn checked_residual(blocks: &[Block], q: &[f64], r: &[f64], u: &[f64], tol: f64) -> f64 {
    let res = residual(blocks, q, r, u);
    if res.is_nan() || res > tol {
        return res;
    }
    let worst = blocks
        .iter()
        .filter(|b| r[b.offset] <= 0.0 && u[b.offset] < 0.0)
        .map(|b| -u[b.offset])
        .fold(0.0, f64::max);
    if worst == 0.0 {
        return res;
    }
    res.max(relative(worst, blocks, q, r, u))
}

/// `‖Φ_α‖²` of one block's Alart–Curnier map with `ρ` on every row:
/// `Φ_N = r_N − max(0, r_N − ρ u_N)`, `Φ_T = r_T − P_{B(μ p_N)}(r_T − ρ u_T)` with
/// `p_N = max(0, r_N − ρ u_N)` (the `Φ` of [`super::newton`]). It states Coulomb's law
/// itself, not De Saxcé's: a sticking block reads `ρ‖u‖` whatever μ, where the natural
/// map of [`residual`] reads `‖u + μ‖u_T‖ e_N‖`, `μ` times the round-off of `u_T`
/// (μ = 1e6: a floor near 1e-10 that no solver can pass), and a block taking off with
/// `u_N < 0` reads `ρ|u_N|`, so no take-off check is needed.
pub(super) fn ac_map2(r: &[f64], u: &[f64], mu: f64, rho: f64) -> f64 {
    let d = r.len();
    let xn = r[0] - rho * u[0];
    let pn = xn.max(0.0);
    let mut e2 = (r[0] - pn).powi(2);
    if d == 1 {
        return e2;
    }
    let mut xt = [0.0; 2];
    for t in 0..d - 1 {
        xt[t] = r[1 + t] - rho * u[1 + t];
    }
    let nx = norm(&xt[..d - 1]);
    let rad = mu * pn;
    let f = if nx <= rad { 1.0 } else { rad / nx };
    for t in 0..d - 1 {
        e2 += (r[1 + t] - f * xt[t]).powi(2);
    }
    e2
}

/// The residual of the step loop's friction solves, in velocity units and relative:
/// `(Σ_α ‖Φ_α‖² / ρ_α²)^½ / max(‖q‖, ‖u‖, ‖D r‖)` with [`ac_map2`]'s `Φ_α` at
/// `ρ_α = 1/W_NN` of the block and `D` the blocks' `W_NN` (`diag`, the 3×3 diagonal
/// blocks, row-major, indexed by offset). Every term is a velocity, so one tolerance
/// means the same for a 10 kg body and a 1 mg node, and μ does not amplify the
/// round-off of `u_T` (module doc of [`residual`]'s difference). Blocks with
/// `W_NN ≤ 0` read infinitely wrong.
pub(super) fn velocity_residual_diag(
    blocks: &[Block],
    diag: &[[f64; 9]],
    q: &[f64],
    r: &[f64],
    u: &[f64],
) -> f64 {
    let (mut e2, mut dr2) = (0.0, 0.0);
    for b in blocks {
        let s = b.offset..b.offset + b.dim;
        let wnn = diag[b.offset][0];
        if wnn.is_nan() || wnn <= 0.0 {
            return f64::INFINITY;
        }
        e2 += ac_map2(&r[s.clone()], &u[s.clone()], b.mu, 1.0 / wnn) * wnn * wnn;
        dr2 += r[s].iter().map(|x| (wnn * x).powi(2)).sum::<f64>();
    }
    let k = blocks.last().map_or(0, |b| b.offset + b.dim);
    let scale = norm(&q[..k]).max(norm(&u[..k])).max(dr2.sqrt());
    if scale <= f64::MIN_POSITIVE {
        e2.sqrt()
    } else {
        e2.sqrt() / scale
    }
}

/// [`Measure::Velocity`]'s residual of `(r, u)` (`u = W r + q`) for the operator `w`:
/// the form the step loop's solvers stop on (`velocity_residual_diag`). Allocates its
/// diagonal: for checks outside the solvers.
pub fn velocity_residual<W: DelassusOperator + ?Sized>(
    w: &W,
    blocks: &[Block],
    q: &[f64],
    r: &[f64],
    u: &[f64],
) -> f64 {
    let k = blocks.last().map_or(0, |b| b.offset + b.dim);
    let mut diag = vec![[0.0; 9]; k];
    for b in blocks {
        diag[b.offset][0] = w.entry(b.offset, b.offset);
    }
    velocity_residual_diag(blocks, &diag, q, r, u)
}

/// The velocity accuracy of a solution, in m/s: the largest over the blocks of
/// `‖Φ_α‖ / ρ` with `ac_map2`'s Alart–Curnier map at `ρ = 1/W_NN` of the block, so
/// that an impulse error counts by the velocity it makes. Unlike [`residual`], which
/// adds impulses and velocities, it means the same for a 10 kg body and a 1 mg node,
/// and μ does not amplify it; the step loop derives its Newton stopping floor from it
/// ([`crate::integrators::core`]). Blocks with `W_NN ≤ 0` count as infinitely wrong.
pub fn velocity_error<W: DelassusOperator + ?Sized>(
    w: &W,
    blocks: &[Block],
    r: &[f64],
    u: &[f64],
) -> f64 {
    let mut worst: f64 = 0.0;
    for b in blocks {
        let s = b.offset..b.offset + b.dim;
        let wnn = w.entry(b.offset, b.offset);
        if wnn.is_nan() || wnn <= 0.0 {
            return f64::INFINITY;
        }
        worst = worst.max(ac_map2(&r[s.clone()], &u[s], b.mu, 1.0 / wnn).sqrt() * wnn);
    }
    worst
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

/// Workspace of the friction solvers, sized once.
#[derive(Clone, Debug)]
pub struct FrictionSolver {
    capacity: usize,
    /// Diagonal blocks `W_αα` (3×3 each, row-major, padded).
    diag: Vec<[f64; 9]>,
    col: Vec<f64>,
    pub(super) qreg: Vec<f64>,
    rprev: Vec<f64>,
    /// The caller's start `r` (`auto` restarts its last stage from it).
    start: Vec<f64>,
    pub(super) one_step: bool,
    /// NSGS leaves when its rate cannot reach the tolerance within its cap (`auto`'s
    /// first stage in one-step problems).
    give_up_early: bool,
    /// Local 2-D solves without a consistent case in the current [`FrictionSolver::solve`].
    inconsistent: usize,
    /// The residual the solves stop on and report.
    measure: Measure,
    /// The Newton methods' workspace of the step loop (`auto`'s fallback; sized once).
    pub(super) newton: Option<Box<super::newton::NewtonWork>>,
}

/// Which residual a [`FrictionSolver`] stops on and reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Measure {
    /// Siconos' [`residual`] (impulses and velocities added; `fc3d_compute_error`), so
    /// that one-step figures compare with Siconos' ([`FrictionSolver::for_one_step`]).
    Siconos,
    /// [`velocity_residual`]: velocities only, each block scaled by its `W_NN`, Coulomb's
    /// law in Alart–Curnier form (the step loop, [`FrictionSolver::with_capacity`]).
    Velocity,
}

impl Measure {
    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Measure::Siconos => "siconos",
            Measure::Velocity => "velocity",
        }
    }

    /// Parses a command-line name.
    pub fn parse(s: &str) -> Option<Self> {
        [Measure::Siconos, Measure::Velocity]
            .into_iter()
            .find(|m| m.name() == s)
    }
}

impl FrictionSolver {
    /// Buffers for problems of up to `capacity` rows, for the step loop: nothing
    /// allocates after this, including `auto`'s Newton fallback (a dense workspace
    /// while `capacity` is at most [`super::newton::STEP_NEWTON_ROWS`]); the residual is
    /// [`Measure::Velocity`].
    pub fn with_capacity(capacity: usize) -> Self {
        FrictionSolver {
            newton: Self::step_newton_work(capacity),
            ..Self::bare(capacity, Measure::Velocity)
        }
    }

    /// Buffers for one-step problems of `rows` rows (`signorini fclib`): `auto` may then
    /// fall back on the Newton methods, which allocate (a sparse `J` where `W` is
    /// sparse); the residual is Siconos' ([`Measure::Siconos`]).
    pub fn for_one_step(rows: usize) -> Self {
        FrictionSolver {
            one_step: true,
            ..Self::bare(rows, Measure::Siconos)
        }
    }

    fn bare(capacity: usize, measure: Measure) -> Self {
        FrictionSolver {
            capacity,
            diag: vec![[0.0; 9]; capacity],
            col: vec![0.0; capacity],
            qreg: vec![0.0; capacity],
            rprev: vec![0.0; capacity],
            start: vec![0.0; capacity],
            one_step: false,
            give_up_early: false,
            inconsistent: 0,
            measure,
            newton: None,
        }
    }

    /// Rows this workspace holds.
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// This solver, stopping on and reporting `measure` instead of its default.
    pub fn with_measure(self, measure: Measure) -> Self {
        FrictionSolver { measure, ..self }
    }

    /// The residual this solver stops on and reports.
    pub fn measure(&self) -> Measure {
        self.measure
    }

    /// The residual of `(r, u)` by [`FrictionSolver::measure`] (`u` already `W r + q`, or
    /// `(W + σI) r + q` for a regularized `q`); for Siconos' measure, checked for
    /// take-off at `tol` ([`checked_residual`]). The diagonal blocks must be those of
    /// the current [`FrictionSolver::solve`].
    pub(super) fn residual_of(
        &self,
        blocks: &[Block],
        q: &[f64],
        r: &[f64],
        u: &[f64],
        tol: f64,
    ) -> f64 {
        match self.measure {
            Measure::Siconos => checked_residual(blocks, q, r, u, tol),
            Measure::Velocity => velocity_residual_diag(blocks, &self.diag, q, r, u),
        }
    }

    /// `u = W r + q` from scratch and [`FrictionSolver::residual_of`].
    pub(super) fn full_residual_of<W: DelassusOperator + ?Sized>(
        &self,
        prob: &FrictionProblem<'_, W>,
        r: &[f64],
        u: &mut [f64],
        tol: f64,
    ) -> f64 {
        let k = prob.blocks.last().map_or(0, |b| b.offset + b.dim);
        u[..k].copy_from_slice(&prob.q[..k]);
        prob.w.mul_add(1.0, &r[..k], &mut u[..k]);
        self.residual_of(prob.blocks, prob.q, &r[..k], &u[..k], tol)
    }

    /// Solves `prob` with `params`; `r` holds the warm start on entry and the solution
    /// on exit, `u` the velocity `W r + q`.
    pub fn solve<W: DelassusOperator + ?Sized>(
        &mut self,
        prob: FrictionProblem<'_, W>,
        params: &FrictionParams,
        r: &mut [f64],
        u: &mut [f64],
    ) -> Result<FrictionInfo, SolveError> {
        let k = prob.blocks.last().map_or(0, |b| b.offset + b.dim);
        if k > self.capacity {
            return Err(SolveError::ActiveRows {
                active: k,
                cap: self.capacity,
            });
        }
        if prob.q[..k].iter().any(|x| !x.is_finite()) {
            return Err(SolveError::NonFinite);
        }
        for b in prob.blocks {
            let mut d = [0.0; 9];
            for i in 0..b.dim {
                for j in 0..b.dim {
                    d[3 * i + j] = prob.w.entry(b.offset + i, b.offset + j);
                }
            }
            // a contact's own compliance W_NN = G_Nᵀ M̂⁻¹ G_N is positive; zero or
            // negative means a bad operator, which no local solve can fix
            if !(d[0] > 0.0 && d[0].is_finite()) {
                return Err(SolveError::NonPositiveDiagonal {
                    row: b.offset,
                    value: d[0],
                });
            }
            self.diag[b.offset] = d;
        }
        self.inconsistent = 0;
        // Coulomb's law in slip pins r_T to μ r_N while u_N is known to the round-off of
        // u: no residual of a slipping block falls below about μ ε (its backward error;
        // measured: every solver stalled at 2.5e-12 to 9e-12 on a μ = 1e6 block at tol
        // 1e-12). The tolerance is raised to that floor: μ = 1e6 gives 2.2e-10; μ ≤ 1e3
        // leaves every tolerance from 1e-12 up unchanged.
        let floor = prob.blocks.iter().map(|b| b.mu).fold(0.0, f64::max) * f64::EPSILON;
        let raised = FrictionParams {
            tol: params.tol.max(floor),
            ..*params
        };
        let params = &raised;
        let nsgs = |s: &mut Self, cap: usize, r: &mut [f64], u: &mut [f64]| {
            let (it, res) = s.nsgs(prob, 0.0, (params.tol, cap), params, r, u);
            FrictionInfo {
                iterations: it,
                residual: res,
                converged: res <= params.tol,
                solver: FrictionSolverKind::Nsgs,
                ..FrictionInfo::default()
            }
        };
        let newton = |s: &mut Self, mode, p: &FrictionParams, r: &mut [f64], u: &mut [f64]| {
            let (mut info, sparse) = s.global_newton(prob, p, mode, k, r, u);
            info.solver = match mode {
                NewtonMode::Plain => FrictionSolverKind::Nsn,
                NewtonMode::Proximal => FrictionSolverKind::Newton,
            };
            info.sparse_jacobian = sparse;
            info
        };
        let info = match params.solver {
            FrictionSolverKind::Nsgs => nsgs(self, params.max_iterations, r, u),
            FrictionSolverKind::Prox => self.prox(prob, params, k, r, u),
            FrictionSolverKind::Nsn => newton(self, NewtonMode::Plain, params, r, u),
            FrictionSolverKind::Newton => newton(self, NewtonMode::Proximal, params, r, u),
            FrictionSolverKind::Auto => {
                let first = if self.one_step {
                    AUTO_NSGS_ONE_STEP
                } else {
                    AUTO_NSGS_STEP
                };
                // the proximal Newton restarts from the caller's start: from NSGS's
                // iterate it spent 2 180 iterations on Capsules-i125-1213 against 13
                self.start[..k].copy_from_slice(&r[..k]);
                self.give_up_early = self.one_step;
                let mut info = nsgs(self, first.min(params.max_iterations), r, u);
                self.give_up_early = false;
                let mut spent = info.iterations;
                // the stages share the cap: none starts once it is spent
                let left = |spent: usize| FrictionParams {
                    max_iterations: params.max_iterations.saturating_sub(spent),
                    ..*params
                };
                if info.converged || spent >= params.max_iterations {
                    return Ok(self.counted(info, params.tol));
                }
                let newton_fits =
                    self.one_step || self.newton.as_ref().is_some_and(|nw| nw.capacity() >= k);
                if !newton_fits {
                    // the step loop beyond the Newton workspace: PROX
                    let mut next = self.prox(prob, &left(spent), k, r, u);
                    next.iterations += spent;
                    return Ok(self.counted(next, params.tol));
                }
                // a Newton stage of at most `cap` iterations; `iterations` counts every stage
                let stage = |s: &mut Self,
                             mode,
                             cap: usize,
                             spent: &mut usize,
                             r: &mut [f64],
                             u: &mut [f64]| {
                    let p = FrictionParams {
                        max_iterations: left(*spent).max_iterations.min(cap),
                        ..*params
                    };
                    let mut next = newton(s, mode, &p, r, u);
                    *spent += next.iterations;
                    next.iterations = *spent;
                    next
                };
                if self.one_step {
                    // one-step problems: the proximal Newton from the caller's start for a
                    // few iterations first (AUTO_NEWTON_FIRST), the plain method after it
                    // from NSGS's iterate only where that did not finish
                    self.rprev[..k].copy_from_slice(&r[..k]);
                    r[..k].copy_from_slice(&self.start[..k]);
                    let next = stage(
                        self,
                        NewtonMode::Proximal,
                        AUTO_NEWTON_FIRST,
                        &mut spent,
                        r,
                        u,
                    );
                    if next.converged || spent >= params.max_iterations {
                        return Ok(self.counted(next, params.tol));
                    }
                    r[..k].copy_from_slice(&self.rprev[..k]);
                }
                info = stage(self, NewtonMode::Plain, AUTO_NSN, &mut spent, r, u);
                if !info.converged && spent < params.max_iterations {
                    // the plain method's iterate, in PROX's scratch (PROX does not run here)
                    let res0 = info.residual;
                    self.rprev[..k].copy_from_slice(&r[..k]);
                    r[..k].copy_from_slice(&self.start[..k]);
                    let mut next = newton(self, NewtonMode::Proximal, &left(spent), r, u);
                    next.iterations += spent;
                    if next.residual.is_nan() || next.residual > res0 {
                        // the plain method's iterate was the better one: keep it
                        r[..k].copy_from_slice(&self.rprev[..k]);
                        u[..k].copy_from_slice(&prob.q[..k]);
                        prob.w.mul_add(1.0, &r[..k], &mut u[..k]);
                        next.residual = res0;
                        next.solver = FrictionSolverKind::Nsn;
                    }
                    info = next;
                }
                info
            }
        };
        Ok(self.counted(info, params.tol))
    }

    /// `info` with the local solves' inconsistency count of this solve and the
    /// tolerance it stopped on.
    fn counted(&self, info: FrictionInfo, tolerance: f64) -> FrictionInfo {
        FrictionInfo {
            inconsistent_local_solves: self.inconsistent,
            tolerance,
            ..info
        }
    }

    /// Proximal point: NSGS on `(W + σI, q − σ r_j)`, σ shrinking while the outer
    /// iterates converge.
    fn prox<W: DelassusOperator + ?Sized>(
        &mut self,
        prob: FrictionProblem<'_, W>,
        params: &FrictionParams,
        k: usize,
        r: &mut [f64],
        u: &mut [f64],
    ) -> FrictionInfo {
        let wmax = prob
            .blocks
            .iter()
            .flat_map(|b| (0..b.dim).map(move |i| b.offset + i))
            .map(|i| prob.w.entry(i, i).abs())
            .fold(0.0, f64::max)
            .max(f64::MIN_POSITIVE);
        let mut sigma = wmax;
        let mut total = 0;
        let mut outer = 0;
        let mut res = self.full_residual_of(&prob, r, u, params.tol);
        while res > params.tol && total < params.max_iterations {
            outer += 1;
            self.rprev[..k].copy_from_slice(&r[..k]);
            for i in 0..k {
                self.qreg[i] = prob.q[i] - sigma * r[i];
            }
            // inner tolerance: two orders below the current outer residual
            let inner_tol = (1e-2 * res).max(0.1 * params.tol);
            let budget = params.max_iterations - total;
            let (it, _) = self.nsgs_reg(prob, sigma, (inner_tol, budget), params, r, u);
            // an outer iteration counts at least one: an inner solve that finds its
            // problem already solved must not let the loop run uncounted (the cap
            // bounds the outer iterations too)
            total += it.max(1);
            res = self.full_residual_of(&prob, r, u, params.tol);
            let step: f64 = (0..k)
                .map(|i| (r[i] - self.rprev[i]).powi(2))
                .sum::<f64>()
                .sqrt();
            // the closer the iterates, the smaller σ can be without hurting NSGS
            if step <= 0.5 * norm(&r[..k]).max(f64::MIN_POSITIVE) {
                sigma = (sigma * 0.5).max(1e-8 * wmax);
            }
        }
        FrictionInfo {
            iterations: total,
            residual: res,
            prox_iterations: outer,
            converged: res <= params.tol,
            solver: FrictionSolverKind::Prox,
            ..FrictionInfo::default()
        }
    }

    /// NSGS on `(W + σI, qreg)` where `qreg` is already in `self.qreg`, to `tol` within
    /// `cap` sweeps (local solves as `params` says); returns the sweeps and the residual of
    /// the regularized problem.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn nsgs_reg<W: DelassusOperator + ?Sized>(
        &mut self,
        prob: FrictionProblem<'_, W>,
        sigma: f64,
        (tol, cap): (f64, usize),
        params: &FrictionParams,
        r: &mut [f64],
        u: &mut [f64],
    ) -> (usize, f64) {
        let k = prob.blocks.last().map_or(0, |b| b.offset + b.dim);
        let qreg = std::mem::take(&mut self.qreg);
        let p = FrictionProblem {
            w: prob.w,
            q: &qreg[..k],
            blocks: prob.blocks,
        };
        let out = self.nsgs(p, sigma, (tol, cap.max(1)), params, r, u);
        self.qreg = qreg;
        out
    }

    /// NSGS sweeps on `(W + σI, q)` to `tol` within `cap` sweeps (`params` gives the local
    /// solves' cap); returns the sweeps done and the residual.
    fn nsgs<W: DelassusOperator + ?Sized>(
        &mut self,
        prob: FrictionProblem<'_, W>,
        sigma: f64,
        (tol, cap): (f64, usize),
        params: &FrictionParams,
        r: &mut [f64],
        u: &mut [f64],
    ) -> (usize, f64) {
        let k = prob.blocks.last().map_or(0, |b| b.offset + b.dim);
        // u = (W + σI) r + q
        u[..k].copy_from_slice(&prob.q[..k]);
        prob.w.mul_add(1.0, &r[..k], &mut u[..k]);
        for i in 0..k {
            u[i] += sigma * r[i];
        }
        let mut res = self.residual_of(prob.blocks, prob.q, r, u, tol);
        if res <= tol {
            return (0, res);
        }
        let mut sweeps = 0;
        // residual and sweep of the reference point of the rate estimate
        let (mut ref_res, mut ref_sweep) = (f64::NAN, 0usize);
        while sweeps < cap {
            if self.give_up_early && sweeps >= 20 && sweeps - ref_sweep >= 10 {
                // `auto`'s first stage: leave when the rate since the reference point
                // cannot reach the tolerance within the budget (NSGS converges linearly;
                // on the slider–crank it needed 367 sweeps where Newton needs 1)
                let rate = (res / ref_res).powf(1.0 / (sweeps - ref_sweep) as f64);
                let needed = if rate < 1.0 {
                    (tol / res).ln() / rate.ln()
                } else {
                    f64::INFINITY
                };
                if needed > (cap - sweeps) as f64 {
                    break;
                }
            }
            if sweeps == 10 || (sweeps > 10 && sweeps - ref_sweep >= 20) {
                (ref_res, ref_sweep) = (res, sweeps);
            }
            sweeps += 1;
            for b in prob.blocks {
                let (o, d) = (b.offset, b.dim);
                let mut wl = self.diag[o];
                for i in 0..d {
                    wl[3 * i + i] += sigma;
                }
                // local constant term: u_α without the block's own contribution
                let mut ql = [0.0; 3];
                for i in 0..d {
                    let mut own = 0.0;
                    for j in 0..d {
                        own += wl[3 * i + j] * r[o + j];
                    }
                    ql[i] = u[o + i] - own;
                }
                let mut rl = [0.0; 3];
                rl[..d].copy_from_slice(&r[o..o + d]);
                if !solve_local(&wl, &ql, b.mu, d, params.local_max_iterations, &mut rl) {
                    self.inconsistent += 1;
                }
                let mut delta = [0.0; 3];
                let mut changed = false;
                for i in 0..d {
                    delta[i] = rl[i] - r[o + i];
                    changed |= delta[i] != 0.0;
                }
                if changed {
                    for j in 0..d {
                        if delta[j] != 0.0 {
                            prob.w
                                .column_add(o + j, delta[j], &mut self.col[..k], &mut u[..k]);
                            u[o + j] += sigma * delta[j];
                        }
                    }
                    r[o..o + d].copy_from_slice(&rl[..d]);
                }
            }
            res = match self.measure {
                Measure::Siconos => residual(prob.blocks, prob.q, r, u),
                Measure::Velocity => velocity_residual_diag(prob.blocks, &self.diag, prob.q, r, u),
            };
            if res <= tol {
                // confirm on u recomputed from scratch (the updates accumulate rounding)
                u[..k].copy_from_slice(&prob.q[..k]);
                prob.w.mul_add(1.0, &r[..k], &mut u[..k]);
                for i in 0..k {
                    u[i] += sigma * r[i];
                }
                res = self.residual_of(prob.blocks, prob.q, r, u, tol);
                if res <= tol {
                    break;
                }
            }
        }
        (sweeps, res)
    }
}

/// Solves one block exactly: `u = W r + q` (W is `d × d`, row-major in a 3×3 array)
/// with `C* ∋ û ⊥ r ∈ C`. `r` holds the warm start (used by the 3-D Newton). Returns
/// false when no case of the 2-D law is consistent (`W_αα` not positive definite, or
/// round-off on a sign): `r` is then the least inconsistent case, and the caller counts
/// it ([`FrictionInfo::inconsistent_local_solves`]).
pub fn solve_local(
    w: &[f64; 9],
    q: &[f64; 3],
    mu: f64,
    d: usize,
    max_it: usize,
    r: &mut [f64; 3],
) -> bool {
    match d {
        1 => {
            r[0] = if q[0] >= 0.0 || w[0] <= 0.0 {
                0.0
            } else {
                -q[0] / w[0]
            };
            true
        }
        2 => solve_local_2d(w, q, mu, r),
        _ => {
            solve_local_3d(w, q, mu, max_it, r);
            true
        }
    }
}

/// The 2-D law in closed form: the first consistent case of open, stick, slip with
/// `u_T > 0` (`r_T = −μ r_N`), slip with `u_T < 0` (`r_T = μ r_N`).
fn solve_local_2d(w: &[f64; 9], q: &[f64; 3], mu: f64, r: &mut [f64; 3]) -> bool {
    let (wnn, wnt, wtn, wtt) = (w[0], w[1], w[3], w[4]);
    let (qn, qt) = (q[0], q[1]);
    r[2] = 0.0;
    if qn >= 0.0 {
        r[0] = 0.0;
        r[1] = 0.0;
        return true;
    }
    // stick: W r = −q
    let det = wnn * wtt - wnt * wtn;
    if det > 0.0 {
        let rn = (-qn * wtt + qt * wnt) / det;
        let rt = (-qt * wnn + qn * wtn) / det;
        if rn >= 0.0 && rt.abs() <= mu * rn {
            r[0] = rn;
            r[1] = rt;
            return true;
        }
    }
    // slip: r_T = −s μ r_N with s = sign(u_T)
    let mut best = (f64::INFINITY, 0.0, 0.0);
    for s in [1.0, -1.0] {
        let den = wnn - s * mu * wnt;
        if den <= 0.0 {
            continue;
        }
        let rn = -qn / den;
        let rt = -s * mu * rn;
        let ut = wtn * rn + wtt * rt + qt;
        if rn >= 0.0 && s * ut >= 0.0 {
            r[0] = rn;
            r[1] = rt;
            return true;
        }
        // keep the least inconsistent case (round-off on a sign)
        let viol = (-s * ut).max(0.0);
        if viol < best.0 {
            best = (viol, rn, rt);
        }
    }
    r[0] = best.1;
    r[1] = best.2;
    false
}

/// The Alart–Curnier function of a 3-D block and (optionally) one element of its
/// generalized Jacobian (row-major 3×3), with `ρ_N = 1/W_NN`, `ρ_T = 2/(W_T1T1 + W_T2T2)`.
fn alart_curnier(
    w: &[f64; 9],
    q: &[f64; 3],
    mu: f64,
    rho: (f64, f64),
    r: &[f64; 3],
    jac: Option<&mut [f64; 9]>,
) -> [f64; 3] {
    let mut u = [0.0; 3];
    for i in 0..3 {
        u[i] = q[i] + w[3 * i] * r[0] + w[3 * i + 1] * r[1] + w[3 * i + 2] * r[2];
    }
    let (rn_, rt_) = rho;
    let xn = r[0] - rn_ * u[0];
    let pn = xn.max(0.0);
    let xt = [r[1] - rt_ * u[1], r[2] - rt_ * u[2]];
    let nx = (xt[0] * xt[0] + xt[1] * xt[1]).sqrt();
    let rad = mu * pn;
    let inside = nx <= rad;
    let (pt0, pt1) = if inside {
        (xt[0], xt[1])
    } else {
        (rad * xt[0] / nx, rad * xt[1] / nx)
    };
    let phi = [r[0] - pn, r[1] - pt0, r[2] - pt1];
    if let Some(j) = jac {
        // dΦ_N
        if xn > 0.0 {
            for c in 0..3 {
                j[c] = rn_ * w[c];
            }
        } else {
            j[0] = 1.0;
            j[1] = 0.0;
            j[2] = 0.0;
        }
        // dx_T/dr = [0 I] − ρ_T W_T
        let mut dxt = [[0.0; 3]; 2];
        for a in 0..2 {
            for c in 0..3 {
                dxt[a][c] = -rt_ * w[3 * (a + 1) + c];
            }
            dxt[a][a + 1] += 1.0;
        }
        if inside {
            for a in 0..2 {
                for c in 0..3 {
                    j[3 * (a + 1) + c] = -dxt[a][c];
                }
                j[3 * (a + 1) + a + 1] += 1.0;
            }
        } else {
            // dR/dr = μ dp_N/dr
            let mut dr = [0.0; 3];
            if xn > 0.0 {
                for c in 0..3 {
                    dr[c] = -mu * rn_ * w[c];
                }
                dr[0] += mu;
            }
            let xh = [xt[0] / nx, xt[1] / nx];
            let f = rad / nx;
            for a in 0..2 {
                for c in 0..3 {
                    let mut proj = 0.0;
                    for b in 0..2 {
                        let pab = if a == b { 1.0 } else { 0.0 } - xh[a] * xh[b];
                        proj += pab * dxt[b][c];
                    }
                    j[3 * (a + 1) + c] = -xh[a] * dr[c] - f * proj;
                }
                j[3 * (a + 1) + a + 1] += 1.0;
            }
        }
    }
    phi
}

/// Semismooth Newton on Alart–Curnier with an Armijo line search on `½‖Φ‖²`, then
/// the projected fixed point if Newton did not reach round-off.
fn solve_local_3d(w: &[f64; 9], q: &[f64; 3], mu: f64, max_it: usize, r: &mut [f64; 3]) {
    if q[0] >= 0.0 {
        // û_N ≥ u_N = q_N ≥ 0 at r = 0: the block opens
        *r = [0.0; 3];
        return;
    }
    // stick, exactly: W r = −q with r inside the cone (u = 0, so û = 0). Tried first:
    // with a large μ every block sticks, and there the Alart–Curnier Newton, whose
    // residual weighs u_T by μ, stalled (μ = 1e3 and 1e6 failed the sliding block at
    // step 1 before this test).
    if let Some(s) = solve3(w, &[-q[0], -q[1], -q[2]])
        && s[0] > 0.0
        && (s[1] * s[1] + s[2] * s[2]).sqrt() <= mu * s[0]
    {
        *r = s;
        return;
    }
    let rho = (
        1.0 / w[0].max(f64::MIN_POSITIVE),
        2.0 / (w[4] + w[8]).max(f64::MIN_POSITIVE),
    );
    let scale = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt() * rho.0.max(rho.1);
    let target = 1e-15 * scale.max(f64::MIN_POSITIVE);
    let mut jac = [0.0; 9];
    let mut phi = alart_curnier(w, q, mu, rho, r, Some(&mut jac));
    let mut f = 0.5 * (phi[0] * phi[0] + phi[1] * phi[1] + phi[2] * phi[2]);
    for _ in 0..max_it {
        if f.sqrt() <= target {
            return;
        }
        let Some(dx) = solve3(&jac, &[-phi[0], -phi[1], -phi[2]]) else {
            break;
        };
        let mut t = 1.0;
        let mut accepted = false;
        for _ in 0..30 {
            let trial = [r[0] + t * dx[0], r[1] + t * dx[1], r[2] + t * dx[2]];
            let p = alart_curnier(w, q, mu, rho, &trial, None);
            let ft = 0.5 * (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
            if ft <= (1.0 - 1e-4 * t) * f {
                *r = trial;
                accepted = true;
                break;
            }
            t *= 0.5;
        }
        if !accepted {
            break;
        }
        phi = alart_curnier(w, q, mu, rho, r, Some(&mut jac));
        f = 0.5 * (phi[0] * phi[0] + phi[1] * phi[1] + phi[2] * phi[2]);
    }
    if f.sqrt() <= target {
        return;
    }
    // fallback: r ← P_C(r − ρ û), ρ = 1/λmax estimate (the largest Gershgorin bound)
    let lam = (0..3)
        .map(|i| (0..3).map(|j| w[3 * i + j].abs()).sum::<f64>())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let rho = 1.0 / lam;
    for _ in 0..20 * max_it {
        let mut u = [0.0; 3];
        for i in 0..3 {
            u[i] = q[i] + w[3 * i] * r[0] + w[3 * i + 1] * r[1] + w[3 * i + 2] * r[2];
        }
        let ut = (u[1] * u[1] + u[2] * u[2]).sqrt();
        let mut x = [
            r[0] - rho * (u[0] + mu * ut),
            r[1] - rho * u[1],
            r[2] - rho * u[2],
        ];
        project_on_cone(&mut x, mu);
        let step = ((x[0] - r[0]).powi(2) + (x[1] - r[1]).powi(2) + (x[2] - r[2]).powi(2)).sqrt();
        *r = x;
        if step <= 1e-16 * (r[0].abs() + r[1].abs() + r[2].abs()).max(f64::MIN_POSITIVE) {
            break;
        }
    }
}

/// Solves the 3×3 system `a x = b` (row-major) by Gaussian elimination with partial
/// pivoting; `None` when singular. Ours rather than nalgebra's fixed-size LU (tried, issue
/// 16 §7): the same algorithm with other roundings, which moved the NSGS iterate that
/// `auto`'s plain Newton stage continues from, and on spheres-in-a-box that Newton then
/// took 1 089 iterations and 2.2 s instead of 125 and 0.40 s (the plain Newton is that
/// sensitive to the last bits of its start, as Siconos' NSN_AC is to those of `W`).
fn solve3(a: &[f64; 9], b: &[f64; 3]) -> Option<[f64; 3]> {
    let mut m = [
        [a[0], a[1], a[2], b[0]],
        [a[3], a[4], a[5], b[1]],
        [a[6], a[7], a[8], b[2]],
    ];
    let amax = a.iter().fold(0.0_f64, |s, x| s.max(x.abs()));
    for c in 0..3 {
        let p = (c..3)
            .max_by(|&i, &j| m[i][c].abs().total_cmp(&m[j][c].abs()))
            .expect("rows");
        if m[p][c].abs() <= 1e-14 * amax {
            return None;
        }
        m.swap(c, p);
        for i in c + 1..3 {
            let f = m[i][c] / m[c][c];
            for j in c..4 {
                m[i][j] -= f * m[c][j];
            }
        }
    }
    let mut x = [0.0; 3];
    for i in (0..3).rev() {
        let mut s = m[i][3];
        for j in i + 1..3 {
            s -= m[i][j] * x[j];
        }
        x[i] = s / m[i][i];
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solvers::operator::DenseOperator;

    /// Issue 16 §6: the local solvers report what they cannot solve. An indefinite 2-D
    /// block `W = [[1, 2], [2, 1]]`, `q = (−1, 0.5)`, μ = 0.5 has no consistent case
    /// (stick needs det W > 0; slip one way has a zero pivot, the other a tangential
    /// velocity of the wrong sign): the solve counts it. A block with `W_NN = 0` is
    /// refused before any sweep.
    #[test]
    fn inconsistent_and_non_positive_blocks_are_reported() {
        let params = FrictionParams {
            solver: FrictionSolverKind::Nsgs,
            max_iterations: 3,
            ..FrictionParams::default()
        };
        let blocks = [Block {
            offset: 0,
            dim: 2,
            mu: 0.5,
        }];
        let solve = |w: &[f64; 4]| {
            let op = DenseOperator::new(2, w);
            let (mut r, mut u) = ([0.0; 2], [0.0; 2]);
            FrictionSolver::with_capacity(2).solve(
                FrictionProblem {
                    w: &op,
                    q: &[-1.0, 0.5],
                    blocks: &blocks,
                },
                &params,
                &mut r,
                &mut u,
            )
        };
        let info = solve(&[1.0, 2.0, 2.0, 1.0]).unwrap();
        assert!(info.inconsistent_local_solves > 0, "{info:?}");
        let err = solve(&[0.0, 0.0, 0.0, 1.0]).unwrap_err();
        assert!(
            matches!(err, SolveError::NonPositiveDiagonal { row: 0, .. }),
            "{err}"
        );
    }

    /// A single 3-D contact pressed with a tangential load below the cone sticks, above
    /// it slides with `‖r_T‖ = μ r_N` and `r_T` against `u_T`.
    #[test]
    fn one_contact_stick_and_slip() {
        let w = [2.0, 0.1, 0.0, 0.1, 1.5, 0.2, 0.0, 0.2, 1.0];
        let op = DenseOperator::new(3, &w);
        let blocks = [Block {
            offset: 0,
            dim: 3,
            mu: 0.5,
        }];
        let mut s = FrictionSolver::with_capacity(3);
        for (qt, sticks) in [(0.1, true), (2.0, false)] {
            let q = [-1.0, qt, 0.0];
            let (mut r, mut u) = ([0.0; 3], [0.0; 3]);
            let p = FrictionProblem {
                w: &op,
                q: &q,
                blocks: &blocks,
            };
            let info = s
                .solve(p, &FrictionParams::default(), &mut r, &mut u)
                .unwrap();
            assert!(info.residual <= 1e-12, "{info:?}");
            let rt = (r[1] * r[1] + r[2] * r[2]).sqrt();
            let ut = (u[1] * u[1] + u[2] * u[2]).sqrt();
            assert!(r[0] > 0.0 && u[0].abs() < 1e-12);
            if sticks {
                assert!(ut < 1e-12 && rt < 0.5 * r[0]);
            } else {
                assert!((rt - 0.5 * r[0]).abs() < 1e-12 && ut > 1e-3);
                assert!(r[1] * u[1] + r[2] * u[2] < 0.0);
            }
        }
    }
}
