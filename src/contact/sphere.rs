//! Nodes against a rigid sphere or cylinder (a circle in 2-D), from inside or outside.
//!
//! Sphere: `d = x − c`; cylinder: `d = (x − c) − ((x − c)·a) a` (the part normal to
//! the unit axis `a`). Outside: `g = |d| − R`, `G = d/|d|`; inside: `g = R − |d|`,
//! `G = −d/|d|`. The gap is nonlinear in `q` and `G` turns with the node, so a scheme
//! that evaluates `G(q_{k+1})` (eq. 18a, 28) iterates (eq. 42–51).

use super::{ContactJacobian, ContactLaw, ContactSet, check_restitution};
use crate::error::{Error, require_positive};

/// Which side of the surface is admissible.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Side {
    /// The body stays inside (a container).
    Inside,
    /// The body stays outside (an obstacle).
    Outside,
}

/// Nodal contacts with a rigid sphere (`axis = None`) or cylinder (`axis = Some`).
#[derive(Clone, Debug)]
pub struct RoundObstacle {
    /// For each contact node, its dofs (one per space dimension).
    pub node_dofs: Vec<Vec<usize>>,
    /// Reference coordinates of each node (`x = X + u`).
    pub reference: Vec<Vec<f64>>,
    /// Centre `c` (a point of the axis for a cylinder).
    pub center: Vec<f64>,
    /// Unit axis of a cylinder.
    pub axis: Option<Vec<f64>>,
    /// Radius `R` (m).
    pub radius: f64,
    /// Admissible side.
    pub side: Side,
    laws: super::UniformLaws,
}

/// The historical name: nodes kept inside a sphere.
pub type InsideSphere = RoundObstacle;

impl RoundObstacle {
    /// Nodes kept inside a sphere of radius `R` at `c`, restitution `e`.
    pub fn new(
        node_dofs: Vec<Vec<usize>>,
        reference: Vec<Vec<f64>>,
        center: Vec<f64>,
        radius: f64,
        e: f64,
    ) -> Result<Self, Error> {
        Self::general(node_dofs, reference, center, None, radius, Side::Inside, e)
    }

    /// Any round obstacle; `axis` is normalized.
    pub fn general(
        node_dofs: Vec<Vec<usize>>,
        reference: Vec<Vec<f64>>,
        center: Vec<f64>,
        axis: Option<Vec<f64>>,
        radius: f64,
        side: Side,
        e: f64,
    ) -> Result<Self, Error> {
        check_restitution("restitution", e)?;
        require_positive("radius", radius)?;
        let dim = center.len();
        if center.iter().any(|c| !c.is_finite()) {
            return Err(Error::invalid(
                "center",
                format!("{center:?}"),
                "must be finite",
            ));
        }
        let axis = match axis {
            Some(a) => {
                let n = a.iter().map(|x| x * x).sum::<f64>().sqrt();
                if a.len() != dim || !(n.is_finite() && n > 0.0) {
                    return Err(Error::invalid(
                        "axis",
                        format!("{a:?}"),
                        &format!("must be a finite non-zero vector of {dim} components"),
                    ));
                }
                Some(a.iter().map(|x| x / n).collect())
            }
            None => None,
        };
        for (a, (d, x)) in node_dofs.iter().zip(&reference).enumerate() {
            if d.len() != dim || x.len() != dim {
                return Err(Error::invalid(
                    &format!("contact[{a}]"),
                    format!("dofs {d:?}"),
                    &format!("needs {dim} dofs and coordinates"),
                ));
            }
        }
        let m = node_dofs.len();
        Ok(RoundObstacle {
            node_dofs,
            reference,
            center,
            axis,
            radius,
            side,
            laws: super::UniformLaws::frictionless(m, e),
        })
    }

    /// Gives every contact the friction coefficient `mu` (blocks of the space dimension
    /// when `mu > 0`; the frame turns with the normal).
    pub fn with_friction(mut self, mu: f64) -> Result<Self, Error> {
        let d = self.center.len();
        self.laws.set_friction(mu, d)?;
        Ok(self)
    }
}

impl ContactSet for RoundObstacle {
    fn len(&self) -> usize {
        self.node_dofs.len()
    }
    fn coordinate_scale(&self) -> f64 {
        self.reference
            .iter()
            .flatten()
            .chain(&self.center)
            .fold(0.0, |a: f64, x| a.max(x.abs()))
    }
    fn is_linear(&self) -> bool {
        false
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
        let nd = self.center.len();
        for (a, dofs) in self.node_dofs.iter().enumerate() {
            let mut buf = [0.0; 3];
            let col = &mut buf[..nd];
            for (k, &d) in dofs.iter().enumerate() {
                col[k] = self.reference[a][k] + q[d] - self.center[k];
            }
            if let Some(ax) = &self.axis {
                let s: f64 = col.iter().zip(ax).map(|(x, y)| x * y).sum();
                col.iter_mut().zip(ax).for_each(|(x, y)| *x -= s * y);
            }
            let r = col.iter().map(|x| x * x).sum::<f64>().sqrt();
            let sign = match self.side {
                Side::Outside => 1.0,
                Side::Inside => -1.0,
            };
            gap[a] = sign * (r - self.radius);
            if r > 0.0 {
                col.iter_mut().for_each(|x| *x *= sign / r);
            } else {
                // On the centre (axis) any direction is a valid (sub)gradient.
                col.iter_mut().for_each(|x| *x = 0.0);
                col[0] = sign;
            }
            super::frame::write_nodal_block(col, self.laws.dim, a * self.laws.dim, jac);
        }
    }
    fn laws(&self) -> &[ContactLaw] {
        &self.laws.laws
    }
}
