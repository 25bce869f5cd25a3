//! The plan of a run, before anything is factored or condensed: which paths the
//! integrator will take (factor backend and fill, Delassus storage, one-step workspaces,
//! matrix-free past them) and one memory ledger for all of it (matrices, factor and its
//! scratch, Delassus data, workspaces, state and contact-space vectors, the history's
//! buffers). `signorini check` prints it at the cost of the validation and a symbolic
//! analysis of the step matrix (no numeric factorization, no Delassus column), and a
//! run checks its total against the memory limit before building the integrator.
//!
//! The decisions come from the integrator's own functions ([`Delassus::plan`] shares
//! [`Delassus::new`]'s choice, [`crate::linalg::analyse_spd`] and
//! [`crate::linalg::analyse_ldlt`] the factors' symbolic analyses and orderings,
//! [`super::core`]'s workspace ledger the workspaces'); `tests/regression_check_plan.rs`
//! checks scene by scene that the planned factor and Delassus path are the built ones.
//! The vectors are counted from the integrators' fields, rounded up; a nonlinear
//! structure's step matrix is planned on the pattern of `M`, `K` and `C` (its tangents
//! share it for the shipped bodies).

use super::step_matrix::StepMatrix;
use super::structure::StructureModel;
use super::{SchemeKind, SchemeParams};
use crate::contact::ContactSet;
use crate::delassus::{Delassus, DelassusPlan};
use crate::error::Error;
use crate::limits::MemoryEstimate;
use crate::linalg::FactorPlan;
use crate::model::LinearSystem;

/// `n`-vectors the integrators hold (state, free and new velocities, linearization
/// points, loads, scratch of the solves and of the Delassus corrections, a rod's `K` as
/// three diagonals), rounded up.
const STATE_VECTORS: u64 = 27;

/// Vectors of `n + rows` the accuracy mode keeps ([`Plan::add_accuracy`]).
pub const ACCURACY_VECTORS: u64 = 5 * 2 + 4;
/// Contact-space vectors (per row: gaps, velocities, impulses, projections, right-hand
/// sides, masks, warm starts), rounded up.
const CONTACT_VECTORS: u64 = 32;

/// What a run will hold and which paths it will take ([`plan`]).
#[derive(Clone, Debug)]
pub struct Plan {
    /// The factor of the step matrix.
    pub factor: FactorPlan,
    /// Where the Delassus data go.
    pub delassus: DelassusPlan,
    /// One phrase for the one-step problems (dense workspaces, matrix-free past them).
    pub workspaces: String,
    /// Every part, in bytes.
    pub ledger: MemoryEstimate,
    /// Entries of the step matrix `M̂` formed for a factorization.
    pub step_matrix_entries: u64,
}

impl Plan {
    /// The planned path, in the words of [`super::Integrator::path`].
    pub fn describe(&self) -> String {
        format!(
            "factor {}; {}; {}",
            self.factor.backend, self.delassus.describe, self.workspaces
        )
    }

    /// Adds what the accuracy mode ([`crate::run::accuracy`]) holds beside a run at one
    /// step (`n` dofs, `rows` contact rows): a structure whose `M̂` is constant
    /// (`step_constant`) keeps the factors and Delassus data of up to
    /// [`super::core::STEP_CACHE_ENTRIES`] other steps of its ladder, within
    /// [`super::core::STEP_CACHE_BYTES`], and forms one more (its `M̂` and factor) while
    /// the cache is full; every run keeps [`ACCURACY_VECTORS`] vectors of `n + rows` (the
    /// window's three snapshots, the companion's state and the snapshot a change of step
    /// takes, two vectors each; `A`'s positions and velocities, the displacement and the
    /// difference) and the energy forms of `M` and `K` (six more of `n`). Measured on the
    /// bar at 2·10⁴–2·10⁵ dofs: 410 bytes per dof above the same run at one step.
    pub fn add_accuracy(&mut self, step_constant: bool, n: usize, rows: usize) {
        if step_constant {
            let per_step = self.factor.entries.saturating_mul(8) + self.delassus.bytes;
            let cache = per_step
                .saturating_mul(super::core::STEP_CACHE_ENTRIES as u64)
                .min(super::core::STEP_CACHE_BYTES);
            self.ledger.add(
                "accuracy mode: other steps' factors and Delassus data",
                1,
                cache,
            );
            self.ledger.add(
                "accuracy mode: a new step's M̂, factor and Delassus data",
                1,
                per_step.saturating_add(self.step_matrix_entries.saturating_mul(16)),
            );
        }
        self.ledger.add(
            format!(
                "accuracy mode: snapshots, the companion and comparison vectors \
                 ({ACCURACY_VECTORS} × (n + rows))"
            ),
            (n + rows) as u64,
            ACCURACY_VECTORS * 8,
        );
        self.ledger
            .add("accuracy mode: energy forms (6 × n)", n as u64, 6 * 8);
    }

    /// Adds the history's buffers: the CSV's 64 KiB, the energies' forms of `n` dofs,
    /// and with HDF5 4096 rows of every column (`m` contacts with `tangent_dim`
    /// tangents).
    pub fn add_history(&mut self, n: usize, m: usize, tangent_dim: usize, hdf5: bool) {
        self.ledger.add("history buffers (CSV)", 1, 1 << 16);
        // the energies' quadratic forms: three diagonals of M and of K where they are
        // tridiagonal (`linalg::QuadraticForm`), counted for every pattern
        self.ledger.add("history energy forms", 6 * n as u64, 8);
        // the history thread's copies of q and v (`run::history_thread::POOL` = 2 of
        // them; counted for every size, the thread runs from 4096 dofs)
        self.ledger
            .add("history thread state copies", 4 * n as u64, 8);
        // each body's centre and momenta per row (`model::BodyMeasures`: a 24-byte map,
        // `M v` and `M 1` per dof; solid scenes only, counted for every one)
        self.ledger.add("history body measures", n as u64, 40);
        if hdf5 {
            let cols = 12 + m as u64 * (4 + 2 * tangent_dim as u64 + 1);
            self.ledger
                .add("history buffers (HDF5, 4096 rows)", 4096 * cols, 8);
        }
    }
}

/// Plans the run of `params` on `system` with `contacts` at step `h` (module doc), with
/// the structure model the build would choose ([`super::structure::for_system`]).
pub fn plan(
    params: &SchemeParams,
    system: &LinearSystem,
    contacts: &dyn ContactSet,
    h: f64,
) -> Result<Plan, Error> {
    let structure = super::structure::for_system(system, &params.newton, params.energy_momentum);
    plan_kept(params, structure.as_ref(), system, contacts, h).map(|(plan, _)| plan)
}

/// [`plan`] on the given `structure`, keeping the step matrix its analysis formed
/// (structures whose step matrix is constant) for the build
/// ([`super::problem::Problem::plan`]). The factor's backend and size are the
/// structure's own statement ([`super::structure::StructureModel::analyse`]).
pub(crate) fn plan_kept(
    params: &SchemeParams,
    structure: &dyn StructureModel,
    system: &LinearSystem,
    contacts: &dyn ContactSet,
    h: f64,
) -> Result<(Plan, Option<StepMatrix>), Error> {
    super::sizing::check_block_rows(params, contacts)?;
    let n = system.ndof();
    let m = contacts.len();
    let rows = contacts.rows();
    let friction = rows > m;
    let sp = params.kind == SchemeKind::SchatzmanPaoli;
    let with_projection = params.kind.capabilities().projection;
    let step = structure.analyse(system, params.step_form(), h)?;
    let factor = step.factor;
    let analysis = step.kept.as_ref().and_then(|k| k.analysis());
    let linear = structure.step_matrix_constant();
    let g_constant = contacts.is_linear();
    let zone = (linear && !g_constant && contacts.condensed()).then(|| contacts.zone().len());
    let ws_cap = super::sizing::workspace_cap(rows, params);
    let mut delassus = Delassus::plan(
        n,
        rows,
        (params.delassus, params.delassus_pool),
        with_projection && linear,
        g_constant && linear,
        zone,
        ws_cap,
        !sp,
    );
    // the core's threshold (Schatzman–Paoli and nonlinear structures keep the cap); its
    // columns are stored up to it
    let mf_from = if linear && !sp {
        super::sizing::matrix_free_rows(ws_cap, g_constant, delassus.dense)
    } else {
        ws_cap
    };
    if mf_from < ws_cap {
        delassus = Delassus::plan(
            n,
            rows,
            (params.delassus, params.delassus_pool),
            with_projection,
            false,
            zone,
            mf_from,
            !sp,
        );
    }
    // a constant G whose problems go matrix-free: F on its dofs for the products
    // (`Delassus::condense_products`, built where `ThetaCore::new` calls it)
    let products = if linear && !sp && g_constant && rows > ws_cap {
        // the dofs of G's non-zero entries, G being constant: at any q
        let mut jac = crate::contact::ContactJacobian::for_set(contacts);
        contacts.evaluate(&vec![0.0; n], &mut vec![0.0; m], &mut jac);
        let dofs = crate::delassus::acting_dofs(&jac);
        let paths = analysis.and_then(|a| a.zone_path_entries(&dofs));
        paths.filter(|_| {
            delassus.add_products(
                params.delassus,
                dofs.len(),
                (factor.supernodal, factor.entries),
            )
        })
    } else {
        None
    };
    let mut ledger = MemoryEstimate::default();
    ledger.add(
        "the process (binary, libraries, threads)",
        1,
        crate::limits::PROCESS_BYTES,
    );
    let nnz = |s: &crate::linalg::SparseMatrix| s.val().len() as u64;
    let model = nnz(&system.mass) + nnz(&system.stiffness) + system.damping.as_ref().map_or(0, nnz);
    ledger.add("mass, stiffness and damping matrices", model, 16);
    ledger.add(
        "step matrix M̂ (for its factorization)",
        step.matrix_entries,
        16,
    );
    ledger.add("factor of M̂", factor.entries, 8);
    ledger.add("factorization scratch", factor.scratch_bytes, 1);
    // the zone's flexibilities from a supernodal factor and its tangent (under the M̂⁻¹
    // metric, or without W_D) hold up to one more factor's entries instead of the
    // swept chunks
    let by_tangent = delassus.zone_flexibilities
        && factor.supernodal
        && !(with_projection && params.metric == crate::integrators::Metric::Euclidean);
    if by_tangent {
        ledger.add("Delassus data", delassus.bytes - delassus.setup_bytes, 1);
        if with_projection {
            ledger.add(
                "zone set-up: tangent of the factor (at most)",
                factor.entries,
                8,
            );
        }
    } else {
        ledger.add("Delassus data", delassus.bytes, 1);
    }
    if let Some(paths) = products {
        // L⁻¹S on the tree paths of G's dofs, freed as the pass climbs
        ledger.add(
            "products' set-up: L⁻¹S on the zone's paths (at most)",
            paths,
            8,
        );
    }
    if sp {
        super::sizing::workspace_ledger(m, m, params, (false, false), &mut ledger);
    } else {
        super::sizing::workspace_ledger(rows, m, params, (friction, with_projection), &mut ledger);
    }
    if rows > mf_from && rows <= ws_cap {
        ledger.add(
            "matrix-free one-step vectors (15 × rows)",
            rows as u64,
            15 * 8,
        );
    }
    ledger.add(
        format!("state and step vectors ({STATE_VECTORS} × n)"),
        n as u64,
        STATE_VECTORS * 8,
    );
    ledger.add(
        format!("contact-space vectors ({CONTACT_VECTORS} × rows)"),
        rows as u64,
        CONTACT_VECTORS * 8,
    );
    let workspaces = if rows > mf_from {
        format!(
            "one-step problems up to {mf_from} active rows in dense workspaces, matrix-free \
             past them (MPRGP{})",
            if friction {
                ", friction by accelerated projected gradient"
            } else {
                ""
            }
        )
    } else {
        format!("one-step problems in dense workspaces of {ws_cap} rows")
    };
    let plan = Plan {
        factor,
        delassus,
        workspaces,
        ledger,
        step_matrix_entries: step.matrix_entries,
    };
    Ok((plan, step.kept))
}
