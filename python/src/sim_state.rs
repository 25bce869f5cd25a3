//! The state of a `_Simulation` between calls: the library's run in progress (an
//! `app::Session`) and where it writes, the model built before the first step, and,
//! once the run has ended, its final state, summary and history (read back with the
//! library's history reader, `signorini::io::read_history`); the temporary directory
//! of a run held in memory, removed with it.

use super::*;

/// A history read back from `history.csv`: column names and values by column.
pub(crate) type Columns = Vec<(String, Vec<f64>)>;

/// What a `_Simulation` holds between calls (module doc).
#[derive(Default)]
pub(crate) struct SimState {
    /// The last chunk's seconds per step (0 before the first: the first chunk of a
    /// new simulation runs with the GIL released).
    pub(crate) step_seconds: f64,
    /// The run between its first step and its last: opened by the first `step()` or
    /// `run()`, advanced by both, finished (and dropped) at the last step.
    pub(crate) session: Option<Session>,
    /// Where the session writes: `run(out=…)`'s or `start(out=…)`'s directory, or a
    /// temporary one (`temporary`), removed once the history is read back at the end.
    pub(crate) dir: Option<PathBuf>,
    pub(crate) temporary: bool,
    /// The last step's statistics, kept when the session ends.
    pub(crate) last: Option<StepStats>,
    pub(crate) finished: Option<State>,
    pub(crate) summary: Option<String>,
    pub(crate) history: Option<Columns>,
    pub(crate) out: Option<PathBuf>,
    /// The model built for `mesh`, `bodies` or `set_state` before the first step, which
    /// the session then integrates instead of building it again.
    pub(crate) model: Option<Built>,
    /// The mesh and dof map of the built model.
    pub(crate) geometry: Option<std::sync::Arc<signorini::model::geometry::Geometry>>,
}

impl SimState {
    /// The integrator of the open run.
    pub(crate) fn integ(&self) -> Option<&dyn Integrator> {
        self.session.as_ref().map(|s| s.integrator())
    }

    /// The state of the open run, or the final state of the finished one.
    pub(crate) fn state(&self) -> Option<&State> {
        self.integ().map(|i| i.state()).or(self.finished.as_ref())
    }

    /// Ends the session advanced to its last step: the summary, the history read back
    /// (the temporary directory removed), the final state.
    pub(crate) fn finish(&mut self) -> Result<(), Error> {
        let session = self.session.take().expect("a session to finish");
        self.last = session.last_stats().copied().or(self.last);
        let r = session.finish()?;
        let dir = self.dir.take().expect("a session has a directory");
        let history = signorini::io::read_history(&dir.join("history.csv"))?.columns();
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

/// A new temporary directory for a run held in memory (the history alone).
pub(crate) fn temp_dir() -> PathBuf {
    use std::sync::atomic::{AtomicUsize, Ordering};
    static COUNT: AtomicUsize = AtomicUsize::new(0);
    std::env::temp_dir().join(format!(
        "signorini-py-{}-{}",
        std::process::id(),
        COUNT.fetch_add(1, Ordering::Relaxed)
    ))
}
