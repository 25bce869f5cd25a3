//! The fields a frame carries, evaluated from the state: strain and stress per cell (the
//! material's law: Hooke's for the linear material, Green–Lagrange strain and Cauchy stress
//! for the hyperelastic ones, the uniaxial stress of rods), and which cell arrays a
//! geometry has.

use super::*;

impl FrameWriter {
    /// The cell arrays: `strain` and `stress` (small strain, Hooke) when every body is
    /// linear; `green_lagrange_strain` and `cauchy_stress` when a body has a
    /// large-deformation law (the linear bodies of such a scene write their small strain
    /// and Hooke stress, the linearizations of these measures, in the same arrays).
    pub(super) fn cell_arrays(&self) -> [(&'static str, usize); 3] {
        if self
            .geom
            .bodies
            .iter()
            .any(|(m, _)| m.model != MaterialModel::LINEAR)
        {
            NONLINEAR_CELL_ARRAYS
        } else {
            CELL_ARRAYS
        }
    }

    pub(super) fn fill(&mut self, s: &Snapshot) {
        let g = &self.geom;
        let dim = g.dim;
        for (k, d) in g.dof_of.iter().enumerate() {
            let (p, i) = (k / dim, k % dim);
            let (u, v, r) = d.map_or((0.0, 0.0, 0.0), |d| (s.q[d], s.v[d], s.reaction[d]));
            self.disp[3 * p + i] = u;
            self.vel[3 * p + i] = v;
            self.force[3 * p + i] = r;
        }
        for &(k, w, f) in &g.prescribed {
            let (p, i) = (k / dim, k % dim);
            let phi = &g.prescribed_functions[f];
            self.disp[3 * p + i] = w * phi.integral(s.time);
            self.vel[3 * p + i] = w * phi.eval(s.time);
        }
        self.gap.iter_mut().for_each(|f| *f = f64::NAN);
        self.status.iter_mut().for_each(|f| *f = f64::NAN);
        for (a, &p) in self.contact_point.iter().enumerate() {
            if p == usize::MAX || a >= s.gap.len() {
                continue;
            }
            // the contact's node, and the master node across a contact between bodies
            let other = s
                .partner
                .get(a)
                .and_then(|&d| self.point_of_dof.get(d).copied())
                .filter(|&o| o != p);
            for q in std::iter::once(p).chain(other) {
                self.gap[q] = if self.gap[q].is_nan() {
                    s.gap[a]
                } else {
                    self.gap[q].min(s.gap[a])
                };
                if !self.status.is_empty() && a < s.status.len() {
                    // a node in several contacts shows its most engaged status
                    let v = s.status[a] as f64;
                    self.status[q] = if self.status[q].is_nan() {
                        v
                    } else {
                        self.status[q].max(v)
                    };
                }
            }
        }
        for (c, (kind, nodes, body)) in g.cells.iter().enumerate() {
            let (mat, form) = &g.bodies[*body];
            let mut eps = [0.0; 6];
            let sig;
            match kind {
                GeomCell::Line => {
                    let (a, b) = (nodes[0], nodes[1]);
                    let l = g.points[b][0] - g.points[a][0];
                    eps[0] = (self.disp[3 * b] - self.disp[3 * a]) / l;
                    sig = [mat.young * eps[0], 0.0, 0.0, 0.0, 0.0, 0.0];
                }
                GeomCell::Solid(k) => {
                    let mut x = [[0.0; 3]; crate::model::element::MAX_NODES];
                    let mut u = [[0.0; 3]; crate::model::element::MAX_NODES];
                    for (j, &p) in nodes.iter().enumerate() {
                        x[j] = g.points[p];
                        u[j] = [self.disp[3 * p], self.disp[3 * p + 1], self.disp[3 * p + 2]];
                    }
                    let law = mat.model.hyperelastic(mat);
                    match law {
                        None => {
                            eps = centre_strain(*k, &x, &u, mat, *form);
                            sig = hooke(mat, &eps);
                        }
                        Some(law) => {
                            let grad = centre_gradient(*k, &x, &u);
                            (eps, sig) = green_lagrange_and_cauchy(&law, &grad)
                                .unwrap_or(([f64::NAN; 6], [f64::NAN; 6]));
                        }
                    }
                }
            }
            self.strain[6 * c..6 * c + 6].copy_from_slice(&eps);
            self.stress[6 * c..6 * c + 6].copy_from_slice(&sig);
            self.mises[c] = von_mises(&sig);
        }
    }
}
