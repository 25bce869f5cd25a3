//! Mixed LCP with equality rows, as posed by the projection step of Algorithm 2
//! (eq. 65 and 68): for rows in `E`, `w_E = 0` with `z_E` free; for rows in `I`,
//! `0 ≤ z_I ⊥ w_I ≥ 0`; `w = M z + q` with `M` symmetric positive definite.
//!
//! Reduction: `z_E = −M_EE⁻¹ (q_E + M_EI z_I)`, then the LCP on the Schur complement
//! `S = M_II − M_IE M_EE⁻¹ M_EI` (SPD, hence a P-matrix) with `q' = q_I − M_IE M_EE⁻¹ q_E`.

use super::lcp::LcpSolver;
use super::{SolveError, SolveInfo, affine};
use crate::linalg::DenseCholesky;

/// Workspace for MLCPs of size up to `capacity`.
#[derive(Clone, Debug)]
pub struct Mlcp {
    capacity: usize,
    e_idx: Vec<usize>,
    i_idx: Vec<usize>,
    mee: Vec<f64>,
    chol: DenseCholesky,
    x: Vec<f64>,
    s: Vec<f64>,
    y: Vec<f64>,
    qi: Vec<f64>,
    zi: Vec<f64>,
    wi: Vec<f64>,
}

impl Mlcp {
    /// Allocates the workspace.
    pub fn with_capacity(capacity: usize) -> Self {
        let c = capacity.max(1);
        Mlcp {
            capacity,
            e_idx: Vec::with_capacity(c),
            i_idx: Vec::with_capacity(c),
            mee: vec![0.0; c * c],
            chol: DenseCholesky::with_capacity(c),
            x: vec![0.0; c * c],
            s: vec![0.0; c * c],
            y: vec![0.0; c],
            qi: vec![0.0; c],
            zi: vec![0.0; c],
            wi: vec![0.0; c],
        }
    }

    /// Solves the MLCP of size `k`; `equality[i]` marks the rows of `E`.
    /// `lcp` solves the reduced LCP on `I`. On return `w = M z + q`.
    #[allow(clippy::too_many_arguments)]
    pub fn solve(
        &mut self,
        m: &[f64],
        k: usize,
        q: &[f64],
        equality: &[bool],
        lcp: &mut LcpSolver,
        z: &mut [f64],
        w: &mut [f64],
    ) -> Result<SolveInfo, SolveError> {
        assert!(k <= self.capacity, "MLCP workspace too small");
        self.e_idx.clear();
        self.i_idx.clear();
        for i in 0..k {
            if equality[i] {
                self.e_idx.push(i);
            } else {
                self.i_idx.push(i);
            }
        }
        let (ne, ni) = (self.e_idx.len(), self.i_idx.len());
        if ne == 0 {
            return lcp.solve(m, k, q, z, w);
        }
        let at = |i: usize, j: usize| m[i + j * k];
        // factor M_EE
        for (b, &j) in self.e_idx.iter().enumerate() {
            for (a, &i) in self.e_idx.iter().enumerate() {
                self.mee[a + b * ne] = at(i, j);
            }
        }
        if !self.chol.factor(&mut self.mee, ne, ne) {
            return Err(SolveError::Singular);
        }
        // y = M_EE⁻¹ q_E ; X = M_EE⁻¹ M_EI (ne × ni)
        for (a, &i) in self.e_idx.iter().enumerate() {
            self.y[a] = q[i];
        }
        self.chol.solve(&self.mee, ne, ne, &mut self.y[..ne], 1);
        for (b, &j) in self.i_idx.iter().enumerate() {
            let col = &mut self.x[b * ne..(b + 1) * ne];
            for (a, &i) in self.e_idx.iter().enumerate() {
                col[a] = at(i, j);
            }
        }
        self.chol
            .solve(&self.mee, ne, ne, &mut self.x[..ne * ni], ni);
        // S = M_II − M_IE X ; q' = q_I − M_IE y
        for (b, &j) in self.i_idx.iter().enumerate() {
            for (a, &i) in self.i_idx.iter().enumerate() {
                let mut s = at(i, j);
                for (c, &e) in self.e_idx.iter().enumerate() {
                    s -= at(i, e) * self.x[c + b * ne];
                }
                self.s[a + b * ni] = s;
            }
        }
        for (a, &i) in self.i_idx.iter().enumerate() {
            let mut s = q[i];
            for (c, &e) in self.e_idx.iter().enumerate() {
                s -= at(i, e) * self.y[c];
            }
            self.qi[a] = s;
            self.zi[a] = z[i];
        }
        let info = if ni > 0 {
            lcp.solve(
                &self.s[..ni * ni],
                ni,
                &self.qi[..ni],
                &mut self.zi[..ni],
                &mut self.wi[..ni],
            )?
        } else {
            SolveInfo::default()
        };
        // z_E = −(y + X z_I)
        for (a, &e) in self.e_idx.iter().enumerate() {
            let mut s = self.y[a];
            for b in 0..ni {
                s += self.x[a + b * ne] * self.zi[b];
            }
            z[e] = -s;
        }
        for (b, &i) in self.i_idx.iter().enumerate() {
            z[i] = self.zi[b];
        }
        affine(m, k, z, q, w);
        let mut residual: f64 = 0.0;
        for i in 0..k {
            let r = if equality[i] {
                w[i].abs()
            } else {
                z[i].min(w[i]).abs()
            };
            residual = residual.max(r);
        }
        Ok(SolveInfo {
            iterations: info.iterations + 1,
            residual,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solvers::lcp::Lemke;

    #[test]
    fn equality_row_takes_a_negative_multiplier_when_needed() {
        // M = [[2,1],[1,2]], q = [1, -1], row 0 equality:
        // w0 = 2 z0 + z1 + 1 = 0, row 1 complementarity.
        // With z1 = 0: z0 = -1/2, w1 = -1/2 - 1 < 0, so z1 > 0:
        // S = 2 - 1/2 = 1.5, q' = -1 - 0.5 = -1.5 -> z1 = 1, z0 = -1.
        let m = [2.0, 1.0, 1.0, 2.0];
        let mut lcp = LcpSolver::Lemke(Lemke::with_capacity(2));
        let mut s = Mlcp::with_capacity(2);
        let (mut z, mut w) = ([0.0; 2], [0.0; 2]);
        s.solve(
            &m,
            2,
            &[1.0, -1.0],
            &[true, false],
            &mut lcp,
            &mut z,
            &mut w,
        )
        .unwrap();
        assert!(
            (z[0] + 1.0).abs() < 1e-14 && (z[1] - 1.0).abs() < 1e-14,
            "{z:?}"
        );
        assert!(w[0].abs() < 1e-14 && w[1].abs() < 1e-14);
    }
}
