//! The Delassus operator of the contact rows (DESIGN.md §4, §8): `W = GᵀÂ⁻¹G`,
//! `W_D = GᵀÂ⁻¹K N G` and `W_N = GᵀNG` of eq. 56–60, and the `n`-space corrections
//! `Â⁻¹G x`, `Â⁻¹K N G x`, `N G x` that turn contact impulses back into velocities and
//! positions. `Â` is the scheme's factored step matrix (`M̂ = M + hθC + h²θ²K` of
//! eq. 47, or Schatzman–Paoli's `M + h²θK + (hθ/2)C`).
//!
//! The operator is indexed by *rows*: a contact `α` of dimension `d_α` (1 frictionless,
//! 2 or 3 with Coulomb friction, eq. 11) owns `d_α` consecutive columns of `G`, normal
//! first, and the block `W_αβ = G_αᵀÂ⁻¹G_β` is the `d_α × d_β` sub-block of rows
//! `α` and columns `β`. Frictionless scenes have one row per contact, exactly the
//! scalar operator of before. The solvers of [`crate::solvers`] see it only through
//! [`DelassusOperator`](crate::solvers::operator::DelassusOperator) (entries, column
//! products, products), with the dense
//! [`DenseOperator`](crate::solvers::operator::DenseOperator) of the gathered
//! sub-problems; they never import an integrator.
//!
//! Two storage paths, chosen by [`DelassusKind`]:
//!
//! * **dense**: `Â⁻¹G` (and `Â⁻¹K N G`) as dense `n × m` blocks plus dense `m × m`
//!   operators, all computed once per linearization (`m` or `2m` sparse solves). Each
//!   correction is then a few axpys: the fastest path for the tens of contacts of the
//!   bar and of the academic examples.
//! * **per-active-column**: only the columns `W_{:,β}` and `W_{D,:,β}` of contacts `β`
//!   that have been active are computed (one or two solves when `β` first becomes
//!   active; for a constant `G` they are kept across steps) and stored as `m`-vectors,
//!   never as `n`-vectors; the `n`-space corrections are one sparse solve of the
//!   gathered right-hand side `G x`. Memory is `O(m · k)` for `k` active contacts
//!   instead of `O(n · m)`, and the set-up cost is paid only for contacts that touch.
//!   This is the path for thousands of candidates on 10⁵–10⁶-dof meshes. The column
//!   pool is allocated at construction; when it is full, the column of the contact
//!   inactive for longest is recomputed on demand, so the step loop never allocates.
//!
//! * **dense on the contact zone** (contacts between bodies, [`Delassus::condense_zone`]):
//!   for a nonlinear `G` on a constant `Â`, every contact being nodal, `G = S B` with `S`
//!   the fixed selection of the `z` dofs any column can touch and `B` a few entries per
//!   column. `Y = Â⁻¹S`, `E = Â⁻¹K N S` (`n × z`) and the zone flexibilities `F = SᵀY`,
//!   `F_E = SᵀE` (`z × z`) are formed once (`z` or `2z` solves); a re-linearization is
//!   then `W = BᵀFB`, `W_D = BᵀF_E B` without a solve, and a correction `Â⁻¹G x` is
//!   `Y (B x)` over the zone columns under the rows that carry an impulse
//!   ([`ZoneStorage::Full`]). The θ-method schemes, which iterate on the zone alone
//!   ([`Delassus::zone_corrections`]), keep only the flexibilities by default
//!   ([`ZoneStorage::Flexibility`]; faster on every between-body scene measured but one,
//!   and smaller: two 20³ hex8 cubes' `Y`, `E` would take 2.3 GB, their `F`, `F_E`
//!   112 MB): they are formed [`ZONE_CHUNK`] columns at a time (`n × ZONE_CHUNK`
//!   scratch, threaded solves), and an `n`-space correction is one sparse solve of
//!   `G x`, as on the per-active-column path. Each storage falls back on the other where
//!   it does not fit the dense budget.
//!
//! * **matrix-free** (any path, [`Delassus::product`]): `W x = Gᵀ Â⁻¹ (G x)` through the
//!   factor, one sparse solve per product, no column stored. [`Delassus::mul_add`] falls
//!   back on it when a column of the support is not in store; the one-step problems
//!   past the dense workspaces (`max_active_rows`, [`Delassus::limit_columns`]) use it
//!   alone ([`crate::solvers::global`]).
//!
//! The `Auto` choice takes the dense path while the dense blocks stay under 2 GiB and
//! either `G` is constant (the blocks are formed once, by blocked solves) or there are
//! at most [`AUTO_DENSE_MAX_CONTACTS`] contacts (a nonlinear `G` re-forms every block at
//! every linearization); the per-active-column path otherwise. Measured
//! (`cargo bench --bench solid`, hex8 box pressed on a plane, every contact active):
//! 10k dofs and 225 contacts, dense 5.9 ms against columns 12.4 ms per step; 98k dofs
//! and 1024 contacts, dense 338 ms (805 MB of blocks) against columns 411 ms.
//! On the 9.7e5-dof slender hex bar with 81 contacts (`benches/solid_scaling.sh 4000`)
//! the dense blocks take 1.26 GB and the step 0.54 s, against 5.0 s on the columns path
//! (each of its corrections is a solve with the 9.7e5-dof factor): the budget is set
//! to 2 GiB, the same as the column pool's, a twelfth of these machines' memory.
//! Both give the same iterates (tested to round-off in `tests/regression_delassus_paths.rs`).

use serde::{Deserialize, Serialize};

use crate::contact::ContactJacobian;
use crate::error::Error;
use crate::linalg::{LinearSolver, SOLVE_BLOCK, SparseMatrix, spmv};
use crate::solvers::SolveError;
use faer::sparse::SparseColMatRef;

mod policy;
mod pool;
mod zone;

pub use policy::DelassusPlan;
use policy::*;
use zone::*;
pub use zone::{ZONE_CHUNK, ZoneStorage};

/// Position projection metric `N` (eq. 58 and remark 3, eq. 59–60).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum Metric {
    /// `N = I`: `q ← q + G τ` (eq. 58). Kicks only the contact dofs.
    Euclidean,
    /// `N = M̂⁻¹`: `q ← q + M̂⁻¹ G τ` (eq. 60); the same matrix as the velocity LCP.
    Mass,
}

impl Metric {
    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Metric::Euclidean => "euclidean",
            Metric::Mass => "mass",
        }
    }
}

/// How the Delassus data are stored (DESIGN.md §4).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum DelassusKind {
    /// Dense while the blocks fit in 2 GiB and `G` is constant (or the contacts are
    /// at most [`AUTO_DENSE_MAX_CONTACTS`]); per-active-column otherwise (default).
    /// Contacts between bodies are condensed on their contact zone, keeping its
    /// flexibilities in the θ-method schemes ([`ZoneStorage::Flexibility`]) and `Â⁻¹S`
    /// in Schatzman–Paoli's ([`ZoneStorage::Full`]), the other where the first does not
    /// fit.
    #[cfg_attr(
        feature = "cli",
        value(
            help = "Dense while the blocks fit in 2 GiB and G is constant (or the contacts \
                    are at most 64); per-active-column otherwise; contacts between bodies \
                    condensed on their contact zone (default)"
        )
    )]
    #[default]
    Auto,
    /// Dense `n × m` blocks `Â⁻¹G`, computed once per linearization; on a condensed
    /// contact zone, its `n × z` blocks `Â⁻¹S` ([`ZoneStorage::Full`]) where they fit.
    #[cfg_attr(
        feature = "cli",
        value(
            help = "Dense n × m blocks M̂⁻¹G, computed once per linearization; on a contact \
                    zone, its n × z blocks M̂⁻¹S where they fit"
        )
    )]
    Dense,
    /// Columns of the active contacts only, computed when first needed.
    Columns,
    /// For a nonlinear contact set condensed onto its contact zone: keep the zone's
    /// flexibilities `F = SᵀÂ⁻¹S` only ([`ZoneStorage::Flexibility`]: less memory,
    /// corrections by sparse solves) in every scheme, Schatzman–Paoli included, where the
    /// flexibilities fit; otherwise as `auto`.
    #[cfg_attr(
        feature = "cli",
        value(
            help = "For contacts between bodies condensed on their contact zone: keep only \
                    the zone's flexibilities F in every scheme (less memory, corrections by \
                    sparse solves); otherwise as auto"
        )
    )]
    Flexibility,
}

impl DelassusKind {
    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            DelassusKind::Auto => "auto",
            DelassusKind::Dense => "dense",
            DelassusKind::Columns => "columns",
            DelassusKind::Flexibility => "flexibility",
        }
    }
}

/// Largest contact count for which [`DelassusKind::Auto`] takes the dense path when `G`
/// changes with `q`.
pub const AUTO_DENSE_MAX_CONTACTS: usize = 64;
/// Largest dense `n × m` storage [`DelassusKind::Auto`] accepts (bytes).
const AUTO_DENSE_MAX_BYTES: usize = 2 << 30;
/// Memory budget of the per-active-column pool (bytes): columns of `m` values each.
const COLUMN_POOL_BYTES: usize = 2 << 30;
const NONE: usize = usize::MAX;

/// Which contact-space operator an entry or product refers to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Op {
    /// `W = GᵀÂ⁻¹G` (eq. 57).
    W,
    /// `W_D = GᵀÂ⁻¹K N G` (the stiffness feedback of eq. 56a).
    Wd,
    /// `W_N = GᵀNG` (eq. 58 or 60).
    Wn,
}

/// When the Delassus data are being formed: at set-up (before the first step, where
/// blocked solves may run on several threads and allocate their scratch) or inside the
/// step loop (sequential, allocation-free). Separate from whether `G` is constant: a
/// nonlinear structure with a constant `G` re-forms `W` in the step loop when `M̂ⁿ`
/// changes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// Building the integrator.
    Setup,
    /// Stepping.
    Step,
}

/// The factored step matrix with the Delassus data of one linearization of `G`.
#[derive(Debug)]
pub struct Delassus {
    /// The factored step matrix `Â` (any backend of [`crate::linalg::solver`]).
    pub factor: Box<dyn LinearSolver>,
    /// The contact Jacobian `G` at the current linearization point.
    pub jac: ContactJacobian,
    n: usize,
    m: usize,
    dense: bool,
    with_d: bool,
    metric: Metric,
    /// `G` does not depend on `q`: [`Delassus::refresh`] runs once, at set-up.
    g_constant: bool,
    /// `W_D` is formed (`with_d`, unless [`Delassus::without_wd`]): a nonlinear structure's
    /// Newton loop carries the projection's feedback in `F` and never reads it.
    need_wd: bool,
    /// Set-up or step loop ([`Delassus::start_stepping`]): the set-up may spread its
    /// blocked solves over threads (allocating), the step loop may not.
    phase: Phase,
    // dense path: Â⁻¹G and Â⁻¹K N G (n × m), W_N (m × m)
    cg: Vec<f64>,
    d: Vec<f64>,
    wn: Vec<f64>,
    // both paths: columns of W and W_D (m values each) in slots
    w: Vec<f64>,
    wd: Vec<f64>,
    slot: Vec<usize>,
    owner: Vec<usize>,
    stamp: Vec<u64>,
    used: usize,
    cap: usize,
    epoch: u64,
    /// Sparse solves spent on columns since construction (set-up included).
    pub column_solves: usize,
    /// Products through the factor ([`Delassus::product`]) since construction.
    pub products: usize,
    /// Largest support whose columns are stored ([`Delassus::limit_columns`]).
    limit: usize,
    /// The pool was sized by the memory budget, not by the caller.
    pool_auto: bool,
    t1: Vec<f64>,
    t2: Vec<f64>,
    // per-active-column path: contacts awaiting columns, and two n × SOLVE_BLOCK blocks
    pending: Vec<usize>,
    blk: Vec<f64>,
    blk2: Vec<f64>,
    /// `blk[n..2n]` holds `Â⁻¹G τ` for the position correction.
    ng_ready: bool,
    /// The contact zone's condensed data ([`Delassus::condense_zone`]).
    zone: Option<Zone>,
    /// The user's choice of storage (with [`DelassusKind::Auto`] or
    /// [`DelassusKind::Flexibility`] the zone may switch a per-active-column choice to
    /// the dense one).
    kind: DelassusKind,
}

impl Delassus {
    /// Stops forming `W_D = GᵀÂ⁻¹K N G` (`W` and `W_N` still are): for a caller that
    /// never reads it (`Op::Wd`, the projection feedback of [`Delassus::add_velocity_correction`]).
    pub fn without_wd(&mut self) {
        self.need_wd = false;
    }

    /// Marks the end of the set-up: from now on the blocks are formed by sequential,
    /// allocation-free solves ([`Phase`]).
    pub fn start_stepping(&mut self) {
        self.phase = Phase::Step;
    }

    /// Whether the blocks being formed now are formed once for the whole run (constant
    /// `G`, at set-up): they may then use the threaded solves and the tiled `K` products.
    fn condensing_once(&self) -> bool {
        self.g_constant && self.phase == Phase::Setup
    }

    /// Sizes the storage for `n` dofs and the `m` columns of `jac`; `with_d` adds
    /// `W_D`, `W_N` (projection schemes); `pool` columns on the per-active-column path
    /// (0: as many as fit in 2 GiB). Columns are computed by [`Delassus::refresh`] and
    /// [`Delassus::ensure`].
    pub fn new(
        factor: Box<dyn LinearSolver>,
        jac: ContactJacobian,
        n: usize,
        (kind, pool): (DelassusKind, usize),
        with_d: bool,
        metric: Metric,
        g_constant: bool,
    ) -> Result<Self, Error> {
        let m = jac.ncols();
        let per = if with_d { 2 } else { 1 };
        let dense = choose_dense(kind, n, m, per, g_constant);
        let cap = pool_cap(dense, pool, m, per);
        let nm = if dense {
            let nm = n.saturating_mul(m);
            let mut mem = crate::limits::MemoryEstimate::default();
            mem.add(
                "dense Delassus blocks M̂⁻¹G (n × m)",
                nm as u64,
                if with_d { 16 } else { 8 },
            );
            mem.check(
                "scheme.delassus",
                format!("dense: {n} dofs × {m} contact rows"),
            )?;
            nm
        } else {
            0
        };
        let nb = if dense {
            0
        } else {
            n * SOLVE_BLOCK.min(m).max(2)
        };
        Ok(Delassus {
            factor,
            jac,
            n,
            m,
            dense,
            with_d,
            metric,
            g_constant,
            need_wd: with_d,
            phase: Phase::Setup,
            cg: vec![0.0; nm],
            d: vec![0.0; if with_d { nm } else { 0 }],
            wn: vec![0.0; if dense && with_d { m * m } else { 0 }],
            w: vec![0.0; m * cap],
            wd: vec![0.0; if with_d { m * cap } else { 0 }],
            slot: vec![NONE; m],
            owner: vec![NONE; cap],
            stamp: vec![0; cap],
            used: 0,
            cap,
            epoch: 1,
            column_solves: 0,
            products: 0,
            limit: usize::MAX,
            pool_auto: pool == 0,
            t1: vec![0.0; n],
            t2: vec![0.0; n],
            pending: Vec::with_capacity(SOLVE_BLOCK),
            blk: vec![0.0; nb],
            blk2: vec![0.0; if with_d { nb } else { 0 }],
            ng_ready: false,
            zone: None,
            kind,
        })
    }

    /// The dense columns `Â⁻¹G` and `Â⁻¹K N G` (`n` values per row, row after row)
    /// when the velocity and position corrections of [`Delassus::add_velocity_correction`]
    /// and [`Delassus::add_position_correction`] are exactly their axpys (the dense path
    /// without a zone, `M̂⁻¹` metric): what the integrator may fuse into one pass over
    /// the state with the same operations in the same order (issue 35).
    pub fn dense_columns(&self) -> Option<(&[f64], &[f64])> {
        (self.dense && self.zone.is_none() && self.metric == Metric::Mass)
            .then_some((&self.cg[..], &self.d[..]))
    }

    /// Stores no columns for a support of more than `rows` rows (the one-step
    /// workspaces' cap): such problems are solved matrix-free, and their columns, computed
    /// `rows` solves at a time, would cost more than the products they save.
    pub fn limit_columns(&mut self, rows: usize) {
        self.limit = rows;
        if !self.dense && self.pool_auto && self.cap > rows.max(1) && self.used == 0 {
            // the default pool need not outgrow the largest set stored at once
            let (m, cap) = (self.m, rows.max(1));
            self.cap = cap;
            self.w = vec![0.0; m * cap];
            self.wd = vec![0.0; if self.with_d { m * cap } else { 0 }];
            self.owner = vec![NONE; cap];
            self.stamp = vec![0; cap];
        }
    }

    /// Number of contacts `m`.
    pub fn len(&self) -> usize {
        self.m
    }

    /// True without contacts.
    pub fn is_empty(&self) -> bool {
        self.m == 0
    }

    /// The projection metric `N`.
    pub fn metric(&self) -> Metric {
        self.metric
    }

    /// True on the dense path.
    pub fn is_dense(&self) -> bool {
        self.dense
    }

    /// Columns the per-active-column pool holds at most.
    pub fn capacity(&self) -> usize {
        self.cap
    }

    /// One phrase for summaries: which path runs.
    pub fn describe(&self) -> String {
        describe_path(
            self.zone.as_ref().map(|z| (z.dofs.len(), z.storage)),
            self.dense,
            self.n,
            self.m,
            self.cap,
        )
    }

    /// `G` changed (or at start): the dense path recomputes every column now, the
    /// per-active-column path forgets its columns and recomputes them on demand.
    pub fn refresh(&mut self, stiffness: &SparseMatrix) {
        self.slot.iter_mut().for_each(|s| *s = NONE);
        self.owner.iter_mut().for_each(|s| *s = NONE);
        self.used = 0;
        if !self.dense {
            return;
        }
        let (n, m) = (self.n, self.m);
        if let Some(zone) = &mut self.zone {
            zone.condensed(&self.jac, false, &mut self.w);
        } else {
            for a in 0..m {
                let col = &mut self.cg[a * n..(a + 1) * n];
                col.iter_mut().for_each(|x| *x = 0.0);
                self.jac.axpy(a, 1.0, col);
            }
            let once = self.condensing_once();
            solve_columns(self.factor.as_mut(), &mut self.cg, m, once);
            self.column_solves += m;
            for b in 0..m {
                for a in 0..m {
                    self.w[a + b * m] = self.jac.dot(a, &self.cg[b * n..(b + 1) * n]);
                }
            }
        }
        for b in 0..m {
            self.slot[b] = b;
            self.owner[b] = b;
        }
        self.used = m;
        if !self.with_d {
            return;
        }
        if self.need_wd {
            match &mut self.zone {
                Some(zone) => zone.condensed(&self.jac, true, &mut self.wd),
                None => self.form_dense_wd(stiffness),
            }
        }
        for b in 0..m {
            for a in 0..m {
                self.wn[a + b * m] = match self.metric {
                    Metric::Euclidean => self.jac.col_dot_col(a, b),
                    Metric::Mass => self.w[a + b * m],
                };
            }
        }
    }

    /// The dense path's `Â⁻¹K N G` and `W_D` (after `Â⁻¹G`).
    fn form_dense_wd(&mut self, stiffness: &SparseMatrix) {
        let (n, m) = (self.n, self.m);
        // K N G column by column: K (Â⁻¹G_b) for the mass metric, K G_b (a combination
        // of the few columns of K that G_b touches) for the Euclidean one. Sequential:
        // the products are bound by memory bandwidth, and on two threads the 98k-dof
        // cube's 1024 columns took 8.7 s against 6.1 s on one.
        let (cg, jac, metric) = (&self.cg, &self.jac, self.metric);
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
            k_times_columns(k, cg, &mut self.d, n);
        } else {
            for (b, d) in self.d.chunks_mut(n).enumerate() {
                column(b, d);
            }
        }
        let once = self.condensing_once();
        solve_columns(self.factor.as_mut(), &mut self.d, m, once);
        self.column_solves += m;
        for b in 0..m {
            for a in 0..m {
                self.wd[a + b * m] = self.jac.dot(a, &self.d[b * n..(b + 1) * n]);
            }
        }
    }

    /// Entry `(a, b)` of `op`; column `b` must be available ([`Delassus::ensure`]).
    #[inline]
    pub fn entry(&self, op: Op, a: usize, b: usize) -> f64 {
        let m = self.m;
        match op {
            Op::W => self.w[self.slot[b] * m + a],
            Op::Wd => self.wd[self.slot[b] * m + a],
            Op::Wn => match self.metric {
                Metric::Mass => self.w[self.slot[b] * m + a],
                Metric::Euclidean if self.dense => self.wn[b * m + a],
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
        if x.iter().all(|&v| v == 0.0) {
            return;
        }
        self.products += 1;
        self.gather_g(x);
        match (op, self.metric) {
            (Op::Wn, Metric::Euclidean) => {}
            (Op::W, _) | (Op::Wn, Metric::Mass) => self.factor.solve_in_place(&mut self.t1),
            (Op::Wd, metric) => {
                if metric == Metric::Mass {
                    self.factor.solve_in_place(&mut self.t1);
                }
                spmv(stiffness.as_ref(), &self.t1, &mut self.t2);
                std::mem::swap(&mut self.t1, &mut self.t2);
                self.factor.solve_in_place(&mut self.t1);
            }
        }
        for (a, o) in out.iter_mut().enumerate() {
            *o += s * self.jac.dot(a, &self.t1);
        }
    }

    /// `out += s · op · x` from the stored columns, which must hold the support of `x`.
    fn mul_add_stored(&self, op: Op, s: f64, x: &[f64], out: &mut [f64]) {
        let m = self.m;
        for (b, &xb) in x.iter().enumerate() {
            if xb == 0.0 {
                continue;
            }
            let f = s * xb;
            let col = match (op, self.metric) {
                (Op::W, _) | (Op::Wn, Metric::Mass) => &self.w,
                (Op::Wd, _) => &self.wd,
                (Op::Wn, Metric::Euclidean) => {
                    if self.dense {
                        &self.wn
                    } else {
                        for (a, o) in out.iter_mut().enumerate() {
                            *o += f * self.jac.col_dot_col(a, b);
                        }
                        continue;
                    }
                }
            };
            let sb = self.slot[b];
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
        if self.dense && self.zone.is_none() {
            let n = self.n;
            for (a, &xa) in x.iter().enumerate() {
                if xa != 0.0 {
                    axpy(s * xa, &self.cg[a * n..(a + 1) * n], y);
                }
            }
            return;
        }
        self.gather_g(x);
        self.factor.solve_in_place(&mut self.t1);
        axpy(s, &self.t1, y);
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
        let n = self.n;
        let feedback = kfac != 0.0 && tau_used.iter().any(|&t| t != 0.0);
        let any_tau = tau.iter().any(|&t| t != 0.0);
        if !self.corrects_by_solves() {
            self.add_inverse_g(1.0, p, v);
            if feedback && let Some(zone) = &mut self.zone {
                zone.apply(&self.jac, true, kfac, tau_used, v);
            } else if feedback {
                for (a, &xa) in tau_used.iter().enumerate() {
                    if xa != 0.0 {
                        axpy(kfac * xa, &self.d[a * n..(a + 1) * n], v);
                    }
                }
            }
            return;
        }
        // blk columns: [G τ_used, G τ] (M̂⁻¹ metric: then solved)
        self.ng_ready = false;
        if self.metric == Metric::Mass && (feedback || any_tau) {
            let blk = &mut self.blk[..2 * n];
            blk.iter_mut().for_each(|x| *x = 0.0);
            let (c0, c1) = blk.split_at_mut(n);
            for a in 0..self.m {
                if feedback && tau_used[a] != 0.0 {
                    self.jac.axpy(a, tau_used[a], c0);
                }
                if tau[a] != 0.0 {
                    self.jac.axpy(a, tau[a], c1);
                }
            }
            // right-hand sides on the contact zone: the forward sweep's zero blocks skipped
            self.factor.solve_sparse_rhs_in_place(blk, 2);
            self.ng_ready = any_tau;
        }
        self.gather_g(p);
        if feedback {
            match self.metric {
                Metric::Mass => spmv(stiffness.as_ref(), &self.blk[..n], &mut self.t2),
                Metric::Euclidean => {
                    let g = &mut self.blk[..n];
                    g.iter_mut().for_each(|x| *x = 0.0);
                    for (a, &t) in tau_used.iter().enumerate() {
                        if t != 0.0 {
                            self.jac.axpy(a, t, g);
                        }
                    }
                    spmv(stiffness.as_ref(), g, &mut self.t2);
                }
            }
            axpy(kfac, &self.t2, &mut self.t1);
        }
        if p.iter().any(|&x| x != 0.0) || feedback {
            self.factor.solve_in_place(&mut self.t1);
            axpy(1.0, &self.t1, v);
        }
    }

    /// `q += N G τ` with the `τ` given to the last [`Delassus::add_velocity_correction`].
    pub fn add_position_correction(&mut self, tau: &[f64], q: &mut [f64]) {
        if self.metric == Metric::Mass && self.corrects_by_solves() {
            if self.ng_ready {
                let n = self.n;
                axpy(1.0, &self.blk[n..2 * n], q);
            }
            return;
        }
        self.add_ng(1.0, tau, q);
    }

    /// `y += s · N G x` (`N = I` or `Â⁻¹`).
    pub fn add_ng(&mut self, s: f64, x: &[f64], y: &mut [f64]) {
        match self.metric {
            Metric::Euclidean => {
                for (a, &xa) in x.iter().enumerate() {
                    if xa != 0.0 {
                        self.jac.axpy(a, s * xa, y);
                    }
                }
            }
            Metric::Mass => self.add_inverse_g(s, x, y),
        }
    }

    /// `t1 = G x`.
    fn gather_g(&mut self, x: &[f64]) {
        self.t1.iter_mut().for_each(|v| *v = 0.0);
        for (a, &xa) in x.iter().enumerate() {
            if xa != 0.0 {
                self.jac.axpy(a, xa, &mut self.t1);
            }
        }
    }
}

/// Solves the `m` columns of a dense `n × m` block of [`Delassus::refresh`]: on every
/// thread when the blocks are condensed `once` (constant `G`, at set-up), otherwise
/// sequentially and without allocating (`refresh` inside the step loop).
fn solve_columns(factor: &mut dyn LinearSolver, x: &mut [f64], m: usize, once: bool) {
    if once {
        factor.solve_block_in_place_par(x, m);
    } else {
        factor.solve_block_in_place(x, m);
    }
}

/// Columns per pass of [`k_times_columns`].
const PRODUCT_TILE: usize = 32;

/// Rows per block of [`k_times_columns`]'s transposes (a block of the tile, 64 × 32
/// values, is 16 KiB: it stays in the first-level cache).
const TRANSPOSE_ROWS: usize = 64;

/// `y = K x` for the `m` columns of `x` (`n × m`, column-major), [`PRODUCT_TILE`]
/// columns per pass over `K`: each tile is transposed to row-major so that every entry
/// of `K` updates a contiguous row of the tile. One pass per column streams all of `K`
/// each time; on the 98 304-dof cube the 1024 products took 5.4 s one column at a time
/// (bound by memory bandwidth), and the whole set-up 19.1 s against 16.2 s tiled. The
/// tiles are spread over rayon's threads (each thread its two tiles, `2 n ×`
/// [`PRODUCT_TILE`] values, allocated here: called at set-up only); a tile's columns do
/// not depend on the thread. On the two 20³ cubes' zone (2 646 columns) the products
/// took 4.0 s on one thread.
fn k_times_columns(k: SparseColMatRef<'_, usize, f64>, x: &[f64], y: &mut [f64], n: usize) {
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
fn axpy(s: f64, x: &[f64], y: &mut [f64]) {
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
