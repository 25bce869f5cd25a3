//! The θ-method machinery shared by Moreau–Jean, Algorithm 1, Algorithm 2 and the
//! position-level trapezoidal rule.
//!
//! For `F(t, q, v) = f − C v − K q` the iteration matrix `M̂ = M + hθC + h²θ²K`
//! (eq. 47) is constant: it is formed and factored once. Each step computes the free
//! velocity (eq. 18 with `P = 0`)
//!
//! `M̂ (v_free − v_k) = h f(t_{k+θ}) − h C v_k − h K (q_k + hθ v_k)`,
//!
//! and every iterate of the decoupled Newton loop (eq. 56–58, with the sign erratum
//! of the module [`crate::integrators`]) is then
//!
//! `vⁿ⁺¹ = v_free + M̂⁻¹G Pⁿ⁺¹ − hθ M̂⁻¹K N G τⁿ`,
//! `qⁿ⁺¹ = q_k + h(1−θ)v_k + hθ vⁿ⁺¹ + N G τⁿ⁺¹`,
//!
//! with `N = I` (eq. 58) or `N = M̂⁻¹` (eq. 60). In contact space this needs only
//! `W = GᵀM̂⁻¹G`, `W_D = Gᵀ M̂⁻¹K N G` and `W_N = GᵀNG`, computed once when `G` is
//! constant (DESIGN.md §4): the velocity LCP (eq. 57) is
//! `U + eU_k = W_AA P_A + (U_free − hθ W_D τⁿ + e U_k)_A`, the linearized gaps
//! (eq. 51) are `g = g(qⁿ) + Gᵀ(q_k + h(1−θ)v_k − qⁿ) + hθ U + W_N τ`, and `v, q` are
//! formed once per step. For nonlinear contacts `G(qⁿ)` and the operators are
//! recomputed every Newton iteration (`m` extra solves, or none on the condensed contact
//! zone, where `W = BᵀFB`). Contacts being nodal, `G` and `g` depend on the zone's dofs
//! alone, and on a linear structure the zone rows of the iterate are
//! `v_z = v_free,z + F B Pⁿ⁺¹ − hθ F_E B τⁿ`, `q_z = … + (N G τⁿ⁺¹)_z`: when the zone keeps
//! only its flexibilities ([`crate::delassus::ZoneStorage::Flexibility`], where each
//! `n`-space correction is a sparse solve) the loop iterates on these `z` values alone,
//! converges on their change, and [`ThetaCore::commit`] forms `v`, `q` once. A round in
//! which no row is in any problem (Algorithm 2's first, free round) re-evaluates `g`
//! and `G` for the activation test without forming the operators, which it never reads.
//!
//! A nonlinear structure ([`crate::model::system::Linearity::ConstantMass`]: bodies with
//! a large-deformation law; [`crate::model::system::Linearity::Nonlinear`]: a mass
//! `M(q)`, the slider–crank) has no constant `M̂`: the structural side of the Newton loop
//! of eq. 41–48 ([`super::structure`]) evaluates `M(q_θ)`, `F`, `Kⁿ` and `Cⁿ` at each
//! iterate, refactors `M̂ⁿ` and gives the iteration's free velocity; `W` is condensed
//! again on each new `M̂ⁿ` and the contact problems above are solved unchanged. The projection's feedback
//! enters through `F(q_θ)` (whose `q` carries the last `τ`) instead of `−hθ W_D τⁿ`, the
//! coupled position solve is not taken, and the loop converges on eq. 41's residual.
//! A nonsymmetric `M̂ⁿ` (gyroscopic tangents) makes `W` nonsymmetric: the projection then
//! takes the Euclidean metric of eq. 58 (`N = M̂⁻¹` is no metric) and the LCPs Lemke's
//! method (block pivoting's Cholesky needs symmetry); the path names it.
//!
//! The operators live in [`Delassus`]: dense `n × m` blocks for the tens of contacts of
//! the bar and the academic examples, per-active-column storage (columns computed when
//! a contact first activates, corrections by one sparse solve) for thousands of
//! candidates (DESIGN.md §4). A one-step problem with more active rows than the dense
//! workspaces hold (`max_active_rows`) is solved matrix-free on products through the
//! factor ([`crate::solvers::global`]: MPRGP, or the accelerated projected gradient with
//! friction), the same laws to the friction tolerance.
//!
//! Contact space is the rows of the contact blocks ([`crate::contact`]): every
//! contact-space vector here (`U`, `P`, `τ`, the right-hand sides) has one entry per
//! row, normal row first in each block; gaps, forecasts and the position problem use
//! the normal rows only (eq. 56–60, 67–70 project the normal part). With friction the
//! velocity problem of an active set is the Coulomb problem of eq. 15 with Newton's law
//! on the normal part, `U + e U_k = W P + (U_free − hθ W_D τⁿ + e U_k)`,
//! `C* ∋ Û ⊥ P ∈ C`, solved by [`crate::solvers::friction`] (warm started from the
//! previous step's impulse); without friction (every block one row) it is the LCP of
//! before, operation for operation.
//!
//! Where the decoupled loop is not enough (issue 16 §1, measured on the undamped
//! elastic block sliding with friction, `tests/regression_alg2_friction_undamped.rs`):
//!
//! - *Slow contraction.* The decoupled iteration feeds `τⁿ` back through `−hθ W_D τⁿ`;
//!   on a mode of frequency ω it contracts by `(ωhθ)²/(1 + (ωhθ)²)` per iteration (metric
//!   `M̂⁻¹`), 0.74 for the block's highest modes at h = 1e-4, 0.97 at 5e-4. From the
//!   second iteration on, a step that has not converged solves the coupled problem of
//!   eq. 52–55 on the current contact states (`ThetaCore::coupled_correction`: impulses
//!   and projections together, dense LU, with active-set rounds on the signs) and takes
//!   its `τ` as the next iterate; the decoupled iteration after it checks every law.
//! - *Equality rows reconsidered.* An equality row (eq. 68, `P > 0`) dropped at selection
//!   because its gap was already 0 re-enters when its neighbours' projection moves it
//!   (before, such rows stayed off: 7e-8 m violations at h = 1e-5).
//! - *Tolerances that follow the friction solve.* The velocity accuracy of the friction
//!   solve (`solvers::friction::velocity_error`, m/s) sets a floor under the Newton
//!   tolerance (16 × accuracy / |U|) and a dead band `2hθ·accuracy` for the rows resting at g ≈ 0, which
//!   otherwise flip in and out of the position problem on the solver's last digits.
//! - *Stagnation.* A loop that gains less than 10 % in 5 iterations ends; it converged
//!   if it got within `√tol` (`StepStats::newton_stalls`), or, with a nonlinear `G`, if
//!   its last iterate moved `q` by at most `tol·|q|∞` (a body at rest on other bodies
//!   takes step increments at the solves' round-off, so the change relative to the
//!   increment never falls), else it is a cap.
//! - Rows that keep `g = 0` with `P = 0` and `τ < 0` because eq. 65 had no solution for
//!   the index set are counted in `StepStats::held_rows` (position problem below).

use super::problem::Problem;
use super::structure::Structure;
use super::{Forecast, NewtonParams, ProjectionRule, SchemeParams, State, StepStats};
use crate::assembly::linear_combination;
use crate::contact::{ContactJacobian, ContactSet, ContactStatus};
use crate::delassus::{Delassus, Op};
use crate::error::Error;
use crate::linalg::{LinearSolver, SolverKind, SparseMatrix, spmv_add, sym_spmv_add};
use crate::model::LinearSystem;
use crate::model::system::Linearity;
use crate::solvers::friction::{
    Block, FrictionParams, FrictionProblem, FrictionSolver, FrictionSolverKind,
};
use crate::solvers::global::GlobalSolver;
use crate::solvers::lcp::LcpSolver;
use crate::solvers::mlcp::Mlcp;
use crate::solvers::operator::{DelassusOperator, DenseOperator};
use crate::solvers::{SolveError, SolveInfo};

/// What the position step enforces (eq. 58 for Algorithm 1, eq. 68 for Algorithm 2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PositionRule {
    /// No position correction (Moreau–Jean).
    None,
    /// `0 ≤ g ⊥ τ ≥ 0` over every contact (Algorithm 1, eq. 28 and 58).
    AllComplementarity,
    /// Over the contacts of `pos_mask`: `g = 0` with free `τ` on the rows `rule` holds
    /// (none, those with `P > 0` as in eq. 68–70, or all), `0 ≤ g ⊥ τ ≥ 0` elsewhere.
    Combined {
        /// Which active rows are held at `g = 0`.
        rule: ProjectionRule,
    },
}

/// How the impulse `P` is determined.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VelocityLaw {
    /// Newton's impact law at velocity level on `vel_mask`:
    /// `0 ≤ U_{k+1} + e U_k ⊥ P ≥ 0` (eq. 18d, 57).
    Impact,
    /// Signorini's condition at position level on every contact:
    /// `0 ≤ g(q_{k+1}) ⊥ P ≥ 0` with `q_{k+1} = q_k + h v_{k+θ}` (the trapezoidal rule of
    /// sec. 6.2, Fig. 11 when θ = 1/2).
    PositionLevel,
}

/// Default cap on the rows of the dense one-step workspaces (4096² values = 128 MiB).
pub const DEFAULT_MAX_ACTIVE_ROWS: usize = 4096;

/// Active rows past which a one-step problem with a nonlinear `G` on the
/// per-active-column Delassus path is solved matrix-free: its columns would be re-solved
/// (two solves per row with the projection) at every linearization, where a matrix-free
/// solve takes a few tens of products (measured 21–25 per solve on the flat impact of
/// `tests/analytic_flat_impact.rs`); the same threshold as the dense re-forming of
/// [`crate::delassus::AUTO_DENSE_MAX_CONTACTS`].
pub const NONLINEAR_COLUMNS_MAX: usize = 64;

/// Active rows past which the θ-method core solves a one-step problem matrix-free: the
/// workspace rows `ws_cap`, or [`NONLINEAR_COLUMNS_MAX`] for a nonlinear `G` on the
/// per-active-column path (which would re-solve every stored column at each
/// linearization, where a matrix-free solve costs a few tens of products). Shared by
/// [`ThetaCore::new`] and the plan of `signorini check`.
pub(crate) fn matrix_free_rows(ws_cap: usize, g_constant: bool, dense: bool) -> usize {
    if !g_constant && !dense {
        NONLINEAR_COLUMNS_MAX.min(ws_cap)
    } else {
        ws_cap
    }
}

/// Dense sub-problem workspace: gathers a principal sub-block, solves, scatters. Sized
/// for `cap` rows (the active rows of a step), not for the candidates.
#[derive(Debug)]
pub(crate) struct Workspace {
    cap: usize,
    pub idx: Vec<usize>,
    sub: Vec<f64>,
    q: Vec<f64>,
    z: Vec<f64>,
    w: Vec<f64>,
    eq: Vec<bool>,
    member: Vec<bool>,
    res: Vec<f64>,
    pub lcp: LcpSolver,
    mlcp: Mlcp,
    /// Friction blocks of the gathered problem (offsets in the gathered rows).
    blocks: Vec<Block>,
    friction: FrictionSolver,
    /// The gathered rows exceed `cap`: the problem is recorded (`gq`, `gz`, `geq`) and
    /// solved matrix-free ([`crate::solvers::global`]) on products with `del`.
    over: bool,
    /// Rows past which a problem is solved matrix-free (`cap`, or fewer:
    /// [`Workspace::matrix_free_from`]).
    mf_from: usize,
    /// Operator and scale of the recorded problem.
    gop: (Op, f64),
    gq: Vec<f64>,
    gz: Vec<f64>,
    gw: Vec<f64>,
    geq: Vec<bool>,
    /// Full contact-space vectors for the restricted products.
    gx: Vec<f64>,
    gy: Vec<f64>,
    global: GlobalSolver,
    /// Tolerance and product cap of the matrix-free solves (the friction solver's).
    gtol: f64,
    gmax: usize,
}

/// The principal sub-block `scale · op[idx, idx]` of a Delassus operator, applied by
/// products with the whole operator ([`Delassus::mul_add`]: stored columns, or through
/// the factor): what the matrix-free solvers of [`crate::solvers::global`] see.
struct Restricted<'a> {
    del: std::cell::RefCell<&'a mut Delassus>,
    stiffness: &'a SparseMatrix,
    op: Op,
    scale: f64,
    idx: &'a [usize],
    x: std::cell::RefCell<&'a mut [f64]>,
    y: std::cell::RefCell<&'a mut [f64]>,
}

impl DelassusOperator for Restricted<'_> {
    fn size(&self) -> usize {
        self.idx.len()
    }
    /// One product per entry: for checks, never in the solvers' loops.
    fn entry(&self, i: usize, j: usize) -> f64 {
        let (mut xs, mut ys) = (self.x.borrow_mut(), self.y.borrow_mut());
        xs.iter_mut().for_each(|v| *v = 0.0);
        ys.iter_mut().for_each(|v| *v = 0.0);
        xs[self.idx[j]] = 1.0;
        self.del
            .borrow_mut()
            .mul_add(self.op, self.scale, &xs, &mut ys, self.stiffness);
        ys[self.idx[i]]
    }
    fn mul_add(&self, s: f64, x: &[f64], out: &mut [f64]) {
        let (mut xs, mut ys) = (self.x.borrow_mut(), self.y.borrow_mut());
        xs.iter_mut().for_each(|v| *v = 0.0);
        ys.iter_mut().for_each(|v| *v = 0.0);
        for (&i, &v) in self.idx.iter().zip(x) {
            xs[i] = v;
        }
        self.del
            .borrow_mut()
            .mul_add(self.op, s * self.scale, &xs, &mut ys, self.stiffness);
        for (o, &i) in out.iter_mut().zip(self.idx) {
            *o += ys[i];
        }
    }
}

impl Workspace {
    /// Buffers for `rows` contact rows and `contacts` contacts, dense blocks capped at
    /// `params.max_active_rows` rows (module doc); `friction` adds the friction solver.
    pub fn new(rows: usize, contacts: usize, params: &SchemeParams, friction: bool) -> Self {
        let cap = Self::cap(rows, params);
        Workspace {
            cap,
            idx: Vec::with_capacity(rows),
            sub: vec![0.0; cap * cap],
            q: vec![0.0; cap],
            z: vec![0.0; cap],
            w: vec![0.0; cap],
            eq: vec![false; cap],
            member: vec![false; rows],
            res: vec![0.0; rows],
            lcp: LcpSolver::new(params.lcp, cap),
            mlcp: Mlcp::with_capacity(cap),
            blocks: Vec::with_capacity(if friction { contacts } else { 0 }),
            friction: FrictionSolver::with_capacity(if friction { cap } else { 0 }),
            over: false,
            mf_from: cap,
            gop: (Op::W, 1.0),
            gq: vec![0.0; if rows > cap { rows } else { 0 }],
            gz: vec![0.0; if rows > cap { rows } else { 0 }],
            gw: vec![0.0; if rows > cap { rows } else { 0 }],
            geq: vec![false; if rows > cap { rows } else { 0 }],
            gx: vec![0.0; if rows > cap { rows } else { 0 }],
            gy: vec![0.0; if rows > cap { rows } else { 0 }],
            global: GlobalSolver::with_capacity(if rows > cap { rows } else { 0 }),
            gtol: params.friction.tol,
            gmax: params.friction.max_iterations,
        }
    }

    /// Rows of the dense blocks: `rows`, capped by `params.max_active_rows`.
    pub(crate) fn cap(rows: usize, params: &SchemeParams) -> usize {
        match params.max_active_rows {
            0 => rows.min(DEFAULT_MAX_ACTIVE_ROWS),
            c => rows.min(c),
        }
    }

    /// The matrix-free fallback, for the path line (empty when every row fits).
    pub fn describe(&self) -> String {
        if self.global.capacity() == 0 {
            return String::new();
        }
        format!(
            "; one-step problems of more than {} active rows solved matrix-free on products \
             W x = Gᵀ(M̂⁻¹(G x)) (MPRGP{})",
            self.mf_from,
            if self.friction.capacity() > 0 {
                ", friction by accelerated projected gradient with the fixed point on ‖u_T‖"
            } else {
                ""
            }
        )
    }

    /// True when the rows of `idx` exceed the dense workspaces (or the threshold of
    /// [`Workspace::matrix_free_from`]): the problem is then solved matrix-free, and its
    /// Delassus columns need not be stored.
    pub fn over_cap(&self) -> bool {
        self.idx.len() > self.mf_from
    }

    /// Solves the problems of more than `rows` active rows matrix-free (at set-up:
    /// sizes the matrix-free buffers for every row).
    fn matrix_free_from(&mut self, rows: usize, params: &SchemeParams) {
        let all = self.member.len();
        if rows >= self.mf_from || all <= rows {
            return;
        }
        self.mf_from = rows;
        if self.global.capacity() < all {
            self.gq = vec![0.0; all];
            self.gz = vec![0.0; all];
            self.gw = vec![0.0; all];
            self.geq = vec![false; all];
            self.gx = vec![0.0; all];
            self.gy = vec![0.0; all];
            self.global = GlobalSolver::with_capacity(all);
            self.gtol = params.friction.tol;
            self.gmax = params.friction.max_iterations;
        }
    }

    /// Gathers `op[idx, idx]` (scaled by `scale`), `rhs[idx]`, the warm start and the
    /// equality flags; the columns of `idx` must be available in `del`. Past the dense
    /// workspaces only `rhs`, the warm start and the flags are gathered (the matrix-free
    /// solve applies `op` by products).
    pub fn gather(
        &mut self,
        del: &Delassus,
        op: Op,
        scale: f64,
        rhs: &[f64],
        warm: &[f64],
        eq: impl Fn(usize) -> bool,
    ) -> Result<(), SolveError> {
        let k = self.idx.len();
        self.over = self.over_cap();
        if self.over {
            self.gop = (op, scale);
            for (b, &j) in self.idx.iter().enumerate() {
                self.gq[b] = rhs[j];
                self.gz[b] = warm[j];
                self.geq[b] = eq(j);
            }
            return Ok(());
        }
        for (b, &j) in self.idx.iter().enumerate() {
            for (a, &i) in self.idx.iter().enumerate() {
                self.sub[a + b * k] = scale * del.entry(op, i, j);
            }
            self.q[b] = rhs[j];
            self.z[b] = warm[j];
            self.eq[b] = eq(j);
        }
        Ok(())
    }

    /// The restricted operator of the recorded problem over `del`.
    fn restricted<'a>(
        del: &'a mut Delassus,
        stiffness: &'a SparseMatrix,
        (op, scale): (Op, f64),
        idx: &'a [usize],
        gx: &'a mut [f64],
        gy: &'a mut [f64],
    ) -> Restricted<'a> {
        Restricted {
            del: std::cell::RefCell::new(del),
            stiffness,
            op,
            scale,
            idx,
            x: std::cell::RefCell::new(gx),
            y: std::cell::RefCell::new(gy),
        }
    }

    /// Solves the gathered problem (an LCP when no row is an equality); past the dense
    /// workspaces by MPRGP on products with `del` (a cap or a residual above the
    /// tolerance is an error).
    pub fn solve(
        &mut self,
        del: &mut Delassus,
        stiffness: &SparseMatrix,
        stats: &mut StepStats,
    ) -> Result<SolveInfo, SolveError> {
        let k = self.idx.len();
        if self.over {
            let a = Self::restricted(
                del,
                stiffness,
                self.gop,
                &self.idx,
                &mut self.gx,
                &mut self.gy,
            );
            let info = self.global.solve_box(
                &a,
                &self.gq[..k],
                &self.geq[..k],
                &mut self.gz[..k],
                &mut self.gw[..k],
                self.gtol,
                self.gmax,
            );
            stats.global_solves += 1;
            stats.global_products += info.products;
            if !info.converged {
                return Err(SolveError::Cap {
                    cap: self.gmax,
                    residual: info.residual,
                });
            }
            return Ok(SolveInfo {
                iterations: info.products,
                residual: info.accuracy,
            });
        }
        if self.eq[..k].iter().any(|&e| e) {
            self.mlcp.solve(
                &self.sub[..k * k],
                k,
                &self.q[..k],
                &self.eq[..k],
                &mut self.lcp,
                &mut self.z[..k],
                &mut self.w[..k],
            )
        } else {
            self.lcp.solve(
                &self.sub[..k * k],
                k,
                &self.q[..k],
                &mut self.z[..k],
                &mut self.w[..k],
            )
        }
    }

    /// Solves the gathered rows as a Coulomb friction problem over `self.blocks`
    /// (warm start in `z`).
    fn solve_friction(
        &mut self,
        params: &FrictionParams,
        del: &mut Delassus,
        stiffness: &SparseMatrix,
        stats: &mut StepStats,
    ) -> Result<(crate::solvers::friction::FrictionInfo, f64), SolveError> {
        let k = self.idx.len();
        if self.over {
            let a = Self::restricted(
                del,
                stiffness,
                self.gop,
                &self.idx,
                &mut self.gx,
                &mut self.gy,
            );
            let info = self.global.solve_friction(
                &a,
                &self.gq[..k],
                &self.blocks,
                &mut self.gz[..k],
                &mut self.gw[..k],
                params.tol,
                params.max_iterations,
            );
            stats.global_solves += 1;
            stats.global_products += info.products;
            let fi = crate::solvers::friction::FrictionInfo {
                iterations: info.products,
                residual: info.residual,
                prox_iterations: info.outer,
                converged: info.converged,
                // not a fallback: counted in `StepStats::global_solves`
                solver: FrictionSolverKind::Nsgs,
                tolerance: params.tol,
                ..Default::default()
            };
            return Ok((fi, info.accuracy));
        }
        let op = DenseOperator::new(k, &self.sub[..k * k]);
        let prob = FrictionProblem {
            w: &op,
            q: &self.q[..k],
            blocks: &self.blocks,
        };
        let info = self
            .friction
            .solve(prob, params, &mut self.z[..k], &mut self.w[..k])?;
        let acc =
            crate::solvers::friction::velocity_error(&op, &self.blocks, &self.z[..k], &self.w[..k]);
        Ok((info, acc))
    }

    /// The growth step of `grow_solve` and of Algorithm 2's position problem: appends to
    /// `idx` every row of `candidates` not in it whose `w = rhs + scale·op·z` at the
    /// current solution `z` is violated: `w < −tol` for a complementarity row, `|w| > tol`
    /// (any `w ≠ 0` when `tol = 0`) for a row of `eq`; returns whether any was added.
    #[allow(clippy::too_many_arguments)]
    fn add_violated(
        &mut self,
        (del, stiffness): (&mut Delassus, &SparseMatrix),
        (op, scale): (Op, f64),
        rhs: &[f64],
        z: &[f64],
        tol: f64,
        candidates: impl Iterator<Item = usize>,
        eq: impl Fn(usize) -> bool,
    ) -> bool {
        self.member.iter_mut().for_each(|x| *x = false);
        for &a in &self.idx {
            self.member[a] = true;
        }
        self.res.copy_from_slice(rhs);
        del.mul_add(op, scale, z, &mut self.res, stiffness);
        let before = self.idx.len();
        for a in candidates {
            let r = self.res[a];
            let violated = if eq(a) {
                r.abs() > tol || (tol == 0.0 && r != 0.0)
            } else {
                r < -tol
            };
            if !self.member[a] && violated {
                self.idx.push(a);
            }
        }
        self.idx.len() > before
    }

    /// `out[idx] = z`, zero elsewhere.
    pub fn scatter(&self, out: &mut [f64]) {
        out.iter_mut().for_each(|x| *x = 0.0);
        let z = if self.over { &self.gz } else { &self.z };
        for (a, &i) in self.idx.iter().enumerate() {
            out[i] = z[a];
        }
    }
}

/// One unknown of the coupled position problem ([`ThetaCore::coupled_correction`]).
#[derive(Clone, Copy, Debug, Default)]
struct Unknown {
    /// Contact-space row of the unknown and of its equation.
    row: usize,
    /// Its contact.
    contact: usize,
    /// A τ of an equality row (`g = 0` whatever the sign of `τ`).
    equality: bool,
    /// A projection `τ` (position equation `g = 0`) rather than an impulse (velocity
    /// equation `U + eU_k = 0`).
    tau: bool,
    /// Slip: the impulse column is `e_N + μ Σ d_j e_{T_j}` (`P_T = μ P_N d` with the
    /// direction `d` of the current iterate); `slip_dim` tangents, 0 otherwise.
    slip_dim: usize,
    slip: [f64; 2],
}

/// Buffers of the coupled position problem, sized once for `cap` unknowns.
#[derive(Debug)]
struct Coupled {
    cap: usize,
    unknowns: Vec<Unknown>,
    cols: Vec<usize>,
    /// Per contact, impulse (even) and projection (odd) unknowns to drop.
    drop: Vec<bool>,
    mat: Vec<f64>,
    rhs: Vec<f64>,
    lu: crate::linalg::DenseLu,
}

impl Coupled {
    fn new(cap: usize, contacts: usize) -> Self {
        Coupled {
            cap,
            unknowns: Vec::with_capacity(cap),
            cols: Vec::with_capacity(cap * 2),
            drop: vec![false; 2 * contacts],
            mat: vec![0.0; cap * cap],
            rhs: vec![0.0; cap],
            lu: crate::linalg::DenseLu::with_capacity(cap),
        }
    }
}

/// Iterations without a 10 % gain in the Newton residual after which the loop counts
/// as stagnated ([`ThetaCore::newton`]).
const STALL: usize = 5;

/// Decoupled iterations after which a step that has not converged takes the coupled
/// position solve ([`ThetaCore::coupled_correction`]).
const COUPLED_AFTER: usize = 2;

/// Forms and factors `M + a·K + b·C` (the step matrix of a scheme), naming it `what` in
/// errors; the inputs were checked once by [`Problem::validate`].
pub(crate) fn factor_step_matrix(
    sys: &LinearSystem,
    (a, b): (f64, f64),
    what: &str,
) -> Result<Box<dyn LinearSolver>, Error> {
    let mut terms = vec![(1.0, &sys.mass), (a, &sys.stiffness)];
    if let Some(c) = &sys.damping {
        terms.push((b, c));
    }
    crate::linalg::solver::factor(
        linear_combination(&terms).as_ref(),
        what,
        SolverKind::Cholesky,
        sys.ordering.as_deref(),
    )
}

/// The [`Integrator`](super::Integrator) accessors of a scheme built on a `core:
/// ThetaCore` field.
macro_rules! delegate_to_core {
    () => {
        fn state(&self) -> &$crate::integrators::State {
            &self.core.state
        }
        fn state_finite(&self) -> Option<bool> {
            self.core.state_finite
        }
        fn system(&self) -> &$crate::model::LinearSystem {
            &self.core.sys
        }
        fn shared_system(&self) -> std::sync::Arc<$crate::model::LinearSystem> {
            self.core.sys.clone()
        }
        fn dt(&self) -> f64 {
            self.core.h
        }
        fn path(&self) -> String {
            self.core.path()
        }
        fn jacobian(&self) -> &$crate::contact::ContactJacobian {
            &self.core.del.jac
        }
        fn save(&self) -> $crate::integrators::saved::IntegratorState {
            self.core.state.save(self.name())
        }
        fn restore(
            &mut self,
            s: &$crate::integrators::saved::IntegratorState,
        ) -> Result<(), $crate::error::Error> {
            let name = self.name();
            self.core.restore(name, s)
        }
        fn prepare(&mut self) -> Result<(), $crate::error::Error> {
            self.core.update_contacts()
        }
    };
}
pub(crate) use delegate_to_core;

/// Shared θ-method data and buffers (see the module doc).
pub struct ThetaCore {
    /// The structure, shared (read-only after the build) with the history thread.
    pub(crate) sys: std::sync::Arc<LinearSystem>,
    pub(crate) contacts: Box<dyn ContactSet>,
    pub(crate) h: f64,
    pub(crate) theta: f64,
    pub(crate) n: usize,
    /// Contacts.
    pub(crate) m: usize,
    /// Rows of the contact space (`m` without friction).
    pub(crate) rows: usize,
    /// First row of each contact's block (`m + 1` values).
    pub(crate) off: Vec<usize>,
    /// Friction coefficient per contact.
    mu: Vec<f64>,
    /// Some contact has friction (blocks of more than one row).
    friction: bool,
    friction_params: FrictionParams,
    /// Row is a normal row.
    normal: Vec<bool>,
    /// `M̂` factored, `G` and the condensed operators.
    pub(crate) del: Delassus,
    /// Restitution per row (0 on tangential rows).
    pub(crate) e: Vec<f64>,
    with_projection: bool,
    feedback: bool,
    /// [`SchemeParams::energy_consistent_restitution`]: the restitution of a normal row
    /// separating at the step's start is at least `(1 − θ)/θ` (the first value); on
    /// every such row under Moreau–Jean (the second, true), on rows open in the last
    /// step under the projection schemes ([`ThetaCore::restitution`]).
    restitution_floor: Option<(f64, bool)>,
    /// `G` does not depend on `q` (every contact set is linear).
    pub(crate) g_constant: bool,
    /// [`ContactSet::coordinate_scale`], for the convergence measure's round-off floor.
    coordinate_scale: f64,
    /// `G` constant and the structure linear: `M̂`, `W` are condensed once and the
    /// Newton loop only re-solves the contact-space problem (eq. 56a).
    pub(crate) operators_constant: bool,
    /// A nonlinear structure's Newton data ([`super::structure`]); `None` when linear.
    structure: Option<Box<Structure>>,
    /// The structure is linearized at the step's first iterate (`v = v_k`, `τ = 0`):
    /// a Newton loop starting now needs no new evaluation.
    at_first_iterate: bool,
    /// The last Newton loop of the step converged: a later round of Algorithm 2 starts
    /// from its velocity ([`ThetaCore::restart_iterate`]).
    last_converged: bool,
    jac_at_qk: bool,
    /// The Delassus data were formed at `q_k` (the step's start) and not since: a round
    /// that re-evaluates `G` at `q_k` need not form them again.
    w_at_qk: bool,
    pub(crate) newton: NewtonParams,
    pub(crate) projection_tolerance: f64,
    pub(crate) state: State,
    /// `U = Gᵀ v` at the start of the step, all rows.
    u_rows: Vec<f64>,
    /// Scratch of the prescribed dofs' velocities and displacements.
    vp_a: Vec<f64>,
    vp_b: Vec<f64>,
    // n-vectors
    pub(crate) v_free: Vec<f64>,
    work: Vec<f64>,
    /// `K` as its three diagonals when it is a rod's ([`crate::linalg::TridiagonalRows`]): the free
    /// velocity's `K (q + hθ v)` without a gather per row.
    k_rows: Option<crate::linalg::TridiagonalRows>,
    /// `q_lin` holds `y = q + hθ v` of the state, written by [`ThetaCore::form_fused`]
    /// and read (once) by [`ThetaCore::begin_step`] instead of another pass.
    y_ready: bool,
    /// Whether the state's `q` and `v` are all finite, when [`ThetaCore::form_fused`]
    /// formed them ([`super::Integrator::state_finite`]).
    pub(crate) state_finite: Option<bool>,
    /// The structure's constant load is `+0.0` everywhere (the bar): `begin_step` reads
    /// it as the constant.
    unloaded: bool,
    q_lin: Vec<f64>,
    pub(crate) v_new: Vec<f64>,
    pub(crate) q_new: Vec<f64>,
    // per contact
    g_at_lin: Vec<f64>,
    // per row
    pub(crate) u_k: Vec<f64>,
    pub(crate) u_free: Vec<f64>,
    u_new: Vec<f64>,
    wp: Vec<f64>,
    wt: Vec<f64>,
    coupling: Vec<f64>,
    a: Vec<f64>,
    pub(crate) b: Vec<f64>,
    pub(crate) g_lin: Vec<f64>,
    pub(crate) p: Vec<f64>,
    p_warm: Vec<f64>,
    pub(crate) tau: Vec<f64>,
    tau_prev: Vec<f64>,
    tau_used: Vec<f64>,
    dtau: Vec<f64>,
    /// Contacts whose velocity-level impact law is enforced this round.
    pub(crate) vel_mask: Vec<bool>,
    /// Contacts projected this round (Algorithm 2).
    pub(crate) pos_mask: Vec<bool>,
    /// Rows projected with `g = 0` in this Newton loop (Algorithm 2: `P > 0` at some
    /// iterate). The set only grows within a loop, so the decoupled iteration cannot
    /// cycle between two equality sets (with friction, a lifting contact's `P_N`
    /// alternated between 0 and > 0 every iteration until the cap).
    eq_rows: Vec<bool>,
    pub(crate) ws: Workspace,
    /// The coupled position problem's buffers (projection with feedback only).
    coupled: Option<Coupled>,
    /// Velocity accuracy (m/s) of the friction solves of this Newton loop (the largest
    /// [`crate::solvers::friction::velocity_error`] met, so that the tolerances derived
    /// from it do not move between iterations); 0 without friction, where the LCP
    /// solves are exact to rounding.
    velocity_accuracy: f64,
    /// The contact zone's dofs when the Newton loop iterates on the zone alone
    /// ([`ThetaCore::form_zone`]: a linear structure, a nonlinear `G`, the zone keeping its
    /// flexibilities only, [`Delassus::flexibility_zone`]); empty otherwise.
    zone: Vec<usize>,
    /// Zone scratch (zone order): the velocity and position corrections, and `q` at the
    /// iterate, at the last iterate and at the step's start.
    zv: Vec<f64>,
    zq: Vec<f64>,
    zq_new: Vec<f64>,
    zq_lin: Vec<f64>,
    zq_k: Vec<f64>,
}

impl ThetaCore {
    /// Forms and factors `M̂`, evaluates the contacts at `q0` and condenses the
    /// Delassus operators. `with_projection` also prepares `W_D` and `W_N`.
    pub fn new(
        params: &SchemeParams,
        problem: Problem,
        h: f64,
        with_projection: bool,
    ) -> Result<Self, Error> {
        let Problem {
            system: sys,
            contacts,
            q0,
            v0,
        } = problem;
        let (q0, v0) = (&q0[..], &v0[..]);
        check_block_rows(params, contacts.as_ref())?;
        // A nonsymmetric M̂ⁿ (gyroscopic terms) makes W nonsymmetric: `N = M̂⁻¹` is then
        // no metric (eq. 59 needs N positive definite) and block pivoting's Cholesky
        // does not apply, so the projection takes eq. 58's Euclidean metric and the
        // LCPs Lemke's method (which needs no symmetry).
        let adjusted;
        let params = if !sys.symmetric() {
            adjusted = SchemeParams {
                metric: crate::delassus::Metric::Euclidean,
                lcp: match params.lcp {
                    p @ crate::solvers::LcpKind::Pgs { .. } => p,
                    _ => crate::solvers::LcpKind::Lemke,
                },
                ..*params
            };
            &adjusted
        } else {
            params
        };
        let theta = params.theta;
        let mut structure = (sys.linearity() != Linearity::Linear).then(|| {
            Box::new(Structure::new(
                &sys,
                params.newton.modified,
                params.energy_momentum,
            ))
        });
        let factor = match &mut structure {
            None => factor_step_matrix(
                &sys,
                (h * h * theta * theta, h * theta),
                "iteration matrix M + hθC + h²θ²K",
            )?,
            Some(st) => {
                // the pattern's symbolic analysis, on M̂ⁿ at the initial state (the mass
                // alone is singular where `mass = "redistributed"` leaves contact nodes
                // none, issue 34); the first step forms its own values
                st.evaluate(&sys, (h, theta), (q0, v0), (q0, v0), true)?;
                st.factor()?
            }
        };
        let n = sys.ndof();
        let np = sys.prescribed.as_ref().map_or(0, |p| p.dofs.len());
        let m = contacts.len();
        let jac = ContactJacobian::for_set(contacts.as_ref());
        let rows = jac.ncols();
        let mut off = Vec::with_capacity(m + 1);
        off.push(0);
        for a in 0..m {
            off.push(off[a] + contacts.dim(a));
        }
        assert_eq!(off[m], rows, "contact blocks and Jacobian columns disagree");
        let laws = contacts.laws();
        let mut e = vec![0.0; rows];
        let mut normal = vec![false; rows];
        for a in 0..m {
            e[off[a]] = laws[a].restitution;
            normal[off[a]] = true;
        }
        let mu: Vec<f64> = laws.iter().map(|l| l.friction).collect();
        let friction = rows > m;
        let tangent_dim = if friction {
            (0..m).map(|a| off[a + 1] - off[a] - 1).max().unwrap_or(0)
        } else {
            0
        };
        let g_constant = contacts.is_linear();
        let coordinate_scale = contacts.coordinate_scale();
        let operators_constant = g_constant && structure.is_none();
        let state = State::with_layout(q0, v0, m, tangent_dim, rows);
        let del = Delassus::new(
            factor,
            jac,
            n,
            (params.delassus, params.delassus_pool),
            with_projection,
            params.metric,
            operators_constant,
        );
        // the dense one-step workspaces (module doc of `Workspace`): the gathered block
        // and the MLCP's three, plus the coupled position problem's matrix
        // the coupled problem has at most the velocity rows plus one τ per contact,
        // capped like the dense workspaces (beyond, the decoupled loop runs alone)
        let ws_cap = Workspace::cap(rows, params);
        let mut del = del?;
        del.limit_columns(ws_cap);
        let coupled_cap =
            (with_projection && params.projection_feedback).then(|| (rows + m).min(ws_cap));
        let mut mem = crate::limits::MemoryEstimate::default();
        workspace_ledger(rows, m, params, (friction, with_projection), &mut mem);
        mem.check("scheme.max_active_rows", format!("{ws_cap} rows"))?;
        let k_rows = crate::linalg::TridiagonalRows::new(sys.stiffness.as_ref());
        let unloaded = crate::linalg::TridiagonalRows::is_positive_zero(&sys.force);
        let mut core = ThetaCore {
            sys: std::sync::Arc::new(sys),
            contacts,
            h,
            theta,
            n,
            m,
            rows,
            off,
            mu,
            friction,
            friction_params: params.friction,
            normal,
            del,
            e,
            with_projection,
            feedback: params.projection_feedback,
            restitution_floor: params
                .energy_consistent_restitution
                .then(|| ((1.0 - params.theta) / params.theta, !with_projection)),
            g_constant,
            coordinate_scale,
            operators_constant,
            structure,
            at_first_iterate: false,
            last_converged: false,
            jac_at_qk: true,
            w_at_qk: false,
            newton: params.newton,
            projection_tolerance: params.projection_tolerance,
            state,
            u_rows: vec![0.0; rows],
            vp_a: vec![0.0; np],
            vp_b: vec![0.0; np],
            v_free: vec![0.0; n],
            work: vec![0.0; n],
            k_rows,
            y_ready: false,
            state_finite: None,
            unloaded,
            q_lin: vec![0.0; n],
            v_new: vec![0.0; n],
            q_new: vec![0.0; n],
            g_at_lin: vec![0.0; m],
            u_k: vec![0.0; rows],
            u_free: vec![0.0; rows],
            u_new: vec![0.0; rows],
            wp: vec![0.0; rows],
            wt: vec![0.0; rows],
            coupling: vec![0.0; rows],
            a: vec![0.0; rows],
            b: vec![0.0; rows],
            g_lin: vec![0.0; rows],
            p: vec![0.0; rows],
            p_warm: vec![0.0; rows],
            tau: vec![0.0; rows],
            tau_prev: vec![0.0; rows],
            tau_used: vec![0.0; rows],
            dtau: vec![0.0; rows],
            vel_mask: vec![false; m],
            pos_mask: vec![false; m],
            eq_rows: vec![false; rows],
            ws: Workspace::new(rows, m, params, friction),
            coupled: coupled_cap.map(|c| Coupled::new(c, m)),
            velocity_accuracy: 0.0,
            zone: Vec::new(),
            zv: Vec::new(),
            zq: Vec::new(),
            zq_new: Vec::new(),
            zq_lin: Vec::new(),
            zq_k: Vec::new(),
        };
        core.contacts
            .evaluate(&core.state.q, &mut core.state.gap, &mut core.del.jac);
        if core.structure.is_none() {
            if !g_constant && core.contacts.condensed() {
                let zone = core.contacts.zone();
                let fixed = fixed_rows(core.contacts.as_ref());
                core.del
                    .condense_zone(&zone, fixed, &core.sys.stiffness, true);
                if let Some(dofs) = core.del.flexibility_zone() {
                    let z = dofs.len();
                    core.zone = dofs.to_vec();
                    for buf in [
                        &mut core.zv,
                        &mut core.zq,
                        &mut core.zq_new,
                        &mut core.zq_lin,
                        &mut core.zq_k,
                    ] {
                        *buf = vec![0.0; z];
                    }
                }
            }
            core.del.refresh(&core.sys.stiffness);
            core.w_at_qk = true;
            let rows_mf = matrix_free_rows(core.ws.cap, g_constant, core.del.is_dense());
            if rows_mf < core.ws.cap {
                core.ws.matrix_free_from(rows_mf, params);
                core.del.limit_columns(rows_mf);
                if let Some(cp) = core.coupled.as_mut() {
                    cp.cap = cp.cap.min(rows_mf);
                }
            }
        } else {
            // a nonlinear structure condenses with each step's first iteration matrix,
            // and carries the projection's feedback in F: W_D is never read
            core.del.without_wd();
        }
        core.del.jac.transpose_mul(&core.state.v, &mut core.u_rows);
        core.scatter_local_velocity();
        core.del.start_stepping();
        Ok(core)
    }

    /// A description of the linear-algebra path, for summaries.
    pub fn path(&self) -> String {
        let structure = match &self.structure {
            None => format!(
                "M̂ = M + hθC + h²θ²K factored once ({}, n = {})",
                self.del.factor.backend_name(),
                self.n
            ),
            Some(st) => format!(
                "nonlinear structure ({}): {} Newton on eq. 41–48{}, M̂ⁿ = M(q) + hθCⁿ + \
                 h²θ²Kⁿ refactored {} ({}, n = {}){}",
                self.sys
                    .nonlinear
                    .iter()
                    .map(|f| f.describe())
                    .collect::<Vec<_>>()
                    .join(", "),
                if st.modified { "modified" } else { "full" },
                if st.energy_momentum {
                    " with discrete-gradient internal forces (energy–momentum)"
                } else {
                    ""
                },
                if st.modified {
                    "at each step's first iterate and when the iterates stop contracting"
                } else {
                    "at every iterate"
                },
                self.del.factor.backend_name(),
                self.n,
                if st.symmetric {
                    ""
                } else {
                    "; M̂ⁿ nonsymmetric: projection metric Euclidean, LCPs by Lemke"
                }
            ),
        };
        format!(
            "{structure}; {} contact(s){}, {}; {}{}",
            self.m,
            if self.friction {
                format!(
                    " with Coulomb friction ({} rows; {} on the velocity problem)",
                    self.rows,
                    self.friction_params.solver.name()
                )
            } else {
                String::new()
            },
            if self.operators_constant {
                "linear gap: G and W constant (condensed once), one sparse solve per step; \
                 Newton iterations only re-solve the contact-space problem (eq. 56a)"
            } else if self.g_constant {
                "linear gap: G constant, W condensed again with each new M̂ⁿ"
            } else if !self.zone.is_empty() {
                "nonlinear gap: G(q) re-linearized every Newton iteration, which iterates on \
                 the contact zone's dofs (F B P, no sparse solve) and forms the state once"
            } else {
                "nonlinear gap: G(q) re-linearized every Newton iteration"
            },
            self.del.describe(),
            if self.with_projection {
                format!("; projection metric {}", self.del.metric().name())
            } else {
                String::new()
            }
        ) + &self.ws.describe()
    }

    /// Free velocity and the contact-space data at the start of a step (for a
    /// nonlinear structure, at its first Newton iterate: [`super::structure`]).
    pub fn begin_step(&mut self, stats: &mut StepStats) -> Result<(), Error> {
        self.update_contacts()?;
        if self.structure.is_some() {
            return self.begin_nonlinear_step(stats);
        }
        let (h, th) = (self.h, self.theta);
        let s = &self.state;
        // work = h f − h K (q + hθ v) − h C v; K and C are symmetric, so their CSC
        // arrays are their CSR arrays and each row is a gather.
        if !std::mem::take(&mut self.y_ready) {
            for ((ql, q), v) in self.q_lin.iter_mut().zip(&s.q).zip(&s.v) {
                *ql = q + h * th * v;
            }
        }
        if let Some(rows) = &self.k_rows {
            // the rods' K: the same sums without the gather (bit for bit)
            let f = (!self.unloaded).then_some(&self.sys.force[..]);
            rows.scaled_residual(h, f, &self.q_lin, &mut self.work);
        } else {
            let k = self.sys.stiffness.as_ref();
            let (kp, ki, kv) = (k.col_ptr(), k.row_idx(), k.val());
            for (i, (w, f)) in self.work.iter_mut().zip(&self.sys.force).enumerate() {
                let r = kp[i]..kp[i + 1];
                let kx: f64 = ki[r.clone()]
                    .iter()
                    .zip(&kv[r])
                    .map(|(&j, &a)| a * self.q_lin[j])
                    .sum();
                *w = h * (f - kx);
            }
        }
        add_step_loads(
            &self.sys,
            (s.time, h, th),
            (&mut self.vp_a, &mut self.vp_b),
            &mut self.work,
        );
        if let Some(c) = &self.sys.damping {
            sym_spmv_add(c.as_ref(), -h, &s.v, &mut self.work);
        }
        // v_free = v_k + M̂⁻¹ work (`work` is scratch afterwards)
        self.del
            .factor
            .solve_add(&mut self.work, &s.v, &mut self.v_free);
        self.u_k.copy_from_slice(&self.u_rows);
        self.del.jac.transpose_mul(&self.v_free, &mut self.u_free);
        self.del.next_epoch();
        // the linearization point is read only where the operators move (a copy of
        // the state: two passes over 8 MB per step at 10⁶ dofs, issue 35)
        if !self.operators_constant {
            self.q_lin.copy_from_slice(&self.state.q);
        }
        self.g_at_lin.copy_from_slice(&self.state.gap);
        Ok(())
    }

    /// [`ThetaCore::begin_step`] of a nonlinear structure: the step's loads, then the
    /// first Newton iterate.
    fn begin_nonlinear_step(&mut self, stats: &mut StepStats) -> Result<(), Error> {
        let (h, th) = (self.h, self.theta);
        let st = self.structure.as_mut().expect("a nonlinear structure");
        for (e, f) in st.ext.iter_mut().zip(&self.sys.force) {
            *e = h * f;
        }
        add_step_loads(
            &self.sys,
            (self.state.time, h, th),
            (&mut self.vp_a, &mut self.vp_b),
            &mut st.ext,
        );
        self.u_k.copy_from_slice(&self.u_rows);
        self.del.next_epoch();
        self.q_lin.copy_from_slice(&self.state.q);
        self.g_at_lin.copy_from_slice(&self.state.gap);
        self.first_iterate(stats)
    }

    /// Linearizes a nonlinear structure at the step's first iterate `v⁰ = v_k`, `τ⁰ = 0`
    /// (`q⁰ = q_k + h v_k`): factors `M̂⁰`, condenses `W` on it (`G` at `q_k`), and sets
    /// the free velocity.
    fn first_iterate(&mut self, stats: &mut StepStats) -> Result<(), Error> {
        let h = self.h;
        let s = &self.state;
        self.v_new.copy_from_slice(&s.v);
        for ((qn, q), v) in self.q_new.iter_mut().zip(&s.q).zip(&s.v) {
            *qn = q + h * v;
        }
        self.linearize_structure(true, stats)?;
        let st = self.structure.as_ref().expect("a nonlinear structure");
        self.del.refresh(&st.tangent);
        self.w_at_qk = false;
        self.del.jac.transpose_mul(&self.v_free, &mut self.u_free);
        self.at_first_iterate = true;
        Ok(())
    }

    /// Starts a later Newton loop of the step (an index-set round of Algorithm 2) from the
    /// velocity the last one converged to, with `τ = 0` (`q = q_k + h v_θ`), on the
    /// iteration matrix in hand: the same fixed point as from the first iterate, from a
    /// closer start and without a factorization (ball of `meshes/ball_crush.toml`, full
    /// Newton, Algorithm 2 at h = 1e-4: 3.32 → 2.56 factorizations per step, modified Newton
    /// 1.71 → 1.0).
    fn restart_iterate(&mut self, stats: &mut StepStats) -> Result<(), Error> {
        let (h, th) = (self.h, self.theta);
        let s = &self.state;
        for (((qn, q), v), vn) in self.q_new.iter_mut().zip(&s.q).zip(&s.v).zip(&self.v_new) {
            *qn = q + h * (th * vn + (1.0 - th) * v);
        }
        self.linearize_structure(false, stats)?;
        if !self.g_constant {
            // G was evaluated again at q_k for this loop
            let st = self.structure.as_ref().expect("a nonlinear structure");
            self.del.refresh(&st.tangent);
            self.w_at_qk = false;
        }
        self.del.jac.transpose_mul(&self.v_free, &mut self.u_free);
        Ok(())
    }

    /// Evaluates a nonlinear structure at the iterate `(q_new, v_new)`: with `tangent`
    /// refactors `M̂ⁿ`; sets `v_free = vⁿ + M̂ⁿ⁻¹(−M(vⁿ − v_k) + hF_θⁿ)` (eq. 45 without
    /// contact impulse). The caller refreshes the Delassus data.
    fn linearize_structure(&mut self, tangent: bool, stats: &mut StepStats) -> Result<(), Error> {
        let at_iterate = self.structure.as_ref().is_some_and(|st| st.rhs_at_iterate);
        if tangent || !at_iterate {
            self.evaluate_structure(tangent, stats)?;
        }
        let st = self.structure.as_mut().expect("a nonlinear structure");
        let s = &self.state;
        st.rhs_at_iterate = false;
        if tangent {
            let t0 = std::time::Instant::now();
            self.del
                .factor
                .refactor(st.step_matrix.as_ref(), super::structure::MATRIX_NAME)
                .map_err(|e| step_error(s, self.h, e))?;
            stats.factorizations += 1;
            stats.factorization_seconds += t0.elapsed().as_secs_f64();
        }
        self.work.copy_from_slice(&st.rhs);
        self.del.factor.solve_in_place(&mut self.work);
        for ((vf, v), w) in self.v_free.iter_mut().zip(&self.v_new).zip(&self.work) {
            *vf = v + w;
        }
        self.at_first_iterate = false;
        Ok(())
    }

    /// [`Structure::evaluate`] at the iterate `(q_new, v_new)` (with `tangent`, `Kⁿ` and
    /// `M̂ⁿ` too), timed into `stats`; an inverted cell is the run's error.
    fn evaluate_structure(&mut self, tangent: bool, stats: &mut StepStats) -> Result<(), Error> {
        let st = self.structure.as_mut().expect("a nonlinear structure");
        let s = &self.state;
        let t0 = std::time::Instant::now();
        st.evaluate(
            &self.sys,
            (self.h, self.theta),
            (&s.q, &s.v),
            (&self.q_new, &self.v_new),
            tangent,
        )
        .map_err(|e| step_error(s, self.h, e))?;
        stats.assembly_seconds += t0.elapsed().as_secs_f64();
        Ok(())
    }

    /// The residual of eq. 41 at the iterate `(q_new, v_new)` with the impulse `P`:
    /// `‖M(v − v_k) − hF_θ − GP‖∞` relative to the largest of its terms (0 below 64 ulps
    /// of that scale).
    fn structure_residual(&mut self, stats: &mut StepStats) -> Result<f64, Error> {
        self.evaluate_structure(false, stats)?;
        let st = self.structure.as_mut().expect("a nonlinear structure");
        // the next linearization, at this iterate, can reuse the right-hand side
        st.rhs_at_iterate = true;
        // work = −R = rhs + G P
        self.work.copy_from_slice(&st.rhs);
        let mut gp = 0.0_f64;
        for a in 0..self.rows {
            if self.p[a] != 0.0 {
                self.del.jac.axpy(a, self.p[a], &mut self.work);
                gp = gp.max(self.p[a].abs());
            }
        }
        let scale = st.scale.max(gp);
        let r = self.work.iter().fold(0.0_f64, |a, x| a.max(x.abs()));
        Ok(if r <= 64.0 * f64::EPSILON * scale {
            0.0
        } else {
            r / scale.max(f64::MIN_POSITIVE)
        })
    }

    /// Sets `vel_mask` from the forecast `ḡ_{k+1}` (eq. 61 or 62): active iff `ḡ ≤ 0`.
    pub fn forecast(&mut self, f: Forecast) {
        let (h, th) = (self.h, self.theta);
        for a in 0..self.m {
            let g = self.state.gap[a];
            let i = self.off[a];
            let gbar = match f {
                Forecast::Explicit { gamma } => g + gamma * h * self.u_k[i],
                Forecast::Free => g + h * (th * self.u_free[i] + (1.0 - th) * self.u_k[i]),
            };
            self.vel_mask[a] = gbar <= 0.0;
        }
    }

    /// Runs the decoupled Newton loop (eq. 56–58) for fixed `vel_mask` (and `pos_mask`
    /// for [`PositionRule::Combined`]), leaving `P`, `τ`, the linearized gaps `g_lin`
    /// and the new `v`, `q` in the core's buffers.
    pub fn newton(
        &mut self,
        law: VelocityLaw,
        rule: PositionRule,
        stats: &mut StepStats,
    ) -> Result<(), Error> {
        let (h, th, m, rows) = (self.h, self.theta, self.m, self.rows);
        if !self.g_constant && !self.jac_at_qk {
            self.contacts
                .evaluate(&self.state.q, &mut self.g_at_lin, &mut self.del.jac);
            if self.structure.is_none() {
                if !self.w_at_qk {
                    self.del.refresh(&self.sys.stiffness);
                    self.w_at_qk = true;
                }
                self.del.jac.transpose_mul(&self.v_free, &mut self.u_free);
            }
            self.jac_at_qk = true;
        }
        // a round with no row in any problem reads no Delassus entry: its
        // re-linearizations evaluate the gaps and G (for the activation test) and leave
        // the operators as they are (formed at q_k, or re-formed by the next round)
        let empty_round = law == VelocityLaw::Impact
            && self.structure.is_none()
            && !self.vel_mask.iter().any(|&x| x)
            && match rule {
                PositionRule::None => true,
                PositionRule::Combined { .. } => !self.pos_mask.iter().any(|&x| x),
                PositionRule::AllComplementarity => false,
            };
        if self.structure.is_some() && !self.at_first_iterate {
            // a later round of Algorithm 2 (or its complementarity redo)
            if self.last_converged {
                self.restart_iterate(stats)?;
            } else {
                self.first_iterate(stats)?;
            }
        }
        // modified Newton: the last two changes of the iterate, for its contraction test
        let (mut change, mut change_before) = (f64::INFINITY, f64::INFINITY);
        self.tau_prev.iter_mut().for_each(|x| *x = 0.0);
        self.p.iter_mut().for_each(|x| *x = 0.0);
        self.eq_rows.iter_mut().for_each(|x| *x = false);
        self.velocity_accuracy = 0.0;
        if !self.operators_constant {
            self.q_lin.copy_from_slice(&self.state.q);
        }
        self.g_at_lin.copy_from_slice(&self.state.gap);
        for (k, &d) in self.zone.iter().enumerate() {
            self.zq_k[k] = self.state.q[d];
            self.zq_lin[k] = self.state.q[d];
        }
        let mut relinearized = false;
        let mut converged = false;
        let (mut best, mut best_it) = (f64::INFINITY, 0);
        let (mut last_r, mut coupled_last) = (f64::INFINITY, false);
        // |qⁿ⁺¹ − qⁿ|∞ / |qⁿ⁺¹|∞ of the last iterate (nonlinear contacts only)
        let mut configuration_change = f64::INFINITY;
        let mut it = 0;
        while it < self.newton.max_iterations {
            it += 1;
            stats.newton_iterations += 1;
            if it > 1 && !self.operators_constant {
                if !self.g_constant {
                    self.contacts
                        .evaluate(&self.q_lin, &mut self.g_at_lin, &mut self.del.jac);
                    relinearized = true;
                    self.jac_at_qk = false;
                }
                // a nonlinear structure: the next iterate's M̂ⁿ (full Newton, or modified
                // Newton when the last change was not at most half the one before) and
                // free velocity
                let refactored = match self.structure.as_ref().map(|s| s.modified) {
                    None => false,
                    Some(modified) => {
                        let tangent = !modified || change > 0.5 * change_before;
                        self.linearize_structure(tangent, stats)?;
                        tangent
                    }
                };
                if (!self.g_constant || refactored) && !empty_round {
                    let k = match &self.structure {
                        Some(st) => &st.tangent,
                        None => &self.sys.stiffness,
                    };
                    self.del.refresh(k);
                    self.w_at_qk = false;
                }
                self.del.jac.transpose_mul(&self.v_free, &mut self.u_free);
            }
            // coupling hθ W_D τⁿ (zero without projection)
            self.coupling.iter_mut().for_each(|x| *x = 0.0);
            if self.feedback && self.structure.is_none() && self.tau_prev.iter().any(|&t| t != 0.0)
            {
                // with a constant G the columns stay and serve every later step; with a
                // nonlinear G they are forgotten at the next linearization, and the
                // product through the factor (two solves) is cheaper than |supp τ|
                // column solves, which would also take pool slots the position problem
                // of this iteration needs (81 contacts of two cubes: τ on 42 rows, then
                // 33 other rows violated, past the 64-column pool)
                if self.g_constant {
                    self.del
                        .ensure_support(&self.tau_prev, &self.sys.stiffness)
                        .map_err(|e| fail(&self.state, "Delassus columns", e))?;
                }
                self.del.mul_add(
                    Op::Wd,
                    h * th,
                    &self.tau_prev,
                    &mut self.coupling,
                    &self.sys.stiffness,
                );
            }
            for a in 0..rows {
                self.a[a] = self.u_free[a] - self.coupling[a] + self.restitution(a) * self.u_k[a];
            }
            // linearized gaps without contact impulse or projection (eq. 51), normal rows
            for c in 0..m {
                let a = self.off[c];
                self.g_lin[a] = if self.g_constant || !relinearized {
                    self.state.gap[c] + h * (1.0 - th) * self.u_k[a]
                } else {
                    self.g_at_lin[c]
                        + self.del.jac.dot(a, &self.state.q)
                        + h * (1.0 - th) * self.del.jac.dot(a, &self.state.v)
                        - self.del.jac.dot(a, &self.q_lin)
                };
            }
            match law {
                VelocityLaw::Impact => {
                    // velocity LCP (eq. 57), or the Coulomb problem (eq. 15), on the
                    // rows of the active set
                    self.ws.idx.clear();
                    self.ws.blocks.clear();
                    let mut frictional = false;
                    for c in (0..m).filter(|&c| self.vel_mask[c]) {
                        let (o, d) = (self.off[c], self.off[c + 1] - self.off[c]);
                        if self.friction {
                            self.ws.blocks.push(Block {
                                offset: self.ws.idx.len(),
                                dim: d,
                                mu: self.mu[c],
                            });
                            frictional |= d > 1;
                        }
                        self.ws.idx.extend(o..o + d);
                    }
                    if !self.ws.idx.is_empty() {
                        if !self.ws.over_cap() {
                            self.del
                                .ensure_all(&self.ws.idx, &self.sys.stiffness)
                                .map_err(|e| fail(&self.state, "Delassus columns", e))?;
                        }
                        // friction: warm start from the previous step's impulse
                        let warm = if frictional && it == 1 {
                            &self.state.impulse_rows
                        } else {
                            &self.p
                        };
                        self.ws
                            .gather(&self.del, Op::W, 1.0, &self.a, warm, |_| false)
                            .map_err(|e| fail(&self.state, "velocity problem", e))?;
                        if frictional {
                            let (info, acc) = self
                                .ws
                                .solve_friction(
                                    &self.friction_params,
                                    &mut self.del,
                                    &self.sys.stiffness,
                                    stats,
                                )
                                .map_err(|e| fail(&self.state, "friction problem", e))?;
                            self.velocity_accuracy = self.velocity_accuracy.max(acc);
                            stats.friction_solves += 1;
                            stats.friction_iterations += info.iterations;
                            stats.friction_residual = stats.friction_residual.max(info.residual);
                            stats.friction_fallbacks +=
                                usize::from(info.solver != FrictionSolverKind::Nsgs);
                            if !info.converged {
                                stats.caps_hit += 1;
                                stats.friction_caps += 1;
                            }
                        } else {
                            let info = self
                                .ws
                                .solve(&mut self.del, &self.sys.stiffness, stats)
                                .map_err(|e| fail(&self.state, "velocity LCP", e))?;
                            stats.lcp_iterations += info.iterations;
                            stats.lcp_residual = stats.lcp_residual.max(info.residual);
                        }
                        self.ws.scatter(&mut self.p);
                    } else {
                        self.p.iter_mut().for_each(|x| *x = 0.0);
                    }
                }
                VelocityLaw::PositionLevel => {
                    // 0 ≤ g_base + hθ (U_free + W P) ⊥ P ≥ 0 on every contact
                    // (frictionless only: one row per contact)
                    for a in 0..m {
                        self.a[a] = self.g_lin[a] + h * th * self.u_free[a];
                    }
                    self.p_warm.copy_from_slice(&self.p);
                    grow_solve(
                        &mut self.ws,
                        &mut self.del,
                        (Op::W, &self.sys.stiffness),
                        h * th,
                        &self.a,
                        &self.p_warm,
                        &mut self.p,
                        (0.0, &self.normal),
                        stats,
                    )
                    .map_err(|e| fail(&self.state, "position-level LCP", e))?;
                }
            }
            self.wp.iter_mut().for_each(|x| *x = 0.0);
            self.del
                .mul_add(Op::W, 1.0, &self.p, &mut self.wp, &self.sys.stiffness);
            for a in 0..rows {
                self.u_new[a] = self.u_free[a] + self.wp[a] - self.coupling[a];
            }
            for c in 0..m {
                let a = self.off[c];
                self.b[a] = self.g_lin[a] + h * th * self.u_new[a];
            }
            // position problem
            let projected = self.solve_position(rule, stats)?;
            if projected {
                stats.projection_iterations += 1;
            }
            self.wt.iter_mut().for_each(|x| *x = 0.0);
            if self.with_projection {
                self.del
                    .mul_add(Op::Wn, 1.0, &self.tau, &mut self.wt, &self.sys.stiffness);
            }
            for c in 0..m {
                let a = self.off[c];
                self.g_lin[a] = self.b[a] + self.wt[a];
            }
            self.tau_used.copy_from_slice(&self.tau_prev);
            for a in 0..rows {
                self.dtau[a] = self.tau[a] - self.tau_prev[a];
            }
            self.tau_prev.copy_from_slice(&self.tau);
            // convergence
            let r = if self.operators_constant {
                self.linear_residual()?
            } else if !self.zone.is_empty() {
                // the iterate on the contact zone alone: the rest of the state follows
                // the zone's impulses linearly and is formed once, at commit
                self.form_zone();
                let r = newton_change(
                    &self.zq_new,
                    &self.zq_lin,
                    &self.zq_k,
                    self.coordinate_scale,
                );
                configuration_change = relative_change(&self.zq_new, &self.zq_lin);
                self.zq_lin.copy_from_slice(&self.zq_new);
                for (&d, &x) in self.zone.iter().zip(&self.zq_new) {
                    self.q_lin[d] = x;
                }
                r
            } else {
                self.form();
                let r = newton_change(
                    &self.q_new,
                    &self.q_lin,
                    &self.state.q,
                    self.coordinate_scale,
                );
                configuration_change = relative_change(&self.q_new, &self.q_lin);
                self.q_lin.copy_from_slice(&self.q_new);
                if self.structure.is_some() {
                    // eq. 41 at the new iterate; with a constant G the gaps are exact
                    // (eq. 49 holds identically) and R alone decides
                    let rs = self.structure_residual(stats)?;
                    let r = if self.g_constant { rs } else { r.max(rs) };
                    (change_before, change) = (change, r);
                    r
                } else {
                    r
                }
            };
            stats.newton_residual = r;
            // the friction solve resolves velocities to `velocity_accuracy` only: the
            // loop cannot tell iterates apart below a relative 16 × that (two iterates of
            // error ≤ acc each, through the position problem, which moved rows of the
            // undamped block by up to 8 × the change of its right-hand side)
            let tol = if self.velocity_accuracy > 0.0 {
                let s_v = self
                    .u_free
                    .iter()
                    .chain(&self.u_k)
                    .chain(&self.u_new)
                    .fold(0.0_f64, |a, x| a.max(x.abs()));
                self.newton
                    .tol
                    .max(16.0 * self.velocity_accuracy / s_v.max(f64::MIN_POSITIVE))
            } else {
                self.newton.tol
            };
            if r <= tol {
                converged = true;
                break;
            }
            // Stagnation: no 10 % gain in STALL iterations. With friction the iterates
            // can cycle among position solutions that differ by rows resting at g ≈ 0
            // within the friction solve's accuracy (period 2–3 at r ≈ 1e-9, gaps moving
            // by 1e-15 m, on the undamped block at h = 1e-5): the loop ends there and is
            // converged when the level reached is within √tol; otherwise it is a cap.
            if r < 0.9 * best {
                best = r;
                best_it = it;
            } else if it >= best_it + STALL {
                // also converged when the iterates no longer move the configuration
                // itself beyond the tolerance: a body at rest on contacts between bodies
                // takes step increments of 5e-13 m, and the solves' round-off (8e-18 m
                // around |q| = 5e-6 m, the three-block stack) is 1.5e-5 of that forever
                converged = best <= tol.sqrt() || configuration_change <= tol;
                stats.newton_stalls += 1;
                break;
            }
            // a coupled solve whose iterate did not lower the residual had the wrong
            // states: the next iterate is the plain decoupled one, which updates them
            let helped = !coupled_last || r < last_r;
            coupled_last = false;
            if it >= COUPLED_AFTER
                && helped
                && self.structure.is_none()
                && law == VelocityLaw::Impact
                && rule != PositionRule::None
                && self.coupled_correction(rule)?
            {
                stats.coupled_solves += 1;
                coupled_last = true;
            }
            last_r = r;
        }
        self.last_converged = converged;
        if !converged {
            stats.caps_hit += 1;
        }
        if let PositionRule::Combined { .. } = rule {
            stats.held_rows = (0..m)
                .filter(|&c| self.pos_mask[c])
                .filter(|&c| self.p[self.off[c]] <= 0.0 && self.tau[self.off[c]] < 0.0)
                .count();
        }
        Ok(())
    }

    /// The coupled position problem of eq. 52–55, solved on the contact states of the
    /// current iterate, as the next iterate's `τ`.
    ///
    /// The decoupled loop (eq. 56–58) feeds `τⁿ` into the velocity problem through
    /// `−hθ W_D τⁿ` and solves the position problem with that velocity: a fixed point
    /// whose contraction factor on a mode of frequency ω is `(ωhθ)² / (1 + (ωhθ)²)`
    /// (metric `M̂⁻¹`), so it crawls once `ωhθ ≳ 1`, which the highest modes of any
    /// finite-element mesh reach (the undamped hex8 block at h = 1e-4: factor 0.74 per
    /// iteration, the cap of 50 reached). On the current states — each active block open
    /// (`P = 0`), sticking (`U + eU_k = 0` on all its rows) or slipping (`U_N + eU_{k,N} = 0`
    /// and `P_T = μ P_N d` along the current direction `d`), each projected row at `g = 0`
    /// (equality rows, and complementarity rows with `τ > 0`) — the velocity and position
    /// equations of eq. 53,
    ///
    /// `U + eU_k = W P − hθ W_D τ + (U_free + eU_k)`,
    /// `g = hθ W P + (W_N − h²θ² W_D) τ + (g_lin + hθ U_free)`,
    ///
    /// are linear in `(P, τ)`; their solution (dense LU) is the fixed point of the
    /// decoupled map on that piece, a semismooth Newton step on it. Its `τ` replaces
    /// `τⁿ⁺¹`; the next decoupled iteration then checks every law (complementarity, the
    /// friction cone, the states) and converges at once when the states were right, or
    /// goes on from a better iterate when they were not. Returns whether a solve ran.
    fn coupled_correction(&mut self, rule: PositionRule) -> Result<bool, Error> {
        let Some(cp) = self.coupled.as_mut() else {
            return Ok(false);
        };
        let (h, th, m) = (self.h, self.theta, self.m);
        let c = h * th;
        cp.unknowns.clear();
        cp.cols.clear();
        for k in (0..m).filter(|&k| self.vel_mask[k]) {
            let (o, d) = (self.off[k], self.off[k + 1] - self.off[k]);
            let pn = self.p[o];
            if pn <= 0.0 {
                continue;
            }
            let pt = self.p[o + 1..o + d]
                .iter()
                .map(|x| x * x)
                .sum::<f64>()
                .sqrt();
            let mu = self.mu[k];
            // the buffers hold `cap` unknowns: a larger problem is not attempted (and
            // must not grow them inside the step)
            if cp.unknowns.len() + d > cp.cap || cp.cols.len() + d > cp.cols.capacity() {
                return Ok(false);
            }
            if d == 1 || mu == 0.0 || pt >= (1.0 - 1e-9) * mu * pn {
                let mut u = Unknown {
                    row: o,
                    contact: k,
                    ..Unknown::default()
                };
                if d > 1 && mu > 0.0 && pt > 0.0 {
                    u.slip_dim = d - 1;
                    for j in 0..d - 1 {
                        u.slip[j] = mu * self.p[o + 1 + j] / pt;
                    }
                }
                cp.unknowns.push(u);
            } else {
                cp.unknowns.extend((o..o + d).map(|row| Unknown {
                    row,
                    contact: k,
                    ..Unknown::default()
                }));
            }
            cp.cols.extend(o..o + d);
        }
        for k in (0..m).filter(|&k| self.pos_mask[k] || rule == PositionRule::AllComplementarity) {
            let a = self.off[k];
            let eq = match rule {
                PositionRule::Combined { rule } => {
                    self.pos_mask[k] && (rule == ProjectionRule::AllActive || self.eq_rows[a])
                }
                _ => false,
            };
            if eq || self.tau[a] > 0.0 {
                if cp.unknowns.len() == cp.cap || cp.cols.len() == cp.cols.capacity() {
                    return Ok(false);
                }
                cp.unknowns.push(Unknown {
                    row: a,
                    contact: k,
                    tau: true,
                    equality: eq,
                    ..Unknown::default()
                });
                cp.cols.push(a);
            }
        }
        if !cp.unknowns.iter().any(|u| u.tau) {
            return Ok(false);
        }
        cp.cols.sort_unstable();
        cp.cols.dedup();
        self.del
            .ensure_all(&cp.cols, &self.sys.stiffness)
            .map_err(|e| fail(&self.state, "Delassus columns", e))?;
        // Active-set rounds: a block whose normal impulse comes out negative opens, a
        // complementarity row whose τ comes out negative leaves; each round drops at
        // least one unknown, so at most `n` rounds.
        loop {
            let n = cp.unknowns.len();
            if n == 0 || !cp.unknowns.iter().any(|u| u.tau) {
                return Ok(false);
            }
            let del = &self.del;
            for (l, ul) in cp.unknowns.iter().enumerate() {
                for (k, uk) in cp.unknowns.iter().enumerate() {
                    let i = uk.row;
                    let v = if ul.tau {
                        let wd = del.entry(Op::Wd, i, ul.row);
                        if uk.tau {
                            del.entry(Op::Wn, i, ul.row) - c * c * wd
                        } else {
                            -c * wd
                        }
                    } else {
                        let mut w = del.entry(Op::W, i, ul.row);
                        for j in 0..ul.slip_dim {
                            w += ul.slip[j] * del.entry(Op::W, i, ul.row + 1 + j);
                        }
                        if uk.tau { c * w } else { w }
                    };
                    cp.mat[k + l * n] = v;
                }
            }
            for (k, uk) in cp.unknowns.iter().enumerate() {
                let i = uk.row;
                cp.rhs[k] = if uk.tau && self.g_constant {
                    -(self.state.gap[uk.contact]
                        + h * (1.0 - th) * self.u_k[i]
                        + c * self.u_free[i])
                } else if uk.tau {
                    // a nonlinear G: the gap linearized at this iterate (eq. 51), which
                    // `b = g_lin + hθ U` still holds
                    -(self.b[i] - c * self.u_new[i] + c * self.u_free[i])
                } else {
                    let (e, u_k) = (self.e[i], self.u_k[i]);
                    let p_k = self.state.impulse_rows[i];
                    -(self.u_free[i]
                        + restitution(self.restitution_floor, e, self.normal[i], u_k, p_k) * u_k)
                };
            }
            if !cp.lu.solve(&mut cp.mat[..n * n], n, &mut cp.rhs[..n]) {
                // singular on this piece (redundant constraints): the decoupled loop goes on
                return Ok(false);
            }
            // contacts to drop: an impulse block with P_N < 0, a complementarity τ < 0
            cp.drop.iter_mut().for_each(|x| *x = false);
            let mut any = false;
            for (u, &y) in cp.unknowns.iter().zip(&cp.rhs[..n]) {
                let wrong = if u.tau {
                    !u.equality && y < 0.0
                } else {
                    u.row == self.off[u.contact] && y < 0.0
                };
                if wrong {
                    cp.drop[2 * u.contact + usize::from(u.tau)] = true;
                    any = true;
                }
            }
            if !any {
                break;
            }
            let drop = &cp.drop;
            cp.unknowns
                .retain(|u| !drop[2 * u.contact + usize::from(u.tau)]);
        }
        let n = cp.unknowns.len();
        self.tau_prev.iter_mut().for_each(|x| *x = 0.0);
        for (u, &y) in cp.unknowns.iter().zip(&cp.rhs[..n]) {
            if u.tau {
                self.tau_prev[u.row] = y;
            }
        }
        Ok(true)
    }

    /// Dimensionless change that the last `Δτ` would make to the next iterate (linear `G`).
    fn linear_residual(&mut self) -> Result<f64, Error> {
        if !self.with_projection || !self.feedback || self.dtau.iter().all(|&x| x == 0.0) {
            return Ok(0.0);
        }
        self.del
            .ensure_support(&self.dtau, &self.sys.stiffness)
            .map_err(|e| fail(&self.state, "Delassus columns", e))?;
        let (h, th, rows) = (self.h, self.theta, self.rows);
        let mut s_v: f64 = 0.0;
        let mut s_g: f64 = 0.0;
        for a in 0..rows {
            s_v = s_v
                .max(self.u_free[a].abs())
                .max(self.u_k[a].abs())
                .max(self.u_new[a].abs());
        }
        for c in 0..self.m {
            s_g = s_g.max(self.b[self.off[c]].abs());
        }
        self.wp.iter_mut().for_each(|x| *x = 0.0);
        self.wt.iter_mut().for_each(|x| *x = 0.0);
        self.del
            .mul_add(Op::Wd, 1.0, &self.dtau, &mut self.wp, &self.sys.stiffness);
        self.del
            .mul_add(Op::Wn, 1.0, &self.dtau, &mut self.wt, &self.sys.stiffness);
        let mut dv: f64 = 0.0;
        let mut dg: f64 = 0.0;
        for a in 0..rows {
            dv = dv.max(h * th * self.wp[a].abs());
        }
        for c in 0..self.m {
            dg = dg.max(self.wt[self.off[c]].abs());
        }
        // Rounding floor: 8 ulps of the quantities the iterate is built from (what the
        // friction solve resolves enters through the tolerance, in `newton`).
        let fv = 8.0 * f64::EPSILON * s_v;
        let fg = 8.0 * f64::EPSILON * (s_g + h * s_v);
        let rv = if dv <= fv {
            0.0
        } else {
            dv / s_v.max(f64::MIN_POSITIVE)
        };
        let rg = if dg <= fg {
            0.0
        } else {
            dg / (h * s_v).max(f64::MIN_POSITIVE)
        };
        Ok(rv.max(rg))
    }

    /// The restitution coefficient of row `a` in this step's impact law
    /// `0 ≤ U_{k+1} + e U_k ⊥ P ≥ 0` (eq. 18d, 57).
    ///
    /// The impulse of a row does the work `P((1 − θ)U_k + θU_{k+1})` in the θ-method's
    /// energy balance (the step moves `q` by `h v_{k+θ}`); with `U_{k+1} = −eU_k` that is
    /// `P U_k ((1 − θ) − θe)`, never positive for a row that closes (`U_k ≤ 0`), but
    /// positive for a row that separates at the step's start (`U_k > 0`) and is caught by
    /// an impulse, unless `e ≥ (1 − θ)/θ`. Such catches happen where the position
    /// projection leaves a node on the obstacle while moving away (the edge of a growing
    /// contact patch, issue 33: +3 % and +22 % of the energy on `meshes/hertz_ball.toml` at
    /// 2× and 4× its step), and in Moreau–Jean's closed active set. With
    /// [`SchemeParams::energy_consistent_restitution`] (the default) a separating normal
    /// row takes `max(e, (1 − θ)/θ)` (1 at θ = 1/2: the catch reverses `U` and does no
    /// work; `e` itself at θ = 1), so no impulse adds energy; a closing row keeps `e`.
    /// Under the projection schemes the floor applies to rows open in the last step
    /// (`P_k ≤ 0`): a row in lasting contact is held at `g = 0` by the projection, and
    /// flooring it kept the rocking block from coming to rest (velocities of 1e-7 at
    /// t = 1.21 s). Under Moreau–Jean, which holds no position, it applies to every
    /// separating row: a lasting contact that separates (two aluminium spheres
    /// released at 2 m/s, h = 6.25e-9) otherwise gained 1.02e-6 of the energy at e = 0.
    /// At θ = 1/2 the floored law reads `0 ≤ U_{k+1} + U_k ⊥ P ≥ 0`: the impulse does
    /// no work.
    #[inline]
    fn restitution(&self, a: usize) -> f64 {
        let s = &self.state;
        restitution(
            self.restitution_floor,
            self.e[a],
            self.normal[a],
            self.u_k[a],
            s.impulse_rows[a],
        )
    }

    /// The activation of eq. 66: adds to `vel_mask` every contact whose gap at the end
    /// of the last [`ThetaCore::newton`] (eq. 51 at the solved iterate) is `≤ 0`: after
    /// the position projection (`g_lin`, Algorithm 2) or before it (`b = g_lin − W_N τ`,
    /// the closure of Moreau–Jean's and Algorithm 1's forecast set). Returns whether the
    /// set grew.
    pub fn activate_violated(&mut self, before_projection: bool) -> bool {
        let gaps = if before_projection {
            &self.b
        } else {
            &self.g_lin
        };
        let mut grew = false;
        for a in 0..self.m {
            if !self.vel_mask[a] && gaps[self.off[a]] <= 0.0 {
                self.vel_mask[a] = true;
                grew = true;
            }
        }
        grew
    }

    /// The forecast set's Newton loop, closed on the solution when `closure`
    /// ([`SchemeParams::activation_closure`]): after each loop, every contact whose gap
    /// before the projection ends `≤ 0` joins `vel_mask` and the loop runs again. The set
    /// only grows, so at most `m` more rounds run; they are counted in
    /// [`StepStats::index_set_iterations`] (0 when the forecast was right).
    pub fn closed_newton(
        &mut self,
        rule: PositionRule,
        closure: bool,
        st: &mut StepStats,
    ) -> Result<(), Error> {
        loop {
            self.newton(VelocityLaw::Impact, rule, st)?;
            if !closure || !self.activate_violated(true) {
                return Ok(());
            }
            st.index_set_iterations += 1;
            if st.index_set_iterations > self.m {
                // unreachable while the set only grows; kept as a reported cap
                st.caps_hit += 1;
                return Ok(());
            }
        }
    }

    /// Solves the position problem for `rule`; returns whether any `τ ≠ 0`.
    fn solve_position(&mut self, rule: PositionRule, stats: &mut StepStats) -> Result<bool, Error> {
        let m = self.m;
        // Gaps are known only to hθ times the velocity accuracy of the friction solve
        // (0 without friction): a row within twice that of zero is neither violated nor
        // projected, or the rows resting at g ≈ 0 flip in and out of the position problem
        // on the solver's last digits and the loop never settles (seen at h = 1e-5 on the
        // undamped sliding block: gaps of ±5e-18 m flipping with U_N known to 1e-12 m/s).
        let ptol = self
            .projection_tolerance
            .max(2.0 * self.h * self.theta * self.velocity_accuracy);
        match rule {
            PositionRule::None => {
                self.tau.iter_mut().for_each(|x| *x = 0.0);
                return Ok(false);
            }
            PositionRule::AllComplementarity => {
                // 0 ≤ b + W_N τ ⊥ τ ≥ 0 over all contacts
                grow_solve(
                    &mut self.ws,
                    &mut self.del,
                    (Op::Wn, &self.sys.stiffness),
                    1.0,
                    &self.b,
                    &self.tau_prev,
                    &mut self.tau,
                    (ptol, &self.normal),
                    stats,
                )
                .map_err(|e| fail(&self.state, "position LCP", e))?;
            }
            PositionRule::Combined { rule } => {
                // eq. 68: equality where P > 0 (eq. 69/70), complementarity elsewhere
                // in the active set; rows already within the tolerance are dropped.
                // A row stays an equality for the rest of the loop once its P was > 0:
                // eq. 65 can have no solution for an index set (the paper says so of
                // imposing g = 0 on all of Iᵛ), and then the states alternate. Seen on
                // the undamped sliding block at h = 2e-4: five rows with P > 0 held at
                // g = 0 need τ < 0, with that τ their P is 0; as complementarity rows
                // their τ is 0 and their P > 0 again, every other iteration until the cap.
                // Keeping them equalities ends the loop; a final P = 0 with τ < 0 is
                // counted in `StepStats::held_rows`.
                for c in 0..m {
                    let a = self.off[c];
                    if self.pos_mask[c]
                        && self.p[a] > 0.0
                        && rule.holds(self.state.impulse_rows[a] > 0.0)
                    {
                        self.eq_rows[a] = true;
                    }
                }
                let (b, eq_rows) = (&self.b, &self.eq_rows);
                let eq = |a: usize| rule == ProjectionRule::AllActive || eq_rows[a];
                self.ws.idx.clear();
                self.ws
                    .idx
                    .extend((0..m).map(|c| (c, self.off[c])).filter_map(|(c, a)| {
                        (self.pos_mask[c]
                            && if eq(a) {
                                b[a].abs() > ptol || (ptol == 0.0 && b[a] != 0.0)
                            } else {
                                b[a] < -ptol
                            })
                        .then_some(a)
                    }));
                self.tau.iter_mut().for_each(|x| *x = 0.0);
                // The rows are chosen at τ = 0; the projection of the equality rows can
                // push a complementarity row of the active set below zero (seen with
                // friction: a lifting node next to projected ones). Such rows join and
                // the problem is solved again, as in `grow_solve`: at most m rounds.
                let mut rounds = 0;
                while !self.ws.idx.is_empty() {
                    rounds += 1;
                    if !self.ws.over_cap() {
                        self.del
                            .ensure_all(&self.ws.idx, &self.sys.stiffness)
                            .map_err(|e| fail(&self.state, "Delassus columns", e))?;
                    }
                    self.ws
                        .gather(&self.del, Op::Wn, 1.0, b, &self.tau_prev, eq)
                        .map_err(|e| fail(&self.state, "position MLCP", e))?;
                    let info = self
                        .ws
                        .solve(&mut self.del, &self.sys.stiffness, stats)
                        .map_err(|e| fail(&self.state, "position MLCP", e))?;
                    stats.lcp_iterations += info.iterations;
                    stats.lcp_residual = stats.lcp_residual.max(info.residual);
                    self.ws.scatter(&mut self.tau);
                    // complementarity rows of the active set left out and now violated
                    let (off, pos) = (&self.off, &self.pos_mask);
                    let candidates = (0..m).filter(|&c| pos[c]).map(|c| off[c]);
                    let grew = self.ws.add_violated(
                        (&mut self.del, &self.sys.stiffness),
                        (Op::Wn, 1.0),
                        b,
                        &self.tau,
                        ptol,
                        candidates,
                        eq,
                    );
                    if !grew {
                        break;
                    }
                    if rounds > m {
                        stats.caps_hit += 1;
                        break;
                    }
                }
            }
        }
        Ok(self.tau.iter().any(|&t| t != 0.0))
    }

    /// `v = v_free + M̂⁻¹G P − hθ M̂⁻¹K N G τ_used`, `q = q_k + h(1−θ)v_k + hθ v + N G τ`.
    pub(crate) fn form(&mut self) {
        let (h, th) = (self.h, self.theta);
        if self.operators_constant {
            // called once per step: v_free is not needed afterwards (begin_step
            // rewrites it), so hand its buffer over instead of copying
            std::mem::swap(&mut self.v_new, &mut self.v_free);
        } else {
            self.v_new.copy_from_slice(&self.v_free);
        }
        // a nonlinear structure has the projection's feedback in F(q_θ) (module doc of
        // `structure`)
        let kfac = if self.feedback && self.structure.is_none() {
            -h * th
        } else {
            0.0
        };
        self.state_finite = None;
        if self.operators_constant && self.form_fused(kfac) {
            return;
        }
        self.del.add_velocity_correction(
            &self.p,
            kfac,
            &self.tau_used,
            &self.tau,
            &mut self.v_new,
            &self.sys.stiffness,
        );
        let s = &self.state;
        for (((qn, q), v), vn) in self.q_new.iter_mut().zip(&s.q).zip(&s.v).zip(&self.v_new) {
            *qn = q + h * ((1.0 - th) * v + th * vn);
        }
        self.del.add_position_correction(&self.tau, &mut self.q_new);
    }

    /// [`ThetaCore::form`] in one pass over the state where the corrections are dense
    /// columns ([`Delassus::dense_columns`]) and at most one row carries each of `P`,
    /// `τ_used` (with feedback) and `τ` (a bar's tip, a few nodes on a plane, one at a
    /// time): per dof the same operations in the same order as the axpys of the general
    /// path, so the same bits, with the next step's `y = q + hθ v` written alongside
    /// (`q_lin`, read by [`ThetaCore::begin_step`]). At 10⁶ dofs the separate passes
    /// read and wrote the state four more times per step than a C loop of it (issue 35).
    /// Returns false (nothing done) where the general path must run.
    fn form_fused(&mut self, kfac: f64) -> bool {
        let Some((cg, d)) = self.del.dense_columns() else {
            return false;
        };
        let n = self.n;
        // the one nonzero row of each vector, if one: (column offset, scale)
        let one = |x: &[f64], s: f64| -> Result<Option<(usize, f64)>, ()> {
            let mut it = x.iter().enumerate().filter(|(_, v)| **v != 0.0);
            match (it.next(), it.next()) {
                (None, _) => Ok(None),
                (Some((a, &v)), None) => Ok(Some((a * n, s * v))),
                _ => Err(()),
            }
        };
        let (Ok(p), Ok(fb), Ok(t)) = (
            one(&self.p, 1.0),
            if kfac != 0.0 {
                one(&self.tau_used, kfac)
            } else {
                Ok(None)
            },
            one(&self.tau, 1.0),
        ) else {
            return false;
        };
        if fb.is_some() && d.len() < cg.len() {
            return false;
        }
        let s = &self.state;
        let cols = [(p, cg), (fb, d), (t, cg)].map(|(c, src)| match c {
            Some((o, k)) => (&src[o..o + n], k),
            None => (&s.q[..], 0.0),
        });
        let out = (
            &mut self.q_new[..],
            &mut self.v_new[..],
            &mut self.q_lin[..],
        );
        let args = (&s.q[..], &s.v[..], out, cols, (self.h, self.theta));
        let finite = fused_update_with((p.is_some(), fb.is_some(), t.is_some()), args);
        self.state_finite = Some(finite);
        self.y_ready = true;
        true
    }

    /// [`ThetaCore::form`] on the contact zone only (`zq_new`): with `G = S B` the gaps and
    /// `G` depend on the zone's dofs alone, and on a linear structure the zone rows of the
    /// corrections are `F (B p) − hθ F_E (B τ_used)` and `(N G τ)_zone`
    /// ([`Delassus::zone_corrections`]), so a Newton iteration needs no sparse solve;
    /// [`ThetaCore::commit`] forms the whole state once with the converged impulses.
    fn form_zone(&mut self) {
        let (h, th) = (self.h, self.theta);
        let kfac = if self.feedback { -h * th } else { 0.0 };
        self.del.zone_corrections(
            &self.p,
            kfac,
            &self.tau_used,
            &self.tau,
            &mut self.zv,
            &mut self.zq,
        );
        let s = &self.state;
        for (k, &d) in self.zone.iter().enumerate() {
            let vn = self.v_free[d] + self.zv[k];
            self.zq_new[k] = s.q[d] + h * ((1.0 - th) * s.v[d] + th * vn) + self.zq[k];
        }
    }

    /// Accepts `v_new`, `q_new`, `P`, `τ` as the state at `t_{k+1}` and evaluates the
    /// contacts there (re-condensing for nonlinear contacts).
    /// Restores a checkpointed state and evaluates again what [`ThetaCore::commit`]
    /// derives from it: the gaps and Jacobian at `q`, the Delassus data of a nonlinear
    /// contact set, `U = Gᵀ v`.
    pub fn restore(
        &mut self,
        scheme: &str,
        s: &crate::integrators::saved::IntegratorState,
    ) -> Result<(), Error> {
        self.state.restore(scheme, s)?;
        self.y_ready = false;
        self.contacts.restart(&self.state.q);
        self.contacts
            .update(&self.state.q)
            .map_err(|e| step_error(&self.state, self.h, e))?;
        self.evaluate_at_state();
        Ok(())
    }

    /// Brings the contact set's search data up to date at `q_k` ([`ContactSet::update`]);
    /// when a pairing changed the gaps, Jacobian and Delassus data are evaluated again.
    pub fn update_contacts(&mut self) -> Result<(), Error> {
        let changed = self
            .contacts
            .update(&self.state.q)
            .map_err(|e| step_error(&self.state, self.h, e))?;
        if changed && !self.g_constant {
            self.evaluate_at_state();
        }
        Ok(())
    }

    /// The gaps and Jacobian at `q`, the Delassus data of a nonlinear contact set, and
    /// `U = Gᵀ v`: what the next step reads, derived from the state.
    fn evaluate_at_state(&mut self) {
        self.contacts
            .evaluate(&self.state.q, &mut self.state.gap, &mut self.del.jac);
        if !self.g_constant {
            if self.structure.is_none() {
                // (a nonlinear structure condenses at the next step's first iterate)
                self.del.refresh(&self.sys.stiffness);
                self.w_at_qk = true;
            }
            self.jac_at_qk = true;
        }
        self.del.jac.transpose_mul(&self.state.v, &mut self.u_rows);
    }

    pub fn commit(&mut self, stats: &mut StepStats) {
        if self.operators_constant || !self.zone.is_empty() {
            self.form();
        }
        self.at_first_iterate = false;
        std::mem::swap(&mut self.state.q, &mut self.q_new);
        std::mem::swap(&mut self.state.v, &mut self.v_new);
        self.state.impulse_rows.copy_from_slice(&self.p);
        for c in 0..self.m {
            self.state.impulse[c] = self.p[self.off[c]];
            self.state.projection[c] = self.tau[self.off[c]];
        }
        self.state.step += 1;
        self.state.time = self.state.step as f64 * self.h;
        self.evaluate_at_state();
        self.scatter_local_velocity();
        stats.max_violation = self.state.gap.iter().fold(0.0_f64, |acc, &g| acc.max(-g));
    }

    /// Copies the normal and tangential parts of `u_rows` and of the impulse into the
    /// state and classifies each frictional contact: open without normal impulse, stick
    /// when `‖U_T‖` is below 1e-9 of the step's velocity scale (or the impulse strictly
    /// inside the cone), slip otherwise; a closed contact without friction (μ = 0 or a
    /// one-row block) has its own status, neither stick nor slip.
    fn scatter_local_velocity(&mut self) {
        let td = self.state.tangent_dim;
        let vs = self
            .u_free
            .iter()
            .chain(&self.u_rows)
            .fold(0.0_f64, |s, x| s.max(x.abs()));
        for c in 0..self.m {
            let (o, e) = (self.off[c], self.off[c + 1]);
            self.state.local_velocity[c] = self.u_rows[o];
            if td == 0 {
                continue;
            }
            let mut ut2 = 0.0;
            let mut pt2 = 0.0;
            for t in 0..td {
                let (ut, pt) = if o + 1 + t < e {
                    (self.u_rows[o + 1 + t], self.p[o + 1 + t])
                } else {
                    (0.0, 0.0)
                };
                self.state.tangent_velocity[c * td + t] = ut;
                self.state.tangent_impulse[c * td + t] = pt;
                ut2 += ut * ut;
                pt2 += pt * pt;
            }
            let pn = self.p[o];
            self.state.status[c] = if pn <= 0.0 {
                ContactStatus::Open
            } else if self.mu[c] == 0.0 || e - o == 1 {
                ContactStatus::Frictionless
            } else if ut2.sqrt() <= 1e-9 * vs || pt2.sqrt() < (1.0 - 1e-9) * self.mu[c] * pn {
                ContactStatus::Stick
            } else {
                ContactStatus::Slip
            };
        }
    }
}

/// Adds what the step's right-hand side owes to time-dependent nodal loads at
/// `t_{k+θ}` and to the prescribed dofs (eliminated): `−M_fp Δv_p − h C_fp v_p(t_{k+θ})
/// − h K_fp u_p(t_{k+θ})`, with `(t_k, h, θ)`; `vp` are two scratch vectors.
fn add_step_loads(
    sys: &LinearSystem,
    (t, h, th): (f64, f64, f64),
    (vp_a, vp_b): (&mut [f64], &mut [f64]),
    out: &mut [f64],
) {
    sys.add_loads(t + th * h, h, out);
    if let Some(p) = &sys.prescribed {
        p.velocity_at(t, vp_a);
        p.velocity_at(t + h, vp_b);
        for (b, a) in vp_b.iter_mut().zip(vp_a.iter()) {
            *b -= a;
        }
        spmv_add(p.mass.as_ref(), -1.0, vp_b, out);
        p.velocity_at(t + th * h, vp_a);
        if let Some(c) = &p.damping {
            spmv_add(c.as_ref(), -h, vp_a, out);
        }
        p.displacement_at(t + th * h, vp_a);
        spmv_add(p.stiffness.as_ref(), -h, vp_a, out);
    }
}

/// [`ThetaCore::restitution`] on row data: `max(e, floor)` for a normal row separating at
/// the step's start (`u_k > 0`), when a floor `(f, every)` is set: on every such row with
/// `every` (Moreau–Jean), on those that carried no impulse in the last step (`p_k ≤ 0`)
/// otherwise; `e` elsewhere.
#[inline]
fn restitution(floor: Option<(f64, bool)>, e: f64, normal: bool, u_k: f64, p_k: f64) -> f64 {
    match floor {
        Some((f, every)) if normal && u_k > 0.0 && (p_k <= 0.0 || every) => e.max(f),
        _ => e,
    }
}

/// A structural failure in the step after `state` (an inverted element, a singular
/// iteration matrix) as the run's error, naming the step and the time it reached.
pub(crate) fn step_error(state: &State, h: f64, e: Error) -> Error {
    Error::RunFailed {
        step: state.step + 1,
        time: state.time + h,
        contact: None,
        detail: match e {
            Error::Numerical(m) => m,
            e => e.to_string(),
        },
    }
}

/// Per contact row, whether its block of `G` is constant
/// ([`ContactSet::block_is_linear`]), for the zone condensation.
pub(crate) fn fixed_rows(contacts: &dyn ContactSet) -> Vec<bool> {
    (0..contacts.len())
        .flat_map(|a| std::iter::repeat_n(contacts.block_is_linear(a), contacts.dim(a)))
        .collect()
}

/// `|a − b|∞ / |a|∞` (0 when both are zero).
fn relative_change(a: &[f64], b: &[f64]) -> f64 {
    let (mut d, mut n) = (0.0_f64, 0.0_f64);
    for (x, y) in a.iter().zip(b) {
        d = d.max((x - y).abs());
        n = n.max(x.abs());
    }
    if d == 0.0 {
        0.0
    } else {
        d / n.max(f64::MIN_POSITIVE)
    }
}

/// The Newton convergence measure of a nonlinear step, shared by every scheme: the
/// change `|qⁿ⁺¹ − qⁿ|∞` relative to the step's increment `|qⁿ⁺¹ − q_k|∞`, and 0 once the
/// change is at the round-off level of `q` (16 ulps): at rest on two curved contacts the
/// projection otherwise flips τ ~ 1e-17 forever (the rocking block at rest hit the cap
/// before this floor; Schatzman–Paoli's own copy of the loop had lost it).
///
/// `coordinate_scale` is the largest reference coordinate the gap functions add to `q`
/// ([`ContactSet::coordinate_scale`]): a gap `g(X + u)` cannot tell apart two `u` closer
/// than the ulps of `X`, so changes below 16 ulps of it are round-off too. Without it, a
/// stack of three stiff blocks at rest (E = 1e10 Pa, the sag 7e-9 m, positions 0.15 m)
/// iterates on 6e-17 m changes, the gap's resolution, and stops at the cap (issue 33).
pub(crate) fn newton_change(
    q_new: &[f64],
    q_lin: &[f64],
    q_k: &[f64],
    coordinate_scale: f64,
) -> f64 {
    let (mut dq, mut inc, mut qn) = (0.0_f64, 0.0_f64, 0.0_f64);
    for ((a, b), c) in q_new.iter().zip(q_lin).zip(q_k) {
        dq = dq.max((a - b).abs());
        inc = inc.max((a - c).abs());
        qn = qn.max(a.abs());
    }
    if dq <= 16.0 * f64::EPSILON * qn.max(coordinate_scale) {
        0.0
    } else {
        dq / (inc + 8.0 * f64::EPSILON * qn).max(f64::MIN_POSITIVE)
    }
}

/// The arguments of [`fused_update`]: `q_k`, `v_k`, the outputs (`q_new`, `v_new`
/// holding `v_free` on entry, `y`), the three columns with their scales (the impulse's
/// `Â⁻¹G`, the feedback's `Â⁻¹K N G`, the projection's `Â⁻¹G`; unused ones any slice of
/// length `n`) and `(h, θ)`.
type FusedArgs<'a> = (
    &'a [f64],
    &'a [f64],
    (&'a mut [f64], &'a mut [f64], &'a mut [f64]),
    [(&'a [f64], f64); 3],
    (f64, f64),
);

/// [`fused_update`] with the terms `(P, F, T)` given at run time.
fn fused_update_with(terms: (bool, bool, bool), args: FusedArgs<'_>) -> bool {
    match terms {
        (false, false, false) => fused_update::<false, false, false>(args),
        (true, false, false) => fused_update::<true, false, false>(args),
        (false, true, false) => fused_update::<false, true, false>(args),
        (true, true, false) => fused_update::<true, true, false>(args),
        (false, false, true) => fused_update::<false, false, true>(args),
        (true, false, true) => fused_update::<true, false, true>(args),
        (false, true, true) => fused_update::<false, true, true>(args),
        (true, true, true) => fused_update::<true, true, true>(args),
    }
}

/// One pass of [`ThetaCore::form_fused`]: `v += k_P c_P + k_F c_F`,
/// `q = q_k + h((1 − θ) v_k + θ v) + k_τ c_τ`, `y = q + hθ v`, each term where its
/// const flag is set, in the order of the general path's axpys. Returns whether every
/// new `q` and `v` is finite (an integer test of the exponent bits, which vectorizes).
#[inline(never)]
fn fused_update<const P: bool, const F: bool, const T: bool>(args: FusedArgs<'_>) -> bool {
    const EXP: u64 = 0x7ff0_0000_0000_0000;
    let (q, v, (qn, vn, y), [(cp, kp), (cf, kf), (ct, kt)], (h, th)) = args;
    let n = q.len();
    assert!(v.len() == n && qn.len() == n && vn.len() == n && y.len() == n);
    assert!(cp.len() == n && cf.len() == n && ct.len() == n);
    let mut bad = 0u64;
    for i in 0..n {
        let mut a = vn[i];
        if P {
            a += kp * cp[i];
        }
        if F {
            a += kf * cf[i];
        }
        let mut b = q[i] + h * ((1.0 - th) * v[i] + th * a);
        if T {
            b += kt * ct[i];
        }
        vn[i] = a;
        qn[i] = b;
        y[i] = b + h * th * a;
        bad |= u64::from(a.to_bits() & EXP == EXP) | u64::from(b.to_bits() & EXP == EXP);
    }
    bad == 0
}

/// Refuses a `max_active_rows` that cannot hold one contact block (the dense one-step
/// workspaces gather whole blocks).
pub(crate) fn check_block_rows(
    params: &SchemeParams,
    contacts: &dyn ContactSet,
) -> Result<(), Error> {
    let block = (0..contacts.len())
        .map(|a| contacts.dim(a))
        .max()
        .unwrap_or(1);
    if params.max_active_rows != 0 && params.max_active_rows < block {
        // issue 34: accepted before
        return Err(Error::invalid(
            "scheme.max_active_rows",
            params.max_active_rows,
            &format!(
                "must hold at least one contact block ({block} rows: the normal and the \
                 tangents of a frictional contact), or be 0 for the default"
            ),
        ));
    }
    Ok(())
}

/// An error for a one-step solve that failed in the step after `state`.
pub(crate) fn fail(state: &State, what: &str, e: SolveError) -> Error {
    Error::NotConverged {
        solver: what.to_string(),
        step: state.step + 1,
        time: state.time,
        detail: e.to_string(),
    }
}

/// Solves `0 ≤ rhs + scale·op z ⊥ z ≥ 0` over the rows flagged in `rows` (the normal
/// rows) by solving on the rows violated at `z = 0` (`rhs < −tol`) and adding any row
/// the solution leaves violated, until none is: the result then solves the full LCP,
/// with work (and Delassus columns) proportional to the rows that matter. At most `m`
/// growth rounds (a cap counted in `stats`).
#[allow(clippy::too_many_arguments)]
pub(crate) fn grow_solve(
    ws: &mut Workspace,
    del: &mut Delassus,
    (op, stiffness): (Op, &SparseMatrix),
    scale: f64,
    rhs: &[f64],
    warm: &[f64],
    out: &mut [f64],
    (tol, rows): (f64, &[bool]),
    stats: &mut StepStats,
) -> Result<(), SolveError> {
    let m = del.len();
    ws.idx.clear();
    ws.idx.extend((0..m).filter(|&a| rows[a] && rhs[a] < -tol));
    out.iter_mut().for_each(|x| *x = 0.0);
    let mut rounds = 0;
    while !ws.idx.is_empty() {
        rounds += 1;
        if !ws.over_cap() {
            del.ensure_all(&ws.idx, stiffness)?;
        }
        ws.gather(del, op, scale, rhs, warm, |_| false)?;
        let info = ws.solve(del, stiffness, stats)?;
        stats.lcp_iterations += info.iterations;
        stats.lcp_residual = stats.lcp_residual.max(info.residual);
        ws.scatter(out);
        let candidates = (0..m).filter(|&a| rows[a]);
        if !ws.add_violated(
            (del, stiffness),
            (op, scale),
            rhs,
            out,
            tol,
            candidates,
            |_| false,
        ) {
            break;
        }
        if rounds > m {
            stats.caps_hit += 1;
            break;
        }
    }
    Ok(())
}

/// The one-step workspaces of the θ-method core in a memory ledger: the dense blocks
/// (the gathered block and the MLCP's three, `scheme.max_active_rows` rows at most), the
/// coupled position problem (the velocity rows plus one τ per contact, capped alike),
/// the matrix-free vectors past the cap, and `auto`'s dense friction Newton fallback.
/// Shared by [`ThetaCore::new`] and the plan of `signorini check`.
pub(crate) fn workspace_ledger(
    rows: usize,
    m: usize,
    params: &SchemeParams,
    (friction, with_projection): (bool, bool),
    mem: &mut crate::limits::MemoryEstimate,
) {
    let ws_cap = Workspace::cap(rows, params);
    let cap = ws_cap as u64;
    let cc = if with_projection && params.projection_feedback {
        (rows + m).min(ws_cap) as u64
    } else {
        0
    };
    mem.add("dense one-step workspaces (4 × rows²)", cap * cap, 32);
    mem.add("coupled position problem (unknowns²)", cc * cc, 8);
    if rows > ws_cap {
        // the matrix-free solves' vectors (`Workspace::gq`…, `GlobalSolver`)
        mem.add(
            "matrix-free one-step vectors (15 × rows)",
            rows as u64,
            15 * 8,
        );
    }
    // `auto`'s dense Newton fallback: W and J (solvers::newton::NewtonWork)
    let fn_rows = if friction {
        cap.min(crate::solvers::newton::STEP_NEWTON_ROWS as u64)
    } else {
        0
    };
    mem.add(
        "friction Newton workspace (2 × rows²)",
        fn_rows * fn_rows,
        16,
    );
}

/// Checks a user-given vector: length and finiteness.
pub(crate) fn check_vector(field: &str, x: &[f64], n: usize) -> Result<(), Error> {
    if x.len() != n {
        return Err(Error::invalid(
            field,
            format!("{} values", x.len()),
            &format!("needs {n} values (one per dof)"),
        ));
    }
    if let Some(i) = x.iter().position(|v| !v.is_finite()) {
        return Err(Error::invalid(
            &format!("{field}[{i}]"),
            x[i],
            "must be finite",
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fused pass gives the bits of the general path's separate passes (the axpys of
    /// `Delassus::add_velocity_correction` and `add_position_correction` around the
    /// update loop) for every combination of terms, and reports a non-finite `q` or `v`
    /// (the run's checks then skip their own scan: it must not miss one).
    #[test]
    fn fused_update_matches_the_separate_passes_and_finds_non_finite_values() {
        let n = 37;
        let wave = |k: f64| -> Vec<f64> { (0..n).map(|i| (k * i as f64).sin() * 1e-3).collect() };
        let (q, v, vf) = (wave(0.3), wave(0.7), wave(1.1));
        let (cp, cf, ct) = (wave(1.7), wave(2.3), wave(2.9));
        let (kp, kf, kt, h, th) = (3.7, -1.3e-7, 0.9, 2e-7, 0.5);
        // the fused pass from q_k = `q`, v_free = `vf`: (q, v, y) and the finiteness
        let fused = |terms: (bool, bool, bool), q: &[f64], vf: &[f64], kt: f64| {
            let (mut q2, mut v2, mut y2) = (vec![0.0; n], vf.to_vec(), vec![0.0; n]);
            let cols = [(&cp[..], kp), (&cf[..], kf), (&ct[..], kt)];
            let args = (
                q,
                &v[..],
                (&mut q2[..], &mut v2[..], &mut y2[..]),
                cols,
                (h, th),
            );
            let finite = fused_update_with(terms, args);
            (q2, v2, y2, finite)
        };
        for mask in 0..8 {
            let (p, f, t) = (mask & 1 != 0, mask & 2 != 0, mask & 4 != 0);
            // the general path
            let mut v1 = vf.clone();
            if p {
                v1.iter_mut().zip(&cp).for_each(|(y, x)| *y += kp * x);
            }
            if f {
                v1.iter_mut().zip(&cf).for_each(|(y, x)| *y += kf * x);
            }
            let mut q1: Vec<f64> = (0..n)
                .map(|i| q[i] + h * ((1.0 - th) * v[i] + th * v1[i]))
                .collect();
            if t {
                q1.iter_mut().zip(&ct).for_each(|(y, x)| *y += kt * x);
            }
            let y1: Vec<f64> = (0..n).map(|i| q1[i] + h * th * v1[i]).collect();
            // the fused pass
            let (q2, v2, y2, finite) = fused((p, f, t), &q, &vf, kt);
            assert!(finite);
            for (a, b) in [(&q1, &q2), (&v1, &v2), (&y1, &y2)] {
                assert!(
                    a.iter()
                        .zip(b.iter())
                        .all(|(x, y)| x.to_bits() == y.to_bits())
                );
            }
        }
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            for at in [0, 17, n - 1] {
                let mut vb = vf.clone();
                vb[at] = bad;
                let (.., finite) = fused((false, false, false), &q, &vb, kt);
                assert!(!finite, "{bad} at {at}");
            }
        }
        // a finite v whose q overflows: reported, or every q finite
        let mut qb = q.clone();
        qb[5] = f64::MAX;
        let (q2, .., finite) = fused((false, false, true), &qb, &vf, 1e300);
        assert!(!finite || q2.iter().all(|x| x.is_finite()));
    }
}
