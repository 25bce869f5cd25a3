//! Post-processing of a solution: displacement gradients and strains at cell centres,
//! Hooke's stress and the von Mises measure (Voigt order of the module doc).

use super::*;
use crate::model::element::MAX_NODES;

/// Reference shape-function gradients at the cell centre (`nodes` entries; the third
/// component is zero in 2-D).
pub(super) fn centre_gradients(kind: CellKind) -> [[f64; 3]; MAX_NODES] {
    let e = kind.element();
    let mut g = [[0.0; 3]; MAX_NODES];
    e.gradients(e.centre(), &mut g);
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
            // hoop strain u_r / r at the centre: the mean of the nodes for the linear
            // kinds (their shape functions there), the shape functions otherwise
            let e = kind.element();
            let (r, ur) = if e.order() == 1 {
                let k = kind.nodes() as f64;
                (
                    x.iter().map(|p| p[0]).sum::<f64>() / k,
                    u.iter().map(|p| p[0]).sum::<f64>() / k,
                )
            } else {
                let mut n = [0.0; MAX_NODES];
                e.shape(e.centre(), &mut n);
                let at = |v: &[[f64; 3]]| (0..e.nodes()).map(|a| n[a] * v[a][0]).sum::<f64>();
                (at(x), at(u))
            };
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
