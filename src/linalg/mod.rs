//! Sparse and small dense linear algebra used by the integrators.
//!
//! Owns:
//! - [`solver`]: the backends of the iteration matrix (Cholesky, LDLᵀ, sparse LU, dense
//!   LU) behind the [`LinearSolver`] trait (with [`SolverKind`], in `backend`);
//! - [`SpdFactor`]: the Cholesky factorization of the iteration matrix
//!   `M̂ = M + hθC + h²θ²K` (eq. 47): faer's sparse Cholesky (AMD ordering, symbolic
//!   analysis once, numeric factorization into a buffer we own), or our tridiagonal
//!   `L D Lᵀ` for 1-D chains; solved in place without allocating, so it can be
//!   called from `step()`.
//! - [`Arithmetic`]: fused multiply-add in the tridiagonal solve where the CPU has it
//!   (pulp's run-time dispatch), or the portable arithmetic that gives the same bits on
//!   every CPU ([`set_portable_arithmetic`]).
//! - `metis` (feature `metis`): METIS' nested dissection of a graph, a fill-reducing
//!   order offered to the Cholesky of `M̂` beside AMD.
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
//!
//! By file: `spd` (the Cholesky backends and their solves), `plan` (the symbolic
//! analysis), `sparse_rhs` (set-up solves that skip zero blocks), `sparse` (the matrix
//! type and products), `forms` (energies and dots of the step loop), `arith` (FMA or
//! portable arithmetic), `dense` (small dense factorizations), `backend` (the trait and
//! the kinds, a leaf), `solver` (the faer backends and the dispatch), `subnormals`, `metis` and `mumps` (features).

mod arith;
mod backend;
mod dense;
mod forms;
#[cfg(feature = "metis")]
pub mod metis;
#[cfg(feature = "mumps")]
pub mod mumps;
mod plan;
pub mod solver;
mod sparse;
mod sparse_rhs;
mod spd;
pub mod subnormals;
mod zone_flex;

pub use arith::*;
pub use dense::*;
pub use forms::*;
pub use plan::*;
pub use sparse::*;
pub use spd::*;

pub use backend::{LinearSolver, SolverKind};
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

/// Test matrices shared by the factor's unit tests.
#[cfg(test)]
pub(crate) mod test_grids {
    use faer::sparse::Triplet;

    /// Node `(i, j, l)` of body `b` of [`two_grids`]: `b g³ + (i g + j) g + l`.
    pub(crate) fn grid_id(g: usize) -> impl Fn(usize, usize, usize, usize) -> usize + Copy {
        move |b, i, j, l| b * g * g * g + (i * g + j) * g + l
    }

    /// Two uncoupled `g × g × g` grids with the 27-point coupling of a hex8 mesh, as
    /// triplets of both triangles: `diag(c)` on the diagonal and `off(c, o)` between
    /// neighbours (symmetric when `off` is), numbered by [`grid_id`].
    pub(crate) fn two_grids(
        g: usize,
        diag: impl Fn(usize) -> f64,
        off: impl Fn(usize, usize) -> f64,
    ) -> Vec<Triplet<usize, usize, f64>> {
        let id = grid_id(g);
        let mut t = Vec::new();
        for b in 0..2 {
            for i in 0..g {
                for j in 0..g {
                    for l in 0..g {
                        let c = id(b, i, j, l);
                        t.push(Triplet::new(c, c, diag(c)));
                        for (di, dj, dl) in (0..27).map(|q| (q / 9, q / 3 % 3, q % 3)) {
                            let (a, bb, cc) = (i + di, j + dj, l + dl);
                            if (di, dj, dl) == (1, 1, 1) || a < 1 || bb < 1 || cc < 1 {
                                continue;
                            }
                            let (a, bb, cc) = (a - 1, bb - 1, cc - 1);
                            if a < g && bb < g && cc < g {
                                let o = id(b, a, bb, cc);
                                t.push(Triplet::new(c, o, off(c, o)));
                            }
                        }
                    }
                }
            }
        }
        t
    }
}
