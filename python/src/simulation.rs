//! `_Simulation`: one run of a scene, opened by the first `step()`, `run()` or `start()`
//! as a library `app::Session` and advanced by both; its state, mesh, bodies and history
//! as numpy arrays.

use super::*;
use crate::convert::{
    BodyRow, MeshArrays, NamedArrays, final_bodies, measure_bodies, mesh_arrays, named_arrays,
};
use crate::sim_state::{SimState, temp_dir};

/// `step(n)` holds the GIL for work expected to take less than this (s): a Python loop of
/// `step(1)` on a small model then pays no release and re-acquisition per call; anything
/// longer (a mesh's step, a long chunk) runs with the GIL released.
const GIL_RELEASE_AFTER: f64 = 50e-6;

/// A simulation of a scene (`signorini.Simulation` wraps it): `run()` for a whole run
/// written as the CLI writes it, or `step(n)` for step-by-step control.
#[pyclass(module = "signorini._signorini", name = "_Simulation", frozen)]
pub(crate) struct PySimulation {
    kind: Kind,
    state: Mutex<SimState>,
    /// Set by `cancel()` (no lock: the stepping thread holds `state`), read at every
    /// step, cleared when a call stops on it.
    cancel: std::sync::Arc<std::sync::atomic::AtomicBool>,
}

impl PySimulation {
    /// The state, or an error while another thread runs or steps this simulation:
    /// waiting for it while holding the GIL would deadlock with the run's progress
    /// callback, which needs the GIL.
    fn lock(&self) -> PyResult<std::sync::MutexGuard<'_, SimState>> {
        self.state.try_lock().map_err(|e| match e {
            std::sync::TryLockError::WouldBlock => PyRuntimeError::new_err(
                "the simulation is running or stepping in another thread: read it when that ends",
            ),
            std::sync::TryLockError::Poisoned(_) => {
                PyRuntimeError::new_err("the simulation failed in another thread")
            }
        })
    }

    /// Builds the model (the GIL released) where neither a run nor a model exists yet,
    /// a copy of its geometry kept for `mesh()` (the run measures, checks and writes
    /// frames on the model's own); the first `step()` or `run()` integrates it.
    fn ensure_model(&self, py: Python<'_>, g: &mut SimState) -> PyResult<()> {
        if g.session.is_none() && g.finished.is_none() && g.model.is_none() {
            let kind = self.kind.clone();
            let built = interruptible(
                py,
                &self.cancel,
                "building the model",
                move || kind.build(),
                drop,
            )?
            .map_err(py_err)?;
            if g.geometry.is_none() {
                g.geometry = Some(std::sync::Arc::new(built.0.geometry.clone()));
            }
            g.model = Some(built);
        }
        Ok(())
    }

    /// Opens the run (the GIL released) into `out`, or into a temporary directory with
    /// no fields, plots or HDF5 (the history alone, read back at the end); integrates
    /// the model built for `mesh()` / `set_state()` where there is one.
    fn open(
        &self,
        py: Python<'_>,
        g: &mut SimState,
        out: Option<PathBuf>,
        fields: Option<bool>,
        plots: Option<bool>,
    ) -> PyResult<()> {
        let mut options = self.kind.output();
        let temporary = out.is_none();
        let dir = out.unwrap_or_else(temp_dir);
        if temporary {
            options.fields = false;
            options.plots = false;
            options.hdf5 = Some(false);
        }
        if let Some(f) = fields {
            options.fields = f;
        }
        if let Some(p) = plots {
            options.plots = p;
        }
        let (kind, built, known) = (self.kind.clone(), g.model.take(), g.geometry.is_some());
        let (target, abandoned) = (dir.clone(), dir.clone());
        let opened = interruptible(
            py,
            &self.cancel,
            "opening the run",
            move || {
                let built = match built {
                    Some(b) => b,
                    None => kind.build()?,
                };
                // `mesh()` after the run opens reads this copy
                let geometry = (!known).then(|| built.0.geometry.clone());
                let s = kind.session(
                    Some(built),
                    Output {
                        dir: &target,
                        options: &options,
                    },
                    &mut signorini::run::Quiet,
                )?;
                Ok((s, geometry))
            },
            // interrupted: the abandoned work removes its own temporary directory once
            // it ends (its writers stopped and its lock gone first)
            move |r: Result<_, Error>| {
                drop(r);
                if temporary {
                    let _ = std::fs::remove_dir_all(&abandoned);
                }
            },
        )?;
        match opened {
            Ok((s, geometry)) => {
                if let Some(geo) = geometry {
                    g.geometry = Some(std::sync::Arc::new(geo));
                }
                g.session = Some(s);
                g.dir = Some(dir);
                g.temporary = temporary;
                Ok(())
            }
            Err(e) => {
                if temporary {
                    let _ = std::fs::remove_dir_all(&dir);
                }
                Err(py_err(e))
            }
        }
    }

    fn vector(
        &self,
        py: Python<'_>,
        pick: impl Fn(&State) -> &[f64],
    ) -> PyResult<Py<PyArray1<f64>>> {
        let g = self.lock()?;
        let s = g
            .state()
            .ok_or_else(|| PyRuntimeError::new_err("no state yet: call run() or step() first"))?;
        Ok(pick(s).to_vec().into_pyarray(py).unbind())
    }
}

#[pymethods]
impl PySimulation {
    #[new]
    fn new(scene: &PyScene) -> Self {
        PySimulation {
            kind: scene.kind.clone(),
            state: Mutex::new(SimState::default()),
            cancel: Default::default(),
        }
    }

    /// Runs the scene to its end with the GIL released, writing into `out` what the CLI
    /// writes (a temporary directory, removed afterwards, when `out` is None: then only
    /// the history is kept, in memory). `fields` / `plots` override the scene's output
    /// options when given. On a simulation already stepped (or a run interrupted) it
    /// goes on from the step reached, into the directory that run opened.
    /// `progress(step, total)` is called at most 1000 times; Ctrl-C (or an exception in
    /// `progress`, or `cancel()`) stops the run after the current step, leaves the files
    /// so far readable and raises: the state reached is kept, and `step()` or `run()`
    /// goes on from it.
    #[pyo3(signature = (out=None, progress=None, fields=None, plots=None))]
    fn run(
        &self,
        py: Python<'_>,
        out: Option<PathBuf>,
        progress: Option<Py<PyAny>>,
        fields: Option<bool>,
        plots: Option<bool>,
    ) -> PyResult<()> {
        let mut g = self.lock()?;
        if g.finished.is_some() {
            return Err(PyRuntimeError::new_err(
                "this simulation has run to its end; make a new one with scene.simulation()",
            ));
        }
        let mut prog = PyProgress {
            callback: progress,
            error: None,
            cancel: self.cancel.clone(),
            started: None,
            signals: true,
        };
        let _flush = signorini::linalg::FlushGuard::for_run();
        match (&g.session, &g.dir) {
            (None, _) => self.open(py, &mut g, out, fields, plots)?,
            (Some(_), Some(dir)) => {
                let same = |a: &Path, b: &Path| {
                    std::fs::canonicalize(a).ok() == std::fs::canonicalize(b).ok()
                };
                let opened_by = if g.temporary {
                    "in memory".to_string()
                } else {
                    format!("into {}", dir.display())
                };
                if out.as_deref().is_some_and(|o| g.temporary || !same(o, dir)) {
                    return Err(PyRuntimeError::new_err(format!(
                        "run(out=…): this simulation's run is already open {opened_by} (by \
                         step(), start() or an interrupted run()); run() goes on there: call \
                         it without `out`, or make a new simulation"
                    )));
                }
                if fields.is_some() || plots.is_some() {
                    return Err(PyRuntimeError::new_err(format!(
                        "run(fields=…, plots=…): this simulation's run is already open \
                         {opened_by}, with its outputs chosen; give them to start() or to \
                         the first run()"
                    )));
                }
            }
            (Some(_), None) => unreachable!("a session has a directory"),
        }
        let session = g.session.as_mut().expect("opened above");
        // to the run's end (an accuracy run's step count is not known before)
        let result = py.detach(|| session.advance(usize::MAX, &mut prog));
        if let Err(e) = result {
            // the files so far readable; the state kept for step() or run() to go on
            let synced = session.sync();
            return Err(match (e, prog.error.take()) {
                (Error::Interrupted { .. }, Some(pe)) => pe,
                (Error::Interrupted { step, time }, None) => {
                    self.cancel
                        .store(false, std::sync::atomic::Ordering::Relaxed);
                    Cancelled::new_err(format!(
                        "run() cancelled after step {step} (t = {time:e} s): the state \
                         reached is kept, and step() or run() goes on from it{}",
                        if g.temporary {
                            String::new()
                        } else {
                            format!(
                                "; the history and frames so far are in {}",
                                g.dir.as_ref().expect("open").display()
                            )
                        }
                    ))
                }
                (e, _) => py_err(synced.err().unwrap_or(e)),
            });
        }
        g.finish().map_err(py_err)
    }

    /// Opens the run without taking a step: into `out` (the CLI's files, frames and
    /// plots as the scene asks unless `fields` / `plots` say otherwise), or in memory
    /// (the history alone) when `out` is None, which is what the first `step()` does by
    /// itself. Refused once the run is open.
    #[pyo3(signature = (out=None, fields=None, plots=None))]
    fn start(
        &self,
        py: Python<'_>,
        out: Option<PathBuf>,
        fields: Option<bool>,
        plots: Option<bool>,
    ) -> PyResult<()> {
        let mut g = self.lock()?;
        if g.session.is_some() || g.finished.is_some() {
            return Err(PyRuntimeError::new_err(
                "start(): this simulation's run is already open (by step(), start() or run())",
            ));
        }
        let _flush = signorini::linalg::FlushGuard::for_run();
        self.open(py, &mut g, out, fields, plots)
    }

    /// Takes `n` steps (opening the run at the first call, in memory unless `start()`
    /// gave a directory) with the GIL released; returns the steps done. Every step goes
    /// through the run's checks and observers, as in `run()`: the history grows, and the
    /// step that reaches the scene's end finishes the run (the summary, the history read
    /// back). Stepping past the end is refused. `progress` is called as in `run()` (at
    /// most 1000 times over the whole run); without it a report costs nothing. The
    /// statistics stay in Rust until asked for (`stats_json`): a Python loop of
    /// `step(1)` pays no conversion per step.
    #[pyo3(signature = (n, progress=None))]
    fn step(&self, py: Python<'_>, n: usize, progress: Option<Py<PyAny>>) -> PyResult<usize> {
        let mut g = self.lock()?;
        // the run's subnormal mode while building and stepping; this thread's own
        // (Python's, numpy's) is put back on return. The pool's workers are set once,
        // with the integrator, and keep the mode (waking them costs more than a step)
        let _flush = if g.session.is_none() {
            signorini::linalg::FlushGuard::for_run()
        } else {
            signorini::linalg::FlushGuard::for_caller()
        };
        if let Some(s) = &g.finished {
            return match n {
                0 => Ok(s.step),
                _ => Err(BadInput::new_err(format!(
                    "step({n}): the scene makes {} steps and {} are done (the run has ended: \
                     its summary and history are formed)",
                    self.kind.steps(),
                    s.step
                ))),
            };
        }
        let mut prog = PyProgress {
            callback: progress,
            error: None,
            cancel: self.cancel.clone(),
            started: None,
            signals: false,
        };
        if g.session.is_none() {
            self.open(py, &mut g, None, None, None)?;
        }
        let SimState {
            session,
            step_seconds,
            ..
        } = &mut *g;
        let session = session.as_mut().expect("opened above");
        let (done, total) = session.progress();
        // an accuracy run (`time.accuracy`) takes steps until its end time
        if n > total - done.min(total) && !session.chooses_steps() {
            return Err(BadInput::new_err(format!(
                "step({n}): the scene makes {total} steps and {done} are done"
            )));
        }
        let mut taken = 0;
        while taken < n {
            // the GIL is taken back for Ctrl-C after at most 1000 steps and, once a step's
            // cost is known, after about INTERRUPT_EVERY seconds (hex_bars: 1–6 ms a step
            // made 1000-step chunks 0.9–5.9 s deaf to Ctrl-C); the first chunk of a new
            // simulation is one step, which measures it
            let by_time = if *step_seconds > 0.0 {
                ((INTERRUPT_EVERY / *step_seconds) as usize).clamp(1, 1000)
            } else {
                1
            };
            let chunk = (n - taken).min(by_time);
            let until = done + taken + chunk;
            let mut work = || session.advance(until, &mut prog);
            // releasing and taking back the GIL costs about a microsecond: worth it when
            // the chunk is expected to take longer than GIL_RELEASE_AFTER
            let t0 = std::time::Instant::now();
            let r = if *step_seconds == 0.0 || chunk as f64 * *step_seconds > GIL_RELEASE_AFTER {
                py.detach(work)
            } else {
                work()
            };
            *step_seconds = t0.elapsed().as_secs_f64() / chunk as f64;
            match r {
                Ok(()) => {}
                Err(Error::Interrupted { step, time }) => {
                    if let Some(e) = prog.error.take() {
                        // an exception in the callback (or Ctrl-C seen by it)
                        return Err(e);
                    }
                    self.cancel
                        .store(false, std::sync::atomic::Ordering::Relaxed);
                    return Err(Cancelled::new_err(format!(
                        "step() cancelled after step {step} (t = {time:e} s): the state \
                         reached is kept, and step() goes on from it"
                    )));
                }
                Err(e) => {
                    // the history so far readable
                    let synced = session.sync();
                    return Err(py_err(synced.err().unwrap_or(e)));
                }
            }
            taken += chunk;
            py.check_signals()?;
            if session.is_done() {
                break;
            }
        }
        let done = session.progress().0;
        if session.is_done() {
            g.finish().map_err(py_err)?;
        }
        Ok(done)
    }

    /// The mesh of the model and where each nodal displacement component is in `q`
    /// (module doc of the Python `Mesh`); builds the model when nothing has yet (the
    /// first `step()` then integrates it without building it again).
    fn mesh(&self, py: Python<'_>) -> PyResult<MeshArrays> {
        let mut g = self.lock()?;
        if g.geometry.is_none() {
            if g.session.is_none() && g.finished.is_none() {
                self.ensure_model(py, &mut g)?;
            } else {
                // a finished run's model is gone: its geometry is built again
                let kind = self.kind.clone();
                let built = interruptible(
                    py,
                    &self.cancel,
                    "building the model",
                    move || kind.build(),
                    drop,
                )?
                .map_err(py_err)?;
                g.geometry = Some(std::sync::Arc::new(built.0.geometry));
            }
        }
        let geo = g.geometry.clone().expect("built");
        drop(g);
        mesh_arrays(py, &geo, self.kind.body_names())
    }

    /// Each body's mass (kg), centre of mass (m), linear momentum (kg·m/s) and angular
    /// momentum about its centre (kg·m²/s) in the current state
    /// ([`signorini::model::BodyMeasures`]): after `step()`, of the integrator's state;
    /// after an in-memory `run()`, the summary's final values; before either, of the
    /// initial state (building the model as `mesh()` does).
    fn bodies(&self, py: Python<'_>) -> PyResult<Vec<BodyRow>> {
        let mut g = self.lock()?;
        if g.finished.is_some() {
            return final_bodies(g.summary.as_deref().unwrap_or_default());
        }
        self.ensure_model(py, &mut g)?;
        let geo = g.geometry.clone().expect("built with the model");
        let (sys, q, v) = match (g.integ(), &g.model) {
            (Some(i), _) => (i.system(), &i.state().q, &i.state().v),
            (None, Some((m, _))) => (&m.problem.system, &m.problem.q0, &m.problem.v0),
            (None, None) => unreachable!("built above"),
        };
        Ok(measure_bodies(&geo, &sys.mass, q, v))
    }

    /// Asks the `step()` or `run()` running (or the next one) to stop after its step:
    /// no lock, so callable while another thread holds the simulation.
    fn cancel(&self) {
        self.cancel
            .store(true, std::sync::atomic::Ordering::Relaxed);
    }

    /// Replaces the displacements `q` and/or velocities `v` (one value per dof, finite):
    /// before the first step, the model's initial state (building it as `mesh()` does:
    /// `Model::set_state`); after, the integrator's state, whose gaps, Jacobians and
    /// Delassus data are evaluated again at the new `q` (`Session::set_state`). A new `q`
    /// passes the scene's own starting-gap rule (no contact node deeper inside its
    /// obstacle or the other body than its contact's `overlap_tolerance`).
    #[pyo3(signature = (q=None, v=None))]
    fn set_state(&self, py: Python<'_>, q: Option<Vec<f64>>, v: Option<Vec<f64>>) -> PyResult<()> {
        let mut g = self.lock()?;
        if g.finished.is_some() {
            return Err(PyRuntimeError::new_err(
                "this simulation has finished its run: make a new one with scene.simulation()",
            ));
        }
        self.ensure_model(py, &mut g)?;
        let n = match (g.integ(), &g.model) {
            (Some(i), _) => i.state().q.len(),
            (None, Some((m, _))) => m.problem.q0.len(),
            (None, None) => unreachable!("built above"),
        };
        for (name, x) in [("q", &q), ("v", &v)] {
            if let Some(x) = x {
                check_vector(
                    name,
                    x.iter().copied(),
                    (n, "one per dof"),
                    "a state is finite",
                )?;
            }
        }
        // the library's rule, the scene's own start's: the starting gaps within each
        // contact's `overlap_tolerance`
        let st = &mut *g;
        match (&mut st.session, &mut st.model) {
            (Some(session), _) => session.set_state(q, v),
            (None, Some((m, _))) => m.set_state(q, v),
            (None, None) => unreachable!("built above"),
        }
        .map_err(py_err)
    }

    /// Nodal displacements `q` (m), one per dof (owned copy).
    #[getter]
    fn q(&self, py: Python<'_>) -> PyResult<Py<PyArray1<f64>>> {
        self.vector(py, |s| &s.q)
    }
    /// Nodal velocities `v` (m/s), one per dof (owned copy).
    #[getter]
    fn v(&self, py: Python<'_>) -> PyResult<Py<PyArray1<f64>>> {
        self.vector(py, |s| &s.v)
    }
    /// Normal impulses `P_N` of the last step (N·s), one per contact (owned copy).
    #[getter]
    fn impulses(&self, py: Python<'_>) -> PyResult<Py<PyArray1<f64>>> {
        self.vector(py, |s| &s.impulse)
    }
    /// Gaps `g(q)` (m), one per contact (owned copy).
    #[getter]
    fn gaps(&self, py: Python<'_>) -> PyResult<Py<PyArray1<f64>>> {
        self.vector(py, |s| &s.gap)
    }
    /// Normal relative velocities `U_N` (m/s), one per contact (owned copy).
    #[getter]
    fn contact_velocities(&self, py: Python<'_>) -> PyResult<Py<PyArray1<f64>>> {
        self.vector(py, |s| &s.local_velocity)
    }
    /// Tangential (friction) impulses `P_T` of the last step (N·s), `tangent_dim` per
    /// contact, contact after contact (owned copy; empty without friction).
    #[getter]
    fn tangent_impulses(&self, py: Python<'_>) -> PyResult<Py<PyArray1<f64>>> {
        self.vector(py, |s| &s.tangent_impulse)
    }
    /// Tangential (slip) velocities `U_T` (m/s), `tangent_dim` per contact.
    #[getter]
    fn slip_velocities(&self, py: Python<'_>) -> PyResult<Py<PyArray1<f64>>> {
        self.vector(py, |s| &s.tangent_velocity)
    }
    /// Tangents per contact: 0 without friction, 1 in 2-D, 2 in 3-D (0 before a state).
    #[getter]
    fn tangent_dim(&self) -> PyResult<usize> {
        Ok(self.lock()?.state().map_or(0, |s| s.tangent_dim))
    }
    /// Open / stick / slip per contact (frictional scenes; empty otherwise).
    #[getter]
    fn statuses(&self) -> PyResult<Vec<String>> {
        let g = self.lock()?;
        let s = g
            .state()
            .ok_or_else(|| PyRuntimeError::new_err("no state yet: call run() or step() first"))?;
        Ok(s.status
            .iter()
            .map(|c| format!("{c:?}").to_lowercase())
            .collect())
    }
    /// Time of the state (s).
    #[getter]
    fn time(&self) -> PyResult<f64> {
        Ok(self.lock()?.state().map_or(0.0, |s| s.time))
    }
    /// Steps done.
    #[getter]
    fn steps_done(&self) -> PyResult<usize> {
        Ok(self.lock()?.state().map_or(0, |s| s.step))
    }
    /// Steps of the whole run (of a run that chooses its steps, those at its largest
    /// step: the fewest it can take).
    #[getter]
    fn steps_total(&self) -> usize {
        self.kind.steps()
    }
    /// The last step's statistics as JSON (`None` before a step).
    #[getter]
    fn stats_json(&self) -> PyResult<Option<String>> {
        let g = self.lock()?;
        let last = g
            .session
            .as_ref()
            .and_then(|s| s.last_stats().copied())
            .or(g.last);
        Ok(last.map(|s| serde_json::to_string(&s).expect("statistics serialize")))
    }
    /// The summary as JSON (after `run()`).
    #[getter]
    fn summary_json(&self) -> PyResult<Option<String>> {
        Ok(self.lock()?.summary.clone())
    }
    /// The output directory of `run(out=…)` or `start(out=…)` (`None` in memory).
    #[getter]
    fn out(&self) -> PyResult<Option<PathBuf>> {
        let g = self.lock()?;
        Ok(g.out.clone().or(g.dir.clone().filter(|_| !g.temporary)))
    }
    /// The history, `[(column, array)]` in the CSV's order: the whole run's once it has
    /// ended, the rows so far while `step()` goes through it (read back from the run's
    /// directory, its writers flushed first); `None` before the first step.
    fn history_columns(&self, py: Python<'_>) -> PyResult<Option<NamedArrays>> {
        let mut g = self.lock()?;
        let st = &mut *g;
        let so_far;
        let h = match (&mut st.session, &st.history) {
            (Some(s), _) => {
                // the rows so far, read from the file being written (no copy of it)
                so_far = py
                    .detach(|| match s.history_so_far()? {
                        Some(part) => signorini::io::read_history(&part).map(|h| h.columns()),
                        None => Ok(Vec::new()),
                    })
                    .map_err(py_err)?;
                &so_far
            }
            (None, Some(h)) => h,
            _ => return Ok(None),
        };
        Ok(Some(named_arrays(py, h)))
    }
}
