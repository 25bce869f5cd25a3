//! Moreau–Jean time-stepping (eq. 18): θ-method for the smooth dynamics, Newton's
//! impact law `0 ≤ U_{k+1} + e U_k ⊥ P_{k+1} ≥ 0` at velocity level on the contacts
//! activated by the forecast `ḡ_{k+1} ≤ 0` (eq. 61 or 62). Positions drift by
//! `O(h)`: on the impacting bar the penetration is `|v0|(1−θ)h`.

use super::core::{PositionRule, ThetaCore, VelocityLaw, delegate_to_core};
use super::{Forecast, Integrator, SchemeParams, StepStats};
use crate::contact::ContactSet;
use crate::error::Error;
use crate::model::LinearSystem;

/// The Moreau–Jean integrator.
pub struct MoreauJean {
    core: ThetaCore,
    forecast: Forecast,
}

impl MoreauJean {
    /// Factors `M̂` and condenses `W` once.
    pub fn new(
        params: &SchemeParams,
        system: LinearSystem,
        contacts: Box<dyn ContactSet>,
        q0: &[f64],
        v0: &[f64],
        h: f64,
    ) -> Result<Self, Error> {
        Ok(MoreauJean {
            core: ThetaCore::new(params, system, contacts, q0, v0, h, false)?,
            forecast: params.forecast,
        })
    }
}

impl Integrator for MoreauJean {
    fn name(&self) -> &'static str {
        "moreau-jean"
    }
    fn step(&mut self) -> Result<StepStats, Error> {
        let mut st = StepStats::default();
        self.core.begin_step(&mut st)?;
        self.core.forecast(self.forecast);
        self.core
            .newton(VelocityLaw::Impact, PositionRule::None, &mut st)?;
        self.core.commit(&mut st);
        Ok(st)
    }
    delegate_to_core!();
}
