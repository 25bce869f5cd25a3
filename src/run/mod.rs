//! The driver: steps an integrator, streams the history, measures the contact response
//! against the analytic reference and assembles the [`Summary`]. It knows integrators,
//! writers and observers, never scenes: the application above it (`crate::app`: `run_bar`,
//! `run_scene`, `resume`) builds the integrator and hands it down with what a checkpoint
//! must keep to rebuild the run (opaque here).
//!
//! Every run goes through one step loop, [`drive`] (or [`drive_to`], to a given step):
//! it checks each state ([`RunChecks`]) and hands it to observers (statistics, the
//! contact measurement, history and frames, checkpoints). A run between its start and
//! its end is a [`RunInProgress`]: opened once, advanced to its last step in one call
//! ([`run_checkpointed`]) or in many (the Python package's `step(n)`), finished into its
//! [`Summary`] — the same history and summary either way. The loop reserves nothing
//! per step: the integrator works in its own buffers, the contact measurement keeps the
//! first contact interval only (and the per-step force up to
//! [`FORCE_TRACE_MAX_STEPS`], reserved once).

pub mod accuracy;
pub mod checkpoint;
mod close;
pub use close::finish;
mod contact;
pub mod driver;
pub mod history_thread;
mod observers;
pub mod probes;
pub mod rotations;
pub mod summary;
mod windows;

pub use contact::FORCE_TRACE_MAX_STEPS;
pub use driver::{Observer, Progress, Quiet, RunChecks, drive, drive_to};
pub use observers::ENERGY_CHECK_STRIDE;
pub use summary::{
    ContactSummary, EnergyBalance, FrictionSummary, Iterations, MeanMax, NewtonLoops,
    RotationSummary, RunResult, Summary, forecast_name, write_summary,
};

use contact::{ContactTracker, contact_summary};
use observers::{Acc, CheckpointPlan, EnergyCheck, RunObserver, Writers};

use std::path::Path;
use std::time::Instant;

use crate::analytic::ImpactingBar;
use crate::error::Error;
use crate::integrators::Integrator;
use crate::io::frames::{FrameStream, FrameWriter, Geometry};
use crate::io::{HistoryWriter, OutputOptions};
use checkpoint::Checkpoint;

/// Snapshots in flight between the run and the frame writer thread: two lets the
/// writer encode one frame while the run fills the next.
const FRAME_POOL: usize = 2;

/// Where and what a run writes.
#[derive(Clone, Copy, Debug)]
pub struct Output<'a> {
    /// Output directory.
    pub dir: &'a Path,
    /// Strides, formats.
    pub options: &'a OutputOptions,
}

/// What [`run`] needs to checkpoint a run or to resume one.
pub struct Checkpointing<'a> {
    /// What the application needs to rebuild the run on resume, saved as it gives it
    /// (opaque to the driver: `crate::app::source::RunSource` for `signorini`'s runs).
    pub source: serde_json::Value,
    /// The files the run reads, as they are at its start (for [`Checkpoint::verify`]);
    /// read from the checkpoint when resuming.
    pub inputs: Vec<checkpoint::InputFile>,
    /// The checkpoint to resume from (`None`: a new run).
    pub resume: Option<&'a Checkpoint>,
}

/// Steps `integ` `steps` times through [`drive`], streaming the history and the field
/// frames (when `out` is given) and measuring the contact; the caller writes the
/// summary ([`write_summary`]).
///
/// Frames are saved at the start, every `frame_stride` steps, at each contact onset and
/// release and at the last step; history rows every `history_stride` steps and at the
/// last step. The time spent writing (including the energies and fields computed only
/// for output) is measured and reported as `output_seconds`.
#[allow(clippy::too_many_arguments)]
pub fn run(
    integ: &mut dyn Integrator,
    steps: usize,
    elements: usize,
    theta: f64,
    checks: &RunChecks,
    reference: Option<ImpactingBar>,
    parameters: serde_json::Value,
    out: Option<(Output, Geometry)>,
    progress: &mut dyn Progress,
) -> Result<RunResult, Error> {
    run_checkpointed(
        integ,
        steps,
        elements,
        theta,
        checks,
        reference,
        parameters,
        out,
        progress,
        None,
        Monitors::default(),
    )
}

/// What a run measures beside its steps: the displacement probes (a scene's
/// `[[probes]]`) and the rotation check of its linear bodies ([`rotations`]).
#[derive(Clone, Debug, Default)]
pub struct Monitors {
    /// The probes.
    pub probes: probes::ProbeSet,
    /// The rotation check (`None`: no linear solid or plane body, or `max_rotation = inf`).
    pub rotations: Option<rotations::RotationCheck>,
    /// The accuracy mode's request (`time.accuracy`; `None`: every step at the
    /// integrator's `h`): the run then takes its steps window by window
    /// ([`accuracy::Controller`]), `steps` being the count at the largest step.
    pub accuracy: Option<accuracy::AccuracySpec>,
}

/// [`run`], writing checkpoints when `out.options.checkpoint_every > 0` (then `ckpt`
/// says what to rebuild), or resuming from `ckpt.resume`, and reading `monitors`:
/// [`RunInProgress::start`], one [`RunInProgress::advance`] to the last step and
/// [`RunInProgress::finish`]. Asked to stop, it leaves the history and frames readable.
#[allow(clippy::too_many_arguments)]
pub fn run_checkpointed(
    integ: &mut dyn Integrator,
    steps: usize,
    elements: usize,
    theta: f64,
    checks: &RunChecks,
    reference: Option<ImpactingBar>,
    parameters: serde_json::Value,
    out: Option<(Output, Geometry)>,
    progress: &mut dyn Progress,
    ckpt: Option<Checkpointing>,
    monitors: Monitors,
) -> Result<RunResult, Error> {
    let mut run = RunInProgress::start(
        integ, steps, elements, theta, checks, reference, parameters, out, ckpt, monitors,
    )?;
    progress.start(run.progress_total());
    if let Err(e) = run.advance(integ, usize::MAX, checks, progress) {
        if matches!(e, Error::Interrupted { .. }) {
            // asked to stop: leave the history and the frames (with their .pvd) readable
            run.close_writers()?;
        }
        return Err(e);
    }
    run.finish(integ)
}

/// A run between its start and its end: the observers of [`drive`] (statistics, the
/// contact measurement, the history and frame writers, checkpoints, the energy balance,
/// probes), the run directory's lock and what the summary needs. The integrator stays
/// the caller's and is lent to each call. [`run_checkpointed`] advances it to the end in
/// one call; the Python package's `step(n)` advances it `n` steps at a time, so both
/// write the same history and summary.
pub struct RunInProgress {
    obs: RunObserver,
    steps: usize,
    elements: usize,
    theta: f64,
    reference: Option<ImpactingBar>,
    parameters: serde_json::Value,
    energy0: f64,
    /// Seconds spent opening the outputs and, at the end, closing them.
    output_seconds: f64,
    /// Seconds spent in [`RunInProgress::advance`] (the summary's wall time).
    stepping_seconds: f64,
    /// The last step's statistics.
    last: Option<crate::integrators::StepStats>,
    /// The accuracy mode's controller.
    control: Option<accuracy::Controller>,
    /// `history.csv` of a run that writes files.
    history_path: Option<std::path::PathBuf>,
    /// Held until the run ends: a second run into the same directory is refused.
    _lock: Option<crate::io::RunLock>,
}

impl RunInProgress {
    /// Opens the outputs (history, frames, HDF5, the lock) and the observers for a run
    /// of `steps` steps of `integ` from its current state, or from `ckpt.resume`'s.
    #[allow(clippy::too_many_arguments)]
    pub fn start(
        integ: &mut dyn Integrator,
        steps: usize,
        elements: usize,
        theta: f64,
        checks: &RunChecks,
        reference: Option<ImpactingBar>,
        parameters: serde_json::Value,
        out: Option<(Output, Geometry)>,
        ckpt: Option<Checkpointing>,
        monitors: Monitors,
    ) -> Result<RunInProgress, Error> {
        let Monitors {
            mut probes,
            rotations,
            accuracy,
        } = monitors;
        if let Some(a) = &accuracy
            && !integ.kind().capabilities().variable_step
        {
            return Err(Error::invalid(
                "time.accuracy",
                a.tol,
                &format!(
                    "{} steps at one h: the accuracy mode needs a one-step scheme",
                    integ.name()
                ),
            ));
        }
        let h = integ.dt();
        let m = integ.state().gap.len();
        let resume = ckpt.as_ref().and_then(|c| c.resume);
        if let Some(c) = resume {
            // an accuracy run's count is at its largest step: it takes more
            let past = accuracy.is_none() && c.integrator.step >= steps;
            if c.steps != steps || past || c.run.accuracy.is_some() != accuracy.is_some() {
                return Err(Error::invalid(
                    "checkpoint steps",
                    format!("{} (at step {})", c.steps, c.integrator.step),
                    &format!("the scene makes {steps} steps"),
                ));
            }
            integ.restore(&c.integrator)?;
        }
        // a starting state that turns a linear body is refused before any file is made
        if let (Some(r), None) = (&rotations, resume) {
            let s = integ.state();
            r.check_start(s.time, &s.q)?;
        }
        let t0 = Instant::now();
        let mut writers = Writers {
            history: None,
            frames: None,
            frame_stride: usize::MAX,
            history_stride: usize::MAX,
            closed_before: false,
            frame_count: 0,
            seconds: 0.0,
        };
        let mut plan = None;
        let energy0 = match resume {
            Some(c) => c.run.energy0.0,
            None => {
                let s = integ.state();
                integ.system().total_energy(s.time, &s.q, &s.v)
            }
        };
        // held until the run returns: a second run into the same directory is refused
        let mut _lock = None;
        let mut history_path = None;
        if let Some((o, geom)) = out {
            o.options.validate()?;
            _lock = Some(crate::io::RunLock::acquire(o.dir)?);
            let geom_outlines = geom.outlines.clone();
            let hist_path = o.dir.join("history.csv");
            history_path = Some(hist_path.clone());
            // solid and plane bodies: each one's centre and momenta per row (a rod's are its
            // summary's release velocity)
            let bodies = (geom.dim >= 2)
                .then(|| crate::model::BodyMeasures::new(&geom, integ.state().q.len()))
                .flatten();
            let hist = match resume {
                Some(c) => HistoryWriter::resume(
                    &hist_path,
                    c.run.history_bytes,
                    c.run.history_rows,
                    o.options.contact_columns.per_contact(m),
                    bodies,
                )?
                .with_dt_column(accuracy.is_some()),
                None => {
                    crate::io::prepare_run_dir(o.dir)?;
                    HistoryWriter::create_with_steps(
                        &hist_path,
                        m,
                        integ.state().tangent_dim,
                        o.options.contact_columns.per_contact(m),
                        bodies,
                        accuracy.is_some(),
                    )?
                }
            };
            let h5 = crate::io::Hdf5Output::open(o.dir, o.options, resume.is_some())?;
            let hist = h5.attach_history(
                hist,
                (m, integ.state().tangent_dim),
                integ.name(),
                h,
                theta,
                &parameters,
                resume.map(|c| c.run.history_rows as usize),
            )?;
            // a model without field geometry (the academic examples) writes no frames
            if o.options.fields && !geom.points.is_empty() {
                let w = match resume {
                    Some(c) => FrameWriter::resume(
                        o.dir,
                        "fields",
                        geom,
                        integ.jacobian(),
                        o.options.encoding,
                        c.run.frames,
                    )?,
                    None => FrameWriter::create(
                        o.dir,
                        "fields",
                        geom,
                        integ.jacobian(),
                        o.options.encoding,
                    )?,
                };
                if !geom_outlines.is_empty() {
                    crate::io::frames::write_outlines(
                        &o.dir.join("obstacles.vtu"),
                        &geom_outlines,
                    )?;
                }
                let w = h5.attach_frames(w, resume.map(|c| c.run.frames))?;
                let s = integ.state();
                let mut w =
                    FrameStream::spawn_with_statuses(w, s.q.len(), m, s.status.len(), FRAME_POOL);
                if resume.is_none() {
                    w.push(s, integ.jacobian(), h)?;
                    writers.frame_count += 1;
                }
                writers.frames = Some(w);
            }
            writers.history = Some(history_thread::History::new(
                hist,
                integ.shared_system(),
                integ.state(),
            ));
            writers.frame_stride = o.options.frame_stride(steps);
            writers.history_stride = o.options.history_stride;
            let every = resume.map_or(o.options.checkpoint_every, |c| c.every);
            if let Some(c) = ckpt.as_ref().filter(|_| every > 0) {
                let inputs = match resume {
                    Some(r) => r.inputs.clone(),
                    None => c.inputs.clone(),
                };
                // where the run is now (a resumed directory may have been moved whole)
                let out_dir = std::fs::canonicalize(o.dir).map_err(|e| Error::io(o.dir, e))?;
                plan = Some(CheckpointPlan {
                    every,
                    dir: o.dir.to_path_buf(),
                    source: c.source.clone(),
                    output: o.options.clone(),
                    steps,
                    energy0,
                    inputs,
                    out_dir,
                    history_hash: Default::default(),
                    abort_after: std::env::var("SIGNORINI_ABORT_AFTER_STEP")
                        .ok()
                        .and_then(|v| v.parse().ok()),
                });
            }
        }
        let output_seconds = t0.elapsed().as_secs_f64();
        let mut obs = RunObserver {
            acc: Acc::default(),
            tracker: ContactTracker::new(
                // an accuracy run takes at least `steps` steps (every step ≤ `dt_max`)
                if accuracy.is_some() {
                    steps.saturating_mul(2)
                } else {
                    steps
                },
                plan.is_none(),
                reference.is_some(),
                h,
            ),
            windowed: accuracy.is_some(),
            writers,
            h,
            plan,
            probes: probes::ProbeSet::default(),
            rotations,
            last_rotation: None,
            // Schatzman–Paoli's velocity is a central difference: its discrete energy is
            // not the θ-method's, whose balance the check reads
            energy: integ.kind().capabilities().theta_energy.then(|| {
                let s = integ.state();
                EnergyCheck {
                    audit: crate::model::energy::EnergyAudit::new(
                        integ.system(),
                        s.time,
                        &s.q,
                        &s.v,
                        checks.energy_floor.joules(integ.system()),
                    ),
                    theta,
                    max: checks.energy_excess_limit(integ.step_matrix_constant()),
                    caps_allowed: checks.allow_caps,
                }
            }),
        };
        {
            let s = integ.state();
            let saved: Option<Vec<Vec<f64>>> =
                resume.map(|c| c.run.probes.iter().map(|f| f.0.clone()).collect());
            probes.start(s.time, h, &s.q, saved.as_deref());
        }
        obs.probes = probes;
        if let Some(c) = resume {
            obs.restore(&c.run);
            if let Some(e) = obs.energy.as_mut() {
                e.audit
                    .restore(c.run.energy_audit.map(|b| b.0), &integ.state().q);
            }
        }
        let pilot_start = Instant::now();
        let control = match accuracy {
            Some(spec) => {
                let saved = resume.and_then(|c| c.run.accuracy.clone());
                let fresh = saved.is_none();
                let mut c = accuracy::Controller::new(spec, integ, checks, theta, saved);
                if fresh {
                    c.pilot(integ, checks)?;
                }
                Some(c)
            }
            None => None,
        };
        // the accuracy mode's pilot pass is part of its stepping
        let pilot_seconds = if control.is_some() {
            pilot_start.elapsed().as_secs_f64()
        } else {
            0.0
        };
        Ok(RunInProgress {
            control,
            obs,
            steps,
            elements,
            theta,
            reference,
            parameters,
            energy0,
            output_seconds,
            // the accuracy mode's pilot pass is part of its stepping
            stepping_seconds: pilot_seconds,
            last: None,
            history_path,
            _lock,
        })
    }

    /// The steps of the whole run (of an accuracy run, its steps at the largest step:
    /// it takes at least these).
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// Whether the run chooses its steps (the accuracy mode).
    pub fn chooses_steps(&self) -> bool {
        self.control.is_some()
    }

    /// What progress counts to: the steps, or (an accuracy run, whose steps are not known
    /// before) thousandths of the span.
    pub fn progress_total(&self) -> usize {
        if self.control.is_some() {
            1000
        } else {
            self.steps
        }
    }

    /// Whether `integ` has reached the run's end: its last step, or (an accuracy run) its
    /// end time.
    pub fn is_done(&self, integ: &dyn Integrator) -> bool {
        match &self.control {
            Some(c) => c.done(integ.state().time),
            None => integ.state().step >= self.steps,
        }
    }

    /// Steps `integ` through [`drive_to`] up to step `until` (at most the run's last),
    /// with every check and observer of a whole run; an error leaves the run where it
    /// stopped (an interrupted run can advance again).
    pub fn advance(
        &mut self,
        integ: &mut dyn Integrator,
        until: usize,
        checks: &RunChecks,
        progress: &mut dyn Progress,
    ) -> Result<(), Error> {
        let start = Instant::now();
        if self.control.is_some() {
            let r = self.advance_windows(integ, until, checks, progress);
            self.stepping_seconds += start.elapsed().as_secs_f64();
            return r;
        }
        let last = &mut self.last;
        let mut keep = |_: &dyn Integrator, st: &crate::integrators::StepStats, _: bool| {
            *last = Some(*st);
            Ok(())
        };
        let r = drive_to(
            integ,
            until.min(self.steps),
            self.steps,
            checks,
            &mut [&mut self.obs, &mut keep],
            progress,
        );
        self.stepping_seconds += start.elapsed().as_secs_f64();
        r
    }

    /// The statistics of the last step taken (`None` before the first).
    pub fn last_stats(&self) -> Option<&crate::integrators::StepStats> {
        self.last.as_ref()
    }

    /// The history file as it is being written (`history.csv.part`), every queued row
    /// written and flushed: the rows so far, to read without ending the run (`None`
    /// for a run that writes no files).
    pub fn history_so_far(&mut self) -> Result<Option<std::path::PathBuf>, Error> {
        match (self.obs.writers.history.as_mut(), &self.history_path) {
            (Some(w), Some(path)) => {
                w.sync()?;
                Ok(Some(crate::io::part_path(path)))
            }
            _ => Ok(None),
        }
    }

    /// Makes the history and the frames on disk whole (every queued row and frame
    /// written and flushed, `history.csv` holding the rows so far, the `.pvd` listing
    /// the frames) without ending the run.
    pub fn sync(&mut self) -> Result<(), Error> {
        if let Some(w) = self.obs.writers.history.as_mut() {
            w.sync()?;
            if let Some(path) = &self.history_path {
                crate::io::publish_part(path)?;
            }
        }
        if let Some(f) = self.obs.writers.frames.as_mut() {
            f.sync()?;
        }
        Ok(())
    }

    /// Closes the history and frame writers (an interrupted run's last act: its files
    /// stay readable, and it cannot advance any more).
    pub fn close_writers(&mut self) -> Result<(), Error> {
        if let Some(w) = self.obs.writers.history.take() {
            w.finish()?;
        }
        if let Some(f) = self.obs.writers.frames.take() {
            f.finish()?;
        }
        Ok(())
    }

    /// The state of `integ` was replaced between steps (the Python package's
    /// `set_state`): the energy balance starts again from it, since the energy given or
    /// taken by the edit is no work of the run's forces.
    pub fn state_replaced(&mut self, integ: &dyn Integrator) {
        if let Some(e) = self.obs.energy.as_mut() {
            let s = integ.state();
            let floor = e.audit.floor();
            e.audit =
                crate::model::energy::EnergyAudit::new(integ.system(), s.time, &s.q, &s.v, floor);
        }
    }
}
