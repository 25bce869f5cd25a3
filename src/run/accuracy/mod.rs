//! The accuracy mode (issue 50): the run chooses its steps to meet a requested accuracy
//! `TOL` on its observables and reports the error it estimates.
//!
//! **The ladder.** Accepted steps are `h_k = dt_max · 2⁻ᵏ`, `k = 0 … K`, down to the
//! floor `dt_min` (by default `dt_max / 2¹⁰`): a structure whose `M̂` is constant keeps
//! the factor and Delassus data of the few steps in use
//! ([`crate::integrators::Integrator::set_dt`], cached within
//! [`crate::integrators::core::STEP_CACHE_BYTES`]); a nonlinear one refactors as it does
//! at every step anyway.
//!
//! **The estimate: step doubling** (Richardson; as MBSim's time-stepping integrator of
//! Moreau's scheme, Studer, Leine & Glocker, IJNME 76, 2008). A window of length `H`
//! from the state `S₀` is taken once at `H` (state `A`) and, from `S₀` again, as two
//! steps at `H/2` (`B₁`, `B₂`); `B₁` and `B₂` are what the run keeps (the observers see
//! them, in order, as the steps they are), `A` serves only the comparison. The θ-method
//! (eq. 18, 42–48) has a local error `O(H^{p+1})` in smooth phases (`p = 2` at θ = ½,
//! `p = 1` otherwise and across impacts), so `|A − B|` bounds the error of `B` from
//! above for every `p ≥ 1` (it is `(2^p − 1)` times that error asymptotically): the
//! estimate written is `|A − B|`, never divided down.
//!
//! **What is compared**, each against an allowance of `TOL` (the sweep's measures,
//! [`crate::study::sweep`], so that what the run promises is what a sweep checks):
//! - the **contact impulse over the window** `Σ_c P_c` (the normal impulses of every
//!   contact; impulses are compared over the window, never per step, so an impact
//!   placed in either half of it is the same impulse): allowance
//!   `TOL (½ |P_B| + ½ S · H/T)`, with `P_B` the window's impulse, `S` the run's
//!   cumulative impulse so far and `T` the run's span. Summed over the run the
//!   allowances come to at most `TOL` times the total impulse, so the estimated error of
//!   the cumulative impulse history (the sweep's `impulse_history_error`) stays within
//!   `TOL`;
//! - the **energy** `E = K + V` at the window's end: allowance
//!   `TOL (½ |E_B − E_{S₀}| + ½ E_s · H/T)`, `E_s` the largest energy met (floored by the
//!   energy check's scale, [`crate::model::energy::EnergyFloor`]): within `TOL E_s` over
//!   a run whose energy varies by at most `E_s` (the sweep's `energy_error`);
//! - the **gaps** of every contact at the window's end, which place the next impacts
//!   and releases (event location: a window whose `B` locates a closing or an opening
//!   that `A` misplaces differs by the distance travelled in between): allowance
//!   `TOL ℓ · H/T` in smooth windows (error per unit step: the position error summed
//!   over the run stays within `TOL ℓ`) and `TOL ℓ` in windows where a contact opens or
//!   closes, `ℓ` the largest gap change met so far (floored at 10⁻⁹ of the model's
//!   size);
//! - the **displacement field** in the mass norm `‖q_A − q_B‖_M`: allowance
//!   `TOL U · H/T` (smooth windows; `TOL U` where a contact opens or closes), `U` the
//!   largest `‖q − q₀‖_M` met. The contact's observables meet an error made inside a
//!   body only when its wave comes back to the contact (the bar at a fixed 1e-5 s
//!   smears its wave and leaves at 0.095 m/s for 0.1, with window impulses that agree
//!   at 1e-5 and 5e-6 s); this norm sees it where it is made. It weights a mode by its
//!   displacement, so the highest modes of a mesh, whose phase no affordable step
//!   resolves (the energy norm of the same difference does not converge on the bar
//!   above h = 10⁻⁹ s), count as little as they move.
//!
//! The window's error ratio `ε` is the largest of the four ratios. `ε ≤ 1` accepts it;
//! the step then grows one rung after two windows with `ε` below `2^{-(p+1)}` (so that
//! the doubled step would still pass), and stays otherwise. `ε > 1` rejects it and goes
//! down `⌈log₂ ε / p⌉` rungs (at least one). A window at the floor rung is accepted
//! whatever `ε` (the run continues, its outputs whole) and counted: a run that met the
//! floor, or whose summed estimate exceeds `TOL`, reports that it could not reach the
//! accuracy and fails with exit code 1 ([`Error::AccuracyNotMet`]) after writing its
//! outputs and summary — never a silent exit 0.
//!
//! Why hand-written: no crate offers an error controller for a nonsmooth one-step scheme
//! (the ODE crates control smooth local errors of their own Runge–Kutta steps).

use serde::{Deserialize, Serialize};

use crate::error::Error;
use crate::integrators::saved::IntegratorState;
use crate::integrators::{Integrator, StepStats};

use super::driver::{Observer, RunChecks};

mod spec;
pub use spec::*;

/// Rungs below `dt_max` when `time.dt_min` is not given: `dt_min = dt_max / 2¹⁰`.
pub const DEFAULT_RUNGS: u32 = 10;

/// Rungs at most (`dt_max / 2⁴⁰`: far below any step a run can afford).
pub const MAX_RUNGS: u32 = 40;

/// Windows with a small error before the step grows one rung.
const CALM_WINDOWS: u32 = 2;

/// What a checkpoint keeps of the controller.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ControllerState {
    /// The gaps at the run's start (the gap scale is their largest change).
    pub gap0: crate::integrators::saved::Floats,
    /// The displacements at the run's start (the displacement scale).
    pub q0: crate::integrators::saved::Floats,
    /// The rung of the next window.
    pub rung: u32,
    /// Calm windows in a row.
    pub calm: u32,
    /// Estimates summed so far (impulse, energy, smooth gaps, nonsmooth gaps max,
    /// state).
    pub sums: [crate::integrators::saved::Bits; 5],
    /// Scales: cumulative impulse, largest energy, largest gap change, largest
    /// displacement from the start (mass norm).
    pub scales: [crate::integrators::saved::Bits; 4],
    /// Windows, rejected, steps taken, floor windows, trial factorizations.
    pub counts: [usize; 5],
    /// Times each observable bounded the step.
    pub bounded: [usize; 4],
    /// Smallest and largest step kept.
    pub used: [crate::integrators::saved::Bits; 2],
}

/// The error controller of an accuracy run (module doc): the ladder, the snapshots it
/// steps back to, the sums of its estimates. Its buffers are sized at the first window
/// and reused (no allocation per window).
pub struct Controller {
    spec: AccuracySpec,
    st: ControllerState,
    s0: IntegratorState,
    b1: IntegratorState,
    b2: IntegratorState,
    gap_a: Vec<f64>,
    impulse_a: Vec<f64>,
    q_a: Vec<f64>,
    diff: Vec<f64>,
    scratch: Vec<f64>,
    /// The layouts of `M` and `K` read once (the energies and the mass norms).
    forms: crate::model::EnergyForms,
    /// The energy at the state the next window starts from (the last window's `B₂`).
    e_next: Option<f64>,
    /// The local order `p` of smooth windows: 2 at θ = ½ (the trapezoidal rule), 1
    /// otherwise.
    order: u32,
    /// Floor of the energy scale (J), of the gap scale (m) and of the displacement
    /// scale (m·√kg).
    floors: [f64; 3],
}

/// Statistics of the two kept steps of a window.
type Kept = (StepStats, StepStats);

/// One window's comparison ([`Controller::compare`]).
struct Window {
    /// Ratios of the estimates to their allowances, in [`OBSERVABLES`] order.
    ratios: [f64; 4],
    /// The estimates of `B`'s error, in the same order.
    d: [f64; 4],
    /// No contact opened or closed in it.
    smooth: bool,
    /// `|P_B|`, `|E_B|`, the largest gap change, `‖q_B − q₀‖_M`: the scales' new values.
    values: [f64; 4],
    /// `E_B`, where the next window starts.
    energy: f64,
}

impl Controller {
    /// A controller for `spec` starting at rung 0 (`dt_max`), or at `resume`'s state.
    pub fn new(
        spec: AccuracySpec,
        integ: &dyn Integrator,
        checks: &RunChecks,
        theta: f64,
        resume: Option<ControllerState>,
    ) -> Self {
        use crate::integrators::saved::Bits;
        let s = integ.state();
        let sys = integ.system();
        let size = if checks.max_violation.is_finite() {
            checks.max_violation
        } else {
            1.0
        };
        let st = resume.unwrap_or_else(|| ControllerState {
            gap0: crate::integrators::saved::Floats(s.gap.clone()),
            q0: crate::integrators::saved::Floats(s.q.clone()),
            used: [Bits(f64::INFINITY), Bits(0.0)],
            ..ControllerState::default()
        });
        Controller {
            spec,
            st,
            s0: IntegratorState::default(),
            b1: IntegratorState::default(),
            b2: IntegratorState::default(),
            gap_a: vec![0.0; s.gap.len()],
            impulse_a: vec![0.0; s.impulse.len()],
            q_a: vec![0.0; s.q.len()],
            diff: vec![0.0; s.q.len()],
            scratch: vec![0.0; 2 * sys.prescribed_dofs()],
            forms: sys.energy_forms(),
            e_next: None,
            order: if theta == 0.5 { 2 } else { 1 },
            floors: [
                checks.energy_floor.joules(sys),
                1e-9 * size,
                1e-9 * size * sys.total_mass().max(0.0).sqrt(),
            ],
        }
    }

    /// The request.
    pub fn spec(&self) -> &AccuracySpec {
        &self.spec
    }

    /// What a checkpoint keeps.
    pub fn save(&self) -> ControllerState {
        self.st.clone()
    }

    /// The run has reached its end (to 10⁻³ of the floor step: what is left is the
    /// rounding of the summed step times).
    pub fn done(&self, t: f64) -> bool {
        self.spec.t_end - t <= 1e-3 * self.spec.step(self.spec.rungs())
    }

    fn energy(&mut self, integ: &dyn Integrator) -> f64 {
        let s = integ.state();
        let (k, v) = integ
            .system()
            .energies_with(&self.forms, s.time, &s.q, &s.v, &mut self.scratch);
        k + v
    }

    /// The window's length from time `t` at the current rung: `2 h_k`, shortened to a
    /// smaller rung (or to what is left) near the end.
    /// Returns the window and its rung.
    fn window(&self, t: f64) -> (f64, u32) {
        let left = self.spec.t_end - t;
        let mut k = self.st.rung;
        while 2.0 * self.spec.step(k) > left * (1.0 + 1e-9) && k < self.spec.rungs() {
            k += 1;
        }
        let w = 2.0 * self.spec.step(k);
        (if w > left * (1.0 + 1e-9) { left } else { w }, k)
    }

    /// Takes one accepted window (two steps the observers see, in order), stepping
    /// back and down the ladder as long as the estimate asks (module doc).
    pub fn window_step(
        &mut self,
        integ: &mut dyn Integrator,
        checks: &RunChecks,
        observers: &mut [&mut dyn Observer],
    ) -> Result<Kept, Error> {
        use crate::integrators::saved::Bits;
        integ.save_into(&mut self.s0);
        let t0 = integ.state().time;
        let e0 = match self.e_next.take() {
            Some(e) => e,
            None => self.energy(integ),
        };
        loop {
            let (big, k) = self.window(t0);
            // a window shortened to end the run starts the rungs below it
            self.st.rung = self.st.rung.max(k);
            let at_floor = k >= self.spec.rungs();
            // A: one step of the whole window
            self.st.counts[2] += 1;
            let a = integ
                .set_dt(big)
                .and_then(|_| integ.prepare())
                .and_then(|_| integ.step());
            let a_ok = match &a {
                Ok(st) => {
                    self.st.counts[4] += st.factorizations;
                    checks.check(integ, st).is_ok()
                }
                Err(_) => false,
            };
            let (p_a, e_a) = if a_ok {
                let s = integ.state();
                self.gap_a.copy_from_slice(&s.gap);
                self.impulse_a.copy_from_slice(&s.impulse);
                self.q_a.copy_from_slice(&s.q);
                (s.impulse.iter().sum::<f64>(), self.energy(integ))
            } else {
                (f64::NAN, f64::NAN)
            };
            // B: two steps of half the window, from S₀ again
            integ.restore(&self.s0)?;
            integ.set_dt(0.5 * big)?;
            self.st.counts[2] += 2;
            let b = (|| -> Result<Kept, Error> {
                integ.prepare()?;
                let s1 = integ.step()?;
                checks.check(integ, &s1)?;
                integ.save_into(&mut self.b1);
                integ.prepare()?;
                let s2 = integ.step()?;
                checks.check(integ, &s2)?;
                Ok((s1, s2))
            })();
            let (s1, s2) = match b {
                Ok(k) => k,
                Err(e) if at_floor => return Err(e),
                Err(_) => {
                    // the half steps failed: down one rung and again
                    self.reject(1.0);
                    integ.restore(&self.s0)?;
                    continue;
                }
            };
            let w = if a_ok {
                Some(self.compare(integ, big, (p_a, e_a), e0))
            } else {
                None
            };
            let ratios = w
                .as_ref()
                .map_or([f64::INFINITY, 0.0, 0.0, 0.0], |w| w.ratios);
            let (worst, eps) = ratios
                .iter()
                .copied()
                .enumerate()
                .fold((0, 0.0f64), |m, (i, r)| if r > m.1 { (i, r) } else { m });
            let smooth = w.as_ref().is_some_and(|w| w.smooth);
            if eps > 1.0 && !at_floor {
                self.st.bounded[worst] += 1;
                self.reject(eps.powf(if smooth { 1.0 / self.order as f64 } else { 1.0 }));
                integ.restore(&self.s0)?;
                continue;
            }
            // accepted: the sums of the estimates, the scales, the next rung
            match &w {
                Some(w) => self.accept(w),
                None => self.accept_scales(integ),
            }
            if eps > 1.0 {
                self.st.counts[3] += 1;
            }
            // the doubled window's ratio is 2^p times this one's
            let grow = eps
                <= if smooth {
                    0.5f64.powi(self.order as i32 + 1)
                } else {
                    0.25
                };
            if grow {
                self.st.calm += 1;
            } else {
                self.st.calm = 0;
                if eps > 0.0 {
                    self.st.bounded[worst] += 1;
                }
            }
            if self.st.calm >= CALM_WINDOWS
                && self.st.rung > 0
                && big >= 2.0 * self.spec.step(self.st.rung) * (1.0 - 1e-9)
            {
                self.st.rung -= 1;
                self.st.calm = 0;
            }
            let h = 0.5 * big;
            self.st.used[0] = Bits(self.st.used[0].0.min(h));
            self.st.used[1] = Bits(self.st.used[1].0.max(h));
            self.st.counts[0] += 1;
            // the observers see B₁, then B₂ (each restored, as a resumed run would be)
            integ.save_into(&mut self.b2);
            integ.restore(&self.b1)?;
            for o in observers.iter_mut() {
                o.observe(integ, &s1, false)?;
            }
            integ.restore(&self.b2)?;
            let last = self.done(integ.state().time);
            for o in observers.iter_mut() {
                o.observe(integ, &s2, last)?;
            }
            return Ok((s1, s2));
        }
    }

    /// Down `⌈log₂ r⌉` rungs (at least one, at most to the floor).
    fn reject(&mut self, r: f64) {
        self.st.counts[1] += 1;
        self.st.calm = 0;
        let down = if r.is_finite() {
            r.log2().ceil().max(1.0) as u32
        } else {
            self.spec.rungs()
        };
        self.st.rung = (self.st.rung + down).min(self.spec.rungs());
    }

    /// Whether no contact opened or closed in the window (impulse signs of `S₀`, `A`,
    /// `B₁`, `B₂` alike).
    fn smooth(&self, b2: &crate::integrators::State) -> bool {
        let (Some(p0), Some(p1)) = (
            self.s0.vectors.get("impulse"),
            self.b1.vectors.get("impulse"),
        ) else {
            return false;
        };
        (0..b2.impulse.len()).all(|c| {
            let on = b2.impulse[c] > 0.0;
            (p0.0[c] > 0.0) == on && (p1.0[c] > 0.0) == on && (self.impulse_a[c] > 0.0) == on
        })
    }

    /// The window's window impulse of `B` (`Σ P` of both steps).
    fn impulse_b(&self, b2: &crate::integrators::State) -> f64 {
        let p1: f64 = self
            .b1
            .vectors
            .get("impulse")
            .map_or(0.0, |f| f.0.iter().sum());
        p1 + b2.impulse.iter().sum::<f64>()
    }

    /// The largest change of a gap from the start, and the gaps' difference `|g_A − g_B|`.
    fn gaps(&self, b2: &crate::integrators::State) -> (f64, f64) {
        let mut change = 0.0f64;
        let mut diff = 0.0f64;
        for c in 0..b2.gap.len() {
            change = change.max((b2.gap[c] - self.st.gap0.0[c]).abs());
            diff = diff.max((b2.gap[c] - self.gap_a[c]).abs());
        }
        (change, diff)
    }

    /// The window's differences `|A − B|` (each divided by `2ᵖ − 1` in a smooth
    /// window, Richardson's estimate of `B`'s error; as they are where a contact opened
    /// or closed) and their ratios to the allowances (module doc).
    fn compare(
        &mut self,
        integ: &dyn Integrator,
        big: f64,
        (p_a, e_a): (f64, f64),
        e0: f64,
    ) -> Window {
        let tol = self.spec.tol;
        let share = big / self.spec.t_end;
        let s = integ.state();
        let smooth = self.smooth(s);
        let rf = if smooth {
            ((1u32 << self.order) - 1) as f64
        } else {
            1.0
        };
        let p_b = self.impulse_b(s);
        let e_b = self.energy(integ);
        let s = integ.state();
        let (change, d_g) = self.gaps(s);
        let (d_x, u) = self.state_difference(integ);
        let d = [
            (p_a - p_b).abs() / rf,
            (e_a - e_b).abs() / rf,
            d_g / rf,
            d_x / rf,
        ];
        let ratio = |d: f64, allow: f64| {
            if d == 0.0 {
                0.0
            } else if allow > 0.0 {
                d / allow
            } else {
                f64::INFINITY
            }
        };
        let cumulative = self.st.scales[0].0 + p_b.abs();
        let e_scale = self.st.scales[1]
            .0
            .max(e0.abs())
            .max(e_b.abs())
            .max(self.floors[0]);
        let ell = self.st.scales[2].0.max(change).max(self.floors[1]);
        let u_scale = self.st.scales[3].0.max(u).max(self.floors[2]);
        let local = if smooth { share } else { 1.0 };
        Window {
            ratios: [
                ratio(d[0], tol * (0.5 * p_b.abs() + 0.5 * cumulative * share)),
                ratio(d[1], tol * (0.5 * (e_b - e0).abs() + 0.5 * e_scale * share)),
                ratio(d[2], tol * ell * local),
                ratio(d[3], tol * u_scale * local),
            ],
            d,
            smooth,
            values: [p_b.abs(), e_b.abs(), change, u],
            energy: e_b,
        }
    }

    /// `‖q_A − q_B‖_M = √(e_qᵀ M e_q)`, and the same norm of the displacement from the
    /// start `‖q_B − q₀‖_M` (the scale).
    fn state_difference(&mut self, integ: &dyn Integrator) -> (f64, f64) {
        let (s, sys) = (integ.state(), integ.system());
        for (d, (a, b)) in self.diff.iter_mut().zip(self.q_a.iter().zip(&s.q)) {
            *d = a - b;
        }
        let e = self.forms.mass_form(sys, &self.diff);
        let u = self.displacement(integ);
        (e.max(0.0).sqrt(), u)
    }

    /// `‖q − q₀‖_M` of the state.
    fn displacement(&mut self, integ: &dyn Integrator) -> f64 {
        let (s, sys) = (integ.state(), integ.system());
        for (d, (a, b)) in self.diff.iter_mut().zip(self.st.q0.0.iter().zip(&s.q)) {
            *d = b - a;
        }
        self.forms.mass_form(sys, &self.diff).max(0.0).sqrt()
    }

    /// Adds an accepted window's differences to the sums and its values to the scales.
    fn accept(&mut self, w: &Window) {
        use crate::integrators::saved::Bits;
        self.e_next = Some(w.energy);
        let sums = &mut self.st.sums;
        sums[0] = Bits(sums[0].0 + w.d[0]);
        sums[1] = Bits(sums[1].0 + w.d[1]);
        if w.smooth {
            sums[2] = Bits(sums[2].0 + w.d[2]);
        } else {
            sums[3] = Bits(sums[3].0.max(w.d[2]));
        }
        sums[4] = Bits(sums[4].0 + w.d[3]);
        let sc = &mut self.st.scales;
        sc[0] = Bits(sc[0].0 + w.values[0]);
        sc[1] = Bits(sc[1].0.max(w.values[1]));
        sc[2] = Bits(sc[2].0.max(w.values[2]));
        sc[3] = Bits(sc[3].0.max(w.values[3]));
    }

    /// The scales of a window accepted at the floor without its comparison (the step
    /// `A` failed): its own values, no difference.
    fn accept_scales(&mut self, integ: &dyn Integrator) {
        use crate::integrators::saved::Bits;
        let s = integ.state();
        let p_b = self.impulse_b(s);
        let e_b = self.energy(integ);
        self.e_next = Some(e_b);
        let s = integ.state();
        let (change, _) = self.gaps(s);
        let u = self.displacement(integ);
        let sc = &mut self.st.scales;
        sc[0] = Bits(sc[0].0 + p_b.abs());
        sc[1] = Bits(sc[1].0.max(e_b.abs()));
        sc[2] = Bits(sc[2].0.max(change));
        sc[3] = Bits(sc[3].0.max(u));
    }

    /// The summary at the end of the run.
    pub fn summary(&self, e_start: f64) -> AccuracySummary {
        let st = &self.st;
        let rel = |d: f64, scale: f64| if d == 0.0 { 0.0 } else { d / scale };
        let e_scale = st.scales[1].0.max(e_start.abs()).max(self.floors[0]);
        let ell = st.scales[2].0.max(self.floors[1]);
        let estimated = AccuracyEstimates {
            impulse_history: rel(st.sums[0].0, st.scales[0].0),
            energy: rel(st.sums[1].0, e_scale),
            gaps: rel(st.sums[2].0 + st.sums[3].0, ell),
            state: rel(st.sums[4].0, st.scales[3].0.max(self.floors[2])),
        };
        let tol = self.spec.tol;
        let met = estimated.impulse_history <= tol
            && estimated.energy <= tol
            && estimated.gaps <= tol
            && estimated.state <= tol;
        let most = (0..4).max_by_key(|&i| st.bounded[i]).unwrap_or(0);
        AccuracySummary {
            target: tol,
            met,
            estimated,
            bounded_by: if st.bounded[most] == 0 {
                "none (every window at the largest step)".to_string()
            } else {
                OBSERVABLES[most].to_string()
            },
            windows: st.counts[0],
            rejected: st.counts[1],
            steps_taken: st.counts[2],
            floor_windows: st.counts[3],
            dt_min_used: if st.counts[0] > 0 {
                st.used[0].0
            } else {
                f64::NAN
            },
            dt_max_used: st.used[1].0,
            ladder: self.spec.ladder(),
            trial_factorizations: st.counts[4],
        }
    }
}
