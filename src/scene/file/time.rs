//! The `[time]` table's modes: a constant step, or the accuracy mode's request
//! ([`crate::run::accuracy`]).

use super::TimeSpec;

impl TimeSpec {
    /// A run of constant step `dt` to `t_end`.
    pub fn fixed(dt: f64, t_end: f64) -> Self {
        TimeSpec {
            dt,
            t_end,
            accuracy: None,
            dt_max: None,
            dt_min: None,
        }
    }

    /// The accuracy mode's request, when `accuracy` is set (checked by
    /// [`super::Scene::validate`]).
    pub fn accuracy_spec(&self) -> Option<crate::run::accuracy::AccuracySpec> {
        let tol = self.accuracy?;
        let dt_max = self.dt_max.unwrap_or(self.dt);
        Some(crate::run::accuracy::AccuracySpec {
            tol,
            dt_max,
            dt_min: self
                .dt_min
                .unwrap_or(dt_max * 0.5f64.powi(crate::run::accuracy::DEFAULT_RUNGS as i32)),
            t_end: self.t_end,
        })
    }
}
