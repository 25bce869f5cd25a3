//! Energies and dot products on the step loop's fast paths: `xᵀ A x` of a sparse matrix
//! (threaded past a size), the tridiagonal rows of a rod's matrices, and lane-wise dots.

use super::*;

/// `xᵀ A x` for a CSC matrix (the energies of the history). Does not allocate.
///
/// Matrices with more than [`PAR_QUADRATIC_NNZ`] entries are split into
/// [`QUADRATIC_PARTS`] fixed column ranges summed on rayon's pool and added in order,
/// so the result does not depend on the number of threads (measured on the 97 443-dof
/// hex bar: the two energies of a history row took 9.5 ms on one thread).
pub fn quadratic_form(a: SparseColMatRef<'_, usize, f64>, x: &[f64]) -> f64 {
    let n = x.len();
    if a.compute_nnz() <= PAR_QUADRATIC_NNZ {
        return quadratic_form_cols(a, x, 0..n, None);
    }
    use rayon::prelude::*;
    let mut parts = [0.0; QUADRATIC_PARTS];
    parts.par_iter_mut().enumerate().for_each(|(p, out)| {
        let r = p * n / QUADRATIC_PARTS..(p + 1) * n / QUADRATIC_PARTS;
        *out = quadratic_form_cols(a, x, r, None);
    });
    parts.iter().sum()
}

/// `[x₀ᵀ A y₀, x₁ᵀ A y₁, …]` in one walk over a CSC matrix: the matrix is read once for
/// all `K` pairs (the accuracy mode's comparison of two states reads `M` and `K` once
/// each instead of once per form). Serial below [`PAR_QUADRATIC_NNZ`] entries, else in
/// [`QUADRATIC_PARTS`] fixed column ranges added in order (the result does not depend on
/// the threads). Does not allocate.
pub fn bilinear_forms<const K: usize>(
    a: SparseColMatRef<'_, usize, f64>,
    pairs: [(&[f64], &[f64]); K],
) -> [f64; K] {
    let n = a.ncols();
    let walk = |cols: std::ops::Range<usize>| -> [f64; K] {
        let (col_ptr, row_idx, val) = (a.col_ptr(), a.row_idx(), a.val());
        let mut s = [0.0; K];
        for j in cols {
            let r = col_ptr[j]..col_ptr[j + 1];
            let mut c = [0.0; K];
            for (&i, &v) in row_idx[r.clone()].iter().zip(&val[r]) {
                for k in 0..K {
                    c[k] += v * pairs[k].1[i];
                }
            }
            for k in 0..K {
                s[k] += c[k] * pairs[k].0[j];
            }
        }
        s
    };
    if a.compute_nnz() <= PAR_QUADRATIC_NNZ {
        return walk(0..n);
    }
    use rayon::prelude::*;
    let mut parts = [[0.0; K]; QUADRATIC_PARTS];
    parts.par_iter_mut().enumerate().for_each(|(p, out)| {
        *out = walk(p * n / QUADRATIC_PARTS..(p + 1) * n / QUADRATIC_PARTS);
    });
    let mut s = [0.0; K];
    for p in &parts {
        for k in 0..K {
            s[k] += p[k];
        }
    }
    s
}

/// `Σ_jk |x_j| |a_jk| |x_k|`: the sum of the absolute terms of `xᵀ A x`, which bounds its
/// rounding error (`xᵀ A x` is known to about `n ε` of it). Serial, allocation-free.
pub fn abs_quadratic_form(a: SparseColMatRef<'_, usize, f64>, x: &[f64]) -> f64 {
    let mut s = 0.0;
    for (j, &xj) in x.iter().enumerate() {
        if xj == 0.0 {
            continue;
        }
        let mut col = 0.0;
        for k in a.col_ptr()[j]..a.col_ptr()[j + 1] {
            col += a.val()[k].abs() * x[a.row_idx()[k]].abs();
        }
        s += xj.abs() * col;
    }
    s
}

/// [`quadratic_form`] of a symmetric `a`, keeping the product `a x` it forms column
/// by column in `ax` (`n` values): the same `xᵀ A x` bit for bit, and `A x` for the
/// price of storing it (the history's kinetic energy and each body's momenta read one
/// pass over `M`). Does not allocate.
pub fn quadratic_form_keep(a: SparseColMatRef<'_, usize, f64>, x: &[f64], ax: &mut [f64]) -> f64 {
    let n = x.len();
    if a.compute_nnz() <= PAR_QUADRATIC_NNZ {
        return quadratic_form_cols(a, x, 0..n, Some(ax));
    }
    use rayon::prelude::*;
    let mut parts = [0.0; QUADRATIC_PARTS];
    // the parts of `quadratic_form`, each with its slice of `ax`
    let mut rest = ax;
    let mut slices: [&mut [f64]; QUADRATIC_PARTS] = std::array::from_fn(|p| {
        let r = p * n / QUADRATIC_PARTS..(p + 1) * n / QUADRATIC_PARTS;
        let (head, tail) = std::mem::take(&mut rest).split_at_mut(r.len());
        rest = tail;
        head
    });
    parts
        .par_iter_mut()
        .zip(slices.par_iter_mut())
        .enumerate()
        .for_each(|(p, (out, ax))| {
            let r = p * n / QUADRATIC_PARTS..(p + 1) * n / QUADRATIC_PARTS;
            *out = quadratic_form_cols(a, x, r, Some(ax));
        });
    parts.iter().sum()
}

/// Entries above which [`quadratic_form`] runs in parallel.
pub const PAR_QUADRATIC_NNZ: usize = 1 << 18;

/// Column ranges of a parallel [`quadratic_form`].
pub const QUADRATIC_PARTS: usize = 32;

/// `Σ_j x_j (Aᵀx)_j` over `cols`; with `keep`, `(Aᵀx)_j` goes to `keep[j − cols.start]`.
pub(super) fn quadratic_form_cols(
    a: SparseColMatRef<'_, usize, f64>,
    x: &[f64],
    cols: std::ops::Range<usize>,
    mut keep: Option<&mut [f64]>,
) -> f64 {
    let col_ptr = a.col_ptr();
    let row_idx = a.row_idx();
    let val = a.val();
    let start = cols.start;
    let mut s = 0.0;
    for j in cols {
        let r = col_ptr[j]..col_ptr[j + 1];
        let c: f64 = row_idx[r.clone()]
            .iter()
            .zip(&val[r])
            .map(|(&i, &v)| v * x[i])
            .sum();
        if let Some(k) = keep.as_deref_mut() {
            k[j - start] = c;
        }
        s += c * x[j];
    }
    s
}

/// `xᵀ A x` for one fixed matrix `A`, its layout read once: the energies of every
/// history row (issue 19 §3).
///
/// [`quadratic_form`] walks the compressed columns, about 10 cycles per column on the
/// bar (three entries each): the history's two energies cost half a step. A symmetric
/// matrix whose rows hold exactly their three diagonals (the 1-D rods) is kept as
/// them and summed as `Σ_j x_j (a_{j−1,j} x_{j−1} + a_jj x_j +
/// a_{j+1,j} x_{j+1})` four columns at a time, which the compiler vectorizes; other
/// matrices keep the column walk. The three-diagonal sum is reordered against a single
/// running sum (four lanes added pairwise), which moves the result by round-off only.
#[derive(Clone, Debug)]
pub enum QuadraticForm {
    /// A symmetric tridiagonal matrix, kept as its three diagonals
    /// ([`TridiagonalRows`], the same arrays the step reads a rod's `K` from).
    Tridiagonal(TridiagonalRows),
    /// Any other pattern: [`quadratic_form`] on the matrix itself.
    General,
}

impl QuadraticForm {
    /// Reads the layout of the square matrix `a` (allocates `3n` values when it is
    /// tridiagonal).
    pub fn new(a: SparseColMatRef<'_, usize, f64>) -> Self {
        if a.ncols() < 4 {
            return QuadraticForm::General;
        }
        TridiagonalRows::new(a).map_or(QuadraticForm::General, QuadraticForm::Tridiagonal)
    }

    /// `xᵀ A x`, `a` the matrix this form was read from. Does not allocate.
    pub fn eval(&self, a: SparseColMatRef<'_, usize, f64>, x: &[f64]) -> f64 {
        match self {
            QuadraticForm::General => quadratic_form(a, x),
            QuadraticForm::Tridiagonal(rows) => {
                // row i of a symmetric matrix is its column i
                // a_{i,i+1} = a_{i+1,i}: the row below's left value
                let (above, diag, below) = (&rows.left, &rows.diag, &rows.left[1..]);
                let n = x.len();
                debug_assert_eq!(diag.len(), n);
                // the first and last columns miss a neighbour
                let ends = x[0] * (diag[0] * x[0] + below[0] * x[1])
                    + x[n - 1] * (above[n - 1] * x[n - 2] + diag[n - 1] * x[n - 1]);
                let m = n - 2;
                let (xl, xc, xr) = (&x[..m], &x[1..=m], &x[2..]);
                let (au, ad, ab) = (&above[1..=m], &diag[1..=m], &below[1..=m]);
                let mut lanes = [0.0; 4];
                let chunks = m / 4;
                for c in 0..chunks {
                    let r = 4 * c..4 * c + 4;
                    let (xl, xc, xr) = (&xl[r.clone()], &xc[r.clone()], &xr[r.clone()]);
                    let (au, ad, ab) = (&au[r.clone()], &ad[r.clone()], &ab[r]);
                    for l in 0..4 {
                        lanes[l] += xc[l] * (au[l] * xl[l] + ad[l] * xc[l] + ab[l] * xr[l]);
                    }
                }
                for j in 4 * chunks..m {
                    lanes[0] += xc[j] * (au[j] * xl[j] + ad[j] * xc[j] + ab[j] * xr[j]);
                }
                ((lanes[0] + lanes[1]) + (lanes[2] + lanes[3])) + ends
            }
        }
    }
}

/// A symmetric matrix whose every row holds exactly its three diagonals (two at the
/// ends): the 1-D rods' `M` and `K`, kept as the diagonals for the history's energies
/// ([`QuadraticForm`]) and so that `h (f − K x)` of the
/// θ-method's free velocity (eq. 18; [`crate::integrators::core`]'s `begin_step`) is a
/// vectorizable pass instead of a gather per row (issue 19 §4).
///
/// Each row sums its three products in the order the stored row does, with the same
/// [`Sum`](std::iter::Sum) of `f64`, so the result is the gather's bit for bit; a
/// matrix with any other stored pattern (a missing off-diagonal entry, an unsorted
/// column, a nonsymmetric value) is not taken.
#[derive(Clone, Debug)]
pub struct TridiagonalRows {
    /// `a_{i,i−1}` (0 for `i = 0`).
    pub(super) left: Vec<f64>,
    /// `a_ii`.
    pub(super) diag: Vec<f64>,
    // `a_{i,i+1}` is `left[i + 1]` (symmetry, checked bit for bit): one array fewer to
    // stream per step (issue 35)
}

impl TridiagonalRows {
    /// The rows of the symmetric CSC matrix `a` (`n ≥ 2`) when every column holds
    /// exactly rows `j − 1, j, j + 1` (those that exist) in order and `a` is symmetric
    /// bit for bit; `None` otherwise.
    pub fn new(a: SparseColMatRef<'_, usize, f64>) -> Option<Self> {
        let n = a.ncols();
        if n < 2 || a.nrows() != n {
            return None;
        }
        let (cp, ri, v) = (a.col_ptr(), a.row_idx(), a.val());
        let (mut left, mut diag, mut right) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        for j in 0..n {
            let expect: Vec<usize> = (j.saturating_sub(1)..(j + 2).min(n)).collect();
            if ri[cp[j]..cp[j + 1]] != expect[..] {
                return None;
            }
            for (k, &i) in (cp[j]..cp[j + 1]).zip(&expect) {
                // column j is row j (symmetry checked below)
                match i.cmp(&j) {
                    std::cmp::Ordering::Less => left[j] = v[k],
                    std::cmp::Ordering::Equal => diag[j] = v[k],
                    std::cmp::Ordering::Greater => right[j] = v[k],
                }
            }
        }
        // a_{j+1,j} (below the diagonal of column j) = a_{j,j+1} (above in column j+1)
        let symmetric = (0..n - 1).all(|j| right[j].to_bits() == left[j + 1].to_bits());
        symmetric.then_some(TridiagonalRows { left, diag })
    }

    /// `out_i = h (f_i − (K x)_i)`, each row summed as the CSC gather of the same matrix
    /// would (bit for bit); `f = None` for a load that is `+0.0` everywhere (read as the
    /// constant, not from memory: the same bits). Does not allocate.
    pub fn scaled_residual(&self, h: f64, f: Option<&[f64]>, x: &[f64], out: &mut [f64]) {
        let n = x.len();
        debug_assert!(n >= 2 && out.len() == n && self.diag.len() == n);
        debug_assert!(f.is_none_or(|f| f.len() == n));
        let (l, d, r) = (&self.left, &self.diag, &self.left[1..]);
        let fi = |i: usize| f.map_or(0.0, |f| f[i]);
        let row2 = |a: f64, b: f64| -> f64 { [a, b].into_iter().sum() };
        out[0] = h * (fi(0) - row2(d[0] * x[0], r[0] * x[1]));
        let m = n - 1;
        let lr = (&l[1..m], &d[1..m], &r[1..m]);
        let out_m = &mut out[1..m];
        pulp::Arch::new().dispatch(InteriorRows {
            h,
            out: out_m,
            f: f.map(|f| &f[1..m]),
            lr,
            x,
        });
        out[n - 1] = h * (fi(n - 1) - row2(l[n - 1] * x[n - 2], d[n - 1] * x[n - 1]));
    }

    /// Whether every value of `f` is `+0.0` (what [`TridiagonalRows::scaled_residual`]
    /// may then read as the constant).
    pub fn is_positive_zero(f: &[f64]) -> bool {
        f.iter().all(|x| x.to_bits() == 0)
    }
}

/// The interior rows of [`TridiagonalRows::scaled_residual`], over zipped slices (no
/// bounds checks), compiled by pulp's dispatch for the CPU's vector width: the loop
/// vectorizes across rows while each row's sum keeps its order, and Rust never fuses a
/// multiply and an add on its own, so the bits are those of the plain loop. `f = None`:
/// a load of `+0.0` everywhere, read as the constant (the same bits without the load's
/// stream).
pub(super) struct InteriorRows<'a> {
    pub(super) h: f64,
    pub(super) out: &'a mut [f64],
    pub(super) f: Option<&'a [f64]>,
    pub(super) lr: (&'a [f64], &'a [f64], &'a [f64]),
    pub(super) x: &'a [f64],
}

impl pulp::WithSimd for InteriorRows<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        match self.f {
            Some(f) => interior_rows(self.h, self.out, f.iter().copied(), self.lr, self.x),
            None => interior_rows(self.h, self.out, std::iter::repeat(0.0), self.lr, self.x),
        }
    }
}

/// `out_i = h (f_i − (K x)_i)` over the interior rows, `f` one value per row.
#[inline(always)]
pub(super) fn interior_rows(
    h: f64,
    out: &mut [f64],
    f: impl Iterator<Item = f64>,
    (l, d, r): (&[f64], &[f64], &[f64]),
    x: &[f64],
) {
    let m = x.len() - 1;
    let rows = out
        .iter_mut()
        .zip(f)
        .zip(l.iter().zip(d).zip(r))
        .zip(x[..m - 1].iter().zip(&x[1..m]).zip(&x[2..]));
    for (((o, fi), ((&li, &di), &ri)), ((&xl, &xc), &xr)) in rows {
        let kx: f64 = [li * xl, di * xc, ri * xr].into_iter().sum();
        *o = h * (fi - kx);
    }
}

/// Dot product summed in four lanes (reordered against [`dot`], so it differs from it
/// by round-off): for diagnostics such as the energies of the history, where a single
/// running sum would wait on every addition. Does not allocate.
pub fn dot_lanes(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut lanes = [0.0; 4];
    let (ac, bc) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ar, br) = (ac.remainder(), bc.remainder());
    for (x, y) in ac.zip(bc) {
        for l in 0..4 {
            lanes[l] += x[l] * y[l];
        }
    }
    for (x, y) in ar.iter().zip(br) {
        lanes[0] += x * y;
    }
    (lanes[0] + lanes[1]) + (lanes[2] + lanes[3])
}

/// Dot product of two slices.
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::Triplet;

    /// The rows of a tridiagonal `K` give `h (f − K x)` bit for bit as the CSC gather
    /// (what `begin_step` did), signed zeros included; another pattern is refused.
    #[test]
    fn tridiagonal_rows_equal_the_gather_bit_for_bit() {
        let n = 9;
        let mut t = Vec::new();
        for i in 0..n {
            t.push(Triplet::new(i, i, 2.0 + 0.1 * i as f64));
            if i + 1 < n {
                let off = -1.0 - 0.01 * (i % 4) as f64;
                t.push(Triplet::new(i, i + 1, off));
                t.push(Triplet::new(i + 1, i, off));
            }
        }
        let a = SparseMatrix::try_new_from_triplets(n, n, &t).unwrap();
        let rows = TridiagonalRows::new(a.as_ref()).expect("tridiagonal");
        let gather = |f: &[f64], x: &[f64], out: &mut [f64]| {
            let (cp, ri, v) = (a.col_ptr(), a.row_idx(), a.val());
            for i in 0..n {
                let kx: f64 = (cp[i]..cp[i + 1]).map(|k| v[k] * x[ri[k]]).sum();
                out[i] = 1e-3 * (f[i] - kx);
            }
        };
        for x in [
            (0..n)
                .map(|i| (i as f64 * 0.9).sin() * 1e-5)
                .collect::<Vec<_>>(),
            vec![0.0; n],
            vec![-0.0; n],
            (0..n)
                .map(|i| if i % 2 == 0 { 0.0 } else { -0.0 })
                .collect(),
        ] {
            for f in [
                vec![0.0; n],
                vec![-0.0; n],
                (0..n).map(|i| i as f64).collect(),
            ] {
                let (mut a1, mut a2) = (vec![7.0; n], vec![7.0; n]);
                gather(&f, &x, &mut a1);
                rows.scaled_residual(1e-3, Some(&f), &x, &mut a2);
                for (p, q) in a1.iter().zip(&a2) {
                    assert_eq!(p.to_bits(), q.to_bits(), "{a1:?} vs {a2:?}");
                }
                // a load of +0.0 read as the constant: the same bits (signed zeros too)
                if TridiagonalRows::is_positive_zero(&f) {
                    let mut a3 = vec![7.0; n];
                    rows.scaled_residual(1e-3, None, &x, &mut a3);
                    for (p, q) in a1.iter().zip(&a3) {
                        assert_eq!(p.to_bits(), q.to_bits(), "{a1:?} vs {a3:?}");
                    }
                }
            }
        }
        // a dropped coupling, and a nonsymmetric value, are refused
        let mut u = t.clone();
        u.retain(|e| !(e.row == 3 && e.col == 4));
        let b = SparseMatrix::try_new_from_triplets(n, n, &u).unwrap();
        assert!(TridiagonalRows::new(b.as_ref()).is_none());
        let mut u = t.clone();
        u.push(Triplet::new(3, 4, 1e-9));
        let b = SparseMatrix::try_new_from_triplets(n, n, &u).unwrap();
        assert!(TridiagonalRows::new(b.as_ref()).is_none());
    }

    /// `quadratic_form_keep` gives `quadratic_form`'s value bit for bit and keeps `A x`
    /// equal to `spmv`'s bit for bit (each column's sum in the same order), on the
    /// sequential path and on the parallel one (a matrix past `PAR_QUADRATIC_NNZ`
    /// entries, split into `QUADRATIC_PARTS` column ranges).
    #[test]
    fn quadratic_form_keep_keeps_the_product() {
        for n in [50usize, 40_000] {
            let mut t = Vec::new();
            for i in 0..n {
                t.push(Triplet::new(i, i, 4.0 + (i % 7) as f64 * 0.1));
                for k in [1usize, 3, 7] {
                    if i + k < n {
                        let off = -0.3 - ((i * k) % 5) as f64 * 0.05;
                        t.push(Triplet::new(i, i + k, off));
                        t.push(Triplet::new(i + k, i, off));
                    }
                }
            }
            let a = SparseMatrix::try_new_from_triplets(n, n, &t).unwrap();
            assert_eq!(a.compute_nnz() > PAR_QUADRATIC_NNZ, n > 1000, "n = {n}");
            let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
            let mut kept = vec![f64::NAN; n];
            let q = quadratic_form_keep(a.as_ref(), &x, &mut kept);
            assert_eq!(
                q.to_bits(),
                quadratic_form(a.as_ref(), &x).to_bits(),
                "n = {n}"
            );
            let mut ax = vec![0.0; n];
            spmv(a.as_ref(), &x, &mut ax);
            let same = kept
                .iter()
                .zip(&ax)
                .all(|(p, r)| p.to_bits() == r.to_bits());
            assert!(same, "n = {n}");
        }
    }

    /// The tridiagonal form and the lane dot product against the column walk and a
    /// plain dot: equal to within the rounding bound of a reordered sum, `2 n ε Σ|terms|`
    /// (Higham, Accuracy and Stability, eq. 3.5, with n terms); a general pattern keeps
    /// the column walk bit for bit; integers (exact in every order) agree exactly.
    #[test]
    fn quadratic_form_paths_agree_to_rounding() {
        for n in [4usize, 5, 7, 8, 1001] {
            let mut t = Vec::new();
            for i in 0..n {
                t.push(Triplet::new(i, i, 2.5 + (i % 7) as f64));
                if i + 1 < n {
                    let off = -1.0 - (i % 3) as f64 * 0.3 - (i % 5) as f64 * 0.2;
                    t.push(Triplet::new(i, i + 1, off));
                    t.push(Triplet::new(i + 1, i, off));
                }
            }
            let a = SparseMatrix::try_new_from_triplets(n, n, &t).unwrap();
            let form = QuadraticForm::new(a.as_ref());
            assert!(matches!(form, QuadraticForm::Tridiagonal(_)), "n = {n}");
            // made nonsymmetric by one entry: the column walk
            let mut u = t.clone();
            u.push(Triplet::new(1, 0, 1e-3));
            let b = SparseMatrix::try_new_from_triplets(n, n, &u).unwrap();
            assert!(matches!(
                QuadraticForm::new(b.as_ref()),
                QuadraticForm::General
            ));
            let x: Vec<f64> = (0..n).map(|i| 1e-4 + (i as f64 * 0.37).sin()).collect();
            let walk = quadratic_form(a.as_ref(), &x);
            let fast = form.eval(a.as_ref(), &x);
            let mut ax = vec![0.0; n];
            spmv(a.as_ref(), &x, &mut ax);
            let terms: f64 = ax.iter().zip(&x).map(|(p, q)| (p * q).abs()).sum();
            let bound = 2.0 * (3 * n) as f64 * f64::EPSILON * (terms + 4.0 * walk.abs());
            assert!((fast - walk).abs() <= bound, "n = {n}: {fast} vs {walk}");
            let xi: Vec<f64> = (0..n).map(|i| (i % 11) as f64 - 5.0).collect();
            let int = SparseMatrix::try_new_from_triplets(
                n,
                n,
                &t.iter()
                    .map(|e| Triplet::new(e.row, e.col, (4.0 * e.val).round()))
                    .collect::<Vec<_>>(),
            )
            .unwrap();
            let fi = QuadraticForm::new(int.as_ref());
            assert_eq!(
                fi.eval(int.as_ref(), &xi),
                quadratic_form(int.as_ref(), &xi)
            );
            let d = dot_lanes(&x, &ax);
            assert!((d - dot(&x, &ax)).abs() <= 2.0 * n as f64 * f64::EPSILON * terms);
        }
        // an arrow matrix is not tridiagonal: the column walk, bit for bit
        let n = 6;
        let mut t: Vec<_> = (0..n).map(|i| Triplet::new(i, i, 4.0 + i as f64)).collect();
        for i in 1..n {
            t.push(Triplet::new(0, i, 0.5));
            t.push(Triplet::new(i, 0, 0.5));
        }
        let a = SparseMatrix::try_new_from_triplets(n, n, &t).unwrap();
        let form = QuadraticForm::new(a.as_ref());
        assert!(matches!(form, QuadraticForm::General));
        let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).cos()).collect();
        assert_eq!(
            form.eval(a.as_ref(), &x).to_bits(),
            quadratic_form(a.as_ref(), &x).to_bits()
        );
    }
}
