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

/// What the contact zone keeps ([`Delassus::condense_zone`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ZoneStorage {
    /// `Y = Â⁻¹S`, `E = Â⁻¹K N S` (`n × z`) and `F`, `F_E` (`z × z`): corrections are
    /// combinations of the columns of `Y` and `E`.
    Full,
    /// `F`, `F_E` only: `n`-space corrections by one sparse solve of `G x`, zone rows by
    /// [`Delassus::zone_corrections`].
    Flexibility,
}

/// Columns of the zone formed per pass by [`ZoneStorage::Flexibility`]'s set-up: a
/// multiple of [`crate::linalg::SOLVE_CHUNK`], so that the factor's block solves see the
/// same chunks as [`ZoneStorage::Full`]'s and give `F`, `F_E` bit for bit, and two
/// chunks so that both threads solve at once.
pub const ZONE_CHUNK: usize = 2 * crate::linalg::SOLVE_CHUNK;

/// The step matrix condensed once onto the contact-zone dofs `S`: `Y = Â⁻¹S` and
/// `E = Â⁻¹K N S` (`n × z` each) and the zone's flexibilities `F = SᵀY`, `F_E = SᵀE`
/// (`z × z`). With `G = S B` (`B` the few entries of each column), a re-linearization is
/// `W = BᵀFB`, `W_D = BᵀF_E B` (no solve, no `n`-vector), and a correction `Â⁻¹G x =
/// Y (B x)` touches only the columns of `Y` under the contacts that carry an impulse.
///
/// `M̂` couples no two bodies, so a column of `F` or `F_E` is zero outside its body's
/// rows: every product runs over [`Zone::span`] only (half the work with two bodies).
#[derive(Debug)]
struct Zone {
    /// Zone index of each dof (`NONE` outside the zone).
    pos: Vec<usize>,
    /// The zone's dofs.
    dofs: Vec<usize>,
    /// Whether `y`, `e` are held (else empty).
    storage: ZoneStorage,
    y: Vec<f64>,
    e: Vec<f64>,
    f: Vec<f64>,
    fe: Vec<f64>,
    /// Rows `lo..hi` of the zone outside which column `k` of `F` and of `F_E` is zero.
    span: Vec<(usize, usize)>,
    /// `F B` and `F_E B` (`z × m`), and a zone vector.
    fb: Vec<f64>,
    feb: Vec<f64>,
    r: Vec<f64>,
    /// Zone index of each entry of the Jacobian (as [`ContactJacobian::entries`] lists them).
    bpos: Vec<usize>,
    /// The Jacobian's non-zero entries, column after column: first of each column
    /// (`m + 1`), zone index, value.
    cptr: Vec<usize>,
    cpos: Vec<usize>,
    cval: Vec<f64>,
    /// The Jacobian's dofs and values when `F B` (`[0]`) and `F_E B` (`[1]`) were formed:
    /// while `G` is still that one, a correction is `(F B) p` (`m` columns) rather than
    /// `F (B p)` (`z` columns).
    formed_at: [(Vec<usize>, Vec<f64>); 2],
    /// Rows whose column `B_α` never changes (a plane contact beside contacts between
    /// bodies): their `F B` columns and their `W`, `W_D` entries with each other are
    /// formed once.
    fixed: Vec<bool>,
    /// `W` and `W_D` formed once already.
    formed: [bool; 2],
}

impl Zone {
    /// A zone on `dofs` (`pos` their inverse) with flexibilities `f`, `fe` (`fe` empty
    /// where `W_D` is not formed) and, for [`ZoneStorage::Full`], the columns `y`, `e`.
    #[allow(clippy::too_many_arguments)]
    fn new(
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
    fn condensed(&mut self, jac: &ContactJacobian, e: bool, out: &mut [f64]) {
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
    fn formed_at(&self, jac: &ContactJacobian, e: bool) -> bool {
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
    fn gather_b(&mut self, jac: &ContactJacobian, x: &[f64]) {
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
    fn zone_times(&self, fe: bool, s: f64, y: &mut [f64]) {
        let x = if fe { &self.fe } else { &self.f };
        pulp::Arch::new().dispatch(ZoneTimes {
            x,
            r: &self.r,
            span: &self.span,
            s,
            y,
        });
    }

    /// `y += s (X B) x` for `X B` (`F B` or `F_E B`, `z × m`) formed at the current `G`.
    fn times_formed(&self, fe: bool, s: f64, x: &[f64], y: &mut [f64]) {
        let xb = if fe { &self.feb } else { &self.fb };
        let z = y.len();
        pulp::Arch::new().dispatch(Combine {
            cols: xb,
            n: z,
            weights: x,
            s,
            y,
        });
    }

    /// `y += s X (B x)` for the zone's `X` (`Y` or `E`, `n × z`).
    fn apply(&mut self, jac: &ContactJacobian, use_e: bool, s: f64, x: &[f64], y: &mut [f64]) {
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
struct TimesB<'a> {
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

/// `y += s X r` over the non-zero entries of `r` and each column's span (as [`TimesB`]).
struct ZoneTimes<'a> {
    x: &'a [f64],
    r: &'a [f64],
    span: &'a [(usize, usize)],
    s: f64,
    y: &'a mut [f64],
}

impl pulp::WithSimd for ZoneTimes<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        let z = self.r.len();
        for (k, &rk) in self.r.iter().enumerate() {
            if rk != 0.0 {
                let (lo, hi) = self.span[k];
                axpy(
                    self.s * rk,
                    &self.x[k * z + lo..k * z + hi],
                    &mut self.y[lo..hi],
                );
            }
        }
    }
}

/// `y += s Σ_b x_b C_b` over the non-zero `x_b` (`C` is `n × len(x)`), as [`TimesB`].
struct Combine<'a> {
    cols: &'a [f64],
    n: usize,
    weights: &'a [f64],
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
                axpy(self.s * xb, &self.cols[b * n..(b + 1) * n], self.y);
            }
        }
    }
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

    /// Condenses the step matrix onto the contact zone `zone` (sorted dofs) for a
    /// nonlinear `G` on a constant `Â` (the zone blocks `Y`, `E`, `F`, `F_E` of the module
    /// doc): `z` solves (`2z` with `W_D`), once, instead of `m` (`2m`) at every
    /// re-linearization. Taken on the dense path
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
        let (n, z, m) = (self.n, zone.len(), self.m);
        let per = if self.with_d && self.need_wd { 2 } else { 1 };
        if (!self.dense && self.kind == DelassusKind::Columns)
            || self.g_constant
            || z == 0
            || zone.iter().any(|&d| d >= n)
        {
            return None;
        }
        let storage = zone_storage(n, z, m, per, zone_preference(self.kind, zone_iterates))?;
        if !self.dense {
            // the per-active-column choice becomes the dense one: m × m operators
            self.dense = true;
            self.cap = m;
            self.w = vec![0.0; m * m];
            self.wd = vec![0.0; if self.with_d { m * m } else { 0 }];
            self.wn = vec![0.0; if self.with_d { m * m } else { 0 }];
            self.owner = vec![NONE; m];
            self.stamp = vec![0; m];
        }
        // the flexibility zone corrects by solves of [G τ_used, G τ] (`blk`, 2 n)
        let nb = match storage {
            ZoneStorage::Full => 0,
            ZoneStorage::Flexibility => 2 * n,
        };
        self.blk = vec![0.0; nb];
        self.blk2 = Vec::new();
        if storage == ZoneStorage::Flexibility {
            self.factor.reserve_sparse_rhs(2);
        }
        let mut pos = vec![NONE; n];
        for (k, &d) in zone.iter().enumerate() {
            pos[d] = k;
        }
        let mut f = vec![0.0; z * z];
        let mut fe = vec![0.0; if per == 2 { z * z } else { 0 }];
        // the columns of the zone, a chunk of `cols` at a time (all at once when the
        // n × z blocks are kept): Y = Â⁻¹S, E = Â⁻¹K N S, and their zone rows
        let cols = match storage {
            ZoneStorage::Full => z,
            ZoneStorage::Flexibility => ZONE_CHUNK.min(z),
        };
        let mut yc = vec![0.0; n * cols];
        let mut ec = vec![0.0; if per == 2 { n * cols } else { 0 }];
        for start in (0..z).step_by(cols) {
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
                match self.metric {
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
        self.cg = Vec::new();
        self.d = Vec::new();
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
        let metric = self.metric;
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
    fn corrects_by_solves(&self) -> bool {
        !self.dense
            || self
                .zone
                .as_ref()
                .is_some_and(|z| z.storage == ZoneStorage::Flexibility)
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

    /// Where [`Delassus::new`], [`Delassus::limit_columns`] and
    /// [`Delassus::condense_zone`] put the Delassus data of `m` contact rows on `n` dofs,
    /// and its bytes: the same decisions, with nothing formed (`zone`: the contact zone's
    /// dofs when the set asks to be condensed, [`crate::contact::ContactSet::condensed`]).
    #[allow(clippy::too_many_arguments)]
    pub fn plan(
        n: usize,
        m: usize,
        (kind, pool): (DelassusKind, usize),
        with_d: bool,
        g_constant: bool,
        zone: Option<usize>,
        limit: usize,
        zone_iterates: bool,
    ) -> DelassusPlan {
        let per = if with_d { 2 } else { 1 };
        let dense = choose_dense(kind, n, m, per, g_constant);
        let mut cap = pool_cap(dense, pool, m, per);
        if !dense && pool == 0 && cap > limit.max(1) {
            cap = limit.max(1);
        }
        let z = zone
            .filter(|&z| {
                (dense || matches!(kind, DelassusKind::Auto | DelassusKind::Flexibility))
                    && !g_constant
                    && z > 0
            })
            .and_then(|z| {
                zone_storage(n, z, m, per, zone_preference(kind, zone_iterates)).map(|s| (z, s))
            });
        let (n8, m8) = (n as u64 * 8, m as u64 * 8);
        let per = per as u64;
        let bytes = match z {
            Some((z, ZoneStorage::Full)) => zone_bytes(n, z, m, per as usize) as u64,
            Some((z, ZoneStorage::Flexibility)) => {
                (flexibility_bytes(n, z, m, per as usize)
                    + flexibility_scratch_bytes(n, z, per as usize)) as u64
            }
            None if dense => n8 * m as u64 * per + m8 * m as u64 * (1 + 2 * u64::from(with_d)),
            None => m8 * cap as u64 * per + n8 * SOLVE_BLOCK.min(m).max(2) as u64 * per + 2 * n8,
        };
        DelassusPlan {
            dense: dense || z.is_some(),
            describe: describe_path(
                z,
                dense || z.is_some(),
                n,
                m,
                if z.is_some() { m } else { cap },
            ),
            bytes,
        }
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

    /// Whether every column of the support of `x` is in store (always on the dense path).
    pub fn has_support(&self, x: &[f64]) -> bool {
        self.dense
            || x.iter()
                .zip(&self.slot)
                .all(|(&xb, &s)| xb == 0.0 || s != NONE)
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

/// The planned Delassus data ([`Delassus::plan`]).
#[derive(Clone, Debug, PartialEq)]
pub struct DelassusPlan {
    /// The phrase [`Delassus::describe`] will give.
    pub describe: String,
    /// Every column formed per linearization (dense, or dense on the contact zone).
    pub dense: bool,
    /// Bytes of the blocks, columns and scratch.
    pub bytes: u64,
}

/// [`DelassusKind::Auto`]'s and the user's choice of the dense path.
fn choose_dense(kind: DelassusKind, n: usize, m: usize, per: usize, g_constant: bool) -> bool {
    match kind {
        DelassusKind::Dense => true,
        DelassusKind::Columns => false,
        DelassusKind::Auto | DelassusKind::Flexibility => {
            (g_constant || m <= AUTO_DENSE_MAX_CONTACTS)
                && n.saturating_mul(m).saturating_mul(8 * per) <= AUTO_DENSE_MAX_BYTES
        }
    }
}

/// Columns the store holds: all on the dense path, else the caller's pool or as many
/// as fit in the pool budget.
fn pool_cap(dense: bool, pool: usize, m: usize, per: usize) -> usize {
    if dense {
        m
    } else if pool > 0 {
        m.min(pool)
    } else {
        m.min((COLUMN_POOL_BYTES / (8 * per * m.max(1))).max(1))
    }
}

/// Bytes of the contact zone's blocks (`Y`, `E`: `n × z`; `F`, `F_E`: `z × z`; `F B`,
/// `F_E B`: `z × m`) and of the `m × m` operators.
fn zone_bytes(n: usize, z: usize, m: usize, per: usize) -> usize {
    n.saturating_mul(z)
        .saturating_mul(8 * per)
        .saturating_add(m.saturating_mul(m).saturating_mul(8 * (per + 1)))
        .saturating_add(z.saturating_mul(z + m).saturating_mul(8 * per))
}

/// Bytes of [`ZoneStorage::Flexibility`]'s data: `F`, `F_E`, `F B`, `F_E B`, the `m × m`
/// operators and the two `n`-vectors of its correction solves. The dense budget bounds
/// these; the set-up's scratch ([`flexibility_scratch_bytes`]) is freed after it.
fn flexibility_bytes(n: usize, z: usize, m: usize, per: usize) -> usize {
    m.saturating_mul(m)
        .saturating_mul(8 * (per + 1))
        .saturating_add(z.saturating_mul(z + m).saturating_mul(8 * per))
        .saturating_add(n.saturating_mul(16))
}

/// The `n ×` [`ZONE_CHUNK`] blocks (`Y` and, with `W_D`, `E`) of
/// [`ZoneStorage::Flexibility`]'s set-up: freed once the flexibilities are formed, but
/// part of the run's peak, so the ledger counts them.
fn flexibility_scratch_bytes(n: usize, z: usize, per: usize) -> usize {
    n.saturating_mul(ZONE_CHUNK.min(z)).saturating_mul(8 * per)
}

/// The zone storage tried first: the flexibilities where the user asks for them, and
/// under [`DelassusKind::Auto`] where the integrator iterates on the zone alone (the
/// θ-method core; Schatzman–Paoli's loop corrects `q` at every iteration and keeps the
/// columns). Measured with `zone_iterates`, flexibilities against `Y`, `E` (medians of
/// two runs, `--no-fields --no-plots`): `hex_bars.toml` 300 steps 6.7 against 9.2 ms per
/// step; two 12³ cubes 33 against 51 ms and 150 against 322 MiB; two 16³ cubes 116
/// against 178 ms and 387 MiB against 1.1 GiB; `sliding_block_on_slab.toml` 3.9 ms both;
/// `block_stack.toml` 12.8 against 12.2 ms.
fn zone_preference(kind: DelassusKind, zone_iterates: bool) -> ZoneStorage {
    match kind {
        DelassusKind::Flexibility => ZoneStorage::Flexibility,
        DelassusKind::Auto if zone_iterates => ZoneStorage::Flexibility,
        _ => ZoneStorage::Full,
    }
}

/// What [`Delassus::condense_zone`] keeps of a zone of `z` dofs: the `preferred` storage
/// if it fits the dense budget, else the other one if it does, else nothing.
fn zone_storage(
    n: usize,
    z: usize,
    m: usize,
    per: usize,
    preferred: ZoneStorage,
) -> Option<ZoneStorage> {
    let fits = |s: ZoneStorage| match s {
        ZoneStorage::Full => zone_bytes(n, z, m, per) <= AUTO_DENSE_MAX_BYTES,
        ZoneStorage::Flexibility => flexibility_bytes(n, z, m, per) <= AUTO_DENSE_MAX_BYTES,
    };
    let other = match preferred {
        ZoneStorage::Full => ZoneStorage::Flexibility,
        ZoneStorage::Flexibility => ZoneStorage::Full,
    };
    [preferred, other].into_iter().find(|&s| fits(s))
}

/// `f[i + j z] = x[j n + zone[i]]`: the zone rows of the `n`-columns of `x` (as many as
/// `f` has `z`-columns).
fn restrict(zone: &[usize], x: &[f64], n: usize, f: &mut [f64]) {
    let z = zone.len();
    for (fc, xc) in f.chunks_mut(z).zip(x.chunks(n)) {
        for (o, &d) in fc.iter_mut().zip(zone) {
            *o = xc[d];
        }
    }
}

/// The phrase of a path: the zone's dofs, dense, or the per-active-column pool.
fn describe_path(
    zone: Option<(usize, ZoneStorage)>,
    dense: bool,
    n: usize,
    m: usize,
    cap: usize,
) -> String {
    if let Some((z, storage)) = zone {
        let (kept, corrections) = match storage {
            ZoneStorage::Full => (format!("Â⁻¹S {n}×{z}"), "(Â⁻¹S)(Bx)"),
            ZoneStorage::Flexibility => (
                format!("F = SᵀÂ⁻¹S {z}×{z} (Â⁻¹S {n}×{z} not kept)"),
                "by one sparse solve",
            ),
        };
        format!(
            "Delassus dense on the contact zone: {kept} condensed once ({z} zone \
             dofs), W = BᵀFB {m}×{m} re-formed per linearization without a solve \
             (constant blocks once), corrections {corrections}"
        )
    } else if dense {
        format!("Delassus dense: Â⁻¹G {n}×{m} and W {m}×{m} condensed per linearization")
    } else {
        format!(
            "Delassus per-active-column: W columns computed when a contact first \
             activates (pool of {cap} columns of {m}), corrections by one sparse solve"
        )
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
        for c in 0..cols {
            for (j, &v) in xs[c * n..(c + 1) * n].iter().enumerate() {
                xt[j * T + c] = v;
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
        for c in 0..cols {
            for (i, v) in ys[c * n..(c + 1) * n].iter_mut().enumerate() {
                *v = yt[i * T + c];
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

    /// The zone storage decisions at the sizes the README quotes: the two 8³ cubes keep
    /// `Y`, `E`; the two 20³ cubes (54 243 dofs, 2 646 zone dofs, 441 rows, with `W_D`)
    /// would need 2.3 GB of `n × z` blocks and keep the flexibilities (112 MB); the two
    /// 40³ cubes (408 483 dofs, 10 086 zone dofs, 1 681 rows) keep the flexibilities
    /// (1.9 GB, under the 2 GiB budget, plus 0.8 GB of set-up scratch in the plan); a
    /// face of 100 × 100 nodes on both sides (60 000 zone dofs: 58 GB) is not condensed.
    #[test]
    fn zone_storage_follows_the_budget() {
        assert_eq!(
            zone_storage(4_131, 486, 81, 2, ZoneStorage::Full),
            Some(ZoneStorage::Full)
        );
        assert_eq!(
            zone_storage(4_131, 486, 81, 2, ZoneStorage::Flexibility),
            Some(ZoneStorage::Flexibility)
        );
        assert!(zone_bytes(54_243, 2_646, 441, 2) > AUTO_DENSE_MAX_BYTES);
        assert_eq!(
            zone_storage(54_243, 2_646, 441, 2, ZoneStorage::Full),
            Some(ZoneStorage::Flexibility)
        );
        let b = flexibility_bytes(54_243, 2_646, 441, 2);
        assert!((110 << 20..130 << 20).contains(&b), "{b}");
        assert_eq!(
            zone_storage(408_483, 10_086, 1_681, 2, ZoneStorage::Full),
            Some(ZoneStorage::Flexibility)
        );
        for s in [ZoneStorage::Full, ZoneStorage::Flexibility] {
            assert_eq!(zone_storage(1_000_000, 60_000, 10_000, 2, s), None);
        }
        assert_eq!(
            zone_preference(DelassusKind::Auto, true),
            ZoneStorage::Flexibility
        );
        assert_eq!(
            zone_preference(DelassusKind::Auto, false),
            ZoneStorage::Full
        );
        assert_eq!(
            zone_preference(DelassusKind::Dense, true),
            ZoneStorage::Full
        );
        let plan = Delassus::plan(
            408_483,
            1_681,
            (DelassusKind::Auto, 0),
            true,
            false,
            Some(10_086),
            4096,
            true,
        );
        let expect = flexibility_bytes(408_483, 10_086, 1_681, 2)
            + flexibility_scratch_bytes(408_483, 10_086, 2);
        assert_eq!(plan.bytes, expect as u64);
        assert!(plan.describe.contains("not kept"), "{}", plan.describe);
    }

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
            model: crate::model::solid::MaterialModel::Linear,
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
