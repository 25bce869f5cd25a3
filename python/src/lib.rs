//! `signorini._signorini`: the Rust side of the Python package (issue 20). It holds no
//! solver of its own: scenes are the library's `Scene` / `BarScene`, runs go through
//! the library's `app::Session` (the CLI's code path, so a run writes the CLI's files
//! byte for byte), and `step(n)` advances the same session `n` steps at a time: the same
//! checks, history and summary as `run()`, and one simulation may mix both.
//! The pure-Python layer (`signorini/__init__.py`) turns keyword arguments into scene
//! overrides and JSON into dicts; this module moves arrays and releases the GIL.
//!
//! Arrays handed to Python are owned copies, not views: the integrator overwrites its
//! state buffers at every step and owns them for as long as the simulation lives, so a
//! view would change under the caller's feet (and outlive its buffer if the simulation
//! were dropped first). A copy costs one pass over `n` values, negligible next to a step.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use numpy::{IntoPyArray, PyArray1, PyArrayMethods};
use pyo3::exceptions::{PyException, PyRuntimeError};
use pyo3::prelude::*;

use signorini::Error;
use signorini::app::Session;
use signorini::integrators::{Integrator, State, StepStats};
use signorini::io::OutputOptions;
use signorini::run::{Output, Progress};
use signorini::scene::bar::BarScene;
use signorini::scene::file::Scene as FileScene;

pyo3::create_exception!(
    _signorini,
    SignoriniError,
    PyException,
    "Base class of signorini's errors."
);
pyo3::create_exception!(
    _signorini,
    BadInput,
    SignoriniError,
    "Bad input (the CLI's exit code 2): the message names the file, the key path or line, the value and what was expected."
);
pyo3::create_exception!(
    _signorini,
    Cancelled,
    SignoriniError,
    "A step() or run() stopped by Simulation.cancel() (from another thread)."
);
pyo3::create_exception!(
    _signorini,
    RunFailed,
    SignoriniError,
    "A run that failed (the CLI's exit code 1): a cap hit, a non-finite state, an output that could not be written."
);

fn py_err(e: Error) -> PyErr {
    match e.exit_code() {
        2 => BadInput::new_err(e.to_string()),
        _ => RunFailed::new_err(e.to_string()),
    }
}

/// Checks that the argument `name` holds `n` values (`per` says what each is for) and
/// that they are finite (`why`), in Python terms.
fn check_vector(
    name: &str,
    x: impl ExactSizeIterator<Item = f64>,
    (n, per): (usize, &str),
    why: &str,
) -> PyResult<()> {
    if x.len() != n {
        return Err(BadInput::new_err(format!(
            "invalid value for `{name}`: {} values (expected {per}: {n})",
            x.len()
        )));
    }
    for (i, y) in x.enumerate() {
        if !y.is_finite() {
            return Err(BadInput::new_err(format!(
                "invalid value for `{name}`: entry {i} is {y} ({why})"
            )));
        }
    }
    Ok(())
}

/// A built model, with its report when it comes from a scene file.
type Built = (
    signorini::scene::Model,
    Option<signorini::scene::file::ModelReport>,
);

/// A scene file's scene, or the built-in impacting bar (its own parameter set).
#[derive(Clone)]
enum Kind {
    File(Box<FileScene>),
    Bar(Box<BarScene>),
}

impl Kind {
    fn steps(&self) -> usize {
        match self {
            Kind::File(s) => s.steps(),
            Kind::Bar(b) => b.steps(),
        }
    }

    /// The model (mesh, assembly, contacts), as a run builds it, with a scene file's
    /// report.
    fn build(&self) -> Result<Built, Error> {
        match self {
            Kind::File(s) => s.build().map(|(m, r)| (m, Some(r))),
            Kind::Bar(b) => Ok((b.build()?, None)),
        }
    }

    /// Opens the run (a [`Session`]) into `out`, from `built` where given.
    fn session(
        &self,
        built: Option<Built>,
        out: Output,
        progress: &mut dyn Progress,
    ) -> Result<Session, Error> {
        match self {
            Kind::File(s) => {
                let built = built.map(|(m, r)| (m, r.expect("a scene file's model has a report")));
                Session::scene(s, built, Some(out), progress, None)
            }
            Kind::Bar(b) => Session::bar(b, built.map(|b| b.0), Some(out), progress, None),
        }
    }

    /// The scene's output options.
    fn output(&self) -> OutputOptions {
        match self {
            Kind::File(s) => s.output.clone(),
            Kind::Bar(_) => OutputOptions::default(),
        }
    }

    /// The bodies' names, in the order of the model's bodies.
    fn body_names(&self) -> Vec<String> {
        match self {
            Kind::File(s) => s.bodies.iter().map(|b| b.name.clone()).collect(),
            Kind::Bar(_) => vec!["bar".to_string()],
        }
    }
}

/// The arrays of [`PySimulation::mesh`]: points `(N, 3)`, node ids `(N,)`, the body of
/// each point `(N,)` (−1 for a point no cell uses), cells as `(kind, body, nodes)`, the
/// displacement components per point and the dof map `(N, dim)` (−1: fixed or
/// prescribed), the bodies' names, and the contacts as `(point, body, target, entry)`.
type MeshArrays = (
    Py<numpy::PyArray2<f64>>,
    Py<PyArray1<u64>>,
    Py<PyArray1<i64>>,
    Vec<(String, usize, Vec<usize>)>,
    usize,
    Py<numpy::PyArray2<i64>>,
    Vec<String>,
    Vec<(usize, usize, String, usize)>,
);

/// One body's mass, centre, momentum and angular momentum (`_Simulation.bodies`).
type BodyRow = (f64, [f64; 3], [f64; 3], [f64; 3]);

/// A validated scene (`signorini.Scene` wraps it).
#[pyclass(module = "signorini._signorini", name = "_Scene", frozen)]
struct PyScene {
    kind: Kind,
}

fn file_scene(s: FileScene) -> PyScene {
    PyScene {
        kind: Kind::File(Box::new(s)),
    }
}

#[pymethods]
impl PyScene {
    /// A scene file with `KEY=VALUE` overrides (`signorini run FILE --set …`).
    #[staticmethod]
    fn from_file(path: PathBuf, set: Vec<String>) -> PyResult<Self> {
        FileScene::from_file_with(&path, &set)
            .map(file_scene)
            .map_err(py_err)
    }

    /// Scene TOML text; relative mesh paths start from `base_dir` (default: the
    /// working directory).
    #[staticmethod]
    #[pyo3(signature = (text, set, base_dir=None))]
    fn from_text(text: &str, set: Vec<String>, base_dir: Option<PathBuf>) -> PyResult<Self> {
        let mut s = FileScene::from_text_with(text, &set).map_err(py_err)?;
        if let Some(d) = base_dir {
            s.base_dir = d;
        }
        Ok(file_scene(s))
    }

    /// A scene given as JSON (the Python dict of the TOML tables): converted to TOML
    /// and read as a scene file would be, so errors name the same key paths.
    #[staticmethod]
    #[pyo3(signature = (json, set, base_dir=None))]
    fn from_json(json: &str, set: Vec<String>, base_dir: Option<PathBuf>) -> PyResult<Self> {
        let mut value: serde_json::Value = serde_json::from_str(json)
            .map_err(|e| BadInput::new_err(format!("scene dict: {e}")))?;
        strip_nulls(&mut value);
        let table = toml::Table::try_from(value).map_err(|e| {
            BadInput::new_err(format!(
                "scene dict: {e} (expected the tables of a scene file)"
            ))
        })?;
        let text =
            toml::to_string(&table).map_err(|e| BadInput::new_err(format!("scene dict: {e}")))?;
        Self::from_text(&text, set, base_dir)
    }

    /// The built-in impacting bar from its parameters as JSON (the reference bar for
    /// `{}`); unknown names are refused with the name.
    #[staticmethod]
    fn bar(json: &str) -> PyResult<Self> {
        let mut de = serde_json::Deserializer::from_str(json);
        let b: BarScene = serde_path_to_error_free(&mut de)?;
        b.validate().map_err(py_err)?;
        Ok(PyScene {
            kind: Kind::Bar(Box::new(b)),
        })
    }

    /// One of the paper's academic examples (bouncing-ball, oscillator, rocking-block,
    /// slider-crank).
    #[staticmethod]
    fn example(name: &str) -> PyResult<Self> {
        signorini::scene::builtin_scene(name)
            .map(file_scene)
            .map_err(py_err)
    }

    /// This scene with overrides (file scenes; the bar takes new parameters instead).
    fn with_overrides(&self, set: Vec<String>) -> PyResult<Self> {
        match &self.kind {
            Kind::File(s) => s.with_overrides(&set).map(file_scene).map_err(py_err),
            Kind::Bar(_) => Err(BadInput::new_err(
                "the built-in bar takes parameters, not scene keys",
            )),
        }
    }

    /// Whether this is the built-in bar.
    fn is_bar(&self) -> bool {
        matches!(self.kind, Kind::Bar(_))
    }

    /// The scene as JSON (file scenes: the TOML tables; the bar: its parameters);
    /// absent optional keys are left out, as in a scene file.
    fn to_json(&self) -> String {
        let mut v = match &self.kind {
            Kind::File(s) => serde_json::to_value(s.as_ref()),
            Kind::Bar(b) => serde_json::to_value(b),
        }
        .expect("scenes serialize");
        strip_nulls(&mut v);
        v.to_string()
    }

    /// The directory relative mesh paths start from (file scenes; None for the bar).
    fn base_dir(&self) -> Option<PathBuf> {
        match &self.kind {
            Kind::File(s) => Some(s.base_dir.clone()),
            Kind::Bar(_) => None,
        }
    }

    /// The scene as TOML text.
    fn to_toml(&self) -> PyResult<String> {
        match &self.kind {
            Kind::File(s) => toml::to_string(s.as_ref()),
            Kind::Bar(b) => toml::to_string(b),
        }
        .map_err(|e| PyRuntimeError::new_err(format!("the scene does not serialize: {e}")))
    }

    /// Steps of a run.
    fn steps(&self) -> usize {
        self.kind.steps()
    }

    /// What `signorini check` reports, as JSON.
    fn check(&self) -> PyResult<String> {
        let c = match &self.kind {
            Kind::File(s) => s.check(),
            Kind::Bar(b) => b.check(),
        }
        .map_err(py_err)?;
        Ok(serde_json::to_string(&c).expect("the report serializes"))
    }
}

/// Drops `null` values (TOML has none: an absent key means the default; Python's
/// `None` reads the same way).
fn strip_nulls(v: &mut serde_json::Value) {
    match v {
        serde_json::Value::Object(m) => {
            m.retain(|_, x| !x.is_null());
            m.values_mut().for_each(strip_nulls);
        }
        serde_json::Value::Array(a) => a.iter_mut().for_each(strip_nulls),
        _ => {}
    }
}

/// The bar's parameters from JSON, an error naming the parameter by its key path in
/// Python's spelling (`scheme.kind`, `dt`) instead of a line and column of the JSON text.
fn serde_path_to_error_free<T: serde::de::DeserializeOwned>(
    de: &mut serde_json::Deserializer<serde_json::de::StrRead<'_>>,
) -> PyResult<T> {
    serde_path_to_error::deserialize(de).map_err(|e| {
        let path = e.path().to_string();
        let inner = e.inner().to_string();
        // serde_json's message ends with the position in the JSON text, which the
        // caller never wrote
        let msg = inner
            .rsplit_once(" at line ")
            .map_or(inner.as_str(), |(m, _)| m)
            .replace("expected f64", "expected a number")
            .replace("expected usize", "expected a whole number ≥ 0");
        if path == "." {
            BadInput::new_err(format!("Scene.bar: {msg}"))
        } else {
            BadInput::new_err(format!("invalid value for `{path}`: {msg}"))
        }
    })
}

/// Calls the Python progress callback and watches for Ctrl-C while the run holds no GIL.
struct PyProgress {
    callback: Option<Py<PyAny>>,
    error: Option<PyErr>,
    /// The simulation's `cancel()` flag, read at every step.
    cancel: std::sync::Arc<std::sync::atomic::AtomicBool>,
    /// When the first step began, and its index (the rate and the ETA count from there).
    started: Option<(std::time::Instant, usize)>,
    /// Look for Ctrl-C at each report (`run()`); `step(n)` looks between its chunks
    /// instead, so that without a callback a report costs nothing.
    signals: bool,
}

impl PyProgress {
    /// `callback(step, total, info)`: `info` the simulated time, the wall time since
    /// the first step, the steps per second, the ETA and the step's statistics.
    fn call(&mut self, step: usize, total: usize, time: f64, st: Option<&StepStats>) {
        if self.error.is_some() || (self.callback.is_none() && !self.signals) {
            return;
        }
        let (t0, first) = *self
            .started
            .get_or_insert((std::time::Instant::now(), step.saturating_sub(1)));
        let elapsed = t0.elapsed().as_secs_f64();
        let done = step.saturating_sub(first) as f64;
        let rate = if elapsed > 0.0 { done / elapsed } else { 0.0 };
        let eta = match total.saturating_sub(step) {
            0 => 0.0,
            left if rate > 0.0 => left as f64 / rate,
            _ => f64::NAN,
        };
        Python::attach(|py| {
            if let Some(cb) = &self.callback {
                let info = pyo3::types::PyDict::new(py);
                let filled = (|| -> PyResult<()> {
                    info.set_item("time", time)?;
                    info.set_item("elapsed", elapsed)?;
                    info.set_item("steps_per_second", rate)?;
                    info.set_item("eta", eta)?;
                    if let Some(st) = st {
                        info.set_item("newton_iterations", st.newton_iterations)?;
                        info.set_item("projection_iterations", st.projection_iterations)?;
                        info.set_item("index_set_iterations", st.index_set_iterations)?;
                        info.set_item("lcp_iterations", st.lcp_iterations)?;
                        info.set_item("max_violation", st.max_violation)?;
                        info.set_item("caps_hit", st.caps_hit)?;
                    }
                    Ok(())
                })();
                if let Err(e) = filled.and_then(|_| cb.call1(py, (step, total, info)).map(|_| ())) {
                    self.error = Some(e);
                    return;
                }
            }
            if let Err(e) = py.check_signals() {
                self.error = Some(e);
            }
        });
    }
}

impl Progress for PyProgress {
    fn start(&mut self, _total: usize) {
        self.started = Some((std::time::Instant::now(), 0));
    }
    fn update(&mut self, step: usize, total: usize) {
        self.call(step, total, f64::NAN, None);
    }
    fn update_with(&mut self, step: usize, total: usize, time: f64, stats: &StepStats) {
        self.call(step, total, time, Some(stats));
    }
    fn cancelled(&mut self) -> bool {
        self.error.is_some() || self.cancel.load(std::sync::atomic::Ordering::Relaxed)
    }
}

/// History columns handed to Python: `(name, array)` in the CSV's order.
type NamedArrays = Vec<(String, Py<PyArray1<f64>>)>;

/// A history read back from `history.csv`: column names and values by column.
type Columns = Vec<(String, Vec<f64>)>;

fn read_history(dir: &Path) -> Result<Columns, Error> {
    let path = dir.join("history.csv");
    let text = std::fs::read_to_string(&path).map_err(|e| Error::io(&path, e))?;
    let mut lines = text.lines();
    let mut cols: Columns = lines
        .next()
        .unwrap_or_default()
        .split(',')
        .map(|h| (h.to_string(), Vec::new()))
        .collect();
    for (i, line) in lines.enumerate() {
        for (c, v) in cols.iter_mut().zip(line.split(',')) {
            // Rust writes the shortest representation that reads back to the same bits
            c.1.push(v.parse().map_err(|_| {
                Error::bad_file(
                    &path,
                    format!("line {}", i + 2),
                    format!("`{v}` is not a number"),
                )
            })?);
        }
    }
    Ok(cols)
}

/// `step(n)` holds the GIL for work expected to take less than this (s): a Python loop of
/// `step(1)` on a small model then pays no release and re-acquisition per call; anything
/// longer (a mesh's step, a long chunk) runs with the GIL released.
const GIL_RELEASE_AFTER: f64 = 50e-6;

/// `step(n)` checks for Ctrl-C about this often (s), whatever a step costs; model
/// building too.
const INTERRUPT_EVERY: f64 = 0.05;

/// Runs `work` (building a model, factoring `M̂`: seconds on a large mesh, with no place
/// to stop inside faer's factorization) on a thread of its own, the GIL released, while
/// this thread wakes every [`INTERRUPT_EVERY`] s for Ctrl-C and `cancel()`. Interrupted,
/// it returns at once; the abandoned work runs to its end in the background and its
/// result is handed to `abandon` there (which drops it, its memory then freed). The
/// thread sets the run's subnormal mode.
fn interruptible<T: Send + 'static>(
    py: Python<'_>,
    cancel: &std::sync::atomic::AtomicBool,
    what: &str,
    work: impl FnOnce() -> T + Send + 'static,
    abandon: impl FnOnce(T) + Send + 'static,
) -> PyResult<T> {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::Builder::new()
        .name("signorini-build".into())
        .spawn(move || {
            let _flush = signorini::linalg::FlushGuard::for_run();
            if let Err(std::sync::mpsc::SendError(v)) = tx.send(work()) {
                abandon(v);
            }
        })
        .map_err(|e| PyRuntimeError::new_err(format!("{what}: cannot start a thread: {e}")))?;
    let wait = std::time::Duration::from_secs_f64(INTERRUPT_EVERY);
    let mut rx = rx;
    loop {
        // the receiver is not Sync: it goes to the GIL-free wait and back
        let (r, back) = py.detach(move || (rx.recv_timeout(wait), rx));
        rx = back;
        match r {
            Ok(v) => return Ok(v),
            Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
                py.check_signals()?;
                if cancel.swap(false, std::sync::atomic::Ordering::Relaxed) {
                    return Err(Cancelled::new_err(format!(
                        "{what} cancelled: nothing was kept (the work started finishes in \
                         the background and is dropped)"
                    )));
                }
            }
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                return Err(PyRuntimeError::new_err(format!(
                    "{what}: the building thread stopped without a result (a panic: please \
                     report it)"
                )));
            }
        }
    }
}

#[derive(Default)]
struct SimState {
    /// The last chunk's seconds per step (0 before the first: the first chunk of a
    /// new simulation runs with the GIL released).
    step_seconds: f64,
    /// The run between its first step and its last: opened by the first `step()` or
    /// `run()`, advanced by both, finished (and dropped) at the last step.
    session: Option<Session>,
    /// Where the session writes: `run(out=…)`'s or `start(out=…)`'s directory, or a
    /// temporary one (`temporary`), removed once the history is read back at the end.
    dir: Option<PathBuf>,
    temporary: bool,
    /// The last step's statistics, kept when the session ends.
    last: Option<StepStats>,
    finished: Option<State>,
    summary: Option<String>,
    history: Option<Columns>,
    out: Option<PathBuf>,
    /// The model built for `mesh`, `bodies` or `set_state` before the first step, which
    /// the session then integrates instead of building it again.
    model: Option<Built>,
    /// The mesh and dof map of the built model.
    geometry: Option<std::sync::Arc<signorini::model::geometry::Geometry>>,
}

impl SimState {
    fn integ(&self) -> Option<&dyn Integrator> {
        self.session.as_ref().map(|s| s.integrator())
    }

    fn state(&self) -> Option<&State> {
        self.integ().map(|i| i.state()).or(self.finished.as_ref())
    }

    /// Ends the session advanced to its last step: the summary, the history read back
    /// (the temporary directory removed), the final state.
    fn finish(&mut self) -> Result<(), Error> {
        let session = self.session.take().expect("a session to finish");
        self.last = session.last_stats().copied().or(self.last);
        let r = session.finish()?;
        let dir = self.dir.take().expect("a session has a directory");
        let history = read_history(&dir)?;
        if self.temporary {
            let _ = std::fs::remove_dir_all(&dir);
        } else {
            self.out = Some(dir);
        }
        self.summary = Some(serde_json::to_string(&r.summary).expect("summaries serialize"));
        self.history = Some(history);
        self.finished = Some(r.state);
        Ok(())
    }
}

impl Drop for SimState {
    fn drop(&mut self) {
        // the session's writer threads end (and its lock goes) before the directory
        drop(self.session.take());
        if let (true, Some(dir)) = (self.temporary, self.dir.take()) {
            let _ = std::fs::remove_dir_all(dir);
        }
    }
}

/// A simulation of a scene (`signorini.Simulation` wraps it): `run()` for a whole run
/// written as the CLI writes it, or `step(n)` for step-by-step control.
#[pyclass(module = "signorini._signorini", name = "_Simulation", frozen)]
struct PySimulation {
    kind: Kind,
    state: Mutex<SimState>,
    /// Set by `cancel()` (no lock: the stepping thread holds `state`), read at every
    /// step, cleared when a call stops on it.
    cancel: std::sync::Arc<std::sync::atomic::AtomicBool>,
}

fn temp_dir() -> PathBuf {
    use std::sync::atomic::{AtomicUsize, Ordering};
    static COUNT: AtomicUsize = AtomicUsize::new(0);
    std::env::temp_dir().join(format!(
        "signorini-py-{}-{}",
        std::process::id(),
        COUNT.fetch_add(1, Ordering::Relaxed)
    ))
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
            move |r: Result<_, Error>| {
                // the session's writers stop and its lock goes before its directory
                drop(r);
                if temporary {
                    let _ = std::fs::remove_dir_all(&abandoned);
                }
            },
        )
        .inspect_err(|_| {
            if temporary {
                let _ = std::fs::remove_dir_all(&dir);
            }
        })?;
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
        let total = session.progress().1;
        let result = py.detach(|| session.advance(total, &mut prog));
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
        if n > total - done.min(total) {
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
        }
        let (done, total) = session.progress();
        if done == total {
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
        let n = geo.points.len();
        let dim = geo.dim;
        let points: Vec<f64> = geo.points.iter().flatten().copied().collect();
        let ids: Vec<u64> = if geo.node_ids.len() == n {
            geo.node_ids.clone()
        } else {
            (0..n as u64).collect()
        };
        let mut body = vec![-1_i64; n];
        let mut cells = Vec::with_capacity(geo.cells.len());
        for (kind, nodes, b) in &geo.cells {
            for &p in nodes {
                body[p] = *b as i64;
            }
            let name = match kind {
                signorini::model::geometry::GeomCell::Line => "line".to_string(),
                signorini::model::geometry::GeomCell::Solid(k) => k.name().to_string(),
            };
            cells.push((name, *b, nodes.clone()));
        }
        let dofs: Vec<i64> = (0..n * dim)
            .map(|i| {
                geo.dof_of
                    .get(i)
                    .copied()
                    .flatten()
                    .map_or(-1, |d| d as i64)
            })
            .collect();
        let to2 = |v: Vec<f64>, cols: usize| {
            numpy::PyArray1::from_vec(py, v)
                .reshape([n, cols])
                .map(|a| a.unbind())
        };
        let points = to2(points, 3)?;
        let dof_map = numpy::PyArray1::from_vec(py, dofs)
            .reshape([n, dim])?
            .unbind();
        Ok((
            points,
            ids.into_pyarray(py).unbind(),
            body.into_pyarray(py).unbind(),
            cells,
            dim,
            dof_map,
            self.kind.body_names(),
            geo.contacts
                .iter()
                .map(|c| (c.point, c.body, c.target.clone(), c.entry))
                .collect(),
        ))
    }

    /// Each body's mass (kg), centre of mass (m), linear momentum (kg·m/s) and angular
    /// momentum about its centre (kg·m²/s) in the current state
    /// ([`signorini::model::BodyMeasures`]): after `step()`, of the integrator's state;
    /// after an in-memory `run()`, the summary's final values; before either, of the
    /// initial state (building the model as `mesh()` does).
    fn bodies(&self, py: Python<'_>) -> PyResult<Vec<BodyRow>> {
        let mut g = self.lock()?;
        let row =
            |s: &signorini::model::BodyState| (s.mass, s.centre, s.momentum, s.angular_momentum);
        if g.finished.is_some() {
            let summary = g.summary.clone().unwrap_or_default();
            let v: serde_json::Value = serde_json::from_str(&summary).unwrap_or_default();
            let parse = |b: &serde_json::Value| -> Option<BodyRow> {
                let s: signorini::model::BodyState =
                    serde_json::from_value(b.get("final")?.clone()).ok()?;
                Some(row(&s))
            };
            return v
                .get("bodies")
                .and_then(|b| b.as_array())
                .map(|b| b.iter().filter_map(parse).collect())
                .ok_or_else(|| PyRuntimeError::new_err("the finished run recorded no bodies"));
        }
        self.ensure_model(py, &mut g)?;
        let geo = g.geometry.clone().expect("built with the model");
        let (sys, q, v) = match (g.integ(), &g.model) {
            (Some(i), _) => (i.system(), &i.state().q, &i.state().v),
            (None, Some((m, _))) => (&m.problem.system, &m.problem.q0, &m.problem.v0),
            (None, None) => unreachable!("built above"),
        };
        let Some(mut bm) = signorini::model::BodyMeasures::new(&geo, q.len()) else {
            return Ok(Vec::new());
        };
        let mut out = vec![signorini::model::BodyState::default(); bm.bodies()];
        bm.measure(&sys.mass, q, v, &mut out);
        Ok(out.iter().map(row).collect())
    }

    /// Asks the `step()` or `run()` running (or the next one) to stop after its step:
    /// no lock, so callable while another thread holds the simulation.
    fn cancel(&self) {
        self.cancel
            .store(true, std::sync::atomic::Ordering::Relaxed);
    }

    /// Replaces the displacements `q` and/or velocities `v` (one value per dof, finite):
    /// before the first step, the model's initial state (building it as `mesh()` does);
    /// after, the integrator's state, whose gaps, Jacobians and Delassus data are
    /// evaluated again at the new `q` (as a checkpoint's restore does).
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
        let st = &mut *g;
        match (&mut st.session, &mut st.model) {
            (Some(session), _) => {
                let integ = session.integrator_mut();
                let mut saved = integ.save();
                for (name, x) in [("q", q), ("v", v)] {
                    if let Some(x) = x {
                        saved
                            .vectors
                            .insert(name.to_string(), signorini::integrators::saved::Floats(x));
                    }
                }
                integ.restore(&saved).map_err(py_err)?;
                // the energy the edit gave or took is no work of the run's forces
                session.state_replaced();
            }
            (None, Some((m, _))) => {
                if let Some(q) = q {
                    m.problem.q0 = q;
                }
                if let Some(v) = v {
                    m.problem.v0 = v;
                }
            }
            (None, None) => unreachable!("built above"),
        }
        Ok(())
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
    /// Steps of the whole run.
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
        let h = match (&mut st.session, &st.dir, &st.history) {
            (Some(s), Some(dir), _) => {
                let dir = dir.clone();
                so_far = py
                    .detach(|| s.sync().and_then(|_| read_history(&dir)))
                    .map_err(py_err)?;
                &so_far
            }
            (None, _, Some(h)) => h,
            _ => return Ok(None),
        };
        Ok(Some(
            h.iter()
                .map(|(name, v)| (name.clone(), v.clone().into_pyarray(py).unbind()))
                .collect(),
        ))
    }
}

/// `(r, u, report as JSON)` of a solved friction problem.
type Solved = (Py<PyArray1<f64>>, Py<PyArray1<f64>>, String);
/// `(W, q, mu)` of a problem file.
type Arrays = (
    Py<numpy::PyArray2<f64>>,
    Py<PyArray1<f64>>,
    Py<PyArray1<f64>>,
);

/// `FrictionSolverKind` by its command-line name.
fn friction_kind(name: &str) -> PyResult<signorini::solvers::friction::FrictionSolverKind> {
    use signorini::solvers::friction::FrictionSolverKind as K;
    [K::Auto, K::Nsgs, K::Prox, K::Nsn, K::Newton]
        .into_iter()
        .find(|k| k.name() == name)
        .ok_or_else(|| {
            BadInput::new_err(format!(
                "invalid value for `solver`: {name:?} (expected auto, nsgs, prox, nsn or newton)"
            ))
        })
}

/// Solves a frictional contact problem as `signorini fclib` does: the parameters,
/// residual measure and report are the CLI's. Returns `(r, u, report as JSON)`.
fn fclib_run(
    py: Python<'_>,
    prob: &signorini::io::fclib::FrictionContactProblem,
    solver: &str,
    tol: Option<f64>,
    max_iter: Option<usize>,
    residual: &str,
    warm: bool,
) -> PyResult<Solved> {
    use signorini::solvers::friction::{FrictionParams, Measure};
    let defaults = FrictionParams::default();
    let params = FrictionParams {
        solver: friction_kind(solver)?,
        tol: tol.unwrap_or(signorini::io::fclib::DEFAULT_TOL),
        max_iterations: max_iter.unwrap_or(signorini::io::fclib::DEFAULT_MAX_ITERATIONS),
        ..defaults
    };
    params.validate_ranges("").map_err(py_err)?;
    let measure = Measure::parse(residual).ok_or_else(|| {
        BadInput::new_err(format!(
            "invalid value for `residual`: {residual:?} (expected siconos or velocity)"
        ))
    })?;
    let sol = py
        .detach(|| signorini::io::fclib::solve_repeated(prob, &params, measure, warm, 1))
        .map_err(py_err)?;
    let report = serde_json::json!({
        "residual": sol.residual,
        "measure": sol.measure.name(),
        "iterations": sol.iterations,
        "prox_iterations": sol.prox_iterations,
        "converged": sol.converged,
        "seconds": sol.seconds,
        "solver": sol.solver,
        "solved_by": sol.solved_by,
        "sparse_jacobian": sol.sparse_jacobian,
        "contacts": prob.contacts(),
        "dim": prob.dim,
        "form": prob.form,
        "asymmetry": prob.asymmetry,
    });
    Ok((
        sol.r.into_pyarray(py).unbind(),
        sol.u.into_pyarray(py).unbind(),
        report.to_string(),
    ))
}

/// `fclib.solve(W, q, mu, …)` on arrays: `W` is read as `n × n` (any memory order).
#[pyfunction]
#[pyo3(signature = (w, q, mu, solver, tol, max_iter, residual, r0=None))]
#[allow(clippy::too_many_arguments)]
fn fclib_solve_arrays(
    py: Python<'_>,
    w: numpy::PyReadonlyArray2<'_, f64>,
    q: numpy::PyReadonlyArray1<'_, f64>,
    mu: numpy::PyReadonlyArray1<'_, f64>,
    solver: &str,
    tol: Option<f64>,
    max_iter: Option<usize>,
    residual: &str,
    r0: Option<numpy::PyReadonlyArray1<'_, f64>>,
) -> PyResult<Solved> {
    let (w, q, mu) = (w.as_array(), q.as_array(), mu.as_array());
    let n = q.len();
    let (wr, wc) = w.dim();
    if wr != wc {
        return Err(BadInput::new_err(format!(
            "invalid value for `W`: shape ({wr}, {wc}) (expected a square matrix)"
        )));
    }
    if wr != n {
        return Err(BadInput::new_err(format!(
            "invalid value for `q`: {n} values (expected one per row of W: {wr})"
        )));
    }
    if let Some(r) = &r0 {
        let r = r.as_array();
        check_vector(
            "r0",
            r.iter().copied(),
            (n, "one per row of W"),
            "a warm start must be finite",
        )?;
    }
    if mu.is_empty() || n % mu.len() != 0 {
        return Err(BadInput::new_err(format!(
            "invalid value for `mu`: {} contacts for {n} rows (expected 2 or 3 rows per contact)",
            mu.len()
        )));
    }
    // column-major, as the solvers read W
    let wv: Vec<f64> = (0..n)
        .flat_map(|j| (0..n).map(move |i| (i, j)))
        .map(|(i, j)| w[(i, j)])
        .collect();
    let prob = signorini::io::fclib::FrictionContactProblem::from_arrays(
        n / mu.len(),
        wv,
        q.to_vec(),
        mu.to_vec(),
        r0.map(|r| r.as_array().to_vec()),
        "arrays",
    )
    .map_err(py_err)?;
    fclib_run(
        py,
        &prob,
        solver,
        tol,
        max_iter,
        residual,
        prob.guess.is_some(),
    )
}

/// `fclib.solve(path, …)`: a problem file as `signorini fclib` reads it (`.dat`; FCLIB
/// HDF5 where the package is built with the feature `hdf5`, as the wheels are).
#[pyfunction]
#[pyo3(signature = (path, solver, tol, max_iter, residual, warm))]
fn fclib_solve_file(
    py: Python<'_>,
    path: PathBuf,
    solver: &str,
    tol: Option<f64>,
    max_iter: Option<usize>,
    residual: &str,
    warm: bool,
) -> PyResult<Solved> {
    let prob = signorini::io::fclib::read(&path).map_err(py_err)?;
    fclib_run(py, &prob, solver, tol, max_iter, residual, warm)
}

/// `fclib.read(path)`: `(W, q, mu)` of a problem file (`W` as `n × n`).
#[pyfunction]
fn fclib_read(py: Python<'_>, path: PathBuf) -> PyResult<Arrays> {
    let prob = signorini::io::fclib::read(&path).map_err(py_err)?;
    let n = prob.rows();
    // W is column-major: its transpose's row-major layout
    let w = numpy::ndarray::Array2::from_shape_vec((n, n), prob.w)
        .expect("n × n values")
        .reversed_axes();
    Ok((
        w.into_pyarray(py).unbind(),
        prob.q.into_pyarray(py).unbind(),
        prob.mu.into_pyarray(py).unbind(),
    ))
}

/// The extension module.
#[pymodule]
fn _signorini(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add_class::<PyScene>()?;
    m.add_class::<PySimulation>()?;
    m.add_function(wrap_pyfunction!(fclib_solve_arrays, m)?)?;
    m.add_function(wrap_pyfunction!(fclib_solve_file, m)?)?;
    m.add_function(wrap_pyfunction!(fclib_read, m)?)?;
    m.add("SignoriniError", py.get_type::<SignoriniError>())?;
    m.add("BadInput", py.get_type::<BadInput>())?;
    m.add("RunFailed", py.get_type::<RunFailed>())?;
    m.add("Cancelled", py.get_type::<Cancelled>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    // built with HDF5 inside (the wheels): FCLIB `.hdf5` problems, VTKHDF frames and
    // HDF5 histories (`output.hdf5` of a scene)
    m.add("HDF5", cfg!(feature = "hdf5"))?;
    Ok(())
}
