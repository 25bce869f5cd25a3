//! `signorini study accuracy SCENE`: what the accuracy mode ([`crate::run::accuracy`])
//! delivers on a scene, against what a fixed step costs (issue 50 §5).
//!
//! For each requested accuracy TOL (default 1e-1, 1e-2, 1e-3) the scene runs in the
//! accuracy mode (its `time.dt`, or `time.dt_max`, the largest step); a reference runs at
//! a fixed step 1/16 of the smallest step any of them kept (at most
//! [`REFERENCE_MAX_STEPS`] steps: the table says when the cap set it); and fixed steps
//! `dt_max · 2⁻ᵏ` run from `k = 0` down until every TOL is met or the step comes within
//! 4× of the reference's. Every run is compared with the reference on the observables
//! the mode promises (each relative, the largest difference over the run):
//!
//! - the cumulative contact impulse history *in time*,
//!   `∫₀ᵀ |P(t) − P_ref(t)| dt / (P_ref(T) T)`
//!   ([`crate::study::sweep::impulse_difference_in_time`]): an impact's impulse error
//!   counts by its size, a shift of its time `δt` by `P δt / T`. The sweep's measure (the
//!   largest difference at [`crate::study::sweep::TRACE_SAMPLES`] times, relative to the
//!   reference's total: `impulse_history_error`) is written beside it (`impulse_at_samples`)
//!   but is not what the mode promises: it counts an impact placed `δt` off whole as soon
//!   as a sample time falls within `δt`, so no estimate made from the run alone can bound it;
//! - the final energy, relative to the reference's largest of the initial and final
//!   energies and the energy check's floor (the work of the loads over the model's size);
//! - each body's final momentum and centre of mass, relative to the largest initial or
//!   final momentum or the contacts' total impulse (a body dropped from rest may end
//!   with little of either momentum), and to the largest of the distance a centre travelled and the
//!   distance its initial or final momentum covers over the run (a body that falls and
//!   bounces ends near its start: its net travel is no scale);
//! - the probes' displacements, relative to the largest reference value;
//! - the impacting bar's plateau, duration and release velocity (its `[reference]`).
//!
//! Beside them, not promised, `accuracy.csv` has the displacement field at the end in
//! the mass norm, `‖q − q_ref‖_M` relative to the largest `‖q − q₀‖_M` the accuracy runs
//! met (`state_at_end`: the scale of their own field estimates): where the step leaves a
//! body's vibration unresolved its phase at the end is off whatever the contact's
//! observables are (the Hertz ball at 4e-7 s: 0.41 with the contact's within 5.4e-2).
//!
//! The achieved error of a run is the largest of these. Wall times are the step loop's
//! (`summary.wall_seconds`), the median of `repeat` runs. Written: `accuracy.csv` (one
//! row per run) and `verdict.txt`: per TOL, the achieved and the estimated error, the
//! steps, the wall time, and the cheapest fixed step that meets TOL with its wall time
//! and the ratio of the two.

use std::fmt::Write as _;
use std::path::Path;

use crate::app::run_scene;
use crate::error::Error;
use crate::io::write_atomic;
use crate::run::{Quiet, RunResult};
use crate::scene::file::Scene;

use super::sweep::{ForceTrace, impulse_difference_in_time, impulse_samples};

/// The reference run's steps at most (its step is raised to `t_end / this` beyond).
pub const REFERENCE_MAX_STEPS: usize = 4_000_000;

/// The accuracies the study asks by default.
pub const DEFAULT_TOLS: [f64; 3] = [1e-1, 1e-2, 1e-3];

/// One run's figures against the reference.
#[derive(Clone, Debug)]
pub struct Measured {
    /// The run's errors per observable (NaN where the scene has none), in
    /// [`OBSERVABLE_NAMES`] order.
    pub errors: Vec<f64>,
    /// The sweep's impulse measure (the largest difference at sample times; module doc),
    /// reported, not promised.
    pub at_samples: f64,
    /// The displacement field at the end in the mass norm, relative to the largest
    /// displacement the accuracy runs met (module doc), reported, not promised.
    pub field: f64,
    /// Steps kept.
    pub steps: usize,
    /// Median wall time of the step loop (s).
    pub wall: f64,
}

/// The observables compared, in [`Measured::errors`] order.
pub const OBSERVABLE_NAMES: [&str; 8] = [
    "impulse_in_time",
    "energy",
    "momentum",
    "centre",
    "probes",
    "plateau",
    "duration",
    "release_velocity",
];

impl Measured {
    /// The largest error over the observables the scene has.
    pub fn achieved(&self) -> f64 {
        self.errors
            .iter()
            .copied()
            .filter(|e| !e.is_nan())
            .fold(0.0, f64::max)
    }

    /// The observable of the largest error.
    pub fn worst(&self) -> &'static str {
        let mut worst = ("none", 0.0f64);
        for (n, e) in OBSERVABLE_NAMES.iter().zip(&self.errors) {
            if *e > worst.1 {
                worst = (n, *e);
            }
        }
        worst.0
    }
}

/// The sweep's impulse measure of `r` against the reference `f`: the largest difference
/// of the cumulative impulses at sample times, relative to the reference's total.
fn at_samples(r: &RunResult, f: &RunResult, t_end: f64) -> f64 {
    let ia = impulse_samples(&r.force, &r.dt, r.summary.dt, t_end);
    let ib = impulse_samples(&f.force, &f.dt, f.summary.dt, t_end);
    let total = ib.last().copied().unwrap_or(0.0);
    if total > 0.0 && ia.len() == ib.len() {
        ia.iter()
            .zip(&ib)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max)
            / total
    } else {
        f64::NAN
    }
}

/// A run's force trace.
fn trace(r: &RunResult) -> ForceTrace<'_> {
    ForceTrace {
        force: &r.force,
        dt: &r.dt,
        h: r.summary.dt,
    }
}

/// The mass matrix and the displacement scale the field's error is measured with.
struct Field<'a> {
    mass: &'a crate::linalg::SparseMatrix,
    scale: f64,
}

/// The displacement field of `r` at the end against the reference `f`'s, `‖q −
/// q_ref‖_M` relative to `field`'s scale (NaN without one).
fn field_error(r: &RunResult, f: &RunResult, field: Option<&Field<'_>>) -> f64 {
    let Some(fd) = field else {
        return f64::NAN;
    };
    let (x, y) = (&r.state.q, &f.state.q);
    if x.len() != y.len() || x.len() != fd.mass.as_ref().ncols() || fd.scale <= 0.0 {
        return f64::NAN;
    }
    let d: Vec<f64> = x.iter().zip(y).map(|(a, b)| a - b).collect();
    let [dmd] = crate::linalg::bilinear_forms(fd.mass.as_ref(), [(&d, &d)]);
    dmd.max(0.0).sqrt() / fd.scale
}

/// The errors of `r` against the reference `f` (module doc).
fn errors(r: &RunResult, f: &RunResult, t_end: f64) -> Vec<f64> {
    let mut e = vec![f64::NAN; OBSERVABLE_NAMES.len()];
    let (a, b) = (&r.summary, &f.summary);
    let total: f64 = match f.dt.is_empty() {
        true => f.force.iter().sum::<f64>() * b.dt,
        false => f.force.iter().zip(&f.dt).map(|(x, h)| x * h).sum(),
    };
    if total > 0.0 {
        e[0] = impulse_difference_in_time(trace(r), trace(f), t_end) / (total * t_end);
    }
    // the energy check's floor (the work of the loads over the model's size) keeps the
    // scale of a run whose total energy stays near zero (a body dropped from rest) the
    // size of the energy it exchanges
    let floor = b.energy_balance.map_or(0.0, |e| e.scale_floor);
    let scale = b.energy[0].abs().max(b.energy[1].abs()).max(floor);
    if scale > 0.0 {
        e[1] = (a.energy[1] - b.energy[1]).abs() / scale;
    }
    if !b.bodies.is_empty() && a.bodies.len() == b.bodies.len() {
        let norm = |v: [f64; 3]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        let diff = |u: [f64; 3], v: [f64; 3]| norm([u[0] - v[0], u[1] - v[1], u[2] - v[2]]);
        // the contacts' total impulse too: a body dropped from rest and caught near
        // the end of its rebound has neither an initial nor a final momentum to scale by
        let p_scale = b
            .bodies
            .iter()
            .map(|s| norm(s.initial.momentum).max(norm(s.last.momentum)))
            .fold(total.max(0.0), f64::max);
        if p_scale > 0.0 {
            e[2] = a
                .bodies
                .iter()
                .zip(&b.bodies)
                .map(|(x, y)| diff(x.last.momentum, y.last.momentum))
                .fold(0.0, f64::max)
                / p_scale;
        }
        // the distance the centre travelled, or the one its initial or final momentum
        // covers over the run (a body that falls and bounces back ends near its start)
        let c_scale = b
            .bodies
            .iter()
            .map(|s| {
                let speed = norm(s.initial.momentum).max(norm(s.last.momentum)) / s.last.mass;
                diff(s.last.centre, s.initial.centre).max(speed * t_end)
            })
            .filter(|x| x.is_finite())
            .fold(0.0, f64::max);
        if c_scale > 0.0 {
            e[3] = a
                .bodies
                .iter()
                .zip(&b.bodies)
                .map(|(x, y)| diff(x.last.centre, y.last.centre))
                .fold(0.0, f64::max)
                / c_scale;
        }
    }
    if !b.probes.is_empty() && a.probes.len() == b.probes.len() {
        let flat = |p: &[crate::run::probes::ProbeSummary]| -> Vec<f64> {
            p.iter()
                .flat_map(|p| p.displacement.iter().flatten().copied())
                .collect()
        };
        let (x, y) = (flat(&a.probes), flat(&b.probes));
        let scale = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        if scale > 0.0 && x.len() == y.len() {
            e[4] = x
                .iter()
                .zip(&y)
                .map(|(u, v)| (u - v).abs())
                .fold(0.0, f64::max)
                / scale;
        }
    }
    if let (Some(x), Some(y)) = (&a.contact, &b.contact) {
        let rel = |u: f64, v: f64| {
            if v != 0.0 {
                (u / v - 1.0).abs()
            } else {
                f64::NAN
            }
        };
        e[5] = rel(x.plateau_force, y.plateau_force);
        e[6] = rel(x.duration, y.duration);
        e[7] = rel(x.release_velocity, y.release_velocity);
    }
    e
}

/// Runs `scene` `repeat` times; the last result and the median wall time.
fn timed(scene: &Scene, repeat: usize) -> Result<(RunResult, f64), Error> {
    let mut walls = Vec::with_capacity(repeat);
    let mut last = None;
    for _ in 0..repeat.max(1) {
        let r = run_scene(scene, None, &mut Quiet)?;
        walls.push(r.summary.wall_seconds);
        last = Some(r);
    }
    walls.sort_by(f64::total_cmp);
    Ok((last.expect("one run at least"), walls[walls.len() / 2]))
}

/// The study on `scene` (overrides applied by the caller) at `tols`, timings the median
/// of `repeat` runs, into `dir`; returns its verdict lines.
pub fn study(scene: &Scene, tols: &[f64], repeat: usize, dir: &Path) -> Result<Vec<String>, Error> {
    let mut base = scene.clone();
    base.time.accuracy = None;
    base.output.plots = false;
    let dt_max = base.time.dt_max.unwrap_or(base.time.dt);
    base.time.dt_max = None;
    base.time.dt_min = None;
    let t_end = base.time.t_end;
    // the accuracy runs
    let mut acc = Vec::new();
    for &tol in tols {
        let mut s = scene.clone();
        s.output.plots = false;
        s.time.accuracy = Some(tol);
        s.validate()?;
        let (r, wall) = timed(&s, repeat)?;
        acc.push((tol, r, wall));
    }
    let smallest = acc
        .iter()
        .filter_map(|(_, r, _)| r.summary.accuracy.as_ref().map(|a| a.dt_min_used))
        .fold(dt_max, f64::min);
    let mut h_ref = smallest / 16.0;
    let capped = t_end / h_ref > REFERENCE_MAX_STEPS as f64;
    if capped {
        h_ref = t_end / REFERENCE_MAX_STEPS as f64;
    }
    let fixed_scene = |h: f64| -> Result<Scene, Error> {
        let mut s = base.clone();
        s.time.dt = h;
        s.validate()?;
        Ok(s)
    };
    let (reference, _) = timed(&fixed_scene(h_ref)?, 1)?;
    // the field in the mass norm, relative to the largest displacement the accuracy
    // runs met (the scale of their own estimates)
    let model = base.build().ok().map(|(m, _)| m);
    let scale = acc
        .iter()
        .filter_map(|(_, r, _)| r.summary.accuracy.as_ref().map(|a| a.state_scale))
        .fold(0.0, f64::max);
    let field = model.as_ref().map(|m| Field {
        mass: &m.problem.system.mass,
        scale,
    });
    let measured = |r: &RunResult, wall: f64| Measured {
        errors: errors(r, &reference, t_end),
        at_samples: at_samples(r, &reference, t_end),
        field: field_error(r, &reference, field.as_ref()),
        steps: r.summary.steps,
        wall,
    };
    let acc: Vec<(f64, RunResult, Measured)> = acc
        .into_iter()
        .map(|(tol, r, wall)| {
            let m = measured(&r, wall);
            (tol, r, m)
        })
        .collect();
    // fixed steps down the ladder until every TOL is met
    let mut fixed: Vec<(f64, Measured)> = Vec::new();
    let mut h = dt_max;
    while h >= 4.0 * h_ref {
        let (r, wall) = timed(&fixed_scene(h)?, repeat)?;
        let m = measured(&r, wall);
        let achieved = m.achieved();
        fixed.push((h, m));
        if tols.iter().all(|&t| achieved <= t) {
            break;
        }
        h *= 0.5;
    }
    let mut csv = String::from("kind,tol,dt,steps,steps_taken,wall_seconds,achieved,estimated");
    for n in OBSERVABLE_NAMES {
        let _ = write!(csv, ",{n}");
    }
    csv.push_str(",impulse_at_samples,state_at_end\n");
    let row =
        |csv: &mut String, kind: &str, tol: f64, h: f64, taken: usize, est: f64, m: &Measured| {
            let _ = write!(
                csv,
                "{kind},{tol:e},{h:e},{},{taken},{:e},{:e},{est:e}",
                m.steps,
                m.wall,
                m.achieved()
            );
            for e in &m.errors {
                let _ = write!(csv, ",{e:e}");
            }
            let _ = writeln!(csv, ",{:e},{:e}", m.at_samples, m.field);
        };
    let mut verdicts = vec![format!(
        "reference: fixed h = {h_ref:.3e} s ({} steps{})",
        reference.summary.steps,
        if capped {
            format!(", capped at {REFERENCE_MAX_STEPS}: 1/16 of the smallest kept step is finer")
        } else {
            String::new()
        }
    )];
    for (h, m) in &fixed {
        row(&mut csv, "fixed", f64::NAN, *h, m.steps, f64::NAN, m);
    }
    for (tol, r, m) in &acc {
        let a = r.summary.accuracy.as_ref().expect("an accuracy run");
        let est = a.estimated.largest();
        row(
            &mut csv,
            "accuracy",
            *tol,
            a.dt_min_used,
            a.steps_taken,
            est,
            m,
        );
        let cheapest = fixed
            .iter()
            .filter(|(_, f)| f.achieved() <= *tol)
            .min_by(|x, y| x.1.wall.total_cmp(&y.1.wall));
        let against = match cheapest {
            Some((h, f)) => format!(
                "cheapest fixed step meeting it: h = {h:.3e} s, {} steps, {:.4} s: the \
                 accuracy run costs {:.2}×",
                f.steps,
                f.wall,
                m.wall / f.wall.max(1e-12)
            ),
            None => format!(
                "no fixed step down to {:.3e} s meets it",
                fixed.last().map_or(dt_max, |f| f.0)
            ),
        };
        verdicts.push(format!(
            "TOL {tol:.0e}: achieved {:.2e} ({}; largest: {}), estimated {est:.2e} (the run \
             says {}), field at the end {:.2e} (not promised), {} steps ({} taken), h \
             {:.3e}…{:.3e} s, {:.4} s; {against}",
            m.achieved(),
            if m.achieved() <= *tol {
                "met"
            } else {
                "NOT met"
            },
            m.worst(),
            if a.met { "met" } else { "NOT met" },
            m.field,
            m.steps,
            a.steps_taken,
            a.dt_min_used,
            a.dt_max_used,
            m.wall
        ));
    }
    std::fs::create_dir_all(dir).map_err(|e| Error::write(dir, e))?;
    write_atomic(&dir.join("accuracy.csv"), csv.as_bytes())?;
    Ok(verdicts)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// At one step the samples are the sweep's own cumulative impulse (bit for bit up
    /// to the order of the sums); over varying steps a constant force F gives F t at
    /// every sample time.
    /// An impulse `P` placed `δt` late differs in time by `P δt` exactly; the same
    /// trace over other steps (a constant force) by nothing; a force `F` against
    /// `(1 + ε) F` over `[0, T]` by `ε F T² / 2`.
    #[test]
    fn the_impulse_difference_in_time_counts_a_shift_by_its_size() {
        fn tr<'a>(force: &'a [f64], dt: &'a [f64], h: f64) -> ForceTrace<'a> {
            ForceTrace { force, dt, h }
        }
        let h = 1e-3;
        let mut a = vec![0.0; 1000];
        let mut b = vec![0.0; 1000];
        a[300] = 5.0;
        b[420] = 5.0;
        let d = impulse_difference_in_time(tr(&a, &[], h), tr(&b, &[], h), 1.0);
        let p = 5.0 * h;
        assert!((d - p * 0.120).abs() <= 1e-12, "{d} against {}", p * 0.12);
        let c = vec![2.0; 1000];
        let dt: Vec<f64> = (0..1500)
            .map(|k| if (500..1000).contains(&k) { 5e-4 } else { 1e-3 })
            .collect();
        let c2 = vec![2.0; 1500];
        let d = impulse_difference_in_time(tr(&c, &[], h), tr(&c2, &dt, f64::NAN), 1.0);
        assert!(d <= 1e-13, "{d}");
        let c3 = vec![2.0 * 1.01; 1000];
        let d = impulse_difference_in_time(tr(&c3, &[], h), tr(&c, &[], h), 1.0);
        assert!((d - 0.01 * 2.0 * 0.5).abs() <= 1e-12, "{d}");
    }

    #[test]
    fn impulse_samples_follow_each_step() {
        let force: Vec<f64> = (0..1000).map(|k| (k as f64 * 0.01).sin().abs()).collect();
        let a = impulse_samples(&force, &[], 1e-3, 1.0);
        let b = crate::study::sweep::impulse_trace(&force, 1e-3, 1.0);
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() <= 1e-12 * y.abs().max(1e-300), "{x} {y}");
        }
        let dt: Vec<f64> = (0..1500)
            .map(|k| if (500..1000).contains(&k) { 5e-4 } else { 1e-3 })
            .collect();
        let f = vec![3.0; dt.len()];
        let t_end: f64 = dt.iter().sum();
        let s = impulse_samples(&f, &dt, f64::NAN, t_end);
        for (i, p) in s.iter().enumerate() {
            let t = t_end * (i + 1) as f64 / crate::study::sweep::TRACE_SAMPLES as f64;
            assert!((p - 3.0 * t).abs() <= 1e-12, "sample {i}: {p} at t = {t}");
        }
    }
}
