//! The contact zone's condensation (issue 18, issue 35): the step matrix condensed
//! once onto the dofs a Jacobian column can touch, so that a re-linearization of `G`
//! forms `W = BᵀFB` and `W_D = BᵀF_E B` without a solve, and a Newton iteration's
//! corrections need none on the zone ([`Delassus::zone_corrections`]).

use super::*;

/// The step matrix condensed once onto the contact-zone dofs `S`: `Y = Â⁻¹S` and
/// `E = Â⁻¹K N S` (`n × z` each) and the zone's flexibilities `F = SᵀY`, `F_E = SᵀE`
/// (`z × z`). With `G = S B` (`B` the few entries of each column), a re-linearization is
/// `W = BᵀFB`, `W_D = BᵀF_E B` (no solve, no `n`-vector), and a correction `Â⁻¹G x =
/// Y (B x)` touches only the columns of `Y` under the contacts that carry an impulse.
///
/// `M̂` couples no two bodies, so a column of `F` or `F_E` is zero outside its body's
/// rows: every product runs over [`Zone::span`] only (half the work with two bodies).
#[derive(Debug)]
pub(super) struct Zone {
    /// Zone index of each dof (`NONE` outside the zone).
    pub(super) pos: Vec<usize>,
    /// The zone's dofs.
    pub(super) dofs: Vec<usize>,
    /// Whether `y`, `e` are held (else empty).
    pub(super) storage: ZoneStorage,
    pub(super) y: Vec<f64>,
    pub(super) e: Vec<f64>,
    pub(super) f: Vec<f64>,
    pub(super) fe: Vec<f64>,
    /// Rows `lo..hi` of the zone outside which column `k` of `F` and of `F_E` is zero.
    pub(super) span: Vec<(usize, usize)>,
    /// `F B` and `F_E B` (`z × m`), and a zone vector.
    pub(super) fb: Vec<f64>,
    pub(super) feb: Vec<f64>,
    pub(super) r: Vec<f64>,
    /// Zone index of each entry of the Jacobian (as [`ContactJacobian::entries`] lists them).
    pub(super) bpos: Vec<usize>,
    /// The Jacobian's non-zero entries, column after column: first of each column
    /// (`m + 1`), zone index, value.
    pub(super) cptr: Vec<usize>,
    pub(super) cpos: Vec<usize>,
    pub(super) cval: Vec<f64>,
    /// The Jacobian's dofs and values when `F B` (`[0]`) and `F_E B` (`[1]`) were formed:
    /// while `G` is still that one, a correction is `(F B) p` (`m` columns) rather than
    /// `F (B p)` (`z` columns).
    pub(super) formed_at: [(Vec<usize>, Vec<f64>); 2],
    /// Rows whose column `B_α` never changes (a plane contact beside contacts between
    /// bodies): their `F B` columns and their `W`, `W_D` entries with each other are
    /// formed once.
    pub(super) fixed: Vec<bool>,
    /// `W` and `W_D` formed once already.
    pub(super) formed: [bool; 2],
}

impl Zone {
    /// A zone on `dofs` (`pos` their inverse) with flexibilities `f`, `fe` (`fe` empty
    /// where `W_D` is not formed) and, for [`ZoneStorage::Full`], the columns `y`, `e`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn new(
        pos: Vec<usize>,
        dofs: Vec<usize>,
        storage: ZoneStorage,
        (y, e): (Vec<f64>, Vec<f64>),
        (f, fe): (Vec<f64>, Vec<f64>),
        fixed: Vec<bool>,
        jac: &ContactJacobian,
    ) -> Zone {
        let (z, m) = (dofs.len(), jac.ncols());
        let nnz = jac.entries().1.len();
        let span = (0..z)
            .map(|k| {
                let nonzero =
                    |i: &usize| f[k * z + i] != 0.0 || fe.get(k * z + i).is_some_and(|&v| v != 0.0);
                let lo = (0..z).find(nonzero).unwrap_or(0);
                let hi = (lo..z).rev().find(nonzero).map_or(lo, |i| i + 1);
                (lo, hi)
            })
            .collect();
        let snapshot = || (vec![NONE; nnz], vec![f64::NAN; nnz]);
        Zone {
            pos,
            dofs,
            storage,
            y,
            e,
            fb: vec![0.0; z * m],
            feb: vec![0.0; if fe.is_empty() { 0 } else { z * m }],
            f,
            fe,
            span,
            r: vec![0.0; z],
            bpos: vec![NONE; nnz],
            cptr: vec![0; m + 1],
            cpos: vec![0; nnz],
            cval: vec![0.0; nnz],
            formed_at: [snapshot(), snapshot()],
            fixed,
            formed: [false; 2],
        }
    }

    /// `out = Bᵀ X B` (`m × m`, column-major) with `X = F_E` (`e`) or `F`; after the
    /// first time only the entries of a changing row (not [`Zone::fixed`]).
    pub(super) fn condensed(&mut self, jac: &ContactJacobian, e: bool, out: &mut [f64]) {
        let z = self.dofs.len();
        let m = jac.ncols();
        let all = !self.formed[usize::from(e)];
        let (ptr, dofs, vals) = jac.entries();
        for (p, &d) in self.bpos.iter_mut().zip(dofs) {
            *p = self.pos[d];
        }
        let (x, xb) = if e {
            (&self.fe, &mut self.feb)
        } else {
            (&self.f, &mut self.fb)
        };
        pulp::Arch::new().dispatch(TimesB {
            ptr,
            bpos: &self.bpos,
            vals,
            span: &self.span,
            x,
            out: xb,
            fixed: (!all).then_some(&self.fixed[..]),
        });
        // the non-zero entries of each column, in their order
        let (cptr, cpos, cval) = (&mut self.cptr, &mut self.cpos, &mut self.cval);
        let mut len = 0;
        for a in 0..m {
            for i in ptr[a]..ptr[a + 1] {
                if vals[i] != 0.0 {
                    (cpos[len], cval[len]) = (self.bpos[i], vals[i]);
                    len += 1;
                }
            }
            cptr[a + 1] = len;
        }
        let (cptr, cpos, cval) = (&self.cptr[..], &self.cpos[..], &self.cval[..]);
        let fixed = &self.fixed;
        // the sum's neutral element, so that each entry is the bits of the iterator's sum
        let zero: f64 = std::iter::empty::<f64>().sum();
        for b in 0..m {
            let col = &xb[b * z..(b + 1) * z];
            let need = |a: usize| all || !fixed[a] || !fixed[b];
            // `B_aᵀ col`, four rows of `W` at a time where their columns have as many
            // entries (independent sums in flight; each in its entries' order)
            let mut a = 0;
            while a < m {
                let l = cptr[a + 1] - cptr[a];
                if a + 4 <= m && (1..4).all(|j| cptr[a + j + 1] - cptr[a + j] == l) {
                    let mut acc = [zero; 4];
                    for t in 0..l {
                        for (j, s) in acc.iter_mut().enumerate() {
                            let i = cptr[a + j] + t;
                            *s += cval[i] * col[cpos[i]];
                        }
                    }
                    for (j, s) in acc.into_iter().enumerate() {
                        if need(a + j) {
                            out[a + j + b * m] = s;
                        }
                    }
                    a += 4;
                } else {
                    if need(a) {
                        let mut s = zero;
                        for i in cptr[a]..cptr[a + 1] {
                            s += cval[i] * col[cpos[i]];
                        }
                        out[a + b * m] = s;
                    }
                    a += 1;
                }
            }
        }
        let at = &mut self.formed_at[usize::from(e)];
        at.0.copy_from_slice(dofs);
        at.1.copy_from_slice(vals);
        self.formed[usize::from(e)] = true;
    }

    /// Whether `F B` (`e`: `F_E B`) was formed at the Jacobian `jac` is now.
    pub(super) fn formed_at(&self, jac: &ContactJacobian, e: bool) -> bool {
        let (_, dofs, vals) = jac.entries();
        let at = &self.formed_at[usize::from(e)];
        self.formed[usize::from(e)]
            && at.0 == dofs
            && at
                .1
                .iter()
                .zip(vals)
                .all(|(a, b)| a.to_bits() == b.to_bits())
    }

    /// `r = B x` (zone coordinates).
    pub(super) fn gather_b(&mut self, jac: &ContactJacobian, x: &[f64]) {
        self.r.iter_mut().for_each(|v| *v = 0.0);
        for (a, &xa) in x.iter().enumerate() {
            if xa != 0.0 {
                let (dofs, vals) = jac.col(a);
                for (&d, &g) in dofs.iter().zip(vals) {
                    if g != 0.0 {
                        self.r[self.pos[d]] += xa * g;
                    }
                }
            }
        }
    }

    /// `y += s X r` for a zone matrix `X` (`F` or `F_E`, `z × z`, column-major), over the
    /// non-zero entries of `r` and the rows of each column's [`Zone::span`].
    pub(super) fn zone_times(&self, fe: bool, s: f64, y: &mut [f64]) {
        let x = if fe { &self.fe } else { &self.f };
        pulp::Arch::new().dispatch(Combine {
            cols: x,
            n: y.len(),
            weights: &self.r,
            span: Some(&self.span),
            s,
            y,
        });
    }

    /// `y += s (X B) x` for `X B` (`F B` or `F_E B`, `z × m`) formed at the current `G`.
    pub(super) fn times_formed(&self, fe: bool, s: f64, x: &[f64], y: &mut [f64]) {
        let xb = if fe { &self.feb } else { &self.fb };
        let z = y.len();
        pulp::Arch::new().dispatch(Combine {
            cols: xb,
            n: z,
            weights: x,
            span: None,
            s,
            y,
        });
    }

    /// `y += s X (B x)` for the zone's `X` (`Y` or `E`, `n × z`).
    pub(super) fn apply(
        &mut self,
        jac: &ContactJacobian,
        use_e: bool,
        s: f64,
        x: &[f64],
        y: &mut [f64],
    ) {
        let n = y.len();
        self.gather_b(jac, x);
        let cols = if use_e { &self.e } else { &self.y };
        for (k, &rk) in self.r.iter().enumerate() {
            if rk != 0.0 {
                axpy(s * rk, &cols[k * n..(k + 1) * n], y);
            }
        }
    }
}

/// `X B` column by column (`X` is `F` or `F_E`, `z × z`; the columns `b` not
/// [`Zone::fixed`] when `fixed` is given), each entry `g` of `B_b` adding `g X_k` over
/// the span of column `k`: compiled by pulp's dispatch for the CPU's vector width, with
/// separate multiply and add (the bits of the plain loop).
pub(super) struct TimesB<'a> {
    ptr: &'a [usize],
    bpos: &'a [usize],
    vals: &'a [f64],
    span: &'a [(usize, usize)],
    x: &'a [f64],
    out: &'a mut [f64],
    fixed: Option<&'a [bool]>,
}

impl pulp::WithSimd for TimesB<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        let z = self.span.len();
        if z == 0 {
            return;
        }
        for (b, col) in self.out.chunks_exact_mut(z).enumerate() {
            if self.fixed.is_some_and(|f| f[b]) {
                continue;
            }
            col.iter_mut().for_each(|v| *v = 0.0);
            for i in self.ptr[b]..self.ptr[b + 1] {
                let g = self.vals[i];
                if g != 0.0 {
                    let k = self.bpos[i];
                    let (lo, hi) = self.span[k];
                    axpy(g, &self.x[k * z + lo..k * z + hi], &mut col[lo..hi]);
                }
            }
        }
    }
}

/// `y += s Σ_b x_b C_b` over the non-zero `x_b` (`C` is `n × len(x)`), over the rows
/// `span[b]` of each column where spans are given (the rows outside are zero), as
/// [`TimesB`].
pub(super) struct Combine<'a> {
    cols: &'a [f64],
    n: usize,
    weights: &'a [f64],
    span: Option<&'a [(usize, usize)]>,
    s: f64,
    y: &'a mut [f64],
}

impl pulp::WithSimd for Combine<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        let n = self.n;
        for (b, &xb) in self.weights.iter().enumerate() {
            if xb != 0.0 {
                let (lo, hi) = self.span.map_or((0, n), |s| s[b]);
                axpy(
                    self.s * xb,
                    &self.cols[b * n + lo..b * n + hi],
                    &mut self.y[lo..hi],
                );
            }
        }
    }
}

/// `f[i + j z] = x[j n + zone[i]]`: the zone rows of the `n`-columns of `x` (as many as
/// `f` has `z`-columns).
pub(super) fn restrict(zone: &[usize], x: &[f64], n: usize, f: &mut [f64]) {
    let z = zone.len();
    for (fc, xc) in f.chunks_mut(z).zip(x.chunks(n)) {
        for (o, &d) in fc.iter_mut().zip(zone) {
            *o = xc[d];
        }
    }
}

impl Delassus {
    /// Condenses the step matrix onto the contact zone `zone` (sorted dofs) for a
    /// nonlinear `G` on a constant `Â` (the zone blocks `Y`, `E`, `F`, `F_E` of the module
    /// doc): once, instead of `m` (`2m`) solves at every re-linearization; the
    /// flexibilities from the factor and its tangent where it can
    /// ([`crate::linalg::SpdFactor::zone_flexibilities`]), else `z` solves (`2z` with
    /// `W_D`). Taken on the dense path
    /// (also when [`DelassusKind::Auto`] had chosen the per-active-column path for a
    /// nonlinear `G`: its reason, `m` solves per re-linearization, is gone) when the
    /// `m × m` operators and the zone's blocks fit the dense budget: `Y`, `E` and `F`,
    /// `F_E` ([`ZoneStorage::Full`]), or `F`, `F_E` alone ([`ZoneStorage::Flexibility`]),
    /// the flexibilities first under [`DelassusKind::Flexibility`], and under
    /// [`DelassusKind::Auto`] when `zone_iterates` (the caller iterates on the zone alone,
    /// [`Delassus::zone_corrections`]), the blocks first otherwise; returns the storage taken, `None`
    /// when the zone was not condensed. `fixed` flags the rows whose column never changes
    /// (a linear contact block beside nonlinear ones): their entries are formed once.
    pub fn condense_zone(
        &mut self,
        zone: &[usize],
        fixed: Vec<bool>,
        stiffness: &SparseMatrix,
        zone_iterates: bool,
    ) -> Option<ZoneStorage> {
        let (n, z, m) = (self.shape.n, zone.len(), self.shape.m);
        let per = if self.shape.with_d && self.shape.need_wd {
            2
        } else {
            1
        };
        if (!self.shape.dense && self.shape.kind == DelassusKind::Columns)
            || self.shape.g_constant
            || z == 0
            || zone.iter().any(|&d| d >= n)
        {
            return None;
        }
        let storage = zone_storage(
            n,
            z,
            m,
            per,
            zone_preference(self.shape.kind, zone_iterates),
        )?;
        if !self.shape.dense {
            // the per-active-column choice becomes the dense one: m × m operators
            self.shape.dense = true;
            self.pool.cap = m;
            self.pool.w = vec![0.0; m * m];
            self.pool.wd = vec![0.0; if self.shape.with_d { m * m } else { 0 }];
            self.blocks.wn = vec![0.0; if self.shape.with_d { m * m } else { 0 }];
            self.pool.owner = vec![NONE; m];
            self.pool.stamp = vec![0; m];
        }
        // the flexibility zone corrects by solves of [G τ_used, G τ] (`blk`, 2 n)
        let nb = match storage {
            ZoneStorage::Full => 0,
            ZoneStorage::Flexibility => 2 * n,
        };
        self.scratch.blk = vec![0.0; nb];
        self.scratch.blk2 = Vec::new();
        if storage == ZoneStorage::Flexibility {
            self.factor.reserve_sparse_rhs(2);
        }
        let mut pos = vec![NONE; n];
        for (k, &d) in zone.iter().enumerate() {
            pos[d] = k;
        }
        // the flexibilities alone under the M̂⁻¹ metric (or without W_D): from the
        // factor and its tangent along K, on the zone's paths (`linalg::zone_flex`)
        let from_factor = (storage == ZoneStorage::Flexibility
            && (per == 1 || self.shape.metric == Metric::Mass))
            .then(|| {
                self.factor
                    .zone_flexibilities(zone, (per == 2).then(|| stiffness.as_ref()))
            })
            .flatten();
        let swept = from_factor.is_none();
        self.zone_by_tangent = !swept;
        let (mut f, mut fe) = from_factor.unwrap_or_else(|| {
            (
                vec![0.0; z * z],
                vec![0.0; if per == 2 { z * z } else { 0 }],
            )
        });
        // else the columns of the zone, a chunk of `cols` at a time (all at once when the
        // n × z blocks are kept): Y = Â⁻¹S, E = Â⁻¹K N S, and their zone rows
        let cols = match storage {
            ZoneStorage::Full => z,
            ZoneStorage::Flexibility => ZONE_CHUNK.min(z),
        };
        let mut yc = vec![0.0; if swept { n * cols } else { 0 }];
        let mut ec = vec![0.0; if swept && per == 2 { n * cols } else { 0 }];
        for start in (0..z).step_by(cols).filter(|_| swept) {
            let w = cols.min(z - start);
            let (yb, eb) = (
                &mut yc[..n * w],
                &mut ec[..if per == 2 { n * w } else { 0 }],
            );
            yb.iter_mut().for_each(|v| *v = 0.0);
            for (k, &d) in zone[start..start + w].iter().enumerate() {
                yb[k * n + d] = 1.0;
            }
            // at set-up: the threaded blocked solves, skipping the factor's blocks that
            // a unit vector on the zone never reaches (issue 35)
            self.factor.solve_block_for_rows(yb, w, None);
            self.column_solves += w;
            restrict(zone, yb, n, &mut f[start * z..(start + w) * z]);
            if per == 2 {
                let k = stiffness.as_ref();
                match self.shape.metric {
                    Metric::Mass => k_times_columns(k, yb, eb, n),
                    Metric::Euclidean => {
                        eb.iter_mut().for_each(|v| *v = 0.0);
                        for (c, &d) in zone[start..start + w].iter().enumerate() {
                            let col = &mut eb[c * n..(c + 1) * n];
                            for p in k.col_ptr()[d]..k.col_ptr()[d + 1] {
                                col[k.row_idx()[p]] += k.val()[p];
                            }
                        }
                    }
                }
                // the flexibilities read only the zone's rows of E (the backward sweep
                // stops at their ancestors); the full storage keeps E whole
                let rows = (storage == ZoneStorage::Flexibility).then_some(zone);
                self.factor.solve_block_for_rows(eb, w, rows);
                self.column_solves += w;
                restrict(zone, eb, n, &mut fe[start * z..(start + w) * z]);
            }
        }
        // the n × z blocks kept, or the chunks' scratch freed
        let (y, e) = match storage {
            ZoneStorage::Full => (yc, ec),
            ZoneStorage::Flexibility => (Vec::new(), Vec::new()),
        };
        // the n × m blocks are never formed on this path
        self.blocks.cg = Vec::new();
        self.blocks.d = Vec::new();
        self.zone = Some(Zone::new(
            pos,
            zone.to_vec(),
            storage,
            (y, e),
            (f, fe),
            fixed,
            &self.jac,
        ));
        Some(storage)
    }

    /// The contact zone's dofs when it keeps its flexibilities only
    /// ([`ZoneStorage::Flexibility`]): the integrator can then iterate on the zone alone
    /// ([`Delassus::zone_corrections`]) and correct the whole state once per step.
    pub fn flexibility_zone(&self) -> Option<&[usize]> {
        self.zone
            .as_ref()
            .filter(|z| z.storage == ZoneStorage::Flexibility)
            .map(|z| z.dofs.as_slice())
    }

    /// The zone rows of the corrections of [`Delassus::add_velocity_correction`] and
    /// [`Delassus::add_position_correction`], without a solve: `v = F (B p) + kfac ·
    /// F_E (B τ_used)` and `q = N G τ` on the zone (`F (B τ)` for the `M̂⁻¹` metric, `B τ`
    /// for `I`), both overwritten (zone order, [`Delassus::flexibility_zone`]). `F_E`
    /// exists where `W_D` is formed. Allocation-free; `O(z · nnz(B x))`.
    pub fn zone_corrections(
        &mut self,
        p: &[f64],
        kfac: f64,
        tau_used: &[f64],
        tau: &[f64],
        v: &mut [f64],
        q: &mut [f64],
    ) {
        let metric = self.shape.metric;
        let zone = self
            .zone
            .as_mut()
            .expect("zone_corrections needs a condensed contact zone");
        v.iter_mut().for_each(|x| *x = 0.0);
        q.iter_mut().for_each(|x| *x = 0.0);
        // `(F B) p`: `m` columns where `F (B p)` reads `z`; `F B` is current whenever `W`
        // was formed at this `G` (the Newton loop's case)
        let fb_current = zone.formed_at(&self.jac, false);
        if fb_current {
            zone.times_formed(false, 1.0, p, v);
        } else {
            zone.gather_b(&self.jac, p);
            zone.zone_times(false, 1.0, v);
        }
        if kfac != 0.0 && !zone.fe.is_empty() && tau_used.iter().any(|&t| t != 0.0) {
            if zone.formed_at(&self.jac, true) {
                zone.times_formed(true, kfac, tau_used, v);
            } else {
                zone.gather_b(&self.jac, tau_used);
                zone.zone_times(true, kfac, v);
            }
        }
        if tau.iter().any(|&t| t != 0.0) {
            match metric {
                Metric::Mass if fb_current => zone.times_formed(false, 1.0, tau, q),
                Metric::Mass => {
                    zone.gather_b(&self.jac, tau);
                    zone.zone_times(false, 1.0, q);
                }
                Metric::Euclidean => {
                    zone.gather_b(&self.jac, tau);
                    q.copy_from_slice(&zone.r);
                }
            }
        }
    }

    /// Whether the `n`-space corrections are sparse solves (the per-active-column path
    /// and [`ZoneStorage::Flexibility`]) rather than combinations of stored columns.
    pub(super) fn corrects_by_solves(&self) -> bool {
        !self.shape.dense
            || self
                .zone
                .as_ref()
                .is_some_and(|z| z.storage == ZoneStorage::Flexibility)
    }
}
