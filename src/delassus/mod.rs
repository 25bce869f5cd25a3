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
//!   112 MB): a supernodal factor gives them without a full sweep, from `L⁻¹S` on the
//!   zone's elimination-tree paths and the factor's tangent along `K`
//!   ([`crate::linalg::SpdFactor::zone_flexibilities`]: two 40³ cubes' set-up 349 →
//!   178 s), other factors and the Euclidean metric in [`ZONE_CHUNK`] columns at a
//!   time (`n × ZONE_CHUNK` scratch, threaded solves); an `n`-space correction is one
//!   sparse solve of `G x`, as on the per-active-column path. Each storage falls back on the other where
//!   it does not fit the dense budget.
//!
//! * **matrix-free** (any path, [`Delassus::product`]): `W x = Gᵀ Â⁻¹ (G x)` through the
//!   factor, one sparse solve per product, no column stored. [`Delassus::mul_add`] falls
//!   back on it when a column of the support is not in store; the one-step problems
//!   past the dense workspaces (`max_active_rows`, [`Delassus::limit_columns`]) use it
//!   alone ([`crate::solvers::global`]). For a constant `G` on the per-active-column
//!   path whose problems go matrix-free, the products of `W` go through the
//!   flexibilities `F` of the dofs `G` acts on instead, `W x = Bᵀ F (B x)`, `F` formed
//!   once from the factor ([`Delassus::condense_products`], `products.rs`).
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

mod apply;
mod condense;
mod kinetic;
mod policy;
mod pool;
mod products;
mod zone;

use condense::*;
use products::ProductFlex;
pub use products::acting_dofs;

use policy::*;
pub use policy::{DelassusPlan, ZONE_CHUNK, ZoneStorage};
use zone::*;

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
    /// flexibilities fit. For a constant `G`: the per-active-column path, whose one-step
    /// problems past the dense workspaces take their products through the flexibilities
    /// of the dofs `G` touches ([`Delassus::condense_products`]; `auto` does so only
    /// where the dense blocks do not fit). Otherwise as `auto`.
    #[cfg_attr(
        feature = "cli",
        value(
            help = "For contacts between bodies condensed on their contact zone: keep only \
                    the zone's flexibilities F in every scheme (less memory, corrections by \
                    sparse solves); for a constant G, per-active-column with the matrix-free \
                    products through the flexibilities of its dofs; otherwise as auto"
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

/// The factored step matrix with the Delassus data of one linearization of `G`: what
/// it was sized for (`Shape`), the dense path's blocks (`DenseBlocks`), the
/// per-active-column pool (`ColumnPool`) and the scratch of the solves
/// (`DelassusScratch`), beside the zone's and the products' condensed data.
#[derive(Debug)]
pub struct Delassus {
    /// The factored step matrix `Â` (any backend of [`crate::linalg::solver`]).
    pub factor: Box<dyn LinearSolver>,
    /// The contact Jacobian `G` at the current linearization point.
    pub jac: ContactJacobian,
    /// Sparse solves spent on columns since construction (set-up included).
    pub column_solves: usize,
    /// Products through the factor ([`Delassus::product`]) since construction (not
    /// those through the flexibilities of [`Delassus::condense_products`]).
    pub products: usize,
    /// Set-up or step loop ([`Delassus::start_stepping`]): the set-up may spread its
    /// blocked solves over threads (allocating), the step loop may not.
    phase: Phase,
    /// The contact zone's condensed data ([`Delassus::condense_zone`]).
    zone: Option<Zone>,
    /// The zone's flexibilities came from the factor and its tangent
    /// ([`LinearSolver::zone_flexibilities`]), not from column solves.
    zone_by_tangent: bool,
    /// `F` on the dofs of a constant `G` for the matrix-free products
    /// ([`Delassus::condense_products`]).
    pflex: Option<ProductFlex>,
    /// The kinetic metric `N = M⁻¹` of a large-deformation structure's projection
    /// ([`Delassus::use_kinetic_metric`]).
    kinetic: Option<kinetic::Kinetic>,
    /// What the data were sized for.
    pub(crate) shape: Shape,
    /// The dense path's blocks.
    pub(crate) blocks: DenseBlocks,
    /// The per-active-column pool (both paths store `W`'s columns here).
    pub(crate) pool: ColumnPool,
    /// The solves' scratch.
    pub(crate) scratch: DelassusScratch,
}

/// What a [`Delassus`] was sized for.
#[derive(Debug)]
pub(crate) struct Shape {
    /// Dofs.
    pub(crate) n: usize,
    /// Contact-space rows (the columns of `G`).
    pub(crate) m: usize,
    /// The dense path (`n × m` blocks) rather than per-active-column storage.
    pub(crate) dense: bool,
    /// `W_D` and `W_N` are formed (projection schemes).
    pub(crate) with_d: bool,
    /// The projection metric `N`.
    pub(crate) metric: Metric,
    /// `G` does not depend on `q`: [`Delassus::refresh`] runs once, at set-up.
    pub(crate) g_constant: bool,
    /// `W_D` is formed (`with_d`, unless [`Delassus::without_wd`]): a nonlinear structure's
    /// Newton loop carries the projection's feedback in `F` and never reads it.
    pub(crate) need_wd: bool,
    /// The user's choice of storage (with [`DelassusKind::Auto`] or
    /// [`DelassusKind::Flexibility`] the zone may switch a per-active-column choice to
    /// the dense one).
    pub(crate) kind: DelassusKind,
}

/// The dense path's `n × m` blocks and `W_N` (empty on the per-active-column path).
#[derive(Debug)]
pub(crate) struct DenseBlocks {
    /// Dense path: `Â⁻¹G` (`n × m`).
    pub(crate) cg: Vec<f64>,
    /// Dense path: `Â⁻¹K N G` (`n × m`).
    pub(crate) d: Vec<f64>,
    /// Dense path: `W_N` (`m × m`).
    pub(crate) wn: Vec<f64>,
}

/// Columns of `W` and `W_D` in slots, least recently used replaced first.
#[derive(Debug)]
pub(crate) struct ColumnPool {
    /// Columns of `W` (`m` values each) in slots.
    pub(crate) w: Vec<f64>,
    /// Columns of `W_D` in the same slots.
    pub(crate) wd: Vec<f64>,
    /// The slot of each contact-space row's column (`NONE`: not stored).
    pub(crate) slot: Vec<usize>,
    /// The row whose column each slot holds.
    pub(crate) owner: Vec<usize>,
    /// The epoch each slot was last used in (least recently used goes first).
    pub(crate) stamp: Vec<u64>,
    /// Slots in use.
    pub(crate) used: usize,
    /// Slots.
    pub(crate) cap: usize,
    /// The current epoch (a step).
    pub(crate) epoch: u64,
    /// Largest support whose columns are stored ([`Delassus::limit_columns`]).
    pub(crate) limit: usize,
    /// The pool was sized by the memory budget, not by the caller.
    pub(crate) pool_auto: bool,
}

/// Scratch of the solves that form columns and corrections.
#[derive(Debug)]
pub(crate) struct DelassusScratch {
    /// `n`-scratch.
    pub(crate) t1: Vec<f64>,
    /// `n`-scratch.
    pub(crate) t2: Vec<f64>,
    /// Per-active-column path: rows awaiting their columns.
    pub(crate) pending: Vec<usize>,
    /// Two `n × SOLVE_BLOCK` blocks of right-hand sides (per-active-column path).
    pub(crate) blk: Vec<f64>,
    /// See `blk`.
    pub(crate) blk2: Vec<f64>,
    /// `blk[n..2n]` holds `Â⁻¹G τ` for the position correction.
    pub(crate) ng_ready: bool,
}

impl Delassus {
    /// Stops forming `W_D = GᵀÂ⁻¹K N G` (`W` and `W_N` still are): for a caller that
    /// never reads it (`Op::Wd`, the projection feedback of [`Delassus::add_velocity_correction`]).
    pub fn without_wd(&mut self) {
        self.shape.need_wd = false;
    }

    /// Marks the end of the set-up: from now on the blocks are formed by sequential,
    /// allocation-free solves ([`Phase`]).
    pub fn start_stepping(&mut self) {
        self.phase = Phase::Step;
    }

    /// Whether the blocks being formed now are formed once for the whole run (constant
    /// `G`, at set-up): they may then use the threaded solves and the tiled `K` products.
    fn condensing_once(&self) -> bool {
        self.shape.g_constant && self.phase == Phase::Setup
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
            column_solves: 0,
            products: 0,
            phase: Phase::Setup,
            zone: None,
            zone_by_tangent: false,
            pflex: None,
            kinetic: None,
            shape: Shape {
                n,
                m,
                dense,
                with_d,
                metric,
                g_constant,
                need_wd: with_d,
                kind,
            },
            blocks: DenseBlocks {
                cg: vec![0.0; nm],
                d: vec![0.0; if with_d { nm } else { 0 }],
                wn: vec![0.0; if dense && with_d { m * m } else { 0 }],
            },
            pool: ColumnPool {
                w: vec![0.0; m * cap],
                wd: vec![0.0; if with_d { m * cap } else { 0 }],
                slot: vec![NONE; m],
                owner: vec![NONE; cap],
                stamp: vec![0; cap],
                used: 0,
                cap,
                epoch: 1,
                limit: usize::MAX,
                pool_auto: pool == 0,
            },
            scratch: DelassusScratch {
                t1: vec![0.0; n],
                t2: vec![0.0; n],
                pending: Vec::with_capacity(SOLVE_BLOCK),
                blk: vec![0.0; nb],
                blk2: vec![0.0; if with_d { nb } else { 0 }],
                ng_ready: false,
            },
        })
    }

    /// The dense columns `Â⁻¹G` and `Â⁻¹K N G` (`n` values per row, row after row)
    /// when the velocity and position corrections of [`Delassus::add_velocity_correction`]
    /// and [`Delassus::add_position_correction`] are exactly their axpys (the dense path
    /// without a zone, `M̂⁻¹` metric): what the integrator may fuse into one pass over
    /// the state with the same operations in the same order (issue 35).
    pub fn dense_columns(&self) -> Option<(&[f64], &[f64])> {
        (self.shape.dense && self.zone.is_none() && self.shape.metric == Metric::Mass)
            .then_some((&self.blocks.cg[..], &self.blocks.d[..]))
    }

    /// Stores no columns for a support of more than `rows` rows (the one-step
    /// workspaces' cap): such problems are solved matrix-free, and their columns, computed
    /// `rows` solves at a time, would cost more than the products they save.
    pub fn limit_columns(&mut self, rows: usize) {
        self.pool.limit = rows;
        if !self.shape.dense
            && self.pool.pool_auto
            && self.pool.cap > rows.max(1)
            && self.pool.used == 0
        {
            // the default pool need not outgrow the largest set stored at once
            let (m, cap) = (self.shape.m, rows.max(1));
            self.pool.cap = cap;
            self.pool.w = vec![0.0; m * cap];
            self.pool.wd = vec![0.0; if self.shape.with_d { m * cap } else { 0 }];
            self.pool.owner = vec![NONE; cap];
            self.pool.stamp = vec![0; cap];
        }
    }

    /// Number of contacts `m`.
    pub fn len(&self) -> usize {
        self.shape.m
    }

    /// True without contacts.
    pub fn is_empty(&self) -> bool {
        self.shape.m == 0
    }

    /// The projection metric `N`.
    pub fn metric(&self) -> Metric {
        self.shape.metric
    }

    /// True on the dense path.
    pub fn is_dense(&self) -> bool {
        self.shape.dense
    }

    /// Columns the per-active-column pool holds at most.
    pub fn capacity(&self) -> usize {
        self.pool.cap
    }

    /// Bytes the data hold: the factor's entries and the stored blocks and columns (not
    /// the zone's or the products' flexibilities, which are bounded by the plan).
    pub fn bytes(&self) -> u64 {
        let vectors = [
            &self.blocks.cg,
            &self.blocks.d,
            &self.blocks.wn,
            &self.pool.w,
            &self.pool.wd,
            &self.scratch.t1,
            &self.scratch.t2,
            &self.scratch.blk,
            &self.scratch.blk2,
        ];
        let values: usize = vectors.iter().map(|v| v.len()).sum();
        8 * (values as u64 + self.factor.factor_entries().unwrap_or(self.shape.n as u64))
    }

    /// One phrase for summaries: which path runs.
    pub fn describe(&self) -> String {
        let path = describe_path(
            self.zone.as_ref().map(|z| (z.dofs.len(), z.storage)),
            self.shape.dense,
            self.shape.n,
            self.shape.m,
            self.pool.cap,
        );
        if self.zone_by_tangent {
            path + "; F from L⁻¹S on the zone's tree paths, F_E from the factor's tangent \
                    along K (no column solve)"
        } else if let Some(p) = self.pflex.as_ref() {
            path + &p.phrase()
        } else {
            path
        }
    }
}
