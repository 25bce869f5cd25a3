//! Sparse assembly: element matrices to global compressed-column matrices.
//!
//! Element contributions are pushed as triplets into a `nalgebra_sparse::CooMatrix`,
//! converted to CSC by nalgebra-sparse (which sorts and sums duplicates; measured about
//! 2× faster than faer's triplet constructor on a 40³ Laplacian, DESIGN.md §6), and the
//! three CSC arrays are moved into a faer [`SparseMatrix`] without copying.

use faer::sparse::SymbolicSparseColMat;
use nalgebra_sparse::{CooMatrix, CscMatrix};

use crate::linalg::SparseMatrix;

/// Collects element contributions for one global matrix.
pub struct Assembler {
    coo: CooMatrix<f64>,
}

impl Assembler {
    /// An empty `n × n` matrix with room for `capacity` triplets.
    pub fn new(n: usize, capacity: usize) -> Self {
        let mut coo = CooMatrix::new(n, n);
        coo.reserve(capacity);
        Assembler { coo }
    }

    /// Adds the dense element matrix `ke` (row-major access through the closure) at the
    /// global dofs `dofs`.
    pub fn add_element(&mut self, dofs: &[usize], ke: impl Fn(usize, usize) -> f64) {
        for (a, &i) in dofs.iter().enumerate() {
            for (b, &j) in dofs.iter().enumerate() {
                let v = ke(a, b);
                if v != 0.0 {
                    self.coo.push(i, j, v);
                }
            }
        }
    }

    /// Adds a single entry (summed with any other entry at the same place).
    pub fn add(&mut self, i: usize, j: usize, v: f64) {
        self.coo.push(i, j, v);
    }

    /// Sums duplicates and hands the CSC arrays to faer without copying.
    pub fn finish(self) -> SparseMatrix {
        let csc = CscMatrix::from(&self.coo);
        csc_into_faer(csc)
    }
}

/// Moves a nalgebra-sparse CSC matrix into a faer sparse matrix (no copy of the arrays).
pub fn csc_into_faer(csc: CscMatrix<f64>) -> SparseMatrix {
    let (nrows, ncols) = (csc.nrows(), csc.ncols());
    let (col_ptr, row_idx, values) = csc.disassemble();
    let sym = SymbolicSparseColMat::new_checked(nrows, ncols, col_ptr, None, row_idx);
    SparseMatrix::new(sym, values)
}

/// `a·A + b·B + c·C` for square matrices of the same size (used once per time step
/// size to form the iteration matrix `M̂ = M + hθC + h²θ²K`, eq. 47).
pub fn linear_combination(terms: &[(f64, &SparseMatrix)]) -> SparseMatrix {
    let n = terms[0].1.nrows();
    let cap = terms.iter().map(|(_, m)| m.val().len()).sum();
    let mut asm = Assembler::new(n, cap);
    for (s, m) in terms {
        if *s == 0.0 {
            continue;
        }
        let m = m.as_ref();
        for j in 0..m.ncols() {
            for k in m.col_ptr()[j]..m.col_ptr()[j + 1] {
                asm.add(m.row_idx()[k], j, s * m.val()[k]);
            }
        }
    }
    // Keep the diagonal in the pattern even if every term is zero there, so the
    // symbolic factorization sees a structurally full diagonal.
    for i in 0..n {
        asm.add(i, i, 0.0);
    }
    asm.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn duplicates_are_summed_and_arrays_survive_the_move() {
        let mut a = Assembler::new(3, 8);
        a.add_element(&[0, 1], |i, j| if i == j { 1.0 } else { -1.0 });
        a.add_element(&[1, 2], |i, j| if i == j { 2.0 } else { -2.0 });
        let m = a.finish();
        let d = m.to_dense();
        assert_eq!(d[(1, 1)], 3.0);
        assert_eq!(d[(0, 1)], -1.0);
        assert_eq!(d[(2, 1)], -2.0);
        assert_eq!(d[(0, 2)], 0.0);
        assert_eq!(m.compute_nnz(), 7);
    }
}
