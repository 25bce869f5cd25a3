//! The per-step history: `history.csv` (one row per step, the columns of DESIGN.md §6,
//! per contact or summed past [`CSV_CONTACTS_MAX`] contacts) and its HDF5 copy, numbers
//! in the shortest decimal that reads back exactly, flushed as the run goes and resumable
//! from a checkpoint.

use super::*;

/// The shortest decimal that reads back as `x` (ryu: about 5× faster than `{}`, which
/// also prints `1e-40` as forty zeros), with `NaN` and `inf` spelled as Python and
/// pandas read them.
pub(super) fn fmt_f64(buf: &mut ryu::Buffer, x: f64) -> &[u8] {
    if x.is_finite() {
        buf.format_finite(x).as_bytes()
    } else if x.is_nan() {
        b"nan"
    } else if x > 0.0 {
        b"inf"
    } else {
        b"-inf"
    }
}

/// The run's HDF5 file (`fields.vtkhdf`: the VTKHDF frames and `/history`), when the
/// `hdf5` feature is built and the output asks for it. Holding the feature switch here
/// keeps it out of the run layer: without the feature (or with `hdf5 = false`) every
/// `attach_*` hands its writer back unchanged.
pub struct Hdf5Output {
    #[cfg(feature = "hdf5")]
    pub(super) file: Option<h5::RunFile>,
}

impl Hdf5Output {
    /// Creates the file in `dir` (or opens the one of a checkpointed run, `resuming`)
    /// when `options` ask for HDF5 and the feature is built.
    pub fn open(dir: &Path, options: &OutputOptions, resuming: bool) -> Result<Self, Error> {
        #[cfg(feature = "hdf5")]
        {
            let file = match (options.hdf5(), resuming) {
                (false, _) => None,
                (true, false) => Some(h5::RunFile::create(dir)?),
                (true, true) => Some(h5::RunFile::open(dir)?),
            };
            Ok(Hdf5Output { file })
        }
        #[cfg(not(feature = "hdf5"))]
        {
            let _ = (dir, options, resuming);
            Ok(Hdf5Output {})
        }
    }

    /// `hist`, also writing every row to `/history` (`m` contacts with `tangent_dim`
    /// tangents; the scheme's name, `h`, `θ` and the parameters as attributes);
    /// `resume_rows`: the rows of a checkpointed run to keep.
    #[allow(clippy::too_many_arguments)]
    pub fn attach_history(
        &self,
        hist: HistoryWriter,
        (m, tangent_dim): (usize, usize),
        scheme: &str,
        h: f64,
        theta: f64,
        parameters: &serde_json::Value,
        resume_rows: Option<usize>,
    ) -> Result<HistoryWriter, Error> {
        #[cfg(feature = "hdf5")]
        if let Some(f) = &self.file {
            let bodies = hist.bodies();
            return Ok(hist.with_hdf5(h5::History::create(
                f,
                (m, tangent_dim, bodies),
                scheme,
                h,
                theta,
                parameters,
                resume_rows,
            )?));
        }
        let _ = (m, tangent_dim, scheme, h, theta, parameters, resume_rows);
        Ok(hist)
    }

    /// `frames`, also appending every frame to the VTKHDF grid; `resume_frames`: the
    /// frames of a checkpointed run to keep.
    pub fn attach_frames(
        &self,
        frames: frames::FrameWriter,
        resume_frames: Option<usize>,
    ) -> Result<frames::FrameWriter, Error> {
        #[cfg(feature = "hdf5")]
        if let Some(f) = &self.file {
            return frames.with_hdf5(f, resume_frames);
        }
        let _ = resume_frames;
        Ok(frames)
    }
}

/// Streams one CSV row per step; see the module doc for the file protocol.
pub struct HistoryWriter {
    #[cfg(feature = "hdf5")]
    pub(super) h5: Option<h5::History>,
    pub(super) out: BufWriter<Counting>,
    pub(super) tmp: PathBuf,
    pub(super) path: PathBuf,
    pub(super) rows_since_flush: usize,
    /// Rows written so far.
    pub(super) rows: u64,
    /// One group of columns per contact; false: the sums ([`ContactColumns`]).
    pub(super) per_contact: bool,
    /// A `dt` column after `time` (a run whose step varies).
    pub(super) dt_column: bool,
    /// Solid scenes: each body's centre, momentum and angular momentum per row.
    pub(super) bodies: Option<BodyColumns>,
}

/// The per-body columns of a history ([`HistoryWriter::with_bodies`]): the measures'
/// dof map and one state per body, reused row after row (no allocation).
pub(super) struct BodyColumns {
    pub(super) measures: crate::model::BodyMeasures,
    pub(super) states: Vec<crate::model::BodyState>,
}

impl BodyColumns {
    fn new(measures: crate::model::BodyMeasures) -> Self {
        let states = vec![crate::model::BodyState::default(); measures.bodies()];
        BodyColumns { measures, states }
    }
}

/// The quantities of the per-body columns, three components each (x, y, z; zeros where
/// a plane body has none): `centre_{b}_{d}` (m), `momentum_{b}_{d}` (kg·m/s),
/// `angular_momentum_{b}_{d}` (about the centre of mass, kg·m²/s).
pub const BODY_COLUMNS: [&str; 3] = ["centre", "momentum", "angular_momentum"];

/// Contacts up to which [`ContactColumns::Auto`] writes per-contact history columns.
pub const CSV_CONTACTS_MAX: usize = 256;

/// Which contact columns `history.csv` has (`output.contact_columns`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ContactColumns {
    /// Per contact up to [`CSV_CONTACTS_MAX`] contacts, the sums above (default).
    #[default]
    Auto,
    /// Per contact whatever their number (a row of 10⁴ frictional contacts is 0.8 MB).
    All,
    /// The sums only: closed contacts, `ΣP_N`, the smallest gap, `Στ` (with friction
    /// `ΣP_T` per tangent and the sticking and slipping counts).
    Sums,
}

impl ContactColumns {
    /// Whether a run with `m` contacts writes per-contact columns.
    pub fn per_contact(self, m: usize) -> bool {
        match self {
            ContactColumns::Auto => m <= CSV_CONTACTS_MAX,
            ContactColumns::All => true,
            ContactColumns::Sums => false,
        }
    }
}

/// A file that counts the bytes written to it (the history's checkpoint cursor).
pub(super) struct Counting {
    pub(super) f: File,
    pub(super) n: u64,
}

impl Write for Counting {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        let k = self.f.write(b)?;
        self.n += k as u64;
        Ok(k)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.f.flush()
    }
}

impl HistoryWriter {
    /// Rows buffered before an explicit flush.
    pub(super) const FLUSH_EVERY: usize = 4096;

    /// Creates `path.part` and writes the header for `m` contacts with `tangent_dim`
    /// tangents each (0 in a frictionless scene: the columns of before, unchanged).
    /// Frictional scenes add per contact `tangent_impulse_{c}_{t}` (N·s),
    /// `slip_velocity_{c}_{t}` (m/s) and `status_{c}` (0 open, 1 stick, 2 slip, 3 closed without friction), and per
    /// row `friction_iterations`, `friction_residual`. Without `per_contact` the contact
    /// columns are the sums of [`ContactColumns::Sums`]: `closed_contacts`,
    /// `total_impulse` (ΣP_N, N·s), `min_gap` (m), `total_projection` (Στ), with friction
    /// `total_tangent_impulse_{t}` (the tangential impulses summed in their own frames:
    /// a vector where the contacts share a frame, as on a plane), `sticking`, `slipping`.
    /// With `bodies` (solid scenes), each row ends with every body's [`BODY_COLUMNS`].
    pub fn create(
        path: &Path,
        m: usize,
        tangent_dim: usize,
        per_contact: bool,
        bodies: Option<crate::model::BodyMeasures>,
    ) -> Result<Self, Error> {
        Self::create_with_steps(path, m, tangent_dim, per_contact, bodies, false)
    }

    /// [`HistoryWriter::create`], with a `dt` column after `time` (each row's step, s)
    /// when `dt_column`: a run whose step varies (the accuracy mode).
    pub fn create_with_steps(
        path: &Path,
        m: usize,
        tangent_dim: usize,
        per_contact: bool,
        bodies: Option<crate::model::BodyMeasures>,
        dt_column: bool,
    ) -> Result<Self, Error> {
        let tmp = part_path(path);
        let f = File::create(&tmp).map_err(|e| Error::write(&tmp, e))?;
        let mut out = BufWriter::with_capacity(1 << 16, Counting { f, n: 0 });
        let mut header = String::from(if dt_column {
            "step,time,dt,kinetic_energy,potential_energy,max_violation,newton_iterations,\
             projection_iterations,index_set_iterations"
        } else {
            "step,time,kinetic_energy,potential_energy,max_violation,newton_iterations,\
             projection_iterations,index_set_iterations"
        });
        if !per_contact {
            header.push_str(",closed_contacts,total_impulse,min_gap,total_projection");
            for t in 0..tangent_dim {
                header.push_str(&format!(",total_tangent_impulse_{t}"));
            }
            if tangent_dim > 0 {
                header.push_str(",sticking,slipping");
            }
        }
        for c in (0..m).filter(|_| per_contact) {
            header.push_str(&format!(",gap_{c},velocity_{c},impulse_{c},projection_{c}"));
            for t in 0..tangent_dim {
                header.push_str(&format!(",tangent_impulse_{c}_{t},slip_velocity_{c}_{t}"));
            }
            if tangent_dim > 0 {
                header.push_str(&format!(",status_{c}"));
            }
        }
        if tangent_dim > 0 {
            header.push_str(",friction_iterations,friction_residual");
        }
        for b in 0..bodies.as_ref().map_or(0, |m| m.bodies()) {
            for q in BODY_COLUMNS {
                for d in 0..3 {
                    header.push_str(&format!(",{q}_{b}_{d}"));
                }
            }
        }
        writeln!(out, "{header}").map_err(|e| Error::write(&tmp, e))?;
        Ok(HistoryWriter {
            #[cfg(feature = "hdf5")]
            h5: None,
            out,
            tmp,
            path: path.to_path_buf(),
            rows_since_flush: 0,
            rows: 0,
            per_contact,
            dt_column,
            bodies: bodies.map(BodyColumns::new),
        })
    }

    /// Reopens the `.part` of a checkpointed run, cut to the `bytes` that belong to the
    /// checkpointed steps (rows a killed run wrote after its checkpoint, and a row the
    /// kill cut, are dropped: the resumed run writes them again). `per_contact` as the
    /// run was created with, and `bodies` too.
    pub fn resume(
        path: &Path,
        bytes: u64,
        rows: u64,
        per_contact: bool,
        bodies: Option<crate::model::BodyMeasures>,
    ) -> Result<Self, Error> {
        let tmp = part_path(path);
        let mut f = std::fs::OpenOptions::new()
            .write(true)
            .open(&tmp)
            .map_err(|e| Error::io(&tmp, e))?;
        let len = f.metadata().map_err(|e| Error::io(&tmp, e))?.len();
        if len < bytes {
            return Err(Error::bad_file(
                &tmp,
                "",
                format!(
                    "holds {len} bytes, fewer than the {bytes} the checkpoint recorded (the \
                     history was cut or replaced)"
                ),
            ));
        }
        use std::io::{Read as _, Seek as _};
        // the cursor must end a row: the byte before it is a newline (the header's or a
        // row's), and there are as many newlines before it as rows plus the header
        let mut r = std::fs::File::open(&tmp).map_err(|e| Error::io(&tmp, e))?;
        let mut newlines = 0u64;
        let mut last = 0u8;
        let mut buf = vec![0u8; 1 << 16];
        let mut left = bytes;
        while left > 0 {
            let n = r
                .read(&mut buf[..left.min(1 << 16) as usize])
                .map_err(|e| Error::io(&tmp, e))?;
            if n == 0 {
                break;
            }
            newlines += buf[..n].iter().filter(|&&b| b == b'\n').count() as u64;
            last = buf[n - 1];
            left -= n as u64;
        }
        if bytes == 0 || last != b'\n' || newlines != rows + 1 {
            return Err(Error::bad_file(
                &tmp,
                format!("byte {bytes}"),
                format!(
                    "the checkpoint's history cursor does not end row {rows} ({newlines} line \
                     ends before it{}): the checkpoint does not belong to this history",
                    if last != b'\n' {
                        ", and it falls inside a line"
                    } else {
                        ""
                    }
                ),
            ));
        }
        f.set_len(bytes).map_err(|e| Error::write(&tmp, e))?;
        f.seek(std::io::SeekFrom::End(0))
            .map_err(|e| Error::write(&tmp, e))?;
        Ok(HistoryWriter {
            #[cfg(feature = "hdf5")]
            h5: None,
            out: BufWriter::with_capacity(1 << 16, Counting { f, n: bytes }),
            tmp,
            path: path.to_path_buf(),
            rows_since_flush: 0,
            rows,
            per_contact,
            dt_column: false,
            bodies: bodies.map(BodyColumns::new),
        })
    }

    /// A resumed history with the `dt` column of [`HistoryWriter::create_with_steps`].
    pub fn with_dt_column(mut self, on: bool) -> Self {
        self.dt_column = on;
        self
    }

    /// The bodies measured in each row (0 without per-body columns).
    pub fn bodies(&self) -> usize {
        self.bodies.as_ref().map_or(0, |b| b.states.len())
    }

    /// Rows written so far.
    pub fn rows(&self) -> u64 {
        self.rows
    }

    /// Bytes on disk; after a [`HistoryWriter::flush`], every row written so far.
    pub fn bytes(&self) -> u64 {
        self.out.get_ref().n
    }

    /// Also writes every row to `/history` of the run's HDF5 file.
    #[cfg(feature = "hdf5")]
    pub fn with_hdf5(mut self, h: h5::History) -> Self {
        self.h5 = Some(h);
        self
    }

    /// Appends the row of the step that just ended. The per-body columns read the
    /// structure's mass matrix `mass` and `M v` where the energies left it (`mv`, as
    /// [`crate::model::LinearSystem::energies_keeping_mv`]; `None`: formed here).
    pub fn row(
        &mut self,
        (mass, mv): (&crate::linalg::SparseMatrix, Option<&[f64]>),
        state: &State,
        stats: &StepStats,
        kinetic: f64,
        potential: f64,
    ) -> Result<(), Error> {
        if let Some(b) = self.bodies.as_mut() {
            match mv {
                Some(mv) => b.measures.measure_with(mass, &state.q, mv, &mut b.states),
                None => b.measures.measure(mass, &state.q, &state.v, &mut b.states),
            }
        }
        let o = &mut self.out;
        let mut buf = ryu::Buffer::new();
        let r = (|| -> std::io::Result<()> {
            write!(o, "{}", state.step)?;
            o.write_all(b",")?;
            o.write_all(fmt_f64(&mut buf, state.time))?;
            if self.dt_column {
                o.write_all(b",")?;
                o.write_all(fmt_f64(&mut buf, stats.dt))?;
            }
            for x in [kinetic, potential, stats.max_violation] {
                o.write_all(b",")?;
                o.write_all(fmt_f64(&mut buf, x))?;
            }
            write!(
                o,
                ",{},{},{}",
                stats.newton_iterations, stats.projection_iterations, stats.index_set_iterations
            )?;
            if !self.per_contact {
                let td = state.tangent_dim;
                let closed = state.impulse.iter().filter(|&&p| p > 0.0).count();
                let total: f64 = state.impulse.iter().sum();
                let min_gap = state.gap.iter().copied().fold(f64::INFINITY, f64::min);
                let tau: f64 = state.projection.iter().sum();
                write!(o, ",{closed}")?;
                for x in [total, if state.gap.is_empty() { 0.0 } else { min_gap }, tau] {
                    o.write_all(b",")?;
                    o.write_all(fmt_f64(&mut buf, x))?;
                }
                for t in 0..td {
                    let s: f64 = state.tangent_impulse.iter().skip(t).step_by(td).sum();
                    o.write_all(b",")?;
                    o.write_all(fmt_f64(&mut buf, s))?;
                }
                if td > 0 {
                    let count = |k| state.status.iter().filter(|s| **s == k).count();
                    write!(
                        o,
                        ",{},{}",
                        count(crate::contact::ContactStatus::Stick),
                        count(crate::contact::ContactStatus::Slip)
                    )?;
                }
            }
            for c in (0..state.gap.len()).filter(|_| self.per_contact) {
                for x in [
                    state.gap[c],
                    state.local_velocity[c],
                    state.impulse[c],
                    state.projection[c],
                ] {
                    o.write_all(b",")?;
                    o.write_all(fmt_f64(&mut buf, x))?;
                }
                let td = state.tangent_dim;
                for t in 0..td {
                    for x in [
                        state.tangent_impulse[c * td + t],
                        state.tangent_velocity[c * td + t],
                    ] {
                        o.write_all(b",")?;
                        o.write_all(fmt_f64(&mut buf, x))?;
                    }
                }
                if td > 0 {
                    write!(o, ",{}", state.status[c].code())?;
                }
            }
            if state.tangent_dim > 0 {
                write!(o, ",{},", stats.friction_iterations)?;
                o.write_all(fmt_f64(&mut buf, stats.friction_residual))?;
            }
            for b in self.bodies.iter().flat_map(|b| &b.states) {
                for x in b
                    .centre
                    .iter()
                    .chain(&b.momentum)
                    .chain(&b.angular_momentum)
                {
                    o.write_all(b",")?;
                    o.write_all(fmt_f64(&mut buf, *x))?;
                }
            }
            o.write_all(b"\n")
        })();
        r.map_err(|e| Error::write(&self.tmp, e))?;
        #[cfg(feature = "hdf5")]
        if let Some(h) = self.h5.as_mut() {
            let bodies = self.bodies.as_ref().map_or(&[][..], |b| &b.states[..]);
            h.row(state, stats, kinetic, potential, bodies)?;
        }
        self.rows_since_flush += 1;
        self.rows += 1;
        if self.rows_since_flush >= Self::FLUSH_EVERY {
            self.out.flush().map_err(|e| Error::write(&self.tmp, e))?;
            self.rows_since_flush = 0;
        }
        Ok(())
    }

    /// Pushes the buffered rows to the file (the run does it at every field frame, so
    /// a killed run's history reaches at least its last frame).
    pub fn flush(&mut self) -> Result<(), Error> {
        self.rows_since_flush = 0;
        #[cfg(feature = "hdf5")]
        if let Some(h) = self.h5.as_mut() {
            h.flush()?;
        }
        self.out.flush().map_err(|e| Error::write(&self.tmp, e))
    }

    /// Flushes and renames the file into place. No `fsync`: a killed process loses
    /// nothing the kernel already holds, and syncing a history of a few MB measured
    /// 10–30 ms here, more than a short run's whole step loop.
    pub fn finish(mut self) -> Result<(), Error> {
        #[cfg(feature = "hdf5")]
        if let Some(h) = self.h5.as_mut() {
            h.flush()?;
        }
        self.out.flush().map_err(|e| Error::write(&self.tmp, e))?;
        std::fs::rename(&self.tmp, &self.path).map_err(|e| Error::write(&self.path, e))
    }
}
