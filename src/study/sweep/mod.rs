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
//!
//! By file: this one runs a sweep ([`Sweep`]: points in parallel jobs, a Slurm shard, MPI
//! ranks); `grid` the points; `record` one point's run and record; `table` the rows and
//! verdicts; `write` the CSV and Markdown files; `shard` shards and their merge.

mod grid;
mod record;
mod shard;
mod table;
mod write;

pub use grid::*;
pub use record::*;
pub use shard::*;
pub use table::*;
pub use write::*;

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

/// Most points a sweep runs at the same time (`--jobs`): a thread and a rayon pool each.
pub const MAX_JOBS: usize = 1024;

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

    /// Every point, each scene read, validated and built (before the first run).
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
            let at = |e: Error| e.context(&format!("sweep point {} ({})", p.id, p.key));
            let scene = self.source.scene(&self.set, p).map_err(at)?;
            // built as well (and dropped): what only the build finds — a node set, a
            // starting gap, a mesh's cells — is refused before the first point runs
            // (issue 48: a misspelt node set on an axis stopped the sweep after point 0)
            scene
                .build()
                .map_err(|e| match &self.source {
                    Source::File(f) => e.in_file(f),
                    Source::Bar => e,
                })
                .map_err(at)?;
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
