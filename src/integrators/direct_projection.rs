//! Direct projection, Algorithm 1 (decoupled implementation, eq. 28, 56–58, 60).
//!
//! The Moreau–Jean step (velocity LCP on the forecast-active set, eq. 57) followed in
//! every Newton iteration by the position LCP `0 ≤ g_{k+1} ⊥ τ ≥ 0` over all contacts
//! (eq. 58 with `N = I`, eq. 60 with `N = M̂⁻¹`), and the coupling `−hθK N G τⁿ` of
//! eq. 56a fed back into the next velocity solve. Both position and velocity
//! constraints hold in discrete time; after an accumulation of impacts the scheme can
//! chatter (sec. 4.5, Fig. 4).

use super::core::{PositionRule, ThetaCore, VelocityLaw, delegate_to_core};
use super::{Forecast, Integrator, SchemeParams, StepStats};
use crate::contact::ContactSet;
use crate::error::Error;
use crate::model::LinearSystem;

/// Algorithm 1.
pub struct DirectProjection {
    core: ThetaCore,
    forecast: Forecast,
}

impl DirectProjection {
    /// Factors `M̂` and condenses `W`, `W_D`, `W_N` once.
    pub fn new(
        params: &SchemeParams,
        system: LinearSystem,
        contacts: Box<dyn ContactSet>,
        q0: &[f64],
        v0: &[f64],
        h: f64,
    ) -> Result<Self, Error> {
        Ok(DirectProjection {
            core: ThetaCore::new(params, system, contacts, q0, v0, h, true)?,
            forecast: params.forecast,
        })
    }
}

impl Integrator for DirectProjection {
    fn name(&self) -> &'static str {
        "direct-projection"
    }
    fn step(&mut self) -> Result<StepStats, Error> {
        let mut st = StepStats::default();
        self.core.begin_step(&mut st)?;
        self.core.forecast(self.forecast);
        self.core.newton(
            VelocityLaw::Impact,
            PositionRule::AllComplementarity,
            &mut st,
        )?;
        self.core.commit(&mut st);
        Ok(st)
    }
    delegate_to_core!();
}
