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

pub mod local;
pub mod newton;
pub mod problem;
pub mod residuals;

pub use local::solve_local;
pub use problem::*;
pub use residuals::*;
pub(in crate::solvers) use residuals::{ac_map2, norm, velocity_residual_diag};

use serde::Serialize;

use super::SolveError;
use super::operator::DelassusOperator;
use newton::NewtonMode;

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
