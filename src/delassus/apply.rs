//! Using the operators in a step: entries and products of `W` for the contact-space
//! solvers (stored columns, or matrix-free through the factor), and the `n`-space
//! corrections `Â⁻¹G x`, `Â⁻¹K N G x`, `N G x` that turn impulses and projections into
//! velocities and positions.

use super::*;

impl Delassus {
    /// Entry `(a, b)` of `op`; column `b` must be available ([`Delassus::ensure`]).
    #[inline]
    pub fn entry(&self, op: Op, a: usize, b: usize) -> f64 {
        let m = self.shape.m;
        match op {
            Op::W => self.pool.w[self.pool.slot[b] * m + a],
            Op::Wd => self.pool.wd[self.pool.slot[b] * m + a],
            Op::Wn => match self.shape.metric {
                // the kinetic metric's W_N is formed before the position problem
                // (`prepare_position_metric`)
                Metric::Mass if let Some(k) = &self.kinetic => k.wn[b * m + a],
                Metric::Mass => self.pool.w[self.pool.slot[b] * m + a],
                Metric::Euclidean if self.shape.dense => self.blocks.wn[b * m + a],
                Metric::Euclidean => self.jac.col_dot_col(a, b),
            },
        }
    }

    /// `out += s · op · x`: from the stored columns when the support of `x` is in store,
    /// else through the factor ([`Delassus::product`]).
    pub fn mul_add(
        &mut self,
        op: Op,
        s: f64,
        x: &[f64],
        out: &mut [f64],
        stiffness: &SparseMatrix,
    ) {
        if op == Op::Wn && self.shape.metric == Metric::Mass && self.kinetic_mul_add(s, x, out) {
            return;
        }
        if !self.has_support(x) {
            self.product(op, s, x, out, stiffness);
            return;
        }
        self.mul_add_stored(op, s, x, out);
    }

    /// `out += s · op · x` through the factor, with no stored column (the matrix-free
    /// operator of the module doc): `Gᵀ Â⁻¹ (G x)` for `W` (one sparse solve),
    /// `Gᵀ Â⁻¹ K N (G x)` for `W_D` (two with the `M̂⁻¹` metric, one with `I`),
    /// `Gᵀ N (G x)` for `W_N`. Allocation-free.
    pub fn product(
        &mut self,
        op: Op,
        s: f64,
        x: &[f64],
        out: &mut [f64],
        stiffness: &SparseMatrix,
    ) {
        if x.iter().all(|&v| v == 0.0)
            || (op == Op::Wn
                && self.shape.metric == Metric::Mass
                && self.kinetic_mul_add(s, x, out))
            || self.product_by_flexibility(op, s, x, out)
        {
            return;
        }
        self.products += 1;
        self.gather_g(x);
        match (op, self.shape.metric) {
            (Op::Wn, Metric::Euclidean) => {}
            (Op::W, _) | (Op::Wn, Metric::Mass) => self.factor.solve_in_place(&mut self.scratch.t1),
            (Op::Wd, metric) => {
                if metric == Metric::Mass {
                    self.factor.solve_in_place(&mut self.scratch.t1);
                }
                spmv(stiffness.as_ref(), &self.scratch.t1, &mut self.scratch.t2);
                std::mem::swap(&mut self.scratch.t1, &mut self.scratch.t2);
                self.factor.solve_in_place(&mut self.scratch.t1);
            }
        }
        for (a, o) in out.iter_mut().enumerate() {
            *o += s * self.jac.dot(a, &self.scratch.t1);
        }
    }

    /// `out += s · op · x` from the stored columns, which must hold the support of `x`.
    pub(super) fn mul_add_stored(&self, op: Op, s: f64, x: &[f64], out: &mut [f64]) {
        let m = self.shape.m;
        for (b, &xb) in x.iter().enumerate() {
            if xb == 0.0 {
                continue;
            }
            let f = s * xb;
            let col = match (op, self.shape.metric) {
                (Op::W, _) | (Op::Wn, Metric::Mass) => &self.pool.w,
                (Op::Wd, _) => &self.pool.wd,
                (Op::Wn, Metric::Euclidean) => {
                    if self.shape.dense {
                        &self.blocks.wn
                    } else {
                        for (a, o) in out.iter_mut().enumerate() {
                            *o += f * self.jac.col_dot_col(a, b);
                        }
                        continue;
                    }
                }
            };
            let sb = self.pool.slot[b];
            for (o, &c) in out.iter_mut().zip(&col[sb * m..(sb + 1) * m]) {
                *o += f * c;
            }
        }
    }

    /// `y += s · Â⁻¹ G x`.
    pub fn add_inverse_g(&mut self, s: f64, x: &[f64], y: &mut [f64]) {
        if x.iter().all(|&v| v == 0.0) {
            return;
        }
        if let Some(zone) = &mut self.zone
            && zone.storage == ZoneStorage::Full
        {
            zone.apply(&self.jac, false, s, x, y);
            return;
        }
        if self.shape.dense && self.zone.is_none() {
            let n = self.shape.n;
            for (a, &xa) in x.iter().enumerate() {
                if xa != 0.0 {
                    axpy(s * xa, &self.blocks.cg[a * n..(a + 1) * n], y);
                }
            }
            return;
        }
        self.gather_g(x);
        self.factor.solve_in_place(&mut self.scratch.t1);
        axpy(s, &self.scratch.t1, y);
    }

    /// `v += Â⁻¹ (G p + kfac · K N G τ_used)`, the velocity update of eq. 56a
    /// (`kfac = −hθ`, or 0 without the projection feedback), and prepares the position
    /// correction `N G τ` for [`Delassus::add_position_correction`]. On the
    /// per-active-column path this is one sparse solve, plus one block solve of
    /// `Â⁻¹G[τ_used, τ]` for the `M̂⁻¹` metric.
    pub fn add_velocity_correction(
        &mut self,
        p: &[f64],
        kfac: f64,
        tau_used: &[f64],
        tau: &[f64],
        v: &mut [f64],
        stiffness: &SparseMatrix,
    ) {
        let n = self.shape.n;
        let feedback = kfac != 0.0 && tau_used.iter().any(|&t| t != 0.0);
        let any_tau = tau.iter().any(|&t| t != 0.0);
        if !self.corrects_by_solves() {
            self.add_inverse_g(1.0, p, v);
            if feedback && let Some(zone) = &mut self.zone {
                zone.apply(&self.jac, true, kfac, tau_used, v);
            } else if feedback {
                for (a, &xa) in tau_used.iter().enumerate() {
                    if xa != 0.0 {
                        axpy(kfac * xa, &self.blocks.d[a * n..(a + 1) * n], v);
                    }
                }
            }
            return;
        }
        // blk columns: [G τ_used, G τ] (M̂⁻¹ metric: then solved)
        self.scratch.ng_ready = false;
        if self.shape.metric == Metric::Mass && (feedback || (any_tau && self.kinetic.is_none())) {
            let blk = &mut self.scratch.blk[..2 * n];
            blk.iter_mut().for_each(|x| *x = 0.0);
            let (c0, c1) = blk.split_at_mut(n);
            for a in 0..self.shape.m {
                if feedback && tau_used[a] != 0.0 {
                    self.jac.axpy(a, tau_used[a], c0);
                }
                if tau[a] != 0.0 {
                    self.jac.axpy(a, tau[a], c1);
                }
            }
            // right-hand sides on the contact zone: the forward sweep's zero blocks skipped
            self.factor.solve_sparse_rhs_in_place(blk, 2);
            self.scratch.ng_ready = any_tau;
        }
        self.gather_g(p);
        if feedback {
            match self.shape.metric {
                Metric::Mass => spmv(
                    stiffness.as_ref(),
                    &self.scratch.blk[..n],
                    &mut self.scratch.t2,
                ),
                Metric::Euclidean => {
                    let g = &mut self.scratch.blk[..n];
                    g.iter_mut().for_each(|x| *x = 0.0);
                    for (a, &t) in tau_used.iter().enumerate() {
                        if t != 0.0 {
                            self.jac.axpy(a, t, g);
                        }
                    }
                    spmv(stiffness.as_ref(), g, &mut self.scratch.t2);
                }
            }
            axpy(kfac, &self.scratch.t2, &mut self.scratch.t1);
        }
        if p.iter().any(|&x| x != 0.0) || feedback {
            self.factor.solve_in_place(&mut self.scratch.t1);
            axpy(1.0, &self.scratch.t1, v);
        }
    }

    /// `q += N G τ` with the `τ` given to the last [`Delassus::add_velocity_correction`].
    pub fn add_position_correction(&mut self, tau: &[f64], q: &mut [f64]) {
        if self.shape.metric == Metric::Mass && self.add_kinetic_ng(1.0, tau, q) {
            return;
        }
        if self.shape.metric == Metric::Mass && self.corrects_by_solves() {
            if self.scratch.ng_ready {
                let n = self.shape.n;
                axpy(1.0, &self.scratch.blk[n..2 * n], q);
            }
            return;
        }
        self.add_ng(1.0, tau, q);
    }

    /// `y += s · N G x` (`N = I`, `Â⁻¹`, or `M⁻¹` with the kinetic metric).
    pub fn add_ng(&mut self, s: f64, x: &[f64], y: &mut [f64]) {
        match self.shape.metric {
            Metric::Euclidean => {
                for (a, &xa) in x.iter().enumerate() {
                    if xa != 0.0 {
                        self.jac.axpy(a, s * xa, y);
                    }
                }
            }
            Metric::Mass => {
                if !self.add_kinetic_ng(s, x, y) {
                    self.add_inverse_g(s, x, y)
                }
            }
        }
    }

    /// `t1 = G x`.
    pub(super) fn gather_g(&mut self, x: &[f64]) {
        self.scratch.t1.iter_mut().for_each(|v| *v = 0.0);
        for (a, &xa) in x.iter().enumerate() {
            if xa != 0.0 {
                self.jac.axpy(a, xa, &mut self.scratch.t1);
            }
        }
    }
}
