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

/// Parses the text of a `.dat` problem; `path` names the file in errors.
pub fn parse_dat(path: &Path, text: &str) -> Result<FrictionContactProblem, Error> {
    let mut tok = text.split_whitespace().enumerate();
    let file = path.display().to_string();
    let mut next = |what: &str| -> Result<&str, Error> {
        tok.next().map(|(_, t)| t).ok_or_else(|| {
            Error::invalid(&file, "end of file", &format!("truncated: expected {what}"))
        })
    };
    let int = |t: &str, what: &str| -> Result<usize, Error> {
        t.parse::<usize>().map_err(|_| {
            Error::invalid(
                &format!("{}: {what}", path.display()),
                t,
                "expected a non-negative integer",
            )
        })
    };
    let real = |t: &str, what: &str| -> Result<f64, Error> {
        t.parse::<f64>().map_err(|_| {
            Error::invalid(
                &format!("{}: {what}", path.display()),
                t,
                "expected a number",
            )
        })
    };
    let dim = int(next("the dimension")?, "dimension")?;
    if !(dim == 2 || dim == 3) {
        return Err(Error::invalid(
            &format!("{}: dimension", path.display()),
            dim,
            "expected 2 or 3 (spacedim)",
        ));
    }
    let nc = int(next("the contact count")?, "contact count")?;
    let storage = int(next("the matrix storage type")?, "storage type")?;
    if storage > 1 {
        return Err(Error::invalid(
            &format!("{}: storage type", path.display()),
            storage,
            "only dense (0) and sparse-block (1) matrices are read (2, CSparse's print, \
             rounds the values to 6 digits)",
        ));
    }
    let s0 = int(next("the matrix rows")?, "matrix rows")?;
    let s1 = int(next("the matrix columns")?, "matrix columns")?;
    let n = nc.saturating_mul(dim);
    let size_err = |got: String| {
        Error::invalid(
            &format!("{}: matrix size", path.display()),
            got,
            &format!("expected {n}×{n} for {nc} contacts in dimension {dim}"),
        )
    };
    if s0 != n || s1 != n {
        return Err(size_err(format!("{s0}×{s1}")));
    }
    // dense: every value needs at least two bytes (digit and separator); sparse-block:
    // q and μ must be in the file, and the dense copy of W may not exceed 100 bytes
    // of W per byte of file (64 MiB at least)
    let dense_needed = if storage == 0 { n.saturating_mul(n) } else { 0 };
    let needed = dense_needed.saturating_add(n).saturating_add(nc);
    let dense_bytes = (n as u64).saturating_mul(n as u64).saturating_mul(8);
    if n > MAX_ROWS
        || needed.saturating_mul(2) as u64 > text.len() as u64
        || (storage == 1 && dense_bytes > (100 * text.len() as u64).max(64 << 20))
    {
        return Err(Error::invalid(
            &format!("{}: contact count", path.display()),
            nc,
            &format!(
                "needs {needed} values and a {n}×{n} dense W, more than the file holds (or \
                 than {MAX_ROWS} dense rows)"
            ),
        ));
    }
    let mut w = vec![0.0; n * n];
    if storage == 0 {
        let r0 = int(next("the matrix rows (repeated)")?, "matrix rows")?;
        let r1 = int(next("the matrix columns (repeated)")?, "matrix columns")?;
        if r0 != n || r1 != n {
            return Err(size_err(format!("{s0}×{s1} ({r0}×{r1})")));
        }
        for (k, x) in w.iter_mut().enumerate() {
            *x = real(next("W values")?, &format!("W value {k}"))?;
        }
    } else {
        // Siconos' SparseBlockStructuredMatrix as SBM_write_in_file prints it: block
        // count, block rows and columns, cumulative block sizes of each, the compressed
        // block-row pointers and block-column indices, then each block's number and its
        // values column by column
        let at = |what: &str| format!("{}: sparse-block {what}", path.display());
        let bad = |what: &str, got: String, want: String| Error::invalid(&at(what), got, &want);
        let nblocks = int(next("the block count")?, "block count")?;
        if nblocks > 0 {
            let nbr = int(next("the block-row count")?, "block-row count")?;
            let nbc = int(next("the block-column count")?, "block-column count")?;
            if nbr == 0 || nbr > n || nbc == 0 || nbc > n {
                return Err(bad(
                    "block rows and columns",
                    format!("{nbr}, {nbc}"),
                    format!("expected 1..={n} each"),
                ));
            }
            let mut sizes = [Vec::new(), Vec::new()];
            for (side, count) in [(0, nbr), (1, nbc)] {
                let mut prev = 0;
                for b in 0..count {
                    let end = int(next("block sizes")?, "block size")?;
                    if end <= prev || end > n || end - prev > 3 {
                        return Err(bad(
                            "block sizes",
                            format!("{end} after {prev}"),
                            format!("cumulative ends rising by 1 to 3 up to {n}"),
                        ));
                    }
                    sizes[side].push(end);
                    prev = end;
                    if b + 1 == count && end != n {
                        return Err(bad("block sizes", end.to_string(), format!("last = {n}")));
                    }
                }
            }
            let filled1 = int(next("filled1")?, "filled1")?;
            let filled2 = int(next("filled2")?, "filled2")?;
            if filled1 != nbr + 1 || filled2 != nblocks || nblocks > nbr.saturating_mul(nbc) {
                return Err(bad(
                    "counts",
                    format!("filled1 {filled1}, filled2 {filled2}, {nblocks} blocks"),
                    format!("filled1 = {} and filled2 = the block count", nbr + 1),
                ));
            }
            let mut rowptr = Vec::with_capacity(filled1);
            for _ in 0..filled1 {
                let p = int(next("block-row pointers")?, "block-row pointer")?;
                if p > nblocks || rowptr.last().is_some_and(|&l| p < l) {
                    return Err(bad(
                        "block-row pointers",
                        p.to_string(),
                        format!("non-decreasing up to {nblocks}"),
                    ));
                }
                rowptr.push(p);
            }
            if rowptr[0] != 0 || rowptr[nbr] != nblocks {
                return Err(bad(
                    "block-row pointers",
                    format!("{}..{}", rowptr[0], rowptr[nbr]),
                    format!("0..{nblocks}"),
                ));
            }
            let mut colidx = Vec::with_capacity(filled2);
            for _ in 0..filled2 {
                let c = int(next("block-column indices")?, "block-column index")?;
                if c >= nbc {
                    return Err(bad(
                        "block-column indices",
                        c.to_string(),
                        format!("< {nbc}"),
                    ));
                }
                colidx.push(c);
            }
            for br in 0..nbr {
                let (r0, r1) = (if br == 0 { 0 } else { sizes[0][br - 1] }, sizes[0][br]);
                for blk in rowptr[br]..rowptr[br + 1] {
                    let num = int(next("a block number")?, "block number")?;
                    if num != blk {
                        return Err(bad(
                            "block number",
                            num.to_string(),
                            format!("{blk} (blocks in order)"),
                        ));
                    }
                    let bc = colidx[blk];
                    let (c0, c1) = (if bc == 0 { 0 } else { sizes[1][bc - 1] }, sizes[1][bc]);
                    for c in c0..c1 {
                        for row in r0..r1 {
                            w[row + c * n] =
                                real(next("block values")?, &format!("block {blk} value"))?;
                        }
                    }
                }
            }
        }
    }
    let mut q = vec![0.0; n];
    for (k, x) in q.iter_mut().enumerate() {
        *x = real(next("q values")?, &format!("q value {k}"))?;
    }
    let mut mu = vec![0.0; nc];
    for (k, x) in mu.iter_mut().enumerate() {
        *x = real(next("μ values")?, &format!("mu value {k}"))?;
    }
    // older Siconos writers end the file with one flag, 0 or 1
    // (FrictionContactProblem00394.dat, Rover4609.dat, FC3D_Example1.dat): allowed once
    let mut rest = tok.peekable();
    if rest.peek().is_some_and(|(_, t)| *t == "0" || *t == "1") {
        rest.next();
    }
    if let Some((i, t)) = rest.next() {
        return Err(Error::invalid(
            &format!("{}: token {}", path.display(), i + 1),
            t,
            "is past the end of the problem (after the μ values and an optional 0/1 flag): \
             expected end of file",
        ));
    }
    FrictionContactProblem {
        dim,
        w,
        q,
        mu,
        guess: None,
        form: "dat",
        asymmetry: 0.0,
    }
    .finish(path)
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
mod hdf5_impl {
    use super::*;

    fn h5err(path: &Path, what: &str, e: impl std::fmt::Display) -> Error {
        Error::invalid(
            &format!("{}: {what}", path.display()),
            "",
            &format!("cannot be read: {e}"),
        )
    }

    fn ints(f: &hdf5::File, path: &Path, name: &str) -> Result<Vec<i64>, Error> {
        f.dataset(name)
            .and_then(|d| d.read_raw::<i64>())
            .map_err(|e| h5err(path, name, e))
    }
    fn int(f: &hdf5::File, path: &Path, name: &str) -> Result<i64, Error> {
        ints(f, path, name)?
            .first()
            .copied()
            .ok_or_else(|| h5err(path, name, "empty"))
    }
    fn reals(f: &hdf5::File, path: &Path, name: &str) -> Result<Vec<f64>, Error> {
        f.dataset(name)
            .and_then(|d| d.read_raw::<f64>())
            .map_err(|e| h5err(path, name, e))
    }

    /// A sparse matrix of the file: its sizes and its entries as (row, column, value)
    /// triplets (duplicates to be summed).
    fn triplets(f: &hdf5::File, path: &Path, g: &str, limit: usize) -> Result<Sparse, Error> {
        let at = |k: &str| format!("{g}/{k}");
        let m = int(f, path, &at("m"))?;
        let n = int(f, path, &at("n"))?;
        let nz = int(f, path, &at("nz"))?;
        let bad = |what: String| Error::invalid(&format!("{}: {g}", path.display()), "", &what);
        if m < 0 || n < 0 || m as u64 > limit as u64 || n as u64 > limit as u64 {
            return Err(bad(format!(
                "size {m}×{n}: expected 0..={limit} rows and columns"
            )));
        }
        let (m, n) = (m as usize, n as usize);
        let p = ints(f, path, &at("p"))?;
        let i = ints(f, path, &at("i"))?;
        let x = reals(f, path, &at("x"))?;
        let mut a = Vec::with_capacity(x.len());
        let idx = |v: i64, lim: usize, what: &str| -> Result<usize, Error> {
            if v < 0 || v as u64 >= lim as u64 {
                Err(bad(format!("{what} index {v} outside 0..{lim}")))
            } else {
                Ok(v as usize)
            }
        };
        match nz {
            -1 | -2 => {
                // compressed: p over the major dimension
                let major = if nz == -1 { n } else { m };
                let minor = if nz == -1 { m } else { n };
                if p.len() < major + 1 {
                    return Err(bad(format!(
                        "p has {} entries, expected {}",
                        p.len(),
                        major + 1
                    )));
                }
                for c in 0..major {
                    let (s, e) = (p[c], p[c + 1]);
                    if s < 0 || e < s || e as u64 > i.len().min(x.len()) as u64 {
                        return Err(bad(format!(
                            "p[{c}..{}] = {s}..{e} is not a valid range",
                            c + 1
                        )));
                    }
                    for k in s as usize..e as usize {
                        let r = idx(i[k], minor, "minor")?;
                        let (row, col) = if nz == -1 { (r, c) } else { (c, r) };
                        a.push((row, col, x[k]));
                    }
                }
            }
            nz if nz >= 0 => {
                let nz = nz as usize;
                if i.len() < nz || p.len() < nz || x.len() < nz {
                    return Err(bad(format!("{nz} triplets but shorter i, p or x")));
                }
                for k in 0..nz {
                    // CSparse triplets: i = row, p = column
                    let row = idx(i[k], m, "row")?;
                    let col = idx(p[k], n, "column")?;
                    a.push((row, col, x[k]));
                }
            }
            other => return Err(bad(format!("nz = {other}: expected −1, −2 or ≥ 0"))),
        }
        Ok(Sparse {
            rows: m,
            cols: n,
            entries: a,
        })
    }

    /// A matrix read from the file, as triplets.
    struct Sparse {
        rows: usize,
        cols: usize,
        entries: Vec<(usize, usize, f64)>,
    }

    impl Sparse {
        /// Dense column-major copy (the caller bounds the size).
        fn dense(&self) -> Vec<f64> {
            let mut a = vec![0.0; self.rows * self.cols];
            for &(i, j, v) in &self.entries {
                a[i + j * self.rows] += v;
            }
            a
        }
    }

    /// `W = Hᵀ M⁻¹ H`, `q = Hᵀ M⁻¹ f + w` with faer's sparse LU of `M` (partial
    /// pivoting: LMGC90's `M` is not always symmetric). A dense LU of Siconos'
    /// Spheres-i099-356-679 (`M` of 12 000 rows, diagonal) would need 1.2 GB and 1e12
    /// flops; the sparse one is instant there and exact on the others.
    fn condense(
        path: &Path,
        mm: &Sparse,
        hh: &Sparse,
        fv: &[f64],
        wv: &[f64],
    ) -> Result<(Vec<f64>, Vec<f64>), Error> {
        use faer::linalg::solvers::Solve;
        use faer::sparse::{SparseColMat, Triplet};
        let (n, m) = (mm.rows, hh.cols);
        let trip: Vec<Triplet<usize, usize, f64>> = mm
            .entries
            .iter()
            .map(|&(i, j, v)| Triplet::new(i, j, v))
            .collect();
        let singular = |what: String| {
            Error::invalid(
                &format!("{}: fclib_global/M", path.display()),
                format!("{n}×{n}"),
                &format!("cannot be factored ({what}): expected an invertible mass matrix"),
            )
        };
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &trip)
            .map_err(|e| singular(format!("{e}")))?;
        let lu = a.sp_lu().map_err(|e| singular(format!("{e}")))?;
        // X = M⁻¹ [H f]
        let mut x = faer::Mat::<f64>::zeros(n, m + 1);
        for &(i, j, v) in &hh.entries {
            x[(i, j)] += v;
        }
        for (i, &fi) in fv.iter().enumerate() {
            x[(i, m)] = fi;
        }
        lu.solve_in_place(x.as_mut());
        if (0..m + 1).any(|j| x.col(j).iter().any(|v| !v.is_finite())) {
            return Err(singular("non-finite solve".into()));
        }
        // W = Hᵀ X (H sparse: column a of H meets every column of X)
        let mut w = vec![0.0; m * m];
        let mut q = wv.to_vec();
        for &(k, a_, v) in &hh.entries {
            for b in 0..m {
                w[a_ + b * m] += v * x[(k, b)];
            }
            q[a_] += v * x[(k, m)];
        }
        Ok((w, q))
    }

    pub(super) fn read(path: &Path) -> Result<FrictionContactProblem, Error> {
        let f = hdf5::File::open(path).map_err(|e| h5err(path, "file", e))?;
        let guess = if f.link_exists("guesses/1/r") {
            reals(&f, path, "guesses/1/r").ok()
        } else {
            None
        };
        if f.link_exists("fclib_local") {
            let dim = int(&f, path, "fclib_local/spacedim")?;
            let wm = triplets(&f, path, "fclib_local/W", MAX_ROWS)?;
            let (m, n, w) = (wm.rows, wm.cols, wm.dense());
            if m != n {
                return Err(Error::invalid(
                    &format!("{}: fclib_local/W", path.display()),
                    format!("{m}×{n}"),
                    "must be square",
                ));
            }
            return FrictionContactProblem {
                dim: dim.max(0) as usize,
                w,
                q: reals(&f, path, "fclib_local/vectors/q")?,
                mu: reals(&f, path, "fclib_local/vectors/mu")?,
                guess,
                form: "local",
                asymmetry: 0.0,
            }
            .finish(path);
        }
        if f.link_exists("fclib_global") {
            let dim = int(&f, path, "fclib_global/spacedim")?;
            let mm = triplets(&f, path, "fclib_global/M", MAX_GLOBAL_DOFS)?;
            let hh = triplets(&f, path, "fclib_global/H", MAX_GLOBAL_DOFS)?;
            let (nm, nm2, hn, hr) = (mm.rows, mm.cols, hh.rows, hh.cols);
            let fv = reals(&f, path, "fclib_global/vectors/f")?;
            let wv = reals(&f, path, "fclib_global/vectors/w")?;
            if nm != nm2 || hn != nm || fv.len() != nm || wv.len() != hr {
                return Err(Error::invalid(
                    &format!("{}: fclib_global", path.display()),
                    format!("M {nm}×{nm2}, H {hn}×{hr}, f {}, w {}", fv.len(), wv.len()),
                    "expected M n×n, H n×m, f of n and w of m values",
                ));
            }
            // M⁻¹ [H f] is n × (m + 1) dense: bounded like a dense W
            if hr > MAX_ROWS || (nm as u64) * (hr as u64 + 1) > (MAX_ROWS as u64).pow(2) {
                return Err(Error::invalid(
                    &format!("{}: fclib_global", path.display()),
                    format!("M {nm}×{nm}, H {hn}×{hr}"),
                    &format!(
                        "too large to condense: M⁻¹ H has {} values, the limit is {}",
                        (nm as u64) * (hr as u64 + 1),
                        (MAX_ROWS as u64).pow(2)
                    ),
                ));
            }
            let (w, q) = condense(path, &mm, &hh, &fv, &wv)?;
            return FrictionContactProblem {
                dim: dim.max(0) as usize,
                w,
                q,
                mu: reals(&f, path, "fclib_global/vectors/mu")?,
                guess,
                form: "global (condensed W = Hᵀ M⁻¹ H by a sparse LU of M)",
                asymmetry: 0.0,
            }
            .finish(path);
        }
        Err(Error::invalid(
            &path.display().to_string(),
            "HDF5",
            "holds neither /fclib_local nor /fclib_global",
        ))
    }
}

/// A solved problem: what `signorini fclib --solution` writes.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Solution {
    /// Reactions, contact by contact, normal first.
    pub r: Vec<f64>,
    /// Velocities `W r + q`, same layout.
    pub u: Vec<f64>,
    /// The residual reached, by [`Solution::measure`].
    pub residual: f64,
    /// Which residual: Siconos' (default) or the step loop's velocity residual.
    pub measure: crate::solvers::friction::Measure,
    /// NSGS sweeps (summed over the proximal iterations for PROX).
    pub iterations: usize,
    /// Proximal iterations (PROX only).
    pub prox_iterations: usize,
    /// The residual reached the tolerance.
    pub converged: bool,
    /// Wall time of the solve (s).
    pub seconds: f64,
    /// The solver asked for.
    pub solver: String,
    /// The solver that produced `r` (for `auto`, the stage that finished).
    pub solved_by: String,
    /// The Newton methods factored a sparse Jacobian.
    pub sparse_jacobian: bool,
}

/// Solves `prob` from `r = 0` (or the file's guess when `warm`) with `params`.
pub fn solve(
    prob: &FrictionContactProblem,
    params: &crate::solvers::friction::FrictionParams,
    warm: bool,
) -> Result<Solution, Error> {
    solve_repeated(prob, params, Measure::Siconos, warm, 1)
}

/// As [`solve`], stopping on `measure`, `repeat` times from the same start; `seconds`
/// is the median (warm caches, as a benchmark in one process measures the other code).
pub fn solve_repeated(
    prob: &FrictionContactProblem,
    params: &crate::solvers::friction::FrictionParams,
    measure: Measure,
    warm: bool,
    repeat: usize,
) -> Result<Solution, Error> {
    let mut times = Vec::with_capacity(repeat.max(1));
    let mut last = None;
    for _ in 0..repeat.max(1) {
        let s = solve_once(prob, params, measure, warm)?;
        times.push(s.seconds);
        last = Some(s);
    }
    times.sort_by(f64::total_cmp);
    let mut s = last.expect("at least one solve");
    s.seconds = times[times.len() / 2];
    Ok(s)
}

fn solve_once(
    prob: &FrictionContactProblem,
    params: &crate::solvers::friction::FrictionParams,
    measure: Measure,
    warm: bool,
) -> Result<Solution, Error> {
    use crate::solvers::friction::{Block, FrictionProblem, FrictionSolver};
    use crate::solvers::operator::DenseOperator;
    let n = prob.rows();
    let blocks: Vec<Block> = prob
        .mu
        .iter()
        .enumerate()
        .map(|(a, &mu)| Block {
            offset: a * prob.dim,
            dim: prob.dim,
            mu,
        })
        .collect();
    let mut r = match (&prob.guess, warm) {
        (Some(g), true) => g.clone(),
        _ => vec![0.0; n],
    };
    let mut u = vec![0.0; n];
    let mut solver = FrictionSolver::for_one_step(n).with_measure(measure);
    let op = DenseOperator::new(n, &prob.w);
    let t0 = std::time::Instant::now();
    let info = solver
        .solve(
            FrictionProblem {
                w: &op,
                q: &prob.q,
                blocks: &blocks,
            },
            params,
            &mut r,
            &mut u,
        )
        .map_err(|e| Error::Numerical(e.to_string()))?;
    let seconds = t0.elapsed().as_secs_f64();
    Ok(Solution {
        r,
        u,
        residual: info.residual,
        measure,
        iterations: info.iterations,
        prox_iterations: info.prox_iterations,
        converged: info.converged,
        seconds,
        solver: params.solver.name().to_string(),
        solved_by: info.solver.name().to_string(),
        sparse_jacobian: info.sparse_jacobian,
    })
}
