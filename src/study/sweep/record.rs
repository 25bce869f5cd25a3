//! Running one point and its record: the run's measures (impulse trace, errors against
//! the reference, cost), written as a JSON record per point and read back for tables,
//! resumes and merges.

use super::*;

/// Samples of the cumulative contact impulse kept per run (uniform in time over
/// `(0, t_end]`): what the comparison with the finest run reads.
pub const TRACE_SAMPLES: usize = 512;

/// What one run of the grid measured.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct RunRecord {
    /// The point.
    pub point: Point,
    /// `ok`, or `failed` (the run stopped: cap hit, energy growth, non-finite state).
    pub status: String,
    /// The error of a failed run.
    #[serde(default)]
    pub message: Option<String>,
    /// Steps run.
    pub steps: usize,
    /// Degrees of freedom.
    pub dofs: usize,
    /// Time step (s; of an accuracy run, its largest).
    pub dt: f64,
    /// The accuracy asked of a run that chose its steps (`time.accuracy`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub accuracy: Option<f64>,
    /// That run's own estimate of its time error (the largest of `summary.json`'s
    /// `accuracy.estimated`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub accuracy_estimated: Option<f64>,
    /// End time (s).
    pub t_end: f64,
    /// Median wall time of the step loop over the repeats (s).
    pub wall_seconds: f64,
    /// Every repeat's wall time (s).
    pub walls: Vec<f64>,
    /// Model and integrator set-up (s, first repeat).
    pub setup_seconds: f64,
    /// Peak resident memory of the run (bytes; Linux, the process's high-water mark
    /// reset before the run).
    pub peak_memory_bytes: Option<u64>,
    /// The memory ledger's total (bytes).
    pub memory_planned_bytes: u64,
    /// Mean Newton iterations per step.
    pub newton_mean: f64,
    /// Largest Newton iteration count of a step.
    pub newton_max: usize,
    /// Mean projection iterations per step.
    pub projection_mean: f64,
    /// Mean LCP pivots or sweeps per step.
    pub lcp_mean: f64,
    /// Mean friction sweeps per solve (frictional scenes).
    pub friction_sweeps_mean: Option<f64>,
    /// Iteration caps hit (allowed by `scheme.allow_caps`).
    pub caps_hit: usize,
    /// Largest penetration (m).
    pub max_violation: f64,
    /// Energy at the start and at the end (J).
    pub energy: [f64; 2],
    /// Against the analytic reference (impacting bar): relative errors of the plateau
    /// force, contact duration, release velocity and total impulse.
    pub analytic: Option<[f64; 4]>,
    /// Largest total contact force `Σ P / h` of a step (N).
    pub peak_force: f64,
    /// Time from the first to the last step with a contact force (s).
    pub contact_duration: f64,
    /// Cumulative contact impulse `Σ P` at `t_end (i + 1) / TRACE_SAMPLES` (N·s).
    pub impulse: Vec<f64>,
    /// Which shard or MPI rank made the run (0 for a sweep on one process).
    #[serde(default)]
    pub worker: usize,
    /// The scene's displacement probes: every probe's displacement at its times, one
    /// component per dimension, in the scene's order (m).
    #[serde(default)]
    pub probes: Vec<f64>,
    /// The impacting bar's closed form at the same probes, when every probe has it.
    #[serde(default)]
    pub probes_analytic: Option<Vec<f64>>,
}

/// The measures of the table: (column, what it is).
pub const MEASURES: [(&str, &str); 10] = [
    (
        "accuracy",
        "worst analytic error (the probes' too where they have one), else worst of impulse \
         history, energy and probes",
    ),
    (
        "plateau_force_error",
        "plateau force against the analytic value",
    ),
    (
        "duration_error",
        "contact duration against the analytic value",
    ),
    (
        "release_velocity_error",
        "release velocity against the analytic value",
    ),
    (
        "impulse_history_error",
        "cumulative impulse against the finest run",
    ),
    (
        "peak_force_error",
        "peak contact force against the finest run",
    ),
    ("energy_error", "final energy against the finest run"),
    ("max_violation", "largest penetration (m)"),
    (
        "probe_error",
        "displacement at the probes against the analytic value, else the finest run",
    ),
    (
        "impulse_in_time_error",
        "cumulative impulse against the finest run, integrated over time (what the accuracy \
         mode promises)",
    ),
];

/// A row of the table: the record and its errors.
#[derive(Clone, Debug)]
pub struct Row {
    /// The run.
    pub record: RunRecord,
    /// Values of [`MEASURES`] (NaN where not measured).
    pub errors: [f64; 10],
    /// On the Pareto front (wall time against the error) per measure.
    pub front: [bool; 10],
    /// The finest run, which the others are compared with.
    pub is_reference: bool,
}

/// Whether `p` is named as a sweep writes its run records (`NNNNNN.json`, the point's
/// id): only such files are read back, and only such files a new sweep removes (issue
/// 34: a sweep deleted every file of `OUT/runs/`, a user's included).
pub(super) fn is_record_file(p: &Path) -> bool {
    p.file_name().and_then(|n| n.to_str()).is_some_and(|n| {
        n.len() == 11 && n.ends_with(".json") && n[..6].bytes().all(|b| b.is_ascii_digit())
    })
}

/// Removes the run records (`NNNNNN.json`) of `runs`, and nothing else.
pub(super) fn remove_records(runs: &Path) -> Result<(), Error> {
    let Ok(rd) = std::fs::read_dir(runs) else {
        return Ok(());
    };
    for p in rd.filter_map(|e| e.ok().map(|e| e.path())) {
        if is_record_file(&p) && p.is_file() {
            std::fs::remove_file(&p).map_err(|e| Error::write(&p, e))?;
        }
    }
    Ok(())
}

/// Reads records back (`runs/NNNNNN.json` under `dir`).
pub fn read_records(dir: &Path) -> Result<Vec<RunRecord>, Error> {
    let runs = dir.join("runs");
    let mut out = Vec::new();
    let Ok(rd) = std::fs::read_dir(&runs) else {
        return Ok(out);
    };
    let mut names: Vec<PathBuf> = rd
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| is_record_file(p))
        .collect();
    names.sort();
    for p in names {
        let text = crate::limits::read_text(&p, "sweep run record", crate::limits::MAX_TEXT_BYTES)?;
        let r: RunRecord = serde_json::from_str(&text)
            .map_err(|e| Error::bad_file(&p, "", format!("is not a run record: {e}")))?;
        out.push(r);
    }
    Ok(out)
}

/// Runs one point `repeat` times; a run that fails is recorded, not raised, unless its
/// input is bad (exit code 2).
pub fn run_point(
    source: &Source,
    set: &[String],
    p: &Point,
    repeat: usize,
) -> Result<RunRecord, Error> {
    let scene = source.scene(set, p)?;
    let mut walls = Vec::new();
    let mut last = None;
    for _ in 0..repeat.max(1) {
        crate::limits::reset_peak_memory();
        match run_scene(&scene, None, &mut Quiet) {
            Ok(r) => {
                walls.push(r.summary.wall_seconds);
                last = Some(r);
            }
            Err(e) if e.exit_code() == 2 => return Err(e),
            Err(e) => {
                return Ok(RunRecord {
                    point: p.clone(),
                    status: "failed".into(),
                    message: Some(e.to_string()),
                    steps: scene.steps(),
                    dofs: 0,
                    dt: scene.time.dt,
                    accuracy: scene.time.accuracy,
                    accuracy_estimated: None,
                    t_end: scene.time.t_end,
                    wall_seconds: f64::NAN,
                    walls,
                    setup_seconds: f64::NAN,
                    peak_memory_bytes: crate::limits::peak_memory(),
                    memory_planned_bytes: 0,
                    newton_mean: f64::NAN,
                    newton_max: 0,
                    projection_mean: f64::NAN,
                    lcp_mean: f64::NAN,
                    friction_sweeps_mean: None,
                    caps_hit: 0,
                    max_violation: f64::NAN,
                    energy: [f64::NAN; 2],
                    analytic: None,
                    peak_force: f64::NAN,
                    contact_duration: f64::NAN,
                    impulse: Vec::new(),
                    worker: 0,
                    probes: Vec::new(),
                    probes_analytic: None,
                });
            }
        }
    }
    let r = last.expect("at least one repeat");
    let s = &r.summary;
    let mut sorted = walls.clone();
    sorted.sort_by(f64::total_cmp);
    let h = s.dt;
    let rel = |a: f64, b: f64| a / b - 1.0;
    let first = r.force.iter().position(|&f| f > 0.0);
    let last_closed = r.force.iter().rposition(|&f| f > 0.0);
    // each step over its own h (an accuracy run's steps vary: `RunResult::dt`)
    let step = |k: usize| r.dt.get(k).copied().unwrap_or(h);
    let contact_duration = match (first, last_closed) {
        (Some(a), Some(b)) if r.dt.is_empty() => (b + 1 - a) as f64 * h,
        (Some(a), Some(b)) => (a..=b).map(step).sum(),
        _ => 0.0,
    };
    Ok(RunRecord {
        point: p.clone(),
        status: "ok".into(),
        message: None,
        steps: s.steps,
        dofs: s.dofs,
        dt: h,
        accuracy: s.accuracy.as_ref().map(|a| a.target),
        accuracy_estimated: s.accuracy.as_ref().map(|a| a.estimated.largest()),
        t_end: s.t_end,
        wall_seconds: sorted[sorted.len() / 2],
        walls,
        setup_seconds: s.model_seconds + s.integrator_seconds,
        peak_memory_bytes: s.peak_memory_bytes,
        memory_planned_bytes: s.memory_planned_bytes,
        newton_mean: s.iterations.newton.mean,
        newton_max: s.iterations.newton.max,
        projection_mean: s.iterations.projection.mean,
        lcp_mean: s.iterations.lcp.mean,
        friction_sweeps_mean: s.friction.as_ref().map(|f| f.sweeps_mean),
        caps_hit: s.caps_hit,
        max_violation: s.max_violation,
        energy: s.energy,
        analytic: s.contact.as_ref().map(|k| {
            [
                rel(k.plateau_force, k.analytic_force),
                rel(k.duration, k.analytic_duration),
                rel(k.release_velocity, k.analytic_release_velocity),
                rel(k.total_impulse, k.analytic_total_impulse),
            ]
        }),
        peak_force: r.force.iter().copied().fold(0.0, f64::max),
        contact_duration,
        impulse: if r.dt.is_empty() {
            impulse_trace(&r.force, h, s.t_end)
        } else {
            impulse_samples(&r.force, &r.dt, h, s.t_end)
        },
        worker: 0,
        probes: s
            .probes
            .iter()
            .flat_map(|p| p.displacement.iter().flatten().copied())
            .collect(),
        probes_analytic: s
            .probes
            .iter()
            .map(|p| p.analytic.as_ref())
            .collect::<Option<Vec<_>>>()
            .filter(|a| !a.is_empty())
            .map(|a| a.into_iter().flatten().flatten().copied().collect()),
    })
}

/// The cumulative impulse `Σ P` of a per-step force trace (`Σ P / h` per step) at
/// `t_end (i + 1) / TRACE_SAMPLES`, linear within a step.
pub fn impulse_trace(force: &[f64], h: f64, t_end: f64) -> Vec<f64> {
    if force.is_empty() {
        return Vec::new();
    }
    let mut out = Vec::with_capacity(TRACE_SAMPLES);
    let (mut k, mut acc) = (0usize, 0.0);
    for i in 0..TRACE_SAMPLES {
        let t = t_end * (i + 1) as f64 / TRACE_SAMPLES as f64;
        // steps wholly before t
        while k < force.len() && (k + 1) as f64 * h <= t * (1.0 + 1e-12) {
            acc += force[k] * h;
            k += 1;
        }
        let part = if k < force.len() {
            ((t - k as f64 * h) / h).clamp(0.0, 1.0) * force[k] * h
        } else {
            0.0
        };
        out.push(acc + part);
    }
    out
}

/// The cumulative impulse at `TRACE_SAMPLES` times over `[0, t_end]` of a force trace
/// whose steps are `dt` (or all `h` when `dt` is empty), linear within a step.
pub fn impulse_samples(force: &[f64], dt: &[f64], h: f64, t_end: f64) -> Vec<f64> {
    let step = |k: usize| if dt.is_empty() { h } else { dt[k] };
    let mut out = Vec::with_capacity(TRACE_SAMPLES);
    let (mut k, mut t0, mut acc) = (0usize, 0.0f64, 0.0f64);
    for i in 0..TRACE_SAMPLES {
        let t = t_end * (i + 1) as f64 / TRACE_SAMPLES as f64;
        while k < force.len() && t0 + step(k) <= t * (1.0 + 1e-12) {
            acc += force[k] * step(k);
            t0 += step(k);
            k += 1;
        }
        let part = if k < force.len() {
            ((t - t0) / step(k)).clamp(0.0, 1.0) * force[k] * step(k)
        } else {
            0.0
        };
        out.push(acc + part);
    }
    out
}

/// A force trace over its steps: the total normal contact force of each step and the
/// steps (`dt`, or all `h` when `dt` is empty).
#[derive(Clone, Copy, Debug)]
pub struct ForceTrace<'a> {
    /// The total normal contact force of each step (N).
    pub force: &'a [f64],
    /// Each step's length (s), or empty for steps all `h`.
    pub dt: &'a [f64],
    /// The step when `dt` is empty (s).
    pub h: f64,
}

impl ForceTrace<'_> {
    fn step(&self, k: usize) -> f64 {
        if self.dt.is_empty() {
            self.h
        } else {
            self.dt[k]
        }
    }
}

/// `∫₀^T |P_a(t) − P_b(t)| dt` (N·s²) of two cumulative impulses `P(t) = ∫₀ᵗ f`, each
/// linear within its own steps, integrated exactly over the union of their step ends
/// up to `t_end`. Divided by `P_b(T) · T` it is the impulse history's error *in time*:
/// an impulse `P` placed `δt` off counts `P δt`, where the largest difference at sample
/// times ([`impulse_samples`]) counts it whole once a sample falls within `δt`. It is
/// the Wasserstein distance of the two impulse measures when their totals agree.
pub fn impulse_difference_in_time(a: ForceTrace<'_>, b: ForceTrace<'_>, t_end: f64) -> f64 {
    // each trace's position: steps consumed, their end time, the impulse at that end
    struct Walk {
        k: usize,
        t: f64,
        p: f64,
    }
    let at = |w: &Walk, tr: &ForceTrace<'_>, t: f64| -> f64 {
        if w.k < tr.force.len() {
            w.p + tr.force[w.k] * (t - w.t).max(0.0)
        } else {
            w.p
        }
    };
    let next = |w: &Walk, tr: &ForceTrace<'_>| -> f64 {
        if w.k < tr.force.len() {
            w.t + tr.step(w.k)
        } else {
            f64::INFINITY
        }
    };
    let advance = |w: &mut Walk, tr: &ForceTrace<'_>, t: f64| {
        while w.k < tr.force.len() && w.t + tr.step(w.k) <= t {
            w.p += tr.force[w.k] * tr.step(w.k);
            w.t += tr.step(w.k);
            w.k += 1;
        }
    };
    let (mut wa, mut wb) = (
        Walk {
            k: 0,
            t: 0.0,
            p: 0.0,
        },
        Walk {
            k: 0,
            t: 0.0,
            p: 0.0,
        },
    );
    let (mut t0, mut d0, mut sum) = (0.0f64, 0.0f64, 0.0f64);
    while t0 < t_end {
        let t1 = next(&wa, &a).min(next(&wb, &b)).min(t_end);
        if t1 <= t0 {
            // a zero-length step: consume it
            advance(&mut wa, &a, t0);
            advance(&mut wb, &b, t0);
            if next(&wa, &a).min(next(&wb, &b)) <= t0 {
                break;
            }
            continue;
        }
        let d1 = at(&wa, &a, t1) - at(&wb, &b, t1);
        let dt = t1 - t0;
        // |d| is linear on the segment, or two triangles where it changes sign
        sum += if d0 * d1 >= 0.0 {
            0.5 * (d0.abs() + d1.abs()) * dt
        } else {
            0.5 * (d0 * d0 + d1 * d1) / (d0.abs() + d1.abs()) * dt
        };
        advance(&mut wa, &a, t1);
        advance(&mut wb, &b, t1);
        (t0, d0) = (t1, d1);
    }
    sum
}

/// A cumulative impulse trace (samples at `t_end (i + 1) / n`, 0 at t = 0) at time `t`,
/// linear between samples (the last sample beyond `t_end`).
pub(super) fn trace_at(trace: &[f64], t_end: f64, t: f64) -> f64 {
    let n = trace.len();
    let x = t / t_end * n as f64;
    if n == 0 || x <= 0.0 {
        return 0.0;
    }
    if x >= n as f64 {
        return trace[n - 1];
    }
    let i = x.floor() as usize;
    let a = if i == 0 { 0.0 } else { trace[i - 1] };
    a + (trace[i] - a) * (x - i as f64)
}

/// The finest run: most refined, then a run at fixed steps before one that chose its
/// steps (`time.accuracy`), then smallest step, then the tightest accuracy, then the
/// lowest index (the first value of every other axis); failed runs are never the
/// reference.
pub(super) fn reference_run(records: &[RunRecord]) -> Option<usize> {
    records
        .iter()
        .enumerate()
        .filter(|(_, r)| r.status == "ok")
        .min_by(|(_, a), (_, b)| {
            let tol = |r: &RunRecord| r.accuracy.unwrap_or(0.0);
            b.point
                .refine
                .cmp(&a.point.refine)
                .then(a.accuracy.is_some().cmp(&b.accuracy.is_some()))
                .then(a.dt.total_cmp(&b.dt))
                .then(tol(a).total_cmp(&tol(b)))
                .then(a.point.id.cmp(&b.point.id))
        })
        .map(|(i, _)| i)
}
