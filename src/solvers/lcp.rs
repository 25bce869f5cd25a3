//! Linear complementarity problems `w = M z + q, 0 ≤ z ⊥ w ≥ 0`.

use super::{LcpKind, SolveError, SolveInfo, affine, complementarity_residual};

/// Lemke's complementary pivoting method with covering vector `d = 1`.
///
/// Works on a tableau allocated once for problems up to `capacity` unknowns. The
/// pivot cap is `10 (k + 1)²`, far above the `k + 1` pivots a P-matrix LCP of the
/// sizes met here needs; reaching it is reported as [`SolveError::Cap`].
#[derive(Clone, Debug)]
pub struct Lemke {
    capacity: usize,
    tab: Vec<f64>,
    basis: Vec<usize>,
}

impl Lemke {
    /// Workspace for LCPs of size up to `capacity`.
    pub fn with_capacity(capacity: usize) -> Self {
        let cols = 2 * capacity + 2;
        Lemke {
            capacity,
            tab: vec![0.0; capacity.max(1) * cols.max(1)],
            basis: vec![0; capacity],
        }
    }

    /// Solves the `k × k` LCP; `m` column-major with leading dimension `k`.
    /// On success `z` and `w = M z + q` hold the solution.
    pub fn solve(
        &mut self,
        m: &[f64],
        k: usize,
        q: &[f64],
        z: &mut [f64],
        w: &mut [f64],
    ) -> Result<SolveInfo, SolveError> {
        assert!(k <= self.capacity, "Lemke workspace too small");
        z[..k].iter_mut().for_each(|x| *x = 0.0);
        if q[..k].iter().all(|&x| x >= 0.0) {
            w[..k].copy_from_slice(&q[..k]);
            return Ok(SolveInfo {
                iterations: 0,
                residual: 0.0,
            });
        }
        if q[..k].iter().any(|x| !x.is_finite()) || m[..k * k].iter().any(|x| !x.is_finite()) {
            return Err(SolveError::RayTermination(0));
        }
        // Tableau rows: w - M z - d z0 = q. Columns: w (0..k), z (k..2k), z0 (2k), rhs (2k+1).
        let cols = 2 * k + 2;
        let (z0, rhs) = (2 * k, 2 * k + 1);
        let tab = &mut self.tab[..k * cols];
        tab.iter_mut().for_each(|x| *x = 0.0);
        let mut scale: f64 = 1.0;
        for i in 0..k {
            tab[i * cols + i] = 1.0;
            for j in 0..k {
                tab[i * cols + k + j] = -m[i + j * k];
                scale = scale.max(m[i + j * k].abs());
            }
            tab[i * cols + z0] = -1.0;
            tab[i * cols + rhs] = q[i];
            self.basis[i] = i;
        }
        let piv_tol = 1e-14 * scale;
        // First pivot: z0 enters, the most negative q_i leaves.
        let mut r = 0;
        for i in 1..k {
            if q[i] < q[r] {
                r = i;
            }
        }
        let cap = 10 * (k + 1) * (k + 1);
        let mut pivots = 0;
        let mut entering = z0;
        loop {
            pivot(tab, cols, k, r, entering);
            pivots += 1;
            let leaving = std::mem::replace(&mut self.basis[r], entering);
            if leaving == z0 {
                break;
            }
            if pivots >= cap {
                return Err(SolveError::Cap {
                    cap,
                    residual: f64::NAN,
                });
            }
            // complement of the variable that left
            entering = if leaving < k {
                leaving + k
            } else {
                leaving - k
            };
            // ratio test (ties: prefer z0 leaving, then the smallest index)
            let mut best: Option<(usize, f64)> = None;
            for i in 0..k {
                let a = tab[i * cols + entering];
                if a > piv_tol {
                    let ratio = tab[i * cols + rhs] / a;
                    match best {
                        None => best = Some((i, ratio)),
                        Some((bi, br)) => {
                            let tie = (ratio - br).abs() <= 1e-15 * br.abs().max(1e-300);
                            if ratio < br && !tie
                                || tie && self.basis[i] == z0 && self.basis[bi] != z0
                            {
                                best = Some((i, ratio));
                            }
                        }
                    }
                }
            }
            match best {
                Some((i, _)) => r = i,
                None => return Err(SolveError::RayTermination(pivots)),
            }
        }
        for i in 0..k {
            let b = self.basis[i];
            if (k..2 * k).contains(&b) {
                z[b - k] = tab[i * cols + rhs].max(0.0);
            }
        }
        affine(m, k, z, q, w);
        Ok(SolveInfo {
            iterations: pivots,
            residual: complementarity_residual(&z[..k], &w[..k]),
        })
    }
}

fn pivot(tab: &mut [f64], cols: usize, k: usize, r: usize, c: usize) {
    let p = tab[r * cols + c];
    for j in 0..cols {
        tab[r * cols + j] /= p;
    }
    for i in 0..k {
        if i == r {
            continue;
        }
        let f = tab[i * cols + c];
        if f != 0.0 {
            for j in 0..cols {
                tab[i * cols + j] -= f * tab[r * cols + j];
            }
        }
    }
}

/// Block principal pivoting (Júdice–Pires) for symmetric positive definite LCPs, with
/// Lemke as the fallback.
///
/// Guess the set `A` of positive unknowns (from the warm start, else `q < 0`), solve
/// `W_AA z_A = −q_A` by dense Cholesky, then move every infeasible index across
/// (`z_i < 0` leaves, `w_i < 0` joins) and repeat. When the guess is right — in a
/// persistent contact it is the previous step's set — one factorization solves the
/// problem exactly, where Lemke pivots once per active contact (O(k³) per pivot
/// sequence: seconds for a thousand contacts). After `max_rounds` rounds without
/// convergence (block pivoting can cycle) the problem goes to Lemke.
#[derive(Clone, Debug)]
pub struct BlockPivoting {
    lemke: Lemke,
    active: Vec<bool>,
    idx: Vec<usize>,
    l: Vec<f64>,
    chol: crate::linalg::DenseCholesky,
    rhs: Vec<f64>,
    /// Rounds before falling back to Lemke.
    pub max_rounds: usize,
}

impl BlockPivoting {
    /// Workspace for LCPs of size up to `capacity`.
    pub fn with_capacity(capacity: usize) -> Self {
        BlockPivoting {
            lemke: Lemke::with_capacity(capacity),
            active: vec![false; capacity],
            idx: Vec::with_capacity(capacity),
            l: vec![0.0; capacity * capacity],
            chol: crate::linalg::DenseCholesky::with_capacity(capacity),
            rhs: vec![0.0; capacity],
            max_rounds: 20,
        }
    }

    /// Solves the LCP (`m` symmetric positive definite); `z` holds the warm start.
    pub fn solve(
        &mut self,
        m: &[f64],
        k: usize,
        q: &[f64],
        z: &mut [f64],
        w: &mut [f64],
    ) -> Result<SolveInfo, SolveError> {
        for i in 0..k {
            self.active[i] = z[i] > 0.0 || (z[i] == 0.0 && q[i] < 0.0);
        }
        for round in 1..=self.max_rounds {
            self.idx.clear();
            self.idx.extend((0..k).filter(|&i| self.active[i]));
            let na = self.idx.len();
            for (b, &j) in self.idx.iter().enumerate() {
                for (a, &i) in self.idx.iter().enumerate() {
                    self.l[a + b * na] = m[i + j * k];
                }
                self.rhs[b] = -q[j];
            }
            if !self.chol.factor(&mut self.l, na, na) {
                break; // not SPD on this block: let Lemke decide
            }
            self.chol.solve(&self.l, na, na, &mut self.rhs[..na], 1);
            z[..k].iter_mut().for_each(|x| *x = 0.0);
            for (a, &i) in self.idx.iter().enumerate() {
                z[i] = self.rhs[a];
            }
            affine(m, k, z, q, w);
            let scale = q[..k].iter().fold(1.0_f64, |a, x| a.max(x.abs()));
            let tol = 1e-14 * scale;
            let mut changed = false;
            for i in 0..k {
                if self.active[i] && z[i] < 0.0 {
                    self.active[i] = false;
                    changed = true;
                } else if !self.active[i] && w[i] < -tol {
                    self.active[i] = true;
                    changed = true;
                }
            }
            if !changed {
                for i in 0..k {
                    if !self.active[i] {
                        z[i] = 0.0;
                    }
                }
                return Ok(SolveInfo {
                    iterations: round,
                    residual: complementarity_residual(&z[..k], &w[..k]),
                });
            }
        }
        let info = self.lemke.solve(m, k, q, z, w)?;
        Ok(SolveInfo {
            iterations: info.iterations + self.max_rounds,
            residual: info.residual,
        })
    }
}

/// Projected Gauss–Seidel: `z_i ← max(0, z_i − w_i / M_ii)` sweep after sweep.
#[derive(Clone, Debug)]
pub struct Pgs {
    /// Stop when the residual is below `tol · max(1, |q|∞)`.
    pub tol: f64,
    /// Iteration cap.
    pub max_sweeps: usize,
}

impl Pgs {
    /// Solves the LCP starting from the `z` given (warm start). Requires `M_ii > 0`.
    pub fn solve(
        &self,
        m: &[f64],
        k: usize,
        q: &[f64],
        z: &mut [f64],
        w: &mut [f64],
    ) -> Result<SolveInfo, SolveError> {
        let qn = q[..k].iter().fold(1.0_f64, |a, x| a.max(x.abs()));
        let target = self.tol * qn;
        for i in 0..k {
            z[i] = z[i].max(0.0);
        }
        let mut residual = f64::INFINITY;
        for sweep in 1..=self.max_sweeps {
            for i in 0..k {
                let mut wi = q[i];
                for j in 0..k {
                    wi += m[i + j * k] * z[j];
                }
                z[i] = (z[i] - wi / m[i + i * k]).max(0.0);
            }
            affine(m, k, z, q, w);
            residual = complementarity_residual(&z[..k], &w[..k]);
            if residual <= target {
                return Ok(SolveInfo {
                    iterations: sweep,
                    residual,
                });
            }
        }
        Err(SolveError::Cap {
            cap: self.max_sweeps,
            residual,
        })
    }
}

/// Largest problem [`LcpKind::Auto`] gives to Lemke: below it Lemke's few pivots are
/// cheaper than a Cholesky per round; above, Lemke's one pivot per active contact is
/// O(k²) each (2.6 s per step for 1024 pressed contacts, `cargo bench --bench solid`).
pub const AUTO_LEMKE_MAX: usize = 16;

/// An LCP solver chosen at run time.
#[derive(Clone, Debug)]
pub enum LcpSolver {
    /// Exact pivoting.
    Lemke(Lemke),
    /// Block principal pivoting (symmetric positive definite matrices), Lemke fallback.
    BlockPivoting(BlockPivoting),
    /// Lemke up to [`AUTO_LEMKE_MAX`] unknowns, block pivoting above.
    Auto(BlockPivoting),
    /// Iterative.
    Pgs(Pgs),
}

impl LcpSolver {
    /// Builds the solver of `kind` with workspace for `capacity` unknowns.
    pub fn new(kind: LcpKind, capacity: usize) -> Self {
        match kind {
            LcpKind::Lemke => LcpSolver::Lemke(Lemke::with_capacity(capacity)),
            LcpKind::BlockPivoting => {
                LcpSolver::BlockPivoting(BlockPivoting::with_capacity(capacity))
            }
            LcpKind::Auto => LcpSolver::Auto(BlockPivoting::with_capacity(capacity)),
            LcpKind::Pgs { tol, max_sweeps } => LcpSolver::Pgs(Pgs { tol, max_sweeps }),
        }
    }

    /// Solves `w = M z + q, 0 ≤ z ⊥ w ≥ 0` (`z` is the warm start for PGS).
    pub fn solve(
        &mut self,
        m: &[f64],
        k: usize,
        q: &[f64],
        z: &mut [f64],
        w: &mut [f64],
    ) -> Result<SolveInfo, SolveError> {
        match self {
            LcpSolver::Lemke(l) => l.solve(m, k, q, z, w),
            LcpSolver::BlockPivoting(b) => b.solve(m, k, q, z, w),
            LcpSolver::Auto(b) if k <= AUTO_LEMKE_MAX => b.lemke.solve(m, k, q, z, w),
            LcpSolver::Auto(b) => b.solve(m, k, q, z, w),
            LcpSolver::Pgs(p) => p.solve(m, k, q, z, w),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lemke_solves_a_two_by_two_with_one_active() {
        // M = [[2,1],[1,2]], q = [-1, 1] -> z = [0.5, 0], w = [0, 1.5]
        let m = [2.0, 1.0, 1.0, 2.0];
        let mut l = Lemke::with_capacity(2);
        let (mut z, mut w) = ([0.0; 2], [0.0; 2]);
        let info = l.solve(&m, 2, &[-1.0, 1.0], &mut z, &mut w).unwrap();
        assert!((z[0] - 0.5).abs() < 1e-15 && z[1] == 0.0);
        assert!((w[1] - 1.5).abs() < 1e-15 && w[0].abs() < 1e-15);
        assert!(info.iterations >= 1);
    }

    #[test]
    fn pgs_reports_its_cap() {
        let m = [1.0, 0.99, 0.99, 1.0];
        let p = Pgs {
            tol: 1e-30,
            max_sweeps: 3,
        };
        let (mut z, mut w) = ([0.0; 2], [0.0; 2]);
        let e = p.solve(&m, 2, &[-1.0, -1.0], &mut z, &mut w).unwrap_err();
        assert!(matches!(e, SolveError::Cap { cap: 3, .. }));
    }
}
