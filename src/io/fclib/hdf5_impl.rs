//! FCLIB's HDF5 files, local and global (the layout of `fclib.h`; the global problem
//! condensed with a dense LU of `M`, as the parent's module doc says).

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
