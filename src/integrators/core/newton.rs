//! The decoupled Newton loop (eq. 42–48 with the one-step problems of eq. 56–58) and
//! the state it forms from the impulses.

use super::*;

/// Iterations without a 10 % gain in the Newton residual after which the loop counts
/// as stagnated ([`ThetaCore::newton`]).
pub(super) const STALL: usize = 5;

/// [`ThetaCore::restitution`] on row data: `max(e, floor)` for a normal row separating at
/// the step's start (`u_k > 0`), when a floor `(f, every)` is set: on every such row with
/// `every` (Moreau–Jean), on those that carried no impulse in the last step (`p_k ≤ 0`)
/// otherwise; `e` elsewhere.
#[inline]
pub(super) fn restitution(
    floor: Option<(f64, bool)>,
    e: f64,
    normal: bool,
    u_k: f64,
    p_k: f64,
) -> f64 {
    match floor {
        Some((f, every)) if normal && u_k > 0.0 && (p_k <= 0.0 || every) => e.max(f),
        _ => e,
    }
}

/// `|a − b|∞ / |a|∞` (0 when both are zero).
pub(super) fn relative_change(a: &[f64], b: &[f64]) -> f64 {
    let (mut d, mut n) = (0.0_f64, 0.0_f64);
    for (x, y) in a.iter().zip(b) {
        d = d.max((x - y).abs());
        n = n.max(x.abs());
    }
    if d == 0.0 {
        0.0
    } else {
        d / n.max(f64::MIN_POSITIVE)
    }
}

/// The Newton convergence measure of a nonlinear step, shared by every scheme: the
/// change `|qⁿ⁺¹ − qⁿ|∞` relative to the step's increment `|qⁿ⁺¹ − q_k|∞`, and 0 once the
/// change is at the round-off level of `q` (16 ulps): at rest on two curved contacts the
/// projection otherwise flips τ ~ 1e-17 forever (the rocking block at rest hit the cap
/// before this floor; Schatzman–Paoli's own copy of the loop had lost it).
///
/// `coordinate_scale` is the largest reference coordinate the gap functions add to `q`
/// ([`ContactSet::coordinate_scale`]): a gap `g(X + u)` cannot tell apart two `u` closer
/// than the ulps of `X`, so changes below 16 ulps of it are round-off too. Without it, a
/// stack of three stiff blocks at rest (E = 1e10 Pa, the sag 7e-9 m, positions 0.15 m)
/// iterates on 6e-17 m changes, the gap's resolution, and stops at the cap (issue 33).
pub(crate) fn newton_change(
    q_new: &[f64],
    q_lin: &[f64],
    q_k: &[f64],
    coordinate_scale: f64,
) -> f64 {
    let (mut dq, mut inc, mut qn) = (0.0_f64, 0.0_f64, 0.0_f64);
    for ((a, b), c) in q_new.iter().zip(q_lin).zip(q_k) {
        dq = dq.max((a - b).abs());
        inc = inc.max((a - c).abs());
        qn = qn.max(a.abs());
    }
    if dq <= 16.0 * f64::EPSILON * qn.max(coordinate_scale) {
        0.0
    } else {
        dq / (inc + 8.0 * f64::EPSILON * qn).max(f64::MIN_POSITIVE)
    }
}

/// Decoupled iterations after which a step that has not converged takes the coupled
/// position solve ([`ThetaCore::coupled_correction`]).
const COUPLED_AFTER: usize = 2;

impl ThetaCore {
    /// Runs the decoupled Newton loop (eq. 56–58) for fixed `vel_mask` (and `pos_mask`
    /// for [`PositionRule::Combined`]), leaving `P`, `τ`, the linearized gaps `g_lin`
    /// and the new `v`, `q` in the core's buffers.
    pub fn newton(
        &mut self,
        law: VelocityLaw,
        rule: PositionRule,
        stats: &mut StepStats,
    ) -> Result<(), Error> {
        let (h, th, m, rows) = (self.h, self.cfg.theta, self.cfg.m, self.cfg.rows);
        if !self.cfg.g_constant && !self.carry.jac_at_qk {
            self.contacts
                .evaluate(&self.state.q, &mut self.rs.g_at_lin, &mut self.del.jac);
            if self.structure.step_matrix_constant() {
                if !self.carry.w_at_qk {
                    self.del.refresh(&self.sys.stiffness);
                    self.carry.w_at_qk = true;
                }
                self.del
                    .jac
                    .transpose_mul(&self.dofs.v_free, &mut self.rs.u_free);
            }
            self.carry.jac_at_qk = true;
        }
        // a round with no row in any problem reads no Delassus entry: its
        // re-linearizations evaluate the gaps and G (for the activation test) and leave
        // the operators as they are (formed at q_k, or re-formed by the next round)
        let empty_round = law == VelocityLaw::Impact
            && self.structure.step_matrix_constant()
            && !self.rs.vel_mask.iter().any(|&x| x)
            && match rule {
                PositionRule::None => true,
                PositionRule::Combined { .. } => !self.rs.pos_mask.iter().any(|&x| x),
                PositionRule::AllComplementarity => false,
            };
        // a later round of Algorithm 2 (or its complementarity redo) on a nonlinear
        // structure starts from a new iterate
        self.restart_structure(stats)?;
        // modified Newton: the last two changes of the iterate, for its contraction test
        let (mut change, mut change_before) = (f64::INFINITY, f64::INFINITY);
        self.rs.tau_prev.iter_mut().for_each(|x| *x = 0.0);
        self.rs.p.iter_mut().for_each(|x| *x = 0.0);
        self.rs.eq_rows.iter_mut().for_each(|x| *x = false);
        self.rs.velocity_accuracy = 0.0;
        if !self.cfg.operators_constant {
            self.dofs.q_lin.copy_from_slice(&self.state.q);
        }
        self.rs.g_at_lin.copy_from_slice(&self.state.gap);
        for (k, &d) in self.zone.dofs.iter().enumerate() {
            self.zone.q_start[k] = self.state.q[d];
            self.zone.q_last[k] = self.state.q[d];
        }
        let mut relinearized = false;
        let mut converged = false;
        let (mut best, mut best_it) = (f64::INFINITY, 0);
        let (mut last_r, mut coupled_last) = (f64::INFINITY, false);
        // |qⁿ⁺¹ − qⁿ|∞ / |qⁿ⁺¹|∞ of the last iterate (nonlinear contacts only)
        let mut configuration_change = f64::INFINITY;
        let mut it = 0;
        while it < self.cfg.newton.max_iterations {
            it += 1;
            stats.newton_iterations += 1;
            if it > 1 && !self.cfg.operators_constant {
                if !self.cfg.g_constant {
                    self.contacts.evaluate(
                        &self.dofs.q_lin,
                        &mut self.rs.g_at_lin,
                        &mut self.del.jac,
                    );
                    relinearized = true;
                    self.carry.jac_at_qk = false;
                }
                // a nonlinear structure: the next iterate's M̂ⁿ (full Newton, or modified
                // Newton when the last change was not at most half the one before) and
                // free velocity
                let refactored = self.relinearize_structure((change, change_before), stats)?;
                if (!self.cfg.g_constant || refactored) && !empty_round {
                    self.del.refresh(self.structure.tangent(&self.sys));
                    self.carry.w_at_qk = false;
                }
                self.del
                    .jac
                    .transpose_mul(&self.dofs.v_free, &mut self.rs.u_free);
            }
            // coupling hθ W_D τⁿ (zero without projection)
            self.rs.wd_tau.iter_mut().for_each(|x| *x = 0.0);
            if self.cfg.feedback
                && self.structure.step_matrix_constant()
                && self.rs.tau_prev.iter().any(|&t| t != 0.0)
            {
                // with a constant G the columns stay and serve every later step; with a
                // nonlinear G they are forgotten at the next linearization, and the
                // product through the factor (two solves) is cheaper than |supp τ|
                // column solves, which would also take pool slots the position problem
                // of this iteration needs (81 contacts of two cubes: τ on 42 rows, then
                // 33 other rows violated, past the 64-column pool)
                if self.cfg.g_constant {
                    self.del
                        .ensure_support(&self.rs.tau_prev, &self.sys.stiffness)
                        .map_err(|e| fail(&self.state, "Delassus columns", e))?;
                }
                self.del.mul_add(
                    Op::Wd,
                    h * th,
                    &self.rs.tau_prev,
                    &mut self.rs.wd_tau,
                    &self.sys.stiffness,
                );
            }
            for a in 0..rows {
                self.rs.lcp_rhs[a] =
                    self.rs.u_free[a] - self.rs.wd_tau[a] + self.restitution(a) * self.rs.u_k[a];
            }
            // linearized gaps without contact impulse or projection (eq. 51), normal rows
            for c in 0..m {
                let a = self.cfg.off[c];
                self.rs.g_lin[a] = if self.cfg.g_constant || !relinearized {
                    self.state.gap[c] + h * (1.0 - th) * self.rs.u_k[a]
                } else {
                    self.rs.g_at_lin[c]
                        + self.del.jac.dot(a, &self.state.q)
                        + h * (1.0 - th) * self.del.jac.dot(a, &self.state.v)
                        - self.del.jac.dot(a, &self.dofs.q_lin)
                };
            }
            match law {
                VelocityLaw::Impact => {
                    // velocity LCP (eq. 57), or the Coulomb problem (eq. 15), on the
                    // rows of the active set
                    self.ws.idx.clear();
                    self.ws.blocks.clear();
                    let mut frictional = false;
                    for c in (0..m).filter(|&c| self.rs.vel_mask[c]) {
                        let (o, d) = (self.cfg.off[c], self.cfg.off[c + 1] - self.cfg.off[c]);
                        if self.cfg.friction {
                            self.ws.blocks.push(Block {
                                offset: self.ws.idx.len(),
                                dim: d,
                                mu: self.cfg.mu[c],
                            });
                            frictional |= d > 1;
                        }
                        self.ws.idx.extend(o..o + d);
                    }
                    if !self.ws.idx.is_empty() {
                        if !self.ws.over_cap() {
                            self.del
                                .ensure_all(&self.ws.idx, &self.sys.stiffness)
                                .map_err(|e| fail(&self.state, "Delassus columns", e))?;
                        }
                        // friction: warm start from the previous step's impulse
                        let warm = if frictional && it == 1 {
                            let r = self.h / self.carry.warm_h;
                            if r.to_bits() == 1f64.to_bits() || !r.is_finite() {
                                &self.state.impulse_rows
                            } else {
                                // the impulse of a step at another h, scaled to this one
                                for (w, p) in
                                    self.carry.p_warm.iter_mut().zip(&self.state.impulse_rows)
                                {
                                    *w = p * r;
                                }
                                &self.carry.p_warm
                            }
                        } else {
                            &self.rs.p
                        };
                        self.ws
                            .gather(&self.del, Op::W, 1.0, &self.rs.lcp_rhs, warm, |_| false)
                            .map_err(|e| fail(&self.state, "velocity problem", e))?;
                        if frictional {
                            let (info, acc) = self
                                .ws
                                .solve_friction(
                                    &self.cfg.friction_params,
                                    &mut self.del,
                                    &self.sys.stiffness,
                                    stats,
                                )
                                .map_err(|e| fail(&self.state, "friction problem", e))?;
                            self.rs.velocity_accuracy = self.rs.velocity_accuracy.max(acc);
                            stats.friction_solves += 1;
                            stats.friction_iterations += info.iterations;
                            stats.friction_residual = stats.friction_residual.max(info.residual);
                            stats.friction_fallbacks +=
                                usize::from(info.solver != FrictionSolverKind::Nsgs);
                            if !info.converged {
                                stats.caps_hit += 1;
                                stats.friction_caps += 1;
                            }
                        } else {
                            let info = self
                                .ws
                                .solve(&mut self.del, &self.sys.stiffness, stats)
                                .map_err(|e| fail(&self.state, "velocity LCP", e))?;
                            stats.lcp_iterations += info.iterations;
                            stats.lcp_residual = stats.lcp_residual.max(info.residual);
                        }
                        self.ws.scatter(&mut self.rs.p);
                    } else {
                        self.rs.p.iter_mut().for_each(|x| *x = 0.0);
                    }
                }
                VelocityLaw::PositionLevel => {
                    // 0 ≤ g_base + hθ (U_free + W P) ⊥ P ≥ 0 on every contact
                    // (frictionless only: one row per contact)
                    for a in 0..m {
                        self.rs.lcp_rhs[a] = self.rs.g_lin[a] + h * th * self.rs.u_free[a];
                    }
                    self.carry.p_warm.copy_from_slice(&self.rs.p);
                    grow_solve(
                        &mut self.ws,
                        &mut self.del,
                        (Op::W, &self.sys.stiffness),
                        h * th,
                        &self.rs.lcp_rhs,
                        &self.carry.p_warm,
                        &mut self.rs.p,
                        (0.0, &self.cfg.normal),
                        stats,
                    )
                    .map_err(|e| fail(&self.state, "position-level LCP", e))?;
                }
            }
            self.rs.w_p.iter_mut().for_each(|x| *x = 0.0);
            self.del.mul_add(
                Op::W,
                1.0,
                &self.rs.p,
                &mut self.rs.w_p,
                &self.sys.stiffness,
            );
            for a in 0..rows {
                self.rs.u_new[a] = self.rs.u_free[a] + self.rs.w_p[a] - self.rs.wd_tau[a];
            }
            for c in 0..m {
                let a = self.cfg.off[c];
                self.rs.gap_unprojected[a] = self.rs.g_lin[a] + h * th * self.rs.u_new[a];
            }
            // position problem
            let projected = self.solve_position(rule, stats)?;
            if projected {
                stats.projection_iterations += 1;
            }
            self.rs.wn_tau.iter_mut().for_each(|x| *x = 0.0);
            if self.cfg.with_projection {
                self.del.mul_add(
                    Op::Wn,
                    1.0,
                    &self.rs.tau,
                    &mut self.rs.wn_tau,
                    &self.sys.stiffness,
                );
            }
            for c in 0..m {
                let a = self.cfg.off[c];
                self.rs.g_lin[a] = self.rs.gap_unprojected[a] + self.rs.wn_tau[a];
            }
            self.rs.tau_used.copy_from_slice(&self.rs.tau_prev);
            for a in 0..rows {
                self.rs.dtau[a] = self.rs.tau[a] - self.rs.tau_prev[a];
            }
            self.rs.tau_prev.copy_from_slice(&self.rs.tau);
            // convergence
            let r = if self.cfg.operators_constant {
                self.linear_residual()?
            } else if !self.zone.dofs.is_empty() {
                // the iterate on the contact zone alone: the rest of the state follows
                // the zone's impulses linearly and is formed once, at commit
                self.form_zone();
                let r = newton_change(
                    &self.zone.q_iterate,
                    &self.zone.q_last,
                    &self.zone.q_start,
                    self.cfg.coordinate_scale,
                );
                configuration_change = relative_change(&self.zone.q_iterate, &self.zone.q_last);
                self.zone.q_last.copy_from_slice(&self.zone.q_iterate);
                for (&d, &x) in self.zone.dofs.iter().zip(&self.zone.q_iterate) {
                    self.dofs.q_lin[d] = x;
                }
                r
            } else {
                self.form();
                let r = newton_change(
                    &self.dofs.q_new,
                    &self.dofs.q_lin,
                    &self.state.q,
                    self.cfg.coordinate_scale,
                );
                configuration_change = relative_change(&self.dofs.q_new, &self.dofs.q_lin);
                self.dofs.q_lin.copy_from_slice(&self.dofs.q_new);
                match self.structure_residual(stats)? {
                    // eq. 41 at the new iterate; with a constant G the gaps are exact
                    // (eq. 49 holds identically) and R alone decides
                    Some(rs) => {
                        let r = if self.cfg.g_constant { rs } else { r.max(rs) };
                        (change_before, change) = (change, r);
                        r
                    }
                    None => r,
                }
            };
            stats.newton_residual = r;
            // the friction solve resolves velocities to `velocity_accuracy` only: the
            // loop cannot tell iterates apart below a relative 16 × that (two iterates of
            // error ≤ acc each, through the position problem, which moved rows of the
            // undamped block by up to 8 × the change of its right-hand side)
            let tol = if self.rs.velocity_accuracy > 0.0 {
                let s_v = self
                    .rs
                    .u_free
                    .iter()
                    .chain(&self.rs.u_k)
                    .chain(&self.rs.u_new)
                    .fold(0.0_f64, |a, x| a.max(x.abs()));
                self.cfg
                    .newton
                    .tol
                    .max(16.0 * self.rs.velocity_accuracy / s_v.max(f64::MIN_POSITIVE))
            } else {
                self.cfg.newton.tol
            };
            if r <= tol {
                converged = true;
                break;
            }
            // Stagnation: no 10 % gain in STALL iterations. With friction the iterates
            // can cycle among position solutions that differ by rows resting at g ≈ 0
            // within the friction solve's accuracy (period 2–3 at r ≈ 1e-9, gaps moving
            // by 1e-15 m, on the undamped block at h = 1e-5): the loop ends there and is
            // converged when the level reached is within √tol; otherwise it is a cap.
            if r < 0.9 * best {
                best = r;
                best_it = it;
            } else if it >= best_it + STALL {
                // also converged when the iterates no longer move the configuration
                // itself beyond the tolerance: a body at rest on contacts between bodies
                // takes step increments of 5e-13 m, and the solves' round-off (8e-18 m
                // around |q| = 5e-6 m, the three-block stack) is 1.5e-5 of that forever
                converged = best <= tol.sqrt() || configuration_change <= tol;
                stats.newton_stalls += 1;
                break;
            }
            // a coupled solve whose iterate did not lower the residual had the wrong
            // states: the next iterate is the plain decoupled one, which updates them
            let helped = !coupled_last || r < last_r;
            coupled_last = false;
            if it >= COUPLED_AFTER
                && helped
                && self.structure.step_matrix_constant()
                && law == VelocityLaw::Impact
                && rule != PositionRule::None
                && self.coupled_correction(rule)?
            {
                stats.coupled_solves += 1;
                coupled_last = true;
            }
            last_r = r;
        }
        self.carry.last_converged = converged;
        if !converged {
            stats.caps_hit += 1;
        }
        if let PositionRule::Combined { .. } = rule {
            stats.held_rows = (0..m)
                .filter(|&c| self.rs.pos_mask[c])
                .filter(|&c| {
                    self.rs.p[self.cfg.off[c]] <= 0.0 && self.rs.tau[self.cfg.off[c]] < 0.0
                })
                .count();
        }
        Ok(())
    }

    /// Dimensionless change that the last `Δτ` would make to the next iterate (linear `G`).
    pub(super) fn linear_residual(&mut self) -> Result<f64, Error> {
        if !self.cfg.with_projection || !self.cfg.feedback || self.rs.dtau.iter().all(|&x| x == 0.0)
        {
            return Ok(0.0);
        }
        self.del
            .ensure_support(&self.rs.dtau, &self.sys.stiffness)
            .map_err(|e| fail(&self.state, "Delassus columns", e))?;
        let (h, th, rows) = (self.h, self.cfg.theta, self.cfg.rows);
        let mut s_v: f64 = 0.0;
        let mut s_g: f64 = 0.0;
        for a in 0..rows {
            s_v = s_v
                .max(self.rs.u_free[a].abs())
                .max(self.rs.u_k[a].abs())
                .max(self.rs.u_new[a].abs());
        }
        for c in 0..self.cfg.m {
            s_g = s_g.max(self.rs.gap_unprojected[self.cfg.off[c]].abs());
        }
        self.rs.w_p.iter_mut().for_each(|x| *x = 0.0);
        self.rs.wn_tau.iter_mut().for_each(|x| *x = 0.0);
        self.del.mul_add(
            Op::Wd,
            1.0,
            &self.rs.dtau,
            &mut self.rs.w_p,
            &self.sys.stiffness,
        );
        self.del.mul_add(
            Op::Wn,
            1.0,
            &self.rs.dtau,
            &mut self.rs.wn_tau,
            &self.sys.stiffness,
        );
        let mut dv: f64 = 0.0;
        let mut dg: f64 = 0.0;
        for a in 0..rows {
            dv = dv.max(h * th * self.rs.w_p[a].abs());
        }
        for c in 0..self.cfg.m {
            dg = dg.max(self.rs.wn_tau[self.cfg.off[c]].abs());
        }
        // Rounding floor: 8 ulps of the quantities the iterate is built from (what the
        // friction solve resolves enters through the tolerance, in `newton`).
        let fv = 8.0 * f64::EPSILON * s_v;
        let fg = 8.0 * f64::EPSILON * (s_g + h * s_v);
        let rv = if dv <= fv {
            0.0
        } else {
            dv / s_v.max(f64::MIN_POSITIVE)
        };
        let rg = if dg <= fg {
            0.0
        } else {
            dg / (h * s_v).max(f64::MIN_POSITIVE)
        };
        Ok(rv.max(rg))
    }

    /// The restitution coefficient of row `a` in this step's impact law
    /// `0 ≤ U_{k+1} + e U_k ⊥ P ≥ 0` (eq. 18d, 57).
    ///
    /// The impulse of a row does the work `P((1 − θ)U_k + θU_{k+1})` in the θ-method's
    /// energy balance (the step moves `q` by `h v_{k+θ}`); with `U_{k+1} = −eU_k` that is
    /// `P U_k ((1 − θ) − θe)`, never positive for a row that closes (`U_k ≤ 0`), but
    /// positive for a row that separates at the step's start (`U_k > 0`) and is caught by
    /// an impulse, unless `e ≥ (1 − θ)/θ`. Such catches happen where the position
    /// projection leaves a node on the obstacle while moving away (the edge of a growing
    /// contact patch, issue 33: +3 % and +22 % of the energy on `meshes/hertz_ball.toml` at
    /// 2× and 4× its step), and in Moreau–Jean's closed active set. With
    /// [`SchemeParams::energy_consistent_restitution`] (the default) a separating normal
    /// row takes `max(e, (1 − θ)/θ)` (1 at θ = 1/2: the catch reverses `U` and does no
    /// work; `e` itself at θ = 1), so no impulse adds energy; a closing row keeps `e`.
    /// Under the projection schemes the floor applies to rows open in the last step
    /// (`P_k ≤ 0`): a row in lasting contact is held at `g = 0` by the projection, and
    /// flooring it kept the rocking block from coming to rest (velocities of 1e-7 at
    /// t = 1.21 s). Under Moreau–Jean, which holds no position, it applies to every
    /// separating row: a lasting contact that separates (two aluminium spheres
    /// released at 2 m/s, h = 6.25e-9) otherwise gained 1.02e-6 of the energy at e = 0.
    /// At θ = 1/2 the floored law reads `0 ≤ U_{k+1} + U_k ⊥ P ≥ 0`: the impulse does
    /// no work.
    #[inline]
    pub(super) fn restitution(&self, a: usize) -> f64 {
        let s = &self.state;
        restitution(
            self.cfg.restitution_floor,
            self.cfg.e[a],
            self.cfg.normal[a],
            self.rs.u_k[a],
            s.impulse_rows[a],
        )
    }

    /// The activation of eq. 66: adds to `vel_mask` every contact whose gap at the end
    /// of the last [`ThetaCore::newton`] (eq. 51 at the solved iterate) is `≤ 0`: after
    /// the position projection (`g_lin`, Algorithm 2) or before it (`b = g_lin − W_N τ`,
    /// the closure of Moreau–Jean's and Algorithm 1's forecast set). Returns whether the
    /// set grew.
    pub fn activate_violated(&mut self, before_projection: bool) -> bool {
        let gaps = if before_projection {
            &self.rs.gap_unprojected
        } else {
            &self.rs.g_lin
        };
        let mut grew = false;
        for a in 0..self.cfg.m {
            if !self.rs.vel_mask[a] && gaps[self.cfg.off[a]] <= 0.0 {
                self.rs.vel_mask[a] = true;
                grew = true;
            }
        }
        grew
    }

    /// The forecast set's Newton loop, closed on the solution when `closure`
    /// ([`SchemeParams::activation_closure`]): after each loop, every contact whose gap
    /// before the projection ends `≤ 0` joins `vel_mask` and the loop runs again. The set
    /// only grows, so at most `m` more rounds run; they are counted in
    /// [`StepStats::index_set_iterations`] (0 when the forecast was right).
    pub fn closed_newton(
        &mut self,
        rule: PositionRule,
        closure: bool,
        st: &mut StepStats,
    ) -> Result<(), Error> {
        loop {
            self.newton(VelocityLaw::Impact, rule, st)?;
            if !closure || !self.activate_violated(true) {
                return Ok(());
            }
            st.index_set_iterations += 1;
            if st.index_set_iterations > self.cfg.m {
                // unreachable while the set only grows; kept as a reported cap
                st.caps_hit += 1;
                return Ok(());
            }
        }
    }
}
