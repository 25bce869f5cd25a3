//! Set-up solves that skip what is zero and what is not needed (issue 35 §3): the
//! zone blocks of contacts between bodies (`delassus`, `condense_zone`) where they are
//! kept whole or not taken from the factor's tangent (`linalg::zone_flex`) solve `2z`
//! columns through the factor, each a unit vector on the contact zone or a product
//! supported on one body.
//!
//! Owns [`SpdFactor::solve_block_for_rows`]: the supernodal `L Lᵀ` sweeps of faer
//! (the same kernels, `Par::Seq`, on the same blocks), with
//! - in the forward sweep, every supernode whose rows of the block are all zero
//!   skipped: a right-hand side supported on some rows reaches only their ancestors in
//!   the elimination tree, and one supported on one body never reaches the other bodies
//!   (the bodies are not coupled in `M̂`, so their supernodes are disjoint subtrees);
//! - in the backward sweep, every supernode skipped whose rows and whose pattern's rows
//!   are all zero (the other bodies again), and, when only some rows of the result are
//!   read, every supernode that is not one of theirs or an ancestor of one (a result
//!   row needs only its ancestors' values).
//!
//! [`SpdFactor::solve_sparse_rhs_in_place`] is the step loop's form of the forward skip
//! (sequential, no allocation): the projection corrections `M̂⁻¹ [G τ_used, G τ]` of a
//! zone kept as flexibilities only, whose right-hand sides live on the contact zone.
//!
//! Written here rather than through faer's `LltRef::solve_in_place_with_conj`, which
//! sweeps every supernode for every block: faer has no sparse right-hand-side solve.
//! The skipped blocks would have computed zeros (up to the sign of a zero), so the
//! results are those of the full solve on every row that is read.

use faer::linalg::matmul::matmul_with_conj;
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place_with_conj, solve_upper_triangular_in_place_with_conj,
};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::cholesky::SymbolicCholeskyRaw;
use faer::sparse::linalg::cholesky::supernodal::SupernodalLltRef;
use faer::{Accum, Conj, MatMut, MatRef, Par};

use super::{Backend, SOLVE_CHUNK, SpdFactor};

impl SpdFactor {
    /// Overwrites the `k` columns of `x` (`n × k`, column-major) with `A⁻¹ x`, where
    /// `rows` (when given) are the only rows of the result the caller reads: the others
    /// are left unspecified. Skips the zero and unneeded blocks of a supernodal factor
    /// (module doc), [`SOLVE_CHUNK`] columns per task on rayon's pool; other factors
    /// solve every row ([`SpdFactor::solve_block_in_place_par`]). Allocates its
    /// scratch: for set-ups, not for the step loop.
    pub fn solve_block_for_rows(&mut self, x: &mut [f64], k: usize, rows: Option<&[usize]>) {
        let n = self.n;
        debug_assert_eq!(x.len(), n * k);
        let supernodal = match &self.backend {
            Backend::Faer(f) if f.simplicial.is_none() => match f.symbolic.raw() {
                SymbolicCholeskyRaw::Supernodal(s) => Some((s, f)),
                SymbolicCholeskyRaw::Simplicial(_) => None,
            },
            _ => None,
        };
        let Some((sym, f)) = supernodal else {
            return self.solve_block_in_place_par(x, k);
        };
        if n == 0 || k == 0 {
            return;
        }
        let llt = SupernodalLltRef::<usize, f64>::new(sym, &f.values);
        let perm = f.symbolic.perm().map(|p| p.arrays());
        let ns = sym.n_supernodes();
        let ends = sym.supernode_end();
        // the supernode holding factor row `r`
        let owner = |r: usize| ends.partition_point(|&e| e <= r);
        let needed = rows.map(|rows| {
            let mut need = vec![false; ns];
            for &r in rows {
                let p = perm.map_or(r, |(_, inv)| inv[r]);
                need[owner(p)] = true;
            }
            // a supernode's parent is the owner of its pattern's first row, after it
            for s in 0..ns {
                if need[s]
                    && let Some(&p0) = llt.supernode(s).pattern().first()
                {
                    need[owner(p0)] = true;
                }
            }
            need
        });
        let widest = (0..ns)
            .map(|s| llt.supernode(s).pattern().len())
            .max()
            .unwrap_or(0);
        // one scratch per worker, reused by its chunks (a fresh `n × SOLVE_CHUNK` block
        // per chunk cost 8 % of the two 30³ cubes' set-up in page faults); every entry a
        // sweep reads is written first, so the reuse changes no bit
        let scratch = || {
            (
                vec![0.0; n * SOLVE_CHUNK.min(k)],
                vec![0.0; widest * SOLVE_CHUNK.min(k)],
            )
        };
        let solve = |(xp, tmp): &mut (Vec<f64>, Vec<f64>), block: &mut [f64]| {
            let cols = block.len() / n;
            permuted_sweeps(
                llt,
                perm,
                block,
                &mut xp[..n * cols],
                &mut tmp[..widest * cols],
                (needed.as_deref(), rows),
            );
        };
        use rayon::prelude::*;
        x.par_chunks_mut(n * SOLVE_CHUNK)
            .for_each_init(scratch, solve);
    }
}

impl SpdFactor {
    /// Sizes the scratch of [`SpdFactor::solve_sparse_rhs_in_place`] for blocks of up to
    /// `k` columns (allocates: at set-up).
    pub fn reserve_sparse_rhs(&mut self, k: usize) {
        let n = self.n;
        if let Backend::Faer(f) = &mut self.backend
            && f.simplicial.is_none()
            && let SymbolicCholeskyRaw::Supernodal(sym) = f.symbolic.raw()
        {
            let llt = SupernodalLltRef::<usize, f64>::new(sym, &f.values);
            let widest = (0..sym.n_supernodes())
                .map(|s| llt.supernode(s).pattern().len())
                .max()
                .unwrap_or(0);
            if f.sparse.0.len() < n * k {
                f.sparse.0 = vec![0.0; n * k];
            }
            if f.sparse.1.len() < widest * k {
                f.sparse.1 = vec![0.0; widest * k];
            }
        }
    }

    /// Overwrites the `k` columns of `x` (`n × k`, column-major) with `A⁻¹ x`, the
    /// forward sweep skipping every supernode whose rows of the block are zero (module
    /// doc): the results of [`SpdFactor::solve_block_in_place`] on every row, at the cost
    /// of the rows the right-hand sides reach. Sequential; allocates nothing once
    /// [`SpdFactor::reserve_sparse_rhs`] covered `k` (else it solves the whole block).
    pub fn solve_sparse_rhs_in_place(&mut self, x: &mut [f64], k: usize) {
        let n = self.n;
        debug_assert_eq!(x.len(), n * k);
        let Backend::Faer(f) = &mut self.backend else {
            return self.solve_block_in_place(x, k);
        };
        let sym = match f.symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(s) if f.simplicial.is_none() => s,
            _ => return self.solve_block_in_place(x, k),
        };
        if f.sparse.0.len() < n * k || n == 0 || k == 0 {
            return self.solve_block_in_place(x, k);
        }
        let llt = SupernodalLltRef::<usize, f64>::new(sym, &f.values);
        let perm = f.symbolic.perm().map(|p| p.arrays());
        let (xp, tmp) = (&mut f.sparse.0[..n * k], &mut f.sparse.1[..]);
        let width = tmp.len() / k;
        permuted_sweeps(llt, perm, x, xp, &mut tmp[..width * k], (None, None));
    }
}

/// `x = A⁻¹ x` for the block `x` (`n`-columns) through the permuted scratch `xp` (as long
/// as `x`): the factor's permutation, [`sweeps`], and back; with `rows`, only those rows
/// of the result are permuted back (the others keep the right-hand side), `needed` the
/// supernodes they need.
fn permuted_sweeps(
    llt: SupernodalLltRef<'_, usize, f64>,
    perm: Option<(&[usize], &[usize])>,
    x: &mut [f64],
    xp: &mut [f64],
    tmp: &mut [f64],
    (needed, rows): (Option<&[bool]>, Option<&[usize]>),
) {
    let n = llt.symbolic().nrows();
    let k = x.len() / n;
    match perm {
        Some((fwd, _)) => {
            for (dst, src) in xp.chunks_exact_mut(n).zip(x.chunks_exact(n)) {
                for (d, &i) in dst.iter_mut().zip(fwd) {
                    *d = src[i];
                }
            }
        }
        None => xp.copy_from_slice(x),
    }
    sweeps(llt, xp, n, k, tmp, needed);
    match (perm, rows) {
        (Some((_, inv)), Some(rows)) => {
            for (dst, src) in x.chunks_exact_mut(n).zip(xp.chunks_exact(n)) {
                for &r in rows {
                    dst[r] = src[inv[r]];
                }
            }
        }
        (Some((_, inv)), None) => {
            for (dst, src) in x.chunks_exact_mut(n).zip(xp.chunks_exact(n)) {
                for (d, &i) in dst.iter_mut().zip(inv) {
                    *d = src[i];
                }
            }
        }
        (None, _) => x.copy_from_slice(xp),
    }
}

/// Whether rows `start..start + size` of the `n × k` block `x` are all zero.
fn rows_zero(x: &[f64], n: usize, k: usize, start: usize, size: usize) -> bool {
    (0..k).all(|j| {
        x[j * n + start..j * n + start + size]
            .iter()
            .all(|&v| v == 0.0)
    })
}

/// The forward and backward sweeps of `L Lᵀ` on the permuted block `x` (`n × k`),
/// skipping as the module doc says; `tmp` holds the widest pattern's `k` columns.
fn sweeps(
    llt: SupernodalLltRef<'_, usize, f64>,
    x: &mut [f64],
    n: usize,
    k: usize,
    tmp: &mut [f64],
    needed: Option<&[bool]>,
) {
    let ns = llt.symbolic().n_supernodes();
    for s in 0..ns {
        let sn = llt.supernode(s);
        let (start, pattern, ls) = (sn.start(), sn.pattern(), sn.val());
        let size = ls.ncols();
        if rows_zero(x, n, k, start, size) {
            continue;
        }
        let (top, bot) = ls.split_at_row(size);
        let mut xm = MatMut::from_column_major_slice_mut(x, n, k);
        let mut x_top = xm.rb_mut().subrows_mut(start, size);
        solve_lower_triangular_in_place_with_conj(top, Conj::No, x_top.rb_mut(), Par::Seq);
        let p = pattern.len();
        let mut t = MatMut::from_column_major_slice_mut(&mut tmp[..p * k], p, k);
        matmul_with_conj(
            t.rb_mut(),
            Accum::Replace,
            bot,
            Conj::No,
            x_top.rb(),
            Conj::No,
            1.0,
            Par::Seq,
        );
        // (a root's pattern is empty: nothing to scatter)
        for (xc, tc) in x
            .chunks_exact_mut(n)
            .zip(tmp[..p * k].chunks_exact(p.max(1)))
        {
            for (&i, &t) in pattern.iter().zip(tc) {
                xc[i] -= t;
            }
        }
    }
    for s in (0..ns).rev() {
        if needed.is_some_and(|need| !need[s]) {
            continue;
        }
        let sn = llt.supernode(s);
        let (start, pattern, ls) = (sn.start(), sn.pattern(), sn.val());
        let size = ls.ncols();
        let p = pattern.len();
        for (tc, xc) in tmp[..p * k]
            .chunks_exact_mut(p.max(1))
            .zip(x.chunks_exact(n))
        {
            for (t, &i) in tc.iter_mut().zip(pattern) {
                *t = xc[i];
            }
        }
        if rows_zero(x, n, k, start, size) && tmp[..p * k].iter().all(|&v| v == 0.0) {
            continue;
        }
        let (top, bot) = ls.split_at_row(size);
        let t = MatRef::from_column_major_slice(&tmp[..p * k], p, k);
        let mut xm = MatMut::from_column_major_slice_mut(x, n, k);
        let mut x_top = xm.rb_mut().subrows_mut(start, size);
        matmul_with_conj(
            x_top.rb_mut(),
            Accum::Add,
            bot.transpose(),
            Conj::Yes,
            t,
            Conj::No,
            -1.0,
            Par::Seq,
        );
        solve_upper_triangular_in_place_with_conj(
            top.transpose(),
            Conj::Yes,
            x_top.rb_mut(),
            Par::Seq,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::SparseMatrix;

    /// Two uncoupled 3-D grid operators (27-point, diagonally dominant) as one matrix, large enough for
    /// faer's supernodal factor: every column of unit vectors on one body's face, solved
    /// with the skips, equals the full solve on every row (or on the rows asked for).
    #[test]
    fn skipped_blocks_change_no_result() {
        let g = 12usize;
        let body = g * g * g;
        let n = 2 * body;
        // diagonally dominant (26 neighbours of −1): dense enough for a supernodal factor
        let t = crate::linalg::test_grids::two_grids(g, |_| 27.5, |_, _| -1.0);
        let id = crate::linalg::test_grids::grid_id(g);
        let a = SparseMatrix::try_new_from_triplets(n, n, &t).unwrap();
        let mut f = SpdFactor::new(a.as_ref(), "test").unwrap();
        assert!(
            matches!(&f.backend, Backend::Faer(ff) if ff.simplicial.is_none()),
            "the test needs a supernodal factor"
        );
        // the face l = 0 of body 1: g² unit vectors
        let face: Vec<usize> = (0..g)
            .flat_map(|i| (0..g).map(move |j| id(1, i, j, 0)))
            .collect();
        let k = face.len();
        let mut full = vec![0.0; n * k];
        for (c, &d) in face.iter().enumerate() {
            full[c * n + d] = 1.0;
        }
        let (mut skip, mut rows) = (full.clone(), full.clone());
        f.solve_block_in_place(&mut full, k);
        f.solve_block_for_rows(&mut skip, k, None);
        f.solve_block_for_rows(&mut rows, k, Some(&face));
        let scale = full.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        for c in 0..k {
            for r in 0..n {
                let (a, b) = (full[c * n + r], skip[c * n + r]);
                assert!(
                    (a - b).abs() <= 1e-14 * scale,
                    "column {c}, row {r}: {a} vs {b}"
                );
                if r < body {
                    assert_eq!(b, 0.0, "the other body stays zero");
                }
            }
            for &r in &face {
                let (a, b) = (full[c * n + r], rows[c * n + r]);
                assert!((a - b).abs() <= 1e-14 * scale, "zone row {r}: {a} vs {b}");
            }
        }
        // the step loop's form: two columns on the face (combinations, as `G τ_used`,
        // `G τ`), the scratch reserved once; every row of both within 1e-14 of the full
        // block solve (the skipped blocks compute zeros; the tolerance covers a reordered
        // sum in faer's kernels, which the history comparison found bitwise equal)
        f.reserve_sparse_rhs(2);
        let mut two = vec![0.0; 2 * n];
        for (i, &d) in face.iter().enumerate() {
            two[d] = 1.0 + i as f64 / k as f64;
            two[n + d] = if i % 3 == 0 { -0.5 } else { 0.0 };
        }
        let mut reference = two.clone();
        f.solve_block_in_place(&mut reference, 2);
        f.solve_sparse_rhs_in_place(&mut two, 2);
        let scale = reference.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        assert!(scale > 0.0);
        for (r, (a, b)) in reference.iter().zip(&two).enumerate() {
            assert!((a - b).abs() <= 1e-14 * scale, "entry {r}: {a} vs {b}");
        }
        // without the reserve a wider block falls back to the whole solve
        let mut three = vec![1.0; 3 * n];
        let mut full3 = three.clone();
        f.solve_block_in_place(&mut full3, 3);
        f.solve_sparse_rhs_in_place(&mut three, 3);
        assert_eq!(three, full3);
    }
}
