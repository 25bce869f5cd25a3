//! Global semismooth Newton methods for one-step friction problems (eq. 11–15 in the
//! local form `u = W r + q`), on the Alart–Curnier function of every block at once:
//!
//! `Φ_N = r_N − max(0, r_N − ρ_N u_N)`,
//! `Φ_T = r_T − P_{B(μ p_N)}(r_T − ρ_T u_T)` with `p_N = max(0, r_N − ρ_N u_N)`,
//!
//! whose zeros are the solutions (Alart and Curnier 1991; Coulomb's law, not De Saxcé's
//! modified velocity, but the same solution set). An element of the generalized Jacobian
//! is `J = A + B (W + σI)` with `A`, `B` block diagonal (`ac_block`), so `J` has the
//! block pattern of `W`. Two methods share the loop:
//!
//! * [`NewtonMode::Plain`] (`nsn`): Newton on `Φ(r) = 0` with `ρ = 1/‖W_αα‖₂` per block,
//!   an Armijo line search on `½‖Φ‖²`, and the full step where the line search fails:
//!   the recipe of Siconos' NSN_AC, quadratic where `W` has full rank near the solution,
//!   and the fastest solver on FCLIB's finite-element and sphere problems (Acary,
//!   Brémond, Huber 2018). It can diverge on rank-deficient `W`: it stops at the first
//!   non-finite iterate and returns the best one it met.
//! * [`NewtonMode::Proximal`] (`newton`): the proximal-point method, Newton on the
//!   regularized problems `(W + σI, q − σ r_j)`, σ shrinking while the inner solves
//!   succeed and growing when they do not, with NSGS finishing a proximal step where
//!   Newton stalls (Siconos' PROX with its Newton inner solver). Robust on rigid stacks.
//!
//! `J` is stored dense (LU from faer, partial pivoting) when `W` is dense, and sparse
//! (faer's sparse LU, the symbolic analysis done once per solve) when at most a quarter
//! of `W`'s blocks are non-zero, as in every multibody problem where a contact couples
//! only with the contacts of its two bodies: on Siconos' 256-contact spheres-in-a-box
//! problem the sparse factorization is what makes an iteration cheap.
//!
//! One-step problems (`signorini fclib`) build the workspace per solve, sparse where `W`
//! is. The step loop's `auto` fallback uses a workspace sized once at set-up
//! (`NewtonWork`: dense `W` and `J`, the LU's scratch; contact spaces up to
//! [`STEP_NEWTON_ROWS`] rows), so a step does not allocate; `nsn` and `newton` by name
//! stay refused in scenes.

use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};

use super::super::operator::DelassusOperator;
use super::{Block, FrictionInfo, FrictionParams, FrictionProblem, FrictionSolver, norm};

mod jacobian;

pub(in crate::solvers) use jacobian::NewtonWork;

/// Which Newton method runs (module doc).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NewtonMode {
    /// Newton on `Φ(r) = 0` directly (Siconos' NSN_AC).
    Plain,
    /// Proximal point with Newton inside (Siconos' PROX).
    Proximal,
}

/// Blocks of `W` that are non-zero, at most this fraction, make `J` sparse. Measured on
/// the FCLIB files (`signorini fclib --solver newton`): at 0.22–0.24 (BoxesStack1,
/// local_problem_test, the LMGC90 polyhedra, 144–180 rows) the sparse LU's fill made an
/// iteration 1.5–2.5× dearer than the dense LU; at 0.006–0.036 (spheres, capsules, the
/// 2-D granular 00071, Box_Stacks, 178–1 068 rows) the sparse one was 3–4× cheaper.
const SPARSE_FRACTION: f64 = 0.1;
/// The plain method stops after this many iterations without a new best residual, or
/// when this many iterations did not divide the best residual by 10.
const STALL: usize = 60;
/// NSGS sweeps that finish a proximal step where Newton stalled (measured with the inner
/// tolerance then two orders below the outer residual: 1 000 made NSGS 90 % of the 9 766
/// iterations on BoxesStack1-i100000-32 and 0.25 s; 50 took 1 315 iterations and 0.21 s,
/// spheres-in-a-box 2.6 → 1.9 s, the others unchanged).
const NSGS_FINISH: usize = 50;
/// Largest contact space (rows) for which the step loop keeps a Newton workspace
/// (`auto`'s fallback there; above it `auto` falls back on PROX): two dense `k × k`
/// matrices, 16 MiB at 1024 rows, and an LU of `k³/3` flops per iteration.
pub const STEP_NEWTON_ROWS: usize = 1024;
/// Below this many rows the dense LU is always used.
const SPARSE_MIN_ROWS: usize = 64;

/// What the Newton loop on one (regularized) problem ended with.
struct Inner {
    iterations: usize,
    solved: bool,
    moved: bool,
}

/// Newton on `(W + σI, q)` from `r` until the regularized residual is at most `tol` or
/// `cap` iterations; `full_step` takes the Newton step where the line search fails.
#[allow(clippy::too_many_arguments)]
fn newton_loop<W: DelassusOperator + ?Sized>(
    solver: &FrictionSolver,
    nw: &mut NewtonWork,
    prob: &FrictionProblem<'_, W>,
    q: &[f64],
    sigma: f64,
    tol: f64,
    cap: usize,
    full_step: bool,
    r: &mut [f64],
) -> Inner {
    let mut bufs = std::mem::take(&mut nw.bufs);
    let out = newton_iterations(
        solver,
        nw,
        prob,
        q,
        (sigma, tol, cap, full_step),
        r,
        &mut bufs,
    );
    nw.bufs = bufs;
    out
}

/// The loop of [`newton_loop`], with its work vectors apart from `nw`.
fn newton_iterations<W: DelassusOperator + ?Sized>(
    solver: &FrictionSolver,
    nw: &mut NewtonWork,
    prob: &FrictionProblem<'_, W>,
    q: &[f64],
    (sigma, tol, cap, full_step): (f64, f64, usize, bool),
    r: &mut [f64],
    bufs: &mut Buffers,
) -> Inner {
    let k = nw.k;
    let blocks = prob.blocks;
    let mut out = Inner {
        iterations: 0,
        solved: false,
        moved: false,
    };
    while out.iterations < cap {
        let f = nw.eval(prob, q, sigma, r, &mut bufs.u, &mut bufs.phi);
        if !f.is_finite() {
            break;
        }
        let res = solver.residual_of(blocks, q, &r[..k], &bufs.u[..k], tol);
        if sigma == 0.0 && res < bufs.best_res {
            // the unregularized problem: keep the best iterate (the full steps of the
            // plain method may climb), stop after STALL iterations without a new best
            bufs.best_res = res;
            bufs.best[..k].copy_from_slice(&r[..k]);
            bufs.since_best = 0;
        } else if sigma == 0.0 {
            bufs.since_best += 1;
            if bufs.since_best >= STALL {
                break;
            }
        }
        if sigma == 0.0 && out.iterations.is_multiple_of(STALL) {
            // and after STALL iterations that did not gain a factor 10
            if out.iterations > 0 && bufs.best_res > 0.1 * bufs.checkpoint {
                break;
            }
            bufs.checkpoint = bufs.best_res;
        }
        if f == 0.0 || res <= tol {
            out.solved = true;
            break;
        }
        out.iterations += 1;
        for i in 0..k {
            bufs.dir[i] = -bufs.phi[i];
        }
        if !nw.solve(blocks, sigma, &mut bufs.dir) {
            break;
        }
        let mut t = 1.0;
        let mut accepted = false;
        for _ in 0..40 {
            for i in 0..k {
                bufs.trial[i] = r[i] + t * bufs.dir[i];
            }
            let ft = nw.eval(prob, q, sigma, &bufs.trial, &mut bufs.ut, &mut bufs.phi);
            if ft.is_finite() && ft <= (1.0 - 1e-4 * t) * f {
                accepted = true;
                break;
            }
            t *= 0.5;
        }
        if accepted {
            r[..k].copy_from_slice(&bufs.trial[..k]);
        } else if full_step {
            for i in 0..k {
                r[i] += bufs.dir[i];
            }
        } else {
            break;
        }
        out.moved = true;
        if r[..k].iter().any(|x| !x.is_finite()) {
            break;
        }
    }
    out
}

/// Work vectors of the Newton loop.
#[derive(Default)]
struct Buffers {
    best: Vec<f64>,
    best_res: f64,
    since_best: usize,
    checkpoint: f64,
    u: Vec<f64>,
    ut: Vec<f64>,
    phi: Vec<f64>,
    dir: Vec<f64>,
    trial: Vec<f64>,
}

impl Buffers {
    fn new(k: usize) -> Self {
        Buffers {
            best: vec![0.0; k],
            best_res: f64::INFINITY,
            since_best: 0,
            checkpoint: f64::INFINITY,
            u: vec![0.0; k],
            ut: vec![0.0; k],
            phi: vec![0.0; k],
            dir: vec![0.0; k],
            trial: vec![0.0; k],
        }
    }

    /// Forgets the best iterate of an earlier solve.
    fn reset(&mut self) {
        self.best_res = f64::INFINITY;
        self.since_best = 0;
        self.checkpoint = f64::INFINITY;
    }
}

impl FrictionSolver {
    /// The step loop's Newton workspace, for contact spaces of up to `capacity` rows
    /// (`None` above [`STEP_NEWTON_ROWS`]).
    pub(super) fn step_newton_work(capacity: usize) -> Option<Box<NewtonWork>> {
        (capacity > 0 && capacity <= STEP_NEWTON_ROWS)
            .then(|| Box::new(NewtonWork::with_capacity(capacity, true)))
    }

    /// The global Newton methods (module doc); `r` holds the start and gets the best
    /// iterate met (by residual), `u` its `W r + q`. `sparse` in the result tells which
    /// storage `J` had. The step loop's solver uses its own workspace (dense `J`, no
    /// allocation; the caller checks that `k` fits); one-step solvers build one.
    pub(super) fn global_newton<W: DelassusOperator + ?Sized>(
        &mut self,
        prob: FrictionProblem<'_, W>,
        params: &FrictionParams,
        mode: NewtonMode,
        k: usize,
        r: &mut [f64],
        u: &mut [f64],
    ) -> (FrictionInfo, bool) {
        let mut nw = match self.newton.take() {
            Some(nw) if nw.capacity() >= k => nw,
            _ => Box::new(NewtonWork::with_capacity(k, false)),
        };
        nw.load(&prob, k, mode, self.one_step);
        let out = self.newton_with(&mut nw, prob, params, mode, k, r, u);
        if !self.one_step {
            self.newton = Some(nw);
        }
        out
    }

    #[allow(clippy::too_many_arguments)]
    fn newton_with<W: DelassusOperator + ?Sized>(
        &mut self,
        nw: &mut NewtonWork,
        prob: FrictionProblem<'_, W>,
        params: &FrictionParams,
        mode: NewtonMode,
        k: usize,
        r: &mut [f64],
        u: &mut [f64],
    ) -> (FrictionInfo, bool) {
        let mut best = std::mem::take(&mut nw.best);
        best[..k].copy_from_slice(&r[..k]);
        let mut res = self.full_residual_of(&prob, r, u, params.tol);
        let mut best_res = if res.is_finite() { res } else { f64::INFINITY };
        let (mut iterations, mut outer) = (0usize, 0usize);
        match mode {
            NewtonMode::Plain => {
                // one Newton run to the tolerance, checked on the true residual
                let inner = newton_loop(
                    self,
                    nw,
                    &prob,
                    prob.q,
                    0.0,
                    params.tol,
                    params.max_iterations,
                    true,
                    r,
                );
                iterations = inner.iterations;
                if nw.bufs.best_res < best_res {
                    best_res = nw.bufs.best_res;
                    best[..k].copy_from_slice(&nw.bufs.best[..k]);
                }
                res = self.full_residual_of(&prob, r, u, params.tol);
                if res.is_finite() && res < best_res {
                    best[..k].copy_from_slice(&r[..k]);
                }
            }
            NewtonMode::Proximal => {
                let wmax = (0..k)
                    .map(|i| nw.wd[i + i * k].abs())
                    .fold(0.0, f64::max)
                    .max(f64::MIN_POSITIVE);
                // σ: small first (measured on the shared FCLIB files: 1e-4 of the largest
                // diagonal took 3–5 proximal iterations where 1e-2 took 5–9); ×0.1 after
                // a short proximal step, ×10 after an inner solve that did not reach its
                // tolerance (on spheres-in-a-box, shrinking σ regardless stalled at 1e-6)
                let mut sigma = 1e-4 * wmax;
                let mut qt = std::mem::take(&mut nw.qt);
                let mut center = std::mem::take(&mut nw.center);
                while res > params.tol && iterations < params.max_iterations {
                    outer += 1;
                    center[..k].copy_from_slice(&r[..k]);
                    for i in 0..k {
                        qt[i] = prob.q[i] - sigma * center[i];
                    }
                    // inner tolerance: one order below the outer residual (Siconos' PROX ratio;
                    // measured against two orders: BoxesStack1 1 313 → 39 Newton iterations,
                    // local_problem_test 43 → 10, Capsules-i100 80 → 36, the others equal
                    // within a few iterations)
                    let inner_tol = (0.1 * res).max(0.1 * params.tol);
                    let budget = (params.max_iterations - iterations).min(50);
                    let inner =
                        newton_loop(self, nw, &prob, &qt, sigma, inner_tol, budget, false, r);
                    iterations += inner.iterations;
                    let mut moved = inner.moved;
                    if !inner.solved {
                        // Newton stalled where ½‖Φ‖² does not decrease (a local minimum
                        // of the merit function; seen with μ > 1 in 2-D): finish this
                        // proximal step with NSGS on the same regularized problem, whose
                        // blocks are positive definite
                        if r[..k].iter().any(|x| !x.is_finite()) {
                            r[..k].copy_from_slice(&center[..k]);
                        }
                        self.qreg[..k].copy_from_slice(&qt[..k]);
                        let left = params.max_iterations.saturating_sub(iterations).max(1);
                        let (it, _) = self.nsgs_reg(
                            prob,
                            sigma,
                            (inner_tol, left.min(NSGS_FINISH)),
                            params,
                            r,
                            &mut nw.bufs.ut,
                        );
                        iterations += it;
                        moved = true;
                    }
                    res = self.full_residual_of(&prob, r, u, params.tol);
                    if res.is_finite() && res < best_res {
                        best_res = res;
                        best[..k].copy_from_slice(&r[..k]);
                    }
                    let step = (0..k)
                        .map(|i| (r[i] - center[i]).powi(2))
                        .sum::<f64>()
                        .sqrt();
                    if !moved || !inner.solved {
                        sigma = (sigma * 10.0).min(1e2 * wmax);
                    } else if step <= 0.5 * norm(&r[..k]).max(f64::MIN_POSITIVE) {
                        sigma = (sigma * 0.1).max(1e-12 * wmax);
                    }
                    if !res.is_finite() || outer > 10_000 {
                        break;
                    }
                }
                nw.qt = qt;
                nw.center = center;
            }
        }
        // the best iterate met
        r[..k].copy_from_slice(&best[..k]);
        nw.best = best;
        let res = self.full_residual_of(&prob, r, u, params.tol);
        (
            FrictionInfo {
                iterations,
                residual: res,
                prox_iterations: outer,
                converged: res <= params.tol,
                ..FrictionInfo::default()
            },
            nw.is_sparse(),
        )
    }
}
