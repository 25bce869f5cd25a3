//! Frames written on a background thread: the step loop hands a [`Snapshot`] (a copy of
//! the state's vectors into reused buffers) to the writer thread and goes on stepping.

use super::*;

/// The part of a [`State`] a frame shows, copied out of the integrator so that the
/// frame can be encoded while the run goes on ([`FrameStream`]).
#[derive(Clone, Debug, Default)]
pub struct Snapshot {
    /// Step index.
    pub step: usize,
    /// Time (s).
    pub time: f64,
    /// Generalized coordinates (m).
    pub q: Vec<f64>,
    /// Generalized velocities (m/s).
    pub v: Vec<f64>,
    /// Contact force in dof space, `G P / h` (N).
    pub reaction: Vec<f64>,
    /// Gap per contact (m).
    pub gap: Vec<f64>,
    /// Open / stick / slip code per contact (frictional scenes; empty otherwise).
    pub status: Vec<u8>,
    /// Per contact, a dof of the other side of a contact between bodies (the master
    /// node that weighs most in the normal column), `usize::MAX` for an obstacle: the
    /// frames show the gap and the status on both sides.
    pub partner: Vec<usize>,
}

impl Snapshot {
    /// A snapshot for `n` dofs and `m` contacts (frictionless: no statuses).
    pub fn new(n: usize, m: usize) -> Self {
        Self::with_statuses(n, m, 0)
    }

    /// A snapshot for `n` dofs, `m` contacts and `statuses` contact statuses (`m` in a
    /// frictional scene, 0 otherwise).
    pub fn with_statuses(n: usize, m: usize, statuses: usize) -> Self {
        Snapshot {
            step: 0,
            time: 0.0,
            q: vec![0.0; n],
            v: vec![0.0; n],
            reaction: vec![0.0; n],
            gap: vec![0.0; m],
            status: vec![0; statuses],
            partner: vec![usize::MAX; m],
        }
    }

    /// Copies `state` in (same sizes; no allocation) and forms `G P / h` with `jac`.
    pub fn copy_from(&mut self, state: &State, jac: &ContactJacobian, h: f64) {
        self.step = state.step;
        self.time = state.time;
        self.q.copy_from_slice(&state.q);
        self.v.copy_from_slice(&state.v);
        self.gap.copy_from_slice(&state.gap);
        if self.status.len() == state.status.len() {
            for (o, s) in self.status.iter_mut().zip(&state.status) {
                *o = s.code();
            }
        }
        // the other side: the entry of the normal column most opposed to its largest one
        // (a master node's `−N_i n` against the slave's `n`)
        for (a, o) in self.partner.iter_mut().enumerate().take(jac.contacts()) {
            let (dofs, vals) = jac.col(jac.block(a).start);
            let r = vals
                .iter()
                .fold(0.0_f64, |m, &v| if v.abs() > m.abs() { v } else { m });
            *o = usize::MAX;
            let mut best = 0.0;
            for (&d, &v) in dofs.iter().zip(vals) {
                if v * r < best {
                    best = v * r;
                    *o = d;
                }
            }
        }
        self.reaction.iter_mut().for_each(|r| *r = 0.0);
        // every row of G: the normal and, with friction, the tangential impulses
        for (a, &p) in state.impulse_rows.iter().enumerate().take(jac.ncols()) {
            if p != 0.0 {
                jac.axpy(a, p / h, &mut self.reaction);
            }
        }
    }
}

/// Writes frames on a background thread, so that encoding and compressing a frame
/// overlaps the next steps instead of stopping them.
///
/// The run copies the state into one of a fixed pool of [`Snapshot`]s (allocated once)
/// and hands it over a bounded channel; the writer thread encodes it with its
/// [`FrameWriter`] and returns the snapshot to the pool. When every snapshot is in
/// flight the run waits (the time is reported), so memory stays bounded and frames are
/// written in order. A write error stops the thread; the run sees it at its next
/// frame or at [`FrameStream::finish`]. Frames already written stay valid: each
/// `.vtu` and the `.pvd` are still renamed into place one by one, and
/// [`FrameStream::sync`] leaves a `.pvd` listing every frame pushed.
///
/// std's channels and thread suffice here (a pool of two or three buffers and one
/// consumer); rayon's pool is for the assembly and the linear algebra.
pub struct FrameStream {
    pub(super) work: Option<std::sync::mpsc::SyncSender<Job>>,
    pub(super) free: std::sync::mpsc::Receiver<Snapshot>,
    /// The writer's answer to [`Job::Collection`].
    pub(super) listed: std::sync::mpsc::Receiver<()>,
    pub(super) thread: Option<std::thread::JoinHandle<Result<FrameWriter, Error>>>,
    pub(super) waited: f64,
    /// Snapshots taken back by [`FrameStream::sync`], used before the pool's.
    pub(super) spare: Vec<Snapshot>,
    pub(super) pool: usize,
}

impl FrameStream {
    /// Starts the writer thread with `pool` snapshots of `n` dofs and `m` contacts.
    pub fn spawn(writer: FrameWriter, n: usize, m: usize, pool: usize) -> Self {
        Self::spawn_with_statuses(writer, n, m, 0, pool)
    }

    /// As [`FrameStream::spawn`], the snapshots also holding `statuses` contact statuses
    /// (a frictional scene's `contact_status` field).
    pub fn spawn_with_statuses(
        mut writer: FrameWriter,
        n: usize,
        m: usize,
        statuses: usize,
        pool: usize,
    ) -> Self {
        let pool = pool.max(1);
        // a collection request follows the frames, so one more place than snapshots
        let (work_tx, work_rx) = std::sync::mpsc::sync_channel::<Job>(pool + 1);
        let (free_tx, free_rx) = std::sync::mpsc::sync_channel::<Snapshot>(pool);
        let (listed_tx, listed_rx) = std::sync::mpsc::sync_channel::<()>(1);
        for _ in 0..pool {
            free_tx
                .send(Snapshot::with_statuses(n, m, statuses))
                .expect("the pool channel holds `pool` snapshots");
        }
        // the spawning run's subnormal mode (inherited on Linux; set, not assumed)
        let flush = crate::linalg::subnormals::current_thread();
        let thread = std::thread::Builder::new()
            .name("signorini-frames".into())
            .spawn(move || {
                crate::linalg::subnormals::apply_to_current_thread(flush);
                for job in work_rx {
                    // the run may have stopped listening (it failed); that is its report
                    match job {
                        Job::Frame(snap) => {
                            writer.write_snapshot(&snap)?;
                            let _ = free_tx.send(snap);
                        }
                        Job::Collection => {
                            writer.write_collection()?;
                            let _ = listed_tx.send(());
                        }
                    }
                }
                writer.write_collection()?;
                Ok(writer)
            })
            .expect("spawning the frame writer thread");
        FrameStream {
            work: Some(work_tx),
            free: free_rx,
            listed: listed_rx,
            thread: Some(thread),
            waited: 0.0,
            spare: Vec::with_capacity(pool),
            pool,
        }
    }

    /// Queues a frame of `state`; waits for a free snapshot if all are in flight.
    pub fn push(&mut self, state: &State, jac: &ContactJacobian, h: f64) -> Result<(), Error> {
        let t0 = std::time::Instant::now();
        let mut snap = match self.spare.pop() {
            Some(s) => s,
            None => match self.free.recv() {
                Ok(s) => s,
                Err(_) => return Err(self.failure()),
            },
        };
        self.waited += t0.elapsed().as_secs_f64();
        snap.copy_from(state, jac, h);
        // the snapshot comes back in a send error only when the writer has stopped
        let sent = self
            .work
            .as_ref()
            .is_some_and(|w| w.send(Job::Frame(snap)).is_ok());
        if sent { Ok(()) } else { Err(self.failure()) }
    }

    /// Waits until every queued frame is on disk and listed by the `.pvd` (a
    /// checkpoint's barrier): takes every snapshot of the pool back, keeps them for the
    /// next pushes, and has the writer rewrite the `.pvd`.
    pub fn sync(&mut self) -> Result<(), Error> {
        while self.spare.len() < self.pool {
            match self.free.recv() {
                Ok(s) => self.spare.push(s),
                Err(_) => return Err(self.failure()),
            }
        }
        let asked = self
            .work
            .as_ref()
            .is_some_and(|w| w.send(Job::Collection).is_ok());
        if asked && self.listed.recv().is_ok() {
            Ok(())
        } else {
            Err(self.failure())
        }
    }

    /// Seconds the run spent waiting for a free snapshot.
    pub fn waited_seconds(&self) -> f64 {
        self.waited
    }

    /// Waits until every queued frame is written and returns the writer.
    pub fn finish(mut self) -> Result<FrameWriter, Error> {
        drop(self.work.take());
        self.join()
    }

    pub(super) fn join(&mut self) -> Result<FrameWriter, Error> {
        match self.thread.take().map(|t| t.join()) {
            Some(Ok(r)) => r,
            Some(Err(p)) => std::panic::resume_unwind(p),
            None => Err(Error::Write {
                path: PathBuf::from("fields.pvd"),
                source: std::io::Error::other("the frame writer already stopped"),
            }),
        }
    }

    /// The writer thread's error (it stopped early).
    pub(super) fn failure(&mut self) -> Error {
        drop(self.work.take());
        match self.join() {
            Err(e) => e,
            Ok(_) => Error::Write {
                path: PathBuf::from("fields.pvd"),
                source: std::io::Error::other("the frame writer stopped without an error"),
            },
        }
    }
}

/// What the run hands the writer thread.
pub(super) enum Job {
    /// A frame to write.
    Frame(Snapshot),
    /// Rewrite the `.pvd` now (and answer).
    Collection,
}

impl Drop for FrameStream {
    fn drop(&mut self) {
        drop(self.work.take());
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}
