//! Element kernels: the stiffness and mass of one cell in plane strain or stress,
//! axisymmetry and 3-D (`K = ∫ Bᵀ D B`, consistent `M = ∫ ρ Nᵀ N`, lumped by row sums), an
//! inverted cell reported with its index.

use super::*;
use crate::model::element::{Rule, points};

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
    /// tri6, 12 dofs.
    Tri6(ElementMatrices<12>),
    /// quad8, 16 dofs.
    Quad8(ElementMatrices<16>),
    /// quad9, 18 dofs.
    Quad9(ElementMatrices<18>),
    /// tet10, 30 dofs.
    Tet10(ElementMatrices<30>),
    /// hex20, 60 dofs.
    Hex20(ElementMatrices<60>),
    /// hex27, 81 dofs.
    Hex27(ElementMatrices<81>),
}

macro_rules! each_element {
    ($s:expr, $e:ident => $body:expr) => {
        match $s {
            AnyElement::Tri3($e) => $body,
            AnyElement::Quad4($e) => $body,
            AnyElement::Tet4($e) => $body,
            AnyElement::Hex8($e) => $body,
            AnyElement::Tri6($e) => $body,
            AnyElement::Quad8($e) => $body,
            AnyElement::Quad9($e) => $body,
            AnyElement::Tet10($e) => $body,
            AnyElement::Hex20($e) => $body,
            AnyElement::Hex27($e) => $body,
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

/// Plane (2-D) kernel: `K = ∫ Bᵀ D B t dA`, `M = ∫ ρ Nᵀ N t dA`; `ND = 2 NN`.
pub(super) fn plane_kernel<const NN: usize, const ND: usize>(
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
pub(super) fn axisymmetric_kernel<const NN: usize, const ND: usize>(
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
pub(super) fn solid_kernel<const NN: usize, const ND: usize>(
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

/// A curved (quadratic) cell's Jacobian must be positive at its nodes too, not only at
/// the integration points: a mid-side node moved across its cell folds the map near an
/// edge while every interior point stays positive.
fn curved_cell_is_positive(
    kind: CellKind,
    x: &[[f64; 3]],
    inverted: &dyn Fn(f64) -> Error,
) -> Result<(), Error> {
    for &xi in kind.element().reference_nodes() {
        let c = crate::model::element::jacobian_columns(kind, x, xi).map(Vector3::from);
        let det = Matrix3::from_columns(&c).determinant();
        if det.is_nan() || det <= 0.0 {
            return Err(inverted(det));
        }
    }
    Ok(())
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
    if kind.element().order() > 1 {
        curved_cell_is_positive(kind, x, &inverted)?;
    }
    if f == Formulation::Axisymmetric {
        return Ok(match kind {
            CellKind::Tri3 => AnyElement::Tri3(axisymmetric_kernel(
                x,
                &points::<3, 2, 3>(kind, Rule::Interior),
                mat,
                &inverted,
            )?),
            CellKind::Quad4 => AnyElement::Quad4(axisymmetric_kernel(
                x,
                &points::<4, 2, 4>(kind, Rule::Interior),
                mat,
                &inverted,
            )?),
            CellKind::Tri6 => AnyElement::Tri6(axisymmetric_kernel(
                x,
                &points::<6, 2, 6>(kind, Rule::Interior),
                mat,
                &inverted,
            )?),
            CellKind::Quad8 => AnyElement::Quad8(axisymmetric_kernel(
                x,
                &points::<8, 2, 9>(kind, Rule::Interior),
                mat,
                &inverted,
            )?),
            CellKind::Quad9 => AnyElement::Quad9(axisymmetric_kernel(
                x,
                &points::<9, 2, 9>(kind, Rule::Interior),
                mat,
                &inverted,
            )?),
            _ => {
                return Err(Error::invalid(
                    &format!("cell {id}"),
                    kind.name(),
                    "does not fit an axisymmetric formulation (a 2-D cell)",
                ));
            }
        });
    }
    Ok(match kind {
        CellKind::Tri3 => AnyElement::Tri3(plane_kernel(
            x,
            &points::<3, 2, 3>(kind, Rule::Full),
            &mat.d2(f),
            rho,
            f.thickness(),
            &inverted,
        )?),
        CellKind::Quad4 => AnyElement::Quad4(plane_kernel(
            x,
            &points::<4, 2, 4>(kind, Rule::Full),
            &mat.d2(f),
            rho,
            f.thickness(),
            &inverted,
        )?),
        CellKind::Tet4 => AnyElement::Tet4(solid_kernel(
            x,
            &points::<4, 3, 4>(kind, Rule::Full),
            &mat.d3(),
            rho,
            &inverted,
        )?),
        CellKind::Hex8 => AnyElement::Hex8(solid_kernel(
            x,
            &points::<8, 3, 8>(kind, Rule::Full),
            &mat.d3(),
            rho,
            &inverted,
        )?),
        CellKind::Tet10 => AnyElement::Tet10(solid_kernel(
            x,
            &points::<10, 3, 36>(kind, Rule::Full),
            &mat.d3(),
            rho,
            &inverted,
        )?),
        CellKind::Hex20 => AnyElement::Hex20(solid_kernel(
            x,
            &points::<20, 3, 27>(kind, Rule::Full),
            &mat.d3(),
            rho,
            &inverted,
        )?),
        CellKind::Hex27 => AnyElement::Hex27(solid_kernel(
            x,
            &points::<27, 3, 27>(kind, Rule::Full),
            &mat.d3(),
            rho,
            &inverted,
        )?),
        CellKind::Tri6 => AnyElement::Tri6(plane_kernel(
            x,
            &points::<6, 2, 6>(kind, Rule::Full),
            &mat.d2(f),
            rho,
            f.thickness(),
            &inverted,
        )?),
        CellKind::Quad8 => AnyElement::Quad8(plane_kernel(
            x,
            &points::<8, 2, 9>(kind, Rule::Full),
            &mat.d2(f),
            rho,
            f.thickness(),
            &inverted,
        )?),
        CellKind::Quad9 => AnyElement::Quad9(plane_kernel(
            x,
            &points::<9, 2, 9>(kind, Rule::Full),
            &mat.d2(f),
            rho,
            f.thickness(),
            &inverted,
        )?),
    })
}
