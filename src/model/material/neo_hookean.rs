//! Compressible neo-Hookean: `W = μ/2 (I₁ − 3) − μ ln J + λ/2 (ln J)²`,
//! `S = μ (I − C⁻¹) + λ ln J C⁻¹`, `ℂ = λ C⁻¹ ⊗ C⁻¹ + 2 (μ − λ ln J) 𝕀_{C⁻¹}` (module doc
//! of [`crate::model::hyperelastic`]).

use nalgebra::{Matrix3, SMatrix};

use super::{HyperelasticLaw, Inverted, StressTangent, VOIGT, positive_det, voigt};

/// Compressible neo-Hookean (`model = "neo-hookean"`).
#[derive(Debug)]
pub struct NeoHookean;

impl HyperelasticLaw for NeoHookean {
    fn name(&self) -> &'static str {
        "neo-hookean"
    }

    fn title(&self) -> &'static str {
        "neo-Hookean"
    }

    fn energy(&self, (lambda, mu): (f64, f64), f: &Matrix3<f64>) -> Result<f64, Inverted> {
        let c = f.transpose() * f;
        let j = positive_det(f)?;
        let lnj = j.ln();
        Ok(0.5 * mu * (c.trace() - 3.0) - mu * lnj + 0.5 * lambda * lnj * lnj)
    }

    fn stress(
        &self,
        (lambda, mu): (f64, f64),
        f: &Matrix3<f64>,
    ) -> Result<SMatrix<f64, 6, 1>, Inverted> {
        let c = f.transpose() * f;
        let j = positive_det(f)?;
        let ci = c.try_inverse().ok_or(Inverted { det: j })?;
        Ok(voigt(
            &(mu * (Matrix3::identity() - ci) + lambda * j.ln() * ci),
        ))
    }

    fn stress_of_c(
        &self,
        (lambda, mu): (f64, f64),
        c: &Matrix3<f64>,
    ) -> Result<Matrix3<f64>, Inverted> {
        let det = c.determinant();
        if det.is_nan() || det <= 0.0 {
            return Err(Inverted { det });
        }
        let ci = c.try_inverse().ok_or(Inverted { det })?;
        Ok(mu * (Matrix3::identity() - ci) + lambda * (0.5 * det.ln()) * ci)
    }

    fn stress_tangent(
        &self,
        (lambda, mu): (f64, f64),
        f: &Matrix3<f64>,
    ) -> Result<StressTangent, Inverted> {
        let c = f.transpose() * f;
        let mut d = SMatrix::<f64, 6, 6>::zeros();
        let j = positive_det(f)?;
        let lnj = j.ln();
        let ci = c.try_inverse().ok_or(Inverted { det: j })?;
        let sm = mu * (Matrix3::identity() - ci) + lambda * lnj * ci;
        let s = voigt(&sm);
        let k = mu - lambda * lnj;
        for (a, &(i, jj)) in VOIGT.iter().enumerate() {
            for (b, &(kk, l)) in VOIGT.iter().enumerate() {
                d[(a, b)] = lambda * ci[(i, jj)] * ci[(kk, l)]
                    + k * (ci[(i, kk)] * ci[(jj, l)] + ci[(i, l)] * ci[(jj, kk)]);
            }
        }
        Ok((s, d))
    }
}
