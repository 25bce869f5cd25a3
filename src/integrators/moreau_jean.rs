//! Moreau–Jean time-stepping (eq. 18): θ-method for the smooth dynamics, Newton's
//! impact law `0 ≤ U_{k+1} + e U_k ⊥ P_{k+1} ≥ 0` at velocity level on the contacts
//! activated by the forecast `ḡ_{k+1} ≤ 0` (eq. 61 or 62). Positions drift by
//! `O(h)`: on the impacting bar the penetration is `|v0|(1−θ)h`.
//!
//! The forecast of eq. 62 predicts each contact's gap from the free velocity, which
//! ignores the impulses of the other contacts. On one contact that is exact (an inactive
//! contact has `P = 0`, so `U_{k+1} = U_free`); on a contact patch between curved bodies
//! it is not: a node at the edge of a growing patch, dragged in by its neighbours'
//! impulses, ends steps at `g < 0` while closing and gets no impulse for 5–40 steps
//! (issue 33: 6× the bound `|U|(1−θ)h` on `meshes/hertz_spheres.toml` at h = 1.25e-8).
//! With [`SchemeParams::activation_closure`] (the default) the forecast set is closed
//! on the solution: every contact whose gap at the end of the step,
//! `g_k + h((1−θ)U_k + θU_{k+1})` (eq. 51 with the solved `U_{k+1}`), is `≤ 0` joins the
//! set and the step is solved again, as Algorithm 2's activation (eq. 66) grows its set.
//! The set only grows, so at most `m` rounds run ([`StepStats::index_set_iterations`]
//! counts the rounds after the first);
//! a contact left out then ends the step open (linear `G`), and an active one within
//! `|U_k|(1−θ)h` below where it started. `activation_closure = false` is eq. 61/62 alone.

use super::SchemeKind;
use super::core::{PositionRule, ThetaCore, delegate_to_core};
use super::problem::Problem;
use super::{Forecast, Integrator, SchemeParams, StepStats};
use crate::error::Error;

/// The Moreau–Jean integrator.
pub struct MoreauJean {
    core: ThetaCore,
    forecast: Forecast,
    closure: bool,
}

impl MoreauJean {
    /// Factors `M̂` and condenses `W` once.
    pub fn new(params: &SchemeParams, problem: Problem, h: f64) -> Result<Self, Error> {
        Ok(MoreauJean {
            core: ThetaCore::new(params, problem, h, false)?,
            forecast: params.forecast,
            closure: params.activation_closure,
        })
    }
}

impl Integrator for MoreauJean {
    fn kind(&self) -> SchemeKind {
        SchemeKind::MoreauJean
    }
    fn step(&mut self) -> Result<StepStats, Error> {
        let mut st = StepStats::default();
        let c = &mut self.core;
        c.begin_step(&mut st)?;
        c.forecast(self.forecast);
        c.closed_newton(PositionRule::None, self.closure, &mut st)?;
        c.commit(&mut st);
        Ok(st)
    }
    delegate_to_core!();
}
