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
//!   frames written); on resume the CSV is cut to those bytes and the HDF5 datasets to
//!   those rows and frames, then appended to.
//!
//! Floats are stored as the hexadecimal bits of their IEEE-754 representation (arrays as
//! base64 of their little-endian bytes), so a resumed run starts from bit-identical
//! values; JSON keeps the rest readable. Why our own format: the state is a few named
//! arrays; a general serialization format would not keep the floats' bits readable.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use base64::Engine as _;
use serde::{Deserialize, Serialize};

use crate::error::Error;

/// The format name in every checkpoint.
pub const FORMAT: &str = "signorini-checkpoint";
/// The format version this build writes and reads.
pub const VERSION: u32 = 1;
/// The checkpoint's file name in a run directory.
pub const FILE: &str = "checkpoint.json";

/// An `f64` stored as its bits (`"0x3ff0000000000000"`), so it reads back exactly,
/// NaN and infinities included.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Bits(pub f64);

impl Serialize for Bits {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&format!("{:#018x}", self.0.to_bits()))
    }
}

impl<'de> Deserialize<'de> for Bits {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        u64::from_str_radix(s.trim_start_matches("0x"), 16)
            .map(|b| Bits(f64::from_bits(b)))
            .map_err(|_| serde::de::Error::custom(format!("`{s}` is not 0x + 16 hex digits")))
    }
}

/// A vector of `f64` stored as base64 of its little-endian bytes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Floats(pub Vec<f64>);

impl Serialize for Floats {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let bytes: Vec<u8> = self.0.iter().flat_map(|x| x.to_le_bytes()).collect();
        s.serialize_str(&base64::engine::general_purpose::STANDARD.encode(bytes))
    }
}

impl<'de> Deserialize<'de> for Floats {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        let bytes = base64::engine::general_purpose::STANDARD
            .decode(s.as_bytes())
            .map_err(|e| serde::de::Error::custom(format!("not base64: {e}")))?;
        if bytes.len() % 8 != 0 {
            return Err(serde::de::Error::custom(format!(
                "{} bytes is not a whole number of f64",
                bytes.len()
            )));
        }
        Ok(Floats(
            bytes
                .chunks_exact(8)
                .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
                .collect(),
        ))
    }
}

/// What an integrator carries from one step to the next (module doc).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IntegratorState {
    /// The scheme's name (a checkpoint resumes with the scheme that wrote it).
    pub scheme: String,
    /// Steps taken.
    pub step: usize,
    /// Time (s).
    pub time: Bits,
    /// Named vectors: `q`, `v`, `impulse`, `projection`, `impulse_rows`,
    /// `local_velocity`, `tangent_velocity`, `tangent_impulse`, and a scheme's own.
    pub vectors: BTreeMap<String, Floats>,
    /// Contact status codes (frictional scenes: 0 open, 1 stick, 2 slip).
    pub status: Vec<u8>,
}

impl IntegratorState {
    /// The vector `name`, which must have `len` entries; the error names the checkpoint.
    pub fn vector(&self, name: &str, len: usize) -> Result<&[f64], Error> {
        match self.vectors.get(name) {
            Some(v) if v.0.len() == len => Ok(&v.0),
            Some(v) => Err(Error::invalid(
                &format!("checkpoint integrator.vectors.{name}"),
                format!("{} values", v.0.len()),
                &format!("the model has {len} (was the mesh or the scene changed?)"),
            )),
            None => Err(Error::invalid(
                &format!("checkpoint integrator.vectors.{name}"),
                "(missing)",
                "a checkpoint of this scheme holds it",
            )),
        }
    }
}

/// What to rebuild on resume.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum RunSource {
    /// The impacting bar (`signorini bar`), with its parameters.
    Bar {
        /// The bar scene as run.
        scene: crate::scene::bar::BarScene,
    },
    /// A scene file: its text as run (a later edit of the file does not change the
    /// resumed run) and the directory its relative mesh paths start from.
    Scene {
        /// The scene file's path (for messages).
        file: PathBuf,
        /// Its TOML text.
        toml: String,
        /// The directory of relative mesh paths.
        base_dir: PathBuf,
    },
}

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
    /// Friction statistics: solves, sweeps, largest sweeps, steps with a solve, caps.
    pub friction_counts: [usize; 5],
    /// Friction residual sum and maximum.
    pub friction_residual: [Bits; 2],
    /// The per-step force trace (empty beyond `FORCE_TRACE_MAX_STEPS`).
    pub trace: Option<Floats>,
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
    /// History rows written up to the checkpoint (the length of the HDF5 `/history`).
    pub history_rows: u64,
    /// Times of the frames written (the `.pvd` entries).
    pub frames: Vec<Bits>,
    /// A contact was closed at the checkpointed step (frames are saved at switches).
    pub closed_before: bool,
}

/// A whole checkpoint.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Checkpoint {
    /// [`FORMAT`].
    pub format: String,
    /// [`VERSION`].
    pub version: u32,
    /// What to rebuild.
    pub source: RunSource,
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
}

impl Checkpoint {
    /// Writes `dir/checkpoint.json` atomically (write, fsync, rename).
    pub fn write(&self, dir: &Path) -> Result<(), Error> {
        let json = serde_json::to_vec(self)
            .map_err(|e| Error::Numerical(format!("serializing the checkpoint: {e}")))?;
        crate::io::write_atomic(&dir.join(FILE), &json)
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
