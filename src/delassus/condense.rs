//! Forming the operators at a linearization: `W = GᵀÂ⁻¹G` and `W_D = GᵀÂ⁻¹K N G` as
//! dense blocks (blocked sparse solves of the columns of `G`), or on the contact zone
//! from its flexibilities, and the tiled `K Y` products they need.

use super::*;

impl Delassus {
    /// `G` changed (or at start): the dense path recomputes every column now, the
    /// per-active-column path forgets its columns and recomputes them on demand.
    pub fn refresh(&mut self, stiffness: &SparseMatrix) {
        self.kinetic_moved();
        self.pool.slot.iter_mut().for_each(|s| *s = NONE);
        self.pool.owner.iter_mut().for_each(|s| *s = NONE);
        self.pool.used = 0;
        if !self.shape.dense {
            return;
        }
        let (n, m) = (self.shape.n, self.shape.m);
        if let Some(zone) = &mut self.zone {
            zone.condensed(&self.jac, false, &mut self.pool.w);
        } else {
            for a in 0..m {
                let col = &mut self.blocks.cg[a * n..(a + 1) * n];
                col.iter_mut().for_each(|x| *x = 0.0);
                self.jac.axpy(a, 1.0, col);
            }
            let once = self.condensing_once();
            solve_columns(self.factor.as_mut(), &mut self.blocks.cg, m, once);
            self.column_solves += m;
            for b in 0..m {
                for a in 0..m {
                    self.pool.w[a + b * m] = self.jac.dot(a, &self.blocks.cg[b * n..(b + 1) * n]);
                }
            }
        }
        for b in 0..m {
            self.pool.slot[b] = b;
            self.pool.owner[b] = b;
        }
        self.pool.used = m;
        if !self.shape.with_d {
            return;
        }
        if self.shape.need_wd {
            match &mut self.zone {
                Some(zone) => zone.condensed(&self.jac, true, &mut self.pool.wd),
                None => self.form_dense_wd(stiffness),
            }
        }
        for b in 0..m {
            for a in 0..m {
                self.blocks.wn[a + b * m] = match self.shape.metric {
                    Metric::Euclidean => self.jac.col_dot_col(a, b),
                    Metric::Mass => self.pool.w[a + b * m],
                };
            }
        }
    }

    /// The dense path's `Â⁻¹K N G` and `W_D` (after `Â⁻¹G`).
    pub(super) fn form_dense_wd(&mut self, stiffness: &SparseMatrix) {
        let (n, m) = (self.shape.n, self.shape.m);
        // K N G column by column: K (Â⁻¹G_b) for the mass metric, K G_b (a combination
        // of the few columns of K that G_b touches) for the Euclidean one. Sequential:
        // the products are bound by memory bandwidth, and on two threads the 98k-dof
        // cube's 1024 columns took 8.7 s against 6.1 s on one.
        let (cg, jac, metric) = (&self.blocks.cg, &self.jac, self.shape.metric);
        let k = stiffness.as_ref();
        let column = |b: usize, d: &mut [f64]| match metric {
            Metric::Euclidean => {
                d.iter_mut().for_each(|x| *x = 0.0);
                let (dofs, vals) = jac.col(b);
                for (&j, &g) in dofs.iter().zip(vals) {
                    let r = k.col_ptr()[j]..k.col_ptr()[j + 1];
                    for (&i, &v) in k.row_idx()[r.clone()].iter().zip(&k.val()[r]) {
                        d[i] += v * g;
                    }
                }
            }
            Metric::Mass => spmv(k, &cg[b * n..(b + 1) * n], d),
        };
        if self.condensing_once() && metric == Metric::Mass && m >= PRODUCT_TILE {
            // once, at construction: K times PRODUCT_TILE columns per pass over K
            k_times_columns(k, cg, &mut self.blocks.d, n);
        } else {
            for (b, d) in self.blocks.d.chunks_mut(n).enumerate() {
                column(b, d);
            }
        }
        let once = self.condensing_once();
        solve_columns(self.factor.as_mut(), &mut self.blocks.d, m, once);
        self.column_solves += m;
        for b in 0..m {
            for a in 0..m {
                self.pool.wd[a + b * m] = self.jac.dot(a, &self.blocks.d[b * n..(b + 1) * n]);
            }
        }
    }
}

/// Solves the `m` columns of a dense `n × m` block of [`Delassus::refresh`]: on every
/// thread when the blocks are condensed `once` (constant `G`, at set-up), otherwise
/// sequentially and without allocating (`refresh` inside the step loop).
pub(super) fn solve_columns(factor: &mut dyn LinearSolver, x: &mut [f64], m: usize, once: bool) {
    if once {
        factor.solve_block_in_place_par(x, m);
    } else {
        factor.solve_block_in_place(x, m);
    }
}

/// Columns per pass of [`k_times_columns`].
pub(super) const PRODUCT_TILE: usize = 32;

/// Rows per block of [`k_times_columns`]'s transposes (a block of the tile, 64 × 32
/// values, is 16 KiB: it stays in the first-level cache).
pub(super) const TRANSPOSE_ROWS: usize = 64;

/// `y = K x` for the `m` columns of `x` (`n × m`, column-major), [`PRODUCT_TILE`]
/// columns per pass over `K`: each tile is transposed to row-major so that every entry
/// of `K` updates a contiguous row of the tile. One pass per column streams all of `K`
/// each time; on the 98 304-dof cube the 1024 products took 5.4 s one column at a time
/// (bound by memory bandwidth), and the whole set-up 19.1 s against 16.2 s tiled. The
/// tiles are spread over rayon's threads (each thread its two tiles, `2 n ×`
/// [`PRODUCT_TILE`] values, allocated here: called at set-up only); a tile's columns do
/// not depend on the thread. On the two 20³ cubes' zone (2 646 columns) the products
/// took 4.0 s on one thread.
pub(super) fn k_times_columns(
    k: SparseColMatRef<'_, usize, f64>,
    x: &[f64],
    y: &mut [f64],
    n: usize,
) {
    use rayon::prelude::*;
    const T: usize = PRODUCT_TILE;
    let (cp, ri, val) = (k.col_ptr(), k.row_idx(), k.val());
    let tile = |(xt, yt): &mut (Vec<f64>, Vec<f64>), (xs, ys): (&[f64], &mut [f64])| {
        let cols = xs.len() / n;
        if cols < T {
            // the last tile's unused lanes: zero, so that a zero row is skipped
            xt.iter_mut().for_each(|v| *v = 0.0);
        }
        // the transposes in blocks of rows, so that a block of the tile stays in cache
        // while the columns are read (column by column, each pass swept the whole
        // tile: 8 % of the two 30³ cubes' set-up)
        for j0 in (0..n).step_by(TRANSPOSE_ROWS) {
            let j1 = (j0 + TRANSPOSE_ROWS).min(n);
            for c in 0..cols {
                for (j, &v) in (j0..j1).zip(&xs[c * n + j0..c * n + j1]) {
                    xt[j * T + c] = v;
                }
            }
        }
        yt.iter_mut().for_each(|v| *v = 0.0);
        for j in 0..n {
            let xr: [f64; T] = xt[j * T..(j + 1) * T].try_into().expect("tile row");
            // a column of K times zeros adds nothing (the columns of a zone's body
            // are zero on every other body: issue 35)
            if xr.iter().all(|&v| v == 0.0) {
                continue;
            }
            for p in cp[j]..cp[j + 1] {
                let (i, a) = (ri[p], val[p]);
                let yr = &mut yt[i * T..(i + 1) * T];
                for c in 0..T {
                    yr[c] += a * xr[c];
                }
            }
        }
        for i0 in (0..n).step_by(TRANSPOSE_ROWS) {
            let i1 = (i0 + TRANSPOSE_ROWS).min(n);
            for c in 0..cols {
                for (i, v) in (i0..i1).zip(&mut ys[c * n + i0..c * n + i1]) {
                    *v = yt[i * T + c];
                }
            }
        }
    };
    x.par_chunks(n * T)
        .zip(y.par_chunks_mut(n * T))
        .for_each_init(|| (vec![0.0; n * T], vec![0.0; n * T]), tile);
}

/// `y += s x` (inlined into the pulp kernels, so it compiles for their vector width).
#[inline(always)]
pub(super) fn axpy(s: f64, x: &[f64], y: &mut [f64]) {
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi += s * xi;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tiled product equals the column-by-column `spmv` bit for bit (same order
    /// of additions per entry), for a column count that is not a multiple of the tile.
    #[test]
    fn tiled_products_equal_column_products() {
        use crate::model::MassKind;
        use crate::model::generate::box_mesh;
        use crate::model::solid::{CellKind, Formulation, Material, assemble};
        let mesh = box_mesh(CellKind::Hex8, [4, 3, 3], [1.0, 1.0, 1.0]);
        let mat = Material {
            young: 210e9,
            poisson: 0.3,
            density: 7800.0,
            model: crate::model::solid::MaterialModel::LINEAR,
        };
        let sys = assemble(&mesh, &mat, Formulation::Solid, MassKind::Consistent).unwrap();
        let n = sys.ndof();
        let m = PRODUCT_TILE + 5;
        let x: Vec<f64> = (0..n * m)
            .map(|i| ((i * 7919) % 1000) as f64 - 500.0)
            .collect();
        let mut tiled = vec![0.0; n * m];
        k_times_columns(sys.stiffness.as_ref(), &x, &mut tiled, n);
        for c in 0..m {
            let mut y = vec![0.0; n];
            spmv(sys.stiffness.as_ref(), &x[c * n..(c + 1) * n], &mut y);
            assert!(y == tiled[c * n..(c + 1) * n], "column {c}");
        }
    }
}
