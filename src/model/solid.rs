//! Isotropic linear elastic solids: element kernels (tri3, quad4, tet4, hex8) and their
//! parallel assembly into the global `M` and `K` of a [`LinearSystem`].
//!
//! Kernels use nalgebra fixed-size matrices; quadrilaterals and hexahedra are
//! integrated with 2×2 (×2) Gauss points, triangles and tetrahedra exactly with their
//! constant strain. Consistent mass is `∫ ρ Nᵀ N`; lumped mass is its row sum
//! (positive for these four linear elements). Stress is written in Voigt order
//! `(xx, yy, zz, yz, xz, xy)` in 3-D and `(xx, yy, xy)` in 2-D, with engineering shear
//! strains. An element whose Jacobian determinant is not positive at any integration
//! point is reported as inverted, with its index.

use nalgebra::{Matrix2, Matrix3, SMatrix, Vector3};

use super::{LinearSystem, MassKind};
use crate::assembly::{Accumulate, PatternAssembler};
use crate::error::{Error, require_in, require_positive};

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

pub use super::material::MaterialModel;

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

    /// 2-D elasticity matrix for plane strain or plane stress.
    pub fn d2(&self, f: Formulation) -> Matrix3<f64> {
        let (e, nu) = (self.young, self.poisson);
        match f {
            Formulation::PlaneStress { .. } => {
                let c = e / (1.0 - nu * nu);
                Matrix3::new(
                    c,
                    c * nu,
                    0.0,
                    c * nu,
                    c,
                    0.0,
                    0.0,
                    0.0,
                    c * (1.0 - nu) / 2.0,
                )
            }
            _ => {
                let (l, m) = self.lame();
                Matrix3::new(l + 2.0 * m, l, 0.0, l, l + 2.0 * m, 0.0, 0.0, 0.0, m)
            }
        }
    }
}

/// Kinematic assumption of the body.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case", deny_unknown_fields)]
pub enum Formulation {
    /// 3-D solid (tet4, hex8).
    Solid,
    /// 2-D plane strain, unit thickness (tri3, quad4).
    PlaneStrain,
    /// 2-D plane stress with a thickness (m).
    PlaneStress {
        /// Out-of-plane thickness (m).
        thickness: f64,
    },
    /// Axisymmetric about the y axis (tri3, quad4 in the half plane x = r ≥ 0, y = z):
    /// the hoop strain `u_r / r` joins the in-plane strains and every integral carries
    /// `2π r`; the body is the solid of revolution of its mesh,
    /// so forces and masses are those of the whole ring.
    Axisymmetric,
}

impl Formulation {
    /// The scene file's spelling (`solid`, `plane-strain`, …).
    pub fn name(self) -> &'static str {
        match self {
            Formulation::Solid => "solid",
            Formulation::PlaneStrain => "plane-strain",
            Formulation::PlaneStress { .. } => "plane-stress",
            Formulation::Axisymmetric => "axisymmetric",
        }
    }

    /// Space dimension (dofs per node).
    pub fn dim(self) -> usize {
        match self {
            Formulation::Solid => 3,
            _ => 2,
        }
    }
    fn thickness(self) -> f64 {
        match self {
            Formulation::PlaneStress { thickness } => thickness,
            _ => 1.0,
        }
    }
}

/// Linear cell kinds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CellKind {
    /// 3-node triangle.
    Tri3,
    /// 4-node quadrilateral (counter-clockwise).
    Quad4,
    /// 4-node tetrahedron (positive volume ordering).
    Tet4,
    /// 8-node hexahedron (VTK / Gmsh ordering).
    Hex8,
}

impl CellKind {
    /// Nodes per cell.
    pub fn nodes(self) -> usize {
        match self {
            CellKind::Tri3 => 3,
            CellKind::Quad4 | CellKind::Tet4 => 4,
            CellKind::Hex8 => 8,
        }
    }
    /// Space dimension of the cell.
    pub fn dim(self) -> usize {
        match self {
            CellKind::Tri3 | CellKind::Quad4 => 2,
            _ => 3,
        }
    }
    /// Name as in meshes and messages.
    pub fn name(self) -> &'static str {
        match self {
            CellKind::Tri3 => "tri3",
            CellKind::Quad4 => "quad4",
            CellKind::Tet4 => "tet4",
            CellKind::Hex8 => "hex8",
        }
    }
}

/// A mesh of one cell kind: points (always 3 coordinates; z = 0 in 2-D) and cells.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Node coordinates (m).
    pub points: Vec<[f64; 3]>,
    /// Cells: kind and node indices.
    pub cells: Vec<(CellKind, Vec<usize>)>,
    /// Named node sets (physical groups, point-data flags).
    pub node_sets: std::collections::BTreeMap<String, Vec<usize>>,
    /// The file's id of each point (Gmsh node tag, VTK point index); empty for generated
    /// meshes, whose ids are the indices. Readers drop the nodes no cell uses and number
    /// the rest in the order the cells first use them; the frames write these ids as
    /// the `node_id` point array, to map results back to the input file.
    pub node_ids: Vec<u64>,
    /// The file's id of each cell (Gmsh element number, VTK cell index); empty for
    /// generated meshes. Errors about a cell name it.
    pub cell_ids: Vec<u64>,
    /// The file the mesh was read from (errors about its cells name it).
    pub source: Option<std::path::PathBuf>,
}

impl Mesh {
    /// How errors name node `v`: its file tag and file for a mesh read from a file,
    /// its index for a generated one.
    pub fn node_label(&self, v: usize) -> String {
        match (self.node_ids.get(v), &self.source) {
            (Some(tag), Some(file)) => {
                let f = file.file_name().map_or_else(
                    || file.display().to_string(),
                    |f| f.to_string_lossy().into_owned(),
                );
                format!("node {tag} (tag in {f})")
            }
            (Some(tag), None) => format!("node {tag} (file tag)"),
            _ => format!("node {v} (index in the generated mesh)"),
        }
    }

    /// Nodes on the boundary: those of the faces (edges in 2-D) that belong to exactly
    /// one cell.
    pub fn boundary_nodes(&self) -> Vec<usize> {
        let all: Vec<usize> = (0..self.points.len()).collect();
        let mut nodes: Vec<usize> = self.boundary_facets(&all).into_iter().flatten().collect();
        nodes.sort_unstable();
        nodes.dedup();
        nodes
    }

    /// The boundary facets (edges in 2-D, faces in 3-D: those of exactly one cell) whose
    /// nodes all lie in `set`, each ordered so that its normal points out of its cell:
    /// an edge `(a, b)` has the body on its left (outward normal `(b − a)` turned by
    /// −90°), a face is counter-clockwise seen from outside (outward normal
    /// `(x₁ − x₀) × (x₂ − x₀)`, or `x_ξ × x_η` for a quadrilateral). The orientation is
    /// taken from the cell's centroid, so it holds for any node order of the cells.
    pub fn boundary_facets(&self, set: &[usize]) -> Vec<Vec<usize>> {
        let mut inside = vec![false; self.points.len()];
        for &v in set {
            if let Some(f) = inside.get_mut(v) {
                *f = true;
            }
        }
        // sorted nodes → (oriented facet, count)
        let mut seen: std::collections::BTreeMap<Vec<usize>, (Vec<usize>, usize)> =
            Default::default();
        for (kind, c) in &self.cells {
            let faces: &[&[usize]] = match kind {
                CellKind::Tri3 => &[&[0, 1], &[1, 2], &[2, 0]],
                CellKind::Quad4 => &[&[0, 1], &[1, 2], &[2, 3], &[3, 0]],
                CellKind::Tet4 => &[&[0, 1, 2], &[0, 1, 3], &[1, 2, 3], &[0, 2, 3]],
                CellKind::Hex8 => &[
                    &[0, 1, 2, 3],
                    &[4, 5, 6, 7],
                    &[0, 1, 5, 4],
                    &[1, 2, 6, 5],
                    &[2, 3, 7, 6],
                    &[3, 0, 4, 7],
                ],
            };
            let centroid = mean(c.iter().map(|&v| self.points[v]));
            for f in faces {
                let mut nodes: Vec<usize> = f.iter().map(|&a| c[a]).collect();
                let mut key = nodes.clone();
                key.sort_unstable();
                if let Some(e) = seen.get_mut(&key) {
                    e.1 += 1;
                    continue;
                }
                let x: Vec<Vector3<f64>> = nodes
                    .iter()
                    .map(|&v| Vector3::from(self.points[v]))
                    .collect();
                let out = mean(x.iter().map(|p| (*p).into())) - centroid;
                let normal = match x.len() {
                    2 => {
                        let t = x[1] - x[0];
                        Vector3::new(t[1], -t[0], 0.0)
                    }
                    3 => (x[1] - x[0]).cross(&(x[2] - x[0])),
                    _ => (x[2] - x[0]).cross(&(x[3] - x[1])),
                };
                if normal.dot(&out) < 0.0 {
                    nodes.reverse();
                    if nodes.len() == 4 {
                        // keep the first node first (a cyclic order either way)
                        nodes.rotate_right(1);
                    }
                }
                seen.insert(key, (nodes, 1));
            }
        }
        seen.into_values()
            .filter(|(f, n)| *n == 1 && f.iter().all(|&v| inside[v]))
            .map(|(f, _)| f)
            .collect()
    }
}

/// The centroid of `points`.
fn mean(points: impl Iterator<Item = [f64; 3]>) -> Vector3<f64> {
    let (mut s, mut n) = (Vector3::zeros(), 0.0);
    for p in points {
        s += Vector3::from(p);
        n += 1.0;
    }
    s / n
}

/// Element matrices of one cell on fixed-size matrices, `ND = nodes·dim` square.
#[derive(Clone, Debug)]
pub struct ElementMatrices<const ND: usize> {
    /// Stiffness.
    pub k: SMatrix<f64, ND, ND>,
    /// Consistent mass.
    pub m: SMatrix<f64, ND, ND>,
    /// Volume (3-D) or area times thickness (2-D) (m³).
    pub volume: f64,
}

/// The element matrices of a cell of any kind (each on its own fixed size).
// Unboxed on purpose: the value lives on the stack of one assembly task; boxing would
// allocate once per cell.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
pub enum AnyElement {
    /// tri3, 6 dofs.
    Tri3(ElementMatrices<6>),
    /// quad4, 8 dofs.
    Quad4(ElementMatrices<8>),
    /// tet4, 12 dofs.
    Tet4(ElementMatrices<12>),
    /// hex8, 24 dofs.
    Hex8(ElementMatrices<24>),
}

macro_rules! each_element {
    ($s:expr, $e:ident => $body:expr) => {
        match $s {
            AnyElement::Tri3($e) => $body,
            AnyElement::Quad4($e) => $body,
            AnyElement::Tet4($e) => $body,
            AnyElement::Hex8($e) => $body,
        }
    };
}

impl AnyElement {
    /// Stiffness entry `(a, b)` (local dofs, node-major).
    pub fn k(&self, a: usize, b: usize) -> f64 {
        each_element!(self, e => e.k[(a, b)])
    }
    /// Consistent mass entry `(a, b)`.
    pub fn m(&self, a: usize, b: usize) -> f64 {
        each_element!(self, e => e.m[(a, b)])
    }
    /// Volume (or area times thickness) (m³).
    pub fn volume(&self) -> f64 {
        each_element!(self, e => e.volume)
    }
    /// Local dofs (`nodes·dim`).
    pub fn ndof(&self) -> usize {
        each_element!(self, e => e.k.nrows())
    }
}

const G2: [f64; 2] = [-0.577_350_269_189_625_8, 0.577_350_269_189_625_8];

/// One integration point: shape values, reference gradients, weight.
pub(super) type Point<const NN: usize, const D: usize> = ([f64; NN], [[f64; D]; NN], f64);

/// Quadrature of the triangle: constant gradients; the 3 edge-midpoint rule (degree 2)
/// integrates the consistent mass exactly.
pub(super) fn tri3_points() -> [Point<3, 2>; 3] {
    let g = [[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]];
    [[0.5, 0.0], [0.5, 0.5], [0.0, 0.5]].map(|[r, s]| ([1.0 - r - s, r, s], g, 1.0 / 6.0))
}

/// Three interior points of the triangle (degree 2, at `(1/6, 1/6)` and permutations):
/// the axisymmetric kernel needs `r > 0` at every point, which the edge-midpoint rule
/// of [`tri3_points`] misses on a cell with an edge on the axis.
fn tri3_interior_points() -> [Point<3, 2>; 3] {
    let g = [[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]];
    let (a, b) = (1.0 / 6.0, 2.0 / 3.0);
    [[a, a], [b, a], [a, b]].map(|[r, s]| ([1.0 - r - s, r, s], g, 1.0 / 6.0))
}

/// 2×2 Gauss points of the bilinear quadrilateral.
pub(super) fn quad4_points() -> [Point<4, 2>; 4] {
    std::array::from_fn(|p| {
        let (r, s) = (G2[p / 2], G2[p % 2]);
        (
            [
                0.25 * (1.0 - r) * (1.0 - s),
                0.25 * (1.0 + r) * (1.0 - s),
                0.25 * (1.0 + r) * (1.0 + s),
                0.25 * (1.0 - r) * (1.0 + s),
            ],
            [
                [-0.25 * (1.0 - s), -0.25 * (1.0 - r)],
                [0.25 * (1.0 - s), -0.25 * (1.0 + r)],
                [0.25 * (1.0 + s), 0.25 * (1.0 + r)],
                [-0.25 * (1.0 + s), 0.25 * (1.0 - r)],
            ],
            1.0,
        )
    })
}

/// The tetrahedron's 4-point rule of degree 2 (exact for the consistent mass).
pub(super) fn tet4_points() -> [Point<4, 3>; 4] {
    let g = [
        [-1.0, -1.0, -1.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    let (a, b) = (0.585_410_196_624_968_5, 0.138_196_601_125_010_5);
    [[b, b, b], [a, b, b], [b, a, b], [b, b, a]]
        .map(|[r, s, u]| ([1.0 - r - s - u, r, s, u], g, 1.0 / 24.0))
}

/// 2×2×2 Gauss points of the trilinear hexahedron (VTK / Gmsh node order).
pub(super) fn hex8_points() -> [Point<8, 3>; 8] {
    const SGN: [[f64; 3]; 8] = [
        [-1.0, -1.0, -1.0],
        [1.0, -1.0, -1.0],
        [1.0, 1.0, -1.0],
        [-1.0, 1.0, -1.0],
        [-1.0, -1.0, 1.0],
        [1.0, -1.0, 1.0],
        [1.0, 1.0, 1.0],
        [-1.0, 1.0, 1.0],
    ];
    std::array::from_fn(|p| {
        let (r, s, u) = (G2[p / 4], G2[(p / 2) % 2], G2[p % 2]);
        (
            SGN.map(|c| 0.125 * (1.0 + c[0] * r) * (1.0 + c[1] * s) * (1.0 + c[2] * u)),
            SGN.map(|c| {
                [
                    0.125 * c[0] * (1.0 + c[1] * s) * (1.0 + c[2] * u),
                    0.125 * c[1] * (1.0 + c[0] * r) * (1.0 + c[2] * u),
                    0.125 * c[2] * (1.0 + c[0] * r) * (1.0 + c[1] * s),
                ]
            }),
            1.0,
        )
    })
}

/// Plane (2-D) kernel: `K = ∫ Bᵀ D B t dA`, `M = ∫ ρ Nᵀ N t dA`; `ND = 2 NN`.
fn plane_kernel<const NN: usize, const ND: usize>(
    x: &[[f64; 3]],
    pts: &[Point<NN, 2>],
    d: &Matrix3<f64>,
    rho: f64,
    t: f64,
    inverted: &dyn Fn(f64) -> Error,
) -> Result<ElementMatrices<ND>, Error> {
    debug_assert_eq!(ND, 2 * NN);
    let mut e = ElementMatrices {
        k: SMatrix::<f64, ND, ND>::zeros(),
        m: SMatrix::<f64, ND, ND>::zeros(),
        volume: 0.0,
    };
    for (n, g, w) in pts {
        let mut jac = Matrix2::<f64>::zeros();
        for a in 0..NN {
            for i in 0..2 {
                for j in 0..2 {
                    jac[(i, j)] += x[a][i] * g[a][j];
                }
            }
        }
        let det: f64 = jac.determinant();
        if det.is_nan() || det <= 0.0 {
            return Err(inverted(det));
        }
        let jinv = jac.try_inverse().ok_or_else(|| inverted(det))?;
        let dv = det * w * t;
        e.volume += dv;
        let mut b = SMatrix::<f64, 3, ND>::zeros();
        for a in 0..NN {
            // ∇N_a = J⁻ᵀ ∇_ref N_a
            let gx = jinv[(0, 0)] * g[a][0] + jinv[(1, 0)] * g[a][1];
            let gy = jinv[(0, 1)] * g[a][0] + jinv[(1, 1)] * g[a][1];
            b[(0, 2 * a)] = gx;
            b[(1, 2 * a + 1)] = gy;
            b[(2, 2 * a)] = gy;
            b[(2, 2 * a + 1)] = gx;
        }
        let db = d * b * dv;
        e.k += b.transpose() * db;
        for a in 0..NN {
            for c in 0..NN {
                let v = rho * n[a] * n[c] * dv;
                e.m[(2 * a, 2 * c)] += v;
                e.m[(2 * a + 1, 2 * c + 1)] += v;
            }
        }
    }
    Ok(e)
}

/// Axisymmetric kernel: `K = ∫ Bᵀ D B 2πr dA`, `M = ∫ ρ Nᵀ N 2πr dA` with
/// `ε = (ε_rr, ε_zz, ε_θθ = u_r/r, γ_rz)` and `D` the 3-D isotropic law restricted to
/// those four strains; `ND = 2 NN`. Quadrature points lie inside the cell, so `r > 0`
/// there even for cells touching the axis; a node on the axis needs no constraint on
/// `u_r` (the hoop term keeps it at zero up to the discretization, as usual for this
/// element).
fn axisymmetric_kernel<const NN: usize, const ND: usize>(
    x: &[[f64; 3]],
    pts: &[Point<NN, 2>],
    mat: &Material,
    inverted: &dyn Fn(f64) -> Error,
) -> Result<ElementMatrices<ND>, Error> {
    debug_assert_eq!(ND, 2 * NN);
    // the 3-D law on (ε_rr, ε_zz, ε_θθ) and one shear
    let d3 = mat.d3();
    let mut d = SMatrix::<f64, 4, 4>::zeros();
    d.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&d3.fixed_view::<3, 3>(0, 0));
    d[(3, 3)] = d3[(3, 3)];
    let mut e = ElementMatrices {
        k: SMatrix::<f64, ND, ND>::zeros(),
        m: SMatrix::<f64, ND, ND>::zeros(),
        volume: 0.0,
    };
    for (n, g, w) in pts {
        let mut jac = Matrix2::<f64>::zeros();
        let mut r = 0.0;
        for a in 0..NN {
            r += n[a] * x[a][0];
            for i in 0..2 {
                for j in 0..2 {
                    jac[(i, j)] += x[a][i] * g[a][j];
                }
            }
        }
        let det: f64 = jac.determinant();
        if det.is_nan() || det <= 0.0 || r.is_nan() || r <= 0.0 {
            return Err(inverted(det));
        }
        let jinv = jac.try_inverse().ok_or_else(|| inverted(det))?;
        let dv = 2.0 * std::f64::consts::PI * r * det * w;
        e.volume += dv;
        let mut b = SMatrix::<f64, 4, ND>::zeros();
        for a in 0..NN {
            let gx = jinv[(0, 0)] * g[a][0] + jinv[(1, 0)] * g[a][1];
            let gy = jinv[(0, 1)] * g[a][0] + jinv[(1, 1)] * g[a][1];
            b[(0, 2 * a)] = gx;
            b[(1, 2 * a + 1)] = gy;
            b[(2, 2 * a)] = n[a] / r;
            b[(3, 2 * a)] = gy;
            b[(3, 2 * a + 1)] = gx;
        }
        let db = d * b * dv;
        e.k += b.transpose() * db;
        for a in 0..NN {
            for c in 0..NN {
                let v = mat.density * n[a] * n[c] * dv;
                e.m[(2 * a, 2 * c)] += v;
                e.m[(2 * a + 1, 2 * c + 1)] += v;
            }
        }
    }
    Ok(e)
}

/// Solid (3-D) kernel: `K = ∫ Bᵀ D B dV`, `M = ∫ ρ Nᵀ N dV`; `ND = 3 NN`.
fn solid_kernel<const NN: usize, const ND: usize>(
    x: &[[f64; 3]],
    pts: &[Point<NN, 3>],
    d: &SMatrix<f64, 6, 6>,
    rho: f64,
    inverted: &dyn Fn(f64) -> Error,
) -> Result<ElementMatrices<ND>, Error> {
    debug_assert_eq!(ND, 3 * NN);
    let mut e = ElementMatrices {
        k: SMatrix::<f64, ND, ND>::zeros(),
        m: SMatrix::<f64, ND, ND>::zeros(),
        volume: 0.0,
    };
    for (n, g, w) in pts {
        let mut jac = Matrix3::<f64>::zeros();
        for a in 0..NN {
            for i in 0..3 {
                for j in 0..3 {
                    jac[(i, j)] += x[a][i] * g[a][j];
                }
            }
        }
        let det: f64 = jac.determinant();
        if det.is_nan() || det <= 0.0 {
            return Err(inverted(det));
        }
        let jinv_t = jac.try_inverse().ok_or_else(|| inverted(det))?.transpose();
        let dv = det * w;
        e.volume += dv;
        let mut b = SMatrix::<f64, 6, ND>::zeros();
        for a in 0..NN {
            let gx = jinv_t * Vector3::new(g[a][0], g[a][1], g[a][2]);
            let c = 3 * a;
            b[(0, c)] = gx[0];
            b[(1, c + 1)] = gx[1];
            b[(2, c + 2)] = gx[2];
            b[(3, c + 1)] = gx[2];
            b[(3, c + 2)] = gx[1];
            b[(4, c)] = gx[2];
            b[(4, c + 2)] = gx[0];
            b[(5, c)] = gx[1];
            b[(5, c + 1)] = gx[0];
        }
        let db = d * b * dv;
        e.k += b.transpose() * db;
        for a in 0..NN {
            for c in 0..NN {
                let v = rho * n[a] * n[c] * dv;
                for i in 0..3 {
                    e.m[(3 * a + i, 3 * c + i)] += v;
                }
            }
        }
    }
    Ok(e)
}

/// Computes the element matrices of cell `id` (nodes at `x`); errors name the cell.
pub fn element_matrices(
    id: usize,
    kind: CellKind,
    x: &[[f64; 3]],
    mat: &Material,
    f: Formulation,
) -> Result<AnyElement, Error> {
    let inverted = |det: f64| {
        Error::invalid(
            &format!("cell {id} ({})", kind.name()),
            format!("Jacobian determinant {det:e}"),
            "is inverted or degenerate: its nodes must be ordered with positive orientation",
        )
    };
    let rho = mat.density;
    if f == Formulation::Axisymmetric {
        return Ok(match kind {
            CellKind::Tri3 => AnyElement::Tri3(axisymmetric_kernel(
                x,
                &tri3_interior_points(),
                mat,
                &inverted,
            )?),
            CellKind::Quad4 => {
                AnyElement::Quad4(axisymmetric_kernel(x, &quad4_points(), mat, &inverted)?)
            }
            _ => {
                return Err(Error::invalid(
                    &format!("cell {id}"),
                    kind.name(),
                    "does not fit an axisymmetric formulation (tri3 or quad4)",
                ));
            }
        });
    }
    Ok(match kind {
        CellKind::Tri3 => AnyElement::Tri3(plane_kernel(
            x,
            &tri3_points(),
            &mat.d2(f),
            rho,
            f.thickness(),
            &inverted,
        )?),
        CellKind::Quad4 => AnyElement::Quad4(plane_kernel(
            x,
            &quad4_points(),
            &mat.d2(f),
            rho,
            f.thickness(),
            &inverted,
        )?),
        CellKind::Tet4 => {
            AnyElement::Tet4(solid_kernel(x, &tet4_points(), &mat.d3(), rho, &inverted)?)
        }
        CellKind::Hex8 => {
            AnyElement::Hex8(solid_kernel(x, &hex8_points(), &mat.d3(), rho, &inverted)?)
        }
    })
}

/// Assembles `M` and `K` of a mesh in parallel (rayon; each task owns a range of
/// columns of the one pattern, see [`PatternAssembler::par_assemble_pair`]); the result
/// does not depend on the thread count. `contact_nodes` matter only for
/// [`MassKind::Redistributed`].
pub fn assemble(
    mesh: &Mesh,
    mat: &Material,
    f: Formulation,
    mass: MassKind,
) -> Result<LinearSystem, Error> {
    assemble_with_contacts(mesh, mat, f, mass, &[])
}

/// Checks `mesh` against formulation `f` before anything reads it: finite coordinates
/// (`x = r ≥ 0` for an axisymmetric body), cells of the formulation's dimension with
/// their node counts and node numbers in range. Errors name the node or cell by its file
/// tag.
pub fn check_mesh(mesh: &Mesh, f: Formulation) -> Result<(), Error> {
    let dim = f.dim();
    for (i, p) in mesh.points.iter().enumerate() {
        if p.iter().any(|c| !c.is_finite()) {
            return Err(Error::invalid(
                &mesh.node_label(i),
                format!("{p:?}"),
                "coordinates must be finite",
            ));
        }
        if f == Formulation::Axisymmetric && p[0] < 0.0 {
            return Err(Error::invalid(
                &mesh.node_label(i),
                format!("{p:?}"),
                "an axisymmetric mesh lies in the half plane x = r ≥ 0 (y is the axis)",
            ));
        }
    }
    for (id, (kind, nodes)) in mesh.cells.iter().enumerate() {
        if kind.dim() != dim {
            // named by the formulation the user chose (issue 34: a tet4 mesh given
            // `axisymmetric` was blamed on an obstacle's point or a negative radius)
            return Err(Error::invalid(
                "formulation",
                f.name(),
                &format!(
                    "takes {dim}-D cells ({}), and cell {} of the mesh is {}: give \
                     formulation = {}",
                    if dim == 3 {
                        "tet4, hex8"
                    } else {
                        "tri3, quad4"
                    },
                    mesh.cell_ids.get(id).map_or(id as u64, |&t| t),
                    kind.name(),
                    if dim == 3 {
                        "\"plane-strain\", \"plane-stress\" or \"axisymmetric\" for a 2-D mesh"
                    } else {
                        "\"solid\" (the default) for a 3-D mesh"
                    }
                ),
            ));
        }
        if nodes.len() != kind.nodes() {
            return Err(Error::invalid(
                &format!("cell {id}"),
                format!("{} nodes", nodes.len()),
                &format!("{} needs {}", kind.name(), kind.nodes()),
            ));
        }
        if let Some(&bad) = nodes.iter().find(|&&v| v >= mesh.points.len()) {
            return Err(Error::invalid(
                &format!("cell {id}"),
                format!("node {bad}"),
                &format!("mesh has {} nodes", mesh.points.len()),
            ));
        }
    }
    Ok(())
}

/// [`assemble`] with the contact nodes named (for the redistributed mass).
pub fn assemble_with_contacts(
    mesh: &Mesh,
    mat: &Material,
    f: Formulation,
    mass: MassKind,
    contact_nodes: &[usize],
) -> Result<LinearSystem, Error> {
    let mut is_contact_node = vec![false; mesh.points.len()];
    for &v in contact_nodes {
        if v < is_contact_node.len() {
            is_contact_node[v] = true;
        }
    }
    mat.validate()?;
    if let Formulation::PlaneStress { thickness } = f {
        require_positive("thickness", thickness)?;
    }
    check_mesh(mesh, f)?;
    let dim = f.dim();
    let n = mesh.points.len() * dim;
    let cell_nodes: Vec<&[usize]> = mesh.cells.iter().map(|(_, c)| c.as_slice()).collect();
    let mut ak = PatternAssembler::new(mesh.points.len(), dim, &cell_nodes);
    let mut am = ak.zeroed_like();
    ak.par_assemble_pair(&mut am, &cell_nodes, |id, k, m| {
        let (kind, nodes) = &mesh.cells[id];
        let mut x = [[0.0; 3]; 8];
        let mut dofs = [0usize; 24];
        for (a, &v) in nodes.iter().enumerate() {
            x[a] = mesh.points[v];
            for i in 0..dim {
                dofs[a * dim + i] = v * dim + i;
            }
        }
        let nd = nodes.len() * dim;
        let (x, dofs) = (&x[..nodes.len()], &dofs[..nd]);
        let e = element_matrices(id, *kind, x, mat, f)?;
        k.add_element(dofs, |a, b| e.k(a, b));
        super::add_element_mass(
            m,
            mass,
            dofs,
            |a, b| e.m(a, b),
            |a| is_contact_node[dofs[a] / dim],
        );
        Ok(())
    })
    .map_err(|(id, e)| match (&mesh.source, e) {
        // a cell of a mesh file: name the file and the file's own element id
        (
            Some(file),
            Error::InvalidParameter {
                field,
                value,
                reason,
            },
        ) => Error::bad_file(
            file,
            format!(
                "element {}",
                mesh.cell_ids.get(id).copied().unwrap_or(id as u64)
            ),
            format!("{field}: {value}: {reason}"),
        ),
        (_, e) => e,
    })?;
    Ok(LinearSystem {
        mass: am.finish(),
        stiffness: ak.finish(),
        damping: None,
        force: vec![0.0; n],
        dofs_per_node: dim,
        component: super::interleaved_components(n, dim),
        ordering: None,
        loads: Vec::new(),
        prescribed: None,
        nonlinear: Vec::new(),
    })
}

/// Reference shape-function gradients at the cell centre (`nodes` entries; the third
/// component is zero in 2-D).
fn centre_gradients(kind: CellKind) -> [[f64; 3]; 8] {
    let mut g = [[0.0; 3]; 8];
    match kind {
        CellKind::Tri3 => {
            for (a, v) in tri3_points()[0].1.iter().enumerate() {
                g[a] = [v[0], v[1], 0.0];
            }
        }
        CellKind::Quad4 => {
            for (a, s) in [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]
                .iter()
                .enumerate()
            {
                g[a] = [0.25 * s[0], 0.25 * s[1], 0.0];
            }
        }
        CellKind::Tet4 => g[..4].copy_from_slice(&tet4_points()[0].1),
        CellKind::Hex8 => {
            for (a, s) in hex8_points()[0].1.iter().enumerate() {
                // at the centre every factor (1 ± ξ) is 1: ∂N_a/∂ξ_i = sign_i / 8
                g[a] = s.map(|c| 0.125 * c.signum());
            }
        }
    }
    g
}

/// Small-strain tensor at the centre of a cell, in the order `(xx, yy, zz, xy, yz, xz)`
/// (tensor components, not engineering shear) from node coordinates `x` and nodal
/// displacements `u` (three components; z ignored in 2-D). In plane strain `ε_zz = 0`;
/// in plane stress `ε_zz = −ν/(1−ν) (ε_xx + ε_yy)`, so that `σ_zz = 0`.
pub fn centre_strain(
    kind: CellKind,
    x: &[[f64; 3]],
    u: &[[f64; 3]],
    mat: &Material,
    f: Formulation,
) -> [f64; 6] {
    let grad = centre_gradient(kind, x, u);
    let e = |i: usize, j: usize| 0.5 * (grad[(i, j)] + grad[(j, i)]);
    let zz = match f {
        Formulation::Solid => e(2, 2),
        Formulation::PlaneStrain => 0.0,
        Formulation::PlaneStress { .. } => -mat.poisson / (1.0 - mat.poisson) * (e(0, 0) + e(1, 1)),
        Formulation::Axisymmetric => {
            // hoop strain u_r / r at the centre (the mean of the nodes for tri3, quad4)
            let k = kind.nodes() as f64;
            let r = x.iter().map(|p| p[0]).sum::<f64>() / k;
            let ur = u.iter().map(|p| p[0]).sum::<f64>() / k;
            if r > 0.0 { ur / r } else { 0.0 }
        }
    };
    [e(0, 0), e(1, 1), zz, e(0, 1), e(1, 2), e(0, 2)]
}

/// The displacement gradient `∂u_i/∂X_j` at the centre of a cell (reference coordinates
/// `x`, nodal displacements `u`; zero rows and columns past the cell's dimension).
pub fn centre_gradient(kind: CellKind, x: &[[f64; 3]], u: &[[f64; 3]]) -> Matrix3<f64> {
    let g = centre_gradients(kind);
    let nn = kind.nodes();
    let d = kind.dim();
    let mut jac = Matrix3::<f64>::identity();
    for i in 0..d {
        for j in 0..d {
            jac[(i, j)] = (0..nn).map(|a| x[a][i] * g[a][j]).sum();
        }
    }
    let jinv_t = jac.try_inverse().unwrap_or_else(Matrix3::zeros).transpose();
    let mut grad = Matrix3::<f64>::zeros();
    for a in 0..nn {
        let gx = jinv_t * Vector3::new(g[a][0], g[a][1], g[a][2]);
        for i in 0..d {
            for j in 0..d {
                grad[(i, j)] += u[a][i] * gx[j];
            }
        }
    }
    grad
}

/// Isotropic Hooke's law on a strain tensor in the order of [`centre_strain`].
pub fn hooke(mat: &Material, eps: &[f64; 6]) -> [f64; 6] {
    let (lambda, mu) = mat.lame();
    let tr = eps[0] + eps[1] + eps[2];
    [
        lambda * tr + 2.0 * mu * eps[0],
        lambda * tr + 2.0 * mu * eps[1],
        lambda * tr + 2.0 * mu * eps[2],
        2.0 * mu * eps[3],
        2.0 * mu * eps[4],
        2.0 * mu * eps[5],
    ]
}

/// Von Mises equivalent stress of a tensor in the order of [`centre_strain`].
pub fn von_mises(s: &[f64; 6]) -> f64 {
    let (a, b, c) = (s[0] - s[1], s[1] - s[2], s[2] - s[0]);
    (0.5 * (a * a + b * b + c * c) + 3.0 * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5])).sqrt()
}
