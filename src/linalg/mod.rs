//! Sparse and small dense linear algebra used by the integrators.
//!
//! Owns:
//! - [`solver`]: the [`LinearSolver`] trait of the iteration matrix and its backends
//!   (Cholesky, LDLᵀ, sparse LU, dense LU);
//! - [`SpdFactor`]: the Cholesky factorization of the iteration matrix
//!   `M̂ = M + hθC + h²θ²K` (eq. 47): faer's sparse Cholesky (AMD ordering, symbolic
//!   analysis once, numeric factorization into a buffer we own), or our tridiagonal
//!   `L D Lᵀ` for 1-D chains; solved in place without allocating, so it can be
//!   called from `step()`.
//! - [`Arithmetic`]: fused multiply-add in the tridiagonal solve where the CPU has it
//!   (pulp's run-time dispatch), or the portable arithmetic that gives the same bits on
//!   every CPU ([`set_portable_arithmetic`]).
//! - [`subnormals`](mod@subnormals): subnormal numbers flushed to zero on every computing thread of a
//!   run ([`FlushGuard`]), or IEEE gradual underflow ([`set_ieee_subnormals`]).
//! - [`spmv`] / [`spmv_add`] / [`sym_spmv_add`]: `y = A x` for a CSC matrix. Written here rather than
//!   calling `faer::sparse::linalg::matmul::sparse_dense_matmul` because the vectors
//!   are plain slices owned by the integrator and the loop is five lines; faer's
//!   kernel goes through `MatMut` views and a `Par` dispatch that costs more than the
//!   product itself on the 10³-dof bar.
//! - [`DenseCholesky`]: an in-place Cholesky for the small dense blocks of the
//!   one-step problems (the active sub-blocks `W_αα` of the Delassus operator, at
//!   most a few hundred rows). It works on caller-owned buffers, so the MLCP solver
//!   does not allocate inside the step loop.

#[cfg(feature = "mumps")]
pub mod mumps;
pub mod solver;
mod sparse_rhs;
pub mod subnormals;

pub use solver::{LinearSolver, SolverKind};
pub use subnormals::{FlushGuard, Subnormals, set_ieee_subnormals, subnormals};

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMat, SparseColMatRef};
use faer::{Conj, MatMut, MatRef, Par, Side};

use crate::error::Error;

/// Right-hand sides that [`SpdFactor::solve_block_in_place`] solves together: a
/// supernodal solve of 16 columns runs as dense matrix–matrix kernels and costs a
/// fraction of 16 single solves (see `cargo bench --bench kernels`).
pub const SOLVE_BLOCK: usize = 16;

/// Right-hand sides per faer call in [`SpdFactor::solve_block_in_place`]. A supernodal
/// solve streams the whole factor once per call, so on a large factor it is bound by
/// memory bandwidth, and more right-hand sides per pass cost little more than one:
/// on the 98 304-dof cube (nnz(L) = 1.9e8) the 1024 columns of `M̂⁻¹G` took 18.7 s in
/// calls of 16, 15.2 s in calls of 32, 12.9 s in calls of 64 and 13.1 s in calls of
/// 256 (one thread). [`SpdFactor::solve_block_in_place_par`] spreads the chunks over
/// rayon's threads, each with its own scratch: 8.4 s on two threads.
pub const SOLVE_CHUNK: usize = 64;

/// Owned sparse matrix type used throughout (compressed sparse columns, `usize` indices).
pub type SparseMatrix = SparseColMat<usize, f64>;

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
    n: usize,
    backend: Backend,
}

enum Backend {
    Tridiagonal(Tridiagonal),
    Faer(Box<FaerLlt>),
}

struct FaerLlt {
    /// "AMD" or "nested dissection".
    ordering: &'static str,
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
    mem: MemBuffer,
    scratch: Vec<f64>,
    /// The permuted block and the update scratch of
    /// [`SpdFactor::solve_sparse_rhs_in_place`] (sized by [`SpdFactor::reserve_sparse_rhs`]).
    sparse: (Vec<f64>, Vec<f64>),
    /// Simplicial factors in solve-ready form.
    simplicial: Option<SimplicialSolve>,
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
struct Tridiagonal {
    /// `l_i` for `i ≥ 1` (`l[0]` unused).
    l: Vec<f64>,
    /// `1 / d_i`.
    dinv: Vec<f64>,
    /// Solve with fused multiply-add (decided at factorization).
    fused: bool,
}

/// The floating-point arithmetic of the chain recurrences (the tridiagonal solve).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Arithmetic {
    /// Fused multiply-add where the CPU has it: the fastest, but the last bits of a
    /// result depend on the CPU.
    Fused,
    /// Separate multiply and add everywhere: the same bits on every CPU (the golden
    /// histories of `tests/golden/` are this arithmetic's). faer's own kernels (the
    /// sparse Cholesky of solids) choose their instructions at run time in either mode.
    Portable,
}

impl Arithmetic {
    /// The name written to `summary.json` and checkpoints.
    pub fn name(self) -> &'static str {
        match self {
            Arithmetic::Fused => "fused",
            Arithmetic::Portable => "portable",
        }
    }
}

static PORTABLE: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Asks for [`Arithmetic::Portable`] (`true`) or the default (`false`) in factorizations
/// made from now on, process-wide (`signorini --portable-arithmetic`).
pub fn set_portable_arithmetic(on: bool) {
    PORTABLE.store(on, std::sync::atomic::Ordering::Relaxed);
}

/// Whether this CPU has fused multiply-add.
pub fn cpu_has_fma() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::is_x86_feature_detected!("fma")
    }
    #[cfg(target_arch = "aarch64")]
    {
        true
    }
    #[cfg(not(any(target_arch = "x86_64", target_arch = "aarch64")))]
    {
        false
    }
}

/// The arithmetic factorizations made now use: [`Arithmetic::Fused`] where the CPU has
/// FMA unless [`set_portable_arithmetic`] asked otherwise.
pub fn arithmetic() -> Arithmetic {
    if !PORTABLE.load(std::sync::atomic::Ordering::Relaxed) && cpu_has_fma() {
        Arithmetic::Fused
    } else {
        Arithmetic::Portable
    }
}

/// The tridiagonal solve's two sweeps (`ADD`: the backward sweep writes `base + x` into
/// `out` and leaves `x` with the forward sweep's values, [`Tridiagonal::solve_add`];
/// else it overwrites `x`), with separate multiply and add, or fused (`FUSED`: compiled
/// for the CPU's vector extension by pulp's dispatch, so `mul_add` is one instruction).
struct Sweeps<'a, const ADD: bool, const FUSED: bool> {
    l: &'a [f64],
    dinv: &'a [f64],
    x: &'a mut [f64],
    base: &'a [f64],
    out: &'a mut [f64],
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
    /// Whether every entry of `a` lies within one diagonal of the main one.
    fn is_tridiagonal(a: SparseColMatRef<'_, usize, f64>) -> bool {
        let (cp, ri) = (a.col_ptr(), a.row_idx());
        (0..a.ncols()).all(|j| {
            ri[cp[j]..cp[j + 1]]
                .iter()
                .all(|&i| i + 1 >= j && i <= j + 1)
        })
    }

    /// Factors a tridiagonal `a`; `Err(i)` if pivot `i` is not positive.
    fn factor(a: SparseColMatRef<'_, usize, f64>) -> Result<Self, usize> {
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
    fn refactor(&mut self, a: SparseColMatRef<'_, usize, f64>) -> Result<(), usize> {
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

    fn solve(&self, x: &mut [f64]) {
        self.sweeps::<false>(x, &[], &mut []);
    }

    /// `out = base + A⁻¹ x` with the sum formed in the backward sweep (`x` keeps the
    /// forward sweep's values): the same operations as [`Tridiagonal::solve`] then the
    /// sum, in one pass fewer.
    fn solve_add(&self, x: &mut [f64], base: &[f64], out: &mut [f64]) {
        assert!(base.len() == x.len() && out.len() == x.len());
        self.sweeps::<true>(x, base, out);
    }

    /// [`Sweeps`] in the factor's arithmetic.
    fn sweeps<const ADD: bool>(&self, x: &mut [f64], base: &[f64], out: &mut [f64]) {
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
struct SimplicialSolve {
    dinv: Vec<f64>,
    ptr: Vec<usize>,
    row: Vec<usize>,
    val: Vec<f64>,
}

impl std::fmt::Debug for SpdFactor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SpdFactor")
            .field("n", &self.n)
            .field("backend", &self.backend_name())
            .finish()
    }
}

fn not_spd(what: &str, detail: String) -> Error {
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
        ordering: Option<&[usize]>,
    ) -> Result<Self, Error> {
        if Tridiagonal::is_tridiagonal(a) {
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
        ordering: Option<&[usize]>,
    ) -> Result<Self, Error> {
        let n = a.nrows();
        let (symbolic, ordering_name) = symbolic_choice(a, what, ordering)?;
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
            .map_err(|e| not_spd(what, format!("Cholesky failed: {e:?}")))?;
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

    fn solve_block(&mut self, x: &mut [f64], k: usize, allow_par: bool) {
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
fn par_for(work: usize) -> Par {
    if work >= PAR_FACTOR_WORK && rayon::current_num_threads() > 1 {
        Par::rayon(0)
    } else {
        Par::Seq
    }
}

/// Solves `L Lᵀ x = b` in place (forward then backward sweep over the columns of `L`;
/// multiplying by the stored inverse diagonal keeps a division off the chain).
fn simplicial_solve(f: &SimplicialSolve, x: &mut [f64]) {
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

/// `y += alpha A x` for a symmetric CSC matrix, computed row by row (the CSC arrays
/// of a symmetric matrix are its CSR arrays), so `y` is written once per row.
pub fn sym_spmv_add(a: SparseColMatRef<'_, usize, f64>, alpha: f64, x: &[f64], y: &mut [f64]) {
    let col_ptr = a.col_ptr();
    let row_idx = a.row_idx();
    let val = a.val();
    for (i, yi) in y.iter_mut().enumerate() {
        let r = col_ptr[i]..col_ptr[i + 1];
        let s: f64 = row_idx[r.clone()]
            .iter()
            .zip(&val[r])
            .map(|(&j, &v)| v * x[j])
            .sum();
        *yi += alpha * s;
    }
}

/// `y = A x` for a CSC matrix `A` (any shape). Does not allocate.
pub fn spmv(a: SparseColMatRef<'_, usize, f64>, x: &[f64], y: &mut [f64]) {
    y.iter_mut().for_each(|yi| *yi = 0.0);
    spmv_add(a, 1.0, x, y);
}

/// `y += alpha A x` for a CSC matrix `A`. Does not allocate.
pub fn spmv_add(a: SparseColMatRef<'_, usize, f64>, alpha: f64, x: &[f64], y: &mut [f64]) {
    debug_assert_eq!(a.ncols(), x.len());
    debug_assert_eq!(a.nrows(), y.len());
    let col_ptr = a.col_ptr();
    let row_idx = a.row_idx();
    let val = a.val();
    for (j, &xj) in x.iter().enumerate() {
        let s = alpha * xj;
        let r = col_ptr[j]..col_ptr[j + 1];
        for (&i, &v) in row_idx[r.clone()].iter().zip(&val[r]) {
            y[i] += v * s;
        }
    }
}

/// `xᵀ A x` for a CSC matrix (the energies of the history). Does not allocate.
///
/// Matrices with more than [`PAR_QUADRATIC_NNZ`] entries are split into
/// [`QUADRATIC_PARTS`] fixed column ranges summed on rayon's pool and added in order,
/// so the result does not depend on the number of threads (measured on the 97 443-dof
/// hex bar: the two energies of a history row took 9.5 ms on one thread).
pub fn quadratic_form(a: SparseColMatRef<'_, usize, f64>, x: &[f64]) -> f64 {
    let n = x.len();
    if a.compute_nnz() <= PAR_QUADRATIC_NNZ {
        return quadratic_form_cols(a, x, 0..n);
    }
    use rayon::prelude::*;
    let mut parts = [0.0; QUADRATIC_PARTS];
    parts.par_iter_mut().enumerate().for_each(|(p, out)| {
        let r = p * n / QUADRATIC_PARTS..(p + 1) * n / QUADRATIC_PARTS;
        *out = quadratic_form_cols(a, x, r);
    });
    parts.iter().sum()
}

/// Entries above which [`quadratic_form`] runs in parallel.
pub const PAR_QUADRATIC_NNZ: usize = 1 << 18;
/// Column ranges of a parallel [`quadratic_form`].
pub const QUADRATIC_PARTS: usize = 32;

fn quadratic_form_cols(
    a: SparseColMatRef<'_, usize, f64>,
    x: &[f64],
    cols: std::ops::Range<usize>,
) -> f64 {
    let col_ptr = a.col_ptr();
    let row_idx = a.row_idx();
    let val = a.val();
    let mut s = 0.0;
    for j in cols {
        let r = col_ptr[j]..col_ptr[j + 1];
        let c: f64 = row_idx[r.clone()]
            .iter()
            .zip(&val[r])
            .map(|(&i, &v)| v * x[i])
            .sum();
        s += c * x[j];
    }
    s
}

/// `xᵀ A x` for one fixed matrix `A`, its layout read once: the energies of every
/// history row (issue 19 §3).
///
/// [`quadratic_form`] walks the compressed columns, about 10 cycles per column on the
/// bar (three entries each): the history's two energies cost half a step. A symmetric
/// matrix whose rows hold exactly their three diagonals (the 1-D rods) is kept as
/// them and summed as `Σ_j x_j (a_{j−1,j} x_{j−1} + a_jj x_j +
/// a_{j+1,j} x_{j+1})` four columns at a time, which the compiler vectorizes; other
/// matrices keep the column walk. The three-diagonal sum is reordered against a single
/// running sum (four lanes added pairwise), which moves the result by round-off only.
#[derive(Clone, Debug)]
pub enum QuadraticForm {
    /// A symmetric tridiagonal matrix, kept as its three diagonals
    /// ([`TridiagonalRows`], the same arrays the step reads a rod's `K` from).
    Tridiagonal(TridiagonalRows),
    /// Any other pattern: [`quadratic_form`] on the matrix itself.
    General,
}

impl QuadraticForm {
    /// Reads the layout of the square matrix `a` (allocates `3n` values when it is
    /// tridiagonal).
    pub fn new(a: SparseColMatRef<'_, usize, f64>) -> Self {
        if a.ncols() < 4 {
            return QuadraticForm::General;
        }
        TridiagonalRows::new(a).map_or(QuadraticForm::General, QuadraticForm::Tridiagonal)
    }

    /// `xᵀ A x`, `a` the matrix this form was read from. Does not allocate.
    pub fn eval(&self, a: SparseColMatRef<'_, usize, f64>, x: &[f64]) -> f64 {
        match self {
            QuadraticForm::General => quadratic_form(a, x),
            QuadraticForm::Tridiagonal(rows) => {
                // row i of a symmetric matrix is its column i
                // a_{i,i+1} = a_{i+1,i}: the row below's left value
                let (above, diag, below) = (&rows.left, &rows.diag, &rows.left[1..]);
                let n = x.len();
                debug_assert_eq!(diag.len(), n);
                // the first and last columns miss a neighbour
                let ends = x[0] * (diag[0] * x[0] + below[0] * x[1])
                    + x[n - 1] * (above[n - 1] * x[n - 2] + diag[n - 1] * x[n - 1]);
                let m = n - 2;
                let (xl, xc, xr) = (&x[..m], &x[1..=m], &x[2..]);
                let (au, ad, ab) = (&above[1..=m], &diag[1..=m], &below[1..=m]);
                let mut lanes = [0.0; 4];
                let chunks = m / 4;
                for c in 0..chunks {
                    let r = 4 * c..4 * c + 4;
                    let (xl, xc, xr) = (&xl[r.clone()], &xc[r.clone()], &xr[r.clone()]);
                    let (au, ad, ab) = (&au[r.clone()], &ad[r.clone()], &ab[r]);
                    for l in 0..4 {
                        lanes[l] += xc[l] * (au[l] * xl[l] + ad[l] * xc[l] + ab[l] * xr[l]);
                    }
                }
                for j in 4 * chunks..m {
                    lanes[0] += xc[j] * (au[j] * xl[j] + ad[j] * xc[j] + ab[j] * xr[j]);
                }
                ((lanes[0] + lanes[1]) + (lanes[2] + lanes[3])) + ends
            }
        }
    }
}

/// A symmetric matrix whose every row holds exactly its three diagonals (two at the
/// ends): the 1-D rods' `M` and `K`, kept as the diagonals for the history's energies
/// ([`QuadraticForm`]) and so that `h (f − K x)` of the
/// θ-method's free velocity (eq. 18; [`crate::integrators::core`]'s `begin_step`) is a
/// vectorizable pass instead of a gather per row (issue 19 §4).
///
/// Each row sums its three products in the order the stored row does, with the same
/// [`Sum`](std::iter::Sum) of `f64`, so the result is the gather's bit for bit; a
/// matrix with any other stored pattern (a missing off-diagonal entry, an unsorted
/// column, a nonsymmetric value) is not taken.
#[derive(Clone, Debug)]
pub struct TridiagonalRows {
    /// `a_{i,i−1}` (0 for `i = 0`).
    left: Vec<f64>,
    /// `a_ii`.
    diag: Vec<f64>,
    // `a_{i,i+1}` is `left[i + 1]` (symmetry, checked bit for bit): one array fewer to
    // stream per step (issue 35)
}

impl TridiagonalRows {
    /// The rows of the symmetric CSC matrix `a` (`n ≥ 2`) when every column holds
    /// exactly rows `j − 1, j, j + 1` (those that exist) in order and `a` is symmetric
    /// bit for bit; `None` otherwise.
    pub fn new(a: SparseColMatRef<'_, usize, f64>) -> Option<Self> {
        let n = a.ncols();
        if n < 2 || a.nrows() != n {
            return None;
        }
        let (cp, ri, v) = (a.col_ptr(), a.row_idx(), a.val());
        let (mut left, mut diag, mut right) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        for j in 0..n {
            let expect: Vec<usize> = (j.saturating_sub(1)..(j + 2).min(n)).collect();
            if ri[cp[j]..cp[j + 1]] != expect[..] {
                return None;
            }
            for (k, &i) in (cp[j]..cp[j + 1]).zip(&expect) {
                // column j is row j (symmetry checked below)
                match i.cmp(&j) {
                    std::cmp::Ordering::Less => left[j] = v[k],
                    std::cmp::Ordering::Equal => diag[j] = v[k],
                    std::cmp::Ordering::Greater => right[j] = v[k],
                }
            }
        }
        // a_{j+1,j} (below the diagonal of column j) = a_{j,j+1} (above in column j+1)
        let symmetric = (0..n - 1).all(|j| right[j].to_bits() == left[j + 1].to_bits());
        symmetric.then_some(TridiagonalRows { left, diag })
    }

    /// `out_i = h (f_i − (K x)_i)`, each row summed as the CSC gather of the same matrix
    /// would (bit for bit); `f = None` for a load that is `+0.0` everywhere (read as the
    /// constant, not from memory: the same bits). Does not allocate.
    pub fn scaled_residual(&self, h: f64, f: Option<&[f64]>, x: &[f64], out: &mut [f64]) {
        let n = x.len();
        debug_assert!(n >= 2 && out.len() == n && self.diag.len() == n);
        debug_assert!(f.is_none_or(|f| f.len() == n));
        let (l, d, r) = (&self.left, &self.diag, &self.left[1..]);
        let fi = |i: usize| f.map_or(0.0, |f| f[i]);
        let row2 = |a: f64, b: f64| -> f64 { [a, b].into_iter().sum() };
        out[0] = h * (fi(0) - row2(d[0] * x[0], r[0] * x[1]));
        let m = n - 1;
        let lr = (&l[1..m], &d[1..m], &r[1..m]);
        let out_m = &mut out[1..m];
        pulp::Arch::new().dispatch(InteriorRows {
            h,
            out: out_m,
            f: f.map(|f| &f[1..m]),
            lr,
            x,
        });
        out[n - 1] = h * (fi(n - 1) - row2(l[n - 1] * x[n - 2], d[n - 1] * x[n - 1]));
    }

    /// Whether every value of `f` is `+0.0` (what [`TridiagonalRows::scaled_residual`]
    /// may then read as the constant).
    pub fn is_positive_zero(f: &[f64]) -> bool {
        f.iter().all(|x| x.to_bits() == 0)
    }
}

/// The interior rows of [`TridiagonalRows::scaled_residual`], over zipped slices (no
/// bounds checks), compiled by pulp's dispatch for the CPU's vector width: the loop
/// vectorizes across rows while each row's sum keeps its order, and Rust never fuses a
/// multiply and an add on its own, so the bits are those of the plain loop. `f = None`:
/// a load of `+0.0` everywhere, read as the constant (the same bits without the load's
/// stream).
struct InteriorRows<'a> {
    h: f64,
    out: &'a mut [f64],
    f: Option<&'a [f64]>,
    lr: (&'a [f64], &'a [f64], &'a [f64]),
    x: &'a [f64],
}

impl pulp::WithSimd for InteriorRows<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        match self.f {
            Some(f) => interior_rows(self.h, self.out, f.iter().copied(), self.lr, self.x),
            None => interior_rows(self.h, self.out, std::iter::repeat(0.0), self.lr, self.x),
        }
    }
}

/// `out_i = h (f_i − (K x)_i)` over the interior rows, `f` one value per row.
#[inline(always)]
fn interior_rows(
    h: f64,
    out: &mut [f64],
    f: impl Iterator<Item = f64>,
    (l, d, r): (&[f64], &[f64], &[f64]),
    x: &[f64],
) {
    let m = x.len() - 1;
    let rows = out
        .iter_mut()
        .zip(f)
        .zip(l.iter().zip(d).zip(r))
        .zip(x[..m - 1].iter().zip(&x[1..m]).zip(&x[2..]));
    for (((o, fi), ((&li, &di), &ri)), ((&xl, &xc), &xr)) in rows {
        let kx: f64 = [li * xl, di * xc, ri * xr].into_iter().sum();
        *o = h * (fi - kx);
    }
}

/// Dot product summed in four lanes (reordered against [`dot`], so it differs from it
/// by round-off): for diagnostics such as the energies of the history, where a single
/// running sum would wait on every addition. Does not allocate.
pub fn dot_lanes(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut lanes = [0.0; 4];
    let (ac, bc) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ar, br) = (ac.remainder(), bc.remainder());
    for (x, y) in ac.zip(bc) {
        for l in 0..4 {
            lanes[l] += x[l] * y[l];
        }
    }
    for (x, y) in ar.iter().zip(br) {
        lanes[0] += x * y;
    }
    (lanes[0] + lanes[1]) + (lanes[2] + lanes[3])
}

/// Dot product of two slices.
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// In-place Cholesky `A = L Lᵀ` of a dense SPD matrix stored column-major in the
/// leading `k × k` block of a buffer with leading dimension `ld`: the active
/// sub-blocks `W_αα` of the one-step problems. Owns the scratch faer needs, sized at
/// construction, so factoring and solving do not allocate.
///
/// Blocks of fewer than [`DENSE_FAER_MIN`] rows use a plain loop (the bar's one
/// contact, the academic examples' two; no call overhead); larger blocks go to faer's
/// blocked, vectorized Cholesky and triangular solves. Measured on the 98 304-dof cube
/// with 1024 active contacts (`benches/cube_setup.toml`): the loop made the LCP and
/// MLCP 1.4 s of a 2.07 s step; see README for faer's.
pub struct DenseCholesky {
    capacity: usize,
    mem: MemBuffer,
}

impl Clone for DenseCholesky {
    fn clone(&self) -> Self {
        DenseCholesky::with_capacity(self.capacity)
    }
}

impl std::fmt::Debug for DenseCholesky {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "DenseCholesky {{ capacity: {} }}", self.capacity)
    }
}

/// Smallest block [`DenseCholesky`] hands to faer.
pub const DENSE_FAER_MIN: usize = 32;

impl DenseCholesky {
    /// Scratch for blocks of up to `capacity` rows.
    pub fn with_capacity(capacity: usize) -> Self {
        let req = faer::linalg::cholesky::llt::factor::cholesky_in_place_scratch::<f64>(
            capacity.max(1),
            Par::Seq,
            Default::default(),
        );
        DenseCholesky {
            capacity,
            mem: MemBuffer::new(req),
        }
    }

    /// Factors the leading `k × k` block of `a` (column-major, leading dimension `ld`)
    /// in place; only the lower triangle is read and written (the strict upper
    /// triangle may be overwritten by faer's path). Returns `false` if a pivot is not
    /// positive or not finite (the block is not SPD to working precision).
    pub fn factor(&mut self, a: &mut [f64], ld: usize, k: usize) -> bool {
        if k < DENSE_FAER_MIN {
            return small_cholesky(a, ld, k);
        }
        let mat =
            MatMut::from_column_major_slice_with_stride_mut(&mut a[..(k - 1) * ld + k], k, k, ld);
        let ok = faer::linalg::cholesky::llt::factor::cholesky_in_place(
            mat,
            LltRegularization::default(),
            Par::Seq,
            MemStack::new(&mut self.mem),
            Default::default(),
        )
        .is_ok();
        ok && (0..k).all(|j| a[j + j * ld].is_finite() && a[j + j * ld] > 0.0)
    }

    /// Solves `L Lᵀ x = b` in place for the `cols` right-hand sides stored
    /// column-major in `x` (leading dimension `k`), with a factor from
    /// [`DenseCholesky::factor`].
    pub fn solve(&self, l: &[f64], ld: usize, k: usize, x: &mut [f64], cols: usize) {
        if k == 0 || cols == 0 {
            return;
        }
        if k < DENSE_FAER_MIN {
            for c in x.chunks_exact_mut(k).take(cols) {
                small_solve(l, ld, k, c);
            }
            return;
        }
        let lm = MatRef::from_column_major_slice_with_stride(&l[..(k - 1) * ld + k], k, k, ld);
        let rhs = MatMut::from_column_major_slice_mut(&mut x[..k * cols], k, cols);
        faer::linalg::cholesky::llt::solve::solve_in_place_with_conj(
            lm,
            Conj::No,
            rhs,
            Par::Seq,
            MemStack::new(&mut []),
        );
    }
}

fn small_cholesky(a: &mut [f64], ld: usize, k: usize) -> bool {
    for j in 0..k {
        let mut d = a[j + j * ld];
        for p in 0..j {
            d -= a[j + p * ld] * a[j + p * ld];
        }
        if d <= 0.0 || !d.is_finite() {
            return false;
        }
        let d = d.sqrt();
        a[j + j * ld] = d;
        for i in j + 1..k {
            let mut s = a[i + j * ld];
            for p in 0..j {
                s -= a[i + p * ld] * a[j + p * ld];
            }
            a[i + j * ld] = s / d;
        }
    }
    true
}

fn small_solve(l: &[f64], ld: usize, k: usize, x: &mut [f64]) {
    for i in 0..k {
        let mut s = x[i];
        for p in 0..i {
            s -= l[i + p * ld] * x[p];
        }
        x[i] = s / l[i + i * ld];
    }
    for i in (0..k).rev() {
        let mut s = x[i];
        for p in i + 1..k {
            s -= l[p + i * ld] * x[p];
        }
        x[i] = s / l[i + i * ld];
    }
}

/// `max |A x − b|`, for the tests of the solvers.
/// The symbolic Cholesky analysis [`SpdFactor::new_general`] keeps: AMD, or `ordering`
/// (position → unknown) where its factor has fewer entries; with the ordering's name.
fn symbolic_choice(
    a: SparseColMatRef<'_, usize, f64>,
    what: &str,
    ordering: Option<&[usize]>,
) -> Result<(SymbolicCholesky<usize>, &'static str), Error> {
    let n = a.nrows();
    // AMD always: faer 0.24.4's `SymmetricOrdering::Identity` path factors the
    // wrong matrix with `Side::Lower` (a 3×3 tridiagonal [4, −1] gave x = [1.14,
    // 1.55, 1.52] for x = [1, 1, 1]; pinned by a test below), so it is not offered.
    let mut symbolic = factorize_symbolic_cholesky(
        a.symbolic(),
        Side::Lower,
        SymmetricOrdering::Amd,
        CholeskySymbolicParams::default(),
    )
    .map_err(|e| Error::Numerical(format!("{what}: symbolic Cholesky failed: {e:?}")))?;
    let mut ordering_name = "AMD";
    if let Some(fwd) = ordering.filter(|o| o.len() == n && n > 0) {
        let mut inv = vec![usize::MAX; n];
        for (i, &d) in fwd.iter().enumerate() {
            if d < n {
                inv[d] = i;
            }
        }
        if inv.iter().all(|&i| i != usize::MAX) {
            let perm = faer::perm::PermRef::new_checked(fwd, &inv, n);
            if let Ok(nd) = factorize_symbolic_cholesky(
                a.symbolic(),
                Side::Lower,
                SymmetricOrdering::Custom(perm),
                CholeskySymbolicParams::default(),
            ) && nd.len_val() < symbolic.len_val()
            {
                symbolic = nd;
                ordering_name = "nested dissection";
            }
        }
    }
    Ok((symbolic, ordering_name))
}

/// Scratch of the numeric factorization (sequential and threaded) and of the solves.
fn factor_scratch(symbolic: &SymbolicCholesky<usize>) -> StackReq {
    StackReq::any_of(&[
        symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
        symbolic.factorize_numeric_llt_scratch::<f64>(Par::rayon(0), Default::default()),
        symbolic.solve_in_place_scratch::<f64>(SOLVE_CHUNK, Par::Seq),
    ])
}

/// What [`SpdFactor::with_ordering`] would build for `a`, from the symbolic analysis
/// alone (no numeric factorization): the backend's name as
/// [`SpdFactor::backend_name`] gives it, the factor's entries and the scratch bytes.
/// What `signorini check` and the run's memory ledger cost.
pub fn analyse_spd(
    a: SparseColMatRef<'_, usize, f64>,
    what: &str,
    ordering: Option<&[usize]>,
) -> Result<FactorPlan, Error> {
    if Tridiagonal::is_tridiagonal(a) {
        return Ok(FactorPlan {
            backend: "tridiagonal LDLᵀ".to_string(),
            entries: 2 * a.nrows() as u64,
            scratch_bytes: 0,
        });
    }
    let (symbolic, name) = symbolic_choice(a, what, ordering)?;
    Ok(FactorPlan {
        backend: format!(
            "faer {} LLᵀ, {name}, nnz(L) = {}",
            if matches!(symbolic.raw(), SymbolicCholeskyRaw::Simplicial(_)) {
                "simplicial"
            } else {
                "supernodal"
            },
            symbolic.len_val()
        ),
        entries: symbolic.len_val() as u64,
        scratch_bytes: factor_scratch(&symbolic).unaligned_bytes_required() as u64,
    })
}

/// What [`solver::SparseLdlt::new`] would build for `a` (AMD, no pivoting), from the
/// symbolic analysis alone: the factor of a nonlinear structure's symmetric `M̂ⁿ`.
pub fn analyse_ldlt(a: SparseColMatRef<'_, usize, f64>, what: &str) -> Result<FactorPlan, Error> {
    let (symbolic, req) = solver::symbolic_ldlt(a, what)?;
    Ok(FactorPlan {
        backend: format!("faer LDLᵀ, AMD, nnz(L) = {}", symbolic.len_val()),
        entries: symbolic.len_val() as u64,
        scratch_bytes: req.unaligned_bytes_required() as u64,
    })
}

/// The outcome of [`analyse_spd`].
#[derive(Clone, Debug, PartialEq)]
pub struct FactorPlan {
    /// The backend's description.
    pub backend: String,
    /// Entries of the factor (8 bytes each).
    pub entries: u64,
    /// Scratch of the factorization and the solves (bytes).
    pub scratch_bytes: u64,
}

#[cfg(test)]
pub(crate) fn max_residual(a: SparseColMatRef<'_, usize, f64>, x: &[f64], b: &[f64]) -> f64 {
    let mut ax = vec![0.0; b.len()];
    spmv(a, x, &mut ax);
    ax.iter()
        .zip(b)
        .map(|(p, q)| (p - q).abs())
        .fold(0.0, f64::max)
}

/// Partial-pivoting LU of a dense column-major square matrix of up to `capacity`
/// rows, with the permutations and faer's scratch owned and sized at construction, so
/// factoring and solving do not allocate (the coupled position problem of the step
/// loop, [`crate::integrators::core`]). [`dense_lu_solve`] is the allocating
/// one-shot form for one-step problems.
pub struct DenseLu {
    capacity: usize,
    perm: Vec<usize>,
    perm_inv: Vec<usize>,
    mem: MemBuffer,
}

impl std::fmt::Debug for DenseLu {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "DenseLu {{ capacity: {} }}", self.capacity)
    }
}

impl DenseLu {
    /// Scratch for matrices of up to `capacity` rows. Factors one identity of up to
    /// 128 rows on the way: faer's matrix-product kernels read the CPU's cache sizes
    /// from `/sys` (allocating) on their first call in the process, which must not be
    /// the step loop's first solve.
    pub fn with_capacity(capacity: usize) -> Self {
        use faer::linalg::lu::partial_pivoting::{factor, solve};
        let c = capacity.max(1);
        let req = factor::lu_in_place_scratch::<usize, f64>(c, c, Par::Seq, Default::default())
            .or(solve::solve_in_place_scratch::<usize, f64>(c, 1, Par::Seq));
        let mut lu = DenseLu {
            capacity,
            perm: vec![0; c],
            perm_inv: vec![0; c],
            mem: MemBuffer::new(req),
        };
        let w = capacity.min(128);
        let mut eye = vec![0.0; w * w];
        (0..w).for_each(|i| eye[i + i * w] = 1.0);
        let mut b = vec![1.0; w];
        lu.solve(&mut eye, w, &mut b);
        lu
    }

    /// Rows this workspace takes.
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// Solves `a x = b` in place (`a`: the leading `k × k` column-major block,
    /// overwritten by its factors; `b`: `k` values, overwritten by `x`). Returns `false`
    /// (and leaves `b` unspecified) when a pivot is zero or a value is not finite, or
    /// when `k` exceeds the capacity.
    pub fn solve(&mut self, a: &mut [f64], k: usize, b: &mut [f64]) -> bool {
        use faer::linalg::lu::partial_pivoting::{factor, solve};
        if k > self.capacity {
            return false;
        }
        if k == 0 {
            return true;
        }
        let mut lu = MatMut::from_column_major_slice_mut(&mut a[..k * k], k, k);
        let (_, p) = factor::lu_in_place(
            lu.as_mut(),
            &mut self.perm[..k],
            &mut self.perm_inv[..k],
            Par::Seq,
            MemStack::new(&mut self.mem),
            Default::default(),
        );
        let scale = (0..k).fold(0.0_f64, |s, j| s.max(lu[(j, j)].abs()));
        if !(scale.is_finite() && scale > 0.0)
            || (0..k).any(|j| lu[(j, j)].abs() <= 1e-14 * scale || lu[(j, j)].is_nan())
        {
            return false;
        }
        let rhs = MatMut::from_column_major_slice_mut(&mut b[..k], k, 1);
        solve::solve_in_place(
            lu.as_ref(),
            lu.as_ref(),
            p,
            rhs,
            Par::Seq,
            MemStack::new(&mut self.mem),
        );
        b[..k].iter().all(|x| x.is_finite())
    }
}

/// Solves `a x = b` in place for a dense column-major `k × k` `a` (overwritten by its LU
/// factors) by faer's partial-pivoting LU, sequential below 512 rows (the global rayon
/// setting of faer's high-level `partial_piv_lu` cost 0.1–0.3 ms per call on the
/// 3-row FCLIB problems, more than the whole solve). Allocates its scratch: for
/// one-step problems, not for the step loop.
pub fn dense_lu_solve(a: &mut [f64], k: usize, b: &mut [f64]) {
    use faer::linalg::lu::partial_pivoting::{factor, solve};
    let par = if k < 512 { Par::Seq } else { Par::rayon(0) };
    let mut perm = vec![0usize; k];
    let mut perm_inv = vec![0usize; k];
    let req = factor::lu_in_place_scratch::<usize, f64>(k, k, par, Default::default())
        .or(solve::solve_in_place_scratch::<usize, f64>(k, 1, par));
    let mut mem = MemBuffer::new(req);
    let mut lu = faer::MatMut::from_column_major_slice_mut(&mut a[..k * k], k, k);
    let (_, p) = factor::lu_in_place(
        lu.as_mut(),
        &mut perm,
        &mut perm_inv,
        par,
        MemStack::new(&mut mem),
        Default::default(),
    );
    let rhs = faer::MatMut::from_column_major_slice_mut(&mut b[..k], k, 1);
    solve::solve_in_place(
        lu.as_ref(),
        lu.as_ref(),
        p,
        rhs,
        par,
        MemStack::new(&mut mem),
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::Triplet;

    #[test]
    fn sparse_cholesky_solves_a_tridiagonal_system_to_rounding() {
        let n = 50;
        let mut t = Vec::new();
        for i in 0..n {
            t.push(Triplet::new(i, i, 4.0));
            if i + 1 < n {
                t.push(Triplet::new(i, i + 1, -1.0));
                t.push(Triplet::new(i + 1, i, -1.0));
            }
        }
        let a = SparseMatrix::try_new_from_triplets(n, n, &t).unwrap();
        let mut f = SpdFactor::new(a.as_ref(), "test").unwrap();
        let x_true: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
        let mut b = vec![0.0; n];
        spmv(a.as_ref(), &x_true, &mut b);
        f.solve_in_place(&mut b);
        let err = b
            .iter()
            .zip(&x_true)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
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

    /// The rows of a tridiagonal `K` give `h (f − K x)` bit for bit as the CSC gather
    /// (what `begin_step` did), signed zeros included; another pattern is refused.
    #[test]
    fn tridiagonal_rows_equal_the_gather_bit_for_bit() {
        let n = 9;
        let mut t = Vec::new();
        for i in 0..n {
            t.push(Triplet::new(i, i, 2.0 + 0.1 * i as f64));
            if i + 1 < n {
                let off = -1.0 - 0.01 * (i % 4) as f64;
                t.push(Triplet::new(i, i + 1, off));
                t.push(Triplet::new(i + 1, i, off));
            }
        }
        let a = SparseMatrix::try_new_from_triplets(n, n, &t).unwrap();
        let rows = TridiagonalRows::new(a.as_ref()).expect("tridiagonal");
        let gather = |f: &[f64], x: &[f64], out: &mut [f64]| {
            let (cp, ri, v) = (a.col_ptr(), a.row_idx(), a.val());
            for i in 0..n {
                let kx: f64 = (cp[i]..cp[i + 1]).map(|k| v[k] * x[ri[k]]).sum();
                out[i] = 1e-3 * (f[i] - kx);
            }
        };
        for x in [
            (0..n)
                .map(|i| (i as f64 * 0.9).sin() * 1e-5)
                .collect::<Vec<_>>(),
            vec![0.0; n],
            vec![-0.0; n],
            (0..n)
                .map(|i| if i % 2 == 0 { 0.0 } else { -0.0 })
                .collect(),
        ] {
            for f in [
                vec![0.0; n],
                vec![-0.0; n],
                (0..n).map(|i| i as f64).collect(),
            ] {
                let (mut a1, mut a2) = (vec![7.0; n], vec![7.0; n]);
                gather(&f, &x, &mut a1);
                rows.scaled_residual(1e-3, Some(&f), &x, &mut a2);
                for (p, q) in a1.iter().zip(&a2) {
                    assert_eq!(p.to_bits(), q.to_bits(), "{a1:?} vs {a2:?}");
                }
                // a load of +0.0 read as the constant: the same bits (signed zeros too)
                if TridiagonalRows::is_positive_zero(&f) {
                    let mut a3 = vec![7.0; n];
                    rows.scaled_residual(1e-3, None, &x, &mut a3);
                    for (p, q) in a1.iter().zip(&a3) {
                        assert_eq!(p.to_bits(), q.to_bits(), "{a1:?} vs {a3:?}");
                    }
                }
            }
        }
        // a dropped coupling, and a nonsymmetric value, are refused
        let mut u = t.clone();
        u.retain(|e| !(e.row == 3 && e.col == 4));
        let b = SparseMatrix::try_new_from_triplets(n, n, &u).unwrap();
        assert!(TridiagonalRows::new(b.as_ref()).is_none());
        let mut u = t.clone();
        u.push(Triplet::new(3, 4, 1e-9));
        let b = SparseMatrix::try_new_from_triplets(n, n, &u).unwrap();
        assert!(TridiagonalRows::new(b.as_ref()).is_none());
    }

    /// The tridiagonal form and the lane dot product against the column walk and a
    /// plain dot: equal to within the rounding bound of a reordered sum, `2 n ε Σ|terms|`
    /// (Higham, Accuracy and Stability, eq. 3.5, with n terms); a general pattern keeps
    /// the column walk bit for bit; integers (exact in every order) agree exactly.
    #[test]
    fn quadratic_form_paths_agree_to_rounding() {
        for n in [4usize, 5, 7, 8, 1001] {
            let mut t = Vec::new();
            for i in 0..n {
                t.push(Triplet::new(i, i, 2.5 + (i % 7) as f64));
                if i + 1 < n {
                    let off = -1.0 - (i % 3) as f64 * 0.3 - (i % 5) as f64 * 0.2;
                    t.push(Triplet::new(i, i + 1, off));
                    t.push(Triplet::new(i + 1, i, off));
                }
            }
            let a = SparseMatrix::try_new_from_triplets(n, n, &t).unwrap();
            let form = QuadraticForm::new(a.as_ref());
            assert!(matches!(form, QuadraticForm::Tridiagonal(_)), "n = {n}");
            // made nonsymmetric by one entry: the column walk
            let mut u = t.clone();
            u.push(Triplet::new(1, 0, 1e-3));
            let b = SparseMatrix::try_new_from_triplets(n, n, &u).unwrap();
            assert!(matches!(
                QuadraticForm::new(b.as_ref()),
                QuadraticForm::General
            ));
            let x: Vec<f64> = (0..n).map(|i| 1e-4 + (i as f64 * 0.37).sin()).collect();
            let walk = quadratic_form(a.as_ref(), &x);
            let fast = form.eval(a.as_ref(), &x);
            let mut ax = vec![0.0; n];
            spmv(a.as_ref(), &x, &mut ax);
            let terms: f64 = ax.iter().zip(&x).map(|(p, q)| (p * q).abs()).sum();
            let bound = 2.0 * (3 * n) as f64 * f64::EPSILON * (terms + 4.0 * walk.abs());
            assert!((fast - walk).abs() <= bound, "n = {n}: {fast} vs {walk}");
            let xi: Vec<f64> = (0..n).map(|i| (i % 11) as f64 - 5.0).collect();
            let int = SparseMatrix::try_new_from_triplets(
                n,
                n,
                &t.iter()
                    .map(|e| Triplet::new(e.row, e.col, (4.0 * e.val).round()))
                    .collect::<Vec<_>>(),
            )
            .unwrap();
            let fi = QuadraticForm::new(int.as_ref());
            assert_eq!(
                fi.eval(int.as_ref(), &xi),
                quadratic_form(int.as_ref(), &xi)
            );
            let d = dot_lanes(&x, &ax);
            assert!((d - dot(&x, &ax)).abs() <= 2.0 * n as f64 * f64::EPSILON * terms);
        }
        // an arrow matrix is not tridiagonal: the column walk, bit for bit
        let n = 6;
        let mut t: Vec<_> = (0..n).map(|i| Triplet::new(i, i, 4.0 + i as f64)).collect();
        for i in 1..n {
            t.push(Triplet::new(0, i, 0.5));
            t.push(Triplet::new(i, 0, 0.5));
        }
        let a = SparseMatrix::try_new_from_triplets(n, n, &t).unwrap();
        let form = QuadraticForm::new(a.as_ref());
        assert!(matches!(form, QuadraticForm::General));
        let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).cos()).collect();
        assert_eq!(
            form.eval(a.as_ref(), &x).to_bits(),
            quadratic_form(a.as_ref(), &x).to_bits()
        );
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

    #[test]
    fn dense_cholesky_matches_known_solution() {
        // A = [[4,2],[2,3]], x = [1,-1] -> b = [2, -1]
        let mut a = vec![4.0, 2.0, 2.0, 3.0];
        let mut ch = DenseCholesky::with_capacity(2);
        assert!(ch.factor(&mut a, 2, 2));
        let mut x = vec![2.0, -1.0];
        ch.solve(&a, 2, 2, &mut x, 1);
        assert!((x[0] - 1.0).abs() < 1e-15 && (x[1] + 1.0).abs() < 1e-15);
        let mut bad = vec![1.0, 2.0, 2.0, 1.0];
        assert!(!ch.factor(&mut bad, 2, 2));
    }

    /// The faer path (k ≥ DENSE_FAER_MIN) and the loop agree on an SPD block with a
    /// leading dimension larger than k, for several right-hand sides; κ ≈ 3 here, so
    /// both backward-stable solves are within 1e-13 of the exact solution. An
    /// indefinite block is refused by both.
    #[test]
    fn dense_cholesky_paths_agree() {
        let (k, ld, cols) = (70, 73, 3);
        let mut a = vec![0.0; ld * k];
        for j in 0..k {
            for i in 0..k {
                a[i + j * ld] = if i == j {
                    4.0
                } else if i.abs_diff(j) == 1 {
                    -1.0
                } else {
                    0.01 / (1.0 + i.abs_diff(j) as f64)
                };
            }
        }
        let x_true: Vec<f64> = (0..k * cols).map(|i| (i as f64 * 0.37).cos()).collect();
        let mut b = vec![0.0; k * cols];
        for c in 0..cols {
            for i in 0..k {
                b[i + c * k] = (0..k).map(|j| a[i + j * ld] * x_true[j + c * k]).sum();
            }
        }
        let mut ch = DenseCholesky::with_capacity(k);
        let mut fa = a.clone();
        assert!(ch.factor(&mut fa, ld, k));
        let mut x = b.clone();
        ch.solve(&fa, ld, k, &mut x, cols);
        let mut sa = a.clone();
        assert!(small_cholesky(&mut sa, ld, k));
        let mut y = b.clone();
        for c in y.chunks_exact_mut(k) {
            small_solve(&sa, ld, k, c);
        }
        for i in 0..k * cols {
            assert!(
                (x[i] - x_true[i]).abs() < 1e-13,
                "{i}: {} {}",
                x[i],
                x_true[i]
            );
            assert!(
                (y[i] - x_true[i]).abs() < 1e-13,
                "{i}: {} {}",
                y[i],
                x_true[i]
            );
        }
        let mut bad = a.clone();
        bad[5 + 5 * ld] = -1.0;
        assert!(!ch.factor(&mut bad.clone(), ld, k));
        assert!(!small_cholesky(&mut bad, ld, k));
    }
}
