//! The per-active-column path: the columns `Â⁻¹G_b` of the contacts a one-step problem
//! reads, computed on demand into a pool of slots and kept while `G` holds (epochs).

use super::*;

impl Delassus {
    /// Starts a new step: columns used from now on are protected from eviction until
    /// the next call.
    pub fn next_epoch(&mut self) {
        self.pool.epoch += 1;
    }

    /// Makes column `b` available (computing it on the per-active-column path).
    pub fn ensure(&mut self, b: usize, stiffness: &SparseMatrix) -> Result<(), SolveError> {
        self.request(b)?;
        self.compute_pending(stiffness);
        Ok(())
    }

    /// Ensures the columns of every contact in `idx`, computing the missing ones
    /// [`SOLVE_BLOCK`] at a time; none for more rows than [`Delassus::limit_columns`]
    /// allows (their problem is solved matrix-free).
    pub fn ensure_all(
        &mut self,
        idx: &[usize],
        stiffness: &SparseMatrix,
    ) -> Result<(), SolveError> {
        if !self.shape.dense && idx.len() > self.pool.limit {
            // more than the one-step workspaces hold: the problem is solved matrix-free
            // and its products go through the factor (past the pool but within the
            // workspaces, the entries are needed: a pool error)
            return Ok(());
        }
        for &b in idx {
            self.request(b)?;
            if self.scratch.pending.len() == SOLVE_BLOCK {
                self.compute_pending(stiffness);
            }
        }
        self.compute_pending(stiffness);
        Ok(())
    }

    /// Marks column `b` as used in this epoch; if absent, gives it a slot (evicting
    /// the column unused for longest) and queues it for computation.
    fn request(&mut self, b: usize) -> Result<(), SolveError> {
        let s = self.pool.slot[b];
        if s != NONE {
            self.pool.stamp[s] = self.pool.epoch;
            return Ok(());
        }
        let s = if self.pool.used < self.pool.cap {
            self.pool.used += 1;
            self.pool.used - 1
        } else {
            let (s, &st) = self
                .pool
                .stamp
                .iter()
                .enumerate()
                .min_by_key(|&(_, &st)| st)
                .expect("pool has at least one slot");
            if st >= self.pool.epoch {
                return Err(SolveError::Capacity { cap: self.pool.cap });
            }
            self.pool.slot[self.pool.owner[s]] = NONE;
            s
        };
        self.pool.slot[b] = s;
        self.pool.owner[s] = b;
        self.pool.stamp[s] = self.pool.epoch;
        self.scratch.pending.push(b);
        Ok(())
    }

    /// Computes the queued columns: `W_{:,β} = GᵀÂ⁻¹G_β` and, with projection,
    /// `W_{D,:,β} = GᵀÂ⁻¹K N G_β`, by block solves.
    fn compute_pending(&mut self, stiffness: &SparseMatrix) {
        let k = self.scratch.pending.len();
        if k == 0 {
            return;
        }
        let (n, m) = (self.shape.n, self.shape.m);
        let blk = &mut self.scratch.blk[..n * k];
        blk.iter_mut().for_each(|x| *x = 0.0);
        for (c, &b) in self.scratch.pending.iter().enumerate() {
            self.jac.axpy(b, 1.0, &mut blk[c * n..(c + 1) * n]);
        }
        // column by column: a column must not depend on the batch it was computed in,
        // or a resumed run (which recomputes its active columns at once) diverges
        self.factor.solve_columns_independently(blk, k);
        for (c, &b) in self.scratch.pending.iter().enumerate() {
            let s = self.pool.slot[b];
            self.jac.transpose_mul(
                &blk[c * n..(c + 1) * n],
                &mut self.pool.w[s * m..(s + 1) * m],
            );
        }
        self.column_solves += k;
        if self.shape.with_d && self.shape.need_wd {
            let blk2 = &mut self.scratch.blk2[..n * k];
            for (c, &b) in self.scratch.pending.iter().enumerate() {
                let out = &mut blk2[c * n..(c + 1) * n];
                match self.shape.metric {
                    Metric::Mass => spmv(stiffness.as_ref(), &blk[c * n..(c + 1) * n], out),
                    Metric::Euclidean => {
                        self.scratch.t1.iter_mut().for_each(|x| *x = 0.0);
                        self.jac.axpy(b, 1.0, &mut self.scratch.t1);
                        spmv(stiffness.as_ref(), &self.scratch.t1, out);
                    }
                }
            }
            self.factor.solve_columns_independently(blk2, k);
            for (c, &b) in self.scratch.pending.iter().enumerate() {
                let s = self.pool.slot[b];
                self.jac.transpose_mul(
                    &blk2[c * n..(c + 1) * n],
                    &mut self.pool.wd[s * m..(s + 1) * m],
                );
            }
            self.column_solves += k;
        }
        self.scratch.pending.clear();
    }

    /// Ensures the columns of the support of `x` (its non-zero entries); none when the
    /// support is larger than the pool or [`Delassus::limit_columns`] allows
    /// ([`Delassus::mul_add`] then goes through the factor).
    pub fn ensure_support(
        &mut self,
        x: &[f64],
        stiffness: &SparseMatrix,
    ) -> Result<(), SolveError> {
        if !self.shape.dense
            && x.iter().filter(|&&v| v != 0.0).count() > self.pool.cap.min(self.pool.limit)
        {
            // more than the pool or the one-step workspaces hold: the products go
            // through the factor
            return Ok(());
        }
        for (b, &xb) in x.iter().enumerate() {
            if xb != 0.0 {
                self.request(b)?;
                if self.scratch.pending.len() == SOLVE_BLOCK {
                    self.compute_pending(stiffness);
                }
            }
        }
        self.compute_pending(stiffness);
        Ok(())
    }

    /// Whether every column of the support of `x` is in store (always on the dense path).
    pub fn has_support(&self, x: &[f64]) -> bool {
        self.shape.dense
            || x.iter()
                .zip(&self.pool.slot)
                .all(|(&xb, &s)| xb == 0.0 || s != NONE)
    }
}
