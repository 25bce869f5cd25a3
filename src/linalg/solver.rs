//! The linear-solver trait of the iteration matrix (`M̂ = M + hθC + h²θ²K` of eq. 47, or
//! its nonlinear `M̂ⁿ` of eq. 48 once the Newton loop refactors it), and its backends.
//!
//! A solver is built on a matrix (symbolic analysis once: ordering, pattern, sizes of
//! every buffer), refactored numerically for new values on the same pattern into the
//! buffers it owns, and solves one or many right-hand sides in place. The Delassus
//! operator ([`crate::delassus::Delassus`]) holds one as a trait object, so it does not
//! depend on which backend factored `M̂`.
//!
//! Backends ([`SolverKind`]):
//! - [`SpdFactor`]: the symmetric positive definite case of every linear scene today:
//!   our tridiagonal `L D Lᵀ` for 1-D chains, faer's sparse Cholesky otherwise;
//! - [`SparseLdlt`]: faer's sparse `L D Lᵀ` (AMD, no pivoting) for symmetric matrices that
//!   are not positive definite (hyperelastic tangents near buckling); a zero pivot is an
//!   error naming the matrix;
//! - [`SparseLu`]: faer's sparse LU with partial pivoting for nonsymmetric iteration
//!   matrices (gyroscopic and follower terms);
//! - [`DenseSolver`]: faer's dense partial-pivoting LU, for systems of a few coordinates
//!   (rigid multibody models), where sparse bookkeeping costs more than the flops;
//! - `Mumps` (cargo feature `mumps`, module `linalg::mumps`): the sparse kinds factored
//!   and solved by MUMPS over the ranks of an MPI job, when the process hosts one
//!   (`signorini run … --mumps` under `mpirun`); [`factor`] then builds it for every
//!   sparse kind.
//!
//! Allocation: after construction, [`LinearSolver::refactor`] and the solves allocate
//! nothing for [`SpdFactor`], [`SparseLdlt`] and [`DenseSolver`]
//! (`tests/no_allocation_in_step.rs`). [`SparseLu`]'s numeric factor has a size that
//! depends on the pivots: faer grows its storage when a refactorization fills more than
//! every earlier one, so it allocates until the largest fill has been met; its solves do
//! not allocate.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
use faer::sparse::SparseColMatRef;
use faer::sparse::linalg::cholesky::{LdltRef, SymbolicCholesky};
use faer::sparse::linalg::lu::{LuRef, NumericLu, SymbolicLu, factorize_symbolic_lu};
use faer::{Conj, MatMut, Par, Side};

pub use super::backend::{LinearSolver, SolverKind};
use super::plan::symbolic_ldlt;
use super::{SOLVE_CHUNK, SpdFactor};
use crate::error::Error;

impl LinearSolver for SpdFactor {
    fn dim(&self) -> usize {
        SpdFactor::dim(self)
    }
    fn backend_name(&self) -> String {
        SpdFactor::backend_name(self)
    }
    fn refactor(&mut self, a: SparseColMatRef<'_, usize, f64>, what: &str) -> Result<(), Error> {
        SpdFactor::refactor(self, a, what)
    }
    fn solve_in_place(&mut self, x: &mut [f64]) {
        SpdFactor::solve_in_place(self, x)
    }
    fn analysis(&self) -> Option<super::SpdAnalysis> {
        SpdFactor::analysis(self)
    }
    fn solve_add(&mut self, x: &mut [f64], base: &[f64], out: &mut [f64]) {
        SpdFactor::solve_add(self, x, base, out)
    }
    fn solve_columns_independently(&mut self, x: &mut [f64], k: usize) {
        SpdFactor::solve_columns_independently(self, x, k)
    }
    fn solve_block_in_place(&mut self, x: &mut [f64], k: usize) {
        SpdFactor::solve_block_in_place(self, x, k)
    }
    fn solve_block_in_place_par(&mut self, x: &mut [f64], k: usize) {
        SpdFactor::solve_block_in_place_par(self, x, k)
    }
    fn solve_block_for_rows(&mut self, x: &mut [f64], k: usize, rows: Option<&[usize]>) {
        SpdFactor::solve_block_for_rows(self, x, k, rows)
    }
    fn zone_flexibilities(
        &self,
        zone: &[usize],
        k: Option<SparseColMatRef<'_, usize, f64>>,
    ) -> Option<(Vec<f64>, Vec<f64>)> {
        SpdFactor::zone_flexibilities(self, zone, k)
    }
    fn factor_entries(&self) -> Option<u64> {
        match &self.backend {
            super::spd::Backend::Faer(f) => Some(f.values.len() as u64),
            super::spd::Backend::Tridiagonal(t) => Some(2 * t.l.len() as u64),
        }
    }
    fn reserve_sparse_rhs(&mut self, k: usize) {
        SpdFactor::reserve_sparse_rhs(self, k)
    }
    fn solve_sparse_rhs_in_place(&mut self, x: &mut [f64], k: usize) {
        SpdFactor::solve_sparse_rhs_in_place(self, x, k)
    }
}

/// Factors `a` with the backend `kind`; `ordering` is a candidate fill-reducing order
/// for the Cholesky backend ([`SpdFactor::with_ordering`]).
pub fn factor(
    a: SparseColMatRef<'_, usize, f64>,
    what: &str,
    kind: SolverKind,
    ordering: Option<&super::DofOrdering>,
) -> Result<Box<dyn LinearSolver>, Error> {
    #[cfg(feature = "mumps")]
    if let Some(f) = super::mumps::factor_if_active(a, what, kind) {
        return f;
    }
    Ok(match kind {
        SolverKind::Cholesky => Box::new(SpdFactor::with_ordering(a, what, ordering)?),
        SolverKind::Ldlt => Box::new(SparseLdlt::new(a, what)?),
        SolverKind::Lu => Box::new(SparseLu::new(a, what)?),
        SolverKind::Dense => Box::new(DenseSolver::new(a, what)?),
    })
}

/// [`factor`] of the SPD `a` ([`SolverKind::Cholesky`]) on the symbolic analysis of its
/// pattern made when the run was planned ([`super::analyse_spd_kept`]), where the
/// backend is faer's.
pub fn factor_spd_analysed(
    a: SparseColMatRef<'_, usize, f64>,
    what: &str,
    ordering: Option<&super::DofOrdering>,
    analysis: Option<super::SpdAnalysis>,
) -> Result<Box<dyn LinearSolver>, Error> {
    #[cfg(feature = "mumps")]
    if let Some(f) = super::mumps::factor_if_active(a, what, SolverKind::Cholesky) {
        return f;
    }
    Ok(Box::new(SpdFactor::with_analysis(
        a, what, analysis, ordering,
    )?))
}

fn square(a: SparseColMatRef<'_, usize, f64>, what: &str) -> Result<usize, Error> {
    if a.nrows() != a.ncols() {
        return Err(Error::Numerical(format!(
            "{what}: {} × {} is not square",
            a.nrows(),
            a.ncols()
        )));
    }
    Ok(a.nrows())
}

/// faer's sparse `L D Lᵀ` of a symmetric matrix (lower triangle read), AMD ordering,
/// no pivoting: for symmetric matrices that need not be positive definite.
pub struct SparseLdlt {
    n: usize,
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
    mem: MemBuffer,
}

impl SparseLdlt {
    /// Analyses and factors `a`.
    pub fn new(a: SparseColMatRef<'_, usize, f64>, what: &str) -> Result<Self, Error> {
        let n = square(a, what)?;
        let (symbolic, req) = symbolic_ldlt(a, what)?;
        let mut mem = crate::limits::MemoryEstimate::default();
        mem.add("LDLᵀ factor", symbolic.len_val() as u64, 8);
        mem.add(
            "factorization scratch",
            req.unaligned_bytes_required() as u64,
            1,
        );
        mem.check(
            what,
            format!("{n} unknowns, {} factor entries", symbolic.len_val()),
        )?;
        let mut this = SparseLdlt {
            n,
            values: vec![0.0; symbolic.len_val()],
            symbolic,
            mem: MemBuffer::new(req),
        };
        LinearSolver::refactor(&mut this, a, what)?;
        Ok(this)
    }
}

impl LinearSolver for SparseLdlt {
    fn dim(&self) -> usize {
        self.n
    }
    fn backend_name(&self) -> String {
        format!("faer LDLᵀ, AMD, nnz(L) = {}", self.symbolic.len_val())
    }
    fn refactor(&mut self, a: SparseColMatRef<'_, usize, f64>, what: &str) -> Result<(), Error> {
        self.symbolic
            .factorize_numeric_ldlt::<f64>(
                &mut self.values,
                a,
                Side::Lower,
                LdltRegularization::default(),
                Par::Seq,
                MemStack::new(&mut self.mem),
                Default::default(),
            )
            .map_err(|e| {
                Error::Numerical(format!(
                    "{what} has a zero pivot in its LDLᵀ ({e:?}): the matrix is singular"
                ))
            })?;
        Ok(())
    }
    fn solve_in_place(&mut self, x: &mut [f64]) {
        self.solve_block_in_place(x, 1);
    }
    fn solve_block_in_place(&mut self, x: &mut [f64], k: usize) {
        let ldlt = LdltRef::<usize, f64>::new(&self.symbolic, &self.values);
        let mem = &mut self.mem;
        in_chunks(x, self.n, k, |rhs| {
            ldlt.solve_in_place_with_conj(Conj::No, rhs, Par::Seq, MemStack::new(mem))
        });
    }
}

/// faer's sparse LU with partial pivoting (COLAMD column order, symbolic analysis
/// once): for nonsymmetric matrices.
pub struct SparseLu {
    n: usize,
    symbolic: SymbolicLu<usize>,
    numeric: NumericLu<usize, f64>,
    mem: MemBuffer,
}

impl SparseLu {
    /// Analyses and factors `a`.
    pub fn new(a: SparseColMatRef<'_, usize, f64>, what: &str) -> Result<Self, Error> {
        let n = square(a, what)?;
        let symbolic = factorize_symbolic_lu(a.symbolic(), Default::default())
            .map_err(|e| Error::Numerical(format!("{what}: symbolic LU failed: {e:?}")))?;
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_lu_scratch::<f64>(Par::Seq, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(SOLVE_CHUNK, Par::Seq),
        ]);
        let mut mem = crate::limits::MemoryEstimate::default();
        mem.add("LU scratch", req.unaligned_bytes_required() as u64, 1);
        mem.add(
            "LU of the matrix (at least A's entries)",
            a.compute_nnz() as u64,
            16,
        );
        mem.check(what, format!("{n} unknowns"))?;
        let mut this = SparseLu {
            n,
            symbolic,
            numeric: NumericLu::new(),
            mem: MemBuffer::new(req),
        };
        LinearSolver::refactor(&mut this, a, what)?;
        Ok(this)
    }
}

impl LinearSolver for SparseLu {
    fn dim(&self) -> usize {
        self.n
    }
    fn backend_name(&self) -> String {
        "faer sparse LU, partial pivoting, COLAMD".to_string()
    }
    fn refactor(&mut self, a: SparseColMatRef<'_, usize, f64>, what: &str) -> Result<(), Error> {
        self.symbolic
            .factorize_numeric_lu::<f64>(
                &mut self.numeric,
                a,
                Par::Seq,
                MemStack::new(&mut self.mem),
                Default::default(),
            )
            .map_err(|e| {
                Error::Numerical(format!("{what}: LU failed ({e:?}): the matrix is singular"))
            })?;
        Ok(())
    }
    fn solve_in_place(&mut self, x: &mut [f64]) {
        self.solve_block_in_place(x, 1);
    }
    fn solve_block_in_place(&mut self, x: &mut [f64], k: usize) {
        // `numeric` is the output of `factorize_numeric_lu` on `symbolic` (refactor)
        let lu = LuRef::<usize, f64>::new_unchecked(&self.symbolic, &self.numeric);
        let mem = &mut self.mem;
        in_chunks(x, self.n, k, |rhs| {
            lu.solve_in_place_with_conj(Conj::No, rhs, Par::Seq, MemStack::new(mem))
        });
    }
}

/// Largest order [`DenseSolver`] takes (an `n²` matrix of 8 MiB): beyond it the sparse
/// backends are the right tool.
pub const DENSE_MAX: usize = 1024;

/// faer's dense partial-pivoting LU of a small matrix, stored column-major in a buffer
/// sized once; for systems of a few coordinates.
pub struct DenseSolver {
    n: usize,
    lu: Vec<f64>,
    perm: Vec<usize>,
    perm_inv: Vec<usize>,
    mem: MemBuffer,
}

impl DenseSolver {
    /// Copies and factors `a` (at most [`DENSE_MAX`] rows).
    pub fn new(a: SparseColMatRef<'_, usize, f64>, what: &str) -> Result<Self, Error> {
        use faer::linalg::lu::partial_pivoting::{factor, solve};
        let n = square(a, what)?;
        if n > DENSE_MAX {
            return Err(Error::invalid(
                "linear solver",
                format!("dense for {what} of {n} rows"),
                &format!("the dense solver takes at most {DENSE_MAX} rows; use a sparse one"),
            ));
        }
        let c = n.max(1);
        let req = factor::lu_in_place_scratch::<usize, f64>(c, c, Par::Seq, Default::default()).or(
            solve::solve_in_place_scratch::<usize, f64>(c, SOLVE_CHUNK, Par::Seq),
        );
        let mut this = DenseSolver {
            n,
            lu: vec![0.0; n * n],
            perm: vec![0; n],
            perm_inv: vec![0; n],
            mem: MemBuffer::new(req),
        };
        LinearSolver::refactor(&mut this, a, what)?;
        Ok(this)
    }
}

impl LinearSolver for DenseSolver {
    fn dim(&self) -> usize {
        self.n
    }
    fn backend_name(&self) -> String {
        format!("faer dense LU, partial pivoting, {} × {}", self.n, self.n)
    }
    fn refactor(&mut self, a: SparseColMatRef<'_, usize, f64>, what: &str) -> Result<(), Error> {
        use faer::linalg::lu::partial_pivoting::factor;
        let n = self.n;
        self.lu.fill(0.0);
        for j in 0..n {
            for (i, v) in a.row_idx_of_col(j).zip(a.val_of_col(j)) {
                self.lu[i + j * n] += v;
            }
        }
        if n == 0 {
            return Ok(());
        }
        let mut lu = MatMut::from_column_major_slice_mut(&mut self.lu, n, n);
        factor::lu_in_place(
            lu.as_mut(),
            &mut self.perm,
            &mut self.perm_inv,
            Par::Seq,
            MemStack::new(&mut self.mem),
            Default::default(),
        );
        let scale = (0..n).fold(0.0_f64, |s, j| s.max(lu[(j, j)].abs()));
        if let Some(j) = (0..n).find(|&j| {
            let p = lu[(j, j)].abs();
            p.is_nan() || p <= 1e-14 * scale || !scale.is_finite() || scale == 0.0
        }) {
            return Err(Error::Numerical(format!(
                "{what}: pivot {j} of its LU is {:e} (largest {scale:e}): the matrix is singular",
                lu[(j, j)]
            )));
        }
        Ok(())
    }
    fn solve_in_place(&mut self, x: &mut [f64]) {
        self.solve_block_in_place(x, 1);
    }
    fn solve_block_in_place(&mut self, x: &mut [f64], k: usize) {
        use faer::linalg::lu::partial_pivoting::solve;
        let n = self.n;
        let lu = faer::MatRef::from_column_major_slice(&self.lu, n, n);
        let p = faer::perm::PermRef::new_checked(&self.perm, &self.perm_inv, n);
        let mem = &mut self.mem;
        in_chunks(x, n, k, |rhs| {
            solve::solve_in_place(lu, lu, p, rhs, Par::Seq, MemStack::new(mem))
        });
    }
}

/// Hands the `k` columns of the column-major `n × k` block `x` to `solve` in chunks of at
/// most [`SOLVE_CHUNK`] columns (one faer call each: block kernels, one scratch).
fn in_chunks(x: &mut [f64], n: usize, k: usize, mut solve: impl FnMut(MatMut<'_, f64>)) {
    if n == 0 {
        return;
    }
    for block in x[..n * k].chunks_mut(n * SOLVE_CHUNK) {
        let cols = block.len() / n;
        solve(MatMut::from_column_major_slice_mut(block, n, cols));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::SparseMatrix;

    /// A matrix from its dense column-major values (entries 0 left out).
    fn sparse(n: usize, a: &[f64]) -> SparseMatrix {
        let mut t = Vec::new();
        for j in 0..n {
            for i in 0..n {
                if a[i + j * n] != 0.0 {
                    t.push(faer::sparse::Triplet::new(i, j, a[i + j * n]));
                }
            }
        }
        SparseMatrix::try_new_from_triplets(n, n, &t).unwrap()
    }

    /// The normwise backward error `‖A x − b‖∞ / (‖A‖∞ ‖x‖∞ + ‖b‖∞)` for the dense `a`.
    fn residual(n: usize, a: &[f64], x: &[f64], b: &[f64]) -> f64 {
        let inf = |v: &[f64]| v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        let mut r: f64 = 0.0;
        let mut norm_a: f64 = 0.0;
        for i in 0..n {
            let ax: f64 = (0..n).map(|j| a[i + j * n] * x[j]).sum();
            r = r.max((ax - b[i]).abs());
            norm_a = norm_a.max((0..n).map(|j| a[i + j * n].abs()).sum());
        }
        r / (norm_a * inf(x) + inf(b))
    }

    /// A 1-D Laplacian plus `shift` on the diagonal (SPD for shift > 0, indefinite for
    /// shift < −λ_min) and, with `skew`, an antisymmetric coupling (nonsymmetric).
    fn test_matrix(n: usize, shift: f64, skew: f64) -> Vec<f64> {
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            a[i + i * n] = 2.0 + shift;
            if i + 1 < n {
                a[i + (i + 1) * n] = -1.0 + skew;
                a[i + 1 + i * n] = -1.0 - skew;
            }
            // a far coupling, so the pattern is not tridiagonal
            if i + 5 < n {
                a[i + (i + 5) * n] = 0.1;
                a[i + 5 + i * n] = 0.1;
            }
        }
        a
    }

    /// Each backend solves its class of matrix to rounding, refactored for new values on
    /// the same pattern, one and several right-hand sides alike: a backward error below
    /// 1e-14, a small multiple of ε = 2.2e-16 (Cholesky, LDLᵀ and partial-pivoting LU are
    /// backward stable with error of order n ε times the growth, here n = 40).
    #[test]
    fn every_backend_solves_its_matrices_to_rounding_after_a_refactor() {
        let n = 40;
        // (kind, first matrix, second matrix on the same pattern)
        let cases = [
            (
                SolverKind::Cholesky,
                test_matrix(n, 0.5, 0.0),
                test_matrix(n, 0.7, 0.0),
            ),
            // 2 − 2.5 + … : about half the eigenvalues negative
            (
                SolverKind::Ldlt,
                test_matrix(n, -2.5, 0.0),
                test_matrix(n, -2.3, 0.0),
            ),
            (
                SolverKind::Lu,
                test_matrix(n, 0.3, 0.4),
                test_matrix(n, -2.5, 0.6),
            ),
            (
                SolverKind::Dense,
                test_matrix(n, 0.3, 0.4),
                test_matrix(n, -2.5, 0.6),
            ),
        ];
        for (kind, a1, a2) in cases {
            let s1 = sparse(n, &a1);
            let mut f = factor(s1.as_ref(), "test", kind, None).unwrap();
            assert_eq!(f.dim(), n);
            for a in [&a1, &a2] {
                let s = sparse(n, a);
                assert_eq!(s.compute_nnz(), s1.compute_nnz(), "same pattern");
                f.refactor(s.as_ref(), "test").unwrap();
                let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin() + 0.1).collect();
                let mut x = b.clone();
                f.solve_in_place(&mut x);
                let r = residual(n, a, &x, &b);
                assert!(
                    r < 1e-14,
                    "{kind:?} ({}): backward error {r:e}",
                    f.backend_name()
                );
                // three right-hand sides: column by column bit for bit (what a resumed
                // run relies on), in one block to rounding (block kernels sum in
                // another order)
                let mut xs: Vec<f64> = (0..3).flat_map(|_| b.iter().copied()).collect();
                let mut xb = xs.clone();
                f.solve_columns_independently(&mut xs, 3);
                f.solve_block_in_place(&mut xb, 3);
                for c in 0..3 {
                    assert_eq!(&xs[c * n..(c + 1) * n], &x[..], "{kind:?} column {c}");
                    let rb = residual(n, a, &xb[c * n..(c + 1) * n], &b);
                    assert!(rb < 1e-14, "{kind:?} block column {c}: {rb:e}");
                }
            }
        }
    }

    /// The Cholesky backend refuses an indefinite matrix, the LDLᵀ and LU backends a
    /// singular one, each naming the matrix; the dense one refuses a size beyond its
    /// cap.
    #[test]
    fn backends_refuse_what_they_cannot_factor() {
        let n = 10;
        let indefinite = sparse(n, &test_matrix(n, -2.5, 0.0));
        let e = factor(indefinite.as_ref(), "M̂", SolverKind::Cholesky, None)
            .err()
            .unwrap();
        assert!(e.to_string().contains("M̂"), "{e}");
        // a zero row and column: singular
        let mut z = test_matrix(n, 0.5, 0.0);
        for i in 0..n {
            z[3 + i * n] = 0.0;
            z[i + 3 * n] = 0.0;
        }
        z[3 + 3 * n] = 0.0;
        let singular = sparse(n, &z);
        for kind in [SolverKind::Ldlt, SolverKind::Dense] {
            let e = factor(singular.as_ref(), "M̂", kind, None).err();
            assert!(e.is_some_and(|e| e.to_string().contains("M̂")), "{kind:?}");
        }
        let big = DENSE_MAX + 1;
        let eye = SparseMatrix::try_new_from_triplets(
            big,
            big,
            &(0..big)
                .map(|i| faer::sparse::Triplet::new(i, i, 1.0))
                .collect::<Vec<_>>(),
        )
        .unwrap();
        let e = factor(eye.as_ref(), "M̂", SolverKind::Dense, None)
            .err()
            .unwrap();
        assert!(e.to_string().contains(&DENSE_MAX.to_string()), "{e}");
    }
}
