//! The θ-method machinery shared by Moreau–Jean, Algorithm 1, Algorithm 2 and the
//! position-level trapezoidal rule.
//!
//! For `F(t, q, v) = f − C v − K q` the iteration matrix `M̂ = M + hθC + h²θ²K`
//! (eq. 47) is constant: it is formed and factored once per step size `h`
//! (`step_size.rs`: [`ThetaCore::set_dt`]). Each step computes the free
//! velocity (eq. 18 with `P = 0`)
//!
//! `M̂ (v_free − v_k) = h f(t_{k+θ}) − h C v_k − h K (q_k + hθ v_k)`,
//!
//! and every iterate of the decoupled Newton loop (eq. 56–58, with the sign erratum
//! of the module [`crate::integrators`]) is then
//!
//! `vⁿ⁺¹ = v_free + M̂⁻¹G Pⁿ⁺¹ − hθ M̂⁻¹K N G τⁿ`,
//! `qⁿ⁺¹ = q_k + h(1−θ)v_k + hθ vⁿ⁺¹ + N G τⁿ⁺¹`,
//!
//! with `N = I` (eq. 58) or `N = M̂⁻¹` (eq. 60). In contact space this needs only
//! `W = GᵀM̂⁻¹G`, `W_D = Gᵀ M̂⁻¹K N G` and `W_N = GᵀNG`, computed once when `G` is
//! constant (DESIGN.md §4): the velocity LCP (eq. 57) is
//! `U + eU_k = W_AA P_A + (U_free − hθ W_D τⁿ + e U_k)_A`, the linearized gaps
//! (eq. 51) are `g = g(qⁿ) + Gᵀ(q_k + h(1−θ)v_k − qⁿ) + hθ U + W_N τ`, and `v, q` are
//! formed once per step. For nonlinear contacts `G(qⁿ)` and the operators are
//! recomputed every Newton iteration (`m` extra solves, or none on the condensed contact
//! zone, where `W = BᵀFB`). Contacts being nodal, `G` and `g` depend on the zone's dofs
//! alone, and on a linear structure the zone rows of the iterate are
//! `v_z = v_free,z + F B Pⁿ⁺¹ − hθ F_E B τⁿ`, `q_z = … + (N G τⁿ⁺¹)_z`: when the zone keeps
//! only its flexibilities ([`crate::delassus::ZoneStorage::Flexibility`], where each
//! `n`-space correction is a sparse solve) the loop iterates on these `z` values alone,
//! converges on their change, and [`ThetaCore::commit`] forms `v`, `q` once. A round in
//! which no row is in any problem (Algorithm 2's first, free round) re-evaluates `g`
//! and `G` for the activation test without forming the operators, which it never reads.
//!
//! A nonlinear structure ([`crate::model::system::Linearity::ConstantMass`]: bodies with
//! a large-deformation law; [`crate::model::system::Linearity::Nonlinear`]: a mass
//! `M(q)`, the slider–crank) has no constant `M̂`: the structural side of the Newton loop
//! of eq. 41–48 ([`super::structure`]) evaluates `M(q_θ)`, `F`, `Kⁿ` and `Cⁿ` at each
//! iterate, refactors `M̂ⁿ` and gives the iteration's free velocity; `W` is condensed
//! again on each new `M̂ⁿ` and the contact problems above are solved unchanged. The projection's feedback
//! enters through `F(q_θ)` (whose `q` carries the last `τ`) instead of `−hθ W_D τⁿ`, the
//! coupled position solve is not taken, and the loop converges on eq. 41's residual.
//! A nonsymmetric `M̂ⁿ` (gyroscopic tangents) makes `W` nonsymmetric: the projection then
//! takes the Euclidean metric of eq. 58 (`N = M̂⁻¹` is no metric) and the LCPs Lemke's
//! method (block pivoting's Cholesky needs symmetry); the path names it.
//!
//! The operators live in [`Delassus`]: dense `n × m` blocks for the tens of contacts of
//! the bar and the academic examples, per-active-column storage (columns computed when
//! a contact first activates, corrections by one sparse solve) for thousands of
//! candidates (DESIGN.md §4). A one-step problem with more active rows than the dense
//! workspaces hold (`max_active_rows`) is solved matrix-free on products through the
//! factor ([`crate::solvers::global`]: MPRGP, or the accelerated projected gradient with
//! friction), the same laws to the friction tolerance.
//!
//! Contact space is the rows of the contact blocks ([`crate::contact`]): every
//! contact-space vector here (`U`, `P`, `τ`, the right-hand sides) has one entry per
//! row, normal row first in each block; gaps, forecasts and the position problem use
//! the normal rows only (eq. 56–60, 67–70 project the normal part). With friction the
//! velocity problem of an active set is the Coulomb problem of eq. 15 with Newton's law
//! on the normal part, `U + e U_k = W P + (U_free − hθ W_D τⁿ + e U_k)`,
//! `C* ∋ Û ⊥ P ∈ C`, solved by [`crate::solvers::friction`] (warm started from the
//! previous step's impulse); without friction (every block one row) it is the LCP of
//! before, operation for operation.
//!
//! Where the decoupled loop is not enough (issue 16 §1, measured on the undamped
//! elastic block sliding with friction, `tests/regression_alg2_friction_undamped.rs`):
//!
//! - *Slow contraction.* The decoupled iteration feeds `τⁿ` back through `−hθ W_D τⁿ`;
//!   on a mode of frequency ω it contracts by `(ωhθ)²/(1 + (ωhθ)²)` per iteration (metric
//!   `M̂⁻¹`), 0.74 for the block's highest modes at h = 1e-4, 0.97 at 5e-4. From the
//!   second iteration on, a step that has not converged solves the coupled problem of
//!   eq. 52–55 on the current contact states (`ThetaCore::coupled_correction`: impulses
//!   and projections together, dense LU, with active-set rounds on the signs) and takes
//!   its `τ` as the next iterate; the decoupled iteration after it checks every law.
//! - *Equality rows reconsidered.* An equality row (eq. 68, `P > 0`) dropped at selection
//!   because its gap was already 0 re-enters when its neighbours' projection moves it
//!   (before, such rows stayed off: 7e-8 m violations at h = 1e-5).
//! - *Tolerances that follow the friction solve.* The velocity accuracy of the friction
//!   solve (`solvers::friction::velocity_error`, m/s) sets a floor under the Newton
//!   tolerance (16 × accuracy / |U|) and a dead band `2hθ·accuracy` for the rows resting at g ≈ 0, which
//!   otherwise flip in and out of the position problem on the solver's last digits.
//! - *Stagnation.* A loop that gains less than 10 % in 5 iterations ends; it converged
//!   if it got within `√tol` (`StepStats::newton_stalls`), or, with a nonlinear `G`, if
//!   its last iterate moved `q` by at most `tol·|q|∞` (a body at rest on other bodies
//!   takes step increments at the solves' round-off, so the change relative to the
//!   increment never falls), else it is a cap.
//! - Rows that keep `g = 0` with `P = 0` and `τ < 0` because eq. 65 had no solution for
//!   the index set are counted in `StepStats::held_rows` (position problem below).

mod build;
mod form;
mod free;
mod newton;
mod position;
mod step_size;
mod workspace;

pub use super::sizing::{DEFAULT_MAX_ACTIVE_ROWS, NONLINEAR_COLUMNS_MAX};
pub(crate) use super::sizing::{
    check_block_rows, matrix_free_rows, workspace_cap, workspace_ledger,
};
use super::step_matrix::StepForm;
pub(crate) use newton::newton_change;
use newton::*;
use position::*;
use step_size::StepCache;
pub(crate) use step_size::fixed_rows;
pub use step_size::{STEP_CACHE_BYTES, STEP_CACHE_ENTRIES};
pub(crate) use workspace::*;

use super::problem::Problem;
use super::structure::{StepData, StructureModel};
use super::{Forecast, NewtonParams, ProjectionRule, SchemeParams, State, StepStats};
use crate::contact::{ContactJacobian, ContactSet, ContactStatus};
use crate::delassus::{Delassus, Op};
use crate::error::Error;
use crate::linalg::SparseMatrix;
use crate::model::LinearSystem;
use crate::solvers::friction::{
    Block, FrictionParams, FrictionProblem, FrictionSolver, FrictionSolverKind,
};
use crate::solvers::global::GlobalSolver;
use crate::solvers::lcp::LcpSolver;
use crate::solvers::mlcp::Mlcp;
use crate::solvers::operator::{DelassusOperator, DenseOperator};
use crate::solvers::{SolveError, SolveInfo};

/// What the position step enforces (eq. 58 for Algorithm 1, eq. 68 for Algorithm 2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PositionRule {
    /// No position correction (Moreau–Jean).
    None,
    /// `0 ≤ g ⊥ τ ≥ 0` over every contact (Algorithm 1, eq. 28 and 58).
    AllComplementarity,
    /// Over the contacts of `pos_mask`: `g = 0` with free `τ` on the rows `rule` holds
    /// (none, those with `P > 0` as in eq. 68–70, or all), `0 ≤ g ⊥ τ ≥ 0` elsewhere.
    Combined {
        /// Which active rows are held at `g = 0`.
        rule: ProjectionRule,
    },
}

/// How the impulse `P` is determined.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VelocityLaw {
    /// Newton's impact law at velocity level on `vel_mask`:
    /// `0 ≤ U_{k+1} + e U_k ⊥ P ≥ 0` (eq. 18d, 57).
    Impact,
    /// Signorini's condition at position level on every contact:
    /// `0 ≤ g(q_{k+1}) ⊥ P ≥ 0` with `q_{k+1} = q_k + h v_{k+θ}` (the trapezoidal rule of
    /// sec. 6.2, Fig. 11 when θ = 1/2).
    PositionLevel,
}

/// The [`Integrator`](super::Integrator) accessors of a scheme built on a `core:
/// ThetaCore` field.
macro_rules! delegate_to_core {
    () => {
        fn state(&self) -> &$crate::integrators::State {
            &self.core.state
        }
        fn state_finite(&self) -> Option<bool> {
            self.core.carry.state_finite
        }
        fn system(&self) -> &$crate::model::LinearSystem {
            &self.core.sys
        }
        fn shared_system(&self) -> std::sync::Arc<$crate::model::LinearSystem> {
            self.core.sys.clone()
        }
        fn dt(&self) -> f64 {
            self.core.h
        }
        fn step_matrix_constant(&self) -> bool {
            self.core.step_matrix_constant()
        }
        fn path(&self) -> String {
            self.core.path()
        }
        fn jacobian(&self) -> &$crate::contact::ContactJacobian {
            &self.core.del.jac
        }
        fn starting_gaps(&self, q: &[f64], gap: &mut [f64]) {
            self.core.contacts.starting_gaps(q, gap)
        }
        fn save(&self) -> $crate::integrators::saved::IntegratorState {
            self.core.save(self.name())
        }
        fn save_into(&self, s: &mut $crate::integrators::saved::IntegratorState) {
            self.core.save_into(self.name(), s)
        }
        fn set_dt(&mut self, h: f64) -> Result<(), $crate::error::Error> {
            let name = self.name();
            self.core.set_dt(name, h)
        }
        fn restore(
            &mut self,
            s: &$crate::integrators::saved::IntegratorState,
        ) -> Result<(), $crate::error::Error> {
            let name = self.name();
            self.core.restore(name, s)
        }
        fn prepare(&mut self) -> Result<(), $crate::error::Error> {
            self.core.update_contacts()
        }
    };
}
pub(crate) use delegate_to_core;

/// Shared θ-method data (see the module doc), in the parts a step treats differently:
/// what the build fixed (`ThetaConfig`), the model and the sub-solvers (fields here),
/// the state and what else the next step reads (`StepCarry`), and the scratch of one
/// step (`DofScratch`, `RowScratch`, `ZoneScratch`), whose contents mean nothing
/// between steps.
///
/// The stages of a step, each in its file: the free step and the structure's calls
/// (`free.rs`: [`ThetaCore::begin_step`]), the Newton loop with the velocity and
/// position problems (`newton.rs`, `position.rs`), forming and accepting the state
/// (`form.rs`, [`ThetaCore::commit`] here), and a change of `h` (`step_size.rs`:
/// [`ThetaCore::set_dt`]); the build is `build.rs`.
pub struct ThetaCore {
    /// The structure, shared (read-only after the build) with the history thread.
    pub(crate) sys: std::sync::Arc<LinearSystem>,
    /// The candidate contacts.
    pub(crate) contacts: Box<dyn ContactSet>,
    /// The step of the next step ([`ThetaCore::set_dt`]).
    pub(crate) h: f64,
    /// The structure's side of the step ([`super::structure`]): the free velocity, the
    /// linearization of each iterate, eq. 41's residual.
    structure: Box<dyn StructureModel>,
    /// `M̂` factored, `G` and the condensed operators.
    pub(crate) del: Delassus,
    /// The one-step problems' workspaces and solvers.
    pub(crate) ws: Workspace,
    /// The coupled position problem's buffers (projection with feedback only).
    coupled: Option<Coupled>,
    /// The Delassus data (factors included) of other step sizes ([`ThetaCore::set_dt`]).
    step_cache: StepCache,
    /// `q`, `v` and the contact quantities at `t_k`.
    pub(crate) state: State,
    /// What the build fixed.
    pub(crate) cfg: ThetaConfig,
    /// What the next step reads beyond the state.
    pub(crate) carry: StepCarry,
    /// `n`-vectors of one step.
    pub(crate) dofs: DofScratch,
    /// Contact-space vectors and masks of one step.
    pub(crate) rs: RowScratch,
    /// The contact zone's scratch when the loop iterates on it.
    pub(crate) zone: ZoneScratch,
}

/// What the build fixed for the run: sizes, laws, the scheme's options ([`ThetaCore`]).
pub(crate) struct ThetaConfig {
    /// `θ` of the θ-method.
    pub(crate) theta: f64,
    /// Free dofs.
    pub(crate) n: usize,
    /// Contacts.
    pub(crate) m: usize,
    /// Rows of the contact space (`m` without friction).
    pub(crate) rows: usize,
    /// First row of each contact's block (`m + 1` values).
    pub(crate) off: Vec<usize>,
    /// Friction coefficient per contact.
    pub(crate) mu: Vec<f64>,
    /// Some contact has friction (blocks of more than one row).
    pub(crate) friction: bool,
    /// The friction solver's settings.
    pub(crate) friction_params: FrictionParams,
    /// Row is a normal row.
    pub(crate) normal: Vec<bool>,
    /// Restitution per row (0 on tangential rows).
    pub(crate) e: Vec<f64>,
    /// The scheme projects positions (Algorithms 1 and 2).
    pub(crate) with_projection: bool,
    /// The projection's feedback `hθ W_D τ` enters the velocity problem.
    pub(crate) feedback: bool,
    /// [`SchemeParams::energy_consistent_restitution`]: the restitution of a normal row
    /// separating at the step's start is at least `(1 − θ)/θ` (the first value); on
    /// every such row under Moreau–Jean (the second, true), on rows open in the last
    /// step under the projection schemes ([`ThetaCore::restitution`]).
    pub(crate) restitution_floor: Option<(f64, bool)>,
    /// `G` does not depend on `q` (every contact set is linear).
    pub(crate) g_constant: bool,
    /// [`ContactSet::coordinate_scale`], for the convergence measure's round-off floor.
    pub(crate) coordinate_scale: f64,
    /// `G` constant and the structure linear: `M̂`, `W` are condensed once and the
    /// Newton loop only re-solves the contact-space problem (eq. 56a).
    pub(crate) operators_constant: bool,
    /// Newton's tolerance and caps.
    pub(crate) newton: NewtonParams,
    /// The position problem's tolerance (m).
    pub(crate) projection_tolerance: f64,
    /// The scheme's step matrix, asked again when `h` changes ([`ThetaCore::set_dt`]).
    pub(crate) step_form: StepForm,
    /// The parameters the core was built with (after the nonsymmetric adjustment): the
    /// Delassus data of another `h` are formed with them.
    pub(crate) built: SchemeParams,
}

/// What a step leaves for the next beyond the [`State`]: `U` at `t_k`, the warm start,
/// flags saying which data are already at `q_k`, the clock's origin ([`ThetaCore`]).
pub(crate) struct StepCarry {
    /// `U = Gᵀ v` at the start of the step, all rows.
    pub(crate) u_rows: Vec<f64>,
    /// The last step's impulse, the warm start of the next solve.
    pub(crate) p_warm: Vec<f64>,
    /// `q_lin` holds `y = q + hθ v` of the state, written by [`ThetaCore::form_fused`]
    /// and read (once) by [`ThetaCore::begin_step`] instead of another pass.
    pub(crate) y_ready: bool,
    /// Whether the state's `q` and `v` are all finite, when [`ThetaCore::form_fused`]
    /// formed them ([`super::Integrator::state_finite`]).
    pub(crate) state_finite: Option<bool>,
    /// The last Newton loop of the step converged: a later round of Algorithm 2 starts
    /// from its velocity ([`ThetaCore::restart_iterate`]).
    pub(crate) last_converged: bool,
    pub(crate) jac_at_qk: bool,
    /// The Delassus data were formed at `q_k` (the step's start) and not since: a round
    /// that re-evaluates `G` at `q_k` need not form them again.
    pub(crate) w_at_qk: bool,
    /// Step and time of the last change of `h`: `t_k = t_o + (k − k_o)·h`, `(0, 0)` for a
    /// run at one `h` (then `k·h` to the bit).
    pub(crate) origin: (usize, f64),
    /// Factorizations [`ThetaCore::set_dt`] made since the last step, counted in the
    /// next step's [`StepStats::factorizations`].
    pub(crate) pending_factorizations: usize,
    /// The step the state's impulse was made over: a frictional solve at another `h`
    /// starts from that impulse scaled by `h / warm_h` (an impulse is a force times its
    /// step; the accuracy mode's comparison steps at `2h` otherwise started from half
    /// their impulse and needed up to 4× the sweeps).
    pub(crate) warm_h: f64,
    /// The state saved by [`ThetaCore::set_dt`] around a change of step, kept so that a
    /// change to a cached `h` allocates nothing.
    pub(crate) snapshot: crate::integrators::saved::IntegratorState,
}

/// The `n`-vectors of one step ([`ThetaCore`]): meaningless between steps.
pub(crate) struct DofScratch {
    /// The free velocity of the step (or iteration).
    pub(crate) v_free: Vec<f64>,
    /// `n`-scratch of the solves.
    pub(crate) work: Vec<f64>,
    pub(crate) q_lin: Vec<f64>,
    /// The iterate's velocity.
    pub(crate) v_new: Vec<f64>,
    /// The iterate's displacement.
    pub(crate) q_new: Vec<f64>,
    /// Scratch of the prescribed dofs' velocities and displacements.
    pub(crate) prescribed_a: Vec<f64>,
    /// See `prescribed_a`.
    pub(crate) prescribed_b: Vec<f64>,
}

/// The contact-space vectors (one entry per row, or per contact where said) and masks of
/// one step ([`ThetaCore`]).
pub(crate) struct RowScratch {
    /// The gaps at the linearization point, per contact.
    pub(crate) g_at_lin: Vec<f64>,
    /// `U_k = Gᵀ v_k` per row (the impact law's `e U_k`).
    pub(crate) u_k: Vec<f64>,
    /// `U_free = Gᵀ v_free` per row.
    pub(crate) u_free: Vec<f64>,
    /// `U` of the iterate per row.
    pub(crate) u_new: Vec<f64>,
    /// `W P` of the iterate (or `W_D Δτ` in the convergence measure).
    pub(crate) w_p: Vec<f64>,
    /// `W_N τ` of the iterate (or `W_N Δτ` in the convergence measure).
    pub(crate) wn_tau: Vec<f64>,
    /// The projection's feedback on the velocities, `hθ W_D τ`.
    pub(crate) wd_tau: Vec<f64>,
    /// The right-hand side of the one-step problem being solved (the velocity LCP's
    /// `U_free − hθW_Dτ + eU_k`, or the position problem's gaps).
    pub(crate) lcp_rhs: Vec<f64>,
    /// The linearized gaps at the end of the step before the projection's `W_N τ`
    /// (`g_lin + hθU`).
    pub(crate) gap_unprojected: Vec<f64>,
    /// The linearized gaps of eq. 51 at the iterate.
    pub(crate) g_lin: Vec<f64>,
    /// The iterate's impulse `P` per row.
    pub(crate) p: Vec<f64>,
    /// The iterate's projection `τ` per row.
    pub(crate) tau: Vec<f64>,
    /// `τ` of the last iterate.
    pub(crate) tau_prev: Vec<f64>,
    /// `τ` whose feedback the free velocity of this iterate carries.
    pub(crate) tau_used: Vec<f64>,
    /// The change of `τ` between iterates.
    pub(crate) dtau: Vec<f64>,
    /// Contacts whose velocity-level impact law is enforced this round.
    pub(crate) vel_mask: Vec<bool>,
    /// Contacts projected this round (Algorithm 2).
    pub(crate) pos_mask: Vec<bool>,
    /// Rows projected with `g = 0` in this Newton loop (Algorithm 2: `P > 0` at some
    /// iterate). The set only grows within a loop, so the decoupled iteration cannot
    /// cycle between two equality sets (with friction, a lifting contact's `P_N`
    /// alternated between 0 and > 0 every iteration until the cap).
    pub(crate) eq_rows: Vec<bool>,
    /// Velocity accuracy (m/s) of the friction solves of this Newton loop (the largest
    /// [`crate::solvers::friction::velocity_error`] met, so that the tolerances derived
    /// from it do not move between iterations); 0 without friction, where the LCP
    /// solves are exact to rounding.
    pub(crate) velocity_accuracy: f64,
}

/// The contact zone's scratch when the Newton loop iterates on the zone's dofs alone
/// ([`ThetaCore::form_zone`]); empty otherwise.
pub(crate) struct ZoneScratch {
    /// The contact zone's dofs when the Newton loop iterates on the zone alone
    /// ([`ThetaCore::form_zone`]: a linear structure, a nonlinear `G`, the zone keeping its
    /// flexibilities only, [`Delassus::flexibility_zone`]); empty otherwise.
    pub(crate) dofs: Vec<usize>,
    /// The zone's velocity correction (zone order).
    pub(crate) velocity_correction: Vec<f64>,
    /// The zone's position correction.
    pub(crate) position_correction: Vec<f64>,
    /// `q` on the zone at the iterate.
    pub(crate) q_iterate: Vec<f64>,
    /// `q` on the zone at the last iterate.
    pub(crate) q_last: Vec<f64>,
    /// `q` on the zone at the step's start.
    pub(crate) q_start: Vec<f64>,
}

impl ThetaCore {
    /// Accepts `v_new`, `q_new`, `P`, `τ` as the state at `t_{k+1}` and evaluates the
    /// contacts there (re-condensing for nonlinear contacts).
    /// Restores a checkpointed state and evaluates again what [`ThetaCore::commit`]
    /// derives from it: the gaps and Jacobian at `q`, the Delassus data of a nonlinear
    /// contact set, `U = Gᵀ v`.
    pub fn restore(
        &mut self,
        scheme: &str,
        s: &crate::integrators::saved::IntegratorState,
    ) -> Result<(), Error> {
        self.state.restore(scheme, s)?;
        self.restore_clock(s);
        self.carry.y_ready = false;
        self.contacts.restart(&self.state.q);
        self.contacts
            .update(&self.state.q)
            .map_err(|e| step_error(&self.state, self.h, e))?;
        self.evaluate_at_state();
        Ok(())
    }

    /// Brings the contact set's search data up to date at `q_k` ([`ContactSet::update`]);
    /// when a pairing changed the gaps, Jacobian and Delassus data are evaluated again.
    pub fn update_contacts(&mut self) -> Result<(), Error> {
        let changed = self
            .contacts
            .update(&self.state.q)
            .map_err(|e| step_error(&self.state, self.h, e))?;
        if changed && !self.cfg.g_constant {
            self.evaluate_at_state();
        }
        Ok(())
    }

    /// The gaps and Jacobian at `q`, the Delassus data of a nonlinear contact set, and
    /// `U = Gᵀ v`: what the next step reads, derived from the state.
    fn evaluate_at_state(&mut self) {
        self.contacts
            .evaluate(&self.state.q, &mut self.state.gap, &mut self.del.jac);
        if !self.cfg.g_constant {
            if self.structure.step_matrix_constant() {
                // (a nonlinear structure condenses at the next step's first iterate)
                self.del.refresh(&self.sys.stiffness);
                self.carry.w_at_qk = true;
            }
            self.carry.jac_at_qk = true;
        }
        self.del
            .jac
            .transpose_mul(&self.state.v, &mut self.carry.u_rows);
    }

    pub fn commit(&mut self, stats: &mut StepStats) {
        if self.cfg.operators_constant || !self.zone.dofs.is_empty() {
            self.form();
        }
        std::mem::swap(&mut self.state.q, &mut self.dofs.q_new);
        std::mem::swap(&mut self.state.v, &mut self.dofs.v_new);
        self.state.impulse_rows.copy_from_slice(&self.rs.p);
        for c in 0..self.cfg.m {
            self.state.impulse[c] = self.rs.p[self.cfg.off[c]];
            self.state.projection[c] = self.rs.tau[self.cfg.off[c]];
        }
        self.state.step += 1;
        self.carry.warm_h = self.h;
        self.state.time =
            self.carry.origin.1 + (self.state.step - self.carry.origin.0) as f64 * self.h;
        self.evaluate_at_state();
        self.scatter_local_velocity();
        stats.max_violation = self.state.gap.iter().fold(0.0_f64, |acc, &g| acc.max(-g));
    }

    /// Copies the normal and tangential parts of `u_rows` and of the impulse into the
    /// state and classifies each frictional contact: open without normal impulse, stick
    /// when `‖U_T‖` is below 1e-9 of the step's velocity scale (or the impulse strictly
    /// inside the cone), slip otherwise; a closed contact without friction (μ = 0 or a
    /// one-row block) has its own status, neither stick nor slip.
    fn scatter_local_velocity(&mut self) {
        let td = self.state.tangent_dim;
        let vs = self
            .rs
            .u_free
            .iter()
            .chain(&self.carry.u_rows)
            .fold(0.0_f64, |s, x| s.max(x.abs()));
        for c in 0..self.cfg.m {
            let (o, e) = (self.cfg.off[c], self.cfg.off[c + 1]);
            self.state.local_velocity[c] = self.carry.u_rows[o];
            if td == 0 {
                continue;
            }
            let mut ut2 = 0.0;
            let mut pt2 = 0.0;
            for t in 0..td {
                let (ut, pt) = if o + 1 + t < e {
                    (self.carry.u_rows[o + 1 + t], self.rs.p[o + 1 + t])
                } else {
                    (0.0, 0.0)
                };
                self.state.tangent_velocity[c * td + t] = ut;
                self.state.tangent_impulse[c * td + t] = pt;
                ut2 += ut * ut;
                pt2 += pt * pt;
            }
            let pn = self.rs.p[o];
            self.state.status[c] = if pn <= 0.0 {
                ContactStatus::Open
            } else if self.cfg.mu[c] == 0.0 || e - o == 1 {
                ContactStatus::Frictionless
            } else if ut2.sqrt() <= 1e-9 * vs || pt2.sqrt() < (1.0 - 1e-9) * self.cfg.mu[c] * pn {
                ContactStatus::Stick
            } else {
                ContactStatus::Slip
            };
        }
    }
}
