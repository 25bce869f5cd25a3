//! Direct projection, Algorithm 1 (decoupled implementation, eq. 28, 56–58, 60).
//!
//! The Moreau–Jean step (velocity LCP on the forecast-active set, eq. 57) followed in
//! every Newton iteration by the position LCP `0 ≤ g_{k+1} ⊥ τ ≥ 0` over all contacts
//! (eq. 58 with `N = I`, eq. 60 with `N = M̂⁻¹`), and the coupling `−hθK N G τⁿ` of
//! eq. 56a fed back into the next velocity solve. Both position and velocity
//! constraints hold in discrete time; after an accumulation of impacts the scheme can
//! chatter (sec. 4.5, Fig. 4).
//!
//! With [`SchemeParams::activation_closure`] (the default) the forecast's active set is
//! closed on the solution, as Moreau–Jean's is: a contact outside it whose gap at the
//! end of the step before the projection, `g_k + h((1−θ)U_k + θU_{k+1})`, is `≤ 0` joins
//! the velocity problem and the step is solved again. Without it the position problem
//! of eq. 58 pushes such contacts out with no impulse (`τ > 0`, `P = 0`), leaving them on
//! the obstacle while they move into it; between stacked elastic bodies that chatters
//! and adds energy (issue 33: +74 % and +100 % on `meshes/block_stack.toml` at 4× and 8×
//! its step, 1.7e-6–2.8e-6 of the energy on the Hertz ball at ⅛–½ of its step, 1.1e-3 on
//! the ball drop with e = 1; none with the closure).

use super::SchemeKind;
use super::core::{PositionRule, ThetaCore, delegate_to_core};
use super::problem::Problem;
use super::{Forecast, Integrator, SchemeParams, StepStats};
use crate::error::Error;

/// Algorithm 1.
pub struct DirectProjection {
    core: ThetaCore,
    forecast: Forecast,
    closure: bool,
}

impl DirectProjection {
    /// Factors `M̂` and condenses `W`, `W_D`, `W_N` once.
    pub fn new(params: &SchemeParams, problem: Problem, h: f64) -> Result<Self, Error> {
        Ok(DirectProjection {
            core: ThetaCore::new(params, problem, h, true)?,
            forecast: params.forecast,
            closure: params.activation_closure,
        })
    }
}

impl Integrator for DirectProjection {
    fn kind(&self) -> SchemeKind {
        SchemeKind::DirectProjection
    }
    fn step(&mut self) -> Result<StepStats, Error> {
        let mut st = StepStats::default();
        let c = &mut self.core;
        c.begin_step(&mut st)?;
        c.forecast(self.forecast);
        c.closed_newton(PositionRule::AllComplementarity, self.closure, &mut st)?;
        c.commit(&mut st);
        Ok(st)
    }
    delegate_to_core!();
}
