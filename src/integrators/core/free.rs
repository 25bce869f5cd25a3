//! The free step (eq. 18 with the forecasts of eq. 61–62) and the core's calls to its
//! structure ([`super::super::structure::StructureModel`]: the free velocity, each
//! iterate's linearization and eq. 41's residual).

use super::*;

impl ThetaCore {
    /// The core's buffers lent to the structure for one call ([`StepData`]), and the
    /// structure.
    pub(super) fn structure_step(&mut self) -> (&mut dyn StructureModel, StepData<'_>) {
        (
            &mut *self.structure,
            StepData {
                sys: &self.sys,
                state: &self.state,
                h: self.h,
                theta: self.cfg.theta,
                factor: &mut *self.del.factor,
                jac: &self.del.jac,
                p: &self.rs.p,
                q_new: &mut self.dofs.q_new,
                v_new: &mut self.dofs.v_new,
                v_free: &mut self.dofs.v_free,
                work: &mut self.dofs.work,
                q_lin: &mut self.dofs.q_lin,
                y_ready: self.carry.y_ready,
                vp: (&mut self.dofs.prescribed_a, &mut self.dofs.prescribed_b),
            },
        )
    }

    /// Free velocity and the contact-space data at the start of a step (for a
    /// nonlinear structure, at its first Newton iterate: [`super::super::structure`]).
    pub fn begin_step(&mut self, stats: &mut StepStats) -> Result<(), Error> {
        stats.factorizations += std::mem::take(&mut self.carry.pending_factorizations);
        stats.dt = self.h;
        self.update_contacts()?;
        let (structure, mut cx) = self.structure_step();
        let refactored = structure
            .begin_step(&mut cx, stats)
            .map_err(|e| step_error(&self.state, self.h, e))?;
        self.carry.y_ready = false;
        self.rs.u_k.copy_from_slice(&self.carry.u_rows);
        self.del.next_epoch();
        if refactored {
            // W condensed on the new M̂ (G at q_k)
            self.del.refresh(self.structure.tangent(&self.sys));
            self.carry.w_at_qk = false;
        }
        self.del
            .jac
            .transpose_mul(&self.dofs.v_free, &mut self.rs.u_free);
        // the linearization point is read only where the operators move (a copy of
        // the state: two passes over 8 MB per step at 10⁶ dofs, issue 35)
        if !self.cfg.operators_constant {
            self.dofs.q_lin.copy_from_slice(&self.state.q);
        }
        self.rs.g_at_lin.copy_from_slice(&self.state.gap);
        Ok(())
    }

    /// Prepares a later Newton loop of the step on a nonlinear structure
    /// ([`StructureModel::restart`]) and brings the Delassus data and `U_free` along.
    pub(super) fn restart_structure(&mut self, stats: &mut StepStats) -> Result<(), Error> {
        let last_converged = self.carry.last_converged;
        let (structure, mut cx) = self.structure_step();
        let restarted = structure
            .restart(&mut cx, last_converged, stats)
            .map_err(|e| step_error(&self.state, self.h, e))?;
        if let Some(refactored) = restarted {
            // a new M̂, or G evaluated again at q_k for this loop
            if refactored || !self.cfg.g_constant {
                self.del.refresh(self.structure.tangent(&self.sys));
                self.carry.w_at_qk = false;
            }
            self.del
                .jac
                .transpose_mul(&self.dofs.v_free, &mut self.rs.u_free);
        }
        Ok(())
    }

    /// Linearizes the structure at the iterate for the next Newton iteration
    /// ([`StructureModel::relinearize`]); whether `M̂` was factored again.
    pub(super) fn relinearize_structure(
        &mut self,
        changes: (f64, f64),
        stats: &mut StepStats,
    ) -> Result<bool, Error> {
        let (structure, mut cx) = self.structure_step();
        structure
            .relinearize(&mut cx, changes, stats)
            .map_err(|e| step_error(&self.state, self.h, e))
    }

    /// The residual of eq. 41 at the iterate with the impulse `P`
    /// ([`StructureModel::residual`]); `None` on a linear structure.
    pub(super) fn structure_residual(
        &mut self,
        stats: &mut StepStats,
    ) -> Result<Option<f64>, Error> {
        let (structure, mut cx) = self.structure_step();
        structure
            .residual(&mut cx, stats)
            .map_err(|e| step_error(&self.state, self.h, e))
    }

    /// Sets `vel_mask` from the forecast `ḡ_{k+1}` (eq. 61 or 62): active iff `ḡ ≤ 0`.
    pub fn forecast(&mut self, f: Forecast) {
        let (h, th) = (self.h, self.cfg.theta);
        for a in 0..self.cfg.m {
            let g = self.state.gap[a];
            let i = self.cfg.off[a];
            let gbar = match f {
                Forecast::Explicit { gamma } => g + gamma * h * self.rs.u_k[i],
                Forecast::Free => g + h * (th * self.rs.u_free[i] + (1.0 - th) * self.rs.u_k[i]),
            };
            self.rs.vel_mask[a] = gbar <= 0.0;
        }
    }
}
