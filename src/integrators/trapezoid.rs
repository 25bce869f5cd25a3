//! θ-method (trapezoidal rule for θ = 1/2) with Signorini's condition at position
//! level, `0 ≤ g(q_{k+1}) ⊥ P ≥ 0`, and an implicit contact impulse (sec. 6.2, Fig. 11).
//!
//! Keeps the position constraint exactly, but as an index-3 formulation it makes the
//! contact velocity and force oscillate step to step (the paper's Fig. 11).

use super::SchemeKind;
use super::core::{PositionRule, ThetaCore, VelocityLaw, delegate_to_core};
use super::problem::Problem;
use super::{Integrator, SchemeParams, StepStats};
use crate::error::Error;

/// The position-level trapezoidal rule.
pub struct TrapezoidPosition {
    core: ThetaCore,
}

impl TrapezoidPosition {
    /// Factors `M̂` and condenses `W` once.
    pub fn new(params: &SchemeParams, problem: Problem, h: f64) -> Result<Self, Error> {
        Ok(TrapezoidPosition {
            core: ThetaCore::new(params, problem, h, false)?,
        })
    }
}

impl Integrator for TrapezoidPosition {
    fn kind(&self) -> SchemeKind {
        SchemeKind::TrapezoidPosition
    }
    fn step(&mut self) -> Result<StepStats, Error> {
        let mut st = StepStats::default();
        self.core.begin_step(&mut st)?;
        self.core
            .newton(VelocityLaw::PositionLevel, PositionRule::None, &mut st)?;
        self.core.commit(&mut st);
        Ok(st)
    }
    delegate_to_core!();
}
