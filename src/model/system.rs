//! What the θ-method needs of a structure beyond its constant matrices: whether it is
//! linear, and the nonlinear internal forces of its large-deformation bodies with their
//! tangents (issue 17 §1–2).
//!
//! A structure is `M v̇ = F(t, q, v) + G λ` (eq. 1) with, here,
//! `F(t, q, v) = f(t) − C v − K q − r(q)`: the constant mass, damping, stiffness and loads
//! of [`LinearSystem`], plus the sum `r(q)` of [`InternalForce`]s. A hyperelastic body
//! contributes `r(q) = f_int(u) − K₀ u` ([`HyperelasticPart`]): its total-Lagrangian
//! internal force minus its small-strain stiffness `K₀` (which stays in `K`, so Rayleigh
//! damping `βK` and every linear formula keep their meaning), with tangent
//! `∂r/∂q = K_t(u) − K₀`. The tangent stiffness of eq. 43 is then `Kⁿ = K + ∂r/∂q`.
//!
//! Without internal forces the structure is [`Linearity::Linear`]: `M̂` is constant and
//! factored once, and the schemes take their linear path, operation for operation as
//! before (`tests/golden/`). With them it is [`Linearity::ConstantMass`]: the Newton loop
//! of eq. 42–51 re-evaluates `F` and `Kⁿ` at every iterate
//! ([`crate::integrators::structure`]). A configuration-dependent mass `M(q)` (rigid
//! multibody in minimal coordinates) is not covered yet.

use std::sync::{Arc, Mutex};

use super::LinearSystem;
use super::hyperelastic::HyperBody;
use crate::error::Error;

/// How `F` and `M` depend on the state (module doc).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Linearity {
    /// `F = f(t) − Cv − Kq` with constant `M`, `C`, `K`: `M̂` factored once.
    Linear,
    /// Constant `M` and `C`, internal forces nonlinear in `q`: the Newton loop refactors
    /// `M̂ⁿ = M + hθC + h²θ²Kⁿ`.
    ConstantMass,
}

impl Linearity {
    /// The name used by `check` and summaries.
    pub fn name(self) -> &'static str {
        match self {
            Linearity::Linear => "linear",
            Linearity::ConstantMass => "nonlinear (constant mass)",
        }
    }
}

/// A nonlinear internal force `r(q)` of a structure (module doc), evaluated into
/// caller-owned buffers.
pub trait InternalForce: Send + Sync + std::fmt::Debug {
    /// The entries `(row, column)` of its tangent `∂r/∂q` in the structure's dofs, in the
    /// order [`InternalForce::evaluate`] fills them (set-up only: allocates).
    fn tangent_entries(&self) -> Vec<(usize, usize)>;
    /// Adds `r(q)` to `force` (one entry per structure dof) and, when given, overwrites
    /// `tangent` (one value per [`InternalForce::tangent_entries`] entry) with `∂r/∂q`.
    /// Reserves nothing. An inverted element is an error naming the body and the cell.
    fn evaluate(
        &self,
        q: &[f64],
        force: &mut [f64],
        tangent: Option<&mut [f64]>,
    ) -> Result<(), Error>;
    /// The energy whose gradient is `r` (J): the body's strain energy minus `½uᵀK₀u`, so
    /// that with the linear system's `½qᵀKq` it sums to the strain energy.
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

impl InternalForce for HyperelasticPart {
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
        force: &mut [f64],
        tangent: Option<&mut [f64]>,
    ) -> Result<(), Error> {
        let mut guard = self.scratch.lock().unwrap_or_else(|p| p.into_inner());
        let s = &mut *guard;
        self.gather(q, &mut s.u);
        let want = tangent.is_some().then_some(&mut s.tangent[..]);
        self.body
            .evaluate_batched(&s.u, want, &mut s.force, &mut s.batch)
            .map_err(|c| inverted(&self.name, &self.cell_tags, c))?;
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
    /// Linear, or nonlinear with a constant mass (module doc).
    pub fn linearity(&self) -> Linearity {
        if self.nonlinear.is_empty() {
            Linearity::Linear
        } else {
            Linearity::ConstantMass
        }
    }

    /// Adds a nonlinear internal force (module doc).
    pub fn add_internal_force(&mut self, f: Arc<dyn InternalForce>) {
        self.nonlinear.push(f);
    }
}
