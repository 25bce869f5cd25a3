//! Sparse and small dense linear algebra used by the integrators.
//!
//! Owns:
//! - [`SpdFactor`]: a sparse Cholesky factorization of the iteration matrix
//!   `M̂ = M + hθC + h²θ²K` (eq. 47), computed with faer (AMD ordering, symbolic
//!   analysis once, numeric factorization into a buffer we own) and solved in place
//!   without allocating, so it can be called from `step()`.
//! - [`spmv`] / [`spmv_add`]: `y = A x` for a CSC matrix. Written here rather than
//!   calling `faer::sparse::linalg::matmul::sparse_dense_matmul` because the vectors
//!   are plain slices owned by the integrator and the loop is five lines; faer's
//!   kernel goes through `MatMut` views and a `Par` dispatch that costs more than the
//!   product itself on the 10³-dof bar.
//! - [`DenseCholesky`]: an in-place Cholesky for the small dense blocks of the
//!   one-step problems (the active sub-blocks `W_αα` of the Delassus operator, at
//!   most a few hundred rows). It works on caller-owned buffers, so the MLCP solver
//!   does not allocate inside the step loop.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMat, SparseColMatRef};
use faer::{Conj, MatMut, Par, Side};

use crate::error::Error;

/// Owned sparse matrix type used throughout (compressed sparse columns, `usize` indices).
pub type SparseMatrix = SparseColMat<usize, f64>;

/// Sparse Cholesky factor `A = L Lᵀ` of a symmetric positive definite matrix.
///
/// The symbolic analysis (fill-reducing ordering and elimination tree) is done
/// once in [`SpdFactor::new`]; [`SpdFactor::refactor`] recomputes the numeric values
/// for a matrix with the same pattern (a new time step `h`, or a new tangent).
/// [`SpdFactor::solve_in_place`] does not allocate.
pub struct SpdFactor {
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
    mem: MemBuffer,
    n: usize,
}

impl std::fmt::Debug for SpdFactor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SpdFactor")
            .field("n", &self.n)
            .field("len_val", &self.values.len())
            .finish()
    }
}

impl SpdFactor {
    /// Analyses the pattern of `a` and factors its values. `what` names the matrix
    /// in error messages.
    pub fn new(a: SparseColMatRef<'_, usize, f64>, what: &str) -> Result<Self, Error> {
        let n = a.nrows();
        let symbolic = factorize_symbolic_cholesky(
            a.symbolic(),
            Side::Lower,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .map_err(|e| Error::Numerical(format!("{what}: symbolic Cholesky failed: {e:?}")))?;
        let par = Par::Seq;
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, par),
        ]);
        let values = vec![0.0; symbolic.len_val()];
        let mut this = SpdFactor {
            symbolic,
            values,
            mem: MemBuffer::new(req),
            n,
        };
        this.refactor(a, what)?;
        Ok(this)
    }

    /// Recomputes the numeric factor for a matrix with the pattern given to [`SpdFactor::new`].
    pub fn refactor(
        &mut self,
        a: SparseColMatRef<'_, usize, f64>,
        what: &str,
    ) -> Result<(), Error> {
        self.symbolic
            .factorize_numeric_llt::<f64>(
                &mut self.values,
                a,
                Side::Lower,
                LltRegularization::default(),
                Par::Seq,
                MemStack::new(&mut self.mem),
                Default::default(),
            )
            .map_err(|e| {
                Error::Numerical(format!(
                    "{what} is not positive definite (Cholesky failed: {e:?}); check that the mass \
                     matrix has no zero rows and that the material parameters are positive"
                ))
            })?;
        Ok(())
    }

    /// Order of the factored matrix.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Overwrites `x` with `A⁻¹ x`. Does not allocate.
    pub fn solve_in_place(&mut self, x: &mut [f64]) {
        debug_assert_eq!(x.len(), self.n);
        let llt = LltRef::<usize, f64>::new(&self.symbolic, &self.values);
        let rhs = MatMut::from_column_major_slice_mut(x, self.n, 1);
        llt.solve_in_place_with_conj(Conj::No, rhs, Par::Seq, MemStack::new(&mut self.mem));
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
        if xj == 0.0 {
            continue;
        }
        let s = alpha * xj;
        for k in col_ptr[j]..col_ptr[j + 1] {
            y[row_idx[k]] += val[k] * s;
        }
    }
}

/// `xᵀ A x` for a symmetric CSC matrix. Does not allocate.
pub fn quadratic_form(a: SparseColMatRef<'_, usize, f64>, x: &[f64]) -> f64 {
    let col_ptr = a.col_ptr();
    let row_idx = a.row_idx();
    let val = a.val();
    let mut s = 0.0;
    for (j, &xj) in x.iter().enumerate() {
        let mut c = 0.0;
        for k in col_ptr[j]..col_ptr[j + 1] {
            c += val[k] * x[row_idx[k]];
        }
        s += c * xj;
    }
    s
}

/// Dot product of two slices.
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// In-place Cholesky `A = L Lᵀ` of a small dense SPD matrix stored column-major in
/// the leading `k × k` block of a buffer with leading dimension `ld`.
///
/// See the module doc for why this is written here.
pub struct DenseCholesky;

impl DenseCholesky {
    /// Factors the leading `k × k` block of `a` (column-major, leading dimension `ld`)
    /// in place; only the lower triangle is read and written. Returns `false` if a
    /// pivot is not positive (the block is not SPD to working precision).
    pub fn factor(a: &mut [f64], ld: usize, k: usize) -> bool {
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

    /// Solves `L Lᵀ x = b` in place with a factor produced by [`DenseCholesky::factor`].
    pub fn solve(l: &[f64], ld: usize, k: usize, x: &mut [f64]) {
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

    #[test]
    fn dense_cholesky_matches_known_solution() {
        // A = [[4,2],[2,3]], x = [1,-1] -> b = [2, -1]
        let mut a = vec![4.0, 2.0, 2.0, 3.0];
        assert!(DenseCholesky::factor(&mut a, 2, 2));
        let mut x = vec![2.0, -1.0];
        DenseCholesky::solve(&a, 2, 2, &mut x);
        assert!((x[0] - 1.0).abs() < 1e-15 && (x[1] + 1.0).abs() < 1e-15);
        let mut bad = vec![1.0, 2.0, 2.0, 1.0];
        assert!(!DenseCholesky::factor(&mut bad, 2, 2));
    }
}
