//! The structure behind the θ-method step: what the Newton loop of
//! [`super::core::ThetaCore`] asks of the mechanical system, answered by a
//! [`StructureModel`] instead of a branch on the system's kind (issue 36 §2).
//!
//! The loop asks four questions, each a method of the trait:
//!
//! 1. *The free velocity of the step* ([`StructureModel::begin_step`]): eq. 18 with
//!    `P = 0`, `M̂ (v_free − v_k) = h f(t_{k+θ}) − h C v_k − h K (q_k + hθ v_k)`, on a
//!    linear structure; the first Newton iterate of eq. 45 (`v⁰ = v_k`, `τ⁰ = 0`) on a
//!    nonlinear one, whose `M̂⁰` is factored there.
//! 2. *The next iterate's linearization* ([`StructureModel::relinearize`],
//!    [`StructureModel::restart`]): nothing on a linear structure (`M̂` of eq. 47 is
//!    constant and `v_free` of the step stands); `M(q_θⁿ)`, `Fⁿ`, `Kⁿ`, `Cⁿ` and, under
//!    full Newton or when modified Newton stops contracting, a new factorization of
//!    `M̂ⁿ` on a nonlinear one (eq. 45–48).
//! 3. *The residual of eq. 41* ([`StructureModel::residual`]): none on a linear structure
//!    (the change of the iterate decides, eq. 49); `‖M(v − v_k) − hF_θ − GP‖∞` relative to
//!    the largest of its terms on a nonlinear one.
//! 4. *Whether `M̂` is constant* ([`StructureModel::step_matrix_constant`]): then `W` is
//!    condensed once (with a constant `G`), the projection's feedback goes through
//!    `W_D = Gᵀ M̂⁻¹ K N G` (eq. 56a), the coupled position solve of eq. 52–55 is
//!    available and the contact zone can be iterated alone; otherwise `W` follows each new
//!    `M̂ⁿ` and the feedback is in `F(q_θ)`.
//!
//! The implementors: [`LinearStructure`] (rods and linear-elastic solids, `F = f − Cv −
//! Kq`) and [`NonlinearStructure`] (a list of [`crate::model::system::NonlinearPart`]s on
//! top of `M`, `K`, `C`: hyperelastic bodies and rigid multibody models, each a part with
//! its own law). [`for_system`] picks between them, from
//! [`crate::model::LinearSystem::linearity`], for a problem that was given none; a caller
//! hands any other implementor to [`crate::integrators::Problem::with_structure`], and
//! the plan, the build and the driver take it as they take these two (issue 49).
//!
//! The step matrix: [`StructureModel::analyse`] states what `M̂(h)` will cost (the plan's
//! figures), [`StructureModel::factor`] forms and factors it (at the build, and again at
//! each new `h` of [`crate::integrators::Integrator::set_dt`] when it is constant).
//!
//! A method reads and writes the step through a [`StepData`], the core's borrowed
//! buffers; the errors it returns are the caller's to attribute to the step.

mod linear;
mod nonlinear;

pub use super::step_matrix::{StepAnalysis, StepForm, StepMatrix, factor_step_matrix};
pub use linear::LinearStructure;
pub use nonlinear::{DENSE_MAX, MATRIX_NAME, NonlinearStructure};

use super::{NewtonParams, State, StepStats};
use crate::contact::ContactJacobian;
use crate::error::Error;
use crate::linalg::{LinearSolver, SparseMatrix, spmv_add};
use crate::model::LinearSystem;
use crate::model::system::Linearity;

/// The core's buffers a [`StructureModel`] reads and writes in a step (borrowed from
/// [`super::core::ThetaCore`] for one call).
pub struct StepData<'a> {
    /// The system the structure was built on.
    pub sys: &'a LinearSystem,
    /// The state at `t_k`.
    pub state: &'a State,
    /// Step `h` and `θ`.
    pub h: f64,
    /// `θ` of the θ-method.
    pub theta: f64,
    /// `M̂` factored (refactored in place by a nonlinear structure).
    pub factor: &'a mut dyn LinearSolver,
    /// `G` at the linearization point, for `G P` in the residual.
    pub jac: &'a ContactJacobian,
    /// The iterate's impulse `P` per contact-space row.
    pub p: &'a [f64],
    /// The iterate `(q, v)` (nonlinear structure: the point of the linearization).
    pub q_new: &'a mut [f64],
    /// See `q_new`.
    pub v_new: &'a mut [f64],
    /// The free velocity of the step or iteration (output).
    pub v_free: &'a mut [f64],
    /// `n`-scratch.
    pub work: &'a mut [f64],
    /// `n`-scratch that holds `y = q_k + hθ v_k` when `y_ready` (linear structure).
    pub q_lin: &'a mut [f64],
    /// `q_lin` already holds `y` of the state (written while the last step formed it).
    pub y_ready: bool,
    /// Scratch of the prescribed dofs' velocities and displacements.
    pub vp: (&'a mut [f64], &'a mut [f64]),
}

/// The mechanical system as the θ-method Newton loop sees it (module doc: the four
/// questions). Built once per integrator ([`for_system`]); a step does not allocate.
pub trait StructureModel: Send + std::fmt::Debug {
    /// `M̂` does not depend on the iterate (eq. 47 with a linear `F`): it is factored once,
    /// `W` is condensed once when `G` is constant, and the projection's feedback goes
    /// through `W_D`.
    fn step_matrix_constant(&self) -> bool;

    /// What the step matrix `M̂(h)` of `form` will cost, before anything is factored:
    /// the factor's backend, entries and scratch from a symbolic analysis, and (where the
    /// matrix is formed once) the matrix with its analysis for [`StructureModel::factor`]
    /// to take. The plan of `signorini check` and the build both ask here
    /// ([`super::step_matrix`]).
    fn analyse(&self, sys: &LinearSystem, form: StepForm, h: f64) -> Result<StepAnalysis, Error>;

    /// Forms and factors `M̂` of `form` at step `h`, at the initial state `(q0, v0)`
    /// (the pattern's analysis; a nonlinear structure forms its values again at the
    /// first step); `planned`: the step matrix [`StructureModel::analyse`] kept, where the
    /// plan ran. A constant `M̂` is asked again through this call when `h` changes
    /// ([`super::core::ThetaCore::set_dt`]).
    fn factor(
        &mut self,
        sys: &LinearSystem,
        step: (StepForm, f64),
        initial: (&[f64], &[f64]),
        planned: Option<StepMatrix>,
    ) -> Result<Box<dyn LinearSolver>, Error>;

    /// The stiffness of the iteration matrix (`K`, or `Kⁿ` at the last tangent): the
    /// `K` of the Delassus data's `W_D` and of their refresh.
    fn tangent<'a>(&'a self, sys: &'a LinearSystem) -> &'a SparseMatrix;

    /// The free velocity at the start of a step into `cx.v_free`; returns whether `M̂`
    /// was factored again (the Delassus data then follow it).
    fn begin_step(&mut self, cx: &mut StepData<'_>, stats: &mut StepStats) -> Result<bool, Error>;

    /// Prepares a later Newton loop of the step (an index-set round of Algorithm 2):
    /// `None` when nothing changes (a linear structure, or a nonlinear one still at its
    /// first iterate); otherwise the new free velocity is in `cx.v_free` and the value
    /// says whether `M̂` was factored again. `last_converged`: the last loop converged, so
    /// the next starts from its velocity.
    /// The default is a structure whose `M̂` is constant: nothing to do.
    fn restart(
        &mut self,
        _cx: &mut StepData<'_>,
        _last_converged: bool,
        _stats: &mut StepStats,
    ) -> Result<Option<bool>, Error> {
        Ok(None)
    }

    /// Linearizes at the iterate `(cx.q_new, cx.v_new)` for the next Newton iteration,
    /// given the last two changes of the iterate, latest first (modified Newton's
    /// contraction test);
    /// returns whether `M̂` was factored again. A linear structure does nothing.
    fn relinearize(
        &mut self,
        _cx: &mut StepData<'_>,
        _changes: (f64, f64),
        _stats: &mut StepStats,
    ) -> Result<bool, Error> {
        Ok(false)
    }

    /// The relative residual of eq. 41 at the iterate `(cx.q_new, cx.v_new)` with the
    /// impulse `cx.p`; `None` where the change of the iterate decides alone (a linear
    /// structure).
    fn residual(
        &mut self,
        _cx: &mut StepData<'_>,
        _stats: &mut StepStats,
    ) -> Result<Option<f64>, Error> {
        Ok(None)
    }

    /// The structure's part of the linear-algebra path, for summaries (`backend`: the
    /// factor's name, `n` the dofs).
    fn describe(&self, sys: &LinearSystem, backend: &str, n: usize) -> String;
}

/// The structure model of `sys`: [`LinearStructure`] for a linear system,
/// [`NonlinearStructure`] otherwise (with the scheme's Newton settings and its
/// energy–momentum option).
pub fn for_system(
    sys: &LinearSystem,
    newton: &NewtonParams,
    energy_momentum: bool,
) -> Box<dyn StructureModel> {
    if sys.linearity() == Linearity::Linear {
        Box::new(LinearStructure::new(sys))
    } else {
        Box::new(NonlinearStructure::new(
            sys,
            newton.modified,
            energy_momentum,
        ))
    }
}

/// Adds what the step's right-hand side owes to time-dependent nodal loads at
/// `t_{k+θ}` and to the prescribed dofs (eliminated): `−M_fp Δv_p − h C_fp v_p(t_{k+θ})
/// − h K_fp u_p(t_{k+θ})`, with `(t_k, h, θ)`; `vp` are two scratch vectors.
pub(crate) fn add_step_loads(
    sys: &LinearSystem,
    (t, h, th): (f64, f64, f64),
    (vp_a, vp_b): (&mut [f64], &mut [f64]),
    out: &mut [f64],
) {
    sys.add_loads(t + th * h, h, out);
    if let Some(p) = &sys.prescribed {
        p.velocity_at(t, vp_a);
        p.velocity_at(t + h, vp_b);
        for (b, a) in vp_b.iter_mut().zip(vp_a.iter()) {
            *b -= a;
        }
        spmv_add(p.mass.as_ref(), -1.0, vp_b, out);
        p.velocity_at(t + th * h, vp_a);
        if let Some(c) = &p.damping {
            spmv_add(c.as_ref(), -h, vp_a, out);
        }
        p.displacement_at(t + th * h, vp_a);
        spmv_add(p.stiffness.as_ref(), -h, vp_a, out);
    }
}
