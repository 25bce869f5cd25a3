//! The per-active-column path: the columns `Â⁻¹G_b` of the contacts a one-step problem
//! reads, computed on demand into a pool of slots and kept while `G` holds (epochs).

use super::*;

impl Delassus {
    /// Starts a new step: columns used from now on are protected from eviction until
    /// the next call.
    pub fn next_epoch(&mut self) {
        self.epoch += 1;
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
        if !self.dense && idx.len() > self.limit {
            // more than the one-step workspaces hold: the problem is solved matrix-free
            // and its products go through the factor (past the pool but within the
            // workspaces, the entries are needed: a pool error)
            return Ok(());
        }
        for &b in idx {
            self.request(b)?;
            if self.pending.len() == SOLVE_BLOCK {
                self.compute_pending(stiffness);
            }
        }
        self.compute_pending(stiffness);
        Ok(())
    }

    /// Marks column `b` as used in this epoch; if absent, gives it a slot (evicting
    /// the column unused for longest) and queues it for computation.
    fn request(&mut self, b: usize) -> Result<(), SolveError> {
        let s = self.slot[b];
        if s != NONE {
            self.stamp[s] = self.epoch;
            return Ok(());
        }
        let s = if self.used < self.cap {
            self.used += 1;
            self.used - 1
        } else {
            let (s, &st) = self
                .stamp
                .iter()
                .enumerate()
                .min_by_key(|&(_, &st)| st)
                .expect("pool has at least one slot");
            if st >= self.epoch {
                return Err(SolveError::Capacity { cap: self.cap });
            }
            self.slot[self.owner[s]] = NONE;
            s
        };
        self.slot[b] = s;
        self.owner[s] = b;
        self.stamp[s] = self.epoch;
        self.pending.push(b);
        Ok(())
    }

    /// Computes the queued columns: `W_{:,β} = GᵀÂ⁻¹G_β` and, with projection,
    /// `W_{D,:,β} = GᵀÂ⁻¹K N G_β`, by block solves.
    fn compute_pending(&mut self, stiffness: &SparseMatrix) {
        let k = self.pending.len();
        if k == 0 {
            return;
        }
        let (n, m) = (self.n, self.m);
        let blk = &mut self.blk[..n * k];
        blk.iter_mut().for_each(|x| *x = 0.0);
        for (c, &b) in self.pending.iter().enumerate() {
            self.jac.axpy(b, 1.0, &mut blk[c * n..(c + 1) * n]);
        }
        // column by column: a column must not depend on the batch it was computed in,
        // or a resumed run (which recomputes its active columns at once) diverges
        self.factor.solve_columns_independently(blk, k);
        for (c, &b) in self.pending.iter().enumerate() {
            let s = self.slot[b];
            self.jac
                .transpose_mul(&blk[c * n..(c + 1) * n], &mut self.w[s * m..(s + 1) * m]);
        }
        self.column_solves += k;
        if self.with_d && self.need_wd {
            let blk2 = &mut self.blk2[..n * k];
            for (c, &b) in self.pending.iter().enumerate() {
                let out = &mut blk2[c * n..(c + 1) * n];
                match self.metric {
                    Metric::Mass => spmv(stiffness.as_ref(), &blk[c * n..(c + 1) * n], out),
                    Metric::Euclidean => {
                        self.t1.iter_mut().for_each(|x| *x = 0.0);
                        self.jac.axpy(b, 1.0, &mut self.t1);
                        spmv(stiffness.as_ref(), &self.t1, out);
                    }
                }
            }
            self.factor.solve_columns_independently(blk2, k);
            for (c, &b) in self.pending.iter().enumerate() {
                let s = self.slot[b];
                self.jac
                    .transpose_mul(&blk2[c * n..(c + 1) * n], &mut self.wd[s * m..(s + 1) * m]);
            }
            self.column_solves += k;
        }
        self.pending.clear();
    }

    /// Ensures the columns of the support of `x` (its non-zero entries); none when the
    /// support is larger than the pool or [`Delassus::limit_columns`] allows
    /// ([`Delassus::mul_add`] then goes through the factor).
    pub fn ensure_support(
        &mut self,
        x: &[f64],
        stiffness: &SparseMatrix,
    ) -> Result<(), SolveError> {
        if !self.dense && x.iter().filter(|&&v| v != 0.0).count() > self.cap.min(self.limit) {
            // more than the pool or the one-step workspaces hold: the products go
            // through the factor
            return Ok(());
        }
        for (b, &xb) in x.iter().enumerate() {
            if xb != 0.0 {
                self.request(b)?;
                if self.pending.len() == SOLVE_BLOCK {
                    self.compute_pending(stiffness);
                }
            }
        }
        self.compute_pending(stiffness);
        Ok(())
    }

    /// Whether every column of the support of `x` is in store (always on the dense path).
    pub fn has_support(&self, x: &[f64]) -> bool {
        self.dense
            || x.iter()
                .zip(&self.slot)
                .all(|(&xb, &s)| xb == 0.0 || s != NONE)
    }
}
