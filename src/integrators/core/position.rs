//! The position problem of Algorithms 1 and 2: the decoupled projection (eq. 56–58) and,
//! where it contracts slowly, the coupled MLCP of eq. 52–55.

use super::*;

/// One unknown of the coupled position problem ([`ThetaCore::coupled_correction`]).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Unknown {
    /// Contact-space row of the unknown and of its equation.
    pub(super) row: usize,
    /// Its contact.
    pub(super) contact: usize,
    /// A τ of an equality row (`g = 0` whatever the sign of `τ`).
    pub(super) equality: bool,
    /// A projection `τ` (position equation `g = 0`) rather than an impulse (velocity
    /// equation `U + eU_k = 0`).
    pub(super) tau: bool,
    /// Slip: the impulse column is `e_N + μ Σ d_j e_{T_j}` (`P_T = μ P_N d` with the
    /// direction `d` of the current iterate); `slip_dim` tangents, 0 otherwise.
    pub(super) slip_dim: usize,
    pub(super) slip: [f64; 2],
}

/// Buffers of the coupled position problem, sized once for `cap` unknowns.
#[derive(Debug)]
pub(super) struct Coupled {
    pub(super) cap: usize,
    pub(super) unknowns: Vec<Unknown>,
    pub(super) cols: Vec<usize>,
    /// Per contact, impulse (even) and projection (odd) unknowns to drop.
    pub(super) drop: Vec<bool>,
    pub(super) mat: Vec<f64>,
    pub(super) rhs: Vec<f64>,
    pub(super) lu: crate::linalg::DenseLu,
}

impl Coupled {
    pub(super) fn new(cap: usize, contacts: usize) -> Self {
        Coupled {
            cap,
            unknowns: Vec::with_capacity(cap),
            cols: Vec::with_capacity(cap * 2),
            drop: vec![false; 2 * contacts],
            mat: vec![0.0; cap * cap],
            rhs: vec![0.0; cap],
            lu: crate::linalg::DenseLu::with_capacity(cap),
        }
    }
}

impl ThetaCore {
    /// The coupled position problem of eq. 52–55, solved on the contact states of the
    /// current iterate, as the next iterate's `τ`.
    ///
    /// The decoupled loop (eq. 56–58) feeds `τⁿ` into the velocity problem through
    /// `−hθ W_D τⁿ` and solves the position problem with that velocity: a fixed point
    /// whose contraction factor on a mode of frequency ω is `(ωhθ)² / (1 + (ωhθ)²)`
    /// (metric `M̂⁻¹`), so it crawls once `ωhθ ≳ 1`, which the highest modes of any
    /// finite-element mesh reach (the undamped hex8 block at h = 1e-4: factor 0.74 per
    /// iteration, the cap of 50 reached). On the current states — each active block open
    /// (`P = 0`), sticking (`U + eU_k = 0` on all its rows) or slipping (`U_N + eU_{k,N} = 0`
    /// and `P_T = μ P_N d` along the current direction `d`), each projected row at `g = 0`
    /// (equality rows, and complementarity rows with `τ > 0`) — the velocity and position
    /// equations of eq. 53,
    ///
    /// `U + eU_k = W P − hθ W_D τ + (U_free + eU_k)`,
    /// `g = hθ W P + (W_N − h²θ² W_D) τ + (g_lin + hθ U_free)`,
    ///
    /// are linear in `(P, τ)`; their solution (dense LU) is the fixed point of the
    /// decoupled map on that piece, a semismooth Newton step on it. Its `τ` replaces
    /// `τⁿ⁺¹`; the next decoupled iteration then checks every law (complementarity, the
    /// friction cone, the states) and converges at once when the states were right, or
    /// goes on from a better iterate when they were not. Returns whether a solve ran.
    pub(super) fn coupled_correction(&mut self, rule: PositionRule) -> Result<bool, Error> {
        let Some(cp) = self.coupled.as_mut() else {
            return Ok(false);
        };
        let (h, th, m) = (self.h, self.cfg.theta, self.cfg.m);
        let c = h * th;
        cp.unknowns.clear();
        cp.cols.clear();
        for k in (0..m).filter(|&k| self.rs.vel_mask[k]) {
            let (o, d) = (self.cfg.off[k], self.cfg.off[k + 1] - self.cfg.off[k]);
            let pn = self.rs.p[o];
            if pn <= 0.0 {
                continue;
            }
            let pt = self.rs.p[o + 1..o + d]
                .iter()
                .map(|x| x * x)
                .sum::<f64>()
                .sqrt();
            let mu = self.cfg.mu[k];
            // the buffers hold `cap` unknowns: a larger problem is not attempted (and
            // must not grow them inside the step)
            if cp.unknowns.len() + d > cp.cap || cp.cols.len() + d > cp.cols.capacity() {
                return Ok(false);
            }
            if d == 1 || mu == 0.0 || pt >= (1.0 - 1e-9) * mu * pn {
                let mut u = Unknown {
                    row: o,
                    contact: k,
                    ..Unknown::default()
                };
                if d > 1 && mu > 0.0 && pt > 0.0 {
                    u.slip_dim = d - 1;
                    for j in 0..d - 1 {
                        u.slip[j] = mu * self.rs.p[o + 1 + j] / pt;
                    }
                }
                cp.unknowns.push(u);
            } else {
                cp.unknowns.extend((o..o + d).map(|row| Unknown {
                    row,
                    contact: k,
                    ..Unknown::default()
                }));
            }
            cp.cols.extend(o..o + d);
        }
        for k in (0..m).filter(|&k| self.rs.pos_mask[k] || rule == PositionRule::AllComplementarity)
        {
            let a = self.cfg.off[k];
            let eq = match rule {
                PositionRule::Combined { rule } => {
                    self.rs.pos_mask[k] && (rule == ProjectionRule::AllActive || self.rs.eq_rows[a])
                }
                _ => false,
            };
            if eq || self.rs.tau[a] > 0.0 {
                if cp.unknowns.len() == cp.cap || cp.cols.len() == cp.cols.capacity() {
                    return Ok(false);
                }
                cp.unknowns.push(Unknown {
                    row: a,
                    contact: k,
                    tau: true,
                    equality: eq,
                    ..Unknown::default()
                });
                cp.cols.push(a);
            }
        }
        if !cp.unknowns.iter().any(|u| u.tau) {
            return Ok(false);
        }
        cp.cols.sort_unstable();
        cp.cols.dedup();
        self.del
            .ensure_all(&cp.cols, &self.sys.stiffness)
            .map_err(|e| fail(&self.state, "Delassus columns", e))?;
        // Active-set rounds: a block whose normal impulse comes out negative opens, a
        // complementarity row whose τ comes out negative leaves; each round drops at
        // least one unknown, so at most `n` rounds.
        loop {
            let n = cp.unknowns.len();
            if n == 0 || !cp.unknowns.iter().any(|u| u.tau) {
                return Ok(false);
            }
            let del = &self.del;
            for (l, ul) in cp.unknowns.iter().enumerate() {
                for (k, uk) in cp.unknowns.iter().enumerate() {
                    let i = uk.row;
                    let v = if ul.tau {
                        let wd = del.entry(Op::Wd, i, ul.row);
                        if uk.tau {
                            del.entry(Op::Wn, i, ul.row) - c * c * wd
                        } else {
                            -c * wd
                        }
                    } else {
                        let mut w = del.entry(Op::W, i, ul.row);
                        for j in 0..ul.slip_dim {
                            w += ul.slip[j] * del.entry(Op::W, i, ul.row + 1 + j);
                        }
                        if uk.tau { c * w } else { w }
                    };
                    cp.mat[k + l * n] = v;
                }
            }
            for (k, uk) in cp.unknowns.iter().enumerate() {
                let i = uk.row;
                cp.rhs[k] = if uk.tau && self.cfg.g_constant {
                    -(self.state.gap[uk.contact]
                        + h * (1.0 - th) * self.rs.u_k[i]
                        + c * self.rs.u_free[i])
                } else if uk.tau {
                    // a nonlinear G: the gap linearized at this iterate (eq. 51), which
                    // `b = g_lin + hθ U` still holds
                    -(self.rs.gap_unprojected[i] - c * self.rs.u_new[i] + c * self.rs.u_free[i])
                } else {
                    let (e, u_k) = (self.cfg.e[i], self.rs.u_k[i]);
                    let p_k = self.state.impulse_rows[i];
                    -(self.rs.u_free[i]
                        + restitution(self.cfg.restitution_floor, e, self.cfg.normal[i], u_k, p_k)
                            * u_k)
                };
            }
            if !cp.lu.solve(&mut cp.mat[..n * n], n, &mut cp.rhs[..n]) {
                // singular on this piece (redundant constraints): the decoupled loop goes on
                return Ok(false);
            }
            // contacts to drop: an impulse block with P_N < 0, a complementarity τ < 0
            cp.drop.iter_mut().for_each(|x| *x = false);
            let mut any = false;
            for (u, &y) in cp.unknowns.iter().zip(&cp.rhs[..n]) {
                let wrong = if u.tau {
                    !u.equality && y < 0.0
                } else {
                    u.row == self.cfg.off[u.contact] && y < 0.0
                };
                if wrong {
                    cp.drop[2 * u.contact + usize::from(u.tau)] = true;
                    any = true;
                }
            }
            if !any {
                break;
            }
            let drop = &cp.drop;
            cp.unknowns
                .retain(|u| !drop[2 * u.contact + usize::from(u.tau)]);
        }
        let n = cp.unknowns.len();
        self.rs.tau_prev.iter_mut().for_each(|x| *x = 0.0);
        for (u, &y) in cp.unknowns.iter().zip(&cp.rhs[..n]) {
            if u.tau {
                self.rs.tau_prev[u.row] = y;
            }
        }
        Ok(true)
    }

    /// Solves the position problem for `rule`; returns whether any `τ ≠ 0`.
    pub(super) fn solve_position(
        &mut self,
        rule: PositionRule,
        stats: &mut StepStats,
    ) -> Result<bool, Error> {
        let m = self.cfg.m;
        // Gaps are known only to hθ times the velocity accuracy of the friction solve
        // (0 without friction): a row within twice that of zero is neither violated nor
        // projected, or the rows resting at g ≈ 0 flip in and out of the position problem
        // on the solver's last digits and the loop never settles (seen at h = 1e-5 on the
        // undamped sliding block: gaps of ±5e-18 m flipping with U_N known to 1e-12 m/s).
        let ptol = self
            .cfg
            .projection_tolerance
            .max(2.0 * self.h * self.cfg.theta * self.rs.velocity_accuracy);
        match rule {
            PositionRule::None => {
                self.rs.tau.iter_mut().for_each(|x| *x = 0.0);
                return Ok(false);
            }
            PositionRule::AllComplementarity => {
                // 0 ≤ b + W_N τ ⊥ τ ≥ 0 over all contacts
                self.del.prepare_position_metric();
                grow_solve(
                    &mut self.ws,
                    &mut self.del,
                    (Op::Wn, &self.sys.stiffness),
                    1.0,
                    &self.rs.gap_unprojected,
                    &self.rs.tau_prev,
                    &mut self.rs.tau,
                    (ptol, &self.cfg.normal),
                    stats,
                )
                .map_err(|e| fail(&self.state, "position LCP", e))?;
            }
            PositionRule::Combined { rule } => {
                // eq. 68: equality where P > 0 (eq. 69/70), complementarity elsewhere
                // in the active set; rows already within the tolerance are dropped.
                // A row stays an equality for the rest of the loop once its P was > 0:
                // eq. 65 can have no solution for an index set (the paper says so of
                // imposing g = 0 on all of Iᵛ), and then the states alternate. Seen on
                // the undamped sliding block at h = 2e-4: five rows with P > 0 held at
                // g = 0 need τ < 0, with that τ their P is 0; as complementarity rows
                // their τ is 0 and their P > 0 again, every other iteration until the cap.
                // Keeping them equalities ends the loop; a final P = 0 with τ < 0 is
                // counted in `StepStats::held_rows`.
                for c in 0..m {
                    let a = self.cfg.off[c];
                    if self.rs.pos_mask[c]
                        && self.rs.p[a] > 0.0
                        && rule.holds(self.state.impulse_rows[a] > 0.0)
                    {
                        self.rs.eq_rows[a] = true;
                    }
                }
                let (b, eq_rows) = (&self.rs.gap_unprojected, &self.rs.eq_rows);
                let eq = |a: usize| rule == ProjectionRule::AllActive || eq_rows[a];
                self.ws.idx.clear();
                self.ws
                    .idx
                    .extend((0..m).map(|c| (c, self.cfg.off[c])).filter_map(|(c, a)| {
                        (self.rs.pos_mask[c]
                            && if eq(a) {
                                b[a].abs() > ptol || (ptol == 0.0 && b[a] != 0.0)
                            } else {
                                b[a] < -ptol
                            })
                        .then_some(a)
                    }));
                self.rs.tau.iter_mut().for_each(|x| *x = 0.0);
                // The rows are chosen at τ = 0; the projection of the equality rows can
                // push a complementarity row of the active set below zero (seen with
                // friction: a lifting node next to projected ones). Such rows join and
                // the problem is solved again, as in `grow_solve`: at most m rounds.
                let mut rounds = 0;
                if !self.ws.idx.is_empty() {
                    // the kinetic metric's W_N, formed only for a problem with rows
                    self.del.prepare_position_metric();
                }
                while !self.ws.idx.is_empty() {
                    rounds += 1;
                    if !self.ws.over_cap() {
                        self.del
                            .ensure_all(&self.ws.idx, &self.sys.stiffness)
                            .map_err(|e| fail(&self.state, "Delassus columns", e))?;
                    }
                    self.ws
                        .gather(&self.del, Op::Wn, 1.0, b, &self.rs.tau_prev, eq)
                        .map_err(|e| fail(&self.state, "position MLCP", e))?;
                    let info = self
                        .ws
                        .solve(&mut self.del, &self.sys.stiffness, stats)
                        .map_err(|e| fail(&self.state, "position MLCP", e))?;
                    stats.lcp_iterations += info.iterations;
                    stats.lcp_residual = stats.lcp_residual.max(info.residual);
                    self.ws.scatter(&mut self.rs.tau);
                    // complementarity rows of the active set left out and now violated
                    let (off, pos) = (&self.cfg.off, &self.rs.pos_mask);
                    let candidates = (0..m).filter(|&c| pos[c]).map(|c| off[c]);
                    let grew = self.ws.add_violated(
                        (&mut self.del, &self.sys.stiffness),
                        (Op::Wn, 1.0),
                        b,
                        &self.rs.tau,
                        ptol,
                        candidates,
                        eq,
                    );
                    if !grew {
                        break;
                    }
                    if rounds > m {
                        stats.caps_hit += 1;
                        break;
                    }
                }
            }
        }
        Ok(self.rs.tau.iter().any(|&t| t != 0.0))
    }
}
