//! The step loop every run goes through ([`drive`]): after each step it checks the
//! state ([`RunChecks`]: non-finite values, exploded penetrations, iteration caps) and
//! hands it to the observers in order ([`Observer`]), and it reports progress
//! ([`Progress`]). It reserves nothing per step.

use crate::error::Error;
use crate::integrators::{Integrator, StepStats};

/// Receives progress; the CLI prints it, the library stays silent.
pub trait Progress {
    /// Called after `step` of `total` steps.
    fn update(&mut self, step: usize, total: usize);
    /// [`Progress::update`] with the simulated time (s) and the statistics of the step
    /// just taken: what the driver calls (the default forwards to `update`).
    fn update_with(&mut self, step: usize, total: usize, _time: f64, _stats: &StepStats) {
        self.update(step, total);
    }
    /// Called when a set-up phase starts (building the model, factoring `M̂` and
    /// condensing the Delassus data, which take tens of seconds on 10⁵–10⁶ dofs).
    fn phase(&mut self, _what: &str) {}
    /// Called once right before the first step, with the number of steps (rates and
    /// ETAs count from here, not from the set-up).
    fn start(&mut self, _total: usize) {}
    /// Asked after every step: `true` stops the run with [`Error::Interrupted`] after
    /// the step just taken (its outputs finished and readable); keep it cheap. The CLI never cancels (Ctrl-C ends the process; the files are written
    /// incrementally and atomically); the Python package does on `KeyboardInterrupt`.
    fn cancelled(&mut self) -> bool {
        false
    }
}

/// A progress sink that prints nothing.
pub struct Quiet;

impl Progress for Quiet {
    fn update(&mut self, _: usize, _: usize) {}
}

/// What the driver checks after every step (DESIGN.md §9): a state that turned
/// non-finite, a penetration that exploded, an iteration cap hit. Each stops the run with
/// [`Error::RunFailed`] (exit code 1) naming the step, the time and the contact.
#[derive(Clone, Copy, Debug)]
pub struct RunChecks {
    /// Count iteration caps in the statistics instead of failing the run
    /// (`scheme.allow_caps`, `--allow-caps`).
    pub allow_caps: bool,
    /// A penetration deeper than this (m) fails the run: no scheme of the paper lets a
    /// node sink through a body's own size, so the solution has exploded.
    pub max_violation: f64,
    /// The Newton / projection cap (`scheme.newton.max_iterations`), for the message.
    pub newton_cap: usize,
    /// The friction sweep cap (`scheme.friction.max_iterations`), for the message.
    pub friction_cap: usize,
    /// The friction solver (`scheme.friction.solver`), for the message: it advises
    /// only what the run has not tried.
    pub friction_solver: crate::solvers::friction::FrictionSolverKind,
    /// Largest relative energy excess (`scheme.max_energy_excess`; `None`: the default
    /// for the structure, [`crate::integrators::SchemeParams::energy_excess_limit`]).
    pub max_energy_excess: Option<f64>,
    /// `scheme.energy_momentum` (the default limit of large-deformation bodies).
    pub energy_momentum: bool,
    /// The scene's magnitudes that floor the energy check's scale
    /// ([`crate::model::energy::EnergyFloor`]).
    pub energy_floor: crate::model::energy::EnergyFloor,
}

/// How each command spells `scheme.allow_caps = true`, for the messages.
pub(crate) const ALLOW_CAPS_SPELLINGS: &str =
    "`signorini run`: --set scheme.allow_caps=true; `signorini bar`: --allow-caps";

/// How each command spells `scheme.max_energy_excess = X`, for the messages.
pub(crate) const MAX_ENERGY_EXCESS_SPELLINGS: &str = "`signorini run`: --set \
     scheme.max_energy_excess=X; `signorini bar`: --max-energy-excess X";

impl RunChecks {
    /// The energy check's limit on a structure that is `linear` or not.
    pub fn energy_excess_limit(&self, linear: bool) -> f64 {
        crate::integrators::energy_excess_limit(
            self.max_energy_excess,
            self.energy_momentum,
            linear,
        )
    }

    /// The checks of a run with `params`, on a model whose bounding box has diagonal
    /// `size` (m; 0 or non-finite when the model has no geometry: no violation limit).
    pub fn new(params: &crate::integrators::SchemeParams, size: f64) -> Self {
        RunChecks {
            allow_caps: params.allow_caps,
            max_violation: if size.is_finite() && size > 0.0 {
                size
            } else {
                f64::INFINITY
            },
            newton_cap: params.newton.max_iterations,
            friction_cap: params.friction.max_iterations,
            friction_solver: params.friction.solver,
            max_energy_excess: params.max_energy_excess,
            energy_momentum: params.energy_momentum,
            energy_floor: crate::model::energy::EnergyFloor {
                size: if size.is_finite() { size.max(0.0) } else { 0.0 },
                wave_speed_sq: 0.0,
                strain: params.newton.tol,
            },
        }
    }

    /// [`RunChecks::new`] on a model with this geometry: its size, and the largest wave
    /// speed `E/ρ` of its bodies for the energy floor.
    pub fn for_geometry(
        params: &crate::integrators::SchemeParams,
        geometry: &crate::model::geometry::Geometry,
    ) -> Self {
        let mut c = Self::new(params, geometry.size());
        c.energy_floor.wave_speed_sq = geometry
            .bodies
            .iter()
            .map(|(m, _)| m.young / m.density)
            .filter(|c2| c2.is_finite())
            .fold(0.0, f64::max);
        c
    }

    /// Checks the state after a step; the error names the step, time and contact.
    pub fn check(&self, integ: &dyn Integrator, st: &StepStats) -> Result<(), Error> {
        let s = integ.state();
        let fail = |contact: Option<usize>, detail: String| Error::RunFailed {
            step: s.step,
            time: s.time,
            contact,
            detail,
        };
        let deepest = || {
            s.gap
                .iter()
                .enumerate()
                .min_by(|a, b| a.1.total_cmp(b.1))
                .map(|(c, _)| c)
        };
        // the integrator may have tested q and v while forming them
        let known = integ.state_finite() == Some(true);
        for (name, v, per_contact) in [
            ("displacement", &s.q, false),
            ("velocity", &s.v, false),
            ("impulse", &s.impulse, true),
            ("gap", &s.gap, true),
        ] {
            if (known && !per_contact) || all_finite(v) {
                continue;
            }
            let i = v.iter().position(|x| !x.is_finite()).unwrap_or(0);
            let (contact, at) = if per_contact {
                (Some(i), String::new())
            } else {
                (None, format!(" of dof {i}"))
            };
            return Err(fail(
                contact,
                format!(
                    "the {name}{at} is {}: the solution broke down (lower the time step, \
                     check the material and loads)",
                    v[i]
                ),
            ));
        }
        if st.max_violation > self.max_violation {
            return Err(fail(
                deepest(),
                format!(
                    "penetration {:.3e} m exceeds the model's size {:.3e} m: the solution \
                     exploded (lower the time step)",
                    st.max_violation, self.max_violation
                ),
            ));
        }
        if st.caps_hit > 0 && !self.allow_caps {
            let detail = if st.friction_caps > 0 {
                use crate::solvers::friction::FrictionSolverKind as K;
                // `auto` already ran everything it has: switching the solver cannot
                // help it, only the budget or the step can; `nsgs` and `prox` lack
                // the Newton methods `auto` adds
                let switch = match self.friction_solver {
                    K::Nsgs | K::Prox => {
                        ", try scheme.friction.solver = \"auto\" (the Newton methods after \
                         NSGS, PROX beyond 1024 contact rows)"
                    }
                    _ => "",
                };
                format!(
                    "the {} friction solver stopped at its cap of {} sweeps with residual \
                     {:.3e} (raise scheme.friction.max_iterations{switch}, lower the time \
                     step, or set scheme.allow_caps = true to count caps instead: \
                     {ALLOW_CAPS_SPELLINGS})",
                    self.friction_solver.name(),
                    self.friction_cap,
                    st.friction_residual
                )
            } else {
                format!(
                    "an iteration loop stopped at its cap (Newton/projection cap {}, residual \
                     {:.3e}; LCP residual {:.3e}): raise scheme.newton.max_iterations or lower \
                     the time step, or set scheme.allow_caps = true to count caps instead \
                     ({ALLOW_CAPS_SPELLINGS})",
                    self.newton_cap, st.newton_residual, st.lcp_residual
                )
            };
            return Err(fail(deepest(), detail));
        }
        Ok(())
    }
}

/// Whether every value is finite, in eight independent lanes (`0 · x` is NaN exactly for
/// an infinite or NaN `x`), so the check vectorizes: about 0.1 µs for the bar's 2 × 1001
/// values, where a scan with an early exit costs microseconds.
fn all_finite(x: &[f64]) -> bool {
    let mut acc = [0.0f64; 8];
    let mut chunks = x.chunks_exact(8);
    for c in &mut chunks {
        for i in 0..8 {
            acc[i] += c[i] * 0.0;
        }
    }
    let tail: f64 = chunks.remainder().iter().map(|v| v * 0.0).sum();
    (acc.iter().sum::<f64>() + tail) == 0.0
}

/// Something that looks at the run after every step: the history and frame writers,
/// the contact measurement, a study's trajectory. Called in order after the checks.
pub trait Observer {
    /// The step just taken (`integ.state()` is the state after it); `last` on the final
    /// step of the run.
    fn observe(
        &mut self,
        integ: &dyn Integrator,
        stats: &StepStats,
        last: bool,
    ) -> Result<(), Error>;
}

impl<F> Observer for F
where
    F: FnMut(&dyn Integrator, &StepStats, bool) -> Result<(), Error>,
{
    fn observe(
        &mut self,
        integ: &dyn Integrator,
        stats: &StepStats,
        last: bool,
    ) -> Result<(), Error> {
        self(integ, stats, last)
    }
}

/// The one step loop every run goes through (scenes, the bar, the examples, the
/// studies): steps `integ` from its current step up to `steps`, checks each state
/// ([`RunChecks`]), hands it to the observers in order, and reports progress.
pub fn drive(
    integ: &mut dyn Integrator,
    steps: usize,
    checks: &RunChecks,
    observers: &mut [&mut dyn Observer],
    progress: &mut dyn Progress,
) -> Result<(), Error> {
    progress.start(steps);
    drive_to(integ, steps, steps, checks, observers, progress)
}

/// [`drive`] stopping at step `until` of a run of `steps` (the observers' `last` is the
/// run's last step, progress is reported against `steps`): a run taken in parts, as the
/// Python package's `step(n)` takes it, goes through the same loop as a whole one.
pub fn drive_to(
    integ: &mut dyn Integrator,
    until: usize,
    steps: usize,
    checks: &RunChecks,
    observers: &mut [&mut dyn Observer],
    progress: &mut dyn Progress,
) -> Result<(), Error> {
    // at most 1000 calls (and the last step): ⌈steps / 1000⌉ apart
    let report_every = steps.div_ceil(1000).max(1);
    let first = integ.state().step;
    for k in first..until.min(steps) {
        integ.prepare()?;
        let st = integ.step()?;
        checks.check(integ, &st)?;
        let last = k + 1 == steps;
        for o in observers.iter_mut() {
            o.observe(integ, &st, last)?;
        }
        if (k + 1) % report_every == 0 || last {
            progress.update_with(k + 1, steps, integ.state().time, &st);
        }
        // asked at every step (a flag for the Python package's `cancel()`, `false` for
        // the CLI): a stop comes one step after it is asked for
        if progress.cancelled() {
            let s = integ.state();
            return Err(Error::Interrupted {
                step: s.step,
                time: s.time,
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::all_finite;

    #[test]
    fn finiteness_is_checked_in_every_lane_and_the_tail() {
        let mut x = vec![1e300; 21];
        assert!(all_finite(&x));
        for i in [0, 7, 8, 15, 16, 20] {
            for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                x[i] = bad;
                assert!(!all_finite(&x), "{bad} at {i}");
                x[i] = -1e300;
            }
        }
        assert!(all_finite(&[]));
    }
}
