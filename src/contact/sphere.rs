//! Nodes inside a rigid sphere (a circle in 2-D): `g^α(q) = R − |X_α + u_α − c|`.
//!
//! The gap is nonlinear in `q` and `G_α = −(x − c)/|x − c|` turns with the node, so a
//! scheme that evaluates `G(q_{k+1})` (eq. 18a, 28) must iterate (eq. 42–51).

use super::{ContactJacobian, ContactSet, check_restitution};
use crate::error::{Error, require_positive};

/// Nodal contacts with the inside wall of a rigid sphere of radius `R` centred at `c`.
#[derive(Clone, Debug)]
pub struct InsideSphere {
    /// For each contact node, its dofs (one per space dimension).
    pub node_dofs: Vec<Vec<usize>>,
    /// Reference coordinates of each node (`x = X + u`).
    pub reference: Vec<Vec<f64>>,
    /// Centre `c`.
    pub center: Vec<f64>,
    /// Radius `R` (m).
    pub radius: f64,
    restitution: Vec<f64>,
}

impl InsideSphere {
    /// Builds the set with restitution `e` for every contact.
    pub fn new(
        node_dofs: Vec<Vec<usize>>,
        reference: Vec<Vec<f64>>,
        center: Vec<f64>,
        radius: f64,
        e: f64,
    ) -> Result<Self, Error> {
        check_restitution("restitution", e)?;
        require_positive("radius", radius)?;
        let m = node_dofs.len();
        Ok(InsideSphere {
            node_dofs,
            reference,
            center,
            radius,
            restitution: vec![e; m],
        })
    }
}

impl ContactSet for InsideSphere {
    fn len(&self) -> usize {
        self.node_dofs.len()
    }
    fn is_linear(&self) -> bool {
        false
    }
    fn pattern(&self) -> Vec<Vec<usize>> {
        self.node_dofs.clone()
    }
    fn evaluate(&self, q: &[f64], gap: &mut [f64], jac: &mut ContactJacobian) {
        for (a, dofs) in self.node_dofs.iter().enumerate() {
            let col = jac.col_values_mut(a);
            let mut r2 = 0.0;
            for (k, &d) in dofs.iter().enumerate() {
                let x = self.reference[a][k] + q[d] - self.center[k];
                col[k] = x;
                r2 += x * x;
            }
            let r = r2.sqrt();
            gap[a] = self.radius - r;
            if r > 0.0 {
                col.iter_mut().for_each(|x| *x /= -r);
            } else {
                // At the centre any direction is a valid (sub)gradient; the gap is R > 0.
                col.iter_mut().for_each(|x| *x = 0.0);
                col[0] = -1.0;
            }
        }
    }
    fn restitution(&self) -> &[f64] {
        &self.restitution
    }
}
