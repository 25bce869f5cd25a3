//! The history rows, written on the step loop's thread or on one of their own
//! ([`History`]), issue 19 §3.
//!
//! A history row costs the two energy quadratic forms `½ vᵀ M v` and `½ qᵀ K q`: on a
//! solid of 10⁴ dofs they read every entry of `M` and `K` (memory-bound, as long as a
//! good part of the step itself). From [`THREAD_MIN_DOFS`] dofs, on a machine with more
//! than one core, the loop copies the state into one of [`POOL`] preallocated buffers
//! (no allocation: the copies keep their capacity) and a thread computes the energies
//! and writes the row, reading the system through the integrator's shared
//! [`LinearSystem`]; the rows come out in order and with the same values as on the loop
//! thread (the same function on the same numbers). Written here rather than with rayon:
//! a row is one task that must run in order with the others and overlap the next steps,
//! which is a thread with a bounded queue, as the frame writer
//! ([`crate::io::frames::FrameStream`]) is.

use std::sync::Arc;
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};
use std::thread::JoinHandle;

use crate::error::Error;
use crate::integrators::{State, StepStats};
use crate::io::HistoryWriter;
use crate::model::{EnergyForms, LinearSystem};

/// Dofs from which the rows go to their own thread (below, the copy and the hand-over
/// cost about what the energies do: the bar's 1001 dofs take 0.1 µs per form with the
/// three-diagonal form).
pub const THREAD_MIN_DOFS: usize = 4096;

/// State copies in flight between the loop and the history thread.
pub const POOL: usize = 2;

/// What the loop hands the history thread.
#[allow(clippy::large_enum_variant)] // rows are the traffic; a flush is rare
enum Job {
    /// A row: the state after the step and its statistics.
    Row((State, StepStats)),
    /// Flush the writer and answer with its bytes and rows (a checkpoint's barrier).
    Flush,
}

/// A row's energies, leaving `M v` in `mv` where the per-body columns want it
/// (`mv` not empty): the same function on both paths, so the same bits.
fn energies(
    sys: &LinearSystem,
    forms: &EnergyForms,
    s: &State,
    scratch: &mut [f64],
    mv: &mut [f64],
) -> (f64, f64) {
    if mv.is_empty() {
        sys.energies_with(forms, s.time, &s.q, &s.v, scratch)
    } else {
        sys.energies_keeping_mv(forms, s.time, &s.q, &s.v, scratch, mv)
    }
}

/// The history thread.
pub struct HistoryThread {
    work: Option<SyncSender<Job>>,
    free: Receiver<(State, StepStats)>,
    flushed: Receiver<(u64, u64)>,
    thread: Option<JoinHandle<Result<HistoryWriter, Error>>>,
    spare: Vec<(State, StepStats)>,
}

impl HistoryThread {
    /// Moves `writer` to a new thread that forms each row's energies with `sys` and
    /// `forms`; `template` sizes the state copies (the run's initial state).
    pub fn spawn(
        mut writer: HistoryWriter,
        sys: Arc<LinearSystem>,
        forms: EnergyForms,
        template: &State,
    ) -> Self {
        let (work_tx, work_rx) = sync_channel::<Job>(POOL + 1);
        let (free_tx, free_rx) = sync_channel::<(State, StepStats)>(POOL);
        let (flushed_tx, flushed_rx) = sync_channel::<(u64, u64)>(1);
        for _ in 0..POOL {
            free_tx
                .send((template.clone(), StepStats::default()))
                .expect("the pool channel holds POOL buffers");
        }
        let mut scratch = vec![0.0; 2 * sys.prescribed_dofs()];
        // `M v` for the per-body columns, kept by the kinetic energy's pass over `M`
        let mut mv = vec![
            0.0;
            if writer.bodies() > 0 {
                template.v.len()
            } else {
                0
            }
        ];
        // the spawning run's subnormal mode (inherited on Linux; set, not assumed)
        let flush = crate::linalg::subnormals::current_thread();
        let thread = std::thread::Builder::new()
            .name("signorini-history".into())
            .spawn(move || {
                crate::linalg::subnormals::apply_to_current_thread(flush);
                for job in work_rx {
                    match job {
                        Job::Row(row) => {
                            let (s, st) = &row;
                            let (ke, pe) = energies(&sys, &forms, s, &mut scratch, &mut mv);
                            let mv = (!mv.is_empty()).then_some(&mv[..]);
                            writer.row((&sys.mass, mv), s, st, ke, pe)?;
                            // the run may have stopped listening (it failed): its report
                            let _ = free_tx.send(row);
                        }
                        Job::Flush => {
                            writer.flush()?;
                            let _ = flushed_tx.send((writer.bytes(), writer.rows()));
                        }
                    }
                }
                Ok(writer)
            })
            .expect("spawning the history thread");
        HistoryThread {
            work: Some(work_tx),
            free: free_rx,
            flushed: flushed_rx,
            thread: Some(thread),
            spare: Vec::with_capacity(POOL),
        }
    }

    /// Queues the row of `state` (waits for a free copy if all are in flight).
    pub fn push(&mut self, state: &State, stats: &StepStats) -> Result<(), Error> {
        let mut row = match self.spare.pop() {
            Some(r) => r,
            None => match self.free.recv() {
                Ok(r) => r,
                Err(_) => return Err(self.failure()),
            },
        };
        state.copy_to(&mut row.0);
        row.1 = *stats;
        let sent = self
            .work
            .as_ref()
            .is_some_and(|w| w.send(Job::Row(row)).is_ok());
        if sent { Ok(()) } else { Err(self.failure()) }
    }

    /// Waits until every queued row is written and flushed; returns the writer's bytes
    /// and rows.
    pub fn sync(&mut self) -> Result<(u64, u64), Error> {
        while self.spare.len() < POOL {
            match self.free.recv() {
                Ok(r) => self.spare.push(r),
                Err(_) => return Err(self.failure()),
            }
        }
        let asked = self
            .work
            .as_ref()
            .is_some_and(|w| w.send(Job::Flush).is_ok());
        match self.flushed.recv() {
            Ok(c) if asked => Ok(c),
            _ => Err(self.failure()),
        }
    }

    /// Waits until every queued row is written and returns the writer.
    pub fn finish(mut self) -> Result<HistoryWriter, Error> {
        drop(self.work.take());
        self.join()
    }

    fn join(&mut self) -> Result<HistoryWriter, Error> {
        match self.thread.take().map(|t| t.join()) {
            Some(Ok(r)) => r,
            Some(Err(p)) => std::panic::resume_unwind(p),
            None => Err(Error::Numerical(
                "the history thread already stopped".to_string(),
            )),
        }
    }

    /// The thread's error (it stopped early).
    fn failure(&mut self) -> Error {
        drop(self.work.take());
        match self.join() {
            Err(e) => e,
            Ok(_) => Error::Numerical("the history thread stopped without an error".into()),
        }
    }
}

impl Drop for HistoryThread {
    fn drop(&mut self) {
        drop(self.work.take());
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// The run's history: written on the loop thread, or by a [`HistoryThread`].
#[allow(clippy::large_enum_variant)] // one per run, never moved in the loop
pub enum History {
    /// Rows formed and written by the loop.
    Inline {
        /// The writer.
        writer: HistoryWriter,
        /// The energies' layouts of `M` and `K`.
        forms: EnergyForms,
        /// Scratch of the prescribed dofs' energy.
        scratch: Vec<f64>,
        /// `M v` for the per-body columns (empty without them).
        mv: Vec<f64>,
    },
    /// Rows formed and written by a thread of their own.
    Thread(HistoryThread),
}

impl History {
    /// Inline below [`THREAD_MIN_DOFS`] dofs or on one core, else on a thread. (Test
    /// hook: `SIGNORINI_HISTORY_THREAD_MIN_DOFS` replaces the threshold, so that the
    /// tests compare both paths on small scenes.)
    pub fn new(writer: HistoryWriter, sys: Arc<LinearSystem>, state: &State) -> History {
        let forms = sys.energy_forms();
        let cores = std::thread::available_parallelism().map_or(1, |c| c.get());
        let min = std::env::var("SIGNORINI_HISTORY_THREAD_MIN_DOFS")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(THREAD_MIN_DOFS);
        if state.q.len() >= min && cores > 1 {
            History::Thread(HistoryThread::spawn(writer, sys, forms, state))
        } else {
            History::Inline {
                mv: vec![
                    0.0;
                    if writer.bodies() > 0 {
                        state.v.len()
                    } else {
                        0
                    }
                ],
                writer,
                forms,
                scratch: vec![0.0; 2 * sys.prescribed_dofs()],
            }
        }
    }

    /// The row of `state` after a step of the system `sys`.
    pub fn row(
        &mut self,
        sys: &LinearSystem,
        state: &State,
        stats: &StepStats,
    ) -> Result<(), Error> {
        match self {
            History::Inline {
                writer,
                forms,
                scratch,
                mv,
            } => {
                let (ke, pe) = energies(sys, forms, state, scratch, mv);
                let mv = (!mv.is_empty()).then_some(&mv[..]);
                writer.row((&sys.mass, mv), state, stats, ke, pe)
            }
            History::Thread(t) => t.push(state, stats),
        }
    }

    /// Writes every row so far to the file; returns its bytes and rows (what a
    /// checkpoint records).
    pub fn sync(&mut self) -> Result<(u64, u64), Error> {
        match self {
            History::Inline { writer, .. } => {
                writer.flush()?;
                Ok((writer.bytes(), writer.rows()))
            }
            History::Thread(t) => t.sync(),
        }
    }

    /// Hands the rows written so far to the file without waiting for queued ones (before
    /// a frame, so that the history is not behind the frames on disk by more than the
    /// queue).
    pub fn flush(&mut self) -> Result<(), Error> {
        match self {
            History::Inline { writer, .. } => writer.flush(),
            History::Thread(_) => Ok(()),
        }
    }

    /// Writes the last rows and completes the file.
    pub fn finish(self) -> Result<(), Error> {
        match self {
            History::Inline { writer, .. } => writer.finish(),
            History::Thread(t) => t.finish()?.finish(),
        }
    }
}
