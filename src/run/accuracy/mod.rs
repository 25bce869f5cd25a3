//! The accuracy mode (issue 50): the run chooses its steps to meet a requested accuracy
//! `TOL` on its observables and reports the error it estimates.
//!
//! **The ladder.** Kept steps are `h_k = dt_max · 2⁻ᵏ`, `k = 0 … K`, down to the floor
//! `dt_min` (by default `dt_max / 2¹⁰`): a structure whose `M̂` is constant keeps the
//! factor and Delassus data of the few steps in use
//! ([`crate::integrators::Integrator::set_dt`], cached within
//! [`crate::integrators::core::STEP_CACHE_BYTES`]); a nonlinear one refactors as it does
//! at every step anyway.
//!
//! **The estimate: step doubling** (Richardson; as MBSim's time-stepping integrator of
//! Moreau's scheme, Studer, Leine & Glocker, IJNME 76, 2008). A window of length `H`
//! from the state `S₀` is taken once at `H` (state `A`) and, from `S₀` again, as two
//! steps at `H/2` (`B₁`, `B₂`); `B₁` and `B₂` are what the run keeps (the observers see
//! them, in order, each restored from its snapshot as a resumed run would be), `A`
//! serves only the comparison. The θ-method (eq. 18, 42–48) has a local error
//! `O(H^{p+1})`, `p = 2` at θ = ½ where no contact opens or closes, `p = 1` otherwise,
//! so `|A − B|` is `2ᵖ − 1` times `B`'s error asymptotically; it is taken undivided: the
//! events (impacts, releases) that the positions of smooth windows place are placed to
//! first order, and the divided estimate fell 2–4 times below the error reached on the
//! academic examples (`signorini study accuracy`).
//!
//! **What is compared**, each against an allowance of `TOL` relative to a scale that is
//! the run's running maximum (so a window is never allowed more than the run's own
//! scale at its end would allow), widened by a **pilot pass** ([`Controller::pilot`]:
//! the whole run at `dt_max`, no observers, the state restored after) which tells the
//! early windows the scale the run will have. Three of the allowances are **budgets**:
//! a window ending at `t` may spend what `TOL · scale · t / T` allows less what the kept
//! windows spent (`T` the run's span), never less than a quarter of its own share
//! `TOL · scale · H / T` (a run that overspent at its floor goes on at sane steps, and
//! its estimate then says it missed). A phase that spends nothing (a flight, which the
//! θ-method integrates exactly under a constant load) leaves its budget to the impact
//! after it: error per unit step without the carry-over held every impact to the
//! window's share and sent the academic examples' accumulations of impacts to the
//! floor step.
//! - the **contact impulse over the window** `Σ_c P_c` (normal impulses; compared over
//!   the window, never per step, so an impact placed in either half of it is the same
//!   impulse): a budget of `TOL S`, `S` the cumulative impulse. Its sum bounds the
//!   cumulative impulse's error at the run's end (the bodies' momenta, which the
//!   contacts change) and, as `∫₀ᵀ |Σ_{w<t} ΔP_w| dt ≤ T Σ_w |ΔP_w|`, the impulse
//!   history's error *in time* (`signorini study accuracy`'s `impulse_in_time`): an
//!   impulse placed `δt` off counts `P δt / T` there. The sweep's measure at sample times
//!   counts such an impulse whole once a sample falls within `δt`: no estimate from the
//!   run alone bounds it, and the mode does not promise it;
//! - the **energy** `E = K + V` at the window's end: a budget of `TOL E_s`, `E_s` the
//!   largest energy met, floored by the energy check's scale
//!   ([`crate::model::energy::EnergyFloor`]). A linear structure at θ = ½ without
//!   damping, time-dependent loads or prescribed motion conserves its energy exactly in
//!   a smooth window (the trapezoidal rule): it is compared only where a contact opens
//!   or closes;
//! - **event location**: the gaps of the contacts that open or close in the window with
//!   an open gap at its start or end (an impact or a release: `B` locates one `A`
//!   misplaces by the distance travelled in between): allowance `TOL ℓ`, `ℓ` the
//!   largest gap change. A contact that takes up or sheds load at a closed gap (a body
//!   resting on another, its first window) places no impact: what its gap differs by
//!   is the body's state, which the displacement field's comparison holds (a stack at
//!   rest otherwise compared its first micrometres of settlement with a scale of
//!   micrometres, and said it missed 1e-1 by 0.7);
//! - the **displacement field** in the mass norm `‖q_A − q_B‖_M`: in smooth windows the
//!   window's own share `TOL U · H / T`, no carry-over (error per unit step: the sum over
//!   the run stays within `TOL U`; the trapezoidal rule propagates a linear structure's
//!   errors without growth); where a contact opens or closes, a budget of `TOL U`; `U`
//!   the largest `‖q − q₀‖_M`. The contact's observables meet an error made inside a
//!   body only when its wave comes back to the contact: the bar at a fixed 1e-5 s
//!   smears its wave and leaves at 0.095 m/s for 0.1, while its window impulses at 1e-5
//!   and 5e-6 s agree. This norm sees the error where it is made, and weights a mode by
//!   its displacement, so the highest modes of a mesh, whose phase no affordable step
//!   resolves (the energy norm of the same difference does not converge on the bar
//!   above h = 10⁻⁹ s), count as little as they move. Its smooth windows keep no
//!   carry-over: with one, the saved budget of a ball's fall let its impact run at
//!   steps that missed its rebound momentum by 6 % at TOL = 1e-2.
//!
//! The window's error ratio `ε` is the largest of the four ratios. `ε ≤ 1` accepts it;
//! the step then grows one rung after two windows with `ε` below `2^{-(p+1)}` (the
//! doubled window would still pass), and stays otherwise. `ε > 1` rejects it and goes
//! down `⌈log₂ ε / p⌉` rungs (at least one). A window at the floor rung is accepted
//! whatever `ε` (the run continues, its outputs whole) and counted. The windows'
//! estimates are the sums of the kept windows' differences relative to the run's own
//! maxima at its end; with the companion's (below) they make the estimates written. A
//! run whose estimate exceeds `TOL` (the floor reached, a pilot that saw larger scales
//! than the run, an error the companion finds) fails with exit code 1
//! ([`Error::AccuracyNotMet`]) after writing its outputs and summary — never a silent
//! exit 0.
//!
//! **The companion run** (a global check). Every comparison above starts from the
//! window's `S₀`: an error made in one window and met at the contact only later (the
//! deformation under a Hertz contact, a wave that comes back) is not in them. The run
//! therefore carries a companion: one step per kept window, of the window's length,
//! from the companion's own state (the same integrator, its state saved and restored
//! around the step; checkpointed with the controller), i.e. the run with every step
//! doubled, propagating its own errors. Its differences from the run — the cumulative
//! impulse in time `∫|P − P_c| dt / (P(T) T)` (trapezoidal over the windows' ends), and
//! at the end the energy and `‖q − q_c‖_M` — are global estimates of the run's error
//! (undivided: `(2ᵖ − 1)` times it asymptotically). The estimate per observable is the
//! larger of the windows' sum and the companion's difference. It costs one step per two
//! kept. The axisymmetric Hertz ball asked 1e-2 from 4e-7 s kept windows whose sums
//! stayed below 1e-2 while its impulse history in time was 4.1e-2 off; the companion's
//! state differs by 0.10 and the run says it missed
//! (`tests/regression_accuracy_hertz_not_silent.rs`). It does not steer the steps: a run
//! it finds short of `TOL` fails (exit 1), it is not taken again.
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
mod companion;
mod window;

/// Rungs below `dt_max` when `time.dt_min` is not given: `dt_min = dt_max / 2¹⁰`.
pub const DEFAULT_RUNGS: u32 = 10;

/// Rungs at most (`dt_max / 2⁴⁰`: far below any step a run can afford).
pub const MAX_RUNGS: u32 = 40;

/// Windows with a small error before the step grows one rung.
const CALM_WINDOWS: u32 = 2;

/// Most calm windows added to [`CALM_WINDOWS`] after growths that did not hold.
const MAX_BACKOFF: u32 = 64;

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
    /// Calm windows asked beyond the usual two before the next growth: raised when a
    /// window at a rung just grown to is rejected, lowered when a growth holds.
    #[serde(default)]
    pub backoff: u32,
    /// The step grew one rung and no window at it has been decided yet.
    #[serde(default)]
    pub grown: bool,
    /// Estimates summed so far (impulse, energy, unused — smooth windows have no gap
    /// difference —, the largest gap difference, state).
    pub sums: [crate::integrators::saved::Bits; 5],
    /// Maxima met: cumulative impulse, largest energy, largest gap change, largest
    /// displacement from the start (mass norm).
    pub scales: [crate::integrators::saved::Bits; 4],
    /// Windows, rejected, steps taken, floor windows, trial factorizations.
    pub counts: [usize; 5],
    /// Times each observable bounded the step.
    pub bounded: [usize; 4],
    /// Smallest and largest step kept.
    pub used: [crate::integrators::saved::Bits; 2],
    /// The pilot pass's total impulse, largest gap change and displacement
    /// ([`Controller::pilot`]).
    pub pilot: [crate::integrators::saved::Bits; 3],
    /// The companion run's state (one step per kept window from its own state:
    /// the module doc of [`self`]); `None` before the first window.
    #[serde(default)]
    pub companion: Option<IntegratorState>,
    /// The companion's comparison so far: `∫|P − P_c| dt`, `|P − P_c|` at the last
    /// window's end, the companion's cumulative impulse `P_c` (the run's is
    /// `scales[0]`), and at the run's end `|E − E_c|` and `‖q − q_c‖_M`.
    #[serde(default)]
    pub global: [crate::integrators::saved::Bits; 5],
    /// Times the companion failed a step and started again from the run's state.
    #[serde(default)]
    pub resyncs: usize,
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
    /// The gaps at the window's start `S₀`.
    gap_s0: Vec<f64>,
    impulse_a: Vec<f64>,
    q_a: Vec<f64>,
    v_a: Vec<f64>,
    /// `q − q₀` of the state measured.
    disp: Vec<f64>,
    /// A linear structure without prescribed motion whose `M` and `K` take the general
    /// column walk: its energies and norms are read in one walk over `M` and one over
    /// `K` ([`crate::linalg::bilinear_forms`]; a rod's three diagonals are faster one
    /// form at a time).
    fused: bool,
    /// θ = ½ on a linear structure without damping, time-dependent loads or prescribed
    /// motion: the trapezoidal rule conserves its energy exactly where no contact
    /// opens or closes.
    conservative: bool,
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
        // the layouts of M and K, read once (the energies and mass norms of every window)
        let forms = sys.energy_forms();
        Controller {
            spec,
            st,
            s0: IntegratorState::default(),
            b1: IntegratorState::default(),
            b2: IntegratorState::default(),
            gap_a: vec![0.0; s.gap.len()],
            gap_s0: vec![0.0; s.gap.len()],
            impulse_a: vec![0.0; s.impulse.len()],
            q_a: vec![0.0; s.q.len()],
            v_a: vec![0.0; s.q.len()],
            disp: vec![0.0; s.q.len()],
            conservative: theta == 0.5
                && sys.nonlinear.is_empty()
                && sys.prescribed.is_none()
                && sys.damping.is_none()
                && sys.loads.is_empty(),
            fused: sys.nonlinear.is_empty() && sys.prescribed.is_none() && forms.general(),
            diff: vec![0.0; s.q.len()],
            scratch: vec![0.0; 2 * sys.prescribed_dofs()],
            forms,
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
        self.measure(integ, false, true).total
    }

    /// The pilot pass: the run from its start to its end at the largest step, without
    /// observers, for the scales of the allowances (the total impulse, the largest gap
    /// change and displacement, the largest energy), then the start restored. A run's
    /// early windows are otherwise held to the scales met so far, which are small
    /// before the motion has developed (the bar at its first contact: no impulse yet),
    /// and the steps there far smaller than the run needs. The pilot's figures only
    /// widen the allowances to the size the run will have; the estimates written are
    /// relative to the run's own maxima, so a pilot that saw more than the run shows
    /// as an estimate above TOL, not as a silent miss. A pilot that fails (its step
    /// too large for the scene) keeps what it met before.
    pub fn pilot(&mut self, integ: &mut dyn Integrator, checks: &RunChecks) -> Result<(), Error> {
        use crate::integrators::saved::Bits;
        integ.save_into(&mut self.s0);
        let mut p = [0.0f64; 3];
        let mut e_max = 0.0f64;
        let h = self.spec.dt_max;
        let steps = (self.spec.t_end / h).round().max(1.0) as usize;
        // the scales at about 256 of the pilot's steps (and every impulse): a scale, not
        // a measurement, and each reading costs a pass over `M` and `K`
        let every = (steps / 256).max(1);
        if integ.set_dt(h).is_ok() {
            for k in 0..steps {
                let ok = integ
                    .prepare()
                    .and_then(|_| integ.step())
                    .is_ok_and(|st| checks.check(integ, &st).is_ok());
                if !ok {
                    break;
                }
                let s = integ.state();
                p[0] += s.impulse.iter().sum::<f64>().abs();
                p[1] = p[1].max(self.gaps(s).0);
                if k % every == 0 || k + 1 == steps {
                    let m = self.measure(integ, false, true);
                    p[2] = p[2].max(m.displacement);
                    e_max = e_max.max(m.total.abs());
                }
            }
        }
        integ.restore(&self.s0)?;
        self.st.pilot = p.map(Bits);
        self.st.scales[1] = Bits(self.st.scales[1].0.max(e_max));
        Ok(())
    }

    /// The window's length from time `t` at the current rung, `2 h_k`, and its rung:
    /// shortened to a smaller rung (or to what is left) near the end.
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
        if self.st.companion.is_none() {
            // the companion starts where the run does (allocated once); a run resumed
            // from a checkpoint written before companions existed starts it here, its
            // differences until here lost (counted as a restart)
            if self.st.counts[0] > 0 {
                self.st.resyncs += 1;
            }
            self.st.companion = Some(self.s0.clone());
        }
        self.gap_s0.copy_from_slice(&integ.state().gap);
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
            let p_a = if a_ok {
                let s = integ.state();
                self.gap_a.copy_from_slice(&s.gap);
                self.impulse_a.copy_from_slice(&s.impulse);
                self.q_a.copy_from_slice(&s.q);
                self.v_a.copy_from_slice(&s.v);
                // A's energy is read beside B's ([`Controller::measure`])
                s.impulse.iter().sum::<f64>()
            } else {
                f64::NAN
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
                Some(self.compare(integ, big, p_a, e0))
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
            // the doubled window's ratio is 2^p times this one's: grow where it would
            // pass (a growth that fails costs one window and makes the next wait longer)
            let grow = eps
                <= if smooth {
                    0.5f64.powi(self.order as i32)
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
            if self.st.grown {
                // the growth held
                self.st.grown = false;
                self.st.backoff /= 2;
            }
            if self.st.calm >= CALM_WINDOWS + self.st.backoff
                && self.st.rung > 0
                && big >= 2.0 * self.spec.step(self.st.rung) * (1.0 - 1e-9)
            {
                self.st.rung -= 1;
                self.st.calm = 0;
                self.st.grown = true;
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
            self.companion_step(integ, checks, big, last)?;
            return Ok((s1, s2));
        }
    }

    /// Down `⌈log₂ r⌉` rungs (at least one, at most to the floor).
    fn reject(&mut self, r: f64) {
        self.st.counts[1] += 1;
        self.st.calm = 0;
        if self.st.grown {
            // a growth that did not hold: wait longer before the next
            self.st.grown = false;
            self.st.backoff = (2 * self.st.backoff + MAX_BACKOFF / 8).min(MAX_BACKOFF);
        }
        let down = if r.is_finite() {
            r.log2().ceil().max(1.0) as u32
        } else {
            self.spec.rungs()
        };
        self.st.rung = (self.st.rung + down).min(self.spec.rungs());
    }

    /// The summary at the end of the run.
    pub fn summary(&self, e_start: f64) -> AccuracySummary {
        let st = &self.st;
        let rel = |d: f64, scale: f64| if d == 0.0 { 0.0 } else { d / scale };
        let e_scale = st.scales[1].0.max(e_start.abs()).max(self.floors[0]);
        let [_, ell, u_scale] = self.scales(st.scales.map(|b| b.0));
        let local = AccuracyEstimates {
            // relative to the total impulse, as a sweep measures it
            impulse_history: rel(st.sums[0].0, st.scales[0].0),
            energy: rel(st.sums[1].0, e_scale),
            gaps: rel(st.sums[3].0, ell),
            state: rel(st.sums[4].0, u_scale),
        };
        let g = st.global.map(|b| b.0);
        let companion = CompanionEstimates {
            impulse_history: rel(g[0], st.scales[0].0 * self.spec.t_end),
            energy: rel(g[3], e_scale),
            state: rel(g[4], u_scale),
            resyncs: st.resyncs,
        };
        let estimated = AccuracyEstimates {
            impulse_history: local.impulse_history.max(companion.impulse_history),
            energy: local.energy.max(companion.energy),
            gaps: local.gaps,
            state: local.state.max(companion.state),
        };
        let tol = self.spec.tol;
        let met = estimated.largest() <= tol;
        let most = (0..4).max_by_key(|&i| st.bounded[i]).unwrap_or(0);
        AccuracySummary {
            target: tol,
            met,
            estimated,
            local,
            companion,
            scope: SCOPE.to_string(),
            state_scale: u_scale,
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
