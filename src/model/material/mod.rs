//! Material laws at large strain and their registry (issue 36 §3).
//!
//! A hyperelastic law is a [`HyperelasticLaw`]: its strain energy `W(F)`, the second
//! Piola–Kirchhoff stress `S = ∂W/∂E` and the material tangent `ℂ = ∂S/∂E` (Voigt order
//! `(11, 22, 33, 23, 13, 12)`, engineering shear), as functions of the Lamé parameters of
//! the body's [`Material`](super::solid::Material). [`Hyperelastic`] pairs a law with its
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

mod neo_hookean;
mod svk;

pub use neo_hookean::NeoHookean;
pub use svk::Svk;

/// Every hyperelastic law a scene can name, by [`HyperelasticLaw::name`].
pub static LAWS: &[&dyn HyperelasticLaw] = &[&Svk, &NeoHookean];

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
    fn stress(&self, lame: (f64, f64), f: &Matrix3<f64>)
    -> Result<SMatrix<f64, 6, 1>, Inverted>;
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

/// The constitutive law of a [`Material`](super::solid::Material): the linear small-strain
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
    pub fn hyperelastic(self, mat: &super::solid::Material) -> Option<Hyperelastic> {
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
    pub fn new(law: &'static dyn HyperelasticLaw, mat: &super::solid::Material) -> Self {
        let (lambda, mu) = mat.lame();
        Hyperelastic { law, lambda, mu }
    }

    /// St. Venant–Kirchhoff with the Lamé parameters of `mat`.
    pub fn svk(mat: &super::solid::Material) -> Self {
        Self::new(&Svk, mat)
    }

    /// Neo-Hookean with the Lamé parameters of `mat`.
    pub fn neo_hookean(mat: &super::solid::Material) -> Self {
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
