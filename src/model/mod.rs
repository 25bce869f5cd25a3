//! Mechanical models: what the integrators step.
//!
//! A model is a [`LinearSystem`] (eq. 1c with `F(t, q, v) = f(t) − C v − K q`: constant
//! sparse mass `M`, stiffness `K`, optional Rayleigh damping `C`, external force `f`)
//! plus a set of contacts (see [`crate::contact`]) and initial conditions.
//! Nonlinear constraints (curved obstacles, rigid rotations) are supported through
//! the contact set; nonlinear internal forces (large strain, nonlinear materials) will
//! add a tangent-returning variant of this type, with the same integrators.
//!
//! Submodules build systems: [`rod`] (P1 rod elements, eq. 71) and [`point_mass`].

pub mod generate;
pub mod point_mass;
pub mod rod;
pub mod solid;

use crate::linalg::{SparseMatrix, quadratic_form};

/// How the element mass matrices are formed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MassKind {
    /// Consistent mass, `∫ ρ Nᵀ N` (eq. 71 for the rod).
    Consistent,
    /// Row-sum lumped mass (diagonal).
    Lumped,
}

impl MassKind {
    /// Parses `consistent` or `lumped`.
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "consistent" => Some(MassKind::Consistent),
            "lumped" => Some(MassKind::Lumped),
            _ => None,
        }
    }
    /// The name used on the command line and in summaries.
    pub fn name(self) -> &'static str {
        match self {
            MassKind::Consistent => "consistent",
            MassKind::Lumped => "lumped",
        }
    }
}

/// A linear structural model `M v̇ + C v + K q = f + G λ` (eq. 1c).
#[derive(Clone, Debug)]
pub struct LinearSystem {
    /// Mass matrix `M` (symmetric positive definite).
    pub mass: SparseMatrix,
    /// Stiffness matrix `K` (symmetric positive semidefinite).
    pub stiffness: SparseMatrix,
    /// Damping matrix `C` (Rayleigh or none).
    pub damping: Option<SparseMatrix>,
    /// Constant external force `f` (N); zero for the free bar.
    pub force: Vec<f64>,
    /// Displacement components per node (1 for rods, 2 or 3 for solids); dof `i`
    /// is component `i % dofs_per_node` of node `i / dofs_per_node`.
    pub dofs_per_node: usize,
}

impl LinearSystem {
    /// Number of degrees of freedom.
    pub fn ndof(&self) -> usize {
        self.mass.nrows()
    }

    /// Kinetic energy `½ vᵀ M v` (J).
    pub fn kinetic_energy(&self, v: &[f64]) -> f64 {
        0.5 * quadratic_form(self.mass.as_ref(), v)
    }

    /// Potential energy `½ qᵀ K q − fᵀ q` (J): elastic energy plus the potential of the
    /// constant external force.
    pub fn potential_energy(&self, q: &[f64]) -> f64 {
        0.5 * quadratic_form(self.stiffness.as_ref(), q)
            - self.force.iter().zip(q).map(|(f, x)| f * x).sum::<f64>()
    }

    /// Linear momentum along the first axis, `e_xᵀ M v` (kg·m/s), where `e_x` is 1 on
    /// every x-component dof.
    pub fn momentum(&self, v: &[f64]) -> f64 {
        let m = self.mass.as_ref();
        let d = self.dofs_per_node;
        let mut s = 0.0;
        for (j, &vj) in v.iter().enumerate() {
            for k in m.col_ptr()[j]..m.col_ptr()[j + 1] {
                if m.row_idx()[k] % d == 0 {
                    s += m.val()[k] * vj;
                }
            }
        }
        s
    }

    /// Total mass `e_xᵀ M e_x` (kg).
    pub fn total_mass(&self) -> f64 {
        let m = self.mass.as_ref();
        let d = self.dofs_per_node;
        let mut s = 0.0;
        for j in (0..m.ncols()).step_by(d) {
            for k in m.col_ptr()[j]..m.col_ptr()[j + 1] {
                if m.row_idx()[k] % d == 0 {
                    s += m.val()[k];
                }
            }
        }
        s
    }
}
