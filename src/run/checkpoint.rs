//! Checkpoints: the whole state of a run, written atomically into its directory every
//! `K` steps (`--checkpoint-every K`), from which `signorini resume DIR` finishes a
//! killed run exactly as an uninterrupted one would (the same `history.csv` byte for
//! byte, the same frames, the same physics in `summary.json`; DESIGN.md §9).
//!
//! What a checkpoint holds (format `signorini-checkpoint`, [`VERSION`]):
//! - what to rebuild: the scene (its TOML text and directory, or the bar's parameters,
//!   or an example's name), the output options and the number of steps;
//! - the integrator's state ([`IntegratorState`]): `t`, `q`, `v`, impulses (the warm
//!   start of the next friction solve), projections, contact statuses, and any vector a
//!   scheme carries from step to step (Schatzman–Paoli's `q_{k−1}`); the gaps,
//!   Jacobians and Delassus data are functions of `q` and are evaluated again;
//! - the run's accumulators (iteration statistics, the contact measurement) and output
//!   cursors (bytes and rows of the history that belong to the checkpointed steps, the
//!   number of frames written, whose times the resumed run reads back from the `.pvd`);
//!   on resume the CSV is cut to those bytes and the HDF5 datasets to those rows and
//!   frames, then appended to. Nothing in it grows with the number of steps (version
//!   3: version 2 held the per-step force trace and every frame's time). Version 4
//!   adds the friction fallback and complementarity fallback counters and the energy
//!   balance; version 5 the digest; version 6 the subnormal mode; version 7 the
//!   SHA-256 of the history it continues, in place of the directory's path.
//!
//! What a checkpoint guards (since version 2): the build that wrote it, the run it
//! belongs to — since version 7 by content: the SHA-256 of the history up to its cursor,
//! so that a run directory moved or copied whole resumes, and a checkpoint copied into
//! another run's directory (which would splice two runs) is refused —, and the size and
//! SHA-256 of every input file (the scene file and its mesh
//! files); `resume` refuses a checkpoint whose build, history or inputs differ, whose
//! `every` is 0, whose history cursor falls inside a row or whose arrays disagree, each
//! with exit code 2 and a message naming what differs ([`Checkpoint::verify`]). Since
//! version 5 it also carries the SHA-256 of its own content (`digest`, all but the
//! digest and the directory): a checkpoint edited or damaged after it was written is
//! refused, whatever field changed.
//!
//! Floats are stored as the hexadecimal bits of their IEEE-754 representation (arrays as
//! base64 of their little-endian bytes), so a resumed run starts from bit-identical
//! values; JSON keeps the rest readable. Why our own format: the state is a few named
//! arrays; a general serialization format would not keep the floats' bits readable.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::Error;
use crate::integrators::saved::{Bits, Floats, IntegratorState};

/// The format name in every checkpoint.
pub const FORMAT: &str = "signorini-checkpoint";
/// The format version this build writes and reads.
pub const VERSION: u32 = 7;
/// The checkpoint's file name in a run directory.
pub const FILE: &str = "checkpoint.json";

/// The run's accumulators and output cursors at the checkpoint.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunState {
    /// Iteration sums and maxima (Newton, projection, index set, LCP).
    pub sum: [usize; 4],
    /// Their maxima.
    pub max: [usize; 4],
    /// Caps hit.
    pub caps: usize,
    /// Largest LCP residual.
    pub lcp_res: Bits,
    /// Largest violation.
    pub violation: Bits,
    /// Friction statistics: solves, sweeps, largest sweeps, steps with a solve, caps,
    /// solves past NSGS.
    pub friction_counts: [usize; 6],
    /// Friction residual sum and maximum.
    pub friction_residual: [Bits; 2],
    /// Coupled position solves, stagnated Newton loops, steps with held rows,
    /// complementarity fallbacks of Algorithm 2.
    pub newton_loops: [usize; 4],
    /// Matrix-free one-step solves and their products.
    #[serde(default)]
    pub global: [usize; 2],
    /// Nonlinear structures: factorizations of `M̂ⁿ` so far.
    #[serde(default)]
    pub factorizations: usize,
    /// The energy balance's sums (`model::energy::EnergyAudit::save`).
    pub energy_audit: [Bits; 6],
    /// Largest relative energy excess met.
    pub energy_excess: Bits,
    /// The per-step force trace (empty beyond `FORCE_TRACE_MAX_STEPS`).
    pub trace: Option<Floats>,
    /// The step of each trace sample, once the step varied (the accuracy mode).
    #[serde(default)]
    pub trace_dt: Option<Floats>,
    /// The step of each sample of the first contact interval so far.
    #[serde(default)]
    pub contact_dt: Floats,
    /// Start time of the first contact interval's first sample.
    #[serde(default)]
    pub first_contact_start: Bits,
    /// `Σ (Σ P)` over the run.
    #[serde(default)]
    pub total_impulse: Bits,
    /// The step varied during the run.
    #[serde(default)]
    pub varied: bool,
    /// First step with a positive impulse.
    pub first_contact: Option<usize>,
    /// Forces of the first contact interval so far.
    pub contact_force: Floats,
    /// Smallest gaps of the first contact interval so far.
    pub contact_min_gap: Floats,
    /// The first interval has ended.
    pub contact_done: bool,
    /// Sum of the forces over the run.
    pub total_force: Bits,
    /// Energy at the start (J).
    pub energy0: Bits,
    /// Bytes of `history.csv.part` written up to the checkpoint.
    pub history_bytes: u64,
    /// SHA-256 (hex) of those bytes: what ties the checkpoint to its run directory
    /// (version 7; before, its absolute path, so a directory moved whole could not be
    /// resumed).
    pub history_sha256: String,
    /// History rows written up to the checkpoint (the length of the HDF5 `/history`).
    pub history_rows: u64,
    /// Frames written (their times are read back from the `.pvd`, so that a checkpoint
    /// does not grow with the run; version 3, version 2 held every time).
    pub frames: usize,
    /// A contact was closed at the checkpointed step (frames are saved at switches).
    pub closed_before: bool,
    /// The probes' values recorded so far (`run::probes::ProbeSet::save`).
    #[serde(default)]
    pub probes: Vec<Floats>,
    /// The accuracy mode's controller after the checkpointed window.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub accuracy: Option<super::accuracy::ControllerState>,
}

/// A running SHA-256 of a history file's first `bytes` bytes: each checkpoint reads only
/// what was written since the last one.
#[derive(Clone, Default)]
pub struct HistoryHash {
    sha: sha2::Sha256,
    bytes: u64,
}

impl HistoryHash {
    /// The hex digest of the bytes hashed so far.
    pub fn hex(&self) -> String {
        use sha2::Digest as _;
        hex(&self.sha.clone().finalize())
    }
}

/// `state` carried on to the first `upto` bytes of `path` (reading only the bytes past
/// those it holds); the file must hold them. Returns the new state twice: one to keep,
/// one that was hashed.
pub fn hash_history(
    path: &Path,
    mut state: HistoryHash,
    upto: u64,
) -> Result<(HistoryHash, HistoryHash), Error> {
    use sha2::Digest as _;
    use std::io::{Read as _, Seek as _};
    if upto < state.bytes {
        state = HistoryHash::default();
    }
    if upto > state.bytes {
        let mut f = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
        f.seek(std::io::SeekFrom::Start(state.bytes))
            .map_err(|e| Error::io(path, e))?;
        let mut left = upto - state.bytes;
        let mut buf = vec![0u8; 1 << 16];
        while left > 0 {
            let want = (buf.len() as u64).min(left) as usize;
            let got = f.read(&mut buf[..want]).map_err(|e| Error::io(path, e))?;
            if got == 0 {
                return Err(Error::bad_file(
                    path,
                    "",
                    format!(
                        "holds {} bytes, fewer than the {upto} the checkpoint recorded (the \
                         history was cut or replaced)",
                        upto - left
                    ),
                ));
            }
            state.sha.update(&buf[..got]);
            left -= got as u64;
        }
        state.bytes = upto;
    }
    Ok((state.clone(), state))
}

/// One input file of a run as the checkpoint saw it.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InputFile {
    /// Its path (absolute when the run was started).
    pub path: PathBuf,
    /// Its size (bytes).
    pub bytes: u64,
    /// SHA-256 of its contents, hexadecimal.
    pub sha256: String,
}

impl InputFile {
    /// Reads and hashes `path` (streamed: mesh files may be large).
    pub fn of(path: &Path) -> Result<InputFile, Error> {
        use sha2::Digest;
        use std::io::Read;
        let path = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
        let io = |e: std::io::Error| Error::io(&path, e);
        let mut f = std::fs::File::open(&path).map_err(io)?;
        let mut hasher = sha2::Sha256::new();
        let mut buf = vec![0u8; 1 << 16];
        let mut bytes = 0u64;
        loop {
            let n = f.read(&mut buf).map_err(io)?;
            if n == 0 {
                break;
            }
            hasher.update(&buf[..n]);
            bytes += n as u64;
        }
        let sha256 = hex(&hasher.finalize());
        Ok(InputFile {
            path,
            bytes,
            sha256,
        })
    }
}

/// Lower-case hexadecimal of a digest.
fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// The build that writes checkpoints: package version and, when it was built from a
/// git checkout, the commit (`build.rs`).
pub fn build_id() -> String {
    format!(
        "signorini {} ({})",
        env!("CARGO_PKG_VERSION"),
        option_env!("SIGNORINI_COMMIT").unwrap_or("commit unknown")
    )
}

/// A whole checkpoint.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Checkpoint {
    /// [`FORMAT`].
    pub format: String,
    /// [`VERSION`].
    pub version: u32,
    /// What the application needs to rebuild the run, as it gave it (opaque to the
    /// driver: `crate::app::source::RunSource` for `signorini`'s runs).
    pub source: serde_json::Value,
    /// The output options as run.
    pub output: crate::io::OutputOptions,
    /// Checkpoint every this many steps (the resumed run goes on doing so).
    pub every: usize,
    /// Steps of the whole run.
    pub steps: usize,
    /// The integrator's state.
    pub integrator: IntegratorState,
    /// The run's accumulators and output cursors.
    pub run: RunState,
    /// The build that wrote it ([`build_id`]).
    pub build: String,
    /// The output directory it was written in (absolute, canonical; for messages only:
    /// the run is identified by `run.history_sha256`, so a directory moved whole resumes).
    pub out_dir: PathBuf,
    /// The run's input files as they were at its start.
    pub inputs: Vec<InputFile>,
    /// The arithmetic of the run's factorizations ([`crate::linalg::arithmetic`]): a
    /// resumed run takes the same, so that it ends byte for byte as the uninterrupted one.
    #[serde(default = "portable")]
    pub arithmetic: crate::linalg::Arithmetic,
    /// What the run's threads did with subnormal numbers
    /// ([`crate::linalg::subnormals`](mod@crate::linalg::subnormals)): a resumed run does the same.
    pub subnormals: crate::linalg::Subnormals,
    /// SHA-256 of the rest of the checkpoint (every field but this one and `out_dir`,
    /// which `verify` checks itself), set by [`Checkpoint::write`]: `resume` refuses a
    /// checkpoint edited or damaged after it was written (issue 34: a NaN
    /// `integrator.time` or an edited `step` was resumed).
    pub digest: String,
}

fn portable() -> crate::linalg::Arithmetic {
    crate::linalg::Arithmetic::Portable
}

impl Checkpoint {
    /// Writes `dir/checkpoint.json` atomically (write, fsync, rename), with its digest.
    pub fn write(mut self, dir: &Path) -> Result<(), Error> {
        self.digest = self.content_digest()?;
        let json = serde_json::to_vec(&self)
            .map_err(|e| Error::Numerical(format!("serializing the checkpoint: {e}")))?;
        crate::io::write_atomic(&dir.join(FILE), &json)
    }

    /// SHA-256 (hex) of the checkpoint's JSON with `digest` and `out_dir` emptied (taken
    /// out and put back: no copy of the state); the fields round-trip exactly (floats as
    /// their bits, the rest as JSON that serde_json reads back bit for bit), so a
    /// checkpoint read back digests alike.
    fn content_digest(&mut self) -> Result<String, Error> {
        use sha2::Digest as _;
        let (digest, out_dir) = (
            std::mem::take(&mut self.digest),
            std::mem::take(&mut self.out_dir),
        );
        let json = serde_json::to_vec(&*self);
        (self.digest, self.out_dir) = (digest, out_dir);
        let json =
            json.map_err(|e| Error::Numerical(format!("serializing the checkpoint: {e}")))?;
        Ok(hex(&sha2::Sha256::digest(&json)))
    }

    /// Reads `dir/checkpoint.json`; a missing, corrupt, foreign or other-version file
    /// gets an error that says which.
    pub fn read(dir: &Path) -> Result<Checkpoint, Error> {
        let path = dir.join(FILE);
        if !path.exists() {
            return Err(Error::bad_file(
                &path,
                "",
                "no checkpoint here: the run was not started with --checkpoint-every K, \
                 finished (a finished run removes its checkpoint), or was killed before \
                 its first checkpoint",
            ));
        }
        let text = crate::limits::read_text(&path, "checkpoint", crate::limits::MAX_TEXT_BYTES)?;
        let head: serde_json::Value = serde_json::from_str(&text).map_err(|e| {
            Error::bad_file(
                &path,
                format!("line {}, column {}", e.line(), e.column()),
                format!("not a readable checkpoint (truncated or corrupt): {e}"),
            )
        })?;
        if head.get("format").and_then(|f| f.as_str()) != Some(FORMAT) {
            return Err(Error::bad_file(
                &path,
                "`format`",
                format!("expected \"{FORMAT}\": not a signorini checkpoint"),
            ));
        }
        let version = head.get("version").and_then(|v| v.as_u64());
        if version != Some(VERSION as u64) {
            return Err(Error::bad_file(
                &path,
                "`version`",
                format!(
                    "checkpoint version {} cannot be resumed by this signorini (it reads \
                     version {VERSION}); finish the run with the signorini that started it",
                    version.map_or("(missing)".to_string(), |v| v.to_string())
                ),
            ));
        }
        let de = &mut serde_json::Deserializer::from_str(&text);
        serde_path_to_error::deserialize(de).map_err(|e| {
            Error::bad_file(
                &path,
                format!("`{}`", e.path()),
                format!("corrupt checkpoint: {}", e.inner()),
            )
        })
    }
}

impl Checkpoint {
    /// Refuses to resume from this checkpoint (read from `dir`) when it belongs to another
    /// build or directory, when an input file changed, or when its own fields disagree;
    /// every error names the checkpoint file, the field and what differs (exit code 2).
    pub fn verify(&self, dir: &Path) -> Result<(), Error> {
        let file = dir.join(FILE);
        let bad = |where_: &str, detail: String| Err(Error::bad_file(&file, where_, detail));
        if self.build != build_id() {
            return bad(
                "`build`",
                format!(
                    "written by {}, this is {}: finish the run with the build that started it",
                    self.build,
                    build_id()
                ),
            );
        }
        if self.every == 0 {
            return bad(
                "`every`",
                "0: a checkpoint is written every K ≥ 1 steps".into(),
            );
        }
        // an accuracy run takes more steps than its count at the largest step
        if self.integrator.step > self.steps && self.run.accuracy.is_none() {
            return bad(
                "`integrator.step`",
                format!(
                    "{} is past the run's {} steps",
                    self.integrator.step, self.steps
                ),
            );
        }
        let r = &self.run;
        if r.contact_force.0.len() != r.contact_min_gap.0.len() {
            return bad(
                "`run.contact_min_gap`",
                format!(
                    "{} values beside {} contact forces: the two arrays go together",
                    r.contact_min_gap.0.len(),
                    r.contact_force.0.len()
                ),
            );
        }
        if let Some(t) = &r.trace
            && t.0.len() != self.integrator.step
        {
            return bad(
                "`run.trace`",
                format!(
                    "{} values for {} steps taken",
                    t.0.len(),
                    self.integrator.step
                ),
            );
        }
        if r.history_rows > self.integrator.step as u64 + 1 {
            return bad(
                "`run.history_rows`",
                format!(
                    "{} rows for {} steps taken",
                    r.history_rows, self.integrator.step
                ),
            );
        }
        for f in &self.inputs {
            let now = match InputFile::of(&f.path) {
                Ok(now) => now,
                Err(_) => {
                    return bad(
                        "`inputs`",
                        format!("{} is gone; the run read it", f.path.display()),
                    );
                }
            };
            if now.bytes != f.bytes || now.sha256 != f.sha256 {
                return bad(
                    "`inputs`",
                    format!(
                        "{} changed since the run started ({} bytes, SHA-256 {} then; {} \
                         bytes, {} now): restore it or start a new run",
                        f.path.display(),
                        f.bytes,
                        &f.sha256[..16.min(f.sha256.len())],
                        now.bytes,
                        &now.sha256[..16.min(now.sha256.len())]
                    ),
                );
            }
        }
        // after the field checks, so that they name what they find
        if self.clone().content_digest()? != self.digest {
            return bad(
                "`digest`",
                "does not match the checkpoint's content: it was edited or damaged after \
                 the run wrote it (a resumed run would not be the run's); start a new run, \
                 or resume from an intact copy"
                    .into(),
            );
        }
        // then, for an intact checkpoint: the directory's history is the one it
        // continues, by content, not by path (a directory moved whole resumes; a
        // checkpoint copied beside another run's history would splice two runs)
        let history = crate::io::part_path(&dir.join("history.csv"));
        let (_, hashed) = hash_history(&history, HistoryHash::default(), self.run.history_bytes)?;
        if hashed.hex() != self.run.history_sha256 {
            return Err(Error::bad_file(
                &history,
                "",
                format!(
                    "its first {} bytes (SHA-256 {}) are not the history the checkpoint \
                     continues (SHA-256 {}; written in {}): the checkpoint was copied beside \
                     another run's history, or the history was edited; resume the directory \
                     the checkpoint was written in (moved whole, it resumes)",
                    self.run.history_bytes,
                    &hashed.hex()[..16],
                    &self.run.history_sha256[..16.min(self.run.history_sha256.len())],
                    self.out_dir.display()
                ),
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floats_keep_their_bits() {
        let v = Floats(vec![0.1, -0.0, f64::NAN, f64::INFINITY, 1e-310, f64::MAX]);
        let s = serde_json::to_string(&v).unwrap();
        let w: Floats = serde_json::from_str(&s).unwrap();
        let bits = |f: &Floats| f.0.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&v), bits(&w));
        let b: Bits = serde_json::from_str(&serde_json::to_string(&Bits(0.1)).unwrap()).unwrap();
        assert_eq!(b.0.to_bits(), 0.1f64.to_bits());
        assert!(serde_json::from_str::<Bits>("\"0xzz\"").is_err());
    }
}
