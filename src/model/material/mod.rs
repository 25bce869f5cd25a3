//! The body's [`Material`] (its small-strain constants `E`, `ν`, `ρ` and the law that
//! holds at large strain, [`MaterialModel`]), the material laws at large strain and their
//! registry (issue 36 §3). The 2-D elasticity matrices, which need the kinematic
//! formulation, are with it in `model::solid`.
//!
//! A hyperelastic law is a [`HyperelasticLaw`]: its strain energy `W(F)`, the second
//! Piola–Kirchhoff stress `S = ∂W/∂E` and the material tangent `ℂ = ∂S/∂E` (Voigt order
//! `(11, 22, 33, 23, 13, 12)`, engineering shear), as functions of the Lamé parameters of
//! the body's [`Material`]. [`Hyperelastic`] pairs a law with its
//! parameters; the element kernels ([`crate::model::hyperelastic`]), the energy balance and
//! the frames' Green–Lagrange strain and Cauchy stress ([`green_lagrange_and_cauchy`]) call
//! it and never name a law.
//!
//! [`LAWS`] is the registry: the scene key `material.model` takes `"linear"` (the small-strain
//! material, the structure stays linear) or the [`HyperelasticLaw::name`] of an entry. To add
//! a law: one file here with a unit struct implementing [`HyperelasticLaw`], and its line in
//! [`LAWS`]; scenes, validation, the kernels, energies and frames take it from there. Each
//! law must reduce to isotropic linear elasticity of the same `λ`, `μ` at small strain
//! (the tangent tests of `model::hyperelastic` check every registered law against finite
//! differences).

use nalgebra::{Matrix3, SMatrix};

use crate::error::{Error, require_in, require_positive};

mod corotational;
mod neo_hookean;
mod svk;

pub use corotational::Corotational;
pub use neo_hookean::NeoHookean;
pub use svk::Svk;

/// An isotropic elastic material: its small-strain constants and the law that holds at
/// large strain.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Young's modulus `E` (Pa).
    pub young: f64,
    /// Poisson's ratio `ν`, in [0, 0.5).
    pub poisson: f64,
    /// Density `ρ` (kg/m³).
    pub density: f64,
    /// The constitutive law (default `linear`).
    #[serde(default)]
    pub model: MaterialModel,
}

impl Material {
    /// Checks the ranges; the error names the field.
    pub fn validate(&self) -> Result<(), Error> {
        require_positive("young", self.young)?;
        require_positive("density", self.density)?;
        require_in("poisson", self.poisson, 0.0, 0.4999999)?;
        Ok(())
    }

    /// Lamé parameters `(λ, μ)`.
    pub fn lame(&self) -> (f64, f64) {
        let (e, nu) = (self.young, self.poisson);
        (
            e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
            e / (2.0 * (1.0 + nu)),
        )
    }

    /// 3-D elasticity matrix (Voigt, engineering shear).
    pub fn d3(&self) -> SMatrix<f64, 6, 6> {
        let (l, m) = self.lame();
        let mut d = SMatrix::<f64, 6, 6>::zeros();
        for i in 0..3 {
            for j in 0..3 {
                d[(i, j)] = l;
            }
            d[(i, i)] = l + 2.0 * m;
            d[(i + 3, i + 3)] = m;
        }
        d
    }
}

/// Every hyperelastic law a scene can name, by [`HyperelasticLaw::name`].
pub static LAWS: &[&dyn HyperelasticLaw] = &[&Svk, &NeoHookean, &Corotational];

/// Stress and tangent at one point: `S` (Voigt) and `ℂ` (6 × 6).
pub type StressTangent = (SMatrix<f64, 6, 1>, SMatrix<f64, 6, 6>);

/// A deformation the law cannot take: `det F ≤ 0` (an inverted element) or not finite.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Inverted {
    /// `det F` met (or of the reference Jacobian, for a cell inverted in its mesh).
    pub det: f64,
}

/// A hyperelastic law: `W`, `S` and `ℂ` at a deformation gradient `F` (or `S` at a right
/// Cauchy–Green tensor `C`), for Lamé parameters `(λ, μ)` in Pa. Every method refuses a
/// deformation the law cannot take with [`Inverted`] (at least `det F ≤ 0`).
pub trait HyperelasticLaw: Sync + std::fmt::Debug {
    /// The name scene files use (`material.model`), unique in [`LAWS`].
    fn name(&self) -> &'static str;
    /// The law's name in prose, for reports.
    fn title(&self) -> &'static str;
    /// Strain energy density `W` (J/m³) at `F`.
    fn energy(&self, lame: (f64, f64), f: &Matrix3<f64>) -> Result<f64, Inverted>;
    /// `S` (Voigt) at `F`.
    fn stress(&self, lame: (f64, f64), f: &Matrix3<f64>) -> Result<SMatrix<f64, 6, 1>, Inverted>;
    /// `S` (as a matrix) at a positive definite `C`: the midpoint stress of
    /// Gonzalez's discrete gradient ([`Hyperelastic::discrete_gradient`]).
    fn stress_of_c(&self, lame: (f64, f64), c: &Matrix3<f64>) -> Result<Matrix3<f64>, Inverted>;
    /// `S` and `ℂ` at `F`.
    fn stress_tangent(&self, lame: (f64, f64), f: &Matrix3<f64>)
    -> Result<StressTangent, Inverted>;
}

/// The registered law named `name`.
pub fn law_named(name: &str) -> Option<&'static dyn HyperelasticLaw> {
    LAWS.iter().copied().find(|l| l.name() == name)
}

/// The names `material.model` accepts: `linear`, then every law of [`LAWS`].
pub fn model_names() -> Vec<&'static str> {
    std::iter::once("linear")
        .chain(LAWS.iter().map(|l| l.name()))
        .collect()
}

/// The constitutive law of a [`Material`]: the linear small-strain
/// material (the default; the structure stays linear and `M̂` is factored once) or a
/// registered hyperelastic law ([`LAWS`]), total-Lagrangian. Every law has the same
/// small-strain limit, the isotropic linear elasticity of `young` and `poisson`. In scene
/// files, the law's name (`"linear"`, `"svk"`, `"neo-hookean"`).
#[derive(Clone, Copy, Default)]
pub struct MaterialModel(Option<&'static dyn HyperelasticLaw>);

impl MaterialModel {
    /// Linear elasticity, small strain.
    pub const LINEAR: MaterialModel = MaterialModel(None);

    /// The model named `name` (`"linear"` or a registered law).
    pub fn named(name: &str) -> Option<MaterialModel> {
        if name == "linear" {
            return Some(Self::LINEAR);
        }
        law_named(name).map(|l| MaterialModel(Some(l)))
    }

    /// The name used in scene files.
    pub fn name(self) -> &'static str {
        self.0.map_or("linear", |l| l.name())
    }

    /// Whether this is the linear small-strain material.
    pub fn is_linear(self) -> bool {
        self.0.is_none()
    }

    /// The hyperelastic law with the Lamé parameters of `mat`, `None` for the linear
    /// material.
    pub fn hyperelastic(self, mat: &Material) -> Option<Hyperelastic> {
        self.0.map(|law| Hyperelastic::new(law, mat))
    }
}

impl PartialEq for MaterialModel {
    fn eq(&self, other: &Self) -> bool {
        self.name() == other.name()
    }
}

impl Eq for MaterialModel {}

impl std::fmt::Debug for MaterialModel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "MaterialModel({:?})", self.name())
    }
}

impl serde::Serialize for MaterialModel {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl<'de> serde::Deserialize<'de> for MaterialModel {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        MaterialModel::named(&name).ok_or_else(|| {
            let expected: Vec<String> = model_names().iter().map(|n| format!("`{n}`")).collect();
            serde::de::Error::custom(format!(
                "unknown variant `{name}`, expected one of {}",
                expected.join(", ")
            ))
        })
    }
}

/// A hyperelastic law with its Lamé parameters `λ`, `μ` (Pa).
#[derive(Clone, Copy, Debug)]
pub struct Hyperelastic {
    law: &'static dyn HyperelasticLaw,
    /// `λ` (Pa).
    pub lambda: f64,
    /// `μ` (Pa).
    pub mu: f64,
}

impl PartialEq for Hyperelastic {
    fn eq(&self, other: &Self) -> bool {
        self.law.name() == other.law.name() && self.lambda == other.lambda && self.mu == other.mu
    }
}

impl Hyperelastic {
    /// `law` with the Lamé parameters of `mat`.
    pub fn new(law: &'static dyn HyperelasticLaw, mat: &Material) -> Self {
        let (lambda, mu) = mat.lame();
        Hyperelastic { law, lambda, mu }
    }

    /// St. Venant–Kirchhoff with the Lamé parameters of `mat`.
    pub fn svk(mat: &Material) -> Self {
        Self::new(&Svk, mat)
    }

    /// Neo-Hookean with the Lamé parameters of `mat`.
    pub fn neo_hookean(mat: &Material) -> Self {
        Self::new(&NeoHookean, mat)
    }

    /// The law.
    pub fn law(&self) -> &'static dyn HyperelasticLaw {
        self.law
    }

    /// Strain energy density `W` (J/m³) at `F`.
    pub fn energy(&self, f: &Matrix3<f64>) -> Result<f64, Inverted> {
        self.law.energy((self.lambda, self.mu), f)
    }

    /// `S` (Voigt) at `F`, without the tangent.
    pub fn stress(&self, f: &Matrix3<f64>) -> Result<SMatrix<f64, 6, 1>, Inverted> {
        self.law.stress((self.lambda, self.mu), f)
    }

    /// `S` and `ℂ` at `F` (module doc of [`crate::model::hyperelastic`]).
    pub fn stress_tangent(&self, f: &Matrix3<f64>) -> Result<StressTangent, Inverted> {
        self.law.stress_tangent((self.lambda, self.mu), f)
    }

    /// Gonzalez's discrete gradient of `W` between `F₀` and `F₁` (Voigt): the stress
    /// `S_alg = S(C_m) + α ΔC`, `C_m = (C₀ + C₁)/2`, `ΔC = C₁ − C₀`, with `α` such that
    /// `½ S_alg : ΔC = W(F₁) − W(F₀)` exactly (`α = 0` when `ΔC` vanishes). With the
    /// force `∫ Bᵀ(F_m) S_alg` at `F_m = (F₀ + F₁)/2`, the work of the internal force over
    /// a step is the change of strain energy, and the force, a stress divergence with a
    /// symmetric `S_alg`, keeps linear and angular momentum (Gonzalez, CMAME 190, 2000).
    pub fn discrete_gradient(
        &self,
        f0: &Matrix3<f64>,
        f1: &Matrix3<f64>,
    ) -> Result<SMatrix<f64, 6, 1>, Inverted> {
        let (w0, w1) = (self.energy(f0)?, self.energy(f1)?);
        let (c0, c1) = (f0.transpose() * f0, f1.transpose() * f1);
        let dc = c1 - c0;
        let sm = self
            .law
            .stress_of_c((self.lambda, self.mu), &(0.5 * (c0 + c1)))?;
        let dd = dc.component_mul(&dc).sum();
        let scale = c0.component_mul(&c0).sum();
        let alpha = if dd > 1e-28 * scale {
            (2.0 * (w1 - w0) - sm.component_mul(&dc).sum()) / dd
        } else {
            0.0
        };
        Ok(voigt(&(sm + alpha * dc)))
    }
}

/// Green–Lagrange strain `E = (FᵀF − I)/2` and Cauchy stress `σ = F S Fᵀ / J` for the
/// displacement gradient `grad` (`F = I + grad`), both in ParaView's order
/// `XX, YY, ZZ, XY, YZ, XZ` (tensor components); `None` where `det F ≤ 0`.
pub fn green_lagrange_and_cauchy(
    law: &Hyperelastic,
    grad: &Matrix3<f64>,
) -> Option<([f64; 6], [f64; 6])> {
    let f = Matrix3::identity() + grad;
    let s = law.stress(&f).ok()?;
    let j = f.determinant();
    let e = 0.5 * (f.transpose() * f - Matrix3::identity());
    let sm = Matrix3::new(s[0], s[5], s[4], s[5], s[1], s[3], s[4], s[3], s[2]);
    let sigma = f * sm * f.transpose() / j;
    let order = |m: &Matrix3<f64>| {
        [
            m[(0, 0)],
            m[(1, 1)],
            m[(2, 2)],
            m[(0, 1)],
            m[(1, 2)],
            m[(0, 2)],
        ]
    };
    Some((order(&e), order(&sigma)))
}

/// Voigt index pairs `(11, 22, 33, 23, 13, 12)`.
pub(crate) const VOIGT: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1)];

pub(super) fn voigt(m: &Matrix3<f64>) -> SMatrix<f64, 6, 1> {
    SMatrix::<f64, 6, 1>::from_fn(|a, _| m[VOIGT[a]])
}

pub(super) fn positive_det(f: &Matrix3<f64>) -> Result<f64, Inverted> {
    let j = f.determinant();
    if j.is_finite() && j > 0.0 {
        Ok(j)
    } else {
        Err(Inverted { det: j })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The registry: names unique and not `linear`; every name round-trips through the
    /// scene key (serde), and an unknown name is refused with the list of names.
    #[test]
    fn registry_names_round_trip_and_unknown_names_are_listed() {
        let names = model_names();
        assert_eq!(names, ["linear", "svk", "neo-hookean", "corotational"]);
        for (i, a) in names.iter().enumerate() {
            assert!(!names[i + 1..].contains(a), "{a} registered twice");
            let m = MaterialModel::named(a).unwrap();
            assert_eq!(m.name(), *a);
            assert_eq!(m.is_linear(), *a == "linear");
            let v: MaterialModel = toml::Value::String(a.to_string()).try_into().unwrap();
            assert_eq!(v, m);
        }
        let e = toml::Value::String("mooney".into())
            .try_into::<MaterialModel>()
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("unknown variant `mooney`") && e.contains("`neo-hookean`"),
            "{e}"
        );
    }

    /// Each law at small strain is the linear isotropic law of the same `λ`, `μ`: the
    /// tangent at `F = I` is Hooke's matrix to round-off.
    #[test]
    fn every_law_reduces_to_hooke_at_small_strain() {
        let (lambda, mu) = (5.77e6, 3.85e6);
        for law in LAWS {
            let (_, d) = law
                .stress_tangent((lambda, mu), &Matrix3::identity())
                .unwrap();
            for a in 0..6 {
                for b in 0..6 {
                    let hooke = match (a < 3, b < 3) {
                        (true, true) if a == b => lambda + 2.0 * mu,
                        (true, true) => lambda,
                        _ if a == b => mu,
                        _ => 0.0,
                    };
                    assert!((d[(a, b)] - hooke).abs() <= 1e-9 * mu, "{}", law.name());
                }
            }
        }
    }
}
