//! Mechanical models: what the integrators step.
//!
//! A model is a [`LinearSystem`] (eq. 1c with `F(t, q, v) = f(t) − C v − K q`: constant
//! sparse mass `M`, stiffness `K`, optional Rayleigh damping `C`, external force `f`)
//! plus a set of contacts (see [`crate::contact`]) and initial conditions.
//! Nonlinear constraints (curved obstacles, rigid rotations) are supported through
//! the contact set; nonlinear internal forces and masses (large-deformation bodies,
//! rigid mechanisms) through the system's [`system::NonlinearPart`]s, which the
//! integrators reach through [`crate::integrators::structure`].
//!
//! Submodules build systems: [`rod`] (P1 rod elements, eq. 71), [`solid`] (linear
//! solids), [`hyperelastic`] and [`material`] (large-deformation bodies and their laws),
//! [`multibody`] and [`point_mass`]; `combine` joins bodies and eliminates fixed and
//! prescribed dofs, `measures` gives a state's energies and momentum (and a body's
//! centre of mass and rigid-motion velocity, for initial states), [`body_measures`]
//! each body's mass, centre, linear and angular momentum, [`energy`] keeps a run's
//! energy balance, and [`pressure`] gives the consistent nodal forces of a uniform
//! pressure on boundary faces.

pub mod element;
pub mod energy;
pub mod generate;
pub mod geometry;
pub mod hyperelastic;
pub mod material;
pub mod multibody;
pub mod ordering;
pub mod point_mass;
pub mod pressure;
pub mod rod;
pub mod solid;
pub mod system;

pub mod body_measures;
mod combine;
mod measures;
pub use body_measures::{BodyMeasures, BodyState};
pub use measures::{centre_of_mass, rigid_velocity};

use crate::linalg::{QuadraticForm, SparseMatrix, quadratic_form};

/// How the element mass matrices are formed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum MassKind {
    /// Consistent mass, `∫ ρ Nᵀ N` (eq. 71 for the rod).
    Consistent,
    /// Row-sum lumped mass (diagonal).
    Lumped,
    /// No mass on the contact nodes (Khenous–Laborde–Renard's idea, as GetFEM offers
    /// it): in each element touching a contact node, the contact nodes' rows and
    /// columns are removed from the consistent mass and their row sums are added
    /// equally to the diagonal of the element's other nodes, so element masses (and the
    /// total mass) are kept. Removes the impact of the contact node's own inertia.
    Redistributed,
}

impl MassKind {
    /// Parses `consistent` or `lumped`.
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "consistent" => Some(MassKind::Consistent),
            "lumped" => Some(MassKind::Lumped),
            "redistributed" => Some(MassKind::Redistributed),
            _ => None,
        }
    }
    /// The name used on the command line and in summaries.
    pub fn name(self) -> &'static str {
        match self {
            MassKind::Consistent => "consistent",
            MassKind::Lumped => "lumped",
            MassKind::Redistributed => "redistributed",
        }
    }
}

/// The layouts of a system's `M` and `K` read once ([`LinearSystem::energy_forms`]), so
/// that the energies of every history row take the fast path of their pattern
/// ([`QuadraticForm`]).
#[derive(Clone, Debug)]
pub struct EnergyForms {
    mass: QuadraticForm,
    stiffness: QuadraticForm,
    /// No constant external force: `fᵀ q` is skipped.
    unloaded: bool,
}

impl EnergyForms {
    /// `xᵀ M x` of `sys` (the system these forms were read from) on the fast path of its
    /// pattern. Does not allocate.
    pub fn mass_form(&self, sys: &LinearSystem, x: &[f64]) -> f64 {
        self.mass.eval(sys.mass.as_ref(), x)
    }

    /// Whether `M` and `K` both take the general column walk (no rod's three diagonals).
    pub fn general(&self) -> bool {
        matches!(self.mass, QuadraticForm::General)
            && matches!(self.stiffness, QuadraticForm::General)
    }
}

/// A linear structural model `M v̇ + C v + K q = f + G λ` (eq. 1c).
#[derive(Clone, Debug)]
pub struct LinearSystem {
    /// Mass matrix `M` (symmetric positive definite).
    pub mass: SparseMatrix,
    /// Stiffness matrix `K` (symmetric positive semidefinite).
    pub stiffness: SparseMatrix,
    /// Damping matrix `C` (Rayleigh or none).
    pub damping: Option<SparseMatrix>,
    /// Constant external force `f` (N); zero for the free bar.
    pub force: Vec<f64>,
    /// Displacement components per node (1 for rods, 2 or 3 for solids).
    pub dofs_per_node: usize,
    /// The displacement component (0 = x, 1 = y, 2 = z) of each dof.
    pub component: Vec<u8>,
    /// A fill-reducing dof order (position → dof) for the Cholesky of `M̂`, from the
    /// mesh ([`ordering::candidate`]); the factorization keeps it only where it
    /// fills less than AMD. `None`: AMD alone.
    pub ordering: Option<crate::linalg::DofOrdering>,
    /// Time-dependent nodal loads `φ_i(t) b_i`, added to `force` at `t_{k+θ}` by the
    /// schemes (the scene's `[[forces]]`).
    pub loads: Vec<NodalLoad>,
    /// Dofs eliminated with a prescribed velocity (the scene's `[[prescribed]]`): their
    /// coupling to the kept dofs.
    pub prescribed: Option<Prescribed>,
    /// Nonlinear internal forces `r(q)` (large-deformation bodies), added to `F` as
    /// `−r(q)` ([`system`]); empty for a linear system. Attached to the final
    /// (restricted) system: [`LinearSystem::block_diagonal`] and
    /// [`LinearSystem::restrict`] take systems without them.
    pub nonlinear: Vec<std::sync::Arc<dyn system::NonlinearPart>>,
}

/// Dofs moved with a prescribed velocity `v_p(t) = w_p φ_p(t)` (displacement
/// `u_p(t) = w_p ∫₀ᵗ φ_p`), eliminated from the system. The kept dofs feel them through
/// the coupling blocks: the θ-method of eq. 18 on the full system, split by rows, adds
/// `−M_fp (v_p(t_{k+1}) − v_p(t_k)) − h C_fp v_p(t_{k+θ}) − h K_fp u_p(t_{k+θ})` to the
/// free-velocity right-hand side of the kept dofs.
#[derive(Clone, Debug)]
pub struct Prescribed {
    /// `M_fp` (kept × prescribed).
    pub mass: SparseMatrix,
    /// `K_fp`.
    pub stiffness: SparseMatrix,
    /// `C_fp` (with damping).
    pub damping: Option<SparseMatrix>,
    /// `w_p` per prescribed dof (m/s).
    pub velocity: Vec<f64>,
    /// Index into `functions` per prescribed dof.
    pub function: Vec<usize>,
    /// The time functions `φ`.
    pub functions: Vec<TimeFunction>,
    /// The old (unreduced) dof of each prescribed dof.
    pub dofs: Vec<usize>,
    /// `M_pp` (prescribed × prescribed), for the energy of the prescribed dofs.
    pub mass_pp: SparseMatrix,
    /// `K_pp`.
    pub stiffness_pp: SparseMatrix,
    /// The constant force on the prescribed dofs (gravity), `f_p`.
    pub force: Vec<f64>,
}

impl Prescribed {
    /// What the prescribed dofs add to the energy of the kept dofs at `(t, q, v)`:
    /// `(vᵀ M_fp v_p + ½ v_pᵀ M_pp v_p, qᵀ K_fp u_p + ½ u_pᵀ K_pp u_p − f_pᵀ u_p)`, so that
    /// the sums are the whole structure's kinetic and potential energy. `vp` and `up`
    /// are scratch of one entry per prescribed dof.
    pub fn energy(
        &self,
        t: f64,
        q: &[f64],
        v: &[f64],
        vp: &mut [f64],
        up: &mut [f64],
    ) -> (f64, f64) {
        self.velocity_at(t, vp);
        self.displacement_at(t, up);
        let cross = |m: &SparseMatrix, x: &[f64], y: &[f64]| -> f64 {
            let m = m.as_ref();
            let mut s = 0.0;
            for (j, &yj) in y.iter().enumerate() {
                if yj != 0.0 {
                    for k in m.col_ptr()[j]..m.col_ptr()[j + 1] {
                        s += x[m.row_idx()[k]] * m.val()[k] * yj;
                    }
                }
            }
            s
        };
        let kinetic = cross(&self.mass, v, vp) + 0.5 * quadratic_form(self.mass_pp.as_ref(), vp);
        let potential = cross(&self.stiffness, q, up)
            + 0.5 * quadratic_form(self.stiffness_pp.as_ref(), up)
            - self
                .force
                .iter()
                .zip(up.iter())
                .map(|(f, u)| f * u)
                .sum::<f64>();
        (kinetic, potential)
    }

    /// `v_p(t)` into `out`.
    pub fn velocity_at(&self, t: f64, out: &mut [f64]) {
        for ((o, &w), &f) in out.iter_mut().zip(&self.velocity).zip(&self.function) {
            *o = w * self.functions[f].eval(t);
        }
    }
    /// `u_p(t)` into `out`.
    pub fn displacement_at(&self, t: f64, out: &mut [f64]) {
        for ((o, &w), &f) in out.iter_mut().zip(&self.velocity).zip(&self.function) {
            *o = w * self.functions[f].integral(t);
        }
    }
}

/// A piecewise-linear function of time through `(t, value)` points (increasing `t`),
/// constant before the first point and after the last.
#[derive(Clone, Debug, PartialEq)]
pub struct TimeFunction {
    points: Vec<(f64, f64)>,
}

impl TimeFunction {
    /// Checks the points (at least one, finite, strictly increasing times); `field`
    /// names them in errors.
    pub fn new(field: &str, points: Vec<(f64, f64)>) -> Result<Self, crate::error::Error> {
        if points.is_empty() {
            return Err(crate::error::Error::invalid(
                field,
                "[]",
                "needs at least one [time, value] point",
            ));
        }
        for (i, &(t, v)) in points.iter().enumerate() {
            if !(t.is_finite() && v.is_finite()) {
                return Err(crate::error::Error::invalid(
                    &format!("{field}[{i}]"),
                    format!("[{t}, {v}]"),
                    "must be finite",
                ));
            }
            if i > 0 && t <= points[i - 1].0 {
                return Err(crate::error::Error::invalid(
                    &format!("{field}[{i}]"),
                    t,
                    &format!("times must increase (previous {})", points[i - 1].0),
                ));
            }
        }
        Ok(TimeFunction { points })
    }

    /// The constant 1.
    pub fn one() -> Self {
        TimeFunction {
            points: vec![(0.0, 1.0)],
        }
    }

    /// `∫₀ᵗ φ` (exact for the piecewise-linear φ, constant extension on either side).
    pub fn integral(&self, t: f64) -> f64 {
        let p = &self.points;
        // ∫₀ᵗ = F(t) − F(0) with F the antiderivative from the first point
        let anti = |t: f64| -> f64 {
            if t <= p[0].0 {
                return (t - p[0].0) * p[0].1;
            }
            let mut acc = 0.0;
            for w in p.windows(2) {
                let ((t0, v0), (t1, v1)) = (w[0], w[1]);
                if t <= t1 {
                    let vt = v0 + (v1 - v0) * (t - t0) / (t1 - t0);
                    return acc + 0.5 * (v0 + vt) * (t - t0);
                }
                acc += 0.5 * (v0 + v1) * (t1 - t0);
            }
            let last = p[p.len() - 1];
            acc + (t - last.0) * last.1
        };
        anti(t) - anti(0.0)
    }

    /// The largest `|φ(t)|` over all `t` (a piecewise-linear function held constant
    /// beyond its points reaches it at a point).
    pub fn max_abs(&self) -> f64 {
        self.points.iter().map(|p| p.1.abs()).fold(0.0, f64::max)
    }

    /// The value at `t`.
    pub fn eval(&self, t: f64) -> f64 {
        let p = &self.points;
        if t <= p[0].0 {
            return p[0].1;
        }
        let last = p[p.len() - 1];
        if t >= last.0 {
            return last.1;
        }
        let k = p.partition_point(|&(tk, _)| tk <= t);
        let ((t0, v0), (t1, v1)) = (p[k - 1], p[k]);
        v0 + (v1 - v0) * (t - t0) / (t1 - t0)
    }
}

/// A load `φ(t) b` on a few dofs (`b` as dof/value pairs).
#[derive(Clone, Debug, PartialEq)]
pub struct NodalLoad {
    /// The dofs loaded.
    pub dofs: Vec<usize>,
    /// `b` on those dofs (N).
    pub values: Vec<f64>,
    /// `φ(t)`.
    pub time: TimeFunction,
}

impl LinearSystem {
    /// `out += s · Σ_i φ_i(t) b_i` (no allocation: the schemes call it every step).
    pub fn add_loads(&self, t: f64, s: f64, out: &mut [f64]) {
        for l in &self.loads {
            let f = s * l.time.eval(t);
            if f != 0.0 {
                for (&d, &b) in l.dofs.iter().zip(&l.values) {
                    out[d] += f * b;
                }
            }
        }
    }
}

/// Adds the element mass `me` (dense, `dofs.len()` square) to `asm` as `kind` asks, a
/// lumped mass by the element's `lumping` rule; `is_contact[a]` marks the element's local
/// dofs that belong to contact nodes (a redistributed mass needs row sums: its caller
/// refuses elements of another lumping rule).
pub(crate) fn add_element_mass(
    asm: &mut impl crate::assembly::Accumulate,
    (kind, lumping): (MassKind, element::Lumping),
    dofs: &[usize],
    me: impl Fn(usize, usize) -> f64,
    is_contact: impl Fn(usize) -> bool,
) {
    let n = dofs.len();
    let row_sum = |a: usize| (0..n).map(|b| me(a, b)).sum::<f64>();
    match kind {
        MassKind::Consistent => asm.add_element(dofs, me),
        MassKind::Lumped if lumping == element::Lumping::Hrz => {
            // Hinton, Rock & Zienkiewicz (1976): the diagonal scaled by the element's
            // total over the diagonal's sum (a solid's mass is I ⊗ m: each displacement
            // component gets the same scaling)
            let total: f64 = (0..n).map(row_sum).sum();
            let diagonal: f64 = (0..n).map(|a| me(a, a)).sum();
            for (a, &i) in dofs.iter().enumerate() {
                asm.add(i, i, me(a, a) * total / diagonal);
            }
        }
        MassKind::Lumped => {
            for (a, &i) in dofs.iter().enumerate() {
                asm.add(i, i, row_sum(a));
            }
        }
        MassKind::Redistributed => {
            let keep: Vec<usize> = (0..n).filter(|&a| !is_contact(a)).collect();
            if keep.len() == n {
                return asm.add_element(dofs, me);
            }
            if keep.is_empty() {
                // every node is a contact node: nothing to move the mass to; lump it
                for (a, &i) in dofs.iter().enumerate() {
                    asm.add(i, i, row_sum(a));
                }
                return;
            }
            // Keep the block of the non-contact dofs and put the rest of the element
            // mass on their diagonal, in proportion to their full row sums, so the
            // element mass is unchanged (for solids each displacement component keeps
            // its share, as the consistent mass is I ⊗ m).
            let total: f64 = (0..n).map(row_sum).sum();
            let kept_block: f64 = keep
                .iter()
                .flat_map(|&a| keep.iter().map(move |&b| (a, b)))
                .map(|(a, b)| me(a, b))
                .sum();
            let kept_rows: f64 = keep.iter().map(|&a| row_sum(a)).sum();
            for &a in &keep {
                for &b in &keep {
                    asm.add(dofs[a], dofs[b], me(a, b));
                }
                asm.add(
                    dofs[a],
                    dofs[a],
                    (total - kept_block) * row_sum(a) / kept_rows,
                );
            }
        }
    }
}

/// Component of each of `n` interleaved dofs with `d` components per node.
pub fn interleaved_components(n: usize, d: usize) -> Vec<u8> {
    (0..n).map(|i| (i % d) as u8).collect()
}

use crate::assembly::Accumulate;
