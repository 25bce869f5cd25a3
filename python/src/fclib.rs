//! `fclib.solve` and `fclib.read`: one-step frictional contact problems from arrays or
//! FCLIB / Siconos files, solved by the library's friction solvers.

use super::*;

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
pub(crate) fn fclib_solve_arrays(
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
pub(crate) fn fclib_solve_file(
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
pub(crate) fn fclib_read(py: Python<'_>, path: PathBuf) -> PyResult<Arrays> {
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
