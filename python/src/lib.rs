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
//!
//! By role: `scene` (the scenes: `Kind`, `_Scene`), `tables` (a scene from a dict, no
//! text: its bodies' arrays set aside, measured against the memory limit and copied
//! flat), `toml_values` (the dict's other values as TOML values, and the messages'
//! words), `table_rows` (a table of numbers from an array or a list of rows, checked and
//! copied in one pass), `simulation` (`_Simulation`: the
//! session, its state, mesh, bodies and history), `sim_state` (what a `_Simulation` holds
//! between calls), `convert` (the mesh, bodies and history as the arrays Python receives),
//! `progress` (the Python callback,
//! Ctrl-C and `cancel()`, model building that can be abandoned), `fclib` (one-step
//! friction problems); here the exceptions, the argument checks and the module.

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

mod convert;
mod fclib;
mod progress;
mod scene;
mod sim_state;
mod simulation;
mod table_rows;
mod tables;
mod toml_values;

use fclib::{fclib_read, fclib_solve_arrays, fclib_solve_file};
use progress::{INTERRUPT_EVERY, PyProgress, interruptible};
use scene::{Built, Kind, PyScene};
use simulation::PySimulation;

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
