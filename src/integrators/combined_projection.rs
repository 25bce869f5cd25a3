//! Combined activation/projection, Algorithm 2 (eq. 65–70).
//!
//! Start from `I⁰ = ∅` (the free step), solve the projection step (65) for the current
//! set — impact law on `Iᵛ`, `g^α = 0` with free `τ^α` on the rows [`ProjectionRule`]
//! holds, `0 ≤ g ⊥ τ ≥ 0` on the rest of `Iᵛ` — then add every contact with `g_{k+1} ≤ 0`
//! (eq. 66) and repeat until the set is stable. The set only grows, so at most `m + 1`
//! rounds run; the count is reported in [`StepStats::index_set_iterations`].
//!
//! Which rows are held: by default those whose impulse is positive in this step and in
//! the last ([`ProjectionRule::Persistent`]); the paper's eq. 67–70 hold every row with
//! `P > 0` ([`ProjectionRule::Paper`]), which pulls a node that carries its first impulse
//! onto the obstacle and, on elastic bodies, throws it off through the feedback of eq.
//! 56a (issue 33; docs/bar.md, "Algorithm 2's position rule"); `AllActive` holds every active
//! row, as Siconos does (its `P > 0` test is commented out), and `Complementarity` none.
//!
//! Eq. 65 need not have a solution for an index set (rows with `P > 0` held at `g = 0`
//! may need `τ < 0`, which makes their `P` vanish; as complementarity rows their `P` is
//! positive again): the Newton loop then cycles to its cap, or ends with a row at
//! `P = 0` and `τ < 0`. Such a round is redone with Algorithm 1's rule, `0 ≤ g ⊥ τ ≥ 0`
//! on every active row (eq. 58), and counted in
//! [`StepStats::complementarity_fallbacks`]: the step is then a direct-projection step,
//! exact at position level with `τ ≥ 0` wherever `P = 0` (docs/friction.md, "Algorithm 2 with
//! friction on undamped elastic bodies").

use super::SchemeKind;
use super::core::{PositionRule, ThetaCore, VelocityLaw, delegate_to_core};
use super::problem::Problem;
use super::{Integrator, ProjectionRule, SchemeParams, StepStats};
use crate::error::Error;

/// Algorithm 2.
pub struct CombinedProjection {
    core: ThetaCore,
    rule: ProjectionRule,
}

impl CombinedProjection {
    /// Factors `M̂` and condenses `W`, `W_D`, `W_N` once.
    pub fn new(params: &SchemeParams, problem: Problem, h: f64) -> Result<Self, Error> {
        Ok(CombinedProjection {
            core: ThetaCore::new(params, problem, h, true)?,
            rule: params.projection_rule,
        })
    }
}

impl Integrator for CombinedProjection {
    fn kind(&self) -> SchemeKind {
        SchemeKind::CombinedProjection
    }
    fn step(&mut self) -> Result<StepStats, Error> {
        let mut st = StepStats::default();
        let c = &mut self.core;
        c.begin_step(&mut st)?;
        c.rs.vel_mask.iter_mut().for_each(|x| *x = false);
        let rule = PositionRule::Combined { rule: self.rule };
        loop {
            st.index_set_iterations += 1;
            c.rs.pos_mask.copy_from_slice(&c.rs.vel_mask);
            let (caps, friction_caps) = (st.caps_hit, st.friction_caps);
            c.newton(VelocityLaw::Impact, rule, &mut st)?;
            if st.caps_hit > caps || st.held_rows > 0 {
                // the round is redone: its caps are not the step's
                (st.caps_hit, st.friction_caps) = (caps, friction_caps);
                st.held_rows = 0;
                st.complementarity_fallbacks += 1;
                c.newton(
                    VelocityLaw::Impact,
                    PositionRule::AllComplementarity,
                    &mut st,
                )?;
            }
            // activation (eq. 66)
            if !c.activate_violated(false) {
                break;
            }
            if st.index_set_iterations > c.cfg.m {
                // unreachable while the set only grows; kept as a reported cap
                st.caps_hit += 1;
                break;
            }
        }
        c.commit(&mut st);
        Ok(st)
    }
    delegate_to_core!();
}
