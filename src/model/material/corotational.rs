//! Corotational linear elasticity: the linear isotropic law in each point's rotated frame.
//!
//! With the polar decomposition `F = R U`, the strain is Biot's `U − I` (the stretch, with
//! the rotation `R` taken out) and the energy is the small-strain one of that strain,
//!
//! `W = μ ‖U − I‖² + λ/2 (tr U − 3)² = μ Σ(u_a − 1)² + λ/2 (Σ u_a − 3)²`
//!
//! (`u_a` the principal stretches, `u_a² ` the eigenvalues of `C = FᵀF`). So a rigid
//! rotation costs no energy at any angle (the linear law of `material.model = "linear"`
//! charges `2(λ + μ)V` for a quarter turn of a body), and at small rotations and strains
//! it is the linear law. It is hyperelastic and frame-indifferent, so the θ-method keeps
//! the momenta a frame-indifferent force keeps, and Gonzalez's discrete gradient
//! (`scheme.energy_momentum`) applies as to any registered law. Since `tr U` has the
//! derivative `½ U⁻¹` in `C`,
//!
//! `S = 2 ∂W/∂C = 2μ (I − U⁻¹) + λ (tr U − 3) U⁻¹`,
//!
//! and with `dU` solving `U dU + dU U = dC` (in `C`'s eigenbasis `dU_ab = dC_ab / (u_a +
//! u_b)`), `ℂ = ∂S/∂E` is, with `P_a` the eigenprojections and `κ = 2μ − λ(tr U − 3)`,
//!
//! `ℂ_ijkl = Σ_ab w_ab ½ (P_a,ik P_b,jl + P_a,il P_b,jk) + λ U⁻¹_ij U⁻¹_kl`,
//! `w_ab = 2κ / (u_a u_b (u_a + u_b))`,
//!
//! smooth where stretches coincide (`w` is a symmetric function of the pair), Hooke's
//! tensor at `U = I`. The eigen-decomposition is nalgebra's `SymmetricEigen` of `C`.

use nalgebra::{Matrix3, SMatrix, SymmetricEigen, Vector3};

use super::{HyperelasticLaw, Inverted, StressTangent, VOIGT, positive_det, voigt};

/// Corotational linear elasticity (`model = "corotational"`).
#[derive(Debug)]
pub struct Corotational;

/// The principal stretches and eigenvectors of `C` (columns), refusing a `C` that is not
/// positive definite (an inverted or degenerate deformation).
fn stretches(c: &Matrix3<f64>) -> Result<(Vector3<f64>, Matrix3<f64>), Inverted> {
    let eig = SymmetricEigen::new(*c);
    let lo = eig.eigenvalues.min();
    if !(lo.is_finite() && lo > 0.0) {
        return Err(Inverted {
            det: c.determinant().max(0.0).sqrt(),
        });
    }
    Ok((eig.eigenvalues.map(f64::sqrt), eig.eigenvectors))
}

/// `U⁻¹ = Q diag(1/u) Qᵀ`.
fn inverse_stretch(u: &Vector3<f64>, q: &Matrix3<f64>) -> Matrix3<f64> {
    q * Matrix3::from_diagonal(&u.map(|x| 1.0 / x)) * q.transpose()
}

/// `S` (matrix) from the stretches.
fn stress_matrix(lambda: f64, mu: f64, u: &Vector3<f64>, q: &Matrix3<f64>) -> Matrix3<f64> {
    let ui = inverse_stretch(u, q);
    2.0 * mu * (Matrix3::identity() - ui) + lambda * (u.sum() - 3.0) * ui
}

impl HyperelasticLaw for Corotational {
    fn name(&self) -> &'static str {
        "corotational"
    }

    fn title(&self) -> &'static str {
        "corotational linear"
    }

    fn energy(&self, (lambda, mu): (f64, f64), f: &Matrix3<f64>) -> Result<f64, Inverted> {
        positive_det(f)?;
        let (u, _) = stretches(&(f.transpose() * f))?;
        let dev = u.map(|x| x - 1.0);
        Ok(mu * dev.norm_squared() + 0.5 * lambda * dev.sum().powi(2))
    }

    fn stress(
        &self,
        (lambda, mu): (f64, f64),
        f: &Matrix3<f64>,
    ) -> Result<SMatrix<f64, 6, 1>, Inverted> {
        positive_det(f)?;
        let (u, q) = stretches(&(f.transpose() * f))?;
        Ok(voigt(&stress_matrix(lambda, mu, &u, &q)))
    }

    fn stress_of_c(
        &self,
        (lambda, mu): (f64, f64),
        c: &Matrix3<f64>,
    ) -> Result<Matrix3<f64>, Inverted> {
        let (u, q) = stretches(c)?;
        Ok(stress_matrix(lambda, mu, &u, &q))
    }

    fn stress_tangent(
        &self,
        (lambda, mu): (f64, f64),
        f: &Matrix3<f64>,
    ) -> Result<StressTangent, Inverted> {
        positive_det(f)?;
        let (u, q) = stretches(&(f.transpose() * f))?;
        let ui = inverse_stretch(&u, &q);
        let s = voigt(&(2.0 * mu * (Matrix3::identity() - ui) + lambda * (u.sum() - 3.0) * ui));
        let kappa = 2.0 * mu - lambda * (u.sum() - 3.0);
        // the eigenprojections P_a = q_a q_aᵀ
        let p: [Matrix3<f64>; 3] = std::array::from_fn(|a| {
            let col = q.column(a);
            col * col.transpose()
        });
        let mut w = [[0.0; 3]; 3];
        for (a, row) in w.iter_mut().enumerate() {
            for (b, x) in row.iter_mut().enumerate() {
                *x = 2.0 * kappa / (u[a] * u[b] * (u[a] + u[b]));
            }
        }
        let mut d = SMatrix::<f64, 6, 6>::zeros();
        for (x, &(i, j)) in VOIGT.iter().enumerate() {
            for (y, &(k, l)) in VOIGT.iter().enumerate() {
                let mut acc = lambda * ui[(i, j)] * ui[(k, l)];
                for (a, pa) in p.iter().enumerate() {
                    for (b, pb) in p.iter().enumerate() {
                        acc += w[a][b] * 0.5 * (pa[(i, k)] * pb[(j, l)] + pa[(i, l)] * pb[(j, k)]);
                    }
                }
                d[(x, y)] = acc;
            }
        }
        Ok((s, d))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A rigid rotation of any angle holds no energy and no stress (round-off of the
    /// eigen-decomposition: 1e-12 of `μ` asserted), where the linear law's strain of a
    /// quarter turn is `−1` on two axes: `W = 2(λ + μ)` per unit volume.
    #[test]
    fn a_rigid_rotation_costs_nothing() {
        let (lambda, mu) = (5.77e6, 3.85e6);
        for angle in [1e-3, 0.3, std::f64::consts::FRAC_PI_2, 3.0] {
            let r = nalgebra::Rotation3::from_axis_angle(
                &nalgebra::Unit::new_normalize(Vector3::new(1.0, 2.0, 3.0)),
                angle,
            );
            let f = *r.matrix();
            let w = Corotational.energy((lambda, mu), &f).unwrap();
            assert!(w.abs() <= 1e-12 * mu, "{angle}: W = {w}");
            let s = Corotational.stress((lambda, mu), &f).unwrap();
            assert!(s.amax() <= 1e-12 * mu, "{angle}: S = {s}");
        }
    }

    /// A uniaxial stretch `F = diag(1 + ε, 1, 1)` rotated by `R`: the Biot strain is
    /// `diag(ε, 0, 0)` exactly, so `W = (μ + λ/2) ε²` and `S₁₁ = (2μ + λ) ε / (1 + ε)`
    /// (`S = U⁻¹·(Biot stress)`), whatever the rotation (1e-12 relative).
    #[test]
    fn a_rotated_stretch_has_the_linear_energy_of_its_biot_strain() {
        let (lambda, mu) = (5.77e6, 3.85e6);
        let eps = 0.2;
        let r = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), 1.1);
        let f = r.matrix() * Matrix3::from_diagonal(&Vector3::new(1.0 + eps, 1.0, 1.0));
        let w = Corotational.energy((lambda, mu), &f).unwrap();
        let want = (mu + 0.5 * lambda) * eps * eps;
        assert!((w - want).abs() <= 1e-12 * want, "{w} vs {want}");
        let s = Corotational.stress((lambda, mu), &f).unwrap();
        let s11 = (2.0 * mu + lambda) * eps / (1.0 + eps);
        assert!((s[0] - s11).abs() <= 1e-12 * s11, "{} vs {s11}", s[0]);
        // the lateral stresses: λ ε from the trace, through U⁻¹ = I there
        assert!((s[1] - lambda * eps).abs() <= 1e-9 * s11, "{}", s[1]);
    }

    /// Equal stretches (a pure dilatation, where the eigenvectors are arbitrary): the
    /// tangent is the isotropic one of the closed form, `w = 2κ/(2u³)` for every pair.
    #[test]
    fn the_tangent_is_smooth_where_stretches_coincide() {
        let (lambda, mu) = (5.77e6, 3.85e6);
        let s = 1.1;
        let f = Matrix3::from_diagonal_element(s);
        let (_, d) = Corotational.stress_tangent((lambda, mu), &f).unwrap();
        let kappa = 2.0 * mu - lambda * (3.0 * s - 3.0);
        let wv = kappa / (s * s * s);
        let li = lambda / (s * s);
        for a in 0..6 {
            for b in 0..6 {
                let want = match (a < 3, b < 3) {
                    (true, true) if a == b => wv + li,
                    (true, true) => li,
                    _ if a == b => 0.5 * wv,
                    _ => 0.0,
                };
                assert!(
                    (d[(a, b)] - want).abs() <= 1e-9 * mu,
                    "{a}{b}: {}",
                    d[(a, b)]
                );
            }
        }
    }
}
