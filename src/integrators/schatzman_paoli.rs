//! Schatzman–Paoli scheme (eq. 20–22), θ-weighted as in eq. 20a:
//!
//! `M (q_{k+1} − 2q_k + q_{k−1}) − h² F(t_{k+θ}, q_{k+θ}, v_{k+θ}) = p_{k+1}`,
//! `v_{k+1} = (q_{k+1} − q_{k−1}) / 2h`, `p_{k+1} = G P_{k+1}`,
//! `0 ≤ g((q_{k+1} + e q_{k−1})/(1+e)) ⊥ P_{k+1} ≥ 0`.
//!
//! With `F = f − C v − K q`, `q_{k+θ} = (1−θ)q_k + θq_{k+1}` and `v_{k+θ}` built from the
//! central velocity, the step matrix is `M_SP = M + h²θK + (hθ/2)C`, factored once.
//! The contact condition is written in its affine-equivalent form
//! `0 ≤ g(q_{k+1}) + e g(q_{k−1}) ⊥ P ≥ 0` (identical to eq. 22 for a linear gap,
//! since `1 + e > 0`; for a nonlinear gap both are linearized at the current Newton
//! iterate). For `e = 0` the position constraint holds at every step; the impact law
//! is only met over two or three steps.
//!
//! Start: `q_{−1} = q_0 − h v_0 + ½h² a_0` with `a_0 = M⁻¹(f − K q_0 − C v_0)` (`a_0 = 0`
//! when `M` is singular, as with the redistributed mass).
//! The reported impulse is `P/h` (N·s), comparable with the velocity-level schemes.

use super::SchemeKind;
use super::core::{Workspace, fail, grow_solve, newton_change};
use super::problem::Problem;
use super::step_matrix::factor_step_matrix;
use super::{Integrator, Metric, NewtonParams, SchemeParams, State, StepStats};
use crate::contact::{ContactJacobian, ContactSet};
use crate::delassus::{Delassus, Op};
use crate::error::Error;
use crate::linalg::{SpdFactor, spmv_add};
use crate::model::LinearSystem;

/// The Schatzman–Paoli integrator.
pub struct SchatzmanPaoli {
    sys: std::sync::Arc<LinearSystem>,
    contacts: Box<dyn ContactSet>,
    h: f64,
    theta: f64,
    n: usize,
    m: usize,
    /// `M_SP` factored, `G` and `W_SP = GᵀM_SP⁻¹G`.
    del: Delassus,
    e: Vec<f64>,
    /// `G` does not depend on `q` (condensed once).
    g_constant: bool,
    /// [`ContactSet::coordinate_scale`], read once (the Newton loop's round-off floor).
    coordinate_scale: f64,
    newton: NewtonParams,
    state: State,
    q_prev: Vec<f64>,
    q_free: Vec<f64>,
    q_lin: Vec<f64>,
    q_new: Vec<f64>,
    work: Vec<f64>,
    g_prev: Vec<f64>,
    g_lin: Vec<f64>,
    rhs: Vec<f64>,
    p: Vec<f64>,
    p_warm: Vec<f64>,
    /// Every row is a normal row (frictionless only).
    all_rows: Vec<bool>,
    ws: Workspace,
}

impl SchatzmanPaoli {
    /// Factors `M_SP` and condenses `W_SP = Gᵀ M_SP⁻¹ G` once.
    pub fn new(params: &SchemeParams, problem: Problem, h: f64) -> Result<Self, Error> {
        let mut problem = problem;
        let planned = problem.take_step_matrix();
        let (sys, contacts, q0, v0) = problem.into_parts();
        let (q0, v0) = (&q0[..], &v0[..]);
        let theta = params.theta;
        let factor = factor_step_matrix(&sys, params.step_form(), h, planned)?;
        let n = sys.ndof();
        let m = contacts.len();
        // start-up: a0 = M⁻¹ (f(0) − K q0 − C v0), the time-dependent loads active at
        // t = 0 included (without them the run started with a velocity error of
        // h f(0)/(2m), a displacement error growing linearly)
        let mut a0 = sys.force.clone();
        sys.add_loads(0.0, 1.0, &mut a0);
        spmv_add(sys.stiffness.as_ref(), -1.0, q0, &mut a0);
        if let Some(c) = &sys.damping {
            spmv_add(c.as_ref(), -1.0, v0, &mut a0);
        }
        // A redistributed mass is singular (massless contact nodes): start with a0 = 0.
        match SpdFactor::new(sys.mass.as_ref(), "mass matrix") {
            Ok(mut m) => m.solve_in_place(&mut a0),
            Err(_) => a0.iter_mut().for_each(|x| *x = 0.0),
        }
        let q_prev: Vec<f64> = (0..n)
            .map(|i| q0[i] - h * v0[i] + 0.5 * h * h * a0[i])
            .collect();
        let jac = ContactJacobian::for_set(contacts.as_ref());
        let e: Vec<f64> = contacts.laws().iter().map(|l| l.restitution).collect();
        let g_constant = contacts.is_linear();
        let del = Delassus::new(
            factor,
            jac,
            n,
            (params.delassus, params.delassus_pool),
            false,
            Metric::Mass,
            g_constant,
        );
        let mut sp = SchatzmanPaoli {
            coordinate_scale: contacts.coordinate_scale(),
            sys: std::sync::Arc::new(sys),
            contacts,
            h,
            theta,
            n,
            m,
            del: {
                let mut del = del?;
                del.limit_columns(super::sizing::workspace_cap(m, params));
                del
            },
            e,
            g_constant,
            newton: params.newton,
            state: State::initial(q0, v0, m),
            q_prev,
            q_free: vec![0.0; n],
            q_lin: vec![0.0; n],
            q_new: vec![0.0; n],
            work: vec![0.0; n],
            g_prev: vec![0.0; m],
            g_lin: vec![0.0; m],
            rhs: vec![0.0; m],
            p: vec![0.0; m],
            p_warm: vec![0.0; m],
            all_rows: vec![true; m],
            ws: Workspace::new(m, m, params, false),
        };
        sp.contacts
            .evaluate(&sp.q_prev, &mut sp.g_prev, &mut sp.del.jac);
        sp.contacts
            .evaluate(&sp.state.q, &mut sp.state.gap, &mut sp.del.jac);
        if !sp.g_constant && sp.contacts.condensed() {
            let zone = sp.contacts.zone();
            let fixed = super::core::fixed_rows(sp.contacts.as_ref());
            sp.del.condense_zone(&zone, fixed, &sp.sys.stiffness, false);
        }
        sp.del.refresh(&sp.sys.stiffness);
        sp.del
            .jac
            .transpose_mul(&sp.state.v, &mut sp.state.local_velocity);
        sp.del.start_stepping();
        Ok(sp)
    }
}

impl Integrator for SchatzmanPaoli {
    fn kind(&self) -> SchemeKind {
        SchemeKind::SchatzmanPaoli
    }

    fn step(&mut self) -> Result<StepStats, Error> {
        let mut st = StepStats {
            dt: self.h,
            ..StepStats::default()
        };
        self.contacts
            .update(&self.state.q)
            .map_err(|e| super::core::step_error(&self.state, self.h, e))?;
        let (h, th, n, m) = (self.h, self.theta, self.n, self.m);
        // M_SP Δ = M(q_k − q_{k−1}) − h²K q_k + h² f − h²(1−θ) C v_k − (hθ/2) C (q_k − q_{k−1})
        for i in 0..n {
            self.q_lin[i] = self.state.q[i] - self.q_prev[i];
        }
        for (w, f) in self.work.iter_mut().zip(&self.sys.force) {
            *w = h * h * f;
        }
        self.sys
            .add_loads(self.state.time + th * h, h * h, &mut self.work);
        spmv_add(self.sys.mass.as_ref(), 1.0, &self.q_lin, &mut self.work);
        spmv_add(
            self.sys.stiffness.as_ref(),
            -h * h,
            &self.state.q,
            &mut self.work,
        );
        if let Some(c) = &self.sys.damping {
            spmv_add(
                c.as_ref(),
                -h * h * (1.0 - th),
                &self.state.v,
                &mut self.work,
            );
            spmv_add(c.as_ref(), -0.5 * h * th, &self.q_lin, &mut self.work);
        }
        self.del.next_epoch();
        self.del.factor.solve_in_place(&mut self.work);
        for i in 0..n {
            self.q_free[i] = self.state.q[i] + self.work[i];
        }
        // Newton loop on the linearization point q^n (starts at q_free)
        self.q_lin.copy_from_slice(&self.q_free);
        self.p.iter_mut().for_each(|x| *x = 0.0);
        let mut converged = false;
        for it in 1..=self.newton.max_iterations {
            st.newton_iterations += 1;
            if !self.g_constant || it == 1 {
                self.contacts
                    .evaluate(&self.q_lin, &mut self.g_lin, &mut self.del.jac);
                if !self.g_constant {
                    self.del.refresh(&self.sys.stiffness);
                }
            }
            for a in 0..m {
                let lin = if it == 1 {
                    0.0
                } else {
                    self.del.jac.dot(a, &self.q_free) - self.del.jac.dot(a, &self.q_lin)
                };
                self.rhs[a] = self.g_lin[a] + lin + self.e[a] * self.g_prev[a];
            }
            self.p_warm.copy_from_slice(&self.p);
            grow_solve(
                &mut self.ws,
                &mut self.del,
                (Op::W, &self.sys.stiffness),
                1.0,
                &self.rhs,
                &self.p_warm,
                &mut self.p,
                (0.0, &self.all_rows),
                &mut st,
            )
            .map_err(|e| fail(&self.state, "Schatzman–Paoli LCP", e))?;
            self.q_new.copy_from_slice(&self.q_free);
            self.del.add_inverse_g(1.0, &self.p, &mut self.q_new);
            if self.g_constant {
                converged = true;
                st.newton_residual = 0.0;
                break;
            }
            let r = newton_change(
                &self.q_new,
                &self.q_lin,
                &self.state.q,
                self.coordinate_scale,
            );
            st.newton_residual = r;
            self.q_lin.copy_from_slice(&self.q_new);
            if r <= self.newton.tol {
                converged = true;
                break;
            }
        }
        if !converged {
            st.caps_hit += 1;
        }
        // commit: v_{k+1} = (q_{k+1} − q_{k−1}) / 2h
        for i in 0..n {
            self.state.v[i] = (self.q_new[i] - self.q_prev[i]) / (2.0 * h);
        }
        self.g_prev.copy_from_slice(&self.state.gap);
        std::mem::swap(&mut self.q_prev, &mut self.state.q);
        std::mem::swap(&mut self.state.q, &mut self.q_new);
        for a in 0..m {
            self.state.impulse[a] = self.p[a] / h;
            self.state.impulse_rows[a] = self.p[a] / h;
        }
        self.state.step += 1;
        self.state.time = self.state.step as f64 * h;
        self.contacts
            .evaluate(&self.state.q, &mut self.state.gap, &mut self.del.jac);
        self.del
            .jac
            .transpose_mul(&self.state.v, &mut self.state.local_velocity);
        st.max_violation = self.state.gap.iter().fold(0.0_f64, |a, &g| a.max(-g));
        Ok(st)
    }

    fn state(&self) -> &State {
        &self.state
    }
    fn prepare(&mut self) -> Result<(), Error> {
        self.contacts
            .update(&self.state.q)
            .map(|_| ())
            .map_err(|e| super::core::step_error(&self.state, self.h, e))
    }
    fn save(&self) -> crate::integrators::saved::IntegratorState {
        let mut s = self.state.save(self.name());
        for (name, v) in [
            ("q_prev", &self.q_prev),
            ("g_prev", &self.g_prev),
            ("q_lin", &self.q_lin),
        ] {
            s.vectors.insert(
                name.to_string(),
                crate::integrators::saved::Floats(v.clone()),
            );
        }
        s
    }
    /// Restores `q`, `q_{k−1}`, the previous gaps and the last linearization point (the
    /// Delassus data of a nonlinear contact set were formed there).
    fn restore(&mut self, s: &crate::integrators::saved::IntegratorState) -> Result<(), Error> {
        self.state.restore(self.name(), s)?;
        let (n, m) = (self.n, self.m);
        self.q_prev.copy_from_slice(s.vector("q_prev", n)?);
        self.g_prev.copy_from_slice(s.vector("g_prev", m)?);
        self.q_lin.copy_from_slice(s.vector("q_lin", n)?);
        self.contacts.restart(&self.state.q);
        self.contacts.update(&self.state.q)?;
        if !self.g_constant {
            self.contacts
                .evaluate(&self.q_lin, &mut self.g_lin, &mut self.del.jac);
            self.del.refresh(&self.sys.stiffness);
        }
        self.contacts
            .evaluate(&self.state.q, &mut self.state.gap, &mut self.del.jac);
        Ok(())
    }
    fn system(&self) -> &LinearSystem {
        &self.sys
    }
    fn shared_system(&self) -> std::sync::Arc<LinearSystem> {
        self.sys.clone()
    }
    fn dt(&self) -> f64 {
        self.h
    }
    fn jacobian(&self) -> &crate::contact::ContactJacobian {
        &self.del.jac
    }
    fn starting_gaps(&self, q: &[f64], gap: &mut [f64]) {
        self.contacts.starting_gaps(q, gap)
    }
    fn path(&self) -> String {
        format!(
            "M + h²θK + (hθ/2)C factored once ({}, n = {}); {} contact(s), {}; {}",
            self.del.factor.backend_name(),
            self.n,
            self.m,
            if self.g_constant {
                "linear gap: no Newton iteration"
            } else {
                "nonlinear gap: re-linearized every Newton iteration"
            },
            self.del.describe()
        ) + &self.ws.describe(self.del.products_by_flexibility())
    }
}
