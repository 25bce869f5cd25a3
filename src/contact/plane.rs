//! Nodes against a fixed rigid plane: `g^α(q) = n·(X_α + u_α) − c` (linear in `q`), with
//! the plane's constant frame ([`super::frame`]) as tangential rows when `μ > 0`.

use super::{ContactJacobian, ContactLaw, ContactSet, check_restitution};
use crate::error::Error;

/// Nodal contacts of a deformable body with the rigid plane `{x : n·x = c}`; the body
/// is on the side `n·x > c`.
#[derive(Clone, Debug)]
pub struct NodesOnPlane {
    /// For each contact node, its dofs (one per space dimension).
    pub node_dofs: Vec<Vec<usize>>,
    /// Reference coordinates `X_α` of each contact node.
    pub reference: Vec<Vec<f64>>,
    /// Unit normal `n` pointing into the admissible side.
    pub normal: Vec<f64>,
    /// Plane offset `c`.
    pub offset: f64,
    laws: super::UniformLaws,
}

impl NodesOnPlane {
    /// Builds the set; `normal` is normalized, `e` is applied to every contact.
    pub fn new(
        node_dofs: Vec<Vec<usize>>,
        reference: Vec<Vec<f64>>,
        normal: Vec<f64>,
        offset: f64,
        e: f64,
    ) -> Result<Self, Error> {
        check_restitution("restitution", e)?;
        let norm = normal.iter().map(|x| x * x).sum::<f64>().sqrt();
        if !(norm.is_finite() && norm > 0.0) {
            return Err(Error::invalid(
                "normal",
                format!("{normal:?}"),
                "must be a finite non-zero vector",
            ));
        }
        let dim = normal.len();
        for (a, (d, x)) in node_dofs.iter().zip(&reference).enumerate() {
            if d.len() != dim || x.len() != dim || x.iter().any(|v| !v.is_finite()) {
                return Err(Error::invalid(
                    &format!("contact[{a}]"),
                    format!("dofs {d:?}, X {x:?}"),
                    &format!("needs {dim} dofs and {dim} finite coordinates"),
                ));
            }
        }
        let m = node_dofs.len();
        Ok(NodesOnPlane {
            node_dofs,
            reference,
            normal: normal.iter().map(|x| x / norm).collect(),
            offset: offset / norm,
            laws: super::UniformLaws::frictionless(m, e),
        })
    }

    /// Gives every contact the friction coefficient `mu` (blocks of the space dimension
    /// when `mu > 0`).
    pub fn with_friction(mut self, mu: f64) -> Result<Self, Error> {
        let d = self.normal.len();
        self.laws.set_friction(mu, d)?;
        Ok(self)
    }
}

impl ContactSet for NodesOnPlane {
    fn len(&self) -> usize {
        self.node_dofs.len()
    }
    fn is_linear(&self) -> bool {
        true
    }
    fn dim(&self, _alpha: usize) -> usize {
        self.laws.dim
    }
    fn pattern(&self) -> Vec<Vec<usize>> {
        self.node_dofs
            .iter()
            .flat_map(|d| std::iter::repeat_n(d.clone(), self.laws.dim))
            .collect()
    }
    fn evaluate(&self, q: &[f64], gap: &mut [f64], jac: &mut ContactJacobian) {
        for (a, dofs) in self.node_dofs.iter().enumerate() {
            let mut g = -self.offset;
            for (k, &d) in dofs.iter().enumerate() {
                g += self.normal[k] * (self.reference[a][k] + q[d]);
            }
            gap[a] = g;
            super::frame::write_nodal_block(&self.normal, self.laws.dim, a * self.laws.dim, jac);
        }
    }
    fn laws(&self) -> &[ContactLaw] {
        &self.laws.laws
    }
}
