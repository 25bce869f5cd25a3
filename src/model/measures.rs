//! What a state of the structure measures: kinetic and potential energy (prescribed dofs
//! and nonlinear parts included), total energy, momentum and mass; a body's centre of
//! mass and rigid-motion velocity field ([`centre_of_mass`], [`rigid_velocity`]).

use super::*;

impl LinearSystem {
    /// Number of degrees of freedom.
    pub fn ndof(&self) -> usize {
        self.mass.nrows()
    }

    /// The whole structure's kinetic and potential energy at `(t, q, v)` (J): those of
    /// the kept dofs ([`LinearSystem::kinetic_energy`], [`LinearSystem::potential_energy`])
    /// plus what the prescribed dofs add ([`Prescribed::energy`]). `scratch` holds at
    /// least twice [`LinearSystem::prescribed_dofs`] values.
    pub fn energies(&self, t: f64, q: &[f64], v: &[f64], scratch: &mut [f64]) -> (f64, f64) {
        let (k, u) = self.prescribed_energy(t, q, v, scratch);
        (self.kinetic_energy(q, v) + k, self.potential_energy(q) + u)
    }

    /// What the prescribed dofs add to the kept dofs' kinetic and potential energy at
    /// `(t, q, v)` ([`Prescribed::energy`]; `(0, 0)` without them). `scratch` as for
    /// [`LinearSystem::energies`].
    pub fn prescribed_energy(
        &self,
        t: f64,
        q: &[f64],
        v: &[f64],
        scratch: &mut [f64],
    ) -> (f64, f64) {
        match &self.prescribed {
            Some(p) => {
                let (vp, up) = scratch[..2 * p.velocity.len()].split_at_mut(p.velocity.len());
                p.energy(t, q, v, vp, up)
            }
            None => (0.0, 0.0),
        }
    }

    /// [`LinearSystem::energies`] summed, with its own scratch (allocates: for the start
    /// and end of a run, not per step).
    pub fn total_energy(&self, t: f64, q: &[f64], v: &[f64]) -> f64 {
        let (ke, pe) = self.energies(t, q, v, &mut vec![0.0; 2 * self.prescribed_dofs()]);
        ke + pe
    }

    /// Number of prescribed (eliminated) dofs.
    pub fn prescribed_dofs(&self) -> usize {
        self.prescribed.as_ref().map_or(0, |p| p.velocity.len())
    }

    /// The layouts of `M` and `K` read once, for [`LinearSystem::energies_with`].
    pub fn energy_forms(&self) -> EnergyForms {
        EnergyForms {
            mass: QuadraticForm::new(self.mass.as_ref()),
            stiffness: QuadraticForm::new(self.stiffness.as_ref()),
            unloaded: self.force.iter().all(|&f| f == 0.0),
        }
    }

    /// [`LinearSystem::energies`] through `forms` (from [`LinearSystem::energy_forms`]
    /// of this system): the same energies, their sums reordered for speed (they differ
    /// by round-off). Does not allocate; what each history row calls.
    pub fn energies_with(
        &self,
        forms: &EnergyForms,
        t: f64,
        q: &[f64],
        v: &[f64],
        scratch: &mut [f64],
    ) -> (f64, f64) {
        self.energies_of(forms, (t, q, v), scratch, None)
    }

    /// [`LinearSystem::energies_with`], also leaving `M v` in `mv` (`n` values) for
    /// each body's momenta ([`crate::model::BodyMeasures::measure_with`]): where the
    /// mass form walks the matrix it keeps the product it forms (the same energies bit
    /// for bit), else one product more.
    pub fn energies_keeping_mv(
        &self,
        forms: &EnergyForms,
        t: f64,
        q: &[f64],
        v: &[f64],
        scratch: &mut [f64],
        mv: &mut [f64],
    ) -> (f64, f64) {
        self.energies_of(forms, (t, q, v), scratch, Some(mv))
    }

    /// The energies of [`LinearSystem::energies_with`], keeping `M v` where asked.
    fn energies_of(
        &self,
        forms: &EnergyForms,
        (t, q, v): (f64, &[f64], &[f64]),
        scratch: &mut [f64],
        mv: Option<&mut [f64]>,
    ) -> (f64, f64) {
        let m = self.mass.as_ref();
        let fits = |mv: &[f64]| mv.len() == m.nrows() && v.len() == m.ncols();
        let vmv = match mv {
            Some(mv) if fits(mv) && matches!(forms.mass, crate::linalg::QuadraticForm::General) => {
                crate::linalg::quadratic_form_keep(m, v, mv)
            }
            Some(mv) => {
                if fits(mv) {
                    crate::linalg::spmv(m, v, mv);
                }
                forms.mass.eval(m, v)
            }
            None => forms.mass.eval(m, v),
        };
        let (k, u) = self.prescribed_energy(t, q, v, scratch);
        let kinetic = 0.5 * vmv + self.parts_kinetic(q, v);
        let mut potential = 0.5 * forms.stiffness.eval(self.stiffness.as_ref(), q);
        if !forms.unloaded {
            potential -= crate::linalg::dot_lanes(&self.force, q);
        }
        (kinetic + k, potential + self.parts_potential(q) + u)
    }

    /// The nonlinear parts' kinetic energy (0 without them).
    pub(super) fn parts_kinetic(&self, q: &[f64], v: &[f64]) -> f64 {
        self.nonlinear
            .iter()
            .map(|p| p.kinetic_energy(q, v))
            .sum::<f64>()
    }

    /// The nonlinear parts' internal energy (0 without them; NaN where a cell is
    /// inverted).
    pub(super) fn parts_potential(&self, q: &[f64]) -> f64 {
        if self.nonlinear.is_empty() {
            return 0.0;
        }
        self.nonlinear
            .iter()
            .map(|r| r.energy(q).unwrap_or(f64::NAN))
            .sum::<f64>()
    }

    /// Kinetic energy of the kept dofs `½ vᵀ M(q) v` (J; `q` matters only with a mass
    /// part, [`system::NonlinearPart::mass_entries`]).
    pub fn kinetic_energy(&self, q: &[f64], v: &[f64]) -> f64 {
        // without parts the sum is a zero, which keeps the constant term bit for bit
        0.5 * quadratic_form(self.mass.as_ref(), v)
            + self
                .nonlinear
                .iter()
                .map(|p| p.kinetic_energy(q, v))
                .sum::<f64>()
    }

    /// Potential energy of the kept dofs `½ qᵀ K q − fᵀ q` (J): elastic energy plus the
    /// potential of the constant external force, plus the energies of the nonlinear
    /// internal forces ([`system::NonlinearPart::energy`]; NaN where a cell is inverted).
    pub fn potential_energy(&self, q: &[f64]) -> f64 {
        let linear = 0.5 * quadratic_form(self.stiffness.as_ref(), q)
            - self.force.iter().zip(q).map(|(f, x)| f * x).sum::<f64>();
        if self.nonlinear.is_empty() {
            return linear;
        }
        linear
            + self
                .nonlinear
                .iter()
                .map(|r| r.energy(q).unwrap_or(f64::NAN))
                .sum::<f64>()
    }

    /// Linear momentum along the first axis, `e_xᵀ M v` (kg·m/s), where `e_x` is 1 on
    /// every x-component dof.
    pub fn momentum(&self, v: &[f64]) -> f64 {
        let m = self.mass.as_ref();
        let mut s = 0.0;
        for (j, &vj) in v.iter().enumerate() {
            for k in m.col_ptr()[j]..m.col_ptr()[j + 1] {
                if self.component[m.row_idx()[k]] == 0 {
                    s += m.val()[k] * vj;
                }
            }
        }
        s
    }

    /// Total mass `e_xᵀ M e_x` (kg).
    pub fn total_mass(&self) -> f64 {
        let m = self.mass.as_ref();
        let mut s = 0.0;
        for j in (0..m.ncols()).filter(|&j| self.component[j] == 0) {
            for k in m.col_ptr()[j]..m.col_ptr()[j + 1] {
                if self.component[m.row_idx()[k]] == 0 {
                    s += m.val()[k];
                }
            }
        }
        s
    }
}

/// The centre of mass of a body whose dof `p·dim + d` is component `d` of point `p`:
/// `c_d = (e_dᵀ M X_d) / (e_dᵀ M e_d)` per component `d < dim`, `X_d` the points'
/// coordinate `d` on the component-`d` dofs (m). With the consistent mass of
/// isoparametric cells this is `∫ρx dV / ∫ρ dV` exactly (the row sums of `M` are
/// `∫ρN_i`, and `Σ N_i x_i = x`); the lumped mass has the same row sums; under the
/// redistributed mass (no mass on contact nodes) it is the discrete model's own centre.
/// `None` when the body has no mass.
pub fn centre_of_mass(
    mass: faer::sparse::SparseColMatRef<'_, usize, f64>,
    points: &[[f64; 3]],
    dim: usize,
) -> Option<[f64; 3]> {
    let mut num = [0.0; 3];
    let mut den = [0.0; 3];
    for j in 0..mass.ncols().min(points.len() * dim) {
        let d = j % dim;
        for k in mass.col_ptr()[j]..mass.col_ptr()[j + 1] {
            let i = mass.row_idx()[k];
            if i % dim == d && i / dim < points.len() {
                num[d] += mass.val()[k] * points[j / dim][d];
                den[d] += mass.val()[k];
            }
        }
    }
    let mut c = [0.0; 3];
    for d in 0..dim {
        if den[d] <= 0.0 || !den[d].is_finite() {
            return None;
        }
        c[d] = num[d] / den[d];
    }
    Some(c)
}

/// The velocity of each dof (`p·dim + d`, as [`centre_of_mass`]) in the rigid motion
/// `v(x) = v₀ + ω × (x − c)`: `v₀` one value per component, `ω` the angular velocity
/// (rad/s; three values in 3-D, one — about z — in 2-D, none in 1-D), `c` the point it
/// turns about.
pub fn rigid_velocity(
    points: &[[f64; 3]],
    dim: usize,
    v0: &[f64],
    omega: &[f64],
    c: [f64; 3],
) -> Vec<f64> {
    let w = match (dim, omega) {
        (3, &[x, y, z]) => [x, y, z],
        (2, &[z]) => [0.0, 0.0, z],
        _ => [0.0; 3],
    };
    let mut v = Vec::with_capacity(points.len() * dim);
    for p in points {
        let r = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
        let wxr = [
            w[1] * r[2] - w[2] * r[1],
            w[2] * r[0] - w[0] * r[2],
            w[0] * r[1] - w[1] * r[0],
        ];
        v.extend((0..dim).map(|d| v0.get(d).copied().unwrap_or(0.0) + wxr[d]));
    }
    v
}
