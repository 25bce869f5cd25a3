//! Each body's mass, centre of mass, linear momentum and angular momentum (about its
//! centre of mass) in a state `(q, v)` of the assembled structure: what a user of
//! impact studies checks a spinning or glancing body against.
//!
//! With `M` the mass matrix of the kept dofs, `x = X + u` the current positions and
//! `M v` the nodal momenta, per body `b` and component `d`:
//! `m = Σ_{i,j ∈ b, d} M_ij` (the component-`d` block's sum, the same for every `d`),
//! `c_d = Σ M_ij x_j / m`, `p_d = Σ M_ij v_j`, and `L = Σ_i (x_i − c) × (M v)_i`.
//! With the consistent mass of isoparametric cells these are the integrals `∫ρ`,
//! `∫ρx / ∫ρ`, `∫ρv` and `∫ρ (x − c) × v` of the interpolated fields (`Σ N_i x_i = x`)
//! to the mass matrix's own quadrature: exactly for tri3, tet4 and parallelepiped quad4
//! and hex8 cells, whose `ρ N_i N_j det J` it integrates exactly; with a lumped or
//! redistributed mass they are the discrete model's own. The sums cover the kept
//! dofs: a fixed or prescribed component adds nothing (exact for free bodies, which
//! are the ones whose momentum a user expects to be conserved). A plane body has `L`
//! along z only; a rod (one component) has no angular momentum; an axisymmetric scene
//! is not measured (its radial dofs carry no momentum of the revolved body).

use super::geometry::Geometry;
use crate::linalg::SparseMatrix;

/// One body's measures in one state (SI units; zeros where a component does not exist).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BodyState {
    /// Mass of its kept dofs (kg).
    pub mass: f64,
    /// Centre of mass in the current configuration (m).
    pub centre: [f64; 3],
    /// Linear momentum (kg·m/s).
    pub momentum: [f64; 3],
    /// Angular momentum about the centre of mass (kg·m²/s); about the origin it is
    /// `angular_momentum + centre × momentum`.
    pub angular_momentum: [f64; 3],
}

/// The dof map [`BodyState`]s are measured through, built once per model; measuring
/// then allocates nothing (the step loop's history may call it).
#[derive(Clone, Debug)]
pub struct BodyMeasures {
    dim: usize,
    /// Per kept dof: its body and component, and the dofs of its point's components
    /// (`NONE` where a component is fixed or prescribed).
    of_dof: Vec<Slot>,
    /// Reference coordinates of the points.
    points: Vec<[f64; 3]>,
    /// Per body, the component-`d` mass sums.
    sums: Vec<[f64; 3]>,
    /// `M v` (one entry per kept dof).
    mv: Vec<f64>,
    /// `M 1`, each dof's share of its body's mass (formed at the first measure).
    row_sums: Vec<f64>,
    row_sums_ready: bool,
}

const NONE: u32 = u32::MAX;

/// 24 bytes per dof (indices as `u32`: [`BodyMeasures::new`] refuses a model past
/// `u32::MAX` points or dofs).
#[derive(Clone, Copy, Debug)]
struct Slot {
    point: u32,
    body: u32,
    component: u32,
    /// The dofs of the point's components (`NONE`: not a kept dof).
    siblings: [u32; 3],
}

impl BodyMeasures {
    /// The map of `geom` for a system of `ndof` kept dofs; `None` where `geom` maps no
    /// dof to a point of a body (the academic examples, which have no mesh), or past
    /// `u32::MAX` points, dofs or bodies.
    pub fn new(geom: &Geometry, ndof: usize) -> Option<Self> {
        let dim = geom.dim;
        let fits = |n: usize| u32::try_from(n).is_ok_and(|n| n < NONE);
        // an axisymmetric body's dofs are the half-section's (r, z): summing its radial
        // components gives no momentum of the ring, so no such scene is measured
        let axisymmetric = geom
            .bodies
            .iter()
            .any(|(_, f)| matches!(f, crate::model::solid::Formulation::Axisymmetric));
        if !(1..=3).contains(&dim)
            || axisymmetric
            || geom.bodies.is_empty()
            || !fits(ndof)
            || !fits(geom.points.len())
            || !fits(geom.bodies.len())
        {
            return None;
        }
        let mut body_of_point = vec![NONE; geom.points.len()];
        for (_, nodes, b) in &geom.cells {
            for &p in nodes {
                if let Some(x) = body_of_point.get_mut(p) {
                    *x = *b as u32;
                }
            }
        }
        let empty = Slot {
            point: NONE,
            body: NONE,
            component: 0,
            siblings: [NONE; 3],
        };
        let mut of_dof = vec![empty; ndof];
        for (p, slots) in geom.dof_of.chunks(dim).enumerate() {
            let b = body_of_point.get(p).copied().unwrap_or(NONE);
            if b as usize >= geom.bodies.len() {
                continue;
            }
            let mut siblings = [NONE; 3];
            for (c, d) in slots.iter().enumerate() {
                siblings[c] = d.filter(|&d| d < ndof).map_or(NONE, |d| d as u32);
            }
            for (c, &d) in siblings.iter().enumerate().take(dim) {
                if d != NONE {
                    of_dof[d as usize] = Slot {
                        point: p as u32,
                        body: b,
                        component: c as u32,
                        siblings,
                    };
                }
            }
        }
        if of_dof.iter().all(|s| s.point == NONE) {
            return None;
        }
        Some(BodyMeasures {
            dim,
            of_dof,
            points: geom.points.clone(),
            sums: vec![[0.0; 3]; geom.bodies.len()],
            mv: vec![0.0; ndof],
            row_sums: vec![0.0; ndof],
            row_sums_ready: false,
        })
    }

    /// Number of bodies measured.
    pub fn bodies(&self) -> usize {
        self.sums.len()
    }

    /// Displacement components per point (1, 2 or 3).
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Each body's [`BodyState`] at `(q, v)` with the mass matrix `mass` of the kept
    /// dofs, into `out` (one per body; bodies beyond `out` are skipped). One product
    /// `M v` and two passes over the dofs: the masses and centres read the row sums
    /// `M 1` (formed at the first call: `M` is the model's constant mass), the momenta
    /// `Σ (M v)_i`, the angular momenta `Σ (x_i − c) × (M v)_i` (`M` couples no two
    /// components and no two bodies, so every sum is exact).
    pub fn measure(&mut self, mass: &SparseMatrix, q: &[f64], v: &[f64], out: &mut [BodyState]) {
        let m = mass.as_ref();
        let n = self
            .of_dof
            .len()
            .min(m.ncols())
            .min(m.nrows())
            .min(q.len())
            .min(v.len());
        out.iter_mut().for_each(|s| *s = BodyState::default());
        self.sums.iter_mut().for_each(|s| *s = [0.0; 3]);
        if self.mv.len() != m.nrows() || v.len() < m.ncols() {
            return; // not this model's mass matrix or state: nothing measured
        }
        crate::linalg::spmv(m, &v[..m.ncols()], &mut self.mv);
        self.accumulate(mass, q, n, out);
    }

    /// [`BodyMeasures::measure`] with `M v` given (`mv`, as
    /// [`crate::model::LinearSystem::energies_keeping_mv`] leaves it): no product.
    pub fn measure_with(
        &mut self,
        mass: &SparseMatrix,
        q: &[f64],
        mv: &[f64],
        out: &mut [BodyState],
    ) {
        let n = self.of_dof.len().min(q.len());
        out.iter_mut().for_each(|s| *s = BodyState::default());
        self.sums.iter_mut().for_each(|s| *s = [0.0; 3]);
        if mv.len() != self.mv.len() || mass.as_ref().ncols() != self.mv.len() {
            return;
        }
        self.mv.copy_from_slice(mv);
        self.accumulate(mass, q, n, out);
    }

    /// The measures from `self.mv` (= `M v`) and the positions `q`.
    fn accumulate(&mut self, mass: &SparseMatrix, q: &[f64], n: usize, out: &mut [BodyState]) {
        let m = mass.as_ref();
        let nb = out.len().min(self.sums.len());
        if !self.row_sums_ready {
            // `M` is symmetric: its row sums are its column sums
            for (j, r) in self.row_sums.iter_mut().enumerate().take(m.ncols()) {
                *r = m.val()[m.col_ptr()[j]..m.col_ptr()[j + 1]].iter().sum();
            }
            self.row_sums_ready = true;
        }
        for j in 0..n {
            let sj = self.of_dof[j];
            let b = sj.body as usize;
            if sj.point == NONE || b >= nb {
                continue;
            }
            let (p, d) = (sj.point as usize, sj.component as usize);
            let r = self.row_sums[j];
            out[b].centre[d] += r * (self.points[p][d] + q[j]);
            out[b].momentum[d] += self.mv[j];
            self.sums[b][d] += r;
        }
        for (s, sums) in out.iter_mut().zip(&self.sums) {
            s.mass = sums[0];
            for d in 0..self.dim {
                s.centre[d] = if sums[d] > 0.0 {
                    s.centre[d] / sums[d]
                } else {
                    0.0
                };
            }
        }
        if self.dim < 2 {
            return;
        }
        for i in 0..n {
            let si = self.of_dof[i];
            if si.point == NONE || si.body as usize >= nb {
                continue;
            }
            let (p, s) = (si.point as usize, &mut out[si.body as usize]);
            let r: [f64; 3] = std::array::from_fn(|c| {
                if c >= self.dim {
                    return 0.0;
                }
                let u = q.get(si.siblings[c] as usize).copied().unwrap_or(0.0);
                self.points[p][c] + u - s.centre[c]
            });
            let f = self.mv[i];
            // L += r × (f e_d)
            let l = &mut s.angular_momentum;
            match si.component {
                0 => {
                    l[1] += r[2] * f;
                    l[2] -= r[1] * f;
                }
                1 => {
                    l[0] -= r[2] * f;
                    l[2] += r[0] * f;
                }
                _ => {
                    l[0] += r[1] * f;
                    l[1] -= r[0] * f;
                }
            }
        }
    }
}
