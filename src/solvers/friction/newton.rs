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

/// `A_α` and `B_α` (row-major `d × d`) of the Alart–Curnier Jacobian of one block,
/// `dΦ_α = A_α dr_α + B_α du_α`, and `Φ_α`, at `(r_α, u_α)`.
pub(in crate::solvers) fn ac_block(
    r: &[f64],
    u: &[f64],
    mu: f64,
    rho: (f64, f64),
    a: &mut [f64; 9],
    b: &mut [f64; 9],
    phi: &mut [f64],
) {
    let d = r.len();
    *a = [0.0; 9];
    *b = [0.0; 9];
    let (rn, rt) = rho;
    let xn = r[0] - rn * u[0];
    let pn = xn.max(0.0);
    phi[0] = r[0] - pn;
    if xn > 0.0 {
        b[0] = rn;
    } else {
        a[0] = 1.0;
    }
    if d == 1 {
        return;
    }
    let mut xt = [0.0; 2];
    for t in 0..d - 1 {
        xt[t] = r[1 + t] - rt * u[1 + t];
    }
    let nx = xt[..d - 1].iter().map(|x| x * x).sum::<f64>().sqrt();
    let rad = mu * pn;
    if nx <= rad {
        for t in 0..d - 1 {
            phi[1 + t] = rt * u[1 + t];
            b[(1 + t) * d + 1 + t] = rt;
        }
        return;
    }
    let f = rad / nx;
    let mut xh = [0.0; 2];
    for t in 0..d - 1 {
        xh[t] = xt[t] / nx;
        phi[1 + t] = r[1 + t] - rad * xh[t];
    }
    for t in 0..d - 1 {
        let row = 1 + t;
        // −x̂ dR with dR = μ [x_N > 0] (dr_N − ρ_N du_N)
        if xn > 0.0 {
            a[row * d] -= xh[t] * mu;
            b[row * d] += xh[t] * mu * rn;
        }
        // dr_T − f (I − x̂x̂ᵀ)(dr_T − ρ_T du_T)
        a[row * d + row] += 1.0;
        for s in 0..d - 1 {
            let pts = if s == t { 1.0 } else { 0.0 } - xh[t] * xh[s];
            a[row * d + 1 + s] -= f * pts;
            b[row * d + 1 + s] += f * pts * rt;
        }
    }
}

/// The sparse storage of `J`: the block pattern of `W` (plus the diagonal blocks) in
/// compressed columns, and faer's symbolic LU of it.
struct SparseJacobian {
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    values: Vec<f64>,
    /// `W` on the same pattern (its products cost the pattern, not `k²`).
    w_values: Vec<f64>,
    /// Per block column β: the block rows α of its non-zero blocks, ascending.
    block_rows: Vec<Vec<usize>>,
    symbolic: SymbolicLu<usize>,
}

/// `J` dense (column-major `k × k`) or sparse.
enum Jacobian {
    Dense(Vec<f64>),
    Sparse(SparseJacobian),
}

/// The data of the Newton methods, sized for up to `capacity` rows: a dense copy of
/// `W`, per-block ρ, `A_α`, `B_α`, `J`, the dense LU's scratch and the work vectors.
/// The step loop keeps one, sized once at set-up ([`FrictionSolver::with_capacity`]),
/// and uses only its dense `J`, so a solve does not allocate; one-step problems build
/// one per solve, sparse where `W` is.
pub(in crate::solvers) struct NewtonWork {
    capacity: usize,
    k: usize,
    wd: Vec<f64>,
    rho: Vec<(f64, f64)>,
    a: Vec<[f64; 9]>,
    b: Vec<[f64; 9]>,
    jac: Jacobian,
    /// The dense `J`'s LU scratch (the step loop); `None`: faer's one-shot LU with
    /// its own scratch (one-step problems, multithreaded above 512 rows).
    lu: Option<crate::linalg::DenseLu>,
    bufs: Buffers,
    best: Vec<f64>,
    qt: Vec<f64>,
    center: Vec<f64>,
}

impl std::fmt::Debug for NewtonWork {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "NewtonWork {{ capacity: {} }}", self.capacity)
    }
}

impl Clone for NewtonWork {
    fn clone(&self) -> Self {
        NewtonWork::with_capacity(self.capacity, self.lu.is_some())
    }
}

impl NewtonWork {
    /// Buffers for up to `capacity` rows; `own_lu`: the dense LU's scratch too (no
    /// allocation per iteration).
    pub(super) fn with_capacity(capacity: usize, own_lu: bool) -> Self {
        let c = capacity;
        NewtonWork {
            capacity,
            k: 0,
            wd: vec![0.0; c * c],
            rho: vec![(0.0, 0.0); c],
            a: vec![[0.0; 9]; c],
            b: vec![[0.0; 9]; c],
            jac: Jacobian::Dense(if own_lu { vec![0.0; c * c] } else { Vec::new() }),
            lu: own_lu.then(|| crate::linalg::DenseLu::with_capacity(c)),
            bufs: Buffers::new(c),
            best: vec![0.0; c],
            qt: vec![0.0; c],
            center: vec![0.0; c],
        }
    }

    /// Rows this workspace takes.
    pub(super) fn capacity(&self) -> usize {
        self.capacity
    }

    /// Loads `prob` (its first `k ≤ capacity` rows): `W` dense, ρ per block, and for
    /// `allow_sparse` a sparse `J` on `W`'s block pattern where that pays (allocates).
    fn load<W: DelassusOperator + ?Sized>(
        &mut self,
        prob: &FrictionProblem<'_, W>,
        k: usize,
        mode: NewtonMode,
        allow_sparse: bool,
    ) {
        self.k = k;
        let wd = &mut self.wd;
        for c in 0..k {
            for i in 0..k {
                wd[i + c * k] = prob.w.entry(i, c);
            }
        }
        let blocks = prob.blocks;
        for (bi, b) in blocks.iter().enumerate() {
            self.rho[bi] = block_rho(wd, k, b, mode);
        }
        self.bufs.reset();
        if !allow_sparse {
            return;
        }
        if let Jacobian::Dense(j) = &mut self.jac
            && j.len() < k * k
        {
            j.resize(k * k, 0.0);
        }
        // block pattern of W
        let nb = blocks.len();
        let mut block_rows: Vec<Vec<usize>> = vec![Vec::new(); nb];
        let mut nnz_blocks = 0usize;
        for (be, bb) in blocks.iter().enumerate() {
            for (al, ba) in blocks.iter().enumerate() {
                let nz = al == be
                    || (0..bb.dim).any(|j| {
                        (0..ba.dim).any(|i| wd[ba.offset + i + (bb.offset + j) * k] != 0.0)
                    });
                if nz {
                    block_rows[be].push(al);
                    nnz_blocks += 1;
                }
            }
        }
        let sparse = k >= SPARSE_MIN_ROWS
            && (nnz_blocks as f64) <= SPARSE_FRACTION * (nb as f64) * (nb as f64);
        if !sparse {
            return;
        }
        let mut col_ptr = Vec::with_capacity(k + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        for (be, bb) in blocks.iter().enumerate() {
            for _ in 0..bb.dim {
                for &al in &block_rows[be] {
                    let ba = &blocks[al];
                    row_idx.extend(ba.offset..ba.offset + ba.dim);
                }
                col_ptr.push(row_idx.len());
            }
        }
        let sym = SymbolicSparseColMatRef::new_checked(k, k, &col_ptr, None, &row_idx);
        let mut w_values = Vec::with_capacity(row_idx.len());
        for c in 0..k {
            w_values.extend(
                row_idx[col_ptr[c]..col_ptr[c + 1]]
                    .iter()
                    .map(|&i| wd[i + c * k]),
            );
        }
        if let Ok(symbolic) = SymbolicLu::try_new(sym) {
            self.jac = Jacobian::Sparse(SparseJacobian {
                values: vec![0.0; row_idx.len()],
                w_values,
                col_ptr,
                row_idx,
                block_rows,
                symbolic,
            });
        }
    }

    /// `Φ` at `r` for `(W + σI, q)`, `u = (W + σI) r + q`, the blocks `A_α`, `B_α`;
    /// returns `½‖Φ‖²`.
    fn eval<W: DelassusOperator + ?Sized>(
        &mut self,
        prob: &FrictionProblem<'_, W>,
        q: &[f64],
        sigma: f64,
        r: &[f64],
        u: &mut [f64],
        phi: &mut [f64],
    ) -> f64 {
        let (k, blocks) = (self.k, prob.blocks);
        u[..k].copy_from_slice(&q[..k]);
        if let Jacobian::Sparse(sp) = &self.jac {
            for (c, &rc) in r[..k].iter().enumerate() {
                if rc != 0.0 {
                    for p in sp.col_ptr[c]..sp.col_ptr[c + 1] {
                        u[sp.row_idx[p]] += sp.w_values[p] * rc;
                    }
                }
            }
        } else {
            prob.w.mul_add(1.0, &r[..k], &mut u[..k]);
        }
        for i in 0..k {
            u[i] += sigma * r[i];
        }
        for (bi, blk) in blocks.iter().enumerate() {
            let (o, d) = (blk.offset, blk.dim);
            ac_block(
                &r[o..o + d],
                &u[o..o + d],
                blk.mu,
                self.rho[bi],
                &mut self.a[bi],
                &mut self.b[bi],
                &mut phi[o..o + d],
            );
        }
        0.5 * phi[..k].iter().map(|x| x * x).sum::<f64>()
    }

    /// Solves `J dir = rhs` in place (the `A_α`, `B_α` of the last [`NewtonWork::eval`]);
    /// false when `J` is singular.
    fn solve(&mut self, blocks: &[Block], sigma: f64, dir: &mut [f64]) -> bool {
        let NewtonWork {
            k,
            wd,
            a,
            b,
            jac,
            lu,
            ..
        } = self;
        let k = *k;
        // J[o_α + i, c] = Σ_l B_α[i,l] (W + σI)[o_α + l, c] + A_α[i, c − o_α], filled
        // one block (α, column c) at a time: W's column c is contiguous
        let fill = |al: usize, c: usize, out: &mut [f64]| {
            let (o, d) = (blocks[al].offset, blocks[al].dim);
            let (ba, aa) = (&b[al], &a[al]);
            let wc = &wd[o + c * k..o + d + c * k];
            if c >= o && c < o + d {
                for (i, v) in out[..d].iter_mut().enumerate() {
                    let mut s = 0.0;
                    for (l, &w) in wc.iter().enumerate() {
                        let wv = w + if o + l == c { sigma } else { 0.0 };
                        s += ba[i * d + l] * wv;
                    }
                    *v = s + aa[i * d + (c - o)];
                }
            } else if d == 3 {
                // the common case, unrolled (same sums in the same order)
                let (w0, w1, w2) = (wc[0], wc[1], wc[2]);
                for (i, v) in out[..3].iter_mut().enumerate() {
                    *v = 0.0 + ba[3 * i] * w0 + ba[3 * i + 1] * w1 + ba[3 * i + 2] * w2;
                }
            } else {
                for (i, v) in out[..d].iter_mut().enumerate() {
                    let mut s = 0.0;
                    for (l, &w) in wc.iter().enumerate() {
                        s += ba[i * d + l] * w;
                    }
                    *v = s;
                }
            }
        };
        match jac {
            Jacobian::Dense(j) => {
                for c in 0..k {
                    let col = &mut j[c * k..(c + 1) * k];
                    for (al, blk) in blocks.iter().enumerate() {
                        fill(al, c, &mut col[blk.offset..blk.offset + blk.dim]);
                    }
                }
                match lu {
                    Some(lu) => {
                        if !lu.solve(j, k, dir) {
                            return false;
                        }
                    }
                    None => crate::linalg::dense_lu_solve(j, k, dir),
                }
            }
            Jacobian::Sparse(sp) => {
                let mut pos = 0;
                for (be, bb) in blocks.iter().enumerate() {
                    for c in bb.offset..bb.offset + bb.dim {
                        for &al in &sp.block_rows[be] {
                            let d = blocks[al].dim;
                            fill(al, c, &mut sp.values[pos..pos + d]);
                            pos += d;
                        }
                    }
                }
                let sym =
                    SymbolicSparseColMatRef::new_checked(k, k, &sp.col_ptr, None, &sp.row_idx);
                let mat = SparseColMatRef::new(sym, &sp.values);
                let Ok(lu) = Lu::try_new_with_symbolic(sp.symbolic.clone(), mat) else {
                    return false;
                };
                use faer::linalg::solvers::SolveCore;
                let rhs = faer::MatMut::from_column_major_slice_mut(&mut dir[..k], k, 1);
                lu.solve_in_place_with_conj(faer::Conj::No, rhs);
            }
        }
        dir[..k].iter().all(|x| x.is_finite())
    }

    fn is_sparse(&self) -> bool {
        matches!(self.jac, Jacobian::Sparse(_))
    }
}

/// ρ of one block: `(1/W_NN, 1/mean W_TT)` for the proximal method, `1/‖W_αα‖₂` on
/// every row for the plain one (Siconos' spectral-norm rule; measured: on
/// spheres-in-a-box it took 70 iterations where the diagonal rule stalled).
fn block_rho(wd: &[f64], k: usize, b: &Block, mode: NewtonMode) -> (f64, f64) {
    let o = b.offset;
    let at = |i: usize, j: usize| wd[o + i + (o + j) * k];
    match mode {
        NewtonMode::Proximal => {
            let wnn = at(0, 0).abs().max(f64::MIN_POSITIVE);
            let wtt = if b.dim > 1 {
                (1..b.dim).map(|t| at(t, t)).sum::<f64>() / (b.dim - 1) as f64
            } else {
                wnn
            };
            (1.0 / wnn, 1.0 / wtt.abs().max(f64::MIN_POSITIVE))
        }
        NewtonMode::Plain => {
            let m = nalgebra::Matrix3::from_fn(|i, j| {
                if i < b.dim && j < b.dim {
                    0.5 * (at(i, j) + at(j, i))
                } else {
                    0.0
                }
            });
            let norm = m.symmetric_eigenvalues().amax().max(f64::MIN_POSITIVE);
            (1.0 / norm, 1.0 / norm)
        }
    }
}

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
