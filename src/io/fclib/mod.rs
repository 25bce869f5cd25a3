//! Readers of one-step frictional contact problems: FCLIB's HDF5 files (Acary, Brémond,
//! Koziara, Pérignon, INRIA RT-0444, 2014; layout of `fclib.h`), local and global, and
//! Siconos' `.dat` text files (2-D and 3-D), into the dense local form
//! `u = W r + q`, `C* ∋ û ⊥ r ∈ C` that [`crate::solvers::friction`] solves.
//!
//! - Local problems (`/fclib_local`): `W` sparse (CSC `nz = −1`, CSR `nz = −2` or
//!   triplets `nz ≥ 0`; triplets store `i` = row and `p` = column, CSparse's convention,
//!   whatever `fclib.h`'s comment says), `q`, `μ`, `spacedim`.
//! - Global problems (`/fclib_global`): `M v = H r + f`, `u = Hᵀ v + w`, condensed here to
//!   `W = Hᵀ M⁻¹ H`, `q = Hᵀ M⁻¹ f + w` with a dense LU of `M` (faer), because LMGC90's
//!   `M` is not always symmetric (the Cholesky of the time-stepping path would not do).
//! - `.dat`: `d`, the contact count, a NumericsMatrix — dense (storage 0: sizes, sizes
//!   again, values column by column) or sparse-block (storage 1, Siconos'
//!   `SBM_write_in_file`: blocks of at most 3×3 with compressed block rows) —, `q`, `μ`, and at most one trailing flag (0 or 1,
//!   written by older Siconos versions) — whitespace-separated tokens; anything more is
//!   refused, as are problems with no contacts, `μ` above [`MAX_MU`], entries above
//!   [`MAX_ENTRY`] and a contact with `W_NN ≤ 0`.
//!
//! The contact frame is (N, T1, T2), as ours. `/guesses/1/{r, u}` is kept as a warm start
//! when present; `/solution` groups are placeholders in the files we know and are
//! ignored. Counts are checked against the file before anything is allocated, and the
//! dense `W` is limited to [`MAX_ROWS`] rows (2 GiB).

use std::path::Path;

use crate::error::Error;
use crate::solvers::friction::Measure;

mod dat;
mod solve;

pub use dat::*;
pub use solve::*;

/// Largest problem (rows of `W`) read into dense storage: 16384² values = 2 GiB.
pub const MAX_ROWS: usize = 16384;
/// Largest friction coefficient read (as in scenes: `contact::check_friction`).
pub const MAX_MU: f64 = 1e6;
/// Largest magnitude of an entry of `W` or `q`.
pub const MAX_ENTRY: f64 = 1e150;
/// Tolerance of `signorini fclib` (and of the Python `fclib.solve`) when none is given:
/// Siconos' relative residual at 1e-8, as FCLIB's results are compared.
pub const DEFAULT_TOL: f64 = 1e-8;
/// Cap on NSGS sweeps of `signorini fclib` when none is given.
pub const DEFAULT_MAX_ITERATIONS: usize = 20000;

/// Largest global problem (rows of `M`) condensed: `M` is read sparse, factored by a
/// sparse LU, and only `M⁻¹ H` is dense.
pub const MAX_GLOBAL_DOFS: usize = 1 << 22;
/// Largest `.dat` file read (bytes).
const MAX_DAT_BYTES: u64 = 1 << 30;

/// A one-step frictional contact problem in local (condensed) form.
#[derive(Clone, Debug)]
pub struct FrictionContactProblem {
    /// Space dimension: rows per contact (2 or 3).
    pub dim: usize,
    /// `W`, dense column-major `n × n` (`n = dim × contacts`).
    pub w: Vec<f64>,
    /// `q` (n values).
    pub q: Vec<f64>,
    /// `μ` per contact.
    pub mu: Vec<f64>,
    /// A warm start `r` from the file (`/guesses/1/r`), if any.
    pub guess: Option<Vec<f64>>,
    /// "local", "global (condensed)" or "dat".
    pub form: &'static str,
    /// `max |W − Wᵀ| / max |W|`.
    pub asymmetry: f64,
}

impl FrictionContactProblem {
    /// Number of contacts.
    pub fn contacts(&self) -> usize {
        self.mu.len()
    }
    /// Rows `n`.
    pub fn rows(&self) -> usize {
        self.q.len()
    }

    /// A local problem from arrays (`W` column-major `n × n`, `q`, `μ` per contact, `n =
    /// dim × contacts`), checked as a file's would be; `what` names the source in errors
    /// (the Python package's `fclib.solve`).
    pub fn from_arrays(
        dim: usize,
        w: Vec<f64>,
        q: Vec<f64>,
        mu: Vec<f64>,
        guess: Option<Vec<f64>>,
        what: &str,
    ) -> Result<Self, Error> {
        FrictionContactProblem {
            dim,
            w,
            q,
            mu,
            guess,
            form: "local",
            asymmetry: 0.0,
        }
        .finish(Path::new(what))
    }

    fn finish(mut self, path: &Path) -> Result<Self, Error> {
        let n = self.q.len();
        let at = |what: &str, reason: String| {
            Error::invalid(&format!("{}: {what}", path.display()), "", &reason)
        };
        if !(self.dim == 2 || self.dim == 3) {
            return Err(at("spacedim", format!("is {}, expected 2 or 3", self.dim)));
        }
        if n != self.dim * self.mu.len() || self.w.len() != n * n {
            return Err(at(
                "sizes",
                format!(
                    "q has {n} values, μ {} and W {} for dimension {}: expected q of d·contacts and W of its square",
                    self.mu.len(),
                    self.w.len(),
                    self.dim
                ),
            ));
        }
        if self.mu.is_empty() {
            return Err(at(
                "contacts",
                "there are none: expected at least one contact to solve for".into(),
            ));
        }
        if let Some(i) = self.w.iter().position(|x| !x.is_finite()) {
            return Err(at(
                "W",
                format!("entry {i} is {} (must be finite)", self.w[i]),
            ));
        }
        if let Some(i) = self.q.iter().position(|x| !x.is_finite()) {
            return Err(at(
                "q",
                format!("entry {i} is {} (must be finite)", self.q[i]),
            ));
        }
        if let Some(i) = self.mu.iter().position(|x| !(x.is_finite() && *x >= 0.0)) {
            return Err(at(
                "mu",
                format!("entry {i} is {} (must be ≥ 0)", self.mu[i]),
            ));
        }
        if let Some(i) = self.mu.iter().position(|x| *x > MAX_MU) {
            return Err(at(
                "mu",
                format!(
                    "entry {i} is {:e}: expected at most {MAX_MU:e}, the range the friction \
                     solvers are checked on (scenes take the same)",
                    self.mu[i]
                ),
            ));
        }
        // the residual squares the data: beyond 1e150 its norms overflow
        for (name, v) in [("W", &self.w), ("q", &self.q)] {
            if let Some(i) = v.iter().position(|x| x.abs() > MAX_ENTRY) {
                return Err(at(
                    name,
                    format!(
                        "entry {i} is {:e}: expected magnitudes up to {MAX_ENTRY:e} (the \
                         residual squares them); rescale the problem",
                        v[i]
                    ),
                ));
            }
        }
        for a in 0..self.mu.len() {
            let o = a * self.dim;
            let wnn = self.w[o + o * n];
            if wnn <= 0.0 {
                return Err(at(
                    "W",
                    format!(
                        "contact {a}: W_NN = W[{o},{o}] is {wnn:e}, expected > 0 (a contact's \
                         own compliance Hᵀ M⁻¹ H is positive; zero means it moves no mass)"
                    ),
                ));
            }
            // read without the flush (issue 48: 1e-320 was refused as "is 0e0, expected
            // > 0"), but the solve flushes subnormals: such a W_NN would be 0 there
            if wnn < f64::MIN_POSITIVE
                && crate::linalg::subnormals() == crate::linalg::Subnormals::Flushed
            {
                return Err(at(
                    "W",
                    format!(
                        "contact {a}: W_NN = W[{o},{o}] is {wnn:e}, positive but subnormal \
                         (below {:e}), which the solve flushes to 0: rescale the problem, or \
                         keep subnormals with --ieee-subnormals",
                        f64::MIN_POSITIVE
                    ),
                ));
            }
        }
        let wmax = self.w.iter().fold(0.0_f64, |s, x| s.max(x.abs()));
        let mut asym: f64 = 0.0;
        for j in 0..n {
            for i in 0..j {
                asym = asym.max((self.w[i + j * n] - self.w[j + i * n]).abs());
            }
        }
        self.asymmetry = if wmax > 0.0 { asym / wmax } else { 0.0 };
        if let Some(g) = &self.guess
            && (g.len() != n || g.iter().any(|x| !x.is_finite()))
        {
            self.guess = None;
        }
        Ok(self)
    }
}

/// Reads a problem by its extension: `.dat` (Siconos text), `.hdf5`/`.h5` (FCLIB; needs
/// the `hdf5` feature).
pub fn read(path: &Path) -> Result<FrictionContactProblem, Error> {
    match path.extension().and_then(|e| e.to_str()) {
        Some("dat") => read_dat(path),
        Some("hdf5" | "h5") => read_hdf5(path),
        other => Err(Error::invalid(
            &path.display().to_string(),
            other.map_or_else(|| "no extension".to_string(), |e| format!(".{e}")),
            "unknown extension: expected .dat (Siconos) or .hdf5/.h5 (FCLIB)",
        )),
    }
}

/// Reads Siconos' `.dat` text format (module doc).
pub fn read_dat(path: &Path) -> Result<FrictionContactProblem, Error> {
    let text = crate::limits::read_text(path, "Siconos .dat", MAX_DAT_BYTES)?;
    parse_dat(path, &text)
}

#[cfg(not(feature = "hdf5"))]
/// FCLIB HDF5 files need the `hdf5` feature.
pub fn read_hdf5(path: &Path) -> Result<FrictionContactProblem, Error> {
    Err(Error::invalid(
        &path.display().to_string(),
        "HDF5",
        "FCLIB files need the `hdf5` feature (cargo build --release --features hdf5, with libhdf5-dev)",
    ))
}

#[cfg(feature = "hdf5")]
/// Reads an FCLIB HDF5 file, local or global (condensed; module doc).
pub fn read_hdf5(path: &Path) -> Result<FrictionContactProblem, Error> {
    hdf5_impl::read(path)
}

#[cfg(feature = "hdf5")]
mod hdf5_impl;
