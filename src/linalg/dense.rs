//! Small dense factorizations on caller-owned buffers for the one-step problems: an
//! in-place Cholesky of the active blocks `W_αα` and an LU for the unsymmetric ones.

use super::*;

/// In-place Cholesky `A = L Lᵀ` of a dense SPD matrix stored column-major in the
/// leading `k × k` block of a buffer with leading dimension `ld`: the active
/// sub-blocks `W_αα` of the one-step problems. Owns the scratch faer needs, sized at
/// construction, so factoring and solving do not allocate.
///
/// Blocks of fewer than [`DENSE_FAER_MIN`] rows use a plain loop (the bar's one
/// contact, the academic examples' two; no call overhead); larger blocks go to faer's
/// blocked, vectorized Cholesky and triangular solves. Measured on the 98 304-dof cube
/// with 1024 active contacts (`benches/cube_setup.toml`): the loop made the LCP and
/// MLCP 1.4 s of a 2.07 s step; see docs/speed.md for faer's.
pub struct DenseCholesky {
    pub(super) capacity: usize,
    pub(super) mem: MemBuffer,
}

impl Clone for DenseCholesky {
    fn clone(&self) -> Self {
        DenseCholesky::with_capacity(self.capacity)
    }
}

impl std::fmt::Debug for DenseCholesky {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "DenseCholesky {{ capacity: {} }}", self.capacity)
    }
}

/// Smallest block [`DenseCholesky`] hands to faer.
pub const DENSE_FAER_MIN: usize = 32;

impl DenseCholesky {
    /// Scratch for blocks of up to `capacity` rows.
    pub fn with_capacity(capacity: usize) -> Self {
        let req = faer::linalg::cholesky::llt::factor::cholesky_in_place_scratch::<f64>(
            capacity.max(1),
            Par::Seq,
            Default::default(),
        );
        DenseCholesky {
            capacity,
            mem: MemBuffer::new(req),
        }
    }

    /// Factors the leading `k × k` block of `a` (column-major, leading dimension `ld`)
    /// in place; only the lower triangle is read and written (the strict upper
    /// triangle may be overwritten by faer's path). Returns `false` if a pivot is not
    /// positive or not finite (the block is not SPD to working precision).
    pub fn factor(&mut self, a: &mut [f64], ld: usize, k: usize) -> bool {
        if k < DENSE_FAER_MIN {
            return small_cholesky(a, ld, k);
        }
        let mat =
            MatMut::from_column_major_slice_with_stride_mut(&mut a[..(k - 1) * ld + k], k, k, ld);
        let ok = faer::linalg::cholesky::llt::factor::cholesky_in_place(
            mat,
            LltRegularization::default(),
            Par::Seq,
            MemStack::new(&mut self.mem),
            Default::default(),
        )
        .is_ok();
        ok && (0..k).all(|j| a[j + j * ld].is_finite() && a[j + j * ld] > 0.0)
    }

    /// Solves `L Lᵀ x = b` in place for the `cols` right-hand sides stored
    /// column-major in `x` (leading dimension `k`), with a factor from
    /// [`DenseCholesky::factor`].
    pub fn solve(&self, l: &[f64], ld: usize, k: usize, x: &mut [f64], cols: usize) {
        if k == 0 || cols == 0 {
            return;
        }
        if k < DENSE_FAER_MIN {
            for c in x.chunks_exact_mut(k).take(cols) {
                small_solve(l, ld, k, c);
            }
            return;
        }
        let lm = MatRef::from_column_major_slice_with_stride(&l[..(k - 1) * ld + k], k, k, ld);
        let rhs = MatMut::from_column_major_slice_mut(&mut x[..k * cols], k, cols);
        faer::linalg::cholesky::llt::solve::solve_in_place_with_conj(
            lm,
            Conj::No,
            rhs,
            Par::Seq,
            MemStack::new(&mut []),
        );
    }
}

pub(super) fn small_cholesky(a: &mut [f64], ld: usize, k: usize) -> bool {
    for j in 0..k {
        let mut d = a[j + j * ld];
        for p in 0..j {
            d -= a[j + p * ld] * a[j + p * ld];
        }
        if d <= 0.0 || !d.is_finite() {
            return false;
        }
        let d = d.sqrt();
        a[j + j * ld] = d;
        for i in j + 1..k {
            let mut s = a[i + j * ld];
            for p in 0..j {
                s -= a[i + p * ld] * a[j + p * ld];
            }
            a[i + j * ld] = s / d;
        }
    }
    true
}

pub(super) fn small_solve(l: &[f64], ld: usize, k: usize, x: &mut [f64]) {
    for i in 0..k {
        let mut s = x[i];
        for p in 0..i {
            s -= l[i + p * ld] * x[p];
        }
        x[i] = s / l[i + i * ld];
    }
    for i in (0..k).rev() {
        let mut s = x[i];
        for p in i + 1..k {
            s -= l[p + i * ld] * x[p];
        }
        x[i] = s / l[i + i * ld];
    }
}

/// Partial-pivoting LU of a dense column-major square matrix of up to `capacity`
/// rows, with the permutations and faer's scratch owned and sized at construction, so
/// factoring and solving do not allocate (the coupled position problem of the step
/// loop, [`crate::integrators::core`]). [`dense_lu_solve`] is the allocating
/// one-shot form for one-step problems.
pub struct DenseLu {
    pub(super) capacity: usize,
    pub(super) perm: Vec<usize>,
    pub(super) perm_inv: Vec<usize>,
    pub(super) mem: MemBuffer,
}

impl std::fmt::Debug for DenseLu {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "DenseLu {{ capacity: {} }}", self.capacity)
    }
}

impl DenseLu {
    /// Scratch for matrices of up to `capacity` rows. Factors one identity of up to
    /// 128 rows on the way: faer's matrix-product kernels read the CPU's cache sizes
    /// from `/sys` (allocating) on their first call in the process, which must not be
    /// the step loop's first solve.
    pub fn with_capacity(capacity: usize) -> Self {
        use faer::linalg::lu::partial_pivoting::{factor, solve};
        let c = capacity.max(1);
        let req = factor::lu_in_place_scratch::<usize, f64>(c, c, Par::Seq, Default::default())
            .or(solve::solve_in_place_scratch::<usize, f64>(c, 1, Par::Seq));
        let mut lu = DenseLu {
            capacity,
            perm: vec![0; c],
            perm_inv: vec![0; c],
            mem: MemBuffer::new(req),
        };
        let w = capacity.min(128);
        let mut eye = vec![0.0; w * w];
        (0..w).for_each(|i| eye[i + i * w] = 1.0);
        let mut b = vec![1.0; w];
        lu.solve(&mut eye, w, &mut b);
        lu
    }

    /// Rows this workspace takes.
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// Solves `a x = b` in place (`a`: the leading `k × k` column-major block,
    /// overwritten by its factors; `b`: `k` values, overwritten by `x`). Returns `false`
    /// (and leaves `b` unspecified) when a pivot is zero or a value is not finite, or
    /// when `k` exceeds the capacity.
    pub fn solve(&mut self, a: &mut [f64], k: usize, b: &mut [f64]) -> bool {
        use faer::linalg::lu::partial_pivoting::{factor, solve};
        if k > self.capacity {
            return false;
        }
        if k == 0 {
            return true;
        }
        let mut lu = MatMut::from_column_major_slice_mut(&mut a[..k * k], k, k);
        let (_, p) = factor::lu_in_place(
            lu.as_mut(),
            &mut self.perm[..k],
            &mut self.perm_inv[..k],
            Par::Seq,
            MemStack::new(&mut self.mem),
            Default::default(),
        );
        let scale = (0..k).fold(0.0_f64, |s, j| s.max(lu[(j, j)].abs()));
        if !(scale.is_finite() && scale > 0.0)
            || (0..k).any(|j| lu[(j, j)].abs() <= 1e-14 * scale || lu[(j, j)].is_nan())
        {
            return false;
        }
        let rhs = MatMut::from_column_major_slice_mut(&mut b[..k], k, 1);
        solve::solve_in_place(
            lu.as_ref(),
            lu.as_ref(),
            p,
            rhs,
            Par::Seq,
            MemStack::new(&mut self.mem),
        );
        b[..k].iter().all(|x| x.is_finite())
    }
}

/// Solves `a x = b` in place for a dense column-major `k × k` `a` (overwritten by its LU
/// factors) by faer's partial-pivoting LU, sequential below 512 rows (the global rayon
/// setting of faer's high-level `partial_piv_lu` cost 0.1–0.3 ms per call on the
/// 3-row FCLIB problems, more than the whole solve). Allocates its scratch: for
/// one-step problems, not for the step loop.
pub fn dense_lu_solve(a: &mut [f64], k: usize, b: &mut [f64]) {
    use faer::linalg::lu::partial_pivoting::{factor, solve};
    let par = if k < 512 { Par::Seq } else { Par::rayon(0) };
    let mut perm = vec![0usize; k];
    let mut perm_inv = vec![0usize; k];
    let req = factor::lu_in_place_scratch::<usize, f64>(k, k, par, Default::default())
        .or(solve::solve_in_place_scratch::<usize, f64>(k, 1, par));
    let mut mem = MemBuffer::new(req);
    let mut lu = faer::MatMut::from_column_major_slice_mut(&mut a[..k * k], k, k);
    let (_, p) = factor::lu_in_place(
        lu.as_mut(),
        &mut perm,
        &mut perm_inv,
        par,
        MemStack::new(&mut mem),
        Default::default(),
    );
    let rhs = faer::MatMut::from_column_major_slice_mut(&mut b[..k], k, 1);
    solve::solve_in_place(
        lu.as_ref(),
        lu.as_ref(),
        p,
        rhs,
        par,
        MemStack::new(&mut mem),
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dense_cholesky_matches_known_solution() {
        // A = [[4,2],[2,3]], x = [1,-1] -> b = [2, -1]
        let mut a = vec![4.0, 2.0, 2.0, 3.0];
        let mut ch = DenseCholesky::with_capacity(2);
        assert!(ch.factor(&mut a, 2, 2));
        let mut x = vec![2.0, -1.0];
        ch.solve(&a, 2, 2, &mut x, 1);
        assert!((x[0] - 1.0).abs() < 1e-15 && (x[1] + 1.0).abs() < 1e-15);
        let mut bad = vec![1.0, 2.0, 2.0, 1.0];
        assert!(!ch.factor(&mut bad, 2, 2));
    }

    /// The faer path (k ≥ DENSE_FAER_MIN) and the loop agree on an SPD block with a
    /// leading dimension larger than k, for several right-hand sides; κ ≈ 3 here, so
    /// both backward-stable solves are within 1e-13 of the exact solution. An
    /// indefinite block is refused by both.
    #[test]
    fn dense_cholesky_paths_agree() {
        let (k, ld, cols) = (70, 73, 3);
        let mut a = vec![0.0; ld * k];
        for j in 0..k {
            for i in 0..k {
                a[i + j * ld] = if i == j {
                    4.0
                } else if i.abs_diff(j) == 1 {
                    -1.0
                } else {
                    0.01 / (1.0 + i.abs_diff(j) as f64)
                };
            }
        }
        let x_true: Vec<f64> = (0..k * cols).map(|i| (i as f64 * 0.37).cos()).collect();
        let mut b = vec![0.0; k * cols];
        for c in 0..cols {
            for i in 0..k {
                b[i + c * k] = (0..k).map(|j| a[i + j * ld] * x_true[j + c * k]).sum();
            }
        }
        let mut ch = DenseCholesky::with_capacity(k);
        let mut fa = a.clone();
        assert!(ch.factor(&mut fa, ld, k));
        let mut x = b.clone();
        ch.solve(&fa, ld, k, &mut x, cols);
        let mut sa = a.clone();
        assert!(small_cholesky(&mut sa, ld, k));
        let mut y = b.clone();
        for c in y.chunks_exact_mut(k) {
            small_solve(&sa, ld, k, c);
        }
        for i in 0..k * cols {
            assert!(
                (x[i] - x_true[i]).abs() < 1e-13,
                "{i}: {} {}",
                x[i],
                x_true[i]
            );
            assert!(
                (y[i] - x_true[i]).abs() < 1e-13,
                "{i}: {} {}",
                y[i],
                x_true[i]
            );
        }
        let mut bad = a.clone();
        bad[5 + 5 * ld] = -1.0;
        assert!(!ch.factor(&mut bad.clone(), ld, k));
        assert!(!small_cholesky(&mut bad, ld, k));
    }
}
