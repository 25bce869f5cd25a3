//! The contact measurement of a run: the [`ContactTracker`] that the run's observer
//! feeds after every step (total impulse, the per-step force trace up to
//! [`FORCE_TRACE_MAX_STEPS`] steps, the samples of the first contact interval) and
//! [`contact_summary`], which reads the tracker at the end of the run into the
//! [`ContactSummary`] compared with the analytic impacting-bar reference.
//!
//! Each sample is the mean force `Σ P / h` over its own step `h`: a run whose step varies
//! (the accuracy mode, [`super::accuracy`]) keeps every sample's step beside it and is
//! measured in time, a run at one step by index (the same numbers, bit for bit, as
//! before steps could vary).

use crate::analytic::ImpactingBar;

use super::summary::ContactSummary;

/// The per-step contact force `Σ P / h` is kept in [`RunResult::force`](super::RunResult::force) for runs of at
/// most this many steps (32 MiB); longer runs keep only the first contact interval,
/// which the contact measurement needs.
pub const FORCE_TRACE_MAX_STEPS: usize = 1 << 22;

/// Measures the contact as the run goes: the total impulse, and the samples of the
/// first contact interval (from the first positive impulse to one step after the last
/// closed step), which is all [`contact_summary`] reads.
///
/// What grows with the run is kept only where something reads it, so that a checkpoint
/// (which saves the tracker) does not grow with the run (issue 16 §4: each held the
/// whole force trace, and the bytes written grew quadratically with the run's length):
/// the per-step trace only for runs that do not checkpoint (library callers read it in
/// [`RunResult::force`](super::RunResult::force)), the first interval only for scenes with the impacting-bar
/// reference (whose interval ends after `2L/c0`).
#[derive(Default)]
pub(super) struct ContactTracker {
    pub(super) trace: Option<Vec<f64>>,
    /// The step of each trace sample, kept from the first step that differs from the
    /// run's first step `h0` (the earlier ones filled in then).
    pub(super) trace_dt: Option<Vec<f64>>,
    pub(super) interval: bool,
    pub(super) first: Option<usize>,
    pub(super) force: Vec<f64>,
    pub(super) min_gap: Vec<f64>,
    /// The step of each interval sample (only read once the step varied).
    pub(super) dt: Vec<f64>,
    /// Start time of the interval's first sample.
    pub(super) first_time: f64,
    pub(super) done: bool,
    pub(super) total_force: f64,
    /// `Σ (Σ P)` over the run: the total impulse of a run whose step varied.
    pub(super) total_impulse: f64,
    /// The run's first step.
    pub(super) h0: f64,
    /// A step differed from `h0`.
    pub(super) varied: bool,
}

impl ContactTracker {
    pub(super) fn new(steps: usize, trace: bool, interval: bool, h0: f64) -> Self {
        ContactTracker {
            trace: (trace && steps <= FORCE_TRACE_MAX_STEPS).then(|| Vec::with_capacity(steps)),
            interval,
            h0,
            ..ContactTracker::default()
        }
    }

    /// The step that ended at `t`, of length `h`, index `k`, mean force `f`, smallest gap
    /// `min_gap`.
    pub(super) fn push(&mut self, k: usize, f: f64, min_gap: f64, t: f64, h: f64) {
        if h.to_bits() != self.h0.to_bits() && !self.varied {
            self.varied = true;
            if let Some(tr) = self.trace.as_ref() {
                let mut dts = Vec::with_capacity(tr.capacity());
                dts.resize(tr.len(), self.h0);
                self.trace_dt = Some(dts);
            }
        }
        if let Some(t) = self.trace.as_mut() {
            if t.len() < FORCE_TRACE_MAX_STEPS {
                t.push(f);
                if let Some(d) = self.trace_dt.as_mut() {
                    d.push(h);
                }
            } else {
                // a run of unknown length (the accuracy mode) past the trace's limit
                self.trace = None;
                self.trace_dt = None;
            }
        }
        self.total_force += f;
        self.total_impulse += f * h;
        if self.done || !self.interval {
            return;
        }
        if self.first.is_none() && f > 0.0 {
            self.first = Some(k);
            self.first_time = t - h;
        }
        if self.first.is_some() {
            self.force.push(f);
            self.min_gap.push(min_gap);
            self.dt.push(h);
            // the interval ended at the previous sample: this one is the sample after it
            if !(f > 0.0 || min_gap <= 0.0) {
                self.done = true;
            }
        }
    }

    /// The total impulse over the run (N·s).
    pub(super) fn total_impulse(&self) -> f64 {
        if self.varied {
            self.total_impulse
        } else {
            self.total_force * self.h0
        }
    }
}

/// Measures the first contact interval.
///
/// The interval is the first run of steps that are closed (positive impulse, or
/// gap ≤ 0) and contain a positive impulse. Sample `k` (0-based) is the mean force
/// over its step, placed at the step's midpoint. The plateau is the mean over the
/// middle 80 % of the interval (of its steps; in time, weighted by each step, when the
/// step varied). The duration is measured between the half-plateau crossings (linear
/// interpolation between samples, zero force before the first sample): the release
/// front of a space-discretized bar is smeared over a few steps by dispersion, and the
/// half-height width is the time its centre takes, independent of how far the tails
/// reach. `closed_duration` counts the whole run.
pub(super) fn contact_summary(
    tracker: &ContactTracker,
    sys: &crate::model::LinearSystem,
    v: &[f64],
    r: ImpactingBar,
) -> ContactSummary {
    let h = tracker.h0;
    let (force, min_gap) = (&tracker.force, &tracker.min_gap);
    let mut c = ContactSummary {
        analytic_force: r.contact_force(),
        analytic_duration: r.contact_duration(),
        first_contact_time: f64::NAN,
        release_velocity: sys.momentum(v) / sys.total_mass(),
        analytic_release_velocity: r.release_velocity(),
        total_impulse: tracker.total_impulse(),
        analytic_total_impulse: r.total_impulse(),
        ..ContactSummary::default()
    };
    // the tracker's window starts at the first positive impulse, step `first`
    let (Some(first), Some(i0)) = (tracker.first, force.iter().position(|&f| f > 0.0)) else {
        return c;
    };
    let mut last = i0;
    let mut k = i0;
    while k < force.len() && (force[k] > 0.0 || min_gap[k] <= 0.0) {
        if force[k] > 0.0 {
            last = k;
        }
        k += 1;
    }
    if tracker.varied {
        timed_interval(tracker, i0, last, &mut c);
        return c;
    }
    let len = last + 1 - i0;
    let lo = i0 + len / 10;
    let hi = (last + 1 - len / 10).max(lo + 1);
    let win = &force[lo..hi];
    let plateau = win.iter().sum::<f64>() / win.len() as f64;
    c.plateau_force = plateau;
    c.plateau_std =
        (win.iter().map(|f| (f - plateau).powi(2)).sum::<f64>() / win.len() as f64).sqrt();
    c.closed_duration = len as f64 * h;
    c.first_contact_time = (first + i0) as f64 * h;
    let half = 0.5 * plateau;
    let at = |j: usize| if j < force.len() { force[j] } else { 0.0 };
    // rising crossing: first sample ≥ half, interpolated from the previous one
    let up = (i0..=last).find(|&j| force[j] >= half).unwrap_or(i0);
    let prev = if up > 0 { force[up - 1] } else { 0.0 };
    let t_up = (up as f64 - 0.5) * h + h * (half - prev) / (force[up] - prev);
    // falling crossing: last sample ≥ half, interpolated to the next one
    let down = (i0..=last)
        .rev()
        .find(|&j| force[j] >= half)
        .unwrap_or(last);
    let next = at(down + 1);
    let t_down = (down as f64 + 0.5) * h + h * (force[down] - half) / (force[down] - next);
    c.duration = t_down - t_up;
    c
}

/// [`contact_summary`]'s interval measured in time, each sample over its own step: the
/// plateau over the samples whose midpoints lie in the middle 80 % of the interval's
/// time, weighted by their steps; the crossings interpolated between sample midpoints.
fn timed_interval(tracker: &ContactTracker, i0: usize, last: usize, c: &mut ContactSummary) {
    let (force, dt) = (&tracker.force, &tracker.dt);
    // start time of each sample, from the first sample's
    let mut start = Vec::with_capacity(force.len() + 1);
    let mut t = tracker.first_time;
    for &d in dt {
        start.push(t);
        t += d;
    }
    start.push(t);
    let mid = |j: usize| start[j] + 0.5 * dt[j];
    let (t0, t1) = (start[i0], start[last + 1]);
    c.first_contact_time = t0;
    c.closed_duration = t1 - t0;
    let (lo, hi) = (t0 + 0.1 * (t1 - t0), t1 - 0.1 * (t1 - t0));
    let mut inside: Vec<usize> = (i0..=last)
        .filter(|&j| (lo..=hi).contains(&mid(j)))
        .collect();
    if inside.is_empty() {
        inside = (i0..=last).collect();
    }
    let span: f64 = inside.iter().map(|&j| dt[j]).sum();
    let plateau = inside.iter().map(|&j| force[j] * dt[j]).sum::<f64>() / span;
    c.plateau_force = plateau;
    c.plateau_std = (inside
        .iter()
        .map(|&j| (force[j] - plateau).powi(2) * dt[j])
        .sum::<f64>()
        / span)
        .sqrt();
    let half = 0.5 * plateau;
    let up = (i0..=last).find(|&j| force[j] >= half).unwrap_or(i0);
    let (prev, m_prev) = if up > 0 {
        (force[up - 1], mid(up - 1))
    } else {
        (0.0, start[0] - 0.5 * dt[0])
    };
    let t_up = m_prev + (mid(up) - m_prev) * (half - prev) / (force[up] - prev);
    let down = (i0..=last)
        .rev()
        .find(|&j| force[j] >= half)
        .unwrap_or(last);
    let (next, m_next) = if down + 1 < force.len() {
        (force[down + 1], mid(down + 1))
    } else {
        (0.0, start[down + 1] + 0.5 * dt[down])
    };
    let t_down = mid(down) + (m_next - mid(down)) * (force[down] - half) / (force[down] - next);
    c.duration = t_down - t_up;
}
