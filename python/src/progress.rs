//! Progress, Ctrl-C and `cancel()` while the library works with the GIL released: the
//! Python callback behind the library's `Progress`, and model building on a thread of
//! its own that the caller can abandon.

use super::*;

/// Calls the Python progress callback and watches for Ctrl-C while the run holds no GIL.
pub(crate) struct PyProgress {
    pub(crate) callback: Option<Py<PyAny>>,
    pub(crate) error: Option<PyErr>,
    /// The simulation's `cancel()` flag, read at every step.
    pub(crate) cancel: std::sync::Arc<std::sync::atomic::AtomicBool>,
    /// When the first step began, and its index (the rate and the ETA count from there).
    pub(crate) started: Option<(std::time::Instant, usize)>,
    /// Look for Ctrl-C at each report (`run()`); `step(n)` looks between its chunks
    /// instead, so that without a callback a report costs nothing.
    pub(crate) signals: bool,
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

/// `step(n)` checks for Ctrl-C about this often (s), whatever a step costs; model
/// building too.
pub(crate) const INTERRUPT_EVERY: f64 = 0.05;

/// Runs `work` (building a model, factoring `M̂`: seconds on a large mesh, with no place
/// to stop inside faer's factorization) on a thread of its own, the GIL released, while
/// this thread wakes every [`INTERRUPT_EVERY`] s for Ctrl-C and `cancel()`. Interrupted,
/// it returns at once; the abandoned work runs to its end in the background and its
/// result is handed to `abandon` there (which drops it, its memory then freed). The
/// thread sets the run's subnormal mode.
pub(crate) fn interruptible<T: Send + 'static>(
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
