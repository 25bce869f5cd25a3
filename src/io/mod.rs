//! Output writers: the per-step history (`history.csv`) and the run summary
//! (`summary.json`), the contract of DESIGN.md §6 and issue 2; and the history's one
//! reader (`history_read`: a cut last row of a `.part` tolerated). Numbers are written as
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

mod history;
mod history_read;
mod run_dir;

pub use history::*;
pub use history_read::*;
pub use run_dir::*;

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::Error;
use crate::integrators::{State, StepStats};

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
