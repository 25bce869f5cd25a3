//! The free step (eq. 18 with the forecasts of eq. 61–62) and, for nonlinear
//! structures, the structural side of the Newton loop (eq. 41–48).

use super::*;

/// Adds what the step's right-hand side owes to time-dependent nodal loads at
/// `t_{k+θ}` and to the prescribed dofs (eliminated): `−M_fp Δv_p − h C_fp v_p(t_{k+θ})
/// − h K_fp u_p(t_{k+θ})`, with `(t_k, h, θ)`; `vp` are two scratch vectors.
pub(super) fn add_step_loads(
    sys: &LinearSystem,
    (t, h, th): (f64, f64, f64),
    (vp_a, vp_b): (&mut [f64], &mut [f64]),
    out: &mut [f64],
) {
    sys.add_loads(t + th * h, h, out);
    if let Some(p) = &sys.prescribed {
        p.velocity_at(t, vp_a);
        p.velocity_at(t + h, vp_b);
        for (b, a) in vp_b.iter_mut().zip(vp_a.iter()) {
            *b -= a;
        }
        spmv_add(p.mass.as_ref(), -1.0, vp_b, out);
        p.velocity_at(t + th * h, vp_a);
        if let Some(c) = &p.damping {
            spmv_add(c.as_ref(), -h, vp_a, out);
        }
        p.displacement_at(t + th * h, vp_a);
        spmv_add(p.stiffness.as_ref(), -h, vp_a, out);
    }
}

impl ThetaCore {
    /// Free velocity and the contact-space data at the start of a step (for a
    /// nonlinear structure, at its first Newton iterate: [`super::super::structure`]).
    pub fn begin_step(&mut self, stats: &mut StepStats) -> Result<(), Error> {
        self.update_contacts()?;
        if self.structure.is_some() {
            return self.begin_nonlinear_step(stats);
        }
        let (h, th) = (self.h, self.theta);
        let s = &self.state;
        // work = h f − h K (q + hθ v) − h C v; K and C are symmetric, so their CSC
        // arrays are their CSR arrays and each row is a gather.
        if !std::mem::take(&mut self.y_ready) {
            for ((ql, q), v) in self.q_lin.iter_mut().zip(&s.q).zip(&s.v) {
                *ql = q + h * th * v;
            }
        }
        if let Some(rows) = &self.k_rows {
            // the rods' K: the same sums without the gather (bit for bit)
            let f = (!self.unloaded).then_some(&self.sys.force[..]);
            rows.scaled_residual(h, f, &self.q_lin, &mut self.work);
        } else {
            let k = self.sys.stiffness.as_ref();
            let (kp, ki, kv) = (k.col_ptr(), k.row_idx(), k.val());
            for (i, (w, f)) in self.work.iter_mut().zip(&self.sys.force).enumerate() {
                let r = kp[i]..kp[i + 1];
                let kx: f64 = ki[r.clone()]
                    .iter()
                    .zip(&kv[r])
                    .map(|(&j, &a)| a * self.q_lin[j])
                    .sum();
                *w = h * (f - kx);
            }
        }
        add_step_loads(
            &self.sys,
            (s.time, h, th),
            (&mut self.vp_a, &mut self.vp_b),
            &mut self.work,
        );
        if let Some(c) = &self.sys.damping {
            sym_spmv_add(c.as_ref(), -h, &s.v, &mut self.work);
        }
        // v_free = v_k + M̂⁻¹ work (`work` is scratch afterwards)
        self.del
            .factor
            .solve_add(&mut self.work, &s.v, &mut self.v_free);
        self.u_k.copy_from_slice(&self.u_rows);
        self.del.jac.transpose_mul(&self.v_free, &mut self.u_free);
        self.del.next_epoch();
        // the linearization point is read only where the operators move (a copy of
        // the state: two passes over 8 MB per step at 10⁶ dofs, issue 35)
        if !self.operators_constant {
            self.q_lin.copy_from_slice(&self.state.q);
        }
        self.g_at_lin.copy_from_slice(&self.state.gap);
        Ok(())
    }

    /// [`ThetaCore::begin_step`] of a nonlinear structure: the step's loads, then the
    /// first Newton iterate.
    pub(super) fn begin_nonlinear_step(&mut self, stats: &mut StepStats) -> Result<(), Error> {
        let (h, th) = (self.h, self.theta);
        let st = self.structure.as_mut().expect("a nonlinear structure");
        for (e, f) in st.ext.iter_mut().zip(&self.sys.force) {
            *e = h * f;
        }
        add_step_loads(
            &self.sys,
            (self.state.time, h, th),
            (&mut self.vp_a, &mut self.vp_b),
            &mut st.ext,
        );
        self.u_k.copy_from_slice(&self.u_rows);
        self.del.next_epoch();
        self.q_lin.copy_from_slice(&self.state.q);
        self.g_at_lin.copy_from_slice(&self.state.gap);
        self.first_iterate(stats)
    }

    /// Linearizes a nonlinear structure at the step's first iterate `v⁰ = v_k`, `τ⁰ = 0`
    /// (`q⁰ = q_k + h v_k`): factors `M̂⁰`, condenses `W` on it (`G` at `q_k`), and sets
    /// the free velocity.
    pub(super) fn first_iterate(&mut self, stats: &mut StepStats) -> Result<(), Error> {
        let h = self.h;
        let s = &self.state;
        self.v_new.copy_from_slice(&s.v);
        for ((qn, q), v) in self.q_new.iter_mut().zip(&s.q).zip(&s.v) {
            *qn = q + h * v;
        }
        self.linearize_structure(true, stats)?;
        let st = self.structure.as_ref().expect("a nonlinear structure");
        self.del.refresh(&st.tangent);
        self.w_at_qk = false;
        self.del.jac.transpose_mul(&self.v_free, &mut self.u_free);
        self.at_first_iterate = true;
        Ok(())
    }

    /// Starts a later Newton loop of the step (an index-set round of Algorithm 2) from the
    /// velocity the last one converged to, with `τ = 0` (`q = q_k + h v_θ`), on the
    /// iteration matrix in hand: the same fixed point as from the first iterate, from a
    /// closer start and without a factorization (ball of `meshes/ball_crush.toml`, full
    /// Newton, Algorithm 2 at h = 1e-4: 3.32 → 2.56 factorizations per step, modified Newton
    /// 1.71 → 1.0).
    pub(super) fn restart_iterate(&mut self, stats: &mut StepStats) -> Result<(), Error> {
        let (h, th) = (self.h, self.theta);
        let s = &self.state;
        for (((qn, q), v), vn) in self.q_new.iter_mut().zip(&s.q).zip(&s.v).zip(&self.v_new) {
            *qn = q + h * (th * vn + (1.0 - th) * v);
        }
        self.linearize_structure(false, stats)?;
        if !self.g_constant {
            // G was evaluated again at q_k for this loop
            let st = self.structure.as_ref().expect("a nonlinear structure");
            self.del.refresh(&st.tangent);
            self.w_at_qk = false;
        }
        self.del.jac.transpose_mul(&self.v_free, &mut self.u_free);
        Ok(())
    }

    /// Evaluates a nonlinear structure at the iterate `(q_new, v_new)`: with `tangent`
    /// refactors `M̂ⁿ`; sets `v_free = vⁿ + M̂ⁿ⁻¹(−M(vⁿ − v_k) + hF_θⁿ)` (eq. 45 without
    /// contact impulse). The caller refreshes the Delassus data.
    pub(super) fn linearize_structure(
        &mut self,
        tangent: bool,
        stats: &mut StepStats,
    ) -> Result<(), Error> {
        let at_iterate = self.structure.as_ref().is_some_and(|st| st.rhs_at_iterate);
        if tangent || !at_iterate {
            self.evaluate_structure(tangent, stats)?;
        }
        let st = self.structure.as_mut().expect("a nonlinear structure");
        let s = &self.state;
        st.rhs_at_iterate = false;
        if tangent {
            let t0 = std::time::Instant::now();
            self.del
                .factor
                .refactor(
                    st.step_matrix.as_ref(),
                    super::super::structure::MATRIX_NAME,
                )
                .map_err(|e| step_error(s, self.h, e))?;
            stats.factorizations += 1;
            stats.factorization_seconds += t0.elapsed().as_secs_f64();
        }
        self.work.copy_from_slice(&st.rhs);
        self.del.factor.solve_in_place(&mut self.work);
        for ((vf, v), w) in self.v_free.iter_mut().zip(&self.v_new).zip(&self.work) {
            *vf = v + w;
        }
        self.at_first_iterate = false;
        Ok(())
    }

    /// [`Structure::evaluate`] at the iterate `(q_new, v_new)` (with `tangent`, `Kⁿ` and
    /// `M̂ⁿ` too), timed into `stats`; an inverted cell is the run's error.
    pub(super) fn evaluate_structure(
        &mut self,
        tangent: bool,
        stats: &mut StepStats,
    ) -> Result<(), Error> {
        let st = self.structure.as_mut().expect("a nonlinear structure");
        let s = &self.state;
        let t0 = std::time::Instant::now();
        st.evaluate(
            &self.sys,
            (self.h, self.theta),
            (&s.q, &s.v),
            (&self.q_new, &self.v_new),
            tangent,
        )
        .map_err(|e| step_error(s, self.h, e))?;
        stats.assembly_seconds += t0.elapsed().as_secs_f64();
        Ok(())
    }

    /// The residual of eq. 41 at the iterate `(q_new, v_new)` with the impulse `P`:
    /// `‖M(v − v_k) − hF_θ − GP‖∞` relative to the largest of its terms (0 below 64 ulps
    /// of that scale).
    pub(super) fn structure_residual(&mut self, stats: &mut StepStats) -> Result<f64, Error> {
        self.evaluate_structure(false, stats)?;
        let st = self.structure.as_mut().expect("a nonlinear structure");
        // the next linearization, at this iterate, can reuse the right-hand side
        st.rhs_at_iterate = true;
        // work = −R = rhs + G P
        self.work.copy_from_slice(&st.rhs);
        let mut gp = 0.0_f64;
        for a in 0..self.rows {
            if self.p[a] != 0.0 {
                self.del.jac.axpy(a, self.p[a], &mut self.work);
                gp = gp.max(self.p[a].abs());
            }
        }
        let scale = st.scale.max(gp);
        let r = self.work.iter().fold(0.0_f64, |a, x| a.max(x.abs()));
        Ok(if r <= 64.0 * f64::EPSILON * scale {
            0.0
        } else {
            r / scale.max(f64::MIN_POSITIVE)
        })
    }

    /// Sets `vel_mask` from the forecast `ḡ_{k+1}` (eq. 61 or 62): active iff `ḡ ≤ 0`.
    pub fn forecast(&mut self, f: Forecast) {
        let (h, th) = (self.h, self.theta);
        for a in 0..self.m {
            let g = self.state.gap[a];
            let i = self.off[a];
            let gbar = match f {
                Forecast::Explicit { gamma } => g + gamma * h * self.u_k[i],
                Forecast::Free => g + h * (th * self.u_free[i] + (1.0 - th) * self.u_k[i]),
            };
            self.vel_mask[a] = gbar <= 0.0;
        }
    }
}
