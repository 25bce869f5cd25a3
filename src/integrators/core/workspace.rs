//! The one-step problems' workspace (sized once, matrix-free past its cap) and the
//! dispatch to the LCP, MLCP and friction solvers; the errors a failed solve becomes.

use super::*;

/// Dense sub-problem workspace: gathers a principal sub-block, solves, scatters. Sized
/// for `cap` rows (the active rows of a step), not for the candidates.
#[derive(Debug)]
pub(crate) struct Workspace {
    /// Rows of the dense blocks.
    pub(super) cap: usize,
    /// The gathered rows (indices in contact space).
    pub idx: Vec<usize>,
    /// The gathered principal sub-block, `cap × cap` column-major.
    pub(super) block: Vec<f64>,
    /// The gathered problem's right-hand side.
    pub(super) rhs: Vec<f64>,
    /// Its solution (impulses or projections).
    pub(super) solution: Vec<f64>,
    /// Its complementary slack (`block · solution + rhs`).
    pub(super) slack: Vec<f64>,
    /// Rows held as equalities (the MLCP's).
    pub(super) equality: Vec<bool>,
    /// Per contact-space row, whether it is gathered.
    pub(super) member: Vec<bool>,
    /// Per contact-space row, the residual of the last solve.
    pub(super) residual: Vec<f64>,
    /// The LCP solver of the velocity problems.
    pub lcp: LcpSolver,
    /// The MLCP solver of the position problems.
    pub(super) mlcp: Mlcp,
    /// Friction blocks of the gathered problem (offsets in the gathered rows).
    pub(super) blocks: Vec<Block>,
    pub(super) friction: FrictionSolver,
    /// The gathered rows exceed `cap`: the problem is recorded (`gq`, `gz`, `geq`) and
    /// solved matrix-free ([`crate::solvers::global`]) on products with `del`.
    pub(super) over: bool,
    /// Rows past which a problem is solved matrix-free (`cap`, or fewer:
    /// [`Workspace::matrix_free_from`]).
    pub(super) mf_from: usize,
    /// Operator and scale of the recorded problem.
    pub(super) mf_op: (Op, f64),
    /// The recorded problem's right-hand side, solution, slack and equality rows.
    pub(super) mf_rhs: Vec<f64>,
    /// See `mf_rhs`.
    pub(super) mf_solution: Vec<f64>,
    /// See `mf_rhs`.
    pub(super) mf_slack: Vec<f64>,
    /// See `mf_rhs`.
    pub(super) mf_equality: Vec<bool>,
    /// Full contact-space vectors for the restricted products (argument and result).
    pub(super) mf_x: Vec<f64>,
    /// See `mf_x`.
    pub(super) mf_y: Vec<f64>,
    /// The matrix-free solver (MPRGP, or the accelerated projected gradient).
    pub(super) matrix_free: GlobalSolver,
    /// Tolerance and product cap of the matrix-free solves (the friction solver's).
    pub(super) mf_tol: f64,
    /// See `mf_tol`.
    pub(super) mf_max_products: usize,
}

/// The principal sub-block `scale · op[idx, idx]` of a Delassus operator, applied by
/// products with the whole operator ([`Delassus::mul_add`]: stored columns, or through
/// the factor): what the matrix-free solvers of [`crate::solvers::global`] see.
pub(super) struct Restricted<'a> {
    pub(super) del: std::cell::RefCell<&'a mut Delassus>,
    pub(super) stiffness: &'a SparseMatrix,
    pub(super) op: Op,
    pub(super) scale: f64,
    pub(super) idx: &'a [usize],
    pub(super) x: std::cell::RefCell<&'a mut [f64]>,
    pub(super) y: std::cell::RefCell<&'a mut [f64]>,
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
        let cap = super::super::sizing::workspace_cap(rows, params);
        Workspace {
            cap,
            idx: Vec::with_capacity(rows),
            block: vec![0.0; cap * cap],
            rhs: vec![0.0; cap],
            solution: vec![0.0; cap],
            slack: vec![0.0; cap],
            equality: vec![false; cap],
            member: vec![false; rows],
            residual: vec![0.0; rows],
            lcp: LcpSolver::new(params.lcp, cap),
            mlcp: Mlcp::with_capacity(cap),
            blocks: Vec::with_capacity(if friction { contacts } else { 0 }),
            friction: FrictionSolver::with_capacity(if friction { cap } else { 0 }),
            over: false,
            mf_from: cap,
            mf_op: (Op::W, 1.0),
            mf_rhs: vec![0.0; if rows > cap { rows } else { 0 }],
            mf_solution: vec![0.0; if rows > cap { rows } else { 0 }],
            mf_slack: vec![0.0; if rows > cap { rows } else { 0 }],
            mf_equality: vec![false; if rows > cap { rows } else { 0 }],
            mf_x: vec![0.0; if rows > cap { rows } else { 0 }],
            mf_y: vec![0.0; if rows > cap { rows } else { 0 }],
            matrix_free: GlobalSolver::with_capacity(if rows > cap { rows } else { 0 }),
            mf_tol: params.friction.tol,
            mf_max_products: params.friction.max_iterations,
        }
    }

    /// The matrix-free fallback, for the path line (empty when every row fits);
    /// `through_f`: its products go through the flexibilities of `G`'s dofs
    /// ([`Delassus::condense_products`]), not through the factor.
    pub fn describe(&self, through_f: bool) -> String {
        if self.matrix_free.capacity() == 0 {
            return String::new();
        }
        format!(
            "; one-step problems of more than {} active rows solved matrix-free on products \
             {} (MPRGP{})",
            self.mf_from,
            if through_f {
                "W x = Bᵀ F (B x)"
            } else {
                "W x = Gᵀ(M̂⁻¹(G x))"
            },
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
    pub(super) fn matrix_free_from(&mut self, rows: usize, params: &SchemeParams) {
        let all = self.member.len();
        if rows >= self.mf_from || all <= rows {
            return;
        }
        self.mf_from = rows;
        if self.matrix_free.capacity() < all {
            self.mf_rhs = vec![0.0; all];
            self.mf_solution = vec![0.0; all];
            self.mf_slack = vec![0.0; all];
            self.mf_equality = vec![false; all];
            self.mf_x = vec![0.0; all];
            self.mf_y = vec![0.0; all];
            self.matrix_free = GlobalSolver::with_capacity(all);
            self.mf_tol = params.friction.tol;
            self.mf_max_products = params.friction.max_iterations;
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
            self.mf_op = (op, scale);
            for (b, &j) in self.idx.iter().enumerate() {
                self.mf_rhs[b] = rhs[j];
                self.mf_solution[b] = warm[j];
                self.mf_equality[b] = eq(j);
            }
            return Ok(());
        }
        for (b, &j) in self.idx.iter().enumerate() {
            for (a, &i) in self.idx.iter().enumerate() {
                self.block[a + b * k] = scale * del.entry(op, i, j);
            }
            self.rhs[b] = rhs[j];
            self.solution[b] = warm[j];
            self.equality[b] = eq(j);
        }
        Ok(())
    }

    /// The restricted operator of the recorded problem over `del`.
    pub(super) fn restricted<'a>(
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
                self.mf_op,
                &self.idx,
                &mut self.mf_x,
                &mut self.mf_y,
            );
            let info = self.matrix_free.solve_box(
                &a,
                &self.mf_rhs[..k],
                &self.mf_equality[..k],
                &mut self.mf_solution[..k],
                &mut self.mf_slack[..k],
                self.mf_tol,
                self.mf_max_products,
            );
            stats.global_solves += 1;
            stats.global_products += info.products;
            if !info.converged {
                return Err(SolveError::Cap {
                    cap: self.mf_max_products,
                    residual: info.residual,
                });
            }
            return Ok(SolveInfo {
                iterations: info.products,
                residual: info.accuracy,
            });
        }
        if self.equality[..k].iter().any(|&e| e) {
            self.mlcp.solve(
                &self.block[..k * k],
                k,
                &self.rhs[..k],
                &self.equality[..k],
                &mut self.lcp,
                &mut self.solution[..k],
                &mut self.slack[..k],
            )
        } else {
            self.lcp.solve(
                &self.block[..k * k],
                k,
                &self.rhs[..k],
                &mut self.solution[..k],
                &mut self.slack[..k],
            )
        }
    }

    /// Solves the gathered rows as a Coulomb friction problem over `self.blocks`
    /// (warm start in `z`).
    pub(super) fn solve_friction(
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
                self.mf_op,
                &self.idx,
                &mut self.mf_x,
                &mut self.mf_y,
            );
            let info = self.matrix_free.solve_friction(
                &a,
                &self.mf_rhs[..k],
                &self.blocks,
                &mut self.mf_solution[..k],
                &mut self.mf_slack[..k],
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
        let op = DenseOperator::new(k, &self.block[..k * k]);
        let prob = FrictionProblem {
            w: &op,
            q: &self.rhs[..k],
            blocks: &self.blocks,
        };
        let info =
            self.friction
                .solve(prob, params, &mut self.solution[..k], &mut self.slack[..k])?;
        let acc = crate::solvers::friction::velocity_error(
            &op,
            &self.blocks,
            &self.solution[..k],
            &self.slack[..k],
        );
        Ok((info, acc))
    }

    /// The growth step of `grow_solve` and of Algorithm 2's position problem: appends to
    /// `idx` every row of `candidates` not in it whose `w = rhs + scale·op·z` at the
    /// current solution `z` is violated: `w < −tol` for a complementarity row, `|w| > tol`
    /// (any `w ≠ 0` when `tol = 0`) for a row of `eq`; returns whether any was added.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn add_violated(
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
        self.residual.copy_from_slice(rhs);
        del.mul_add(op, scale, z, &mut self.residual, stiffness);
        let before = self.idx.len();
        for a in candidates {
            let r = self.residual[a];
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
        let z = if self.over {
            &self.mf_solution
        } else {
            &self.solution
        };
        for (a, &i) in self.idx.iter().enumerate() {
            out[i] = z[a];
        }
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
