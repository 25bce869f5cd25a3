//! HDF5 output (cargo feature `hdf5`, on the system libhdf5 through hdf5-metno; DESIGN.md
//! §6): one file per run, `fields.vtkhdf`, holding
//!
//! - `/VTKHDF`: the VTKHDF 2.x transient unstructured grid that VTK ≥ 9.3
//!   (`vtkHDFReader`) and ParaView ≥ 5.12 read with every time step. The mesh is
//!   written once (`NumberOf*` have one entry, every `Steps/*Offsets` of the geometry is
//!   0) and each frame appends its point and cell arrays (same names and units as the
//!   `.vtu` frames) to extendible datasets, with `Steps/Values` (time),
//!   `Steps/PointDataOffsets/<name>` and `Steps/CellDataOffsets/<name>` pointing at it
//!   and `Steps@NSteps` updated. `Type` is a fixed-length ASCII string so that older
//!   readers accept the file.
//! - `/history`: the per-step history with the names of `history.csv`: one 1-D
//!   dataset per scalar column (`step`, `time`, `kinetic_energy`, …) and one 2-D dataset
//!   `[rows, m]` per contact quantity (`gap`, `velocity`, `impulse`, `projection`;
//!   column `c` is the CSV's `gap_c`, …); in a frictional scene also
//!   `tangent_impulse` and `slip_velocity` `[rows, m·t]` (column `c·t + j` is the CSV's
//!   `tangent_impulse_c_j`), `status` `[rows, m]` (0 open, 1 stick, 2 slip, 3 closed without friction),
//!   `friction_iterations` and `friction_residual`. Attributes: `scheme`, `dt`, `theta`
//!   and `parameters` (the run's parameters as JSON).
//!
//! Rows are buffered and appended in blocks (at every field frame, every 4096 rows and at
//! the end), then the file is flushed, so a killed run keeps every completed frame and
//! the history up to it. The file is written in place (HDF5 has no atomic rename of a
//! growing file); a run that finishes renames nothing.
//!
//! Every file is created and opened **without HDF5's advisory lock** (`options`).
//! HDF5 opens files without `O_CLOEXEC` and locks them with `flock`, whose lock
//! belongs to the open file description: a child process that any thread of the same
//! program spawns while a file is open (a test, a sweep driver, a Python kernel
//! calling a subprocess) inherits the descriptor and holds the lock until that child
//! exits, and every reader meanwhile fails with `errno = 11` (CI saw it once). The
//! lock protects nothing here: tables are written under a private `.part` name and
//! renamed, and a run's file has one writer that flushes whole frames for readers
//! that look at it mid-run.

use std::path::{Path, PathBuf};

use hdf5::types::{FixedAscii, VarLenUnicode};
use ndarray::{ArrayView1, ArrayView2, s};

use crate::error::Error;
use crate::integrators::{State, StepStats};

mod history;
mod vtkhdf;

pub use history::*;
pub use vtkhdf::*;

fn h5err(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Write {
        path: path.to_path_buf(),
        source: std::io::Error::other(format!("HDF5: {e}")),
    }
}

/// A file builder with HDF5's advisory file lock off (the module doc says why).
pub(crate) fn options() -> hdf5::FileBuilder {
    let mut b = hdf5::File::with_options();
    b.with_fapl(|p| p.file_locking(false));
    b
}

/// The run's HDF5 file, shared by the field and history writers.
#[derive(Clone)]
pub struct RunFile {
    file: hdf5::File,
    path: PathBuf,
}

impl RunFile {
    /// Creates (truncates) `dir/fields.vtkhdf`.
    pub fn create(dir: &Path) -> Result<Self, Error> {
        let path = dir.join("fields.vtkhdf");
        let file = options().create(&path).map_err(|e| h5err(&path, e))?;
        Ok(RunFile { file, path })
    }
    /// Opens the `dir/fields.vtkhdf` of a checkpointed run, to cut its datasets to the
    /// checkpoint and append to them ([`VtkHdf::create`], [`History::create`] with
    /// `reopen`).
    pub fn open(dir: &Path) -> Result<Self, Error> {
        let path = dir.join("fields.vtkhdf");
        let file = options().open_rw(&path).map_err(|e| h5err(&path, e))?;
        Ok(RunFile { file, path })
    }
    /// Path of the file.
    pub fn path(&self) -> &Path {
        &self.path
    }
    fn flush(&self) -> Result<(), Error> {
        self.file.flush().map_err(|e| h5err(&self.path, e))
    }
}

/// An extendible dataset of rows of `cols` values (`cols = 0`: 1-D).
struct Growing {
    ds: hdf5::Dataset,
    cols: usize,
    rows: usize,
}

impl Growing {
    fn create<T: hdf5::H5Type>(
        g: &hdf5::Group,
        name: &str,
        cols: usize,
        chunk_rows: usize,
    ) -> hdf5::Result<Self> {
        let ds = if cols == 0 {
            g.new_dataset::<T>()
                .chunk(chunk_rows.max(1))
                .shape(0..)
                .create(name)?
        } else {
            g.new_dataset::<T>()
                .chunk((chunk_rows.max(1), cols))
                .shape((0.., cols))
                .create(name)?
        };
        Ok(Growing { ds, cols, rows: 0 })
    }
    /// [`Growing::create`], or with `reopen = Some(rows)` the dataset of a checkpointed
    /// run cut to its first `rows` rows (rows written after the checkpoint are dropped:
    /// the resumed run writes them again).
    fn make<T: hdf5::H5Type>(
        g: &hdf5::Group,
        name: &str,
        cols: usize,
        chunk_rows: usize,
        reopen: Option<usize>,
    ) -> hdf5::Result<Self> {
        let Some(rows) = reopen else {
            return Self::create::<T>(g, name, cols, chunk_rows);
        };
        let ds = g.dataset(name)?;
        let have = ds.shape().first().copied().unwrap_or(0);
        if have < rows {
            return Err(hdf5::Error::from(format!(
                "{name} holds {have} rows, fewer than the {rows} of the checkpoint"
            )));
        }
        if cols == 0 {
            ds.resize(rows)?;
        } else {
            ds.resize((rows, cols))?;
        }
        Ok(Growing { ds, cols, rows })
    }

    /// Appends `data` (`k · cols` values, or `k` for 1-D).
    fn append<T: hdf5::H5Type>(&mut self, data: &[T]) -> hdf5::Result<()> {
        let k = data.len().checked_div(self.cols).unwrap_or(data.len());
        if k == 0 {
            return Ok(());
        }
        let (a, b) = (self.rows, self.rows + k);
        if self.cols == 0 {
            self.ds.resize(b)?;
            self.ds.write_slice(ArrayView1::from(data), s![a..b])?;
        } else {
            self.ds.resize((b, self.cols))?;
            let v = ArrayView2::from_shape((k, self.cols), data).expect("whole rows");
            self.ds.write_slice(v, s![a..b, ..])?;
        }
        self.rows = b;
        Ok(())
    }
}
