//! The Cholesky factorization of the step matrix `M̂ = M + hθC + h²θ²K` (eq. 47):
//! faer's sparse Cholesky (symbolic analysis once, numeric factorization into a buffer
//! owned here), or the tridiagonal `L D Lᵀ` of 1-D chains; solved in place without
//! allocating, one right-hand side or blocks of them.

use super::*;

/// Right-hand sides that [`SpdFactor::solve_block_in_place`] solves together: a
/// supernodal solve of 16 columns runs as dense matrix–matrix kernels and costs a
/// fraction of 16 single solves (see `cargo bench --bench kernels`).
pub const SOLVE_BLOCK: usize = 16;

/// Cholesky factor of a symmetric positive definite sparse matrix.
///
/// Two backends, chosen by the matrix:
/// - tridiagonal (the 1-D bar): our `L D Lᵀ` (`Tridiagonal`'s doc says why);
/// - anything else: faer's sparse Cholesky with AMD ordering. The symbolic analysis is
///   done once in [`SpdFactor::new`]; [`SpdFactor::refactor`] recomputes the numeric
///   values for the same pattern (a new `h`, a new tangent). Simplicial factors are
///   solved by our loops over faer's arrays, supernodal ones by faer.
///
/// [`SpdFactor::solve_in_place`] does not allocate.
pub struct SpdFactor {
    pub(super) n: usize,
    pub(super) backend: Backend,
}

pub(super) enum Backend {
    Tridiagonal(Tridiagonal),
    Faer(Box<FaerLlt>),
}

pub(super) struct FaerLlt {
    /// "AMD" or "nested dissection".
    pub(super) ordering: &'static str,
    /// The symbolic analysis, shared with the factors of other matrices of the same
    /// pattern ([`SpdFactor::analysis`]: the accuracy mode's `M̂(h)` of each step of its
    /// ladder).
    pub(super) symbolic: std::sync::Arc<SymbolicCholesky<usize>>,
    /// A fingerprint of the pattern analysed (`plan::pattern_fingerprint`).
    pub(super) pattern: u64,
    pub(super) values: Vec<f64>,
    pub(super) mem: MemBuffer,
    pub(super) scratch: Vec<f64>,
    /// The permuted block and the update scratch of
    /// [`SpdFactor::solve_sparse_rhs_in_place`] (sized by [`SpdFactor::reserve_sparse_rhs`]).
    pub(super) sparse: (Vec<f64>, Vec<f64>),
    /// Simplicial factors in solve-ready form.
    pub(super) simplicial: Option<SimplicialSolve>,
}

/// `A = L D Lᵀ` of a symmetric tridiagonal matrix, `L` unit lower bidiagonal.
///
/// Written here because on a chain the solve is bound by the latency of its two
/// recurrences, not by arithmetic: faer's general sparse path (and the simplicial
/// loop below) carry a load–multiply–store chain per row, measured at 13.6 ns per row
/// for the 1001-dof bar, while `y_i = r_i − l_i y_{i−1}` and
/// `x_i = y_i/d_i − l_{i+1} x_{i+1}` keep one multiply and one subtraction per row in
/// the chain (4.8 ns per row in the portable arithmetic, 2.8 fused, `cargo bench --bench
/// kernels -- bar_kernels`).
///
/// Where the CPU has fused multiply-add (x86-64 with FMA, every aarch64) and the
/// process has not asked for [`Arithmetic::Portable`], both recurrences run fused
/// (pulp's run-time dispatch, so a build without `target-cpu=native` gets it): one
/// rounding per row instead of two, and half the latency of the chain. The results then
/// differ from the unfused ones by round-off (see [`arithmetic`]).
#[derive(Debug, Default)]
pub(super) struct Tridiagonal {
    /// `l_i` for `i ≥ 1` (`l[0]` unused).
    pub(super) l: Vec<f64>,
    /// `1 / d_i`.
    pub(super) dinv: Vec<f64>,
    /// Solve with fused multiply-add (decided at factorization).
    pub(super) fused: bool,
}

/// The tridiagonal solve's two sweeps (`ADD`: the backward sweep writes `base + x` into
/// `out` and leaves `x` with the forward sweep's values, [`Tridiagonal::solve_add`];
/// else it overwrites `x`), with separate multiply and add, or fused (`FUSED`: compiled
/// for the CPU's vector extension by pulp's dispatch, so `mul_add` is one instruction).
pub(super) struct Sweeps<'a, const ADD: bool, const FUSED: bool> {
    pub(super) l: &'a [f64],
    pub(super) dinv: &'a [f64],
    pub(super) x: &'a mut [f64],
    pub(super) base: &'a [f64],
    pub(super) out: &'a mut [f64],
}

impl<const ADD: bool, const FUSED: bool> pulp::WithSimd for Sweeps<'_, ADD, FUSED> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        let (l, dinv, x, base, out) = (self.l, self.dinv, self.x, self.base, self.out);
        // `a − b c` as the arithmetic asks
        let sub = |a: f64, b: f64, c: f64| if FUSED { (-b).mul_add(c, a) } else { a - b * c };
        let n = x.len();
        let mut y = x[0];
        for i in 1..n {
            y = sub(x[i], l[i], y);
            x[i] = y;
        }
        let mut xn = x[n - 1] * dinv[n - 1];
        let mut put = |i: usize, v: f64, x: &mut [f64]| {
            if ADD {
                out[i] = base[i] + v;
            } else {
                x[i] = v;
            }
        };
        put(n - 1, xn, x);
        for i in (0..n - 1).rev() {
            xn = sub(x[i] * dinv[i], l[i + 1], xn);
            put(i, xn, x);
        }
    }
}

impl Tridiagonal {
    /// Factors a tridiagonal `a`; `Err(i)` if pivot `i` is not positive.
    pub(super) fn factor(a: SparseColMatRef<'_, usize, f64>) -> Result<Self, usize> {
        let n = a.nrows();
        let mut t = Tridiagonal {
            l: vec![0.0; n],
            dinv: vec![0.0; n],
            fused: false,
        };
        t.refactor(a)?;
        Ok(t)
    }

    /// Factors `a` (of the order this factor was built for) into the buffers it owns,
    /// without allocating: `dinv` first holds the diagonal and `l` the subdiagonal.
    pub(super) fn refactor(&mut self, a: SparseColMatRef<'_, usize, f64>) -> Result<(), usize> {
        let n = a.nrows();
        self.fused = arithmetic() == Arithmetic::Fused;
        let (cp, ri, v) = (a.col_ptr(), a.row_idx(), a.val());
        let (l, dinv) = (&mut self.l, &mut self.dinv);
        debug_assert_eq!(l.len(), n);
        l.fill(0.0);
        dinv.fill(0.0);
        for j in 0..n {
            for k in cp[j]..cp[j + 1] {
                let i = ri[k];
                if i == j {
                    dinv[j] += v[k];
                } else if i == j + 1 {
                    l[i] += v[k];
                }
            }
        }
        let mut d_prev = 0.0;
        for i in 0..n {
            let d = if i == 0 {
                dinv[0]
            } else {
                let sub = l[i];
                l[i] = sub / d_prev;
                dinv[i] - l[i] * sub
            };
            if !(d > 0.0 && d.is_finite()) {
                return Err(i);
            }
            dinv[i] = 1.0 / d;
            d_prev = d;
        }
        Ok(())
    }

    pub(super) fn solve(&self, x: &mut [f64]) {
        self.sweeps::<false>(x, &[], &mut []);
    }

    /// `out = base + A⁻¹ x` with the sum formed in the backward sweep (`x` keeps the
    /// forward sweep's values): the same operations as [`Tridiagonal::solve`] then the
    /// sum, in one pass fewer.
    pub(super) fn solve_add(&self, x: &mut [f64], base: &[f64], out: &mut [f64]) {
        assert!(base.len() == x.len() && out.len() == x.len());
        self.sweeps::<true>(x, base, out);
    }

    /// [`Sweeps`] in the factor's arithmetic.
    pub(super) fn sweeps<const ADD: bool>(&self, x: &mut [f64], base: &[f64], out: &mut [f64]) {
        let n = x.len();
        if n == 0 {
            return;
        }
        assert!(self.l.len() == n && self.dinv.len() == n);
        let (l, dinv) = (&self.l[..], &self.dinv[..]);
        if self.fused {
            pulp::Arch::new().dispatch(Sweeps::<ADD, true> {
                l,
                dinv,
                x,
                base,
                out,
            });
        } else {
            // the portable arithmetic: plain code, no dispatch
            pulp::WithSimd::with_simd(
                Sweeps::<ADD, false> {
                    l,
                    dinv,
                    x,
                    base,
                    out,
                },
                pulp::Scalar::new(),
            );
        }
    }
}

/// `L` without its diagonal (CSC) plus the inverse diagonal, extracted from faer's
/// simplicial factor after each numeric factorization.
#[derive(Debug, Default)]
pub(super) struct SimplicialSolve {
    pub(super) dinv: Vec<f64>,
    pub(super) ptr: Vec<usize>,
    pub(super) row: Vec<usize>,
    pub(super) val: Vec<f64>,
}

impl std::fmt::Debug for SpdFactor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SpdFactor")
            .field("n", &self.n)
            .field("backend", &self.backend_name())
            .finish()
    }
}

/// A failed sparse Cholesky factorization in words (faer prints its errors as Rust
/// debug text: `NonPositivePivot { index: 20 }`).
fn llt_reason(e: &faer::linalg::solvers::LltError) -> String {
    match e {
        faer::linalg::solvers::LltError::NonPositivePivot { index } => format!(
            "the Cholesky factorization met a pivot ≤ 0 at row {index} of the reordered matrix"
        ),
    }
}

pub(super) fn not_spd(what: &str, detail: String) -> Error {
    Error::Numerical(format!(
        "{what} is not positive definite ({detail}); check that the mass matrix has no zero \
         rows and that the material parameters are positive"
    ))
}

impl SpdFactor {
    /// Factors `a`, picking the backend (see the type doc). `what` names the matrix in
    /// error messages.
    pub fn new(a: SparseColMatRef<'_, usize, f64>, what: &str) -> Result<Self, Error> {
        Self::with_ordering(a, what, None)
    }

    /// Like [`SpdFactor::new`], with a candidate fill-reducing order of the unknowns
    /// (position → unknown, e.g. [`crate::model::ordering::nested_dissection`]): both it
    /// and AMD are analysed symbolically and the one whose factor has fewer entries is
    /// kept ([`SpdFactor::backend_name`] says which).
    pub fn with_ordering(
        a: SparseColMatRef<'_, usize, f64>,
        what: &str,
        ordering: Option<&DofOrdering>,
    ) -> Result<Self, Error> {
        if is_tridiagonal(a) {
            let t = Tridiagonal::factor(a)
                .map_err(|i| not_spd(what, format!("pivot {i} of its LDLᵀ is not positive")))?;
            return Ok(SpdFactor {
                n: a.nrows(),
                backend: Backend::Tridiagonal(t),
            });
        }
        Self::new_general(a, what, ordering)
    }

    /// Factors `a` with faer's sparse Cholesky whatever its pattern (AMD, or
    /// `ordering` where it fills less).
    pub fn new_general(
        a: SparseColMatRef<'_, usize, f64>,
        what: &str,
        ordering: Option<&DofOrdering>,
    ) -> Result<Self, Error> {
        let (symbolic, ordering) = symbolic_choice(a, what, ordering)?;
        Self::factor_on(
            a,
            what,
            SpdAnalysis {
                symbolic: std::sync::Arc::new(symbolic),
                ordering,
                pattern: super::plan::pattern_fingerprint(a),
            },
        )
    }

    /// [`SpdFactor::with_ordering`] on the symbolic analysis of `a`'s pattern made
    /// before ([`super::analyse_spd_kept`] on the same matrix, or another factor's
    /// [`SpdFactor::analysis`]; `None`, or an analysis of another pattern: `a` is
    /// tridiagonal, or analyse it now).
    pub fn with_analysis(
        a: SparseColMatRef<'_, usize, f64>,
        what: &str,
        analysis: Option<SpdAnalysis>,
        ordering: Option<&DofOrdering>,
    ) -> Result<Self, Error> {
        match analysis {
            Some(an)
                if an.symbolic.nrows() == a.nrows()
                    && an.pattern == super::plan::pattern_fingerprint(a) =>
            {
                Self::factor_on(a, what, an)
            }
            _ => Self::with_ordering(a, what, ordering),
        }
    }

    /// The numeric factorization of `a` on its symbolic analysis.
    fn factor_on(
        a: SparseColMatRef<'_, usize, f64>,
        what: &str,
        analysis: SpdAnalysis,
    ) -> Result<Self, Error> {
        let n = a.nrows();
        let SpdAnalysis {
            symbolic,
            ordering: ordering_name,
            pattern,
        } = analysis;
        let req = factor_scratch(&symbolic);
        // the factor's size is known now: check it (and the scratch) before allocating
        let mut mem = crate::limits::MemoryEstimate::default();
        mem.add("Cholesky factor of M̂", symbolic.len_val() as u64, 8);
        mem.add(
            "factorization scratch",
            req.unaligned_bytes_required() as u64,
            1,
        );
        mem.add(
            "assembled matrices and vectors",
            n as u64,
            crate::limits::bytes_per_dof(9, 1),
        );
        mem.check(
            what,
            format!("{n} dofs, {} factor entries", symbolic.len_val()),
        )?;
        let values = vec![0.0; symbolic.len_val()];
        let mut this = SpdFactor {
            n,
            backend: Backend::Faer(Box::new(FaerLlt {
                ordering: ordering_name,
                symbolic,
                pattern,
                values,
                mem: MemBuffer::new(req),
                scratch: vec![0.0; n],
                sparse: (Vec::new(), Vec::new()),
                simplicial: None,
            })),
        };
        this.refactor(a, what)?;
        Ok(this)
    }

    /// The symbolic analysis this factor runs on, for the factor of another matrix of
    /// the same pattern (`None`: a tridiagonal factor, which has none).
    pub fn analysis(&self) -> Option<SpdAnalysis> {
        match &self.backend {
            Backend::Faer(f) => Some(SpdAnalysis {
                symbolic: std::sync::Arc::clone(&f.symbolic),
                ordering: f.ordering,
                pattern: f.pattern,
            }),
            Backend::Tridiagonal(_) => None,
        }
    }

    /// Which backend factored the matrix, for summaries.
    pub fn backend_name(&self) -> String {
        match &self.backend {
            Backend::Tridiagonal(_) => "tridiagonal LDLᵀ".to_string(),
            Backend::Faer(f) => format!(
                "faer {} LLᵀ, {}, nnz(L) = {}",
                if f.simplicial.is_some() {
                    "simplicial"
                } else {
                    "supernodal"
                },
                f.ordering,
                f.symbolic.len_val()
            ),
        }
    }

    /// Recomputes the numeric factor for a matrix with the pattern given to
    /// [`SpdFactor::new`].
    pub fn refactor(
        &mut self,
        a: SparseColMatRef<'_, usize, f64>,
        what: &str,
    ) -> Result<(), Error> {
        let f = match &mut self.backend {
            Backend::Tridiagonal(t) => {
                t.refactor(a)
                    .map_err(|i| not_spd(what, format!("pivot {i} of its LDLᵀ is not positive")))?;
                return Ok(());
            }
            Backend::Faer(f) => f,
        };
        f.symbolic
            .factorize_numeric_llt::<f64>(
                &mut f.values,
                a,
                Side::Lower,
                LltRegularization::default(),
                par_for(f.symbolic.len_val()),
                MemStack::new(&mut f.mem),
                Default::default(),
            )
            .map_err(|e| not_spd(what, llt_reason(&e)))?;
        // the simplicial copy reuses its buffers after the first factorization: a
        // refactorization (the Newton loop's `M̂ⁿ`) does not allocate
        let previous = f.simplicial.take();
        f.simplicial = match f.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(sym) => {
                let (cp, ri) = (sym.col_ptr(), sym.row_idx());
                let n = self.n;
                let mut s = previous.unwrap_or_else(|| SimplicialSolve {
                    dinv: Vec::with_capacity(n),
                    ptr: Vec::with_capacity(n + 1),
                    row: Vec::with_capacity(ri.len() - n),
                    val: Vec::with_capacity(ri.len() - n),
                });
                s.dinv.clear();
                s.ptr.clear();
                s.row.clear();
                s.val.clear();
                s.ptr.push(0);
                for j in 0..n {
                    let r = cp[j]..cp[j + 1];
                    debug_assert_eq!(ri[r.start], j, "diagonal first");
                    s.dinv.push(1.0 / f.values[r.start]);
                    s.row.extend_from_slice(&ri[r.start + 1..r.end]);
                    s.val.extend_from_slice(&f.values[r.start + 1..r.end]);
                    s.ptr.push(s.row.len());
                }
                Some(s)
            }
            SymbolicCholeskyRaw::Supernodal(_) => None,
        };
        Ok(())
    }

    /// Order of the factored matrix.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Overwrites `x` with `A⁻¹ x`. Does not allocate.
    pub fn solve_in_place(&mut self, x: &mut [f64]) {
        debug_assert_eq!(x.len(), self.n);
        let f = match &mut self.backend {
            Backend::Tridiagonal(t) => return t.solve(x),
            Backend::Faer(f) => f,
        };
        if let Some(s) = &f.simplicial {
            match f.symbolic.perm() {
                None => simplicial_solve(s, x),
                Some(p) => {
                    let (fwd, _) = p.arrays();
                    for (y, &i) in f.scratch.iter_mut().zip(fwd) {
                        *y = x[i];
                    }
                    simplicial_solve(s, &mut f.scratch);
                    for (y, &i) in f.scratch.iter().zip(fwd) {
                        x[i] = *y;
                    }
                }
            }
            return;
        }
        let llt = LltRef::<usize, f64>::new(&f.symbolic, &f.values);
        let rhs = MatMut::from_column_major_slice_mut(x, self.n, 1);
        llt.solve_in_place_with_conj(Conj::No, rhs, Par::Seq, MemStack::new(&mut f.mem));
    }

    /// `out = base + A⁻¹ x` ([`LinearSolver::solve_add`]): the tridiagonal factor adds
    /// within its backward sweep and leaves `x` holding the forward sweep's values; the
    /// others solve in place, then add. The same bits either way.
    pub fn solve_add(&mut self, x: &mut [f64], base: &[f64], out: &mut [f64]) {
        debug_assert!(x.len() == self.n && base.len() == self.n && out.len() == self.n);
        if let Backend::Tridiagonal(t) = &self.backend {
            return t.solve_add(x, base, out);
        }
        self.solve_in_place(x);
        for ((o, b), d) in out.iter_mut().zip(base).zip(x.iter()) {
            *o = b + d;
        }
    }

    /// Overwrites the `k` columns of the column-major `n × k` block `x` with `A⁻¹ x`,
    /// one column at a time, so that each column's result does not depend on which
    /// others are solved with it (a supernodal block solve runs dense kernels whose
    /// summation order follows the block's width). The per-active-column Delassus path
    /// computes its columns in batches that a resumed run cannot reproduce (all active
    /// columns at once after a restore, a few per activation before): with block solves
    /// a resumed history differed from the uninterrupted one in the last bits (issue 16
    /// §4, `tests/regression_checkpoint_resume.rs`). Does not allocate.
    pub fn solve_columns_independently(&mut self, x: &mut [f64], k: usize) {
        let n = self.n;
        debug_assert_eq!(x.len(), n * k);
        for col in x.chunks_exact_mut(n.max(1)).take(k) {
            self.solve_in_place(col);
        }
    }

    /// Overwrites the `k` columns of the column-major `n × k` block `x` with `A⁻¹ x`,
    /// [`SOLVE_CHUNK`] columns per faer call, sequentially. Does not allocate (the step
    /// loop's path).
    pub fn solve_block_in_place(&mut self, x: &mut [f64], k: usize) {
        self.solve_block(x, k, false);
    }

    /// Like [`SpdFactor::solve_block_in_place`], with the chunks spread over rayon's
    /// threads when there are several and the factor is large ([`PAR_FACTOR_WORK`]);
    /// each thread gets its own scratch, allocated by this call: for set-ups, not for
    /// the step loop.
    pub fn solve_block_in_place_par(&mut self, x: &mut [f64], k: usize) {
        self.solve_block(x, k, true);
    }

    pub(super) fn solve_block(&mut self, x: &mut [f64], k: usize, allow_par: bool) {
        let n = self.n;
        debug_assert_eq!(x.len(), n * k);
        let supernodal = matches!(&self.backend, Backend::Faer(f) if f.simplicial.is_none());
        if !supernodal {
            for col in x.chunks_exact_mut(n.max(1)) {
                self.solve_in_place(col);
            }
            return;
        }
        let Backend::Faer(f) = &mut self.backend else {
            unreachable!()
        };
        let llt = LltRef::<usize, f64>::new(&f.symbolic, &f.values);
        let solve = |block: &mut [f64], mem: &mut MemBuffer| {
            let cols = block.len() / n;
            let rhs = MatMut::from_column_major_slice_mut(block, n, cols);
            llt.solve_in_place_with_conj(Conj::No, rhs, Par::Seq, MemStack::new(mem));
        };
        if allow_par && k > SOLVE_CHUNK && par_for(f.symbolic.len_val()) != Par::Seq {
            // chunks on rayon's pool, each thread with its own scratch
            use rayon::prelude::*;
            let req = f
                .symbolic
                .solve_in_place_scratch::<f64>(SOLVE_CHUNK, Par::Seq);
            x.par_chunks_mut(n * SOLVE_CHUNK)
                .for_each_init(|| MemBuffer::new(req), |mem, block| solve(block, mem));
        } else {
            for block in x.chunks_mut(n * SOLVE_CHUNK) {
                solve(block, &mut f.mem);
            }
        }
    }
}

/// Factor entries from which the numeric factorization runs on rayon's pool through
/// faer's `Par` (below it the threads cost more than they save). Measured on the
/// 98 304-dof hex8 cube (nnz(L) = 1.9e8): 11.1 s on one thread, 5.8 s on two. The
/// solves stay sequential: they stream the factor and are bound by memory bandwidth,
/// which two threads share (two threads made the cube's blocked solves 15 % slower).
pub const PAR_FACTOR_WORK: usize = 1 << 24;

/// `Par::rayon(0)` (every thread of the current pool) for `work` ≥
/// [`PAR_FACTOR_WORK`] when the pool has more than one thread, else `Par::Seq`.
pub(super) fn par_for(work: usize) -> Par {
    if work >= PAR_FACTOR_WORK && rayon::current_num_threads() > 1 {
        Par::rayon(0)
    } else {
        Par::Seq
    }
}

/// Solves `L Lᵀ x = b` in place (forward then backward sweep over the columns of `L`;
/// multiplying by the stored inverse diagonal keeps a division off the chain).
pub(super) fn simplicial_solve(f: &SimplicialSolve, x: &mut [f64]) {
    let n = x.len();
    for j in 0..n {
        let xj = x[j] * f.dinv[j];
        x[j] = xj;
        for k in f.ptr[j]..f.ptr[j + 1] {
            x[f.row[k]] -= f.val[k] * xj;
        }
    }
    for j in (0..n).rev() {
        let mut s = x[j];
        for k in f.ptr[j]..f.ptr[j + 1] {
            s -= f.val[k] * x[f.row[k]];
        }
        x[j] = s * f.dinv[j];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::Triplet;

    /// The `n × n` tridiagonal matrix with 4 on its diagonal and −1 beside it (κ ≤ 3).
    fn tridiagonal(n: usize) -> SparseMatrix {
        let mut t = Vec::new();
        for i in 0..n {
            t.push(Triplet::new(i, i, 4.0));
            if i + 1 < n {
                t.push(Triplet::new(i, i + 1, -1.0));
                t.push(Triplet::new(i + 1, i, -1.0));
            }
        }
        SparseMatrix::try_new_from_triplets(n, n, &t).unwrap()
    }

    /// The largest error of `f`'s solve of `a x = a x_true`.
    fn solve_error(f: &mut SpdFactor, a: &SparseMatrix, x_true: &[f64]) -> f64 {
        let mut b = vec![0.0; x_true.len()];
        spmv(a.as_ref(), x_true, &mut b);
        f.solve_in_place(&mut b);
        b.iter()
            .zip(x_true)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
    }

    #[test]
    fn sparse_cholesky_solves_a_tridiagonal_system_to_rounding() {
        let n = 50;
        let a = tridiagonal(n);
        let mut f = SpdFactor::new(a.as_ref(), "test").unwrap();
        let x_true: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
        let err = solve_error(&mut f, &a, &x_true);
        // κ(A) ≤ 6/2 = 3, so the backward-stable solve is accurate to a few ulps.
        assert!(err < 1e-14, "err = {err}");
    }

    /// The fused and the separate recurrences of the tridiagonal solve give the same
    /// solution up to round-off (κ ≤ 3: a few ulps), and the fused one is taken only on
    /// a CPU with FMA (else `mul_add` would be a slow library call).
    #[test]
    fn fused_and_portable_tridiagonal_solves_agree_to_rounding() {
        let n = 1001;
        let mut t = Vec::new();
        for i in 0..n {
            t.push(Triplet::new(i, i, 4.0 + (i as f64 * 0.37).sin()));
            if i + 1 < n {
                t.push(Triplet::new(i, i + 1, -1.0));
                t.push(Triplet::new(i + 1, i, -1.0));
            }
        }
        let a = SparseMatrix::try_new_from_triplets(n, n, &t).unwrap();
        let mut tri = Tridiagonal::factor(a.as_ref()).unwrap();
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.1).cos()).collect();
        let solve = |tri: &Tridiagonal| {
            let mut x = b.clone();
            tri.solve(&mut x);
            x
        };
        tri.fused = false;
        let plain = solve(&tri);
        tri.fused = cpu_has_fma();
        let fused = solve(&tri);
        let scale = plain.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let diff = plain
            .iter()
            .zip(&fused)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(diff <= 1e-14 * scale, "{diff:e} of {scale:e}");
        // both solve the system: residual at round-off
        let mut ax = vec![0.0; n];
        spmv(a.as_ref(), &fused, &mut ax);
        let res = ax
            .iter()
            .zip(&b)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(res < 1e-14, "residual {res:e}");
    }

    #[test]
    fn permuted_simplicial_and_symmetric_spmv_paths_agree() {
        // Arrow matrix: a dense first row and column. The natural order fills L
        // completely; AMD moves the hub last, so the permuted path is taken.
        let n = 40;
        let mut t = Vec::new();
        for i in 0..n {
            t.push(Triplet::new(i, i, 2.0 * n as f64));
            if i > 0 {
                t.push(Triplet::new(0, i, 1.0));
                t.push(Triplet::new(i, 0, 1.0));
            }
        }
        let a = SparseMatrix::try_new_from_triplets(n, n, &t).unwrap();
        let mut f = SpdFactor::new(a.as_ref(), "arrow").unwrap();
        match &f.backend {
            Backend::Faer(g) => assert!(g.symbolic.perm().is_some(), "AMD permutes the hub"),
            Backend::Tridiagonal(_) => panic!("an arrow matrix is not tridiagonal"),
        }
        let x_true: Vec<f64> = (0..n).map(|i| 1.0 + (i as f64).cos()).collect();
        let mut b = vec![0.0; n];
        let mut b2 = vec![0.0; n];
        spmv(a.as_ref(), &x_true, &mut b);
        sym_spmv_add(a.as_ref(), 1.0, &x_true, &mut b2);
        assert!(b.iter().zip(&b2).all(|(x, y)| (x - y).abs() < 1e-12));
        f.solve_in_place(&mut b);
        let err = b
            .iter()
            .zip(&x_true)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        // diagonally dominant, κ ≈ 2: rounding level
        assert!(err < 1e-13, "err = {err}");
    }

    #[test]
    fn small_tridiagonal_solves_exactly() {
        // The case that exposed faer's Identity-ordering result (see SpdFactor::new).
        let t = [
            Triplet::new(0, 0, 4.0),
            Triplet::new(1, 1, 4.0),
            Triplet::new(2, 2, 4.0),
            Triplet::new(0, 1, -1.0),
            Triplet::new(1, 0, -1.0),
            Triplet::new(1, 2, -1.0),
            Triplet::new(2, 1, -1.0),
        ];
        let a = SparseMatrix::try_new_from_triplets(3, 3, &t).unwrap();
        for mut f in [
            SpdFactor::new(a.as_ref(), "3x3").unwrap(),
            SpdFactor::new_general(a.as_ref(), "3x3", None).unwrap(),
        ] {
            let mut b = vec![3.0, 2.0, 3.0];
            f.solve_in_place(&mut b);
            assert!(b.iter().all(|x| (x - 1.0).abs() < 1e-15), "{b:?}");
        }
    }

    #[test]
    fn tridiagonal_path_solves_to_rounding() {
        let n = 200;
        let mut t = Vec::new();
        for i in 0..n {
            t.push(Triplet::new(i, i, 2.5 + (i % 7) as f64));
            if i + 1 < n {
                t.push(Triplet::new(i, i + 1, -1.0 - (i % 3) as f64 * 0.3));
                t.push(Triplet::new(i + 1, i, -1.0 - (i % 3) as f64 * 0.3));
            }
        }
        let a = SparseMatrix::try_new_from_triplets(n, n, &t).unwrap();
        let mut f = SpdFactor::new(a.as_ref(), "tri").unwrap();
        assert_eq!(f.backend_name(), "tridiagonal LDLᵀ");
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let mut x1 = b.clone();
        f.solve_in_place(&mut x1);
        let r = max_residual(a.as_ref(), &x1, &b);
        // diagonally dominant (κ ≤ 10): residual at rounding level
        assert!(r < 1e-14, "residual {r}");
        // not SPD: a negative pivot is reported, not a NaN solve
        let bad = SparseMatrix::try_new_from_triplets(
            2,
            2,
            &[Triplet::new(0, 0, 1.0), Triplet::new(1, 1, -1.0)],
        )
        .unwrap();
        assert!(SpdFactor::new(bad.as_ref(), "bad").is_err());
    }

    /// A factor on a shared symbolic analysis (the accuracy mode's `M̂(h)` of another
    /// step) gives the bits of a factor analysed afresh, and a matrix of another pattern
    /// is analysed afresh (its solve accurate to rounding).
    #[test]
    fn a_factor_of_the_same_pattern_shares_its_analysis_bit_for_bit() {
        let k = 12;
        let n = k * k;
        let grid = |s: f64| {
            let mut t = Vec::new();
            for i in 0..k {
                for j in 0..k {
                    let p = i * k + j;
                    t.push(Triplet::new(p, p, 1.0 + 4.0 * s));
                    for (di, dj) in [(0usize, 1usize), (1, 0)] {
                        let (ii, jj) = (i + di, j + dj);
                        if ii < k && jj < k {
                            let q = ii * k + jj;
                            t.push(Triplet::new(p, q, -s));
                            t.push(Triplet::new(q, p, -s));
                        }
                    }
                }
            }
            SparseMatrix::try_new_from_triplets(n, n, &t).unwrap()
        };
        let (a1, a2) = (grid(1.0), grid(2.5));
        let f1 = SpdFactor::new(a1.as_ref(), "test").unwrap();
        assert!(
            matches!(f1.backend, Backend::Faer(_)),
            "a grid is not tridiagonal"
        );
        let mut shared =
            SpdFactor::with_analysis(a2.as_ref(), "test", f1.analysis(), None).unwrap();
        let mut fresh = SpdFactor::new(a2.as_ref(), "test").unwrap();
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.3).sin()).collect();
        let (mut x, mut y) = (b.clone(), b.clone());
        shared.solve_in_place(&mut x);
        fresh.solve_in_place(&mut y);
        assert!(x.iter().zip(&y).all(|(a, b)| a.to_bits() == b.to_bits()));
        // another pattern (a tridiagonal matrix of the same order): analysed afresh
        let a3 = tridiagonal(n);
        let mut other = SpdFactor::with_analysis(a3.as_ref(), "test", f1.analysis(), None).unwrap();
        let err = solve_error(&mut other, &a3, &b);
        // κ ≤ 3 (as above): a few ulps
        assert!(err < 1e-14, "err = {err}");
    }
}
