//! One-step nonsmooth problems: the small dense LCPs and MLCPs that every scheme solves
//! in contact space.
//!
//! - [`lcp::Lemke`]: complementary pivoting, exact up to rounding (finite termination for
//!   P-matrices such as the Delassus blocks `W_αα` of eq. 57 and `GᵀNG` of eq. 58/60).
//! - [`lcp::Pgs`]: projected Gauss–Seidel with tolerance, iteration cap and warm start.
//! - [`lcp::BlockPivoting`]: block principal pivoting for SPD matrices (one dense
//!   Cholesky per guess of the active set, warm-started), falling back to Lemke.
//! - [`global::GlobalSolver`]: matrix-free MPRGP (LCP, MLCP) and accelerated projected
//!   gradient (Coulomb friction) on products `W x` only, for active sets past the dense
//!   workspaces.
//! - [`mlcp::Mlcp`]: the projection problem of Algorithm 2 (eq. 65, 68), with equality
//!   rows (`g^α = 0`, free `τ^α`, for contacts with a positive impulse) and
//!   complementarity rows (`0 ≤ g ⊥ τ ≥ 0`), reduced to an LCP by a Schur complement.
//!
//! All solvers work in caller-sized workspaces allocated once, so the step loop does
//! not allocate. Matrices are dense, column-major, `k × k` with leading dimension `k`.
//! Each returns its iteration count and complementarity residual
//! `max_i |min(z_i, w_i)|` as data.

pub mod friction;
pub mod global;
pub mod lcp;
pub mod mlcp;
pub mod operator;

/// The semismooth Newton friction solver, now a child of [`friction`] (the path kept).
pub use friction::newton;

/// What a one-step solve reports.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SolveInfo {
    /// Pivots (Lemke) or sweeps (PGS).
    pub iterations: usize,
    /// `max_i |min(z_i, w_i)|` computed from the returned `z` and `w = M z + q`.
    pub residual: f64,
}

/// Why a one-step solve failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SolveError {
    /// Lemke's method met an unbounded ray (the matrix is not a P-matrix, or the data
    /// are not finite).
    #[error("Lemke ray termination after {0} pivots (matrix not P or data not finite)")]
    RayTermination(usize),
    /// The iteration cap was reached.
    #[error("iteration cap {cap} reached, residual {residual:e}")]
    Cap {
        /// The cap.
        cap: usize,
        /// Residual at the cap.
        residual: f64,
    },
    /// An equality block was not positive definite.
    #[error("equality block of the MLCP is not positive definite")]
    Singular,
    /// More contacts are active in one step than the per-active-column Delassus pool
    /// holds (see [`crate::delassus`]).
    #[error(
        "more than {cap} contacts active in one step: the per-active-column Delassus pool \
         is full (raise `delassus_pool`, use `delassus = \"dense\"` or fewer candidates)"
    )]
    Capacity {
        /// Columns the pool holds.
        cap: usize,
    },
    /// More contact rows are active in one step than the dense workspaces hold.
    #[error(
        "{active} contact rows active in one step, more than the one-step workspace holds \
         ({cap}; raise `scheme.max_active_rows`)"
    )]
    ActiveRows {
        /// Rows needed.
        active: usize,
        /// Rows the workspace holds.
        cap: usize,
    },
    /// A contact's own normal compliance `W_NN` is not positive.
    #[error(
        "contact row {row} has W_NN = {value:e}: a contact's own compliance must be positive \
         (W = Gᵀ M̂⁻¹ G; zero means the contact moves no mass)"
    )]
    NonPositiveDiagonal {
        /// The block's first row.
        row: usize,
        /// `W_NN`.
        value: f64,
    },
    /// The problem data are not finite.
    #[error("the one-step problem has non-finite data")]
    NonFinite,
}

/// Which LCP algorithm the schemes use.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LcpKind {
    /// Lemke for problems of up to 16 unknowns, block pivoting above (both exact;
    /// default).
    Auto,
    /// Lemke's complementary pivoting (exact).
    Lemke,
    /// Block principal pivoting with warm start, Lemke fallback (exact; for the
    /// symmetric Delassus blocks with many active contacts).
    BlockPivoting,
    /// Projected Gauss–Seidel with the given tolerance and cap.
    Pgs {
        /// Stop when the complementarity residual is below `tol · max(1, |q|∞)`.
        tol: f64,
        /// Maximal number of sweeps.
        max_sweeps: usize,
    },
}

/// Complementarity residual `max_i |min(z_i, w_i)|`.
pub fn complementarity_residual(z: &[f64], w: &[f64]) -> f64 {
    z.iter()
        .zip(w)
        .map(|(&a, &b)| a.min(b).abs())
        .fold(0.0, f64::max)
}

/// `w = M z + q` for a dense column-major `k × k` matrix.
pub fn affine(m: &[f64], k: usize, z: &[f64], q: &[f64], w: &mut [f64]) {
    w[..k].copy_from_slice(&q[..k]);
    for j in 0..k {
        let zj = z[j];
        if zj != 0.0 {
            for i in 0..k {
                w[i] += m[i + j * k] * zj;
            }
        }
    }
}
