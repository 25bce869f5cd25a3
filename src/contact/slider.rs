//! The four corners of the slider–crank's slider against its guides (paper sec. 6.3.1;
//! the system is [`crate::model::multibody`]).
//!
//! A corner of body coordinates `(a_i, b_i) ∈ {±a} × {±b}` is at height
//! `y_i = y_s + a_i sin θ₃ + b_i cos θ₃` and abscissa `x_i = x_s + a_i cos θ₃ − b_i sin θ₃`,
//! with the slider centre `(x_s, y_s) = l₁(cos θ₁, sin θ₁) + l₂(cos θ₂, sin θ₂)`. The
//! upper corners (`b_i = +b`) face the guide `y = d/2`: `g_i = d/2 − y_i`; the lower
//! ones the guide `y = −d/2`: `g_i = d/2 + y_i`. At `q = 0` every gap is the clearance
//! `c`. Order as in Siconos' example: `(−a, b)`, `(a, b)`, `(−a, −b)`, `(a, −b)`.
//!
//! `∇y_i = (l₁ cos θ₁, l₂ cos θ₂, a_i cos θ₃ − b_i sin θ₃)`; the normal row is `−∇y_i`
//! (upper) or `∇y_i` (lower). With friction the tangent row follows the 2-D frame rule
//! of [`super::frame`] (normal turned by +90°): the guide's normal is `(0, ∓1)`, so the
//! tangent is `(±1, 0)` and the row is `±∇x_i`, with
//! `∇x_i = (−l₁ sin θ₁, −l₂ sin θ₂, −a_i sin θ₃ − b_i cos θ₃)`.

use super::{ContactJacobian, ContactLaw, ContactSet};
use crate::error::Error;
use crate::model::multibody::SliderCrankParams;

/// The slider's four corners against the two guides (module doc).
#[derive(Clone, Debug)]
pub struct SliderCorners {
    p: SliderCrankParams,
    laws: [ContactLaw; 4],
    dim: usize,
}

impl SliderCorners {
    /// Corners of the slider of `p` with restitution `e` and friction `mu`.
    pub fn new(p: &SliderCrankParams, e: f64, mu: f64) -> Result<Self, Error> {
        p.validate("")?;
        crate::error::require_in("restitution", e, 0.0, 1.0)?;
        super::check_friction("friction", mu)?;
        Ok(SliderCorners {
            p: *p,
            laws: [ContactLaw {
                restitution: e,
                friction: mu,
            }; 4],
            dim: if mu > 0.0 { 2 } else { 1 },
        })
    }

    /// Body coordinates `(a_i, b_i)` of corner `i` (module doc).
    pub fn corner(&self, i: usize) -> (f64, f64) {
        let (a, b) = (self.p.a, self.p.b);
        [(-a, b), (a, b), (-a, -b), (a, -b)][i]
    }
}

impl ContactSet for SliderCorners {
    fn len(&self) -> usize {
        4
    }
    fn is_linear(&self) -> bool {
        false
    }
    fn dim(&self, _alpha: usize) -> usize {
        self.dim
    }
    fn pattern(&self) -> Vec<Vec<usize>> {
        vec![vec![0, 1, 2]; 4 * self.dim]
    }
    fn evaluate(&self, q: &[f64], gap: &mut [f64], jac: &mut ContactJacobian) {
        let p = &self.p;
        let (s1, c1) = q[0].sin_cos();
        let (s2, c2) = q[1].sin_cos();
        let (s3, c3) = q[2].sin_cos();
        let ys = p.l1 * s1 + p.l2 * s2;
        let half = p.half_gap();
        for i in 0..4 {
            let (ai, bi) = self.corner(i);
            let y = ys + ai * s3 + bi * c3;
            let dy = [p.l1 * c1, p.l2 * c2, ai * c3 - bi * s3];
            let sign = if bi > 0.0 { -1.0 } else { 1.0 };
            gap[i] = half + sign * y;
            let col = jac.block(i).start;
            let n = jac.col_values_mut(col);
            for (x, d) in n.iter_mut().zip(dy) {
                *x = sign * d;
            }
            if self.dim == 2 {
                let dx = [-p.l1 * s1, -p.l2 * s2, -ai * s3 - bi * c3];
                let t = jac.col_values_mut(col + 1);
                for (x, d) in t.iter_mut().zip(dx) {
                    *x = -sign * d;
                }
            }
        }
    }
    fn laws(&self) -> &[ContactLaw] {
        &self.laws
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Gaps equal the clearance at `q = 0`, and the Jacobian rows are the gradients of
    /// the gaps and of the corners' abscissae (central differences, 1e-8 relative).
    #[test]
    fn gaps_and_rows_match_differences() {
        let p = SliderCrankParams::default();
        let set = SliderCorners::new(&p, 0.4, 0.01).unwrap();
        let mut jac = ContactJacobian::for_set(&set);
        let mut gap = [0.0; 4];
        set.evaluate(&[0.0; 3], &mut gap, &mut jac);
        for g in gap {
            assert!((g - p.c).abs() < 1e-15, "{g}");
        }
        let q = [0.9, -0.2, 0.03];
        set.evaluate(&q, &mut gap, &mut jac);
        let eps = 1e-6;
        let abscissa = |q: &[f64], i: usize| {
            let (ai, bi) = set.corner(i);
            let (xs, _) = p.slider_centre(q);
            xs + ai * q[2].cos() - bi * q[2].sin()
        };
        for j in 0..3 {
            let (mut qp, mut qm) = (q, q);
            qp[j] += eps;
            qm[j] -= eps;
            let (mut gp, mut gm) = ([0.0; 4], [0.0; 4]);
            let mut scratch = ContactJacobian::for_set(&set);
            set.evaluate(&qp, &mut gp, &mut scratch);
            set.evaluate(&qm, &mut gm, &mut scratch);
            for i in 0..4 {
                let col = jac.block(i).start;
                let fd = (gp[i] - gm[i]) / (2.0 * eps);
                assert!((jac.col(col).1[j] - fd).abs() < 1e-8, "normal {i} {j}");
                // tangent: +∇x on the upper guide, −∇x on the lower
                let sign = if i < 2 { 1.0 } else { -1.0 };
                let fdx = sign * (abscissa(&qp, i) - abscissa(&qm, i)) / (2.0 * eps);
                assert!(
                    (jac.col(col + 1).1[j] - fdx).abs() < 1e-8,
                    "tangent {i} {j}"
                );
            }
        }
    }
}
