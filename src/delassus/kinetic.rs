//! The kinetic metric of the position projection on a large-deformation structure:
//! `N = M⁻¹` (the paper's remark 3, eq. 59–60: the metric of the velocity projection,
//! the kinetic energy's), in place of `N = M̂ⁿ⁻¹`.
//!
//! On a linear structure `M̂ = M + hθC + h²θ²K` is factored once and `N = M̂⁻¹` reuses
//! its columns (the bar's force plateau: DESIGN.md §3). On a structure with a
//! large-deformation law, `M̂ⁿ` carries the tangent `Kⁿ(q)`, which couples a node's
//! normal to its tangential directions: `M̂ⁿ⁻¹ G τ` moves nodes along the plane of a
//! frictionless obstacle, and since the midpoint rule's angular momentum changes by
//! `Σ δq_i × p_i` under a position change `δq` that no force made, a spinning block
//! dropped on a plane had its angular momentum about the normal moved by 7.1e-6 of
//! itself at the one step its positions were projected (Moreau–Jean: 2e-12). `M` is
//! block-diagonal by displacement component (every element's consistent, lumped and
//! redistributed mass), so `M⁻¹ G τ` is along the normal wherever `G τ` is: the
//! correction keeps the momenta the contact forces keep (linear momentum along the
//! plane, angular momentum about its normal). `M` is constant on such structures
//! ([`crate::model::system::Linearity::ConstantMass`]): it is factored once, and `W_N =
//! GᵀM⁻¹G` is formed once for a constant `G`, at each linearization for a moving one
//! (`m` solves with the factor of `M`), dense `m × m`. Where `M` is singular (the
//! redistributed mass puts none on the contact nodes) or `W_N` would pass
//! `KINETIC_MAX_BYTES` (512 MiB), the projection keeps `N = M̂ⁿ⁻¹` and the path says so.

use super::*;

/// Largest `W_N` block the kinetic metric forms (bytes); past it the projection keeps
/// `N = M̂ⁿ⁻¹` and the path says so.
const KINETIC_MAX_BYTES: usize = 512 << 20;

/// The factor of `M` and `W_N = GᵀM⁻¹G` (module doc).
#[derive(Debug)]
pub(super) struct Kinetic {
    factor: Box<dyn LinearSolver>,
    /// `W_N`, column `b` at `b·m`.
    pub(super) wn: Vec<f64>,
    /// `wn` holds the current `G`'s.
    valid: bool,
    t: Vec<f64>,
}

impl Delassus {
    /// Projects positions in the kinetic metric `N = M⁻¹` instead of `M̂ⁿ⁻¹` (module doc)
    /// where the metric is [`Metric::Mass`]; `mass` is the structure's constant `M`.
    /// Returns whether it took it (not for the Euclidean metric, nor past
    /// 512 MiB of `W_N`, nor for a singular `M`: the redistributed mass).
    pub fn use_kinetic_metric(&mut self, mass: &SparseMatrix) -> Result<bool, Error> {
        let m = self.shape.m;
        if self.shape.metric != Metric::Mass
            || m.saturating_mul(m).saturating_mul(8) > KINETIC_MAX_BYTES
        {
            return Ok(false);
        }
        // a mass with no mass on the contact nodes (`mass = "redistributed"`) is no
        // metric: the projection keeps `N = M̂ⁿ⁻¹` there
        let Ok(factor) = crate::linalg::solver::factor(
            mass.as_ref(),
            "the mass matrix M",
            crate::linalg::SolverKind::Cholesky,
            None,
        ) else {
            return Ok(false);
        };
        self.kinetic = Some(Kinetic {
            factor,
            wn: vec![0.0; m * m],
            valid: false,
            t: vec![0.0; self.shape.n],
        });
        Ok(true)
    }

    /// Whether positions are projected in the kinetic metric.
    pub fn kinetic(&self) -> bool {
        self.kinetic.is_some()
    }

    /// Forms `W_N = GᵀM⁻¹G` if `G` changed since it was last formed (allocation-free).
    pub fn prepare_position_metric(&mut self) {
        let (m, jac) = (self.shape.m, &self.jac);
        let Some(k) = self.kinetic.as_mut() else {
            return;
        };
        if k.valid {
            return;
        }
        for b in 0..m {
            k.t.iter_mut().for_each(|x| *x = 0.0);
            jac.axpy(b, 1.0, &mut k.t);
            k.factor.solve_in_place(&mut k.t);
            for a in 0..m {
                k.wn[a + b * m] = jac.dot(a, &k.t);
            }
        }
        self.column_solves += m;
        k.valid = true;
    }

    /// `G` was re-linearized: `W_N` is formed again before its next use.
    pub(super) fn kinetic_moved(&mut self) {
        if let Some(k) = self.kinetic.as_mut()
            && !self.shape.g_constant
        {
            k.valid = false;
        }
    }

    /// `y += s · M⁻¹ G x`; false (nothing done) without the kinetic metric.
    pub(super) fn add_kinetic_ng(&mut self, s: f64, x: &[f64], y: &mut [f64]) -> bool {
        let jac = &self.jac;
        let Some(k) = self.kinetic.as_mut() else {
            return false;
        };
        if x.iter().all(|&v| v == 0.0) {
            return true;
        }
        k.t.iter_mut().for_each(|v| *v = 0.0);
        for (a, &xa) in x.iter().enumerate() {
            if xa != 0.0 {
                jac.axpy(a, xa, &mut k.t);
            }
        }
        k.factor.solve_in_place(&mut k.t);
        axpy(s, &k.t, y);
        true
    }

    /// `out += s · W_N x` from the formed `W_N`; false without the kinetic metric.
    pub(super) fn kinetic_mul_add(&mut self, s: f64, x: &[f64], out: &mut [f64]) -> bool {
        if self.kinetic.is_none() {
            return false;
        }
        if x.iter().all(|&v| v == 0.0) {
            return true;
        }
        self.prepare_position_metric();
        let (m, k) = (self.shape.m, self.kinetic.as_ref().expect("checked above"));
        for (b, &xb) in x.iter().enumerate() {
            if xb != 0.0 {
                for (o, &c) in out.iter_mut().zip(&k.wn[b * m..(b + 1) * m]) {
                    *o += s * xb * c;
                }
            }
        }
        true
    }
}
