//! Elastic solids on first-order cells (tri3, quad4, tet4, hex8): the kinematic
//! formulation, the cell kinds and the mesh, the small-strain element kernels and their
//! parallel assembly into the global `M` and `K` of a [`LinearSystem`]. A [`Material`]
//! (defined in `model::material`, re-exported here) may name a large-strain law; its
//! internal forces and tangents are `model::hyperelastic`'s, on these cells and
//! quadrature rules.
//!
//! Kernels use nalgebra fixed-size matrices; quadrilaterals and hexahedra are
//! integrated with 2×2 (×2) Gauss points, triangles and tetrahedra exactly with their
//! constant strain. Consistent mass is `∫ ρ Nᵀ N`; lumped mass is its row sum
//! (positive for these four linear elements). Stress is written in Voigt order
//! `(xx, yy, zz, yz, xz, xy)` in 3-D and `(xx, yy, xy)` in 2-D, with engineering shear
//! strains. An element whose Jacobian determinant is not positive at any integration
//! point is reported as inverted, with its index.
//!
//! By role: the formulation, the mesh and the 2-D elasticity matrices here (the cell
//! kinds, their shape functions and integration points are [`crate::model::element`]'s);
//! `kernels` the element matrices,
//! `assemble` the global assembly and the mesh checks, `stress` the cell-centre
//! strains and stresses of the frames.

use nalgebra::{Matrix2, Matrix3, SMatrix, Vector3};

use super::{LinearSystem, MassKind};
use crate::assembly::{Accumulate, PatternAssembler};
use crate::error::{Error, require_positive};

pub use super::material::{Material, MaterialModel};

mod assemble;
mod kernels;
mod stress;

use super::element::facet_corners;
pub use super::element::{CellKind, HEX8_CORNERS, Point, QUAD4_CORNERS};
pub use assemble::*;
pub use kernels::*;
pub use stress::*;

// The 2-D matrix needs the formulation, which is this module's: the constants and the
// 3-D matrix are with `Material` in `model::material`.
impl Material {
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
    /// What a 2-D body's edge integrals carry at radius `r` (its x): `2πr` on an
    /// axisymmetric body (the whole ring), the thickness in plane stress, 1 m otherwise.
    pub fn edge_weight(self, r: f64) -> f64 {
        match self {
            Formulation::Axisymmetric => std::f64::consts::TAU * r,
            f => f.thickness(),
        }
    }

    /// The depth a plane body's cells and faces are integrated over: the thickness of a
    /// plane-stress body, 1 m otherwise (per metre of depth in plane strain).
    pub fn thickness(self) -> f64 {
        match self {
            Formulation::PlaneStress { thickness } => thickness,
            _ => 1.0,
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
            let faces = kind.element().faces();
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
                let corners = facet_corners(kind.dim(), nodes.len()).unwrap_or(nodes.len());
                let out = mean(x[..corners].iter().map(|p| (*p).into())) - centroid;
                let normal = match corners {
                    2 => {
                        let t = x[1] - x[0];
                        Vector3::new(t[1], -t[0], 0.0)
                    }
                    3 => (x[1] - x[0]).cross(&(x[2] - x[0])),
                    _ => (x[2] - x[0]).cross(&(x[3] - x[1])),
                };
                if normal.dot(&out) < 0.0 {
                    reverse_facet(&mut nodes, corners);
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

/// Reverses the orientation of a facet with `k` corners (corners first, then the
/// mid-side nodes of the edges `i → i + 1`, then a centre node): the corners in reverse
/// order, the first kept first on a quadrilateral (a cyclic order either way), the
/// mid-side nodes following their edges.
fn reverse_facet(f: &mut [usize], k: usize) {
    let mut order = [0usize; 4];
    for (i, o) in order.iter_mut().enumerate().take(k) {
        *o = k - 1 - i;
    }
    if k == 4 {
        order.rotate_right(1);
    }
    let old: Vec<usize> = f.to_vec();
    for i in 0..k {
        f[i] = old[order[i]];
    }
    if k > 2 && old.len() >= 2 * k {
        for i in 0..k {
            // the new edge i joins old corners order[i] and order[i + 1]; the old edge j
            // joins j and j + 1
            let (a, b) = (order[i], order[(i + 1) % k]);
            let j = if (a + 1) % k == b { a } else { b };
            f[k + i] = old[k + j];
        }
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
