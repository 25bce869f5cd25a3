//! St. Venant–Kirchhoff: `W = λ/2 (tr E)² + μ E:E`, `S = λ tr E I + 2μ E`, constant `ℂ`
//! (module doc of [`crate::model::hyperelastic`]).

use nalgebra::{Matrix3, SMatrix};

use super::{HyperelasticLaw, Inverted, StressTangent, positive_det, voigt};

/// St. Venant–Kirchhoff (`model = "svk"`).
#[derive(Debug)]
pub struct Svk;

impl HyperelasticLaw for Svk {
    fn name(&self) -> &'static str {
        "svk"
    }

    fn title(&self) -> &'static str {
        "St. Venant–Kirchhoff"
    }

    fn energy(&self, (lambda, mu): (f64, f64), f: &Matrix3<f64>) -> Result<f64, Inverted> {
        let c = f.transpose() * f;
        // defined for any F, but a cell with det F ≤ 0 is turned inside out: the
        // law's energy has a spurious minimum there (issue 34: an SVK cube
        // pushed with 5 E A ran on with its top 0.39 m below its base)
        positive_det(f)?;
        let e = 0.5 * (c - Matrix3::identity());
        Ok(0.5 * lambda * e.trace().powi(2) + mu * e.component_mul(&e).sum())
    }

    fn stress(
        &self,
        (lambda, mu): (f64, f64),
        f: &Matrix3<f64>,
    ) -> Result<SMatrix<f64, 6, 1>, Inverted> {
        let c = f.transpose() * f;
        positive_det(f)?;
        let e = 0.5 * (c - Matrix3::identity());
        Ok(voigt(
            &(lambda * e.trace() * Matrix3::identity() + 2.0 * mu * e),
        ))
    }

    fn stress_of_c(
        &self,
        (lambda, mu): (f64, f64),
        c: &Matrix3<f64>,
    ) -> Result<Matrix3<f64>, Inverted> {
        let e = 0.5 * (c - Matrix3::identity());
        Ok(lambda * e.trace() * Matrix3::identity() + 2.0 * mu * e)
    }

    fn stress_tangent(
        &self,
        (lambda, mu): (f64, f64),
        f: &Matrix3<f64>,
    ) -> Result<StressTangent, Inverted> {
        let c = f.transpose() * f;
        let mut d = SMatrix::<f64, 6, 6>::zeros();
        positive_det(f)?;
        let e = 0.5 * (c - Matrix3::identity());
        let tr = e.trace();
        let sm = lambda * tr * Matrix3::identity() + 2.0 * mu * e;
        let s = voigt(&sm);
        for i in 0..3 {
            for j in 0..3 {
                d[(i, j)] = lambda;
            }
            d[(i, i)] = lambda + 2.0 * mu;
            d[(i + 3, i + 3)] = mu;
        }
        Ok((s, d))
    }
}
