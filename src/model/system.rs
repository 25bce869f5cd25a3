//! What the θ-method needs of a structure beyond its constant matrices: whether it is
//! linear, and its nonlinear parts with their tangents (issue 17 §1–3).
//!
//! A structure is `M(q) v̇ = F(t, q, v) + G λ` (eq. 1) with, here,
//! `M(q) = M + ΔM(q)` and `F(t, q, v) = f(t) − C v − K q − r(q, v)`: the constant mass,
//! damping, stiffness and loads of [`LinearSystem`], plus the sum of its
//! [`NonlinearPart`]s, each giving a force `r(q, v)` with its tangents `∂r/∂q`, `∂r/∂v`
//! and possibly a mass `ΔM(q)`. Two kinds exist:
//!
//! - a hyperelastic body ([`HyperelasticPart`]): `r(q) = f_int(u) − K₀ u`, its
//!   total-Lagrangian internal force minus its small-strain stiffness `K₀` (which stays
//!   in `K`, so Rayleigh damping `βK` and every linear formula keep their meaning), with
//!   tangent `∂r/∂q = K_t(u) − K₀`;
//! - a rigid multibody model in minimal coordinates
//!   ([`crate::model::multibody::SliderCrank`]): `ΔM(q)` from the kinematics, gyroscopic
//!   forces quadratic in `v` and gravity, with nonsymmetric tangents.
//!
//! The tangents of eq. 43 are then `Kⁿ = K + ∂r/∂q` and `Cⁿ = C + ∂r/∂v`; following the
//! paper's semi-Newton (sec. 4.3), the derivative of `M(q)` is not in the iteration matrix
//! (`M(q_θ)` is updated at each iterate as a fixed point).
//!
//! Without parts the structure is [`Linearity::Linear`]: `M̂` is constant and factored
//! once, and the schemes take their linear path, operation for operation as before
//! (`tests/golden/`). With forces only it is [`Linearity::ConstantMass`]; with a mass
//! part [`Linearity::Nonlinear`]: the Newton loop of eq. 42–51 re-evaluates `M`, `F`,
//! `Kⁿ`, `Cⁿ` at every iterate ([`crate::integrators::structure`]).

use std::sync::{Arc, Mutex};

use super::LinearSystem;
use super::hyperelastic::HyperBody;
use crate::error::Error;

/// How `F` and `M` depend on the state (module doc).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Linearity {
    /// `F = f(t) − Cv − Kq` with constant `M`, `C`, `K`: `M̂` factored once.
    Linear,
    /// Constant `M`, forces nonlinear in `q` (and `v`): the Newton loop refactors
    /// `M̂ⁿ = M + hθCⁿ + h²θ²Kⁿ`.
    ConstantMass,
    /// Configuration-dependent mass `M(q)` too: `M̂ⁿ = M(q_θⁿ) + hθCⁿ + h²θ²Kⁿ`.
    Nonlinear,
}

impl Linearity {
    /// The name used by `check` and summaries.
    pub fn name(self) -> &'static str {
        match self {
            Linearity::Linear => "linear",
            Linearity::ConstantMass => "nonlinear (constant mass)",
            Linearity::Nonlinear => "nonlinear (configuration-dependent mass)",
        }
    }
}

/// A nonlinear part of a structure (module doc): a force `r(q, v)` with its tangents and,
/// for multibody models, a mass `ΔM(q)`, evaluated into caller-owned buffers.
pub trait NonlinearPart: Send + Sync + std::fmt::Debug {
    /// The entries `(row, column)` of `∂r/∂q` in the structure's dofs, in the order
    /// [`NonlinearPart::evaluate`] fills them (set-up only: allocates).
    fn tangent_entries(&self) -> Vec<(usize, usize)>;
    /// The entries of `∂r/∂v` (none for a force independent of `v`).
    fn damping_entries(&self) -> Vec<(usize, usize)> {
        Vec::new()
    }
    /// The entries of `ΔM(q)`, symmetric (none for a constant mass).
    fn mass_entries(&self) -> Vec<(usize, usize)> {
        Vec::new()
    }
    /// True when `∂r/∂q` and `∂r/∂v` are symmetric (then so is `M̂ⁿ`).
    fn symmetric(&self) -> bool {
        true
    }
    /// Adds `r(q, v)` to `force` (one entry per structure dof) and, when given, overwrites
    /// `tangent` with `∂r/∂q` and `damping` with `∂r/∂v` (one value per entry of
    /// [`NonlinearPart::tangent_entries`], [`NonlinearPart::damping_entries`]).
    /// Reserves nothing. An inverted element is an error naming the body and the cell.
    fn evaluate(
        &self,
        q: &[f64],
        v: &[f64],
        force: &mut [f64],
        tangent: Option<&mut [f64]>,
        damping: Option<&mut [f64]>,
    ) -> Result<(), Error>;
    /// True when the part offers [`NonlinearPart::evaluate_discrete_gradient`].
    fn has_discrete_gradient(&self) -> bool {
        false
    }
    /// Adds the discrete gradient `r(q₀, q₁)` of the part's energy between the step's
    /// start `q₀` and end `q₁` to `force` (so that `r · (q₁ − q₀)` is the change of the
    /// energy, exactly), and overwrites `tangent` with `∂r/∂q` at the midpoint; for parts
    /// with [`NonlinearPart::has_discrete_gradient`] only.
    fn evaluate_discrete_gradient(
        &self,
        _q0: &[f64],
        _q1: &[f64],
        _force: &mut [f64],
        _tangent: Option<&mut [f64]>,
    ) -> Result<(), Error> {
        Err(Error::Numerical(format!(
            "{}: no discrete gradient",
            self.describe()
        )))
    }
    /// Overwrites `values` (one per [`NonlinearPart::mass_entries`] entry) with `ΔM(q)`.
    fn mass(&self, _q: &[f64], _values: &mut [f64]) {}
    /// `½ vᵀ ΔM(q) v` (J).
    fn kinetic_energy(&self, _q: &[f64], _v: &[f64]) -> f64 {
        0.0
    }
    /// The energy whose gradient is the conservative part of `r` (J): for a body, its
    /// strain energy minus `½uᵀK₀u`, so that with the linear system's `½qᵀKq` it sums to
    /// the strain energy; for a multibody model, the potential of gravity.
    fn energy(&self, q: &[f64]) -> Result<f64, Error>;
    /// One phrase for `check` and summaries.
    fn describe(&self) -> String;
}

/// A hyperelastic body's part of the structure: `r = f_int(u) − K₀u` on its dofs.
#[derive(Debug)]
pub struct HyperelasticPart {
    name: String,
    body: HyperBody,
    /// Structure dof of each body dof (`None`: fixed, `u = 0`).
    dof: Vec<Option<usize>>,
    /// `K₀ = K_t(0)` on the body's pattern.
    k0: Vec<f64>,
    /// Column of each pattern entry (the pattern's compressed columns, expanded).
    col: Vec<usize>,
    row: Vec<usize>,
    /// Pattern entries whose row and column are both free: what the tangent reports.
    kept: Vec<usize>,
    /// Cells of the body's mesh, for the element named in errors: its file tags.
    cell_tags: Vec<u64>,
    scratch: Mutex<Scratch>,
}

#[derive(Debug)]
struct Scratch {
    u: Vec<f64>,
    /// The step's start displacement (discrete gradient).
    u0: Vec<f64>,
    force: Vec<f64>,
    tangent: Vec<f64>,
    batch: crate::assembly::ElementBatch,
}

impl HyperelasticPart {
    /// The body named `name` with its structure dof map `dof` (three per node; `None`
    /// where fixed) and the file tag of each cell (`cell_tags`, for errors).
    pub fn new(
        name: &str,
        body: HyperBody,
        dof: Vec<Option<usize>>,
        cell_tags: Vec<u64>,
    ) -> Result<Self, Error> {
        let plan = body.plan();
        let (n, nnz) = (plan.order(), plan.nnz());
        assert_eq!(dof.len(), n, "one structure dof per body dof");
        let mut k0 = vec![0.0; nnz];
        let mut f0 = vec![0.0; n];
        body.evaluate(&vec![0.0; n], &mut k0, &mut f0)
            .map_err(|c| inverted(name, &cell_tags, c))?;
        let pattern = plan.matrix(&k0);
        let p = pattern.as_ref();
        let mut col = Vec::with_capacity(nnz);
        for j in 0..n {
            col.extend(std::iter::repeat_n(j, p.col_ptr()[j + 1] - p.col_ptr()[j]));
        }
        let row = p.row_idx().to_vec();
        let kept = (0..nnz)
            .filter(|&k| dof[row[k]].is_some() && dof[col[k]].is_some())
            .collect();
        let batch = body.batch();
        Ok(HyperelasticPart {
            name: name.to_string(),
            body,
            dof,
            k0,
            col,
            row,
            kept,
            cell_tags,
            scratch: Mutex::new(Scratch {
                u: vec![0.0; n],
                u0: vec![0.0; n],
                force: vec![0.0; n],
                tangent: vec![0.0; nnz],
                batch,
            }),
        })
    }

    /// The body's displacement from the structure's `q` (0 on fixed dofs).
    fn gather(&self, q: &[f64], u: &mut [f64]) {
        for (ui, d) in u.iter_mut().zip(&self.dof) {
            *ui = d.map_or(0.0, |d| q[d]);
        }
    }

    /// `r(q)` (no `q0`) or the discrete gradient `r(q0, q)` added to `force`, and the
    /// tangent (at `q`, or at the midpoint) into `tangent` ([`NonlinearPart::evaluate`],
    /// [`NonlinearPart::evaluate_discrete_gradient`]).
    fn evaluate_from(
        &self,
        q0: Option<&[f64]>,
        q: &[f64],
        force: &mut [f64],
        tangent: Option<&mut [f64]>,
    ) -> Result<(), Error> {
        let mut guard = self.scratch.lock().unwrap_or_else(|p| p.into_inner());
        let s = &mut *guard;
        if let Some(q0) = q0 {
            self.gather(q0, &mut s.u0);
        }
        self.gather(q, &mut s.u);
        let want = tangent.is_some().then_some(&mut s.tangent[..]);
        let u0 = q0.is_some().then_some(&s.u0[..]);
        self.body
            .evaluate_batched((u0, &s.u), want, &mut s.force, &mut s.batch)
            .map_err(|c| inverted(&self.name, &self.cell_tags, c))?;
        if q0.is_some() {
            // − K₀ u_m: the linear part K₀ stays in K, which the structure applies at
            // the midpoint (its quadratic energy is conserved there)
            for (a, b) in s.u.iter_mut().zip(&s.u0) {
                *a = 0.5 * (*a + b);
            }
        }
        self.k0_mul_add(-1.0, &s.u, &mut s.force);
        for (f, d) in s.force.iter().zip(&self.dof) {
            if let Some(d) = d {
                force[*d] += f;
            }
        }
        if let Some(t) = tangent {
            for (out, &k) in t.iter_mut().zip(&self.kept) {
                *out = s.tangent[k] - self.k0[k];
            }
        }
        Ok(())
    }

    /// `K₀ u` added to `out` with factor `s` (body dofs).
    fn k0_mul_add(&self, s: f64, u: &[f64], out: &mut [f64]) {
        for ((&k, &i), &j) in self.k0.iter().zip(&self.row).zip(&self.col) {
            out[i] += s * k * u[j];
        }
    }
}

/// The error of an inverted cell of body `name`, naming its file tag.
fn inverted(name: &str, tags: &[u64], c: super::hyperelastic::InvertedCell) -> Error {
    let cell = match tags.get(c.cell) {
        Some(tag) => format!("cell {tag} (file tag)"),
        None => format!("cell {} (index in the generated mesh)", c.cell),
    };
    Error::Numerical(format!(
        "body \"{name}\": {cell} is inverted: det F = {:.6e}, expected > 0 \
         (the step is too large for the deformation, or the body is crushed)",
        c.det
    ))
}

impl NonlinearPart for HyperelasticPart {
    fn tangent_entries(&self) -> Vec<(usize, usize)> {
        self.kept
            .iter()
            .map(|&k| {
                (
                    self.dof[self.row[k]].expect("kept row"),
                    self.dof[self.col[k]].expect("kept column"),
                )
            })
            .collect()
    }

    fn evaluate(
        &self,
        q: &[f64],
        _v: &[f64],
        force: &mut [f64],
        tangent: Option<&mut [f64]>,
        _damping: Option<&mut [f64]>,
    ) -> Result<(), Error> {
        self.evaluate_from(None, q, force, tangent)
    }

    fn has_discrete_gradient(&self) -> bool {
        true
    }

    fn evaluate_discrete_gradient(
        &self,
        q0: &[f64],
        q1: &[f64],
        force: &mut [f64],
        tangent: Option<&mut [f64]>,
    ) -> Result<(), Error> {
        self.evaluate_from(Some(q0), q1, force, tangent)
    }

    fn energy(&self, q: &[f64]) -> Result<f64, Error> {
        let mut guard = self.scratch.lock().unwrap_or_else(|p| p.into_inner());
        let s = &mut *guard;
        self.gather(q, &mut s.u);
        let w = self
            .body
            .strain_energy(&s.u)
            .map_err(|c| inverted(&self.name, &self.cell_tags, c))?;
        s.force.fill(0.0);
        self.k0_mul_add(1.0, &s.u, &mut s.force);
        let quad: f64 = s.u.iter().zip(&s.force).map(|(a, b)| a * b).sum();
        Ok(w - 0.5 * quad)
    }

    fn describe(&self) -> String {
        format!(
            "body \"{}\": {} total-Lagrangian, {} dofs",
            self.name,
            self.body.law_name(),
            self.dof.iter().filter(|d| d.is_some()).count()
        )
    }
}

impl LinearSystem {
    /// Linear, nonlinear with a constant mass, or with `M(q)` (module doc).
    pub fn linearity(&self) -> Linearity {
        if self.nonlinear.is_empty() {
            Linearity::Linear
        } else if self.nonlinear.iter().all(|p| p.mass_entries().is_empty()) {
            Linearity::ConstantMass
        } else {
            Linearity::Nonlinear
        }
    }

    /// True when the iteration matrix `M̂ⁿ` is symmetric (every part's tangents are).
    pub fn symmetric(&self) -> bool {
        self.nonlinear.iter().all(|p| p.symmetric())
    }

    /// Adds a nonlinear part (module doc).
    pub fn add_nonlinear_part(&mut self, f: Arc<dyn NonlinearPart>) {
        self.nonlinear.push(f);
    }
}
