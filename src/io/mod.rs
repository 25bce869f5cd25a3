//! Output writers: the per-step history (`history.csv`) and the run summary
//! (`summary.json`), the contract of DESIGN.md §6 and issue 2. Numbers are written as
//! the shortest decimal that reads back exactly (`ryu`).
//!
//! Files are written next to their final name (`NAME.part`), flushed as the run goes,
//! and renamed into place when complete, so a killed run never leaves a truncated file
//! under the final name and keeps every flushed row in the `.part` file.

pub mod fclib;
pub mod frames;
#[cfg(feature = "hdf5")]
pub mod h5;
pub mod mesh;
pub(crate) mod vtu;

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::Error;
use crate::integrators::{State, StepStats};

/// Writes `bytes` to `path` atomically (write `path.part`, flush, sync, rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    let tmp = part_path(path);
    let mut f = File::create(&tmp).map_err(|e| Error::write(&tmp, e))?;
    f.write_all(bytes).map_err(|e| Error::write(&tmp, e))?;
    f.sync_all().map_err(|e| Error::write(&tmp, e))?;
    std::fs::rename(&tmp, path).map_err(|e| Error::write(path, e))
}

/// The files a run writes into its directory (besides `fields/frame_*.vtu`).
pub const RUN_FILES: [&str; 12] = [
    "summary.json",
    "history.csv",
    "fields.pvd",
    "fields.vtkhdf",
    "obstacles.vtu",
    "checkpoint.json",
    "contact_force.png",
    "contact_force.svg",
    "energy.png",
    "energy.svg",
    "violation.png",
    "violation.svg",
];

/// What a path is, for the messages of [`check_output_file`] and [`check_output_dir`].
fn kind_of(md: &std::fs::Metadata) -> &'static str {
    let ft = md.file_type();
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt as _;
        if ft.is_block_device() || ft.is_char_device() {
            return "a device";
        }
        if ft.is_fifo() {
            return "a FIFO";
        }
        if ft.is_socket() {
            return "a socket";
        }
    }
    if ft.is_symlink() {
        "a symbolic link"
    } else if ft.is_dir() {
        "a directory"
    } else if ft.is_file() {
        "a regular file"
    } else {
        "not a regular file"
    }
}

/// Refuses (exit code 2) an output file `path` that exists as anything but a regular
/// file — a device, a FIFO, a socket, a directory, a symbolic link — or that is one of
/// the run's `inputs`: the atomic write renames over its target, which would replace a
/// device node (as root, `--solution /dev/full` did) or an input.
pub fn check_output_file(flag: &str, path: &Path, inputs: &[&Path]) -> Result<(), Error> {
    if let Ok(md) = std::fs::symlink_metadata(path) {
        if !md.file_type().is_file() {
            return Err(Error::invalid(
                flag,
                path.display(),
                &format!(
                    "is {}: an output is written as a regular file, never through a link \
                     or onto a device",
                    kind_of(&md)
                ),
            ));
        }
        let same = |a: &Path| matches!((std::fs::canonicalize(a), std::fs::canonicalize(path)), (Ok(x), Ok(y)) if x == y);
        if let Some(input) = inputs.iter().find(|i| same(i)) {
            return Err(Error::invalid(
                flag,
                path.display(),
                &format!(
                    "is the input {}: the output would replace it",
                    input.display()
                ),
            ));
        }
    }
    Ok(())
}

/// Refuses (exit code 2) an output directory that exists as anything but a directory.
pub fn check_output_dir(flag: &str, dir: &Path) -> Result<(), Error> {
    match std::fs::metadata(dir) {
        Ok(md) if !md.is_dir() => Err(Error::invalid(
            flag,
            dir.display(),
            &format!(
                "is {}, not a directory: choose a directory for the run",
                kind_of(&md)
            ),
        )),
        _ => Ok(()),
    }
}

/// The lock file a run holds in its output directory.
pub const LOCK_FILE: &str = ".signorini.lock";

/// How long [`RunLock::acquire`] waits for a lock that this process itself holds (a
/// child process between its fork and its exec) before refusing the directory.
const SELF_HELD_RETRY: std::time::Duration = std::time::Duration::from_secs(2);

/// One run's hold on its output directory: the operating system's advisory exclusive
/// lock (`flock` on Unix, `LockFileEx` on Windows, through `std::fs::File::try_lock`) on
/// [`LOCK_FILE`], held for the run or its resume and released when dropped, or by the
/// kernel when the process dies (a killed run leaves no stale lock). The holder's
/// process id is written into the file so that a refused run can name it.
#[derive(Debug)]
pub struct RunLock {
    _file: File,
}

impl RunLock {
    /// Creates `dir` if needed and takes its lock; a directory held by another run is
    /// refused (exit code 2) with the holder's process id.
    pub fn acquire(dir: &Path) -> Result<RunLock, Error> {
        check_output_dir("--out", dir)?;
        std::fs::create_dir_all(dir).map_err(|e| Error::write(dir, e))?;
        let path = dir.join(LOCK_FILE);
        let mut file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&path)
            .map_err(|e| Error::write(&path, e))?;
        // a descriptor this process's threads let a child inherit between its fork and
        // its exec holds the lock for that moment (flock belongs to the open file,
        // which the child shares): when the holder is this process, try again for a
        // while before refusing
        let deadline = std::time::Instant::now() + SELF_HELD_RETRY;
        loop {
            match file.try_lock() {
                Ok(()) => break,
                Err(std::fs::TryLockError::WouldBlock) => {
                    let holder = std::fs::read_to_string(&path).unwrap_or_default();
                    let holder = holder.trim();
                    let ours = holder == std::process::id().to_string();
                    if ours && std::time::Instant::now() < deadline {
                        std::thread::sleep(std::time::Duration::from_millis(10));
                        continue;
                    }
                    let who = if ours {
                        format!("another run in this process (process {holder})")
                    } else if holder.is_empty() {
                        "another signorini run".to_string()
                    } else {
                        format!("another signorini run (process {holder})")
                    };
                    return Err(Error::invalid(
                        "--out",
                        dir.display(),
                        &format!(
                            "{who} is writing into this directory; wait for it to finish or \
                             choose another output directory"
                        ),
                    ));
                }
                Err(std::fs::TryLockError::Error(e)) => return Err(Error::write(&path, e)),
            }
        }
        file.set_len(0).map_err(|e| Error::write(&path, e))?;
        writeln!(file, "{}", std::process::id()).map_err(|e| Error::write(&path, e))?;
        file.flush().map_err(|e| Error::write(&path, e))?;
        Ok(RunLock { _file: file })
    }
}

/// Makes `dir` ready for a new run: creates it, and removes what an earlier run left
/// there that this run would write or that would contradict it (its summary, history,
/// frames, plots, checkpoint, and their leftover `.part` files: the names of
/// [`RUN_FILES`] and the frames, nothing else — a user's own files, `.part` or not, stay),
/// so a finished directory never mixes two runs.
pub fn prepare_run_dir(dir: &Path) -> Result<(), Error> {
    std::fs::create_dir_all(dir).map_err(|e| Error::write(dir, e))?;
    let entries = std::fs::read_dir(dir).map_err(|e| Error::write(dir, e))?;
    for e in entries {
        let path = e.map_err(|e| Error::write(dir, e))?.path();
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
        let ours = RUN_FILES.contains(&name)
            || name
                .strip_suffix(".part")
                .is_some_and(|stem| RUN_FILES.contains(&stem));
        if ours && path.is_file() {
            std::fs::remove_file(&path).map_err(|e| Error::write(&path, e))?;
        }
    }
    let frames = dir.join("fields");
    if frames.is_dir() {
        frames::remove_stale_frames(&frames)?;
    }
    Ok(())
}

fn part_path(path: &Path) -> PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push(".part");
    PathBuf::from(s)
}

/// The shortest decimal that reads back as `x` (ryu: about 5× faster than `{}`, which
/// also prints `1e-40` as forty zeros), with `NaN` and `inf` spelled as Python and
/// pandas read them.
fn fmt_f64(buf: &mut ryu::Buffer, x: f64) -> &[u8] {
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
    file: Option<h5::RunFile>,
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
            return Ok(hist.with_hdf5(h5::History::create(
                f,
                m,
                tangent_dim,
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
    h5: Option<h5::History>,
    out: BufWriter<Counting>,
    tmp: PathBuf,
    path: PathBuf,
    rows_since_flush: usize,
    /// Rows written so far.
    rows: u64,
    /// One group of columns per contact; false: the sums ([`ContactColumns`]).
    per_contact: bool,
}

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
struct Counting {
    f: File,
    n: u64,
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
    const FLUSH_EVERY: usize = 4096;

    /// Creates `path.part` and writes the header for `m` contacts with `tangent_dim`
    /// tangents each (0 in a frictionless scene: the columns of before, unchanged).
    /// Frictional scenes add per contact `tangent_impulse_{c}_{t}` (N·s),
    /// `slip_velocity_{c}_{t}` (m/s) and `status_{c}` (0 open, 1 stick, 2 slip, 3 closed without friction), and per
    /// row `friction_iterations`, `friction_residual`. Without `per_contact` the contact
    /// columns are the sums of [`ContactColumns::Sums`]: `closed_contacts`,
    /// `total_impulse` (ΣP_N, N·s), `min_gap` (m), `total_projection` (Στ), with friction
    /// `total_tangent_impulse_{t}` (the tangential impulses summed in their own frames:
    /// a vector where the contacts share a frame, as on a plane), `sticking`, `slipping`.
    pub fn create(
        path: &Path,
        m: usize,
        tangent_dim: usize,
        per_contact: bool,
    ) -> Result<Self, Error> {
        let tmp = part_path(path);
        let f = File::create(&tmp).map_err(|e| Error::write(&tmp, e))?;
        let mut out = BufWriter::with_capacity(1 << 16, Counting { f, n: 0 });
        let mut header = String::from(
            "step,time,kinetic_energy,potential_energy,max_violation,newton_iterations,\
             projection_iterations,index_set_iterations",
        );
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
        })
    }

    /// Reopens the `.part` of a checkpointed run, cut to the `bytes` that belong to the
    /// checkpointed steps (rows a killed run wrote after its checkpoint, and a row the
    /// kill cut, are dropped: the resumed run writes them again). `per_contact` as the
    /// run was created with.
    pub fn resume(path: &Path, bytes: u64, rows: u64, per_contact: bool) -> Result<Self, Error> {
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
        })
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

    /// Appends the row of the step that just ended.
    pub fn row(
        &mut self,
        state: &State,
        stats: &StepStats,
        kinetic: f64,
        potential: f64,
    ) -> Result<(), Error> {
        let o = &mut self.out;
        let mut buf = ryu::Buffer::new();
        let r = (|| -> std::io::Result<()> {
            write!(o, "{}", state.step)?;
            for x in [state.time, kinetic, potential, stats.max_violation] {
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
            o.write_all(b"\n")
        })();
        r.map_err(|e| Error::write(&self.tmp, e))?;
        #[cfg(feature = "hdf5")]
        if let Some(h) = self.h5.as_mut() {
            h.row(state, stats, kinetic, potential)?;
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

/// What a run writes and how often (`[output]` in scene files; `--save-every`,
/// `--history-every`, `--no-fields`, `--ascii` on the command line).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputOptions {
    /// Output directory (the CLI's `--out` overrides it).
    #[serde(default)]
    pub dir: Option<PathBuf>,
    /// Save a field frame every `stride` steps; 0 (default) picks about 100 frames over
    /// the run. Frames are also saved at the start, at every contact onset and release
    /// (the set of closed contacts turns non-empty or empty) and at the last step.
    #[serde(default)]
    pub stride: usize,
    /// Write a history row every `history_stride` steps (default 1: every step).
    #[serde(default = "one")]
    pub history_stride: usize,
    /// Write field frames (default true): `.vtu` files with the `.pvd` collection and,
    /// with `hdf5`, the VTKHDF grid. False writes none, and the HDF5 file then holds
    /// `/history` only.
    #[serde(default = "yes")]
    pub fields: bool,
    /// Array encoding of the `.vtu` files (default zlib-compressed binary).
    #[serde(default)]
    pub encoding: frames::Encoding,
    /// Draw the plots (contact force, energy, violation; PNG and SVG) at the end of the
    /// run (default true).
    #[serde(default = "yes")]
    pub plots: bool,
    /// Write `fields.vtkhdf` (VTKHDF fields and `/history`); default: yes when built with
    /// the `hdf5` feature, and asking for it without the feature is an error.
    #[serde(default)]
    pub hdf5: Option<bool>,
    /// Write a checkpoint (`checkpoint.json`, [`crate::run::checkpoint`]) every this many
    /// steps (default 0: none); `signorini resume DIR` finishes a killed run from it.
    #[serde(default)]
    pub checkpoint_every: usize,
    /// Contact columns of `history.csv` (default `auto`: one group per contact up to
    /// [`CSV_CONTACTS_MAX`] contacts, their sums beyond; the HDF5 `/history` always
    /// keeps every contact).
    #[serde(default)]
    pub contact_columns: ContactColumns,
}

fn one() -> usize {
    1
}
fn yes() -> bool {
    true
}

impl Default for OutputOptions {
    fn default() -> Self {
        OutputOptions {
            dir: None,
            stride: 0,
            history_stride: 1,
            fields: true,
            encoding: frames::Encoding::Zlib,
            plots: true,
            hdf5: None,
            checkpoint_every: 0,
            contact_columns: ContactColumns::Auto,
        }
    }
}

impl OutputOptions {
    /// The frame stride for a run of `steps` steps (`stride`, or about 100 frames).
    pub fn frame_stride(&self, steps: usize) -> usize {
        if self.stride > 0 {
            self.stride
        } else {
            steps.div_ceil(100).max(1)
        }
    }
    /// Whether the HDF5 file is written.
    pub fn hdf5(&self) -> bool {
        self.hdf5.unwrap_or(cfg!(feature = "hdf5"))
    }
    /// Rejects a zero history stride, and HDF5 output from a build without it.
    pub fn validate(&self) -> Result<(), Error> {
        if self.hdf5() && !cfg!(feature = "hdf5") {
            return Err(Error::invalid(
                "hdf5",
                "true",
                "this signorini was built without the `hdf5` cargo feature \
                 (cargo build --release --features hdf5, with libhdf5-dev installed)",
            ));
        }
        if self.history_stride == 0 {
            return Err(Error::invalid("history_stride", 0, "must be at least 1"));
        }

        Ok(())
    }
}
