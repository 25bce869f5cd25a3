//! The application: what `signorini bar`, `signorini run` and `signorini resume` do, as
//! library calls. It sits above the scenes (it builds a scene's model and integrator)
//! and below the studies and the CLI; it hands the driver (`crate::run`) an integrator
//! and, for checkpoints, what it needs to rebuild the run ([`source::RunSource`], which
//! the driver saves without reading). A run held between steps is a [`Session`] (model,
//! integrator, memory plan, the driver's run in progress): `run_bar` and `run_scene`
//! advance one to its end in one call, the Python package's `step(n)` `n` steps at a time.

pub mod source;

use std::path::Path;
use std::time::Instant;

use crate::error::Error;
use crate::run::checkpoint::{self, Checkpoint};
use crate::run::{
    Checkpointing, Output, Progress, RunChecks, RunInProgress, RunResult, finish, probes,
};
use crate::scene::bar::BarScene;
use source::RunSource;

/// Announces the integrator build of `model` (dofs and contacts) to `progress`.
fn announce_integrator(model: &crate::scene::Model, progress: &mut dyn Progress) {
    progress.phase(&format!(
        "building the integrator: factoring M̂ ({} dofs) and the Delassus data of {} contact(s)",
        model.problem.q0.len(),
        model.problem.contacts.len()
    ));
}

/// Runs the bar scene; writes `history.csv`, `summary.json` and the field frames
/// (`fields.pvd`, `fields/*.vtu`) into `out.dir` if given.
pub fn run_bar(
    scene: &BarScene,
    out: Option<Output>,
    progress: &mut dyn Progress,
) -> Result<RunResult, Error> {
    run_bar_from(scene, out, progress, None)
}

fn run_bar_from(
    scene: &BarScene,
    out: Option<Output>,
    progress: &mut dyn Progress,
    resume: Option<&Checkpoint>,
) -> Result<RunResult, Error> {
    let _flush = crate::linalg::FlushGuard::for_run();
    Session::bar(scene, None, out, progress, resume)?.run_to_end(progress)
}

/// Runs a scene file; writes into `out.dir` if given. Errors raised while building name
/// the scene's key paths; [`Scene::from_file`](crate::scene::file::Scene::from_file)
/// adds the file.
pub fn run_scene(
    scene: &crate::scene::file::Scene,
    out: Option<Output>,
    progress: &mut dyn Progress,
) -> Result<RunResult, Error> {
    run_scene_from(scene, out, progress, None)
}

fn run_scene_from(
    scene: &crate::scene::file::Scene,
    out: Option<Output>,
    progress: &mut dyn Progress,
    resume: Option<&Checkpoint>,
) -> Result<RunResult, Error> {
    let _flush = crate::linalg::FlushGuard::for_run();
    Session::scene(scene, None, out, progress, resume)?.run_to_end(progress)
}

/// A run of the bar or of a scene file, held between steps: the integrator, the
/// driver's [`RunInProgress`] (observers, writers, the directory's lock) and what the
/// summary needs (set-up times, the memory plan, the bodies' initial measures).
/// [`run_bar`] and [`run_scene`] are a session advanced to its end in one call; the
/// Python package's `step(n)` advances one `n` steps at a time, with the same checks,
/// history, frames and summary.
pub struct Session {
    integ: Box<dyn crate::integrators::Integrator>,
    run: RunInProgress,
    checks: RunChecks,
    setup: [f64; 2],
    planned: u64,
    bodies: Option<BodyRecord>,
    out: Option<(std::path::PathBuf, crate::io::OutputOptions)>,
    /// The scene's starting-gap rule, for a state set between steps.
    starting_gaps: crate::scene::file::StartingGaps,
}

impl Session {
    /// Builds the bar's model (or takes `model`, built by [`BarScene::build`]) and its
    /// integrator, and opens the run into `out` (from `resume`'s state when given).
    pub fn bar(
        scene: &BarScene,
        model: Option<crate::scene::Model>,
        out: Option<Output>,
        progress: &mut dyn Progress,
        resume: Option<&Checkpoint>,
    ) -> Result<Session, Error> {
        let t0 = Instant::now();
        let mut model = match model {
            Some(m) => m,
            None => {
                progress.phase("building the model");
                scene.build()?
            }
        };
        let geometry = std::mem::take(&mut model.geometry);
        let starting_gaps = std::mem::take(&mut model.starting_gaps);
        announce_integrator(&model, progress);
        let t1 = Instant::now();
        let mut integ = model.into_integrator(&scene.scheme, scene.dt)?;
        let setup = [(t1 - t0).as_secs_f64(), t1.elapsed().as_secs_f64()];
        let parameters = serde_json::to_value(scene).expect("scene serializes");
        let checks = RunChecks::for_geometry(&scene.scheme, &geometry);
        let ckpt =
            (resume.is_some() || out.is_some_and(|o| o.options.checkpoint_every > 0)).then(|| {
                Checkpointing {
                    source: RunSource::Bar {
                        scene: Box::new(scene.clone()),
                    }
                    .to_value(),
                    // the bar reads no file
                    inputs: Vec::new(),
                    resume,
                }
            });
        let run = RunInProgress::start(
            integ.as_mut(),
            scene.steps(),
            scene.elements,
            scene.scheme.theta,
            &checks,
            scene.analytic(),
            parameters,
            out.map(|o| (o, geometry)),
            ckpt,
            crate::run::Monitors {
                accuracy: scene.accuracy_spec(),
                ..crate::run::Monitors::default()
            },
        )?;
        Ok(Session {
            integ,
            run,
            checks,
            setup,
            planned: scene.memory().total(),
            bodies: None,
            out: out.map(|o| (o.dir.to_path_buf(), o.options.clone())),
            starting_gaps,
        })
    }

    /// Builds a scene file's model (or takes `built`, from
    /// [`Scene::build`](crate::scene::file::Scene::build), whose initial state may have
    /// been edited), checks the run's memory plan, builds the integrator and opens the
    /// run into `out` (from `resume`'s state when given).
    pub fn scene(
        scene: &crate::scene::file::Scene,
        built: Option<(crate::scene::Model, crate::scene::file::ModelReport)>,
        out: Option<Output>,
        progress: &mut dyn Progress,
        resume: Option<&Checkpoint>,
    ) -> Result<Session, Error> {
        let t0 = Instant::now();
        let (mut model, report) = match built {
            Some(b) => b,
            None => {
                progress.phase("building the model (mesh, assembly, contacts)");
                scene.build()?
            }
        };
        let probes = probes::ProbeSet::new(&model.probes, &model.geometry);
        let bodies = BodyRecord::start(scene, &model);
        let geometry = std::mem::take(&mut model.geometry);
        let starting_gaps = std::mem::take(&mut model.starting_gaps);
        let names: Vec<String> = scene.bodies.iter().map(|b| b.name.clone()).collect();
        let rotations =
            crate::run::rotations::RotationCheck::new(&geometry, &names, scene.scheme.max_rotation);
        // the run's memory ledger, checked before anything is factored
        let mut plan = model.plan(&scene.scheme, scene.time.dt)?;
        let (m, rows) = (model.problem.contacts.len(), model.problem.contacts.rows());
        if let Some(o) = out {
            plan.add_history(report.dofs, m, (rows - m) / m.max(1), o.options.hdf5());
        }
        if scene.time.accuracy.is_some() {
            plan.add_accuracy(report.linear_structure, report.dofs, rows);
        }
        plan.ledger.check(
            "scene",
            format!("{} dofs, {m} contacts ({rows} rows)", report.dofs),
        )?;
        announce_integrator(&model, progress);
        let t1 = Instant::now();
        let mut integ = model.into_integrator(&scene.scheme, scene.time.dt)?;
        let setup = [(t1 - t0).as_secs_f64(), t1.elapsed().as_secs_f64()];
        let parameters = serde_json::to_value(scene).expect("scene serializes");
        let checks = RunChecks::for_geometry(&scene.scheme, &geometry);
        // what a checkpoint rebuilds from: only formed when the run writes checkpoints
        let ckpt = match resume {
            Some(c) => Some(Checkpointing {
                source: c.source.clone(),
                inputs: Vec::new(),
                resume,
            }),
            None if out.is_some_and(|o| o.options.checkpoint_every > 0) => {
                let source = RunSource::Scene {
                    file: scene.file.clone().unwrap_or_default(),
                    toml: toml::to_string(scene).map_err(|e| {
                        Error::Numerical(format!(
                            "the scene does not serialize for a checkpoint: {e}"
                        ))
                    })?,
                    base_dir: std::path::absolute(&scene.base_dir)
                        .unwrap_or(scene.base_dir.clone()),
                };
                Some(Checkpointing {
                    inputs: source.input_files()?,
                    source: source.to_value(),
                    resume: None,
                })
            }
            None => None,
        };
        let run = RunInProgress::start(
            integ.as_mut(),
            scene.steps(),
            report.cells,
            scene.scheme.theta,
            &checks,
            scene.reference.map(|r| r.impacting_bar),
            parameters,
            out.map(|o| (o, geometry)),
            ckpt,
            crate::run::Monitors {
                probes,
                rotations,
                accuracy: scene.time.accuracy_spec(),
            },
        )?;
        Ok(Session {
            integ,
            run,
            checks,
            setup,
            planned: plan.ledger.total(),
            bodies: Some(bodies),
            out: out.map(|o| (o.dir.to_path_buf(), o.options.clone())),
            starting_gaps,
        })
    }

    /// The integrator, at the state of the last step taken.
    pub fn integrator(&self) -> &dyn crate::integrators::Integrator {
        self.integ.as_ref()
    }

    /// The integrator, to replace its state between steps (then call
    /// [`Session::state_replaced`]).
    pub fn integrator_mut(&mut self) -> &mut dyn crate::integrators::Integrator {
        self.integ.as_mut()
    }

    /// Steps taken so far, and the run's total (of an accuracy run, its count at the
    /// largest step: it takes at least these; [`Session::is_done`] says when it ends).
    pub fn progress(&self) -> (usize, usize) {
        (self.integ.state().step, self.run.steps())
    }

    /// Whether the run has reached its end (its last step, or an accuracy run's end
    /// time).
    pub fn is_done(&self) -> bool {
        self.run.is_done(self.integ.as_ref())
    }

    /// Whether the run chooses its steps (`time.accuracy`): its step count is not known
    /// before it ends.
    pub fn chooses_steps(&self) -> bool {
        self.run.chooses_steps()
    }

    /// Steps up to step `until` (at most the last) with the run's checks and observers;
    /// after an error (an interrupt among them) the session stays where it stopped.
    pub fn advance(&mut self, until: usize, progress: &mut dyn Progress) -> Result<(), Error> {
        self.run
            .advance(self.integ.as_mut(), until, &self.checks, progress)
    }

    /// The statistics of the last step taken (`None` before the first).
    pub fn last_stats(&self) -> Option<&crate::integrators::StepStats> {
        self.run.last_stats()
    }

    /// The history file being written, its rows so far flushed
    /// ([`RunInProgress::history_so_far`]).
    pub fn history_so_far(&mut self) -> Result<Option<std::path::PathBuf>, Error> {
        self.run.history_so_far()
    }

    /// Makes the history and frames on disk whole without ending the run.
    pub fn sync(&mut self) -> Result<(), Error> {
        self.run.sync()
    }

    /// The integrator's state was replaced between steps: the energy balance restarts
    /// from it.
    pub fn state_replaced(&mut self) {
        self.run.state_replaced(self.integ.as_ref());
    }

    /// Replaces the state between steps: the displacements `q` and/or the velocities
    /// `v`, one finite value per dof each ([`crate::scene::check_state`]). A new `q` must
    /// pass the scene's starting-gap rule ([`crate::scene::file::StartingGaps::check`]:
    /// no contact node deeper inside its obstacle or the other body than its entry's
    /// `overlap_tolerance`, the error the scene's own start gives); the gaps, Jacobians
    /// and Delassus data are then evaluated again at it (as a checkpoint's restore
    /// does), and the energy balance restarts from the new state (the energy the edit
    /// gave or took is no work of the run's forces). Refused, the state is left as it
    /// was.
    pub fn set_state(&mut self, q: Option<Vec<f64>>, v: Option<Vec<f64>>) -> Result<(), Error> {
        let integ = self.integ.as_mut();
        crate::scene::check_state(&q, &v, integ.state().q.len())?;
        if let Some(q) = &q {
            let mut gap = vec![0.0; integ.state().gap.len()];
            integ.starting_gaps(q, &mut gap);
            self.starting_gaps.check(&gap)?;
        }
        // the state's vectors under the names every scheme saves them by
        // (`State::save`), restored as a checkpoint's are
        let mut saved = integ.save();
        for (name, x) in [("q", q), ("v", v)] {
            if let Some(x) = x {
                let x = crate::integrators::saved::Floats(x);
                saved.vectors.insert(name.to_string(), x);
            }
        }
        integ.restore(&saved)?;
        self.state_replaced();
        Ok(())
    }

    /// Advances to the last step and [`finish`](Session::finish)es; asked to stop, it
    /// closes the writers (the files so far readable) and returns the interrupt.
    pub fn run_to_end(mut self, progress: &mut dyn Progress) -> Result<RunResult, Error> {
        progress.start(self.run.progress_total());
        if let Err(e) = self.advance(usize::MAX, progress) {
            if matches!(e, Error::Interrupted { .. }) {
                self.run.close_writers()?;
            }
            return Err(e);
        }
        self.finish()
    }

    /// Ends a session advanced to its last step: closes the outputs and writes
    /// `summary.json` and the plots where the run writes files.
    pub fn finish(self) -> Result<RunResult, Error> {
        let Session {
            mut integ,
            run,
            setup,
            planned,
            mut bodies,
            out,
            ..
        } = self;
        let mut r = run.finish(integ.as_mut())?;
        if let Some(b) = bodies.as_mut() {
            r.summary.bodies = b.finish(integ.system(), &r.state);
        }
        let out = out.as_ref().map(|(dir, options)| Output { dir, options });
        finish(r, setup, planned, out)
    }
}

/// Each body's measures at the start of a scene's run, for its summary's `bodies`.
struct BodyRecord {
    measures: Option<crate::model::BodyMeasures>,
    names: Vec<String>,
    initial: Vec<crate::model::BodyState>,
}

impl BodyRecord {
    /// Measures `model`'s initial state (before its geometry goes to the frames).
    fn start(scene: &crate::scene::file::Scene, model: &crate::scene::Model) -> Self {
        let p = &model.problem;
        let mut measures = crate::model::BodyMeasures::new(&model.geometry, p.q0.len());
        let mut initial = Vec::new();
        if let Some(m) = measures.as_mut() {
            initial = vec![crate::model::BodyState::default(); m.bodies()];
            m.measure(&p.system.mass, &p.q0, &p.v0, &mut initial);
        }
        BodyRecord {
            measures,
            names: scene.bodies.iter().map(|b| b.name.clone()).collect(),
            initial,
        }
    }

    /// The start's and `state`'s measures, body by body.
    fn finish(
        &mut self,
        sys: &crate::model::LinearSystem,
        state: &crate::integrators::State,
    ) -> Vec<crate::run::summary::BodySummary> {
        let Some(m) = self.measures.as_mut() else {
            return Vec::new();
        };
        let mut last = vec![crate::model::BodyState::default(); m.bodies()];
        m.measure(&sys.mass, &state.q, &state.v, &mut last);
        self.initial
            .iter()
            .zip(last)
            .enumerate()
            .map(|(b, (&initial, last))| crate::run::summary::BodySummary {
                name: self
                    .names
                    .get(b)
                    .cloned()
                    .unwrap_or_else(|| format!("body {b}")),
                initial,
                last,
            })
            .collect()
    }
}

/// Finishes the killed run in `dir` from its `checkpoint.json` (see
/// [`crate::run::checkpoint`]): rebuilds the model from the scene the checkpoint holds,
/// restores the state and the outputs' cursors, and steps to the end, writing the same
/// files an uninterrupted run writes.
pub fn resume(dir: &Path, progress: &mut dyn Progress) -> Result<RunResult, Error> {
    let c = Checkpoint::read(dir)?;
    c.verify(dir)?;
    // the run's arithmetic, for the same bits as the uninterrupted run
    match c.arithmetic {
        crate::linalg::Arithmetic::Fused if !crate::linalg::cpu_has_fma() => {
            return Err(Error::bad_file(
                dir.join(checkpoint::FILE),
                "`arithmetic`",
                "fused: the run was started on a CPU with fused multiply-add and this one has \
                 none, so the resumed steps would round differently; resume on such a CPU"
                    .to_string(),
            ));
        }
        a => crate::linalg::set_portable_arithmetic(a == crate::linalg::Arithmetic::Portable),
    }
    // and its subnormal mode (the guard of the run rebuilt below applies it)
    match c.subnormals {
        crate::linalg::Subnormals::Flushed if !crate::linalg::subnormals::flush_supported() => {
            return Err(Error::bad_file(
                dir.join(checkpoint::FILE),
                "`subnormals`",
                "flushed: the run flushed subnormal numbers to zero and this build cannot \
                 on this CPU, so the resumed steps would round differently; resume on an \
                 x86-64 or aarch64 machine"
                    .to_string(),
            ));
        }
        m => crate::linalg::set_ieee_subnormals(m == crate::linalg::Subnormals::Ieee),
    }
    let out = Output {
        dir,
        options: &c.output,
    };
    let file = dir.join(checkpoint::FILE);
    match &RunSource::from_checkpoint(&c.source, &file)? {
        RunSource::Bar { scene } => {
            scene.validate().map_err(|e| e.in_file(&file))?;
            run_bar_from(scene, Some(out), progress, Some(&c))
        }
        RunSource::Scene {
            file: scene_file,
            toml,
            base_dir,
        } => {
            let mut scene =
                crate::scene::file::Scene::from_toml(toml).map_err(|e| e.in_file(&file))?;
            scene.base_dir = base_dir.clone();
            scene.file = Some(scene_file.clone());
            run_scene_from(&scene, Some(out), progress, Some(&c))
        }
    }
}
