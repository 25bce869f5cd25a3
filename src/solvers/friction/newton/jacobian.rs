//! The generalized Jacobian `J = A + B (W + σI)` of the Alart–Curnier function and its
//! factorization: the blocks `A`, `B` of one contact (`ac_block`), ρ per block, and the
//! workspace that holds `W`, `J` dense or sparse with its LU and scratch (`NewtonWork`).

use super::*;

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
pub(super) struct SparseJacobian {
    pub(super) col_ptr: Vec<usize>,
    pub(super) row_idx: Vec<usize>,
    pub(super) values: Vec<f64>,
    /// `W` on the same pattern (its products cost the pattern, not `k²`).
    pub(super) w_values: Vec<f64>,
    /// Per block column β: the block rows α of its non-zero blocks, ascending.
    pub(super) block_rows: Vec<Vec<usize>>,
    pub(super) symbolic: SymbolicLu<usize>,
}

/// `J` dense (column-major `k × k`) or sparse.
pub(super) enum Jacobian {
    Dense(Vec<f64>),
    Sparse(SparseJacobian),
}

/// The data of the Newton methods, sized for up to `capacity` rows: a dense copy of
/// `W`, per-block ρ, `A_α`, `B_α`, `J`, the dense LU's scratch and the work vectors.
/// The step loop keeps one, sized once at set-up ([`FrictionSolver::with_capacity`]),
/// and uses only its dense `J`, so a solve does not allocate; one-step problems build
/// one per solve, sparse where `W` is.
pub(in crate::solvers) struct NewtonWork {
    pub(super) capacity: usize,
    pub(super) k: usize,
    pub(super) wd: Vec<f64>,
    pub(super) rho: Vec<(f64, f64)>,
    pub(super) a: Vec<[f64; 9]>,
    pub(super) b: Vec<[f64; 9]>,
    pub(super) jac: Jacobian,
    /// The dense `J`'s LU scratch (the step loop); `None`: faer's one-shot LU with
    /// its own scratch (one-step problems, multithreaded above 512 rows).
    pub(super) lu: Option<crate::linalg::DenseLu>,
    pub(super) bufs: Buffers,
    pub(super) best: Vec<f64>,
    pub(super) qt: Vec<f64>,
    pub(super) center: Vec<f64>,
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
    pub(in crate::solvers) fn with_capacity(capacity: usize, own_lu: bool) -> Self {
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
    pub(in crate::solvers) fn capacity(&self) -> usize {
        self.capacity
    }

    /// Loads `prob` (its first `k ≤ capacity` rows): `W` dense, ρ per block, and for
    /// `allow_sparse` a sparse `J` on `W`'s block pattern where that pays (allocates).
    pub(super) fn load<W: DelassusOperator + ?Sized>(
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
    pub(super) fn eval<W: DelassusOperator + ?Sized>(
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
    pub(super) fn solve(&mut self, blocks: &[Block], sigma: f64, dir: &mut [f64]) -> bool {
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

    pub(super) fn is_sparse(&self) -> bool {
        matches!(self.jac, Jacobian::Sparse(_))
    }
}

/// ρ of one block: `(1/W_NN, 1/mean W_TT)` for the proximal method, `1/‖W_αα‖₂` on
/// every row for the plain one (Siconos' spectral-norm rule; measured: on
/// spheres-in-a-box it took 70 iterations where the diagonal rule stalled).
pub(super) fn block_rho(wd: &[f64], k: usize, b: &Block, mode: NewtonMode) -> (f64, f64) {
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
