//! `signorini sweep`: the speed–accuracy trade of any scene, measured over a grid
//! (issue 19 §1–2).
//!
//! A grid is the product of axes, each a list of values of one scene key: schemes
//! (`scheme.kind`), time steps (`time.dt`), mesh refinement levels (every generated
//! mesh's cell counts times the level: rod elements, box and rectangle cells), θ
//! (`scheme.theta`), projection metrics (`scheme.metric`), friction solvers and
//! tolerances (`scheme.friction.solver`, `.tol`), and any other key as a list of TOML
//! values (`axes`, e.g. a list of mesh files). The axes come from a `[sweep]` table
//! of the scene ([`SweepSpec`]) or from flags. Every point's scene is read and
//! validated before the first run, so a bad value stops the sweep at once (exit code 2)
//! rather than hours in.
//!
//! Each run goes through [`run_scene`] without output files (the cost is the step
//! loop's, median of `repeat` runs); its record ([`RunRecord`]: cost, iterations, caps,
//! penetration, energies, the analytic comparison where the scene has one, and the
//! cumulative contact impulse at [`TRACE_SAMPLES`] times) is written as
//! `runs/NNNNNN.json` as soon as it ends, so `--resume` skips what is there and a shard
//! of a Slurm array writes only its own points; under MPI (`Sweep::run_mpi`, cargo
//! feature `mpi`) rank 0 gathers the other ranks' records and writes them.
//!
//! The table ([`table`]) is formed from the records alone: errors against the scene's
//! analytic reference where it has one (the impacting bar: plateau force, contact
//! duration, release velocity), and always against the finest run of the grid (most
//! refined mesh, then smallest step, then the first value of every other axis): the
//! cumulative impulse history (largest difference over the run, relative to the
//! reference's total), the peak contact force and the final energy; and the scene's
//! displacement probes (`[[probes]]`: the displacement of node sets at named times,
//! `run::probes`) against the closed form where every probe has one (rods of the
//! impacting bar), else against the finest run (largest difference over every probe,
//! time and component, relative to the largest reference value). The accuracy of a
//! run is its worst analytic error where there is one, else the worst of its
//! impulse-history, energy and probe errors. Written: `sweep.csv` (one row per run, a
//! Pareto-front flag per error measure), `sweep.h5` (the same columns, cargo feature
//! `hdf5`), `sweep-accuracy.png/.svg` (accuracy against wall time, each scheme's Pareto
//! front), `verdict.txt` (per scheme, the cheapest run reaching each accuracy level). A
//! sharded sweep's table covers its own runs; `signorini sweep merge` gathers every
//! shard's records and writes the whole grid's table, equal to the unsharded one but for
//! the timings.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::app::run_scene;
use crate::error::Error;
use crate::io::write_atomic;
use crate::plot::{Curve, lines};
use crate::run::Quiet;
use crate::scene::file::{MeshSpec, Scene};
use crate::scene::sweep::scene_key;
pub use crate::scene::sweep::{MAX_POINTS, SweepSpec};

/// Samples of the cumulative contact impulse kept per run (uniform in time over
/// `(0, t_end]`): what the comparison with the finest run reads.
pub const TRACE_SAMPLES: usize = 512;

/// Most points a sweep runs at the same time (`--jobs`): a thread and a rayon pool each.
pub const MAX_JOBS: usize = 1024;

/// Accuracy levels of the verdict when the sweep names none.
pub const DEFAULT_LEVELS: [f64; 3] = [1e-1, 1e-2, 1e-3];

/// One point of the grid.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Point {
    /// Index in the grid's order.
    pub id: usize,
    /// `name=value` per axis, joined by spaces (what identifies the point on resume).
    pub key: String,
    /// Axis name → value (TOML text).
    pub values: BTreeMap<String, String>,
    /// Refinement level (1 without the axis).
    pub refine: usize,
    /// The `--set` overrides of the point.
    pub overrides: Vec<String>,
}

/// The grid's points in order (the last axis varies fastest).
pub fn points(spec: &SweepSpec) -> Vec<Point> {
    let axes = spec.axes_list();
    let total: usize = axes.iter().map(|a| a.2.len()).product();
    (0..total)
        .map(|id| {
            let mut rem = id;
            let mut picks = vec![0; axes.len()];
            for (k, a) in axes.iter().enumerate().rev() {
                picks[k] = rem % a.2.len();
                rem /= a.2.len();
            }
            let mut values = BTreeMap::new();
            let mut key = Vec::new();
            let mut overrides = Vec::new();
            let mut refine = 1;
            for ((name, scene_key, vals), &p) in axes.iter().zip(&picks) {
                let v = &vals[p];
                key.push(format!("{name}={}", v.trim_matches('"')));
                values.insert(name.clone(), v.clone());
                match scene_key {
                    Some(k) => overrides.push(format!("{k}={v}")),
                    None => refine = v.parse().expect("refine levels are integers"),
                }
            }
            Point {
                id,
                key: key.join(" "),
                values,
                refine,
                overrides,
            }
        })
        .collect()
}

/// Where a sweep's scene comes from.
#[derive(Clone, Debug)]
pub enum Source {
    /// A scene file.
    File(PathBuf),
    /// The reference impacting bar (`meshes/bar.toml`, built in).
    Bar,
}

/// The reference bar as a scene (the text of `meshes/bar.toml`).
pub const BAR_SCENE: &str = include_str!("../../meshes/bar.toml");

impl Source {
    /// The scene of one point: the source with `set` (the user's) then the point's
    /// overrides, its meshes refined.
    pub fn scene(&self, set: &[String], p: &Point) -> Result<Scene, Error> {
        let all: Vec<String> = set.iter().chain(&p.overrides).cloned().collect();
        let mut s = match self {
            Source::File(f) => Scene::from_file_with(f, &all).map_err(|e| e.in_file(f))?,
            Source::Bar => Scene::from_text_with(BAR_SCENE, &all)?,
        };
        if p.refine > 1 {
            refine(&mut s, p.refine).map_err(|e| match self {
                Source::File(f) => e.in_file(f),
                Source::Bar => e,
            })?;
        }
        s.output.plots = false;
        Ok(s)
    }

    /// How the source is named in the table and on resume.
    pub fn name(&self) -> String {
        match self {
            Source::File(f) => f.display().to_string(),
            Source::Bar => "bar (built in)".to_string(),
        }
    }
}

/// Multiplies every generated mesh's cell counts by `level`; a mesh file cannot be
/// refined (list files on an axis instead).
pub fn refine(s: &mut Scene, level: usize) -> Result<(), Error> {
    if s.bodies.is_empty() {
        // issue 34: the levels ran the same point twice
        return Err(Error::invalid(
            "sweep.refine",
            level,
            "the scene has no mesh to refine (an [example] scene): give no refine axis",
        ));
    }
    for (i, b) in s.bodies.iter_mut().enumerate() {
        let grow = |n: usize| {
            n.checked_mul(level)
                .ok_or_else(|| Error::invalid(&format!("bodies[{i}].mesh"), n, "overflows"))
        };
        match &mut b.mesh {
            MeshSpec::Rod { elements, .. } => *elements = grow(*elements)?,
            MeshSpec::Box { cells, .. } => {
                for c in cells.iter_mut() {
                    *c = grow(*c)?;
                }
            }
            MeshSpec::Rectangle { cells, .. } => {
                for c in cells.iter_mut() {
                    *c = grow(*c)?;
                }
            }
            MeshSpec::File { path } => {
                return Err(Error::invalid(
                    &format!("bodies[{i}].mesh"),
                    path.display(),
                    "is a mesh file, which `refine` cannot refine: list the files on an \
                     axis instead (--axis 'bodies[N].mesh.path=[\"a.msh\", \"b.msh\"]')",
                ));
            }
        }
    }
    s.validate()
}

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
    /// Time step (s).
    pub dt: f64,
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
pub const MEASURES: [(&str, &str); 9] = [
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
];

/// A row of the table: the record and its errors.
#[derive(Clone, Debug)]
pub struct Row {
    /// The run.
    pub record: RunRecord,
    /// Values of [`MEASURES`] (NaN where not measured).
    pub errors: [f64; 9],
    /// On the Pareto front (wall time against the error) per measure.
    pub front: [bool; 9],
    /// The finest run, which the others are compared with.
    pub is_reference: bool,
}

/// Whether `p` is named as a sweep writes its run records (`NNNNNN.json`, the point's
/// id): only such files are read back, and only such files a new sweep removes (issue
/// 34: a sweep deleted every file of `OUT/runs/`, a user's included).
fn is_record_file(p: &Path) -> bool {
    p.file_name().and_then(|n| n.to_str()).is_some_and(|n| {
        n.len() == 11 && n.ends_with(".json") && n[..6].bytes().all(|b| b.is_ascii_digit())
    })
}

/// Removes the run records (`NNNNNN.json`) of `runs`, and nothing else.
fn remove_records(runs: &Path) -> Result<(), Error> {
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
    let contact_duration = match (first, last_closed) {
        (Some(a), Some(b)) => (b + 1 - a) as f64 * h,
        _ => 0.0,
    };
    Ok(RunRecord {
        point: p.clone(),
        status: "ok".into(),
        message: None,
        steps: s.steps,
        dofs: s.dofs,
        dt: h,
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
        impulse: impulse_trace(&r.force, h, s.t_end),
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

/// A cumulative impulse trace (samples at `t_end (i + 1) / n`, 0 at t = 0) at time `t`,
/// linear between samples (the last sample beyond `t_end`).
fn trace_at(trace: &[f64], t_end: f64, t: f64) -> f64 {
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

/// The finest run: most refined, then smallest step, then the lowest index (the first
/// value of every other axis); failed runs are never the reference.
fn reference_run(records: &[RunRecord]) -> Option<usize> {
    records
        .iter()
        .enumerate()
        .filter(|(_, r)| r.status == "ok")
        .min_by(|(_, a), (_, b)| {
            b.point
                .refine
                .cmp(&a.point.refine)
                .then(a.dt.total_cmp(&b.dt))
                .then(a.point.id.cmp(&b.point.id))
        })
        .map(|(i, _)| i)
}

/// The table of `records` (any order; sorted by point id).
pub fn table(mut records: Vec<RunRecord>) -> Vec<Row> {
    records.sort_by_key(|r| r.point.id);
    let reference = reference_run(&records);
    let refr = reference.map(|i| records[i].clone());
    let mut rows: Vec<Row> = records
        .into_iter()
        .enumerate()
        .map(|(i, r)| {
            let mut e = [f64::NAN; 9];
            // max |u − u_ref| / max |u_ref| over every probe, time and component
            let probe_error = |u: &[f64], v: &[f64]| {
                let scale = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
                (scale > 0.0 && !u.is_empty() && u.len() == v.len()).then(|| {
                    u.iter()
                        .zip(v)
                        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()))
                        / scale
                })
            };
            let probe_analytic = r
                .probes_analytic
                .as_deref()
                .and_then(|a| probe_error(&r.probes, a));
            if r.status == "ok" {
                if let Some(a) = r.analytic {
                    e[1] = a[0].abs();
                    e[2] = a[1].abs();
                    e[3] = a[2].abs();
                }
                let same_span = refr
                    .as_ref()
                    .is_some_and(|f| (r.t_end - f.t_end).abs() <= 1e-12 * f.t_end);
                if let Some(f) = refr.as_ref().filter(|_| Some(i) != reference && !same_span) {
                    // runs of different lengths (an axis on time.t_end): the impulse
                    // compared by time over the shorter span, sample by sample of this
                    // run; the final energy and the peak force are not comparable (NaN)
                    // (issue 34: they were compared sample by sample, error 0.63 for
                    // the same trajectory)
                    let span = r.t_end.min(f.t_end);
                    let total = trace_at(&f.impulse, f.t_end, span);
                    let n = r.impulse.len();
                    if total > 0.0 && n > 0 && !f.impulse.is_empty() {
                        e[4] = r
                            .impulse
                            .iter()
                            .enumerate()
                            .map(|(j, a)| (j, a, r.t_end * (j + 1) as f64 / n as f64))
                            .filter(|&(_, _, t)| t <= span * (1.0 + 1e-12))
                            .map(|(_, a, t)| (a - trace_at(&f.impulse, f.t_end, t)).abs())
                            .fold(0.0, f64::max)
                            / total;
                    }
                }
                if let Some(f) = refr.as_ref().filter(|_| Some(i) != reference && same_span) {
                    let total = f.impulse.last().copied().unwrap_or(0.0);
                    if total > 0.0 && r.impulse.len() == f.impulse.len() {
                        e[4] = r
                            .impulse
                            .iter()
                            .zip(&f.impulse)
                            .map(|(a, b)| (a - b).abs())
                            .fold(0.0, f64::max)
                            / total;
                    }
                    if f.peak_force > 0.0 {
                        e[5] = (r.peak_force / f.peak_force - 1.0).abs();
                    }
                    let scale = f.energy[0].abs().max(f.energy[1].abs());
                    if scale > 0.0 {
                        e[6] = (r.energy[1] - f.energy[1]).abs() / scale;
                    }
                }
                e[7] = r.max_violation;
                e[8] = match (
                    probe_analytic,
                    refr.as_ref().filter(|_| Some(i) != reference),
                ) {
                    (Some(x), _) => x,
                    (None, Some(f)) => probe_error(&r.probes, &f.probes).unwrap_or(f64::NAN),
                    (None, None) => f64::NAN,
                };
                e[0] = if r.analytic.is_some() {
                    let probes = probe_analytic.unwrap_or(0.0);
                    e[1].max(e[2]).max(e[3]).max(probes)
                } else {
                    [e[4], e[6], e[8]]
                        .into_iter()
                        .filter(|x| !x.is_nan())
                        .fold(f64::NAN, f64::max)
                };
            }
            Row {
                record: r,
                errors: e,
                front: [false; 9],
                is_reference: Some(i) == reference,
            }
        })
        .collect();
    for m in 0..MEASURES.len() {
        let mut idx: Vec<usize> = (0..rows.len())
            .filter(|&i| !rows[i].errors[m].is_nan() && rows[i].record.wall_seconds.is_finite())
            .collect();
        idx.sort_by(|&a, &b| {
            rows[a]
                .record
                .wall_seconds
                .total_cmp(&rows[b].record.wall_seconds)
                .then(rows[a].errors[m].total_cmp(&rows[b].errors[m]))
        });
        let mut best = f64::INFINITY;
        for i in idx {
            if rows[i].errors[m] < best {
                best = rows[i].errors[m];
                rows[i].front[m] = true;
            }
        }
    }
    rows
}

/// The CSV of `rows`; `timings` false leaves the timing columns out (what a merged
/// table is compared with the unsharded one on).
pub fn csv(rows: &[Row], timings: bool) -> String {
    let axes: Vec<String> = rows
        .first()
        .map(|r| r.record.point.values.keys().cloned().collect())
        .unwrap_or_default();
    let mut x = String::from("id");
    for a in &axes {
        let _ = write!(x, ",{a}");
    }
    x.push_str(",status,steps,dofs,time_step");
    if timings {
        x.push_str(",wall_seconds,us_per_step,setup_seconds,peak_memory_bytes,worker");
    }
    x.push_str(
        ",memory_planned_bytes,newton_mean,newton_max,projection_mean,lcp_mean,\
         friction_sweeps_mean,caps_hit,energy_start,energy_end,peak_force,contact_duration,\
         reference",
    );
    for (m, _) in MEASURES {
        let _ = write!(x, ",{m}");
    }
    if timings {
        for (m, _) in MEASURES {
            let _ = write!(x, ",front_{m}");
        }
    }
    x.push_str(",message\n");
    let reference_id = rows
        .iter()
        .find(|r| r.is_reference)
        .map(|r| r.record.point.id);
    let f = |v: f64| {
        if v.is_nan() {
            String::new()
        } else {
            format!("{v:e}")
        }
    };
    for r in rows {
        let c = &r.record;
        let _ = write!(x, "{}", c.point.id);
        for a in &axes {
            let v = c.point.values.get(a).map_or("", |s| s.as_str());
            let _ = write!(x, ",{}", v.trim_matches('"').replace(',', ";"));
        }
        let _ = write!(x, ",{},{},{},{:e}", c.status, c.steps, c.dofs, c.dt);
        if timings {
            let _ = write!(
                x,
                ",{},{},{},{},{}",
                f(c.wall_seconds),
                f(1e6 * c.wall_seconds / c.steps.max(1) as f64),
                f(c.setup_seconds),
                c.peak_memory_bytes.map_or(String::new(), |b| b.to_string()),
                c.worker
            );
        }
        let _ = write!(
            x,
            ",{},{},{},{},{},{},{},{},{},{},{},{}",
            c.memory_planned_bytes,
            f(c.newton_mean),
            c.newton_max,
            f(c.projection_mean),
            f(c.lcp_mean),
            c.friction_sweeps_mean.map_or(String::new(), f),
            c.caps_hit,
            f(c.energy[0]),
            f(c.energy[1]),
            f(c.peak_force),
            f(c.contact_duration),
            if c.analytic.is_some() {
                "analytic".to_string()
            } else if r.is_reference {
                "itself (the finest run)".to_string()
            } else {
                reference_id.map_or("none".to_string(), |i| format!("run {i}"))
            }
        );
        for e in r.errors {
            let _ = write!(x, ",{}", f(e));
        }
        if timings {
            for b in r.front {
                let _ = write!(x, ",{}", u8::from(b));
            }
        }
        let msg = c.message.as_deref().unwrap_or("").replace(['\n', ','], " ");
        let _ = writeln!(x, ",{msg}");
    }
    x
}

/// The columns of a CSV written by [`csv`]: numbers where every non-empty cell is
/// one (empty cells NaN), text otherwise (the HDF5 table's columns).
#[cfg(feature = "hdf5")]
fn csv_columns(text: &str) -> Vec<(String, crate::io::h5::TableColumn)> {
    use crate::io::h5::TableColumn;
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    header
        .iter()
        .enumerate()
        .map(|(k, name)| {
            let cells: Vec<&str> = rows
                .iter()
                .map(|r| r.get(k).copied().unwrap_or(""))
                .collect();
            let numbers: Option<Vec<f64>> = cells
                .iter()
                .map(|c| {
                    if c.is_empty() {
                        Some(f64::NAN)
                    } else {
                        c.parse().ok()
                    }
                })
                .collect();
            let col = match numbers {
                Some(v) if name != &"message" => TableColumn::Numbers(v),
                _ => TableColumn::Text(cells.iter().map(|c| c.to_string()).collect()),
            };
            (name.to_string(), col)
        })
        .collect()
}

/// The scheme of a row (its `scheme` axis value, else `scene`).
fn scheme_of(r: &Row) -> String {
    r.record
        .point
        .values
        .get("scheme")
        .map_or("scene's scheme".to_string(), |s| {
            s.trim_matches('"').to_string()
        })
}

/// One verdict line per scheme: the cheapest run reaching each level of accuracy, and
/// the best accuracy reached; then which scheme reaches each level first.
pub fn verdicts(rows: &[Row], levels: &[f64]) -> Vec<String> {
    let mut out = Vec::new();
    let against = if rows.iter().any(|r| r.record.analytic.is_some()) {
        "the analytic reference".to_string()
    } else {
        match rows.iter().find(|r| r.is_reference) {
            Some(r) => format!(
                "the finest run (#{}: {})",
                r.record.point.id, r.record.point.key
            ),
            None => "nothing (no run ended)".to_string(),
        }
    };
    out.push(format!(
        "sweep: {} runs, accuracy (relative error) against {against}",
        rows.len()
    ));
    let failed = rows.iter().filter(|r| r.record.status != "ok").count();
    if failed > 0 {
        out.push(format!(
            "sweep: {failed} runs failed (see the message column)"
        ));
    }
    let mut schemes: Vec<String> = rows.iter().map(scheme_of).collect();
    schemes.dedup();
    schemes.sort();
    schemes.dedup();
    let describe = |r: &Row| {
        let key = &r.record.point.key;
        format!(
            "{} in {:.3e} s ({})",
            pct(r.errors[0]),
            r.record.wall_seconds,
            if key.is_empty() { "the scene" } else { key }
        )
    };
    for s in &schemes {
        let mine: Vec<&Row> = rows
            .iter()
            .filter(|r| &scheme_of(r) == s && !r.errors[0].is_nan())
            .collect();
        let mut parts = Vec::new();
        for &l in levels {
            let best = mine
                .iter()
                .filter(|r| r.errors[0] <= l)
                .min_by(|a, b| a.record.wall_seconds.total_cmp(&b.record.wall_seconds));
            parts.push(match best {
                Some(r) => format!("error ≤ {l:.0e}: {}", describe(r)),
                None => format!("error ≤ {l:.0e} not reached"),
            });
        }
        match mine
            .iter()
            .min_by(|a, b| a.errors[0].total_cmp(&b.errors[0]))
        {
            Some(b) => out.push(format!(
                "sweep {s}: {}; best {}",
                parts.join("; "),
                describe(b)
            )),
            None => out.push(format!("sweep {s}: no measured run")),
        }
    }
    for &l in levels {
        let mut by: Vec<(&Row, f64)> = Vec::new();
        for s in &schemes {
            if let Some(r) = rows
                .iter()
                .filter(|r| &scheme_of(r) == s && r.errors[0] <= l)
                .min_by(|a, b| a.record.wall_seconds.total_cmp(&b.record.wall_seconds))
            {
                by.push((r, r.record.wall_seconds));
            }
        }
        by.sort_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((r, w)) = by.first() {
            let next = by
                .get(1)
                .map(|(q, v)| format!(", {:.1}× faster than {}", v / w, scheme_of(q)))
                .unwrap_or_default();
            out.push(format!(
                "sweep: cheapest to error ≤ {l:.0e}: {} ({:.3e} s{next})",
                scheme_of(r),
                w
            ));
        }
    }
    out
}

/// A relative error or level as `3.06e-4` (`n/a` when not measured).
fn pct(x: f64) -> String {
    if x.is_nan() {
        "n/a".to_string()
    } else {
        format!("{x:.2e}")
    }
}

/// Writes `sweep.csv`, the plot and `verdict.txt` of `rows` into `dir`; returns the
/// verdicts.
pub fn write_table(
    dir: &Path,
    rows: &[Row],
    levels: &[f64],
    stem: &str,
) -> Result<Vec<String>, Error> {
    let text = csv(rows, true);
    write_atomic(&dir.join(format!("{stem}.csv")), text.as_bytes())?;
    #[cfg(feature = "hdf5")]
    crate::io::h5::write_table(&dir.join(format!("{stem}.h5")), &csv_columns(&text))?;
    let mut schemes: Vec<String> = rows.iter().map(scheme_of).collect();
    schemes.sort();
    schemes.dedup();
    let curves: Vec<Curve> = schemes
        .iter()
        .map(|s| {
            // each scheme's own front
            let mut own: Vec<(f64, f64)> = rows
                .iter()
                .filter(|r| {
                    &scheme_of(r) == s && !r.errors[0].is_nan() && r.record.wall_seconds.is_finite()
                })
                .map(|r| (r.record.wall_seconds, r.errors[0].max(1e-15)))
                .collect();
            own.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
            let mut best = f64::INFINITY;
            own.retain(|p| {
                let keep = p.1 < best;
                best = best.min(p.1);
                keep
            });
            Curve {
                name: s.clone(),
                points: own,
            }
        })
        .filter(|c| !c.points.is_empty())
        .collect();
    if !curves.is_empty() {
        lines(
            &dir.join(format!("{stem}-accuracy")),
            "accuracy reachable within a wall time (each scheme's Pareto front)",
            "wall time of the step loop (s)",
            "relative error",
            &curves,
            true,
        )?;
    }
    let v = verdicts(rows, levels);
    write_atomic(&dir.join("verdict.txt"), (v.join("\n") + "\n").as_bytes())?;
    Ok(v)
}

/// A shard of the grid: points `id` with `id % count == index`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// This shard (0-based).
    pub index: usize,
    /// Shards in all.
    pub count: usize,
}

impl Shard {
    /// Parses `i/N` (0 ≤ i < N).
    pub fn parse(s: &str) -> Result<Shard, Error> {
        let bad = || Error::invalid("--shard", s, "expected i/N with 0 ≤ i < N, e.g. 0/4");
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count): (usize, usize) = (
            i.trim().parse().map_err(|_| bad())?,
            n.trim().parse().map_err(|_| bad())?,
        );
        if count == 0 || index >= count || count > MAX_POINTS {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }

    /// From Slurm's job-array variables: `SLURM_ARRAY_TASK_ID` less
    /// `SLURM_ARRAY_TASK_MIN` (0 when unset) of `SLURM_ARRAY_TASK_COUNT`; `None` outside
    /// an array job.
    pub fn from_slurm(env: impl Fn(&str) -> Option<String>) -> Result<Option<Shard>, Error> {
        let (Some(id), Some(count)) = (env("SLURM_ARRAY_TASK_ID"), env("SLURM_ARRAY_TASK_COUNT"))
        else {
            return Ok(None);
        };
        let num = |name: &str, v: &str| -> Result<usize, Error> {
            v.trim()
                .parse()
                .map_err(|_| Error::invalid(name, v, "expected a non-negative integer"))
        };
        let id = num("SLURM_ARRAY_TASK_ID", &id)?;
        let min = match env("SLURM_ARRAY_TASK_MIN") {
            Some(m) => num("SLURM_ARRAY_TASK_MIN", &m)?,
            None => 0,
        };
        let count = num("SLURM_ARRAY_TASK_COUNT", &count)?;
        let index = id.checked_sub(min).ok_or_else(|| {
            Error::invalid("SLURM_ARRAY_TASK_ID", id, "is below SLURM_ARRAY_TASK_MIN")
        })?;
        if count == 0 || index >= count {
            // named in the user's terms: they never passed a --shard (issue 34)
            return Err(Error::invalid(
                "SLURM_ARRAY_TASK_ID",
                id,
                &format!(
                    "is task {index} of an array of SLURM_ARRAY_TASK_COUNT = {count} tasks \
                     from SLURM_ARRAY_TASK_MIN = {min}: the sweep expects consecutive task \
                     ids (sbatch --array=0-{})",
                    count.saturating_sub(1)
                ),
            ));
        }
        Shard::parse(&format!("{index}/{count}")).map(Some)
    }

    /// Whether point `id` is this shard's.
    pub fn owns(&self, id: usize) -> bool {
        id % self.count == self.index
    }

    /// The shard's directory under the sweep's.
    pub fn dir(&self, sweep: &Path) -> PathBuf {
        sweep.join(format!("shard-{}-of-{}", self.index, self.count))
    }
}

/// What [`Sweep::run_parallel`] reports against: the records' directory, the worker
/// (shard) index, the points of this process and their total weight.
struct Jobs<'a> {
    dir: Option<&'a Path>,
    worker: usize,
    total: usize,
    total_weight: f64,
}

/// What `grid.json` holds: the sweep's identity, checked on resume and merge.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Grid {
    /// The scene's name.
    pub source: String,
    /// The user's `--set` overrides.
    pub set: Vec<String>,
    /// The axes.
    pub spec: SweepSpec,
    /// Points in all.
    pub points: usize,
}

/// How a sweep reports its progress: one line per run (also in quiet mode).
pub trait SweepProgress {
    /// Run `done` of `total` ended; `eta` seconds left (estimated).
    fn run(&mut self, done: usize, total: usize, record: &RunRecord, eta: f64);
}

/// A sweep's inputs.
pub struct Sweep {
    /// The scene.
    pub source: Source,
    /// The user's `--set` overrides (before the point's).
    pub set: Vec<String>,
    /// The axes.
    pub spec: SweepSpec,
    /// Output directory (a shard writes into its own under it).
    pub dir: PathBuf,
    /// Keep the records already in the directory.
    pub resume: bool,
    /// Run only this shard's points.
    pub shard: Option<Shard>,
    /// Points run at the same time, each on its share of the cores in a rayon pool of
    /// its own (`--jobs`); 0 picks [`default_jobs`]. A point's record is the same bit
    /// for bit with any value, but for the measurements of the process (times, peak
    /// memory: the process's peak over the points running together).
    pub jobs: usize,
}

/// The cores of this machine (1 where it cannot be read).
pub fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// `--jobs` when not given: one point per core, or one at a time when `repeat` asks for
/// timing medians (points running together share the memory bandwidth and caches, and
/// a timing study wants each point alone).
pub fn default_jobs(repeat: usize) -> usize {
    if repeat > 1 { 1 } else { cores() }
}

impl Sweep {
    /// Validates every point's scene, runs the points not yet recorded, and writes the
    /// table of the records in its directory; returns the verdicts.
    pub fn run(&self, progress: &mut dyn SweepProgress) -> Result<Vec<String>, Error> {
        let points = self.validate_points()?;
        let dir = match self.shard {
            Some(s) => s.dir(&self.dir),
            None => self.dir.clone(),
        };
        let (_lock, mut done) = self.open_dir(&dir, &points)?;
        let mine: Vec<&Point> = points
            .iter()
            .filter(|p| self.shard.is_none_or(|s| s.owns(p.id)))
            .collect();
        let worker = self.shard.map_or(0, |s| s.index);
        for r in self.run_points(&mine, &done, Some(&dir), worker, progress)? {
            done.insert(r.point.id, r);
        }
        self.finish(&dir, done.into_values().collect())
    }

    /// Every point, each scene read and validated (before the first run).
    fn validate_points(&self) -> Result<Vec<Point>, Error> {
        self.spec.validate()?;
        // a `--set` on an axis' key is overridden at every point
        let axes = self.spec.axes_list();
        for set in &self.set {
            let key = scene_key(set.split_once('=').map_or(set.as_str(), |(k, _)| k));
            if let Some((name, _, _)) = axes
                .iter()
                .find(|(_, k, _)| k.as_deref().is_some_and(|k| scene_key(k) == key))
            {
                return Err(Error::invalid(
                    "--set",
                    set,
                    &format!(
                        "sets the key of the sweep's axis `{name}`, which every point overrides"
                    ),
                ));
            }
        }
        let points = points(&self.spec);
        for p in &points {
            self.source
                .scene(&self.set, p)
                .map_err(|e| e.context(&format!("sweep point {} ({})", p.id, p.key)))?;
        }
        Ok(points)
    }

    /// Locks `dir`, writes `grid.json`, and returns the records kept by `--resume`
    /// (none for a new sweep, whose directory loses an earlier sweep's records).
    fn open_dir(
        &self,
        dir: &Path,
        points: &[Point],
    ) -> Result<(crate::io::RunLock, BTreeMap<usize, RunRecord>), Error> {
        crate::io::check_output_dir("--out", dir)?;
        std::fs::create_dir_all(dir.join("runs")).map_err(|e| Error::write(dir, e))?;
        let lock = crate::io::RunLock::acquire(dir)?;
        let grid = Grid {
            source: self.source.name(),
            set: self.set.clone(),
            spec: self.spec.clone(),
            points: points.len(),
        };
        let grid_path = dir.join("grid.json");
        let mut done: BTreeMap<usize, RunRecord> = BTreeMap::new();
        if self.resume && grid_path.exists() {
            check_grid(&grid_path, &grid)?;
            for r in read_records(dir)? {
                let ok = points.get(r.point.id).is_some_and(|p| p == &r.point);
                if !ok {
                    return Err(Error::bad_file(
                        dir.join("runs"),
                        "",
                        format!(
                            "holds run {} ({}), not a point of this grid",
                            r.point.id, r.point.key
                        ),
                    ));
                }
                done.insert(r.point.id, r);
            }
        } else {
            // a new sweep: records of an earlier one would mix two grids (its own
            // files only: what else the user keeps there stays)
            remove_records(&dir.join("runs"))?;
        }
        write_atomic(
            &grid_path,
            serde_json::to_string_pretty(&grid)
                .expect("grid serializes")
                .as_bytes(),
        )?;
        Ok((lock, done))
    }

    /// Runs the points of `mine` not in `done`, each record written into `dir/runs/`
    /// (when given) as soon as it is made; returns the new records.
    fn run_points(
        &self,
        mine: &[&Point],
        done: &BTreeMap<usize, RunRecord>,
        dir: Option<&Path>,
        worker: usize,
        progress: &mut dyn SweepProgress,
    ) -> Result<Vec<RunRecord>, Error> {
        let weight = |p: &Point| -> f64 {
            let s = self
                .source
                .scene(&self.set, p)
                .map(|s| s.steps())
                .unwrap_or(1);
            s as f64 * (p.refine as f64).powi(2)
        };
        let todo: Vec<&&Point> = mine.iter().filter(|p| !done.contains_key(&p.id)).collect();
        let total_weight: f64 = todo.iter().map(|p| weight(p)).sum();
        let (mut spent, mut spent_weight) = (0.0, 0.0);
        let repeat = self.spec.repeat.unwrap_or(1);
        let mut n_done = mine.len() - todo.len();
        let jobs = match self.jobs {
            0 => default_jobs(repeat),
            j => j,
        }
        .min(todo.len());
        if jobs > 1 {
            let weights: Vec<f64> = todo.iter().map(|p| weight(p)).collect();
            let ctx = Jobs {
                dir,
                worker,
                total: mine.len(),
                total_weight,
            };
            return self.run_parallel(&todo, &weights, jobs, n_done, ctx, progress);
        }
        let mut out = Vec::with_capacity(todo.len());
        for p in todo {
            let t0 = Instant::now();
            let mut rec = run_point(&self.source, &self.set, p, repeat)?;
            rec.worker = worker;
            if let Some(dir) = dir {
                write_atomic(
                    &dir.join("runs").join(format!("{:06}.json", p.id)),
                    serde_json::to_string(&rec)
                        .expect("record serializes")
                        .as_bytes(),
                )?;
            }
            spent += t0.elapsed().as_secs_f64();
            spent_weight += weight(p);
            n_done += 1;
            let eta = spent / spent_weight.max(1e-300) * (total_weight - spent_weight).max(0.0);
            progress.run(n_done, mine.len(), &rec, eta);
            out.push(rec);
        }
        Ok(out)
    }

    /// [`Sweep::run_points`] on `jobs` threads, each running one point at a time in a
    /// rayon pool of `cores / jobs` threads, the heaviest points first (longest
    /// processing time first: the last points to end are the short ones). This thread
    /// writes each record as it arrives and reports it; the first error stops the
    /// workers from taking new points (those running finish, their records are kept)
    /// and is returned.
    fn run_parallel(
        &self,
        todo: &[&&Point],
        weights: &[f64],
        jobs: usize,
        mut n_done: usize,
        ctx: Jobs<'_>,
        progress: &mut dyn SweepProgress,
    ) -> Result<Vec<RunRecord>, Error> {
        use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
        let mut order: Vec<usize> = (0..todo.len()).collect();
        order.sort_by(|&a, &b| weights[b].total_cmp(&weights[a]).then(a.cmp(&b)));
        let threads = (cores() / jobs).max(1);
        let repeat = self.spec.repeat.unwrap_or(1);
        let next = AtomicUsize::new(0);
        let stop = AtomicBool::new(false);
        let (tx, rx) = std::sync::mpsc::channel::<(usize, Result<RunRecord, Error>)>();
        let t0 = Instant::now();
        let mut out = Vec::with_capacity(todo.len());
        let mut first_error = None;
        std::thread::scope(|scope| {
            for _ in 0..jobs {
                let tx = tx.clone();
                let (order, next, stop) = (&order, &next, &stop);
                scope.spawn(move || {
                    let pool = match rayon::ThreadPoolBuilder::new().num_threads(threads).build() {
                        Ok(p) => p,
                        Err(e) => {
                            let e = Error::invalid("--jobs", jobs.to_string(), &e.to_string());
                            let _ = tx.send((usize::MAX, Err(e)));
                            return;
                        }
                    };
                    while !stop.load(Ordering::Relaxed) {
                        let k = next.fetch_add(1, Ordering::Relaxed);
                        let Some(&i) = order.get(k) else { break };
                        let r =
                            pool.install(|| run_point(&self.source, &self.set, todo[i], repeat));
                        if tx.send((i, r)).is_err() {
                            break;
                        }
                    }
                });
            }
            drop(tx);
            let mut spent_weight = 0.0;
            for (i, r) in rx {
                let written = r.and_then(|mut rec| {
                    rec.worker = ctx.worker;
                    if let Some(dir) = ctx.dir {
                        write_atomic(
                            &dir.join("runs").join(format!("{:06}.json", rec.point.id)),
                            serde_json::to_string(&rec)
                                .expect("record serializes")
                                .as_bytes(),
                        )?;
                    }
                    Ok(rec)
                });
                match written {
                    Ok(rec) => {
                        spent_weight += weights[i];
                        n_done += 1;
                        let spent = t0.elapsed().as_secs_f64();
                        let eta = spent / spent_weight.max(1e-300)
                            * (ctx.total_weight - spent_weight).max(0.0);
                        progress.run(n_done, ctx.total, &rec, eta);
                        out.push(rec);
                    }
                    Err(e) => {
                        stop.store(true, Ordering::Relaxed);
                        first_error.get_or_insert(e);
                    }
                }
            }
        });
        match first_error {
            Some(e) => Err(e),
            None => {
                out.sort_by_key(|r| r.point.id);
                Ok(out)
            }
        }
    }

    /// Writes the table of `records` into `dir`; returns the verdicts.
    fn finish(&self, dir: &Path, records: Vec<RunRecord>) -> Result<Vec<String>, Error> {
        let rows = table(records);
        let levels = if self.spec.levels.is_empty() {
            DEFAULT_LEVELS.to_vec()
        } else {
            self.spec.levels.clone()
        };
        write_table(dir, &rows, &levels, "sweep")
    }

    /// The sweep spread over the ranks of an MPI job (cargo feature `mpi`): rank r runs
    /// the points `id ≡ r (mod size)`; every rank's records are gathered on rank 0,
    /// which alone writes the directory (records, table, verdicts: the same as a sweep
    /// on one process, timings aside) and returns `Some(verdicts)`; the other ranks
    /// return `None`. Every rank validates the grid (the same checks, so a bad grid
    /// stops all of them); a rank whose run cannot be written or whose input turns out
    /// bad still joins the gather, and rank 0 reports its error. `--resume` works
    /// through rank 0, which tells the others what is recorded. The records reach the
    /// directory at the gather: a job killed before it keeps rank 0's records only
    /// (Slurm arrays with `--shard` keep every finished run).
    #[cfg(feature = "mpi")]
    pub fn run_mpi(&self, progress: &mut dyn SweepProgress) -> Result<Option<Vec<String>>, Error> {
        use mpi::traits::{Communicator, Root};
        let universe = mpi::initialize().ok_or_else(|| {
            Error::invalid("--mpi", "", "MPI was already initialized in this process")
        })?;
        let world = universe.world();
        let (rank, size) = (world.rank() as usize, world.size() as usize);
        let root = world.process_at_rank(0);
        let points = self.validate_points()?;
        let shard = Shard {
            index: rank,
            count: size,
        };
        // rank 0 opens the directory and tells the others which points are recorded
        let mut opened = None;
        let mut recorded = vec![0u8; points.len()];
        let mut open_error = 0u8;
        if rank == 0 {
            match self.open_dir(&self.dir, &points) {
                Ok((lock, done)) => {
                    for id in done.keys() {
                        recorded[*id] = 1;
                    }
                    opened = Some((lock, done));
                }
                Err(e) => {
                    open_error = 1;
                    // the others learn it below and stop
                    root.broadcast_into(&mut open_error);
                    return Err(e);
                }
            }
        }
        root.broadcast_into(&mut open_error);
        if open_error != 0 {
            return Ok(None);
        }
        root.broadcast_into(&mut recorded[..]);
        let done: BTreeMap<usize, RunRecord> = match &opened {
            Some((_, d)) => d.clone(),
            None => BTreeMap::new(),
        };
        let mine: Vec<&Point> = points
            .iter()
            .filter(|p| shard.owns(p.id) && recorded[p.id] == 0)
            .collect();
        let dir = (rank == 0).then_some(self.dir.as_path());
        let result: Result<Vec<RunRecord>, String> = self
            .run_points(&mine, &done, dir, rank, progress)
            .map_err(|e| format!("rank {rank}: {e}"));
        let bytes = serde_json::to_vec(&result).expect("records serialize");
        let len = bytes.len() as mpi::Count;
        if rank != 0 {
            root.gather_into(&len);
            root.gather_varcount_into(&bytes[..]);
            return Ok(None);
        }
        let mut lens = vec![0 as mpi::Count; size];
        root.gather_into_root(&len, &mut lens[..]);
        let displs: Vec<mpi::Count> = lens
            .iter()
            .scan(0, |acc, &x| {
                let d = *acc;
                *acc += x;
                Some(d)
            })
            .collect();
        let mut all = vec![0u8; lens.iter().map(|&l| l as usize).sum()];
        {
            let mut part = mpi::datatype::PartitionMut::new(&mut all[..], &lens[..], &displs[..]);
            root.gather_varcount_into_root(&bytes[..], &mut part);
        }
        let (_lock, mut done) = opened.expect("rank 0 opened the directory");
        for (r, (&d, &l)) in displs.iter().zip(&lens).enumerate() {
            let slice = &all[d as usize..(d + l) as usize];
            let got: Result<Vec<RunRecord>, String> =
                serde_json::from_slice(slice).map_err(|e| {
                    Error::Numerical(format!("rank {r} sent an unreadable record list: {e}"))
                })?;
            match got {
                Ok(records) => {
                    for rec in records {
                        write_atomic(
                            &self
                                .dir
                                .join("runs")
                                .join(format!("{:06}.json", rec.point.id)),
                            serde_json::to_string(&rec)
                                .expect("record serializes")
                                .as_bytes(),
                        )?;
                        done.insert(rec.point.id, rec);
                    }
                }
                Err(msg) => return Err(Error::Numerical(msg)),
            }
        }
        self.finish(&self.dir, done.into_values().collect())
            .map(Some)
    }
}

/// Refuses a `grid.json` that is not `grid`'s.
fn check_grid(path: &Path, grid: &Grid) -> Result<(), Error> {
    let text = crate::limits::read_text(path, "sweep grid", crate::limits::MAX_TEXT_BYTES)?;
    let old: Grid = serde_json::from_str(&text)
        .map_err(|e| Error::bad_file(path, "", format!("is not a sweep grid: {e}")))?;
    if &old != grid {
        return Err(Error::bad_file(
            path,
            "",
            "describes another sweep (scene, --set or axes differ): resume with the same \
             arguments, or write the new sweep into another directory",
        ));
    }
    Ok(())
}

/// `signorini sweep merge DIR`: gathers the records of `DIR/shard-*-of-N/` (every shard
/// of one grid) into `DIR/runs/`, and writes the whole grid's table into `DIR`; returns
/// the verdicts. Refuses shards of different grids and a grid with points missing.
pub fn merge(dir: &Path) -> Result<Vec<String>, Error> {
    let mut shards: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| Error::io(dir, e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.is_dir()
                && p.file_name()
                    .and_then(|n| n.to_str())
                    .is_some_and(|n| n.starts_with("shard-"))
        })
        .collect();
    shards.sort();
    if shards.is_empty() {
        return Err(Error::bad_file(
            dir,
            "",
            "holds no shard-i-of-N directory to merge",
        ));
    }
    // every shard's grid first: one grid, whose points the records must be
    let mut grid: Option<Grid> = None;
    for s in &shards {
        let gp = s.join("grid.json");
        let text = crate::limits::read_text(&gp, "sweep grid", crate::limits::MAX_TEXT_BYTES)?;
        let g: Grid = serde_json::from_str(&text)
            .map_err(|e| Error::bad_file(&gp, "", format!("is not a sweep grid: {e}")))?;
        match &grid {
            None => grid = Some(g),
            Some(first) if first != &g => {
                return Err(Error::bad_file(
                    &gp,
                    "",
                    format!(
                        "describes another sweep than {}",
                        shards[0].join("grid.json").display()
                    ),
                ));
            }
            Some(_) => {}
        }
    }
    let grid = grid.expect("at least one shard");
    let expected = points(&grid.spec);
    let mut records: BTreeMap<usize, RunRecord> = BTreeMap::new();
    for s in &shards {
        for r in read_records(s)? {
            // a record of another grid (issue 34: it became a third row of a 2-point
            // grid)
            if expected.get(r.point.id) != Some(&r.point) {
                return Err(Error::bad_file(
                    s.join("runs").join(format!("{:06}.json", r.point.id)),
                    "",
                    format!(
                        "holds run {} ({}), not a point of the grid of {}",
                        r.point.id,
                        r.point.key,
                        s.join("grid.json").display()
                    ),
                ));
            }
            records.insert(r.point.id, r);
        }
    }
    let missing: Vec<usize> = expected
        .iter()
        .filter(|p| records.get(&p.id).is_none_or(|r| &r.point != *p))
        .map(|p| p.id)
        .collect();
    if !missing.is_empty() {
        return Err(Error::bad_file(
            dir,
            "",
            format!(
                "misses {} of the grid's {} runs (first: {:?}): a shard has not finished; \
                 rerun it with --resume",
                missing.len(),
                expected.len(),
                &missing[..missing.len().min(8)]
            ),
        ));
    }
    // held while the merged table is written: a second merge (or a sweep) into the
    // same directory is refused meanwhile
    let _lock = crate::io::RunLock::acquire(dir)?;
    let runs = dir.join("runs");
    std::fs::create_dir_all(&runs).map_err(|e| Error::write(&runs, e))?;
    // the records of an older sweep or merge in this directory would sit beside a new
    // grid.json
    remove_records(&runs)?;
    for r in records.values() {
        write_atomic(
            &runs.join(format!("{:06}.json", r.point.id)),
            serde_json::to_string(r)
                .expect("record serializes")
                .as_bytes(),
        )?;
    }
    write_atomic(
        &dir.join("grid.json"),
        serde_json::to_string_pretty(&grid)
            .expect("grid serializes")
            .as_bytes(),
    )?;
    let rows = table(records.into_values().collect());
    let levels = if grid.spec.levels.is_empty() {
        DEFAULT_LEVELS.to_vec()
    } else {
        grid.spec.levels.clone()
    };
    write_table(dir, &rows, &levels, "sweep")
}
