//! Time integrators: the paper's five event-capturing schemes.
//!
//! | scheme | file | paper |
//! |---|---|---|
//! | Moreau–Jean | [`moreau_jean`] | eq. 18, forecasts eq. 61 (γ) and eq. 62 (free) |
//! | Schatzman–Paoli | [`schatzman_paoli`] | eq. 20–22 |
//! | trapezoidal rule, position-level contact | [`trapezoid`] | sec. 6.2, Fig. 11 |
//! | direct projection (Algorithm 1, decoupled) | [`direct_projection`] | eq. 28, 56–58, 60 |
//! | combined activation/projection (Algorithm 2) | [`combined_projection`] | eq. 65–70 |
//!
//! An integrator is built once (iteration matrix factored, Delassus operator
//! `W = Gᵀ M̂⁻¹ G` condensed, buffers sized) and stepped many times; [`Integrator::step`]
//! does not allocate and returns its [`StepStats`] as data.
//!
//! The θ-method schemes share [`core::ThetaCore`]: the free velocity of eq. 18/45,
//! the condensed operators of DESIGN.md §4, and the decoupled Newton loop of
//! eq. 56–58 written in contact space (for a linear system with constant `G` every
//! iterate is a small `m`-dimensional computation; `v` and `q` are formed once per
//! step).
//!
//! Erratum carried here: as printed, eq. 45, 48 and 56a give the stiffness terms
//! `+hθK(q_k − qⁿ + h(1−θ)v_k)` and `+hθK G τ`. Substituting the second line of eq. 44
//! into its first gives `−hθK(q_k − qⁿ + h(1−θ)v_k + hθvⁿ) − hθK G τ`; only this sign
//! reduces to the plain θ-method (eq. 18) when `τ = 0`. The code uses the derived form.

pub mod combined_projection;
pub mod core;
pub mod direct_projection;
pub mod moreau_jean;
pub mod plan;
pub mod problem;
pub mod saved;
pub mod schatzman_paoli;
mod sizing;
pub mod step_matrix;
pub mod structure;
pub mod trapezoid;

mod params;
mod state;

pub use params::*;
pub use state::*;

use serde::{Deserialize, Serialize};

use crate::contact::{ContactSet, ContactStatus};
use crate::error::Error;
use crate::model::LinearSystem;
use crate::solvers::LcpKind;

/// A time integrator for a linear structure with contacts. `Send`: a built integrator
/// can move to another thread (the Python package steps it with the GIL released).
pub trait Integrator: Send {
    /// The scheme this integrator runs (what the driver asks, e.g. whether the θ-method's
    /// energy balance applies: never a name parsed back).
    fn kind(&self) -> SchemeKind;
    /// Short name, as on the command line ([`SchemeKind::name`]).
    fn name(&self) -> &'static str {
        self.kind().name()
    }
    /// Advances one step of size `h`. Does not allocate, unless the contact search had
    /// to be rebuilt in it (then [`Integrator::prepare`] was not called before).
    fn step(&mut self) -> Result<StepStats, Error>;
    /// Brings the contact search up to date before a step ([`ContactSet::update`]: the
    /// candidate facets of contacts between bodies), so that [`Integrator::step`] finds
    /// it fresh; [`crate::run::driver::drive`] calls it before every step. It may
    /// allocate (a rebuilt tree).
    ///
    /// [`ContactSet::update`]: crate::contact::ContactSet::update
    fn prepare(&mut self) -> Result<(), Error> {
        Ok(())
    }
    /// The current state.
    fn state(&self) -> &State;
    /// Whether every displacement and velocity of the state is finite, when the last
    /// step found out while forming it (`None`: not known, the caller scans). Saves
    /// the run's checks a pass over the state (issue 35).
    fn state_finite(&self) -> Option<bool> {
        None
    }
    /// The mechanical system being integrated.
    fn system(&self) -> &LinearSystem;
    /// The same system, shared: nothing changes it after the build, so a writer thread
    /// may read it while the run steps (the history's energies).
    fn shared_system(&self) -> std::sync::Arc<LinearSystem>;
    /// Whether the step matrix `M̂` is constant for a given `h` (a linear structure:
    /// [`structure::StructureModel::step_matrix_constant`]), which the run's checks read
    /// instead of the system's kind.
    fn step_matrix_constant(&self) -> bool {
        true
    }
    /// The time step `h` (s) of the next step.
    fn dt(&self) -> f64;
    /// Makes `h` the step of the next steps: the step matrix `M̂(h)` and the Delassus data
    /// on it are asked through the structure's one call (kept per `h` within
    /// [`core::STEP_CACHE_BYTES`]), and the run continues bit for bit as one resumed from
    /// a checkpoint at `h` would. A scheme that steps at a constant `h` (Schatzman–Paoli,
    /// a two-step scheme) refuses any other `h`.
    fn set_dt(&mut self, h: f64) -> Result<(), Error> {
        if h.to_bits() == self.dt().to_bits() {
            return Ok(());
        }
        Err(Error::invalid(
            "dt",
            h,
            &format!(
                "{} steps at the constant h = {:e} s it was built with",
                self.name(),
                self.dt()
            ),
        ))
    }
    /// A one-line description of the solution path taken (factorization, Delassus
    /// data, Newton or not), for summaries.
    fn path(&self) -> String;
    /// The gap of each contact at `q` as a scene's start is checked
    /// ([`ContactSet::starting_gaps`]: a node far inside another body reads its depth,
    /// not the search's cap), for a state replaced between steps. It may allocate.
    fn starting_gaps(&self, q: &[f64], gap: &mut [f64]);
    /// The contact Jacobian `G` of the last evaluation (at the end of the last step;
    /// for nonlinear gaps, at the last Newton iterate), for the output of `G P / h`.
    fn jacobian(&self) -> &crate::contact::ContactJacobian;
    /// What the next step reads beyond the model, for a checkpoint
    /// ([`crate::run::checkpoint`]).
    fn save(&self) -> crate::integrators::saved::IntegratorState;
    /// [`Integrator::save`] into `s`, reusing its buffers: the θ-method schemes allocate
    /// nothing once `s` holds a state of this size (a snapshot to step back to).
    fn save_into(&self, s: &mut crate::integrators::saved::IntegratorState) {
        *s = self.save();
    }
    /// Restores a state saved by an integrator built from the same model and parameters;
    /// the gaps, Jacobians and Delassus data are evaluated again at the restored `q`.
    fn restore(&mut self, s: &crate::integrators::saved::IntegratorState) -> Result<(), Error>;
}

pub use crate::delassus::Metric;
pub use problem::Problem;

/// Builds the integrator chosen by `params` for `problem` with step `h`, after checking
/// them once ([`Problem::validate`]); nothing below checks them again.
pub fn build_problem(
    params: &SchemeParams,
    problem: Problem,
    h: f64,
) -> Result<Box<dyn Integrator>, Error> {
    // validated once: by the plan of this problem, or here
    let mut problem = problem;
    problem.validate_once(params, h)?;
    Ok(match params.kind {
        SchemeKind::MoreauJean => Box::new(moreau_jean::MoreauJean::new(params, problem, h)?),
        SchemeKind::DirectProjection => Box::new(direct_projection::DirectProjection::new(
            params, problem, h,
        )?),
        SchemeKind::CombinedProjection => Box::new(combined_projection::CombinedProjection::new(
            params, problem, h,
        )?),
        SchemeKind::TrapezoidPosition => {
            Box::new(trapezoid::TrapezoidPosition::new(params, problem, h)?)
        }
        SchemeKind::SchatzmanPaoli => {
            Box::new(schatzman_paoli::SchatzmanPaoli::new(params, problem, h)?)
        }
    })
}

/// [`build_problem`] from the parts of a [`Problem`]: the structure `system`, its
/// `contacts`, the initial state `(q0, v0)` at `t = 0` (the form the tests, benches and
/// studies that assemble a system by hand use).
pub fn build(
    params: &SchemeParams,
    system: LinearSystem,
    contacts: Box<dyn ContactSet>,
    q0: &[f64],
    v0: &[f64],
    h: f64,
) -> Result<Box<dyn Integrator>, Error> {
    build_problem(
        params,
        Problem::new(system, contacts, q0.to_vec(), v0.to_vec()),
        h,
    )
}
