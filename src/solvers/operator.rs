//! What the contact solvers need of a Delassus operator `W` (entries, column products,
//! products; rows `0..size()`), and its dense implementation for gathered sub-problems
//! and problems read from files. The trait lives with the solvers that consume it; the
//! Delassus store of [`crate::delassus`] and the FCLIB readers provide operators.

/// What the contact solvers need of a Delassus operator (rows `0..size()`).
pub trait DelassusOperator {
    /// Number of rows.
    fn size(&self) -> usize;
    /// Entry `(i, j)`.
    fn entry(&self, i: usize, j: usize) -> f64;
    /// `out += s · W x`.
    fn mul_add(&self, s: f64, x: &[f64], out: &mut [f64]) {
        for (j, &xj) in x.iter().enumerate() {
            if xj != 0.0 {
                for (i, o) in out.iter_mut().enumerate() {
                    *o += s * xj * self.entry(i, j);
                }
            }
        }
    }
    /// `out += s · W_{:,j}`; `scratch` has `size()` values for operators that form the
    /// column first.
    fn column_add(&self, j: usize, s: f64, scratch: &mut [f64], out: &mut [f64]) {
        let _ = scratch;
        for (i, o) in out.iter_mut().enumerate() {
            *o += s * self.entry(i, j);
        }
    }
}

/// A dense column-major `k × k` operator (the gathered active sub-problem of a step, or
/// a problem read from a file).
#[derive(Clone, Copy, Debug)]
pub struct DenseOperator<'a> {
    k: usize,
    a: &'a [f64],
}

impl<'a> DenseOperator<'a> {
    /// Wraps the column-major `k × k` matrix `a` (leading dimension `k`).
    pub fn new(k: usize, a: &'a [f64]) -> Self {
        assert!(
            a.len() >= k * k,
            "dense operator: {} values for {k}×{k}",
            a.len()
        );
        DenseOperator { k, a }
    }
}

impl DelassusOperator for DenseOperator<'_> {
    fn size(&self) -> usize {
        self.k
    }
    #[inline]
    fn entry(&self, i: usize, j: usize) -> f64 {
        self.a[i + j * self.k]
    }
    fn mul_add(&self, s: f64, x: &[f64], out: &mut [f64]) {
        let k = self.k;
        for (j, &xj) in x.iter().enumerate().take(k) {
            if xj != 0.0 {
                let f = s * xj;
                for (o, &c) in out.iter_mut().zip(&self.a[j * k..(j + 1) * k]) {
                    *o += f * c;
                }
            }
        }
    }
    fn column_add(&self, j: usize, s: f64, _scratch: &mut [f64], out: &mut [f64]) {
        let k = self.k;
        for (o, &c) in out.iter_mut().zip(&self.a[j * k..(j + 1) * k]) {
            *o += s * c;
        }
    }
}
