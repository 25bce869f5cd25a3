//! The accuracy mode's request ([`AccuracySpec`], its ladder and checks) and report
//! ([`AccuracySummary`], the failure of a run that missed its accuracy).

use serde::{Deserialize, Serialize};

use crate::error::Error;

use super::MAX_RUNGS;

/// The request: `[time] accuracy`, `dt_max`, `dt_min` of a scene (`--accuracy` of the
/// CLI).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AccuracySpec {
    /// Relative accuracy asked of the observables (`time.accuracy`).
    pub tol: f64,
    /// Largest step (s): `time.dt_max`, else `time.dt`.
    pub dt_max: f64,
    /// Smallest step (s): `time.dt_min`, else `dt_max / 2¹⁰`.
    pub dt_min: f64,
    /// The run's end (s).
    pub t_end: f64,
}

impl AccuracySpec {
    /// Checks the request: `0 < tol < 1`, `0 < dt_min ≤ dt_max ≤ t_end`, at most
    /// [`MAX_RUNGS`] rungs between them. `keys` names the fields in the errors.
    pub fn validate(&self, keys: [&str; 3]) -> Result<(), Error> {
        if !(self.tol > 0.0 && self.tol < 1.0) {
            return Err(Error::invalid(
                keys[0],
                self.tol,
                "expected a relative accuracy in (0, 1), e.g. 1e-2",
            ));
        }
        crate::error::require_positive(keys[1], self.dt_max)?;
        crate::error::require_positive(keys[2], self.dt_min)?;
        if self.dt_min > self.dt_max {
            return Err(Error::invalid(
                keys[2],
                self.dt_min,
                &format!("expected at most {} = {:e} s", keys[1], self.dt_max),
            ));
        }
        if self.rungs() > MAX_RUNGS {
            return Err(Error::invalid(
                keys[2],
                self.dt_min,
                &format!(
                    "expected at least {} / 2^{MAX_RUNGS} = {:e} s",
                    keys[1],
                    self.dt_max / 2f64.powi(MAX_RUNGS as i32)
                ),
            ));
        }
        Ok(())
    }

    /// The floor rung `K`: the last `k` with `dt_max · 2⁻ᵏ ≥ dt_min` (to 10⁻⁹).
    pub fn rungs(&self) -> u32 {
        let r = (self.dt_max / self.dt_min).log2();
        if !r.is_finite() || r < 0.0 {
            return 0;
        }
        (r + 1e-9).floor().min(1e3) as u32
    }

    /// The accepted steps of the ladder, largest first.
    pub fn ladder(&self) -> Vec<f64> {
        (0..=self.rungs()).map(|k| self.step(k)).collect()
    }

    /// The step of rung `k` (s).
    pub fn step(&self, k: u32) -> f64 {
        self.dt_max * 0.5f64.powi(k as i32)
    }
}

/// What an accuracy run's estimates cover ([`AccuracySummary::scope`]).
pub const SCOPE: &str = "time: the step's error on this mesh; the mesh's (space) error is not \
                         estimated (`sweep --refine` with a time.accuracy axis says which dominates)";

impl AccuracyEstimates {
    /// The largest estimate.
    pub fn largest(&self) -> f64 {
        self.impulse_history
            .max(self.energy)
            .max(self.gaps)
            .max(self.state)
    }
}

/// The observables the controller compares (in [`AccuracySummary`] order).
pub const OBSERVABLES: [&str; 4] = ["impulse_history", "energy", "gaps", "state"];

/// Estimated errors per observable, relative to their scales (module doc).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct AccuracyEstimates {
    /// The cumulative contact impulse: `Σ |P_A − P_B|` over the windows, relative to the
    /// total impulse. It bounds the cumulative impulse's error at the end and its error
    /// in time, `∫|P − P_ref| dt / (P_ref(T) T)` (`signorini study accuracy`'s
    /// `impulse_in_time`; [`super`] says why not the sweep's sampled measure).
    pub impulse_history: f64,
    /// The energy: `Σ |E_A − E_B|`, relative to the largest energy met.
    pub energy: f64,
    /// The gaps: the largest `max_c |g_A − g_B|` over the contacts that opened or closed
    /// with an open gap (event location), relative to the largest gap change.
    pub gaps: f64,
    /// The displacement field in the mass norm `‖e_q‖_M = √(e_qᵀ M e_q)`: `Σ ‖q_A −
    /// q_B‖_M` relative to the largest `‖q − q₀‖_M` met. It sees what the contact's
    /// observables meet only later (the wave inside a body, which comes back to the
    /// contact) and weights a mode by its displacement, so the highest modes of a mesh,
    /// whose phase no affordable step resolves, count as little as they move.
    pub state: f64,
}

/// The companion run's differences from the run, relative to the same scales as
/// [`AccuracyEstimates`] ([`super`]: the companion takes one step per kept window, from
/// its own state). Undivided: where the step's error is first order (an impact, a
/// release, the θ-method at θ ≠ ½), the companion's is twice the run's and the
/// difference the run's own; where it is second order, three times the run's.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct CompanionEstimates {
    /// `∫₀ᵀ |P − P_c| dt / (P(T) T)`: the cumulative contact impulse in time.
    pub impulse_history: f64,
    /// `|E(T) − E_c(T)|` relative to the largest energy met.
    pub energy: f64,
    /// `‖q(T) − q_c(T)‖_M` relative to the largest `‖q − q₀‖_M` met.
    pub state: f64,
    /// Times the companion failed a step and started again from the run's state (its
    /// differences before then are kept; what it would have made after is lost).
    pub resyncs: usize,
}

/// What the accuracy mode did and estimates (`summary.json` `accuracy`).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct AccuracySummary {
    /// The requested relative accuracy.
    pub target: f64,
    /// Whether the estimates are all within `target` (the windows accepted at the floor
    /// included: their differences are in the sums).
    pub met: bool,
    /// Estimated error per observable: the larger of the windows' estimates
    /// ([`AccuracySummary::local`]) and the companion run's difference
    /// ([`AccuracySummary::companion`]).
    pub estimated: AccuracyEstimates,
    /// The windows' own estimates (sums of `|A − B|` from each window's start).
    pub local: AccuracyEstimates,
    /// The companion run's differences from the run (global: what an error made in one
    /// window does to the observables later).
    pub companion: CompanionEstimates,
    /// The scale of the displacement field's estimates: the largest `‖q − q₀‖_M` met
    /// (m·√kg; the pilot's included).
    pub state_scale: f64,
    /// What the estimates cover: the time discretisation's error on the mesh the run
    /// has ([`SCOPE`]); the mesh's own error is not estimated.
    pub scope: String,
    /// The observable that limited the step most often (its ratio was the largest in a
    /// window that was rejected or could not grow).
    pub bounded_by: String,
    /// Windows accepted (each two steps of the run).
    pub windows: usize,
    /// Windows rejected (taken again at a smaller step).
    pub rejected: usize,
    /// Steps taken in all: the comparison steps `A`, the companion's and the rejected
    /// windows' included.
    pub steps_taken: usize,
    /// Windows accepted at the floor with `ε > 1`: where the local allowance was not
    /// reached (an accumulation of impacts, a contact that chatters); their differences
    /// are in the estimates, which say whether the run as a whole met `target`.
    pub floor_windows: usize,
    /// Smallest and largest step the run kept (s).
    pub dt_min_used: f64,
    /// Largest step the run kept (s).
    pub dt_max_used: f64,
    /// The ladder's steps, largest first (s).
    pub ladder: Vec<f64>,
    /// Factorizations of `M̂(h)` the comparison and rejected steps made (the kept steps'
    /// are in the run's statistics).
    pub trial_factorizations: usize,
}

impl AccuracySummary {
    /// The error of a run that did not reach its accuracy (exit code 1), or `None`.
    pub fn failure(&self) -> Option<Error> {
        if self.met {
            return None;
        }
        let e = &self.estimated;
        let over: Vec<String> = [
            ("impulse_history", e.impulse_history),
            ("energy", e.energy),
            ("gaps", e.gaps),
            ("state", e.state),
        ]
        .iter()
        .filter(|(_, x)| *x > self.target)
        .map(|(n, x)| format!("{n} {x:.3e}"))
        .collect();
        let mut detail = format!("estimated errors above it: {}", over.join(", "));
        let c = &self.companion;
        if c.impulse_history.max(c.energy).max(c.state) > self.target {
            detail.push_str(&format!(
                " (the companion run at twice the steps differs by impulse history {:.3e}, \
                 energy {:.3e}, state {:.3e}: an error made in one window and met later; \
                 a smaller time.accuracy or time.dt asks for more)",
                c.impulse_history, c.energy, c.state
            ));
        }
        if self.floor_windows > 0 {
            detail.push_str(&format!(
                "; {} window(s) at the smallest step dt_min = {:e} s missed their allowance \
                 (lower time.dt_min, or ask a looser time.accuracy)",
                self.floor_windows,
                self.ladder.last().copied().unwrap_or(f64::NAN)
            ));
        }
        Some(Error::AccuracyNotMet {
            target: self.target,
            detail,
        })
    }
}
