//! The rotation check of linear bodies: small-strain elasticity is not invariant under
//! rotation, so a linear body that turns is silently wrong (issue 48).
//!
//! The linear law measures the strain `sym(∇u)`, which a rigid rotation by `φ` does not
//! leave at zero: it strains the body by `1 − cos φ` across the axis (a quarter turn
//! holds `2(λ + μ)` of strain energy per unit volume), and a spinning linear body does
//! not turn but stretches along its tangents. A run with a linear solid or plane body
//! therefore measures each of its cells' rotation at the cell centre: the angle of the
//! rotation `R` of the polar decomposition `F = R U`, `F = I + ∇u` (in 2-D in closed
//! form, `φ = atan2(F₂₁ − F₁₂, F₁₁ + F₂₂)`; in 3-D from the singular value decomposition,
//! `R = W Vᵀ`, `φ = acos((tr R − 1)/2)`), and stops the run (exit 1), naming the body,
//! the cell, the angle and the remedies, once an angle passes `scheme.max_rotation`
//! ([`crate::integrators::SchemeParams::max_rotation`]). A state that starts beyond it
//! (an `initial_displacement` that turns a body) is refused before the first step.
//!
//! The cheap part runs on every cell: `∇u` at the centre and `‖∇u‖_F`; a rotation by `φ`
//! has `‖R − I‖_F = 2√2 sin(φ/2) ≥ φ·0.9` for `φ ≤ 0.5`, so cells with `‖∇u‖_F` below
//! 0.9 times the limit cannot have turned past it, and only the others take the polar
//! decomposition (nalgebra's SVD; 2-D needs none). The check runs with the energy check,
//! every [`super::observers::ENERGY_CHECK_STRIDE`] steps and at the last, and at the
//! start. Rods (uniaxial, no rotation), axisymmetric bodies (a rigid turn in the `r–z`
//! plane is no motion of the body of revolution) and large-deformation bodies are not
//! measured.

use nalgebra::{Matrix2, Matrix3, Vector3};

use crate::error::Error;
use crate::model::geometry::{GeomCell, Geometry};
use crate::model::solid::{CellKind, Formulation, centre_gradient};

/// One measured cell.
#[derive(Clone, Debug)]
struct Cell {
    kind: CellKind,
    body: usize,
    /// Index of the cell within its body.
    index: usize,
    /// Offset of its nodes in [`RotationCheck::nodes`].
    start: usize,
}

/// The cells of the linear solid and plane bodies of a model, and how to read their
/// nodal displacements (module doc).
#[derive(Clone, Debug)]
pub struct RotationCheck {
    /// The limit (rad).
    max: f64,
    /// Body names, for the messages.
    names: Vec<String>,
    cells: Vec<Cell>,
    nodes: Vec<usize>,
    points: Vec<[f64; 3]>,
    dim: usize,
    dof_of: Vec<Option<usize>>,
    prescribed: Vec<(usize, f64, usize)>,
    functions: Vec<crate::model::TimeFunction>,
}

/// What one check found: the cell that turned most.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Turned {
    /// Body index.
    pub body: usize,
    /// Cell index within the body.
    pub cell: usize,
    /// Its rotation angle (rad).
    pub angle: f64,
}

impl RotationCheck {
    /// The check of `geometry`'s linear solid and plane bodies (`names` their names, in
    /// order) at the limit `max` (rad); `None` when no body is measured or the limit is
    /// infinite.
    pub fn new(geometry: &Geometry, names: &[String], max: f64) -> Option<Self> {
        if max.is_nan() || max == f64::INFINITY || geometry.dim < 2 {
            return None;
        }
        let measured: Vec<bool> = geometry
            .bodies
            .iter()
            .map(|(m, f)| m.model.is_linear() && !matches!(f, Formulation::Axisymmetric))
            .collect();
        let mut cells = Vec::new();
        let mut nodes = Vec::new();
        let mut per_body = vec![0usize; geometry.bodies.len()];
        for (c, cell_nodes, body) in &geometry.cells {
            let GeomCell::Solid(kind) = c else { continue };
            let index = per_body.get(*body).copied().unwrap_or(0);
            if let Some(n) = per_body.get_mut(*body) {
                *n += 1;
            }
            if !measured.get(*body).copied().unwrap_or(false) {
                continue;
            }
            cells.push(Cell {
                kind: *kind,
                body: *body,
                index,
                start: nodes.len(),
            });
            nodes.extend_from_slice(cell_nodes);
        }
        if cells.is_empty() {
            return None;
        }
        Some(RotationCheck {
            max,
            names: names.to_vec(),
            cells,
            nodes,
            points: geometry.points.clone(),
            dim: geometry.dim,
            dof_of: geometry.dof_of.clone(),
            prescribed: geometry.prescribed.clone(),
            functions: geometry.prescribed_functions.clone(),
        })
    }

    /// The limit (rad).
    pub fn limit(&self) -> f64 {
        self.max
    }

    /// The displacement component `c` of point `p` at time `t` in the state `q`.
    fn displacement(&self, q: &[f64], t: f64, p: usize, c: usize) -> f64 {
        let k = p * self.dim + c;
        match self.dof_of.get(k).copied().flatten() {
            Some(d) => q.get(d).copied().unwrap_or(0.0),
            None => match self.prescribed.binary_search_by_key(&k, |e| e.0) {
                Ok(i) => {
                    let (_, w, f) = self.prescribed[i];
                    w * self.functions[f].integral(t)
                }
                Err(_) => 0.0,
            },
        }
    }

    /// The cell that turned most at `(t, q)` and its angle (allocates nothing).
    pub fn largest(&self, t: f64, q: &[f64]) -> Option<Turned> {
        let cut = 0.9 * self.max;
        let mut worst: Option<Turned> = None;
        let mut x = [[0.0; 3]; crate::model::element::MAX_NODES];
        let mut u = [[0.0; 3]; crate::model::element::MAX_NODES];
        for cell in &self.cells {
            let nn = cell.kind.nodes();
            for (a, &p) in self.nodes[cell.start..cell.start + nn].iter().enumerate() {
                x[a] = self.points[p];
                for (c, uc) in u[a].iter_mut().enumerate().take(self.dim) {
                    *uc = self.displacement(q, t, p, c);
                }
            }
            let grad = centre_gradient(cell.kind, &x[..nn], &u[..nn]);
            let norm = grad.norm();
            if !norm.is_finite() {
                continue;
            }
            let angle = if norm < cut {
                // cannot have turned past the limit (module doc); the skew part's size
                // is the angle to first order
                let w = 0.5 * (grad - grad.transpose());
                (w[(2, 1)].powi(2) + w[(0, 2)].powi(2) + w[(1, 0)].powi(2)).sqrt()
            } else {
                polar_angle(&(Matrix3::identity() + grad), self.dim)
            };
            if worst.is_none_or(|w| angle > w.angle) {
                worst = Some(Turned {
                    body: cell.body,
                    cell: cell.index,
                    angle,
                });
            }
        }
        worst
    }

    /// The cell that turned most at step `step`, time `t`, or the run's error when it
    /// turned past the limit.
    pub fn check(&self, step: usize, t: f64, q: &[f64]) -> Result<Option<Turned>, Error> {
        match self.largest(t, q) {
            Some(w) if w.angle > self.max => Err(Error::RunFailed {
                step,
                time: t,
                contact: None,
                detail: self.describe(&w),
            }),
            w => Ok(w),
        }
    }

    /// The start's check: a state that turns a linear body past the limit is bad input
    /// (an `initial_displacement` that rotates it).
    pub fn check_start(&self, t: f64, q: &[f64]) -> Result<(), Error> {
        match self.largest(t, q) {
            Some(w) if w.angle > self.max => Err(Error::invalid(
                &format!("bodies[{}].initial_displacement", w.body),
                format!("a rotation of {:.4} rad at cell {}", w.angle, w.cell),
                &format!(
                    "at most scheme.max_rotation = {} rad on a linear body: {}",
                    self.max,
                    remedy()
                ),
            )),
            _ => Ok(()),
        }
    }

    fn describe(&self, w: &Turned) -> String {
        let name = self.names.get(w.body).map_or("?", |s| s.as_str());
        format!(
            "body `{name}` (bodies[{}]) cell {} has turned {:.4} rad ({:.1}°), beyond \
             scheme.max_rotation = {} rad: the linear law's small strain is not invariant \
             under rotation (a rigid turn of φ strains it by 1 − cos φ = {:.2e}); {}",
            w.body,
            w.cell,
            w.angle,
            w.angle.to_degrees(),
            self.max,
            1.0 - w.angle.cos(),
            remedy()
        )
    }
}

fn remedy() -> &'static str {
    "give the body material.model = \"corotational\" (the linear law in each cell's \
     rotated frame) or a large-deformation law (\"neo-hookean\", \"svk\"), or raise \
     scheme.max_rotation (inf: no check) to accept the linear law's error"
}

/// The angle of the rotation of `F`'s polar decomposition (module doc).
fn polar_angle(f: &Matrix3<f64>, dim: usize) -> f64 {
    if dim == 2 {
        let f2 = Matrix2::new(f[(0, 0)], f[(0, 1)], f[(1, 0)], f[(1, 1)]);
        return (f2[(1, 0)] - f2[(0, 1)])
            .atan2(f2[(0, 0)] + f2[(1, 1)])
            .abs();
    }
    let svd = f.svd(true, true);
    let (Some(w), Some(vt)) = (svd.u, svd.v_t) else {
        return f64::NAN;
    };
    let mut r = w * vt;
    if r.determinant() < 0.0 {
        // an inverted cell: the nearest proper rotation flips the smallest direction
        let mut d = Vector3::new(1.0, 1.0, 1.0);
        let k = svd.singular_values.imin();
        d[k] = -1.0;
        r = w * Matrix3::from_diagonal(&d) * vt;
    }
    ((r.trace() - 1.0) / 2.0).clamp(-1.0, 1.0).acos()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The polar angle of a rotation times a stretch is the rotation's, in 2-D and 3-D,
    /// up to a half turn (1e-12).
    #[test]
    fn polar_angle_of_a_rotated_stretch() {
        for phi in [0.01, 0.3, 1.5, 3.0] {
            let r = nalgebra::Rotation3::from_axis_angle(
                &nalgebra::Unit::new_normalize(Vector3::new(0.2, -1.0, 0.5)),
                phi,
            );
            let f = r.matrix() * Matrix3::from_diagonal(&Vector3::new(1.1, 0.95, 1.02));
            assert!((polar_angle(&f, 3) - phi).abs() <= 1e-12, "{phi}");
            let r2 = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), phi);
            let f2 = r2.matrix() * Matrix3::from_diagonal(&Vector3::new(1.1, 0.95, 1.0));
            assert!((polar_angle(&f2, 2) - phi).abs() <= 1e-12, "{phi}");
        }
    }
}
