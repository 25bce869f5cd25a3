//! Output writers: the per-step history (`history.csv`) and the run summary
//! (`summary.json`), the contract of DESIGN.md §6 and issue 2.
//!
//! Files are written next to their final name (`NAME.part`), flushed as the run goes,
//! and renamed into place when complete, so a killed run never leaves a truncated file
//! under the final name and keeps every flushed row in the `.part` file.

pub mod mesh;

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::error::Error;
use crate::integrators::{State, StepStats};

/// Writes `bytes` to `path` atomically (write `path.part`, flush, sync, rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    let tmp = part_path(path);
    let mut f = File::create(&tmp).map_err(|e| Error::io(&tmp, e))?;
    f.write_all(bytes).map_err(|e| Error::io(&tmp, e))?;
    f.sync_all().map_err(|e| Error::io(&tmp, e))?;
    std::fs::rename(&tmp, path).map_err(|e| Error::io(path, e))
}

fn part_path(path: &Path) -> PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push(".part");
    PathBuf::from(s)
}

/// Streams one CSV row per step; see the module doc for the file protocol.
pub struct HistoryWriter {
    out: BufWriter<File>,
    tmp: PathBuf,
    path: PathBuf,
    rows_since_flush: usize,
}

impl HistoryWriter {
    /// Rows buffered before an explicit flush.
    const FLUSH_EVERY: usize = 4096;

    /// Creates `path.part` and writes the header for `m` contacts.
    pub fn create(path: &Path, m: usize) -> Result<Self, Error> {
        let tmp = part_path(path);
        let f = File::create(&tmp).map_err(|e| Error::io(&tmp, e))?;
        let mut out = BufWriter::with_capacity(1 << 16, f);
        let mut header = String::from(
            "step,time,kinetic_energy,potential_energy,max_violation,newton_iterations,\
             projection_iterations,index_set_iterations",
        );
        for c in 0..m {
            header.push_str(&format!(",gap_{c},velocity_{c},impulse_{c},projection_{c}"));
        }
        writeln!(out, "{header}").map_err(|e| Error::io(&tmp, e))?;
        Ok(HistoryWriter {
            out,
            tmp,
            path: path.to_path_buf(),
            rows_since_flush: 0,
        })
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
        let r = (|| -> std::io::Result<()> {
            write!(
                o,
                "{},{},{},{},{},{},{},{}",
                state.step,
                state.time,
                kinetic,
                potential,
                stats.max_violation,
                stats.newton_iterations,
                stats.projection_iterations,
                stats.index_set_iterations
            )?;
            for c in 0..state.gap.len() {
                write!(
                    o,
                    ",{},{},{},{}",
                    state.gap[c], state.local_velocity[c], state.impulse[c], state.projection[c]
                )?;
            }
            writeln!(o)
        })();
        r.map_err(|e| Error::io(&self.tmp, e))?;
        self.rows_since_flush += 1;
        if self.rows_since_flush >= Self::FLUSH_EVERY {
            self.out.flush().map_err(|e| Error::io(&self.tmp, e))?;
            self.rows_since_flush = 0;
        }
        Ok(())
    }

    /// Flushes, syncs and renames the file into place.
    pub fn finish(mut self) -> Result<(), Error> {
        self.out.flush().map_err(|e| Error::io(&self.tmp, e))?;
        self.out
            .get_ref()
            .sync_all()
            .map_err(|e| Error::io(&self.tmp, e))?;
        std::fs::rename(&self.tmp, &self.path).map_err(|e| Error::io(&self.path, e))
    }
}
