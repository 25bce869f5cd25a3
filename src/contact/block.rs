//! The rocking block of eq. 9–10: a rigid 2-D block (q = [x, y, θ]: centre of mass and
//! angle) whose two bottom corners A and B touch the ground `y = 0`.
//!
//! The printed eq. 9 lost its lengths. Derivation: a point of body coordinates `(a, b)`
//! (along the block's length and thickness, from the centre) is at height
//! `y + a sin θ + b cos θ`. The bottom corners are `(±L/2, −l/2)` for a block of length
//! `L` and thickness `l`, so
//! `g_A = y + (L/2) sin θ − (l/2) cos θ`, `g_B = y − (L/2) sin θ − (l/2) cos θ`,
//! with gradients `∇g_A = [0, 1, (L/2) cos θ + (l/2) sin θ]` and
//! `∇g_B = [0, 1, −(L/2) cos θ + (l/2) sin θ]`. Both depend on θ, so `G` changes with
//! `q` and the Newton loop iterates.
//!
//! With friction each corner gets the ground's tangent row (frame of [`super::frame`]:
//! `t = (−1, 0)`): the corner's abscissa is `x + a cos θ − b sin θ`, so
//! `G_T = −[1, 0, −a sin θ − b cos θ]` on the dofs `x, θ`.

use super::{ContactJacobian, ContactLaw, ContactSet};
use crate::error::{Error, require_positive};

/// The two bottom corners of a rigid block on the ground `y = 0`.
#[derive(Clone, Debug)]
pub struct BlockCorners {
    length: f64,
    thickness: f64,
    laws: [ContactLaw; 2],
    dim: usize,
}

impl BlockCorners {
    /// Corners of a block of `length` L and `thickness` l (m) with restitution `e`.
    pub fn new(length: f64, thickness: f64, e: f64) -> Result<Self, Error> {
        require_positive("length", length)?;
        require_positive("thickness", thickness)?;
        crate::error::require_in("restitution", e, 0.0, 1.0)?;
        Ok(BlockCorners {
            length,
            thickness,
            laws: [ContactLaw {
                restitution: e,
                friction: 0.0,
            }; 2],
            dim: 1,
        })
    }
}

impl BlockCorners {
    /// Gives both corners the friction coefficient `mu` (two rows each when `mu > 0`).
    pub fn with_friction(mut self, mu: f64) -> Result<Self, Error> {
        super::check_friction("friction", mu)?;
        self.laws.iter_mut().for_each(|l| l.friction = mu);
        self.dim = if mu > 0.0 { 2 } else { 1 };
        Ok(self)
    }
}

impl ContactSet for BlockCorners {
    fn len(&self) -> usize {
        2
    }
    fn is_linear(&self) -> bool {
        false
    }
    fn dim(&self, _alpha: usize) -> usize {
        self.dim
    }
    fn pattern(&self) -> Vec<Vec<usize>> {
        if self.dim == 1 {
            vec![vec![1, 2], vec![1, 2]]
        } else {
            vec![vec![1, 2], vec![0, 2], vec![1, 2], vec![0, 2]]
        }
    }
    fn evaluate(&self, q: &[f64], gap: &mut [f64], jac: &mut ContactJacobian) {
        let (y, th) = (q[1], q[2]);
        let (hl, ht) = (0.5 * self.length, 0.5 * self.thickness);
        let (s, c) = th.sin_cos();
        gap[0] = y + hl * s - ht * c;
        gap[1] = y - hl * s - ht * c;
        let d = self.dim;
        jac.col_values_mut(0)
            .copy_from_slice(&[1.0, hl * c + ht * s]);
        jac.col_values_mut(d)
            .copy_from_slice(&[1.0, -hl * c + ht * s]);
        if d == 2 {
            // body coordinates (a, b) = (±L/2, −l/2): dX/dθ = −a sin θ − b cos θ
            for (col, a) in [(1, hl), (3, -hl)] {
                jac.col_values_mut(col)
                    .copy_from_slice(&[-1.0, -(-a * s + ht * c)]);
            }
        }
    }
    fn laws(&self) -> &[ContactLaw] {
        &self.laws
    }
}
