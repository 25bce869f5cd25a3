//! The linear-solver interface: the [`LinearSolver`] trait every backend of the
//! iteration matrix implements (module doc of `linalg::solver`, which holds the faer
//! backends and the [`factor`](super::solver::factor) that picks one), and
//! [`SolverKind`], the backend a caller asks for. A leaf: the optional MUMPS backend
//! (`linalg::mumps`) implements the trait without reaching back into `solver.rs`.

use faer::sparse::SparseColMatRef;

use crate::error::Error;

/// A factorization of a square sparse matrix that can be refactored for new values on
/// the same pattern and solved in place (module doc).
pub trait LinearSolver: Send {
    /// Order of the factored matrix.
    fn dim(&self) -> usize;
    /// Which backend factored the matrix (for `check` and summaries).
    fn backend_name(&self) -> String;
    /// Recomputes the numeric factor of `a`, whose pattern must be the one the solver
    /// was built on; `what` names the matrix in errors.
    fn refactor(&mut self, a: SparseColMatRef<'_, usize, f64>, what: &str) -> Result<(), Error>;
    /// Overwrites `x` with `A⁻¹ x`.
    fn solve_in_place(&mut self, x: &mut [f64]);
    /// The symbolic analysis this factor runs on, for the factor of another matrix of
    /// its pattern (`None`: the backend keeps none to share).
    fn analysis(&self) -> Option<super::SpdAnalysis> {
        None
    }
    /// `out = base + A⁻¹ x`, leaving `x` as scratch (its content afterwards is not
    /// specified): the free velocity `v_free = v_k + M̂⁻¹ r` of every linear step. The
    /// tridiagonal factor forms it within its backward sweep (one pass over the state
    /// fewer, issue 35); every backend gives the bits of `solve_in_place` then the sum.
    fn solve_add(&mut self, x: &mut [f64], base: &[f64], out: &mut [f64]) {
        self.solve_in_place(x);
        for ((o, b), d) in out.iter_mut().zip(base).zip(x.iter()) {
            *o = b + d;
        }
    }
    /// Overwrites the `k` columns of the column-major `n × k` block `x` with `A⁻¹ x`,
    /// each column alone, so that its result does not depend on the others'.
    fn solve_columns_independently(&mut self, x: &mut [f64], k: usize) {
        let n = self.dim();
        for col in x.chunks_exact_mut(n.max(1)).take(k) {
            self.solve_in_place(col);
        }
    }
    /// Overwrites the `k` columns of `x` with `A⁻¹ x`, several per pass where the
    /// backend has block solves; does not allocate (the step loop's form).
    fn solve_block_in_place(&mut self, x: &mut [f64], k: usize) {
        self.solve_columns_independently(x, k);
    }
    /// Like [`LinearSolver::solve_block_in_place`], spread over rayon's threads where
    /// the backend can (allocates per thread: set-ups only).
    fn solve_block_in_place_par(&mut self, x: &mut [f64], k: usize) {
        self.solve_block_in_place(x, k);
    }
    /// Like [`LinearSolver::solve_block_in_place_par`] where only `rows` of the result
    /// are read (all when `None`; the others are then unspecified): a supernodal factor
    /// skips the blocks that are zero or not needed (`linalg::sparse_rhs`, the zone
    /// flexibilities' set-up); other backends solve every row.
    fn solve_block_for_rows(&mut self, x: &mut [f64], k: usize, rows: Option<&[usize]>) {
        let _ = rows;
        self.solve_block_in_place_par(x, k);
    }
    /// The zone flexibilities `F = SᵀA⁻¹S` and, given `k`, `F_E = SᵀA⁻¹KA⁻¹S` for the
    /// unit columns `S` on the dofs `zone` (`z × z` each, column-major, in the order of
    /// `zone`), without a full sweep per column (`linalg::zone_flex`); `None` where the
    /// backend cannot (the caller then solves the columns).
    fn zone_flexibilities(
        &self,
        zone: &[usize],
        k: Option<SparseColMatRef<'_, usize, f64>>,
    ) -> Option<(Vec<f64>, Vec<f64>)> {
        let _ = (zone, k);
        None
    }
    /// Sizes what [`LinearSolver::solve_sparse_rhs_in_place`] needs for `k` columns
    /// (at set-up; nothing for backends without it).
    fn reserve_sparse_rhs(&mut self, k: usize) {
        let _ = k;
    }
    /// Stored entries of the factor (`nnz(L)`), where the backend knows them: what one
    /// solve reads twice (the cost model of `Delassus::condense_products`).
    fn factor_entries(&self) -> Option<u64> {
        None
    }
    /// Like [`LinearSolver::solve_block_in_place`] for right-hand sides supported on a
    /// few rows: a supernodal factor skips the forward sweep's zero blocks
    /// (`linalg::sparse_rhs`); the same results on every row; does not allocate.
    fn solve_sparse_rhs_in_place(&mut self, x: &mut [f64], k: usize) {
        self.solve_block_in_place(x, k);
    }
}

impl std::fmt::Debug for dyn LinearSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "LinearSolver({}, n = {})",
            self.backend_name(),
            self.dim()
        )
    }
}

/// Which backend a [`factor`](super::solver::factor) call builds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SolverKind {
    /// Symmetric positive definite ([`SpdFactor`](super::SpdFactor)).
    Cholesky,
    /// Symmetric, possibly indefinite ([`SparseLdlt`](super::solver::SparseLdlt)).
    Ldlt,
    /// Any nonsingular matrix ([`SparseLu`](super::solver::SparseLu)).
    Lu,
    /// Any nonsingular matrix, stored dense ([`DenseSolver`](super::solver::DenseSolver)).
    Dense,
}
