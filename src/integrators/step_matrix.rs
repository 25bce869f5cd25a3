//! The step matrix `M̂(h)`, in one place: which combination of `M`, `K` and `C` a scheme
//! factors at a step `h` ([`StepForm`]: eq. 47's `M + hθC + h²θ²K` for the θ-method,
//! `M + h²θK + (hθ/2)C` for Schatzman–Paoli's eq. 20a), the matrix formed with its
//! symbolic analysis ([`StepMatrix`]), and what the analysis states about the factor
//! ([`StepAnalysis`]: backend, entries, scratch, as faer's symbolic objects state their
//! own memory).
//!
//! Every caller asks here: the structures ([`super::structure::StructureModel::analyse`]
//! and `factor`), the plan of `signorini check` and the build (which takes the matrix the
//! plan formed and analysed, matched on its coefficients bit for bit), Schatzman–Paoli,
//! and a step whose `h` changes ([`super::core::ThetaCore::set_dt`]). Before issue 49 the
//! coefficients were written in four files and the plan copied each structure's choice
//! of backend.

use crate::assembly::linear_combination;
use crate::error::Error;
use crate::linalg::{FactorPlan, LinearSolver, SparseMatrix, SpdAnalysis};
use crate::model::LinearSystem;

/// Which step matrix a scheme factors (module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StepForm {
    /// The θ-method's iteration matrix `M + hθC + h²θ²K` (eq. 47; eq. 18 on a linear
    /// structure).
    Theta {
        /// `θ` of the θ-method.
        theta: f64,
    },
    /// Schatzman–Paoli's `M + h²θK + (hθ/2)C` (eq. 20a with the central velocity).
    SchatzmanPaoli {
        /// `θ` of eq. 20a.
        theta: f64,
    },
}

impl StepForm {
    /// The coefficients `(a, b)` of `M + a·K + b·C` at step `h`.
    pub fn coefficients(self, h: f64) -> (f64, f64) {
        match self {
            StepForm::Theta { theta } => (h * h * theta * theta, h * theta),
            StepForm::SchatzmanPaoli { theta } => (h * h * theta, 0.5 * h * theta),
        }
    }

    /// `θ` of the form.
    pub fn theta(self) -> f64 {
        match self {
            StepForm::Theta { theta } | StepForm::SchatzmanPaoli { theta } => theta,
        }
    }

    /// The matrix's name in errors and paths.
    pub fn name(self) -> &'static str {
        match self {
            StepForm::Theta { .. } => "iteration matrix M + hθC + h²θ²K",
            StepForm::SchatzmanPaoli { .. } => "Schatzman–Paoli matrix M + h²θK + (hθ/2)C",
        }
    }
}

/// The step matrix `M + a·K + b·C` of a scheme with its coefficients, formed (and, for
/// the factor of an SPD matrix, analysed) when the run was planned and kept for the build
/// ([`super::problem::Problem::plan`]).
#[derive(Debug)]
pub struct StepMatrix {
    coefficients: (f64, f64),
    matrix: SparseMatrix,
    analysis: Option<SpdAnalysis>,
}

impl StepMatrix {
    /// `M + a·K + b·C` of `sys`.
    pub fn form(sys: &LinearSystem, (a, b): (f64, f64)) -> Self {
        let mut terms = vec![(1.0, &sys.mass), (a, &sys.stiffness)];
        if let Some(c) = &sys.damping {
            terms.push((b, c));
        }
        StepMatrix {
            coefficients: (a, b),
            matrix: linear_combination(&terms),
            analysis: None,
        }
    }

    /// The matrix.
    pub fn matrix(&self) -> &SparseMatrix {
        &self.matrix
    }

    /// Keeps the symbolic analysis of the matrix's pattern for its factorization.
    pub fn keep_analysis(&mut self, analysis: Option<SpdAnalysis>) {
        self.analysis = analysis;
    }

    /// The kept symbolic analysis (an SPD factor's, when one was made).
    pub fn analysis(&self) -> Option<&SpdAnalysis> {
        self.analysis.as_ref()
    }

    /// Whether this is `M + a·K + b·C` for exactly `(a, b)` (to the bit).
    fn has_coefficients(&self, (a, b): (f64, f64)) -> bool {
        self.coefficients.0.to_bits() == a.to_bits() && self.coefficients.1.to_bits() == b.to_bits()
    }
}

/// What a structure states about its step matrix before anything is factored
/// ([`super::structure::StructureModel::analyse`]).
#[derive(Debug)]
pub struct StepAnalysis {
    /// The factor's backend, entries and scratch.
    pub factor: FactorPlan,
    /// Entries of the step matrix itself (16 bytes each with its index).
    pub matrix_entries: u64,
    /// The matrix formed and analysed, for the build to factor without forming and
    /// analysing it again (`None` where the structure forms its own at each step).
    pub kept: Option<StepMatrix>,
}

/// Forms `M̂(h)` of `form` and analyses it as an SPD matrix (the factor of a constant step
/// matrix: a tridiagonal `LDLᵀ`, or faer's Cholesky in the system's ordering), keeping
/// both for [`factor_step_matrix`].
pub fn analyse_spd_step(sys: &LinearSystem, form: StepForm, h: f64) -> Result<StepAnalysis, Error> {
    let mut kept = StepMatrix::form(sys, form.coefficients(h));
    let (factor, analysis) = crate::linalg::analyse_spd_kept(
        kept.matrix().as_ref(),
        form.name(),
        sys.ordering.as_ref(),
    )?;
    kept.keep_analysis(analysis);
    Ok(StepAnalysis {
        factor,
        matrix_entries: kept.matrix().val().len() as u64,
        kept: Some(kept),
    })
}

/// Forms and factors `M̂(h)` of `form` as an SPD matrix; `planned` is the one the run's
/// plan formed and analysed, taken when its coefficients are this step's bit for bit. The
/// inputs were checked once by [`crate::integrators::problem::Problem::validate`].
pub fn factor_step_matrix(
    sys: &LinearSystem,
    form: StepForm,
    h: f64,
    planned: Option<StepMatrix>,
) -> Result<Box<dyn LinearSolver>, Error> {
    let coefficients = form.coefficients(h);
    let step = match planned.filter(|p| p.has_coefficients(coefficients)) {
        Some(p) => p,
        None => StepMatrix::form(sys, coefficients),
    };
    crate::linalg::solver::factor_spd_analysed(
        step.matrix.as_ref(),
        form.name(),
        sys.ordering.as_ref(),
        step.analysis,
    )
}
