//! Hyperelastic solids at large deformation, total-Lagrangian (issue 17 §2): the
//! material laws and the element kernels that give the internal force `f_int(u)` and
//! its consistent tangent `K_t = ∂f_int/∂u` of a tet4 or hex8 cell (tri3 and quad4 in
//! plane strain: integrated as 3-D cells without z-part, `F₃₃ = 1`), the `F(q)` and
//! `Kⁿ = −∂F/∂q` that the θ-method Newton loop of eq. 42–51 evaluates at every iterate.
//!
//! Kinematics: `F = I + ∇_X u`, `C = FᵀF`, Green–Lagrange `E = (C − I)/2`; the second
//! Piola–Kirchhoff stress `S = ∂W/∂E` and the material tangent `ℂ = ∂S/∂E` in Voigt
//! order `(11, 22, 33, 23, 13, 12)` with engineering shear, as in [`super::solid`].
//! Internal force of node `a`: `f_a = ∫ B_aᵀ S dV₀` with the nonlinear strain–displacement
//! matrix `B_a` (rows `F_{i1} ∂₁N_a`, …, `F_{i1} ∂₂N_a + F_{i2} ∂₁N_a`); tangent
//! `K_ab = ∫ (B_aᵀ ℂ B_b + (∇N_a · S ∇N_b) I) dV₀` (material plus geometric part).
//!
//! Materials ([`Hyperelastic`]: a law of the registry [`crate::model::material::LAWS`]), each reducing to linear isotropic elasticity with the
//! same Lamé parameters at small strain:
//! - St. Venant–Kirchhoff: `W = λ/2 (tr E)² + μ E:E`, `S = λ tr E I + 2μ E`, constant `ℂ`;
//! - compressible neo-Hookean `W = μ/2 (I₁ − 3) − μ ln J + λ/2 (ln J)²` (the form FEBio,
//!   Kratos and GetFEM's Bonet variant share): `S = μ (I − C⁻¹) + λ ln J C⁻¹`,
//!   `ℂ = λ C⁻¹ ⊗ C⁻¹ + 2 (μ − λ ln J) 𝕀_{C⁻¹}` with
//!   `𝕀_{C⁻¹,ijkl} = ½ (C⁻¹_ik C⁻¹_jl + C⁻¹_il C⁻¹_jk)`.
//!
//! Both refuse a deformation with `det F ≤ 0` ([`Inverted`]): neo-Hookean's energy is
//! undefined there, St. Venant–Kirchhoff's is defined but describes a cell turned inside
//! out, which its energy's second minimum lets a run reach and keep (issue 34).
//!
//! Tangents are hand-derived and checked against central finite differences of the
//! stress and of the internal force on random deformations (tests below, relative error
//! ≤ 1e-6). Written here rather than taken from a crate: no maintained Rust crate offers
//! total-Lagrangian kernels on nalgebra's fixed-size types (DESIGN.md §6).

use nalgebra::{Matrix3, SMatrix, Vector3};

use crate::assembly::AssemblyPlan;

use super::element::{MAX_NODES, Rule, points};
use super::solid::{CellKind, Point};

pub use super::material::{
    Hyperelastic, HyperelasticLaw, Inverted, StressTangent, green_lagrange_and_cauchy,
};

/// Internal force `f_int` (`3 NN` values) and tangent `K_t` of one total-Lagrangian
/// cell: reference coordinates `x`, nodal displacements `u` (node-major, 3 per node).
/// Also returns the strain energy `∫ W dV₀`.
pub struct HyperElement<const ND: usize> {
    /// Internal force `∂Π/∂u` (N).
    pub force: SMatrix<f64, ND, 1>,
    /// Tangent `∂f_int/∂u` (N/m).
    pub tangent: SMatrix<f64, ND, ND>,
    /// Strain energy `Π = ∫ W dV₀` (J).
    pub energy: f64,
}

/// Reference gradients of the shape functions at one point: `(∇_X N_a, dV₀)`.
type RefPoint<const NN: usize> = ([Vector3<f64>; NN], f64);

/// Reference gradients `∇_X N_a` and weights `det J · w` at the points of a `D`-D rule
/// (`D` = 3, or 2 for a plane cell: gradients `(∂N/∂X, ∂N/∂Y, 0)`, unit thickness, the
/// Jacobian completed by 1 in z as in [`super::solid::centre_gradient`]).
fn reference_points<const NN: usize, const D: usize, const P: usize>(
    x: &[[f64; 3]],
    pts: &[Point<NN, D>; P],
) -> Result<[RefPoint<NN>; P], Inverted> {
    let mut out = [([Vector3::zeros(); NN], 0.0); P];
    for ((_, g, w), o) in pts.iter().zip(out.iter_mut()) {
        let mut jac = Matrix3::<f64>::identity();
        for i in 0..D {
            for j in 0..D {
                jac[(i, j)] = (0..NN).map(|a| x[a][i] * g[a][j]).sum();
            }
        }
        let det = jac.determinant();
        if det.is_nan() || det <= 0.0 {
            return Err(Inverted { det });
        }
        let jinv_t = jac.try_inverse().ok_or(Inverted { det })?.transpose();
        for a in 0..NN {
            let mut ga = Vector3::zeros();
            for j in 0..D {
                ga[j] = g[a][j];
            }
            o.0[a] = jinv_t * ga;
        }
        o.1 = det * w;
    }
    Ok(out)
}

/// What a kernel call computes beyond the force.
#[derive(Clone, Copy)]
struct Want {
    tangent: bool,
    energy: bool,
}

const ALL: Want = Want {
    tangent: true,
    energy: true,
};

fn kernel<const NN: usize, const ND: usize>(
    law: &Hyperelastic,
    pts: &[RefPoint<NN>],
    u: &[f64],
    want: Want,
) -> Result<HyperElement<ND>, Inverted> {
    let mut out = HyperElement {
        force: SMatrix::<f64, ND, 1>::zeros(),
        tangent: SMatrix::<f64, ND, ND>::zeros(),
        energy: 0.0,
    };
    let tangent = want.tangent.then_some(out.tangent.as_mut_slice());
    out.energy = kernel_into::<NN, ND>(law, pts, u, None, want, out.force.as_mut_slice(), tangent)?;
    Ok(out)
}

/// The element force (added into `fe`, `ND` values) and, with `ke`, the column-major
/// tangent (added into `ke`, `ND²` values) of one cell; returns the strain energy when
/// `want.energy` (else 0). The material part `Bᵀ ℂ B` is formed on its upper triangle
/// and mirrored (it is symmetric), the geometric part block by block.
fn kernel_into<const NN: usize, const ND: usize>(
    law: &Hyperelastic,
    pts: &[RefPoint<NN>],
    u: &[f64],
    u0: Option<&[f64]>,
    want: Want,
    fe: &mut [f64],
    mut ke: Option<&mut [f64]>,
) -> Result<f64, Inverted> {
    debug_assert_eq!(ND, 3 * NN);
    let gradient = |u: &[f64], g: &[Vector3<f64>; NN]| {
        // F = I + Σ_a u_a ⊗ ∇N_a
        let mut f = Matrix3::<f64>::identity();
        for a in 0..NN {
            for i in 0..3 {
                for j in 0..3 {
                    f[(i, j)] += u[3 * a + i] * g[a][j];
                }
            }
        }
        f
    };
    let mut energy = 0.0;
    for (g, dv) in pts {
        let mut f = gradient(u, g);
        if want.energy {
            energy += law.energy(&f)? * dv;
        }
        // from a start state u0: Gonzalez's stress, B and the tangent at F_m
        let dg = match u0 {
            Some(u0) => {
                let f0 = gradient(u0, g);
                let s = law.discrete_gradient(&f0, &f)?;
                f = 0.5 * (f0 + f);
                Some(s)
            }
            None => None,
        };
        let Some(ke) = ke.as_deref_mut() else {
            // the force alone: B's columns formed one at a time
            let s = match dg {
                Some(s) => s,
                None => law.stress(&f)?,
            };
            for a in 0..NN {
                let ga = &g[a];
                for i in 0..3 {
                    let col = [
                        f[(i, 0)] * ga[0],
                        f[(i, 1)] * ga[1],
                        f[(i, 2)] * ga[2],
                        f[(i, 1)] * ga[2] + f[(i, 2)] * ga[1],
                        f[(i, 0)] * ga[2] + f[(i, 2)] * ga[0],
                        f[(i, 0)] * ga[1] + f[(i, 1)] * ga[0],
                    ];
                    fe[3 * a + i] += (0..6).map(|k| col[k] * s[k]).sum::<f64>() * dv;
                }
            }
            continue;
        };
        // B (6 × ND): column c = 3a + i
        let mut b = SMatrix::<f64, 6, ND>::zeros();
        for a in 0..NN {
            let ga = &g[a];
            for i in 0..3 {
                let c = 3 * a + i;
                b[(0, c)] = f[(i, 0)] * ga[0];
                b[(1, c)] = f[(i, 1)] * ga[1];
                b[(2, c)] = f[(i, 2)] * ga[2];
                b[(3, c)] = f[(i, 1)] * ga[2] + f[(i, 2)] * ga[1];
                b[(4, c)] = f[(i, 0)] * ga[2] + f[(i, 2)] * ga[0];
                b[(5, c)] = f[(i, 0)] * ga[1] + f[(i, 1)] * ga[0];
            }
        }
        let (s, d) = law.stress_tangent(&f)?;
        let s = dg.unwrap_or(s);
        for c in 0..ND {
            let col = b.column(c);
            fe[c] += (0..6).map(|k| col[k] * s[k]).sum::<f64>() * dv;
        }
        // material part: upper triangle of Bᵀ (ℂ B)
        let db = d * b;
        for j in 0..ND {
            let dbj = db.column(j);
            for i in 0..=j {
                let bi = b.column(i);
                let v = (0..6).map(|k| bi[k] * dbj[k]).sum::<f64>() * dv;
                ke[i + j * ND] += v;
            }
        }
        // geometric part: (∇N_a · S ∇N_b) I, on the upper triangle of blocks
        let sm = Matrix3::new(
            s[0], s[5], s[4], //
            s[5], s[1], s[3], //
            s[4], s[3], s[2],
        );
        for a in 0..NN {
            let sga = sm * g[a];
            for bb in a..NN {
                let k = sga.dot(&g[bb]) * dv;
                for i in 0..3 {
                    ke[(3 * a + i) + (3 * bb + i) * ND] += k;
                }
            }
        }
    }
    if let Some(ke) = ke {
        for j in 0..ND {
            for i in 0..j {
                ke[j + i * ND] = ke[i + j * ND];
            }
        }
    }
    Ok(energy)
}

/// The tet4 cell at reference coordinates `x` (4 nodes) displaced by `u` (12 values).
pub fn tet4(law: &Hyperelastic, x: &[[f64; 3]], u: &[f64]) -> Result<HyperElement<12>, Inverted> {
    let pts = reference_points(x, &points::<4, 3, 1>(CellKind::Tet4, Rule::Energy))?;
    kernel::<4, 12>(law, &pts, u, ALL)
}

/// The hex8 cell at reference coordinates `x` (8 nodes, VTK order) displaced by `u` (24
/// values), 2 × 2 × 2 Gauss points.
pub fn hex8(law: &Hyperelastic, x: &[[f64; 3]], u: &[f64]) -> Result<HyperElement<24>, Inverted> {
    let pts = reference_points(x, &points::<8, 3, 8>(CellKind::Hex8, Rule::Energy))?;
    kernel::<8, 24>(law, &pts, u, ALL)
}

/// The cells this module integrates: every kind (3-D ones as solids, 2-D ones in plane
/// strain).
pub fn supports(kind: CellKind) -> bool {
    match kind {
        CellKind::Tri3
        | CellKind::Quad4
        | CellKind::Tet4
        | CellKind::Hex8
        | CellKind::Tri6
        | CellKind::Quad8
        | CellKind::Quad9
        | CellKind::Tet10
        | CellKind::Hex20
        | CellKind::Hex27 => true,
    }
}

/// The most dofs of a cell in 3 components per node.
const MAX_ND: usize = 3 * MAX_NODES;

/// A hyperelastic body on a mesh of any cell kind: the internal force `f_int(u)`
/// and tangent `K_t(u)` assembled in parallel on the mesh's fixed pattern
/// ([`AssemblyPlan`]), deterministically and without reserving anything per call.
pub struct HyperBody {
    plan: AssemblyPlan,
    points: Vec<[f64; 3]>,
    cells: Vec<(CellKind, Vec<usize>)>,
    law: Hyperelastic,
    dim: usize,
}

/// Why a body cannot be evaluated: cell `cell` is inverted (`det F ≤ 0` or, for the
/// reference geometry, `det J ≤ 0`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InvertedCell {
    /// The cell's index in the mesh.
    pub cell: usize,
    /// The determinant met.
    pub det: f64,
}

impl std::fmt::Debug for HyperBody {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "HyperBody({:?}, {} cells, {} nodes)",
            self.law,
            self.cells.len(),
            self.points.len()
        )
    }
}

impl HyperBody {
    /// The body of `mesh` under `law`: 3-D cells, or 2-D cells in plane strain, of any
    /// kind; plans the assembly.
    pub fn new(mesh: &super::solid::Mesh, law: Hyperelastic) -> Result<Self, crate::Error> {
        if let Some((id, (kind, _))) = mesh.cells.iter().enumerate().find(|(_, c)| !supports(c.0)) {
            return Err(crate::Error::invalid(
                &format!("cell {id}"),
                kind.name(),
                "a hyperelastic body takes solid (3-D) and plane-strain (2-D) cells",
            ));
        }
        let dim = mesh.cells.first().map_or(3, |(k, _)| k.dim());
        if let Some((id, (kind, _))) = mesh
            .cells
            .iter()
            .enumerate()
            .find(|(_, c)| c.0.dim() != dim)
        {
            return Err(crate::Error::invalid(
                &format!("cell {id}"),
                kind.name(),
                &format!("the body's cells are {dim}-D; one dimension per body"),
            ));
        }
        let lists: Vec<&[usize]> = mesh.cells.iter().map(|(_, c)| c.as_slice()).collect();
        Ok(HyperBody {
            plan: AssemblyPlan::new(mesh.points.len(), dim, &lists),
            points: mesh.points.clone(),
            cells: mesh.cells.clone(),
            law,
            dim,
        })
    }

    /// The law's name in prose ("St. Venant–Kirchhoff", "neo-Hookean").
    pub fn law_name(&self) -> &'static str {
        self.law.law().title()
    }

    /// Displacement components per node: 3, or 2 in plane strain.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// The assembly plan (order, pattern).
    pub fn plan(&self) -> &AssemblyPlan {
        &self.plan
    }

    /// Fills `tangent` (the plan's `nnz` values) with `K_t(u)` and `force` with
    /// `f_int(u)` ([`HyperBody::dim`] per node); reserves nothing. The error names the
    /// first inverted cell in mesh order.
    pub fn evaluate(
        &self,
        u: &[f64],
        tangent: &mut [f64],
        force: &mut [f64],
    ) -> Result<(), InvertedCell> {
        let dim = self.dim;
        self.plan
            .assemble(tangent, force, |id, k, f| {
                // buffers of the linear cells' size unless the cell needs more (zeroing a
                // hex27's 81 × 81 for every hex8 would cost more than its kernel)
                if dim * self.cells[id].1.len() <= 24 {
                    self.add_cell::<24, 576>(id, u, k, f)
                } else {
                    self.add_cell::<MAX_ND, { MAX_ND * MAX_ND }>(id, u, k, f)
                }
            })
            .map_err(|(cell, e): (usize, Inverted)| InvertedCell { cell, det: e.det })
    }

    /// Cell `id`'s force and tangent added into `f` and `k`, in stack buffers of `ND`
    /// and `ND2 = ND²` values.
    fn add_cell<const ND: usize, const ND2: usize>(
        &self,
        id: usize,
        u: &[f64],
        k: &mut crate::assembly::ColumnSlab,
        f: &mut crate::assembly::RowSlab,
    ) -> Result<(), Inverted> {
        use crate::assembly::Accumulate;
        let dim = self.dim;
        let nodes = &self.cells[id].1;
        let nd = dim * nodes.len();
        let mut dofs = [0usize; ND];
        for (a, &v) in nodes.iter().enumerate() {
            for i in 0..dim {
                dofs[dim * a + i] = dim * v + i;
            }
        }
        let (mut fe, mut ke) = ([0.0; ND], [0.0; ND2]);
        self.cell_into(id, (None, u), ALL, &mut fe[..nd], Some(&mut ke[..nd * nd]))?;
        k.add_element(&dofs[..nd], |a, b| ke[a + b * nd]);
        for a in 0..nd {
            f.add(dofs[a], fe[a]);
        }
        Ok(())
    }

    /// Buffers for [`HyperBody::evaluate_batched`] (a batch of element matrices).
    pub fn batch(&self) -> crate::assembly::ElementBatch {
        let nd = self
            .cells
            .iter()
            .map(|(_, c)| self.dim * c.len())
            .max()
            .unwrap_or(0);
        self.plan.batch(nd)
    }

    /// [`HyperBody::evaluate`] with every cell evaluated once (the batched assembly of
    /// [`AssemblyPlan::assemble_batched`], the same sums bit for bit); without `tangent`
    /// only the force, by the stress alone. With a start state `u0`, the force of
    /// Gonzalez's discrete gradient between `u0` and `u`
    /// ([`Hyperelastic::discrete_gradient`]) and the tangent at the midpoint. Reserves
    /// nothing.
    pub fn evaluate_batched(
        &self,
        (u0, u): (Option<&[f64]>, &[f64]),
        tangent: Option<&mut [f64]>,
        force: &mut [f64],
        batch: &mut crate::assembly::ElementBatch,
    ) -> Result<(), InvertedCell> {
        let want = Want {
            tangent: tangent.is_some(),
            energy: false,
        };
        let dim = self.dim;
        self.plan
            .assemble_batched(tangent, force, batch, |id, fe, ke| {
                let nd = dim * self.cells[id].1.len();
                self.cell_into(
                    id,
                    (u0, u),
                    want,
                    &mut fe[..nd],
                    ke.map(|k| &mut k[..nd * nd]),
                )
                .map(|_| ())
            })
            .map_err(|(cell, e): (usize, Inverted)| InvertedCell { cell, det: e.det })
    }

    /// Cell `id`'s element force into `fe` and (with `ke`) its column-major tangent into
    /// `ke`, both overwritten, in the body's dofs (`dim` per node); returns the strain
    /// energy when `want.energy`. A plane-strain cell is integrated as a 3-D one whose
    /// gradients and displacements have no z-part (`F₃₃ = 1`, `F₁₃ = F₂₃ = 0`), its
    /// in-plane rows and columns kept: the plane-strain law exactly.
    fn cell_into(
        &self,
        id: usize,
        (u0, u): (Option<&[f64]>, &[f64]),
        want: Want,
        fe: &mut [f64],
        mut ke: Option<&mut [f64]>,
    ) -> Result<f64, Inverted> {
        let (nodes, x, ue) = self.gather(id, u);
        let ue0 = u0.map(|u0| self.gather(id, u0).2);
        let ue0 = ue0.as_ref().map(|a| &a[..]);
        let nn = nodes.len();
        fe.fill(0.0);
        if let Some(k) = ke.as_deref_mut() {
            k.fill(0.0);
        }
        let law = &self.law;
        macro_rules! solid {
            ($kind:expr, $nn:literal, $nd:literal, $p:literal) => {{
                let pts = reference_points(&x[..$nn], &points::<$nn, 3, $p>($kind, Rule::Energy))?;
                kernel_into::<$nn, $nd>(law, &pts, &ue[..$nd], ue0.map(|u| &u[..$nd]), want, fe, ke)
            }};
        }
        match self.cells[id].0 {
            CellKind::Hex8 => {
                let pts = reference_points(&x, &points::<8, 3, 8>(CellKind::Hex8, Rule::Energy))?;
                kernel_into::<8, 24>(law, &pts, &ue, ue0, want, fe, ke)
            }
            CellKind::Tet4 => {
                let pts =
                    reference_points(&x[..4], &points::<4, 3, 1>(CellKind::Tet4, Rule::Energy))?;
                kernel_into::<4, 12>(law, &pts, &ue[..12], ue0.map(|u| &u[..12]), want, fe, ke)
            }
            CellKind::Tet10 => solid!(CellKind::Tet10, 10, 30, 36),
            CellKind::Hex20 => solid!(CellKind::Hex20, 20, 60, 27),
            CellKind::Hex27 => solid!(CellKind::Hex27, 27, 81, 27),
            kind @ (CellKind::Tri3 | CellKind::Quad4) => {
                let (mut f3, mut k3) = ([0.0; 12], [0.0; 144]);
                let energy =
                    self.plane_into(kind, &x, (&ue, ue0), want, &mut f3, &mut k3, ke.is_some())?;
                Self::plane_out(nn, &f3, &k3, fe, ke);
                Ok(energy)
            }
            kind @ (CellKind::Tri6 | CellKind::Quad8 | CellKind::Quad9) => {
                let (mut f3, mut k3) = ([0.0; 27], [0.0; 729]);
                let energy =
                    self.plane_into(kind, &x, (&ue, ue0), want, &mut f3, &mut k3, ke.is_some())?;
                Self::plane_out(nn, &f3, &k3, fe, ke);
                Ok(energy)
            }
        }
    }

    /// A plane-strain cell integrated as a 3-D one ([`HyperBody::cell_into`]): its force
    /// and (with `tangent`) column-major tangent in 3 dofs per node into `f3`, `k3`.
    #[allow(clippy::too_many_arguments)]
    fn plane_into(
        &self,
        kind: CellKind,
        x: &[[f64; 3]],
        (ue, ue0): (&[f64], Option<&[f64]>),
        want: Want,
        f3: &mut [f64],
        k3: &mut [f64],
        tangent: bool,
    ) -> Result<f64, Inverted> {
        let law = &self.law;
        macro_rules! plane {
            ($nn:literal, $nd:literal, $p:literal) => {{
                let pts = reference_points(&x[..$nn], &points::<$nn, 2, $p>(kind, Rule::Energy))?;
                let k3s = tangent.then_some(&mut k3[..$nd * $nd]);
                kernel_into::<$nn, $nd>(
                    law,
                    &pts,
                    &ue[..$nd],
                    ue0.map(|u| &u[..$nd]),
                    want,
                    &mut f3[..$nd],
                    k3s,
                )
            }};
        }
        match kind {
            CellKind::Tri3 => plane!(3, 9, 1),
            CellKind::Quad4 => plane!(4, 12, 4),
            CellKind::Tri6 => plane!(6, 18, 6),
            CellKind::Quad8 => plane!(8, 24, 9),
            CellKind::Quad9 => plane!(9, 27, 9),
            _ => unreachable!("a 3-D cell in a plane-strain body: `HyperBody::new` refuses it"),
        }
    }

    /// The in-plane rows and columns of a plane cell's 3-D force and tangent
    /// ([`HyperBody::plane_into`]) into the body's 2 dofs per node.
    fn plane_out(nn: usize, f3: &[f64], k3: &[f64], fe: &mut [f64], mut ke: Option<&mut [f64]>) {
        let (n2, n3) = (2 * nn, 3 * nn);
        for a in 0..nn {
            for i in 0..2 {
                fe[2 * a + i] = f3[3 * a + i];
                if let Some(k) = ke.as_deref_mut() {
                    for b in 0..nn {
                        for j in 0..2 {
                            k[(2 * a + i) + (2 * b + j) * n2] = k3[(3 * a + i) + (3 * b + j) * n3];
                        }
                    }
                }
            }
        }
    }

    /// Cell `id`'s nodes, their reference coordinates and their displacements in `u`,
    /// three per node (z zero in plane strain; the first `nodes` entries used).
    fn gather(&self, id: usize, u: &[f64]) -> (&[usize], [[f64; 3]; MAX_NODES], [f64; MAX_ND]) {
        let nodes = &self.cells[id].1;
        let d = self.dim;
        let mut x = [[0.0; 3]; MAX_NODES];
        let mut ue = [0.0; MAX_ND];
        for (a, &v) in nodes.iter().enumerate() {
            x[a] = self.points[v];
            ue[3 * a..3 * a + d].copy_from_slice(&u[d * v..d * v + d]);
        }
        (nodes, x, ue)
    }

    /// Strain energy `Σ ∫ W dV₀` (J; per unit thickness in plane strain), summed in
    /// cell order.
    pub fn strain_energy(&self, u: &[f64]) -> Result<f64, InvertedCell> {
        let want = Want {
            tangent: false,
            energy: true,
        };
        let mut total = 0.0;
        let mut fe = [0.0; MAX_ND];
        for id in 0..self.cells.len() {
            let nd = self.dim * self.cells[id].1.len();
            total += self
                .cell_into(id, (None, u), want, &mut fe[..nd], None)
                .map_err(|e| InvertedCell {
                    cell: id,
                    det: e.det,
                })?;
        }
        Ok(total)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::material::VOIGT;
    use crate::model::solid::{Formulation, Material, element_matrices};

    const MAT: Material = Material {
        young: 1e7,
        poisson: 0.3,
        density: 1000.0,
        model: crate::model::solid::MaterialModel::LINEAR,
    };

    /// A reproducible pseudo-random sequence in [−1, 1] (no dependency).
    fn lcg(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }

    /// An element evaluation: force, tangent (column-major), energy.
    type Eval<'a> = dyn Fn(&[f64]) -> (Vec<f64>, Vec<f64>, f64) + 'a;

    /// Every registered law ([`crate::model::material::LAWS`]): a new law is checked by
    /// every test below without being named here.
    fn laws() -> Vec<Hyperelastic> {
        let laws: Vec<_> = crate::model::material::LAWS
            .iter()
            .map(|&l| Hyperelastic::new(l, &MAT))
            .collect();
        assert!(laws.len() >= 2, "the registry lost a law");
        laws
    }

    /// A deformation gradient with stretches up to ±30 % and a rotation.
    fn random_f(seed: &mut u64) -> Matrix3<f64> {
        let a = Matrix3::from_fn(|_, _| 0.3 * lcg(seed));
        let rot =
            nalgebra::Rotation3::from_scaled_axis(Vector3::new(lcg(seed), lcg(seed), lcg(seed)));
        rot.matrix() * (Matrix3::identity() + 0.5 * (a + a.transpose()))
    }

    const HEX: [[f64; 3]; 8] = [
        [0.0, 0.0, 0.0],
        [0.1, 0.0, 0.0],
        [0.1, 0.12, 0.0],
        [0.0, 0.12, 0.0],
        [0.0, 0.0, 0.08],
        [0.1, 0.0, 0.08],
        [0.1, 0.12, 0.08],
        [0.0, 0.12, 0.08],
    ];
    const TET: [[f64; 3]; 4] = [
        [0.0, 0.0, 0.0],
        [0.1, 0.01, 0.0],
        [0.02, 0.12, 0.0],
        [0.01, 0.02, 0.09],
    ];

    /// Gonzalez's discrete gradient: `½ S_alg : ΔC = W(F₁) − W(F₀)` to rounding (1e-12 of
    /// the energies) for random pairs of deformations, and `S_alg → S(F)` as `F₀ → F₁`
    /// (within 1e-5 at differences up to 4e-7 in F: the first-order term, measured 1e-6).
    #[test]
    fn discrete_gradient_is_exact_and_tends_to_the_stress() {
        let mut seed = 7;
        for law in laws() {
            for _ in 0..10 {
                let (f0, f1) = (random_f(&mut seed), random_f(&mut seed));
                let s = law.discrete_gradient(&f0, &f1).unwrap();
                let dc = f1.transpose() * f1 - f0.transpose() * f0;
                let sm = Matrix3::new(s[0], s[5], s[4], s[5], s[1], s[3], s[4], s[3], s[2]);
                let work = 0.5 * sm.component_mul(&dc).sum();
                let (w0, w1) = (law.energy(&f0).unwrap(), law.energy(&f1).unwrap());
                let scale = w0.abs().max(w1.abs());
                assert!(
                    (work - (w1 - w0)).abs() <= 1e-12 * scale,
                    "{work} vs {}",
                    w1 - w0
                );
                let near = f1 + Matrix3::from_fn(|i, j| 1e-7 * ((i + 2 * j) as f64 - 2.0));
                let s_near = law.discrete_gradient(&near, &f1).unwrap();
                let s1 = law.stress(&f1).unwrap();
                let err = (s_near - s1).amax() / s1.amax();
                assert!(err <= 1e-5, "{err}");
            }
        }
    }

    /// `S = ∂W/∂E` and `ℂ = ∂S/∂E` against central differences in `E` (through `F =
    /// R U`, `U = √(2E + I)` built from `C`): relative error ≤ 1e-6 on ten random
    /// deformations per law (the difference step 1e-6 leaves errors near 1e-9).
    #[test]
    fn stress_and_tangent_match_finite_differences_of_the_energy() {
        let mut seed = 7;
        for law in laws() {
            for _ in 0..10 {
                let f = random_f(&mut seed);
                let c = f.transpose() * f;
                let (s, d) = law.stress_tangent(&f).unwrap();
                // W, S as functions of C through F = sqrt(C) (W and S depend on C only)
                let at = |c: &Matrix3<f64>| {
                    let u = c.symmetric_eigen();
                    let sq = u.eigenvectors
                        * Matrix3::from_diagonal(&u.eigenvalues.map(f64::sqrt))
                        * u.eigenvectors.transpose();
                    (law.energy(&sq).unwrap(), law.stress_tangent(&sq).unwrap().0)
                };
                let h = 1e-6;
                for (a, &(i, j)) in VOIGT.iter().enumerate() {
                    // a symmetric perturbation δE with engineering component 1 in slot a
                    let mut de = Matrix3::zeros();
                    if i == j {
                        de[(i, i)] = 1.0;
                    } else {
                        de[(i, j)] = 0.5;
                        de[(j, i)] = 0.5;
                    }
                    let (wp, sp) = at(&(c + 2.0 * h * de));
                    let (wm, sm) = at(&(c - 2.0 * h * de));
                    let ds = (wp - wm) / (2.0 * h);
                    let scale = s.amax().max(1.0);
                    assert!(
                        (ds - s[a]).abs() <= 1e-6 * scale,
                        "{law:?}: S[{a}] = {} against {ds}",
                        s[a]
                    );
                    let col = (sp - sm) / (2.0 * h);
                    let dscale = d.amax();
                    for r in 0..6 {
                        assert!(
                            (col[r] - d[(r, a)]).abs() <= 1e-6 * dscale,
                            "{law:?}: ℂ[{r},{a}] = {} against {}",
                            d[(r, a)],
                            col[r]
                        );
                    }
                }
            }
        }
    }

    /// For a cell, `f_int = ∂Π/∂u` and `K_t = ∂f_int/∂u` against central differences on
    /// random displacements of up to 20 % of the cell size: relative error ≤ 1e-6.
    #[test]
    fn element_force_and_tangent_match_finite_differences() {
        let mut seed = 11;
        for law in laws() {
            for trial in 0..4 {
                let u24: Vec<f64> = (0..24).map(|_| 0.02 * lcg(&mut seed)).collect();
                let u12 = &u24[..12];
                let check = |nd: usize, eval: &Eval<'_>| {
                    let u = if nd == 24 { &u24[..] } else { u12 };
                    let (f0, k0, _) = eval(u);
                    let fscale = f0.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
                    let kscale = k0.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
                    let h = 1e-7;
                    for c in 0..nd {
                        let mut up = u.to_vec();
                        let mut um = u.to_vec();
                        up[c] += h;
                        um[c] -= h;
                        let (fp, _, ep) = eval(&up);
                        let (fm, _, em) = eval(&um);
                        let de = (ep - em) / (2.0 * h);
                        assert!(
                            (de - f0[c]).abs() <= 1e-6 * fscale,
                            "{law:?} trial {trial}: f[{c}] = {} against dΠ/du = {de}",
                            f0[c]
                        );
                        for r in 0..nd {
                            let dk = (fp[r] - fm[r]) / (2.0 * h);
                            assert!(
                                (dk - k0[r + c * nd]).abs() <= 1e-6 * kscale,
                                "{law:?} trial {trial}: K[{r},{c}] = {} against {dk}",
                                k0[r + c * nd]
                            );
                        }
                    }
                };
                check(24, &|u| {
                    let e = hex8(&law, &HEX, u).unwrap();
                    (
                        e.force.as_slice().to_vec(),
                        e.tangent.as_slice().to_vec(),
                        e.energy,
                    )
                });
                check(12, &|u| {
                    let e = tet4(&law, &TET, u).unwrap();
                    (
                        e.force.as_slice().to_vec(),
                        e.tangent.as_slice().to_vec(),
                        e.energy,
                    )
                });
            }
        }
    }

    /// At `u = 0` both laws give the linear solid's stiffness (the small-strain limit:
    /// same Lamé parameters) to rounding, and no force.
    #[test]
    fn small_strain_limit_is_the_linear_solid() {
        for law in laws() {
            let e = hex8(&law, &HEX, &[0.0; 24]).unwrap();
            let lin = element_matrices(0, CellKind::Hex8, &HEX, &MAT, Formulation::Solid).unwrap();
            let scale = e.tangent.amax();
            for r in 0..24 {
                for c in 0..24 {
                    assert!(
                        (e.tangent[(r, c)] - lin.k(r, c)).abs() <= 1e-12 * scale,
                        "{law:?}: K[{r},{c}]"
                    );
                }
            }
            assert_eq!(e.force.amax(), 0.0);
            assert_eq!(e.energy, 0.0);
        }
    }

    /// A rigid rotation of 60° strains nothing: zero force and energy (to rounding)
    /// under both laws, where the linear solid's `K u` is of the order of `K` times the
    /// displacement.
    #[test]
    fn a_large_rigid_rotation_has_no_internal_force() {
        let rot = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), 60f64.to_radians());
        let u: Vec<f64> = HEX
            .iter()
            .flat_map(|x| {
                let p = Vector3::new(x[0], x[1], x[2]);
                let q = rot * p - p;
                [q[0], q[1], q[2]]
            })
            .collect();
        let lin = element_matrices(0, CellKind::Hex8, &HEX, &MAT, Formulation::Solid).unwrap();
        let ku: f64 = (0..24)
            .map(|r| (0..24).map(|c| lin.k(r, c) * u[c]).sum::<f64>().abs())
            .fold(0.0, f64::max);
        for law in laws() {
            let e = hex8(&law, &HEX, &u).unwrap();
            assert!(
                e.force.amax() <= 1e-9 * ku,
                "{law:?}: {} vs K u {ku}",
                e.force.amax()
            );
            assert!(
                e.energy.abs() <= 1e-12 * MAT.young * 1e-3,
                "{law:?}: {}",
                e.energy
            );
        }
        assert!(ku > 1e4, "the linear solid's spurious force {ku} N");
    }

    /// A cell turned inside out (`det F ≤ 0` at a Gauss point) is reported, not
    /// integrated, by the neo-Hookean law (whose `ln J` has no value there).
    #[test]
    fn an_inverted_deformation_is_reported() {
        let mut u = [0.0; 24];
        // push the top face through the bottom one
        for a in 4..8 {
            u[3 * a + 2] = -0.16;
        }
        let e = hex8(&Hyperelastic::neo_hookean(&MAT), &HEX, &u);
        assert!(
            matches!(e, Err(Inverted { det }) if det <= 0.0),
            "{:?}",
            e.err()
        );
    }
    /// The frames' measures: under a uniaxial stretch `F = diag(s, 1, 1)` the
    /// Green–Lagrange strain is `(s² − 1)/2` and the neo-Hookean Cauchy stress
    /// `σ_xx = (μ(s² − 1) + λ ln s)/s`, `σ_yy = σ_zz = λ ln s / s`; under a rotation both
    /// vanish (to 1e-12 of μ), where the small strain gives `cos φ − 1`.
    #[test]
    fn green_lagrange_and_cauchy_of_a_stretch_and_a_rotation() {
        let law = Hyperelastic::neo_hookean(&MAT);
        let (lambda, mu) = (law.lambda, law.mu);
        let s = 1.3_f64;
        let grad = Matrix3::new(s - 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        let (e, sig) = green_lagrange_and_cauchy(&law, &grad).unwrap();
        assert!((e[0] - (s * s - 1.0) / 2.0).abs() < 1e-15);
        assert!(e[1..].iter().all(|x| x.abs() < 1e-15));
        let sxx = (mu * (s * s - 1.0) + lambda * s.ln()) / s;
        assert!((sig[0] - sxx).abs() <= 1e-12 * sxx.abs());
        for k in [1, 2] {
            assert!((sig[k] - lambda * s.ln() / s).abs() <= 1e-12 * sxx.abs());
        }
        let phi = 0.7_f64;
        let (c, sn) = (phi.cos(), phi.sin());
        let rot = Matrix3::new(c, -sn, 0.0, sn, c, 0.0, 0.0, 0.0, 1.0);
        let (e, sig) = green_lagrange_and_cauchy(&law, &(rot - Matrix3::identity())).unwrap();
        assert!(e.iter().all(|x| x.abs() < 1e-15), "{e:?}");
        assert!(sig.iter().all(|x| x.abs() < 1e-12 * mu), "{sig:?}");
        assert!(green_lagrange_and_cauchy(&law, &(-2.0 * Matrix3::identity())).is_none());
    }

    /// A 3 × 2 × 2 hex8 box and the same box cut into tet4 cells; a 3 × 2 quad4 rectangle
    /// and the same cut into tri3 cells (plane strain).
    fn meshes() -> Vec<crate::model::solid::Mesh> {
        use crate::model::generate::{box_mesh, rectangle_mesh};
        vec![
            box_mesh(CellKind::Hex8, [3, 2, 2], [0.3, 0.2, 0.2]),
            box_mesh(CellKind::Tet4, [3, 2, 2], [0.3, 0.2, 0.2]),
            rectangle_mesh(CellKind::Quad4, [3, 2], [0.3, 0.2]),
            rectangle_mesh(CellKind::Tri3, [3, 2], [0.3, 0.2]),
            // the quadratic kinds (issue 51), on fewer cells
            box_mesh(CellKind::Hex20, [2, 1, 1], [0.3, 0.2, 0.2]),
            box_mesh(CellKind::Hex27, [2, 1, 1], [0.3, 0.2, 0.2]),
            box_mesh(CellKind::Tet10, [1, 1, 1], [0.3, 0.2, 0.2]),
            rectangle_mesh(CellKind::Quad8, [2, 1], [0.3, 0.2]),
            rectangle_mesh(CellKind::Quad9, [2, 1], [0.3, 0.2]),
            rectangle_mesh(CellKind::Tri6, [2, 1], [0.3, 0.2]),
        ]
    }

    /// Displacement components per node of `mesh`.
    fn dim(mesh: &crate::model::solid::Mesh) -> usize {
        mesh.cells[0].0.dim()
    }

    /// The assembled `K_t` is the derivative of the assembled `f_int` (central
    /// differences, relative error ≤ 1e-6) on a random displacement of up to 5 % of
    /// the box, and `f_int` that of the strain energy.
    #[test]
    fn assembled_tangent_and_force_match_finite_differences() {
        let mut seed = 5;
        for mesh in meshes() {
            for law in laws() {
                let body = HyperBody::new(&mesh, law).unwrap();
                let n = body.plan().order();
                let u: Vec<f64> = (0..n).map(|_| 0.01 * lcg(&mut seed)).collect();
                let mut k = vec![0.0; body.plan().nnz()];
                let mut f = vec![0.0; n];
                body.evaluate(&u, &mut k, &mut f).unwrap();
                let kt = body.plan().matrix(&k).to_dense();
                let (kscale, fscale) =
                    (kt.norm_max(), f.iter().fold(0.0_f64, |m, v| m.max(v.abs())));
                let (mut kp, mut fp, mut fm) = (k.clone(), vec![0.0; n], vec![0.0; n]);
                let h = 1e-8;
                for c in (0..n).step_by(5) {
                    let (mut up, mut um) = (u.clone(), u.clone());
                    up[c] += h;
                    um[c] -= h;
                    body.evaluate(&up, &mut kp, &mut fp).unwrap();
                    body.evaluate(&um, &mut kp, &mut fm).unwrap();
                    for r in 0..n {
                        let dk = (fp[r] - fm[r]) / (2.0 * h);
                        assert!(
                            (dk - kt[(r, c)]).abs() <= 1e-6 * kscale,
                            "{law:?}: K[{r},{c}] = {} against {dk}",
                            kt[(r, c)]
                        );
                    }
                    let de = (body.strain_energy(&up).unwrap() - body.strain_energy(&um).unwrap())
                        / (2.0 * h);
                    assert!((de - f[c]).abs() <= 1e-6 * fscale, "{law:?}: f[{c}]");
                }
            }
        }
    }

    /// The batched assembly (each cell evaluated once) gives the bits of the per-task one
    /// on one and two threads; its force-only evaluation (the stress without the
    /// tangent) gives the same force to 1e-13 of the largest. Plane-strain meshes
    /// included; the 1 200-cell box takes two batches.
    #[test]
    fn batched_assembly_equals_per_task_assembly() {
        let mut seed = 13;
        let big = crate::model::generate::box_mesh(CellKind::Hex8, [12, 10, 10], [1.2, 1.0, 1.0]);
        assert!(big.cells.len() > crate::assembly::ELEMENT_BATCH);
        for mesh in meshes().into_iter().chain([big]) {
            let law = Hyperelastic::neo_hookean(&MAT);
            let n = dim(&mesh) * mesh.points.len();
            let u: Vec<f64> = (0..n).map(|_| 0.01 * lcg(&mut seed)).collect();
            for threads in [1, 2] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                pool.install(|| {
                    let body = HyperBody::new(&mesh, law).unwrap();
                    let mut batch = body.batch();
                    let (mut k, mut f) = (vec![0.0; body.plan().nnz()], vec![0.0; n]);
                    body.evaluate(&u, &mut k, &mut f).unwrap();
                    let (mut kb, mut fb) = (vec![0.0; k.len()], vec![0.0; n]);
                    body.evaluate_batched((None, &u), Some(&mut kb), &mut fb, &mut batch)
                        .unwrap();
                    assert!(k.iter().zip(&kb).all(|(a, b)| a.to_bits() == b.to_bits()));
                    assert!(f.iter().zip(&fb).all(|(a, b)| a.to_bits() == b.to_bits()));
                    let mut ff = vec![0.0; n];
                    body.evaluate_batched((None, &u), None, &mut ff, &mut batch)
                        .unwrap();
                    let scale = f.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
                    for (a, b) in f.iter().zip(&ff) {
                        assert!((a - b).abs() <= 1e-13 * scale, "{a} against {b}");
                    }
                });
            }
        }
    }

    /// The same bits on one thread and on two (each column and row gets its terms in
    /// cell order whatever the cut), and at `u = 0` the linear solid's `K`.
    #[test]
    fn assembly_is_thread_independent_and_linear_at_rest() {
        let mut seed = 9;
        for mesh in meshes() {
            let law = Hyperelastic::neo_hookean(&MAT);
            let n = dim(&mesh) * mesh.points.len();
            let u: Vec<f64> = (0..n).map(|_| 0.01 * lcg(&mut seed)).collect();
            let run = |threads: usize, u: &[f64]| {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                pool.install(|| {
                    let body = HyperBody::new(&mesh, law).unwrap();
                    let mut k = vec![0.0; body.plan().nnz()];
                    let mut f = vec![0.0; n];
                    body.evaluate(u, &mut k, &mut f).unwrap();
                    (k, f)
                })
            };
            let (k1, f1) = run(1, &u);
            let (k2, f2) = run(2, &u);
            assert!(k1.iter().zip(&k2).all(|(a, b)| a.to_bits() == b.to_bits()));
            assert!(f1.iter().zip(&f2).all(|(a, b)| a.to_bits() == b.to_bits()));
            let (k0, f0) = run(2, &vec![0.0; n]);
            let form = if dim(&mesh) == 3 {
                Formulation::Solid
            } else {
                Formulation::PlaneStrain
            };
            let lin = crate::model::solid::assemble(
                &mesh,
                &MAT,
                form,
                crate::model::MassKind::Consistent,
            )
            .unwrap();
            let body = HyperBody::new(&mesh, law).unwrap();
            let kd = body.plan().matrix(&k0).to_dense();
            let ld = lin.stiffness.to_dense();
            let scale = ld.norm_max();
            assert!((kd - ld).norm_max() <= 1e-12 * scale);
            assert_eq!(f0.iter().fold(0.0_f64, |m, v| m.max(v.abs())), 0.0);
        }
    }
}
