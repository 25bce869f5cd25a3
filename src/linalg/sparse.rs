//! The sparse matrix type and its products: `y = A x`, `y += α A x` and the symmetric
//! half-stored form, and the residual of a sparse system.

use super::*;

/// Owned sparse matrix type used throughout (compressed sparse columns, `usize` indices).
pub type SparseMatrix = SparseColMat<usize, f64>;

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

#[cfg(test)]
pub(crate) fn max_residual(a: SparseColMatRef<'_, usize, f64>, x: &[f64], b: &[f64]) -> f64 {
    let mut ax = vec![0.0; b.len()];
    spmv(a, x, &mut ax);
    ax.iter()
        .zip(b)
        .map(|(p, q)| (p - q).abs())
        .fold(0.0, f64::max)
}
