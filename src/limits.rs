//! Limits a run is checked against before it allocates: step counts, input sizes, header
//! counts of mesh files, and the memory of a run (DESIGN.md §9: "nothing is allocated from
//! an unchecked count; the memory of a run is estimated before it starts").
//!
//! Why our own code: the checks are a handful of comparisons with the messages the
//! project's error contract asks for (file, field, value, expectation); no crate states
//! them in those terms.
//!
//! The memory limit is the machine's total memory (`/proc/meminfo`), or the environment
//! variable `SIGNORINI_MEMORY_LIMIT` (bytes, or with a `K`, `M`, `G` suffix in powers of
//! 1024) when set: a shared machine can hold a run to less.

use std::io::Read;
use std::path::Path;

use crate::error::{Error, num};

/// Largest number of steps a run may take (10⁹: 1.7 hours at the bar's 6 µs per step,
/// 30 years at a 10⁶-dof solid's second per step).
pub const MAX_STEPS: u64 = 1_000_000_000;

/// Largest scene file read (a scene is a page of TOML; 16 MiB leaves room for long
/// time functions and node lists).
pub const MAX_SCENE_BYTES: u64 = 16 << 20;

/// Largest mesh file read (a 10⁶-cell hex8 mesh in ASCII Gmsh is about 200 MB).
pub const MAX_MESH_BYTES: u64 = 4 << 30;

/// Largest FCLIB `.dat` or history file read.
pub const MAX_TEXT_BYTES: u64 = 2 << 30;

/// The number of steps `round(t_end / dt)`, checked: at least 1, at most [`MAX_STEPS`].
/// `t_field` and `dt_field` name the keys or flags for the message.
pub fn step_count(t_end: f64, dt: f64, t_field: &str, dt_field: &str) -> Result<usize, Error> {
    crate::error::require_positive(dt_field, dt)?;
    crate::error::require_positive(t_field, t_end)?;
    let steps = (t_end / dt).round();
    if steps.is_nan() || steps < 1.0 {
        return Err(Error::invalid(
            t_field,
            num(t_end),
            &format!("must be at least one step ({dt_field} = {})", num(dt)),
        ));
    }
    if steps > MAX_STEPS as f64 {
        return Err(Error::invalid(
            dt_field,
            num(dt),
            &format!(
                "{t_field}/{dt_field} = {steps:.3e} steps; at most {MAX_STEPS} are allowed (raise \
                 {dt_field} or lower {t_field})"
            ),
        ));
    }
    Ok(steps as usize)
}

/// Reads an input file of at most `max` bytes. Refuses, naming the file: what is not a
/// regular file (a directory, a FIFO, a device such as `/dev/zero`, which would hang or
/// read forever) and a file larger than `max`.
pub fn read_input(path: &Path, what: &str, max: u64) -> Result<Vec<u8>, Error> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if !meta.is_file() {
        let kind = if meta.is_dir() {
            "a directory"
        } else {
            "not a regular file (a FIFO, socket or device)"
        };
        return Err(Error::bad_file(
            path,
            "",
            format!("is {kind}; expected a {what} file"),
        ));
    }
    if meta.len() > max {
        return Err(Error::bad_file(
            path,
            "",
            format!(
                "is {} bytes; a {what} file may have at most {max} bytes",
                meta.len()
            ),
        ));
    }
    let f = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    // `take` guards against a file that grows while it is read
    f.take(max + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, e))?;
    if bytes.len() as u64 > max {
        return Err(Error::bad_file(
            path,
            "",
            format!("grew past {max} bytes while it was read"),
        ));
    }
    Ok(bytes)
}

/// [`read_input`] as UTF-8 text; the error names the line of the first invalid byte.
pub fn read_text(path: &Path, what: &str, max: u64) -> Result<String, Error> {
    let bytes = read_input(path, what, max)?;
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let line = 1 + e.as_bytes()[..at].iter().filter(|&&b| b == b'\n').count();
        Error::bad_file(
            path,
            format!("line {line}"),
            format!("byte {at} is not UTF-8; expected a {what} text file"),
        )
    })
}

/// Checks a count read from a file header against the bytes left in the file: `count`
/// items of at least `min_bytes` each must fit in `left` bytes. Stops counts such as
/// `POINTS 2000000000` in a 1 kB file before anything is allocated from them.
pub fn check_count(
    path: &Path,
    where_: &str,
    what: &str,
    count: u64,
    min_bytes: u64,
    left: u64,
) -> Result<usize, Error> {
    match count.checked_mul(min_bytes) {
        Some(need) if need <= left && count <= usize::MAX as u64 => Ok(count as usize),
        _ => Err(Error::bad_file(
            path,
            where_,
            format!(
                "{what} count {count} needs at least {} bytes, but {left} bytes are left in the \
                 file (truncated, or a wrong count)",
                if count.checked_mul(min_bytes).is_some() {
                    (count * min_bytes).to_string()
                } else {
                    format!("{count} × {min_bytes}")
                }
            ),
        )),
    }
}

/// An estimate of the memory a run needs, part by part (bytes), checked against the
/// memory limit before the parts are allocated.
#[derive(Clone, Debug, Default)]
pub struct MemoryEstimate {
    parts: Vec<(String, u64)>,
}

impl MemoryEstimate {
    /// Adds a part of `count × bytes_each` bytes (saturating: an absurd count gives an
    /// absurd estimate, never an overflow).
    pub fn add(&mut self, what: impl Into<String>, count: u64, bytes_each: u64) -> &mut Self {
        self.parts
            .push((what.into(), count.saturating_mul(bytes_each)));
        self
    }

    /// The parts: what, bytes.
    pub fn parts(&self) -> &[(String, u64)] {
        &self.parts
    }

    /// The total (bytes, saturating).
    pub fn total(&self) -> u64 {
        self.parts
            .iter()
            .fold(0u64, |a, (_, b)| a.saturating_add(*b))
    }

    /// Refuses when the total exceeds [`memory_limit`], listing the parts; `field` names
    /// what the user can change.
    pub fn check(&self, field: &str, value: impl std::fmt::Display) -> Result<(), Error> {
        let limit = memory_limit_checked()?;
        let total = self.total();
        if total <= limit {
            return Ok(());
        }
        let parts: Vec<String> = self
            .parts
            .iter()
            .filter(|(_, b)| *b > 0)
            .map(|(w, b)| format!("{w} {}", bytes(*b)))
            .collect();
        Err(Error::invalid(
            field,
            value,
            &format!(
                "the run would need at least {} ({}), more than the memory limit {} \
                 (the machine's memory, or SIGNORINI_MEMORY_LIMIT)",
                bytes(total),
                parts.join(", "),
                bytes(limit)
            ),
        ))
    }
}

/// What the process itself holds before any model (binary, libraries, threads): the
/// built-in bar's whole process peaks at 7.5 MiB with a model of 0.5 MiB. Counted in
/// every run's ledger.
pub const PROCESS_BYTES: u64 = 8 << 20;

/// Peak resident memory of this process (bytes): `VmHWM` of `/proc/self/status`
/// (Linux); `None` where it cannot be read.
pub fn peak_memory() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Resets the peak resident memory [`peak_memory`] reads to the current resident size
/// (Linux ≥ 4.0: `5` written to `/proc/self/clear_refs`), so that the runs of a sweep
/// each report their own peak; `false` where it cannot.
pub fn reset_peak_memory() -> bool {
    std::fs::write("/proc/self/clear_refs", b"5").is_ok()
}

/// A byte count as `12.3 GiB`.
pub fn bytes(b: u64) -> String {
    let b = b as f64;
    if b >= (1u64 << 60) as f64 {
        format!("{:.3e} bytes", b)
    } else if b >= (1u64 << 30) as f64 {
        format!("{:.1} GiB", b / (1u64 << 30) as f64)
    } else if b >= (1u64 << 20) as f64 {
        format!("{:.1} MiB", b / (1u64 << 20) as f64)
    } else {
        format!("{:.0} KiB", (b / 1024.0).ceil())
    }
}

/// The memory a run may use (bytes): `SIGNORINI_MEMORY_LIMIT` when set (refused when
/// not valid: [`memory_limit_setting`], which every command checks first), else the
/// machine's total memory, else 16 GiB.
pub fn memory_limit() -> u64 {
    memory_limit_checked().unwrap_or_else(|_| machine_memory())
}

/// [`memory_limit`], or the error of a `SIGNORINI_MEMORY_LIMIT` that is not valid.
pub fn memory_limit_checked() -> Result<u64, Error> {
    Ok(memory_limit_setting()?.unwrap_or_else(machine_memory))
}

/// The machine's total memory (`/proc/meminfo`), else 16 GiB.
fn machine_memory() -> u64 {
    std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("MemTotal:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|k| k.parse::<u64>().ok())
        })
        .map(|kib| kib.saturating_mul(1024))
        .unwrap_or(16 << 30)
}

/// `SIGNORINI_MEMORY_LIMIT`, parsed strictly: `None` when unset; an error naming the
/// variable, its value and the accepted forms when it is not a positive whole number
/// of bytes, optionally with a `K`, `M`, `G` or `T` suffix (powers of 1024, also written
/// `KiB` … `TiB`), or when it overflows. Before issue 34, `lots`, `-1G`, `2GB` and
/// overflowing values were ignored silently.
pub fn memory_limit_setting() -> Result<Option<u64>, Error> {
    match std::env::var("SIGNORINI_MEMORY_LIMIT") {
        Err(std::env::VarError::NotPresent) => Ok(None),
        Err(std::env::VarError::NotUnicode(v)) => Err(bad_limit(&v.to_string_lossy())),
        Ok(s) => parse_bytes(&s).map(Some).ok_or_else(|| bad_limit(&s)),
    }
}

fn bad_limit(value: &str) -> Error {
    Error::invalid(
        "SIGNORINI_MEMORY_LIMIT",
        format!("{value:?}"),
        "must be a whole number of bytes > 0, optionally with a suffix K, M, G or T \
         (powers of 1024; also KiB, MiB, GiB, TiB), below 16 EiB: e.g. 512M or 2G \
         (`GB`, decimal or binary, is not taken)",
    )
}

/// `123`, `64K`, `512M`, `2G`, `1T`, `2GiB` (powers of 1024); `None` for anything else,
/// zero, or a value past `u64`.
fn parse_bytes(s: &str) -> Option<u64> {
    let s = s.trim();
    let split = s.find(|c: char| !c.is_ascii_digit()).unwrap_or(s.len());
    let (digits, unit) = s.split_at(split);
    if digits.is_empty() {
        return None;
    }
    let mult: u64 = match unit.trim() {
        "" => 1,
        "K" | "k" | "KiB" => 1 << 10,
        "M" | "m" | "MiB" => 1 << 20,
        "G" | "g" | "GiB" => 1 << 30,
        "T" | "t" | "TiB" => 1 << 40,
        _ => return None,
    };
    digits
        .parse::<u64>()
        .ok()?
        .checked_mul(mult)
        .filter(|&v| v > 0)
}

/// Bytes per degree of freedom of the assembled sparse matrices and the vectors of a
/// step, for a mesh whose nodes have about `neighbours` neighbours (itself included):
/// `M`, `K` and `M̂` in CSC (value and row index, 16 bytes an entry, `neighbours × dim`
/// entries a column) and about 40 vectors of the dofs (state, forecasts, work arrays,
/// frame snapshots). A lower bound: the Cholesky factor is checked when its size is
/// known, after the symbolic analysis.
pub fn bytes_per_dof(neighbours: u64, dim: u64) -> u64 {
    3 * 16 * neighbours * dim + 40 * 8
}

/// The memory of a mesh of `nodes` nodes and `cells` cells of `nodes_per_cell` nodes in
/// `dim` dimensions, assembled (see [`bytes_per_dof`]; about 27 neighbours a node in 3-D,
/// 9 in 2-D, 3 on a rod), for a check before the mesh is generated or assembled.
pub fn mesh_memory(nodes: u64, cells: u64, nodes_per_cell: u64, dim: u64) -> MemoryEstimate {
    let neighbours = match dim {
        1 => 3,
        2 => 9,
        _ => 27,
    };
    let mut m = MemoryEstimate::default();
    m.add("nodes", nodes, 24 + 24);
    m.add("cells", cells, 2 * (24 + 8 * nodes_per_cell));
    m.add(
        "assembled dofs",
        nodes.saturating_mul(dim),
        bytes_per_dof(neighbours, dim),
    );
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn step_counts_are_capped() {
        assert_eq!(step_count(1e-3, 1e-6, "t", "dt").unwrap(), 1000);
        for (t, dt) in [(1e30, 1e-3), (1.0, 1e-300), (1e10, 1e-7)] {
            let e = step_count(t, dt, "t_end", "dt").unwrap_err().to_string();
            assert!(e.contains("at most 1000000000"), "{e}");
            assert!(e.len() < 300, "short message: {e}");
        }
        assert!(step_count(1e-9, 1e-3, "t", "dt").is_err());
        assert!(step_count(f64::NAN, 1e-3, "t", "dt").is_err());
    }

    #[test]
    fn counts_must_fit_the_file() {
        let p = Path::new("m.vtk");
        assert_eq!(check_count(p, "line 5", "POINTS", 10, 12, 120).unwrap(), 10);
        let e = check_count(p, "line 5", "POINTS", 2_000_000_000, 12, 1000).unwrap_err();
        assert!(e.to_string().contains("m.vtk:line 5"), "{e}");
        assert!(check_count(p, "", "CELLS", u64::MAX / 2, 4, 1000).is_err());
    }

    #[test]
    fn byte_sizes_parse_and_print() {
        assert_eq!(parse_bytes("2G"), Some(2 << 30));
        assert_eq!(parse_bytes("512m"), Some(512 << 20));
        assert_eq!(parse_bytes("x"), None);
        assert_eq!(parse_bytes("2GiB"), Some(2 << 30));
        assert_eq!(parse_bytes(" 1T "), Some(1 << 40));
        assert_eq!(parse_bytes("123"), Some(123));
        // issue 34: each of these was ignored silently
        for bad in [
            "lots",
            "-1G",
            "2GB",
            "99999999999999999999",
            "16777216T",
            "0",
            "",
            "1.5G",
            "G",
        ] {
            assert_eq!(parse_bytes(bad), None, "{bad:?}");
        }
        assert_eq!(bytes(3 << 30), "3.0 GiB");
        let mut m = MemoryEstimate::default();
        m.add("dofs", u64::MAX, 8);
        assert_eq!(m.total(), u64::MAX);
        assert!(m.check("elements", 1).is_err());
    }
}
