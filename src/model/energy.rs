//! The energy balance of a run: what the structure holds against what its loads and
//! prescribed motion supplied, so that a run whose energy grows beyond that is stopped
//! (DESIGN.md §9; issue 16 §2).
//!
//! The energy is the whole structure's, prescribed dofs included
//! ([`LinearSystem::energies`]): kinetic, elastic, and the potential of the constant
//! forces such as gravity. What enters it from outside is summed step by step on the
//! kept dofs' displacement `Δq = q_{k+1} − q_k`, as the θ-method applies it:
//!
//! - the time-dependent loads (`[[forces]]`) at `t_{k+θ}`: `φ(t_{k+θ}) bᵀ Δq`;
//! - the prescribed dofs through their coupling blocks, the force the scheme adds to the
//!   kept dofs (`integrators::core`):
//!   `h F_c = −M_fp (v_p(t_{k+1}) − v_p(t_k)) − h C_fp v_p(t_{k+θ}) − h K_fp u_p(t_{k+θ})`,
//!   work `F_cᵀ Δq`; the supports then supply that work plus the change of the energy the
//!   prescribed dofs add ([`super::Prescribed::energy`]), which is what
//!   [`EnergyAudit::work`] reports.
//!
//! For the θ-method (eq. 18) with `q_{k+1} = q_k + h(θ v_{k+1} + (1 − θ) v_k)`, on the kept
//! dofs, this is the discrete energy identity: `ΔE = W − (θ − ½)(ΔvᵀMΔv + ΔqᵀKΔq) −
//! h v_θᵀ C v_θ +` the contact impulses' work, which is at most 0 for Newton's law with
//! `e ≤ 1` and for Coulomb friction. So `E − E₀ − W` is at most round-off for θ = ½
//! without contact, and negative otherwise, up to what the position projections of
//! Algorithms 1 and 2 and the tolerances move: [`EnergyAudit::excess`] measures it
//! against the run's energy scale. Written here because the balance is the scheme's own,
//! not a library's.
//!
//! The scale is the largest of what the run met (`|E|`, the kinetic energy, `Σ|ΔW|`) and a
//! floor from the scene's own magnitudes ([`EnergyFloor`]): a body that holds nothing
//! but round-off (clamped, resting under gravity, displaced rigidly) would otherwise
//! measure its round-off against itself and "gain 100 % of its energy". The floor is the
//! largest of
//!
//! - the work the constant forces (gravity) do over the model's size `L` (the diagonal of
//!   its bounding box): `L Σ|f_i|`, that is `m g L` for a body under gravity;
//! - the work each time-dependent load does over `L` at its largest factor:
//!   `L Σ_l max|φ_l| Σ|b_l|`;
//! - the elastic energy of the model at a uniform strain of the Newton tolerance `ε`:
//!   `½ m c² ε²` with `m` the mass of the kept dofs and `c² = E/ρ` the largest of its
//!   bodies' (`½ E V ε²` for one body).
//!
//! The first two are what the scene can supply and hold at any moment, so an energy that
//! grows by a fraction of them is no round-off; the third is the energy of a strain the
//! Newton loop does not resolve.
//!
//! The energy itself is known only to the rounding of its sums: a body displaced rigidly
//! by 0.5 m holds `½ qᵀKq` as the difference of terms of about `½ |q|ᵀ|K||q|` (1.3e6 J for
//! a 1 dm³ cube of E = 1 MPa), whose rounding (4.7e-12 J measured) is far above its own
//! energy. [`EnergyAudit::roundoff`] bounds it: [`ROUNDOFF_RELATIVE`] of the summed
//! absolute terms of the kinetic and potential energies; an excess within it is round-off,
//! whatever the scale (the run's check asks for it only when an excess passes its limit).

use super::LinearSystem;

/// What a computed energy is known to, relative to the sum of the absolute terms of its
/// quadratic forms: `10⁴ ε`, the rounding of sums of up to 10⁴ terms per row with room
/// (module doc).
pub const ROUNDOFF_RELATIVE: f64 = 1e4 * f64::EPSILON;

/// The scene's magnitudes the energy scale's floor is made of (module doc).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EnergyFloor {
    /// The model's size `L` (m): the diagonal of its bounding box (0 without geometry).
    pub size: f64,
    /// The largest `c² = E/ρ` of the model's bodies (m²/s²; 0 without bodies).
    pub wave_speed_sq: f64,
    /// The strain the Newton loop does not resolve (its relative tolerance).
    pub strain: f64,
}

impl EnergyFloor {
    /// The floor (J) on `sys` (module doc): the largest of `L Σ|f|`, `L Σ max|φ| Σ|b|`
    /// and `½ m c² ε²`; non-finite or negative terms count as 0.
    pub fn joules(&self, sys: &LinearSystem) -> f64 {
        let l = if self.size.is_finite() {
            self.size.max(0.0)
        } else {
            0.0
        };
        let mut constant: f64 = sys.force.iter().map(|f| f.abs()).sum();
        if let Some(p) = &sys.prescribed {
            constant += p.force.iter().map(|f| f.abs()).sum::<f64>();
        }
        let loads: f64 = sys
            .loads
            .iter()
            .map(|ld| ld.time.max_abs() * ld.values.iter().map(|b| b.abs()).sum::<f64>())
            .sum();
        // the mass of the kept dofs: `1ᵀ M 1` over one displacement component
        let m_ref = sys.mass.as_ref();
        let mut mass = 0.0;
        for j in 0..m_ref.ncols() {
            if sys.component.get(j).copied().unwrap_or(0) != 0 {
                continue;
            }
            for k in m_ref.col_ptr()[j]..m_ref.col_ptr()[j + 1] {
                if sys.component.get(m_ref.row_idx()[k]).copied().unwrap_or(0) == 0 {
                    mass += m_ref.val()[k];
                }
            }
        }
        let elastic = 0.5 * mass * self.wave_speed_sq * self.strain * self.strain;
        [l * constant, l * loads, elastic]
            .into_iter()
            .filter(|x| x.is_finite() && *x > 0.0)
            .fold(0.0, f64::max)
    }
}

/// What [`EnergyAudit::excess`] measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Excess {
    /// `(E − E₀ − W) / scale`.
    pub relative: f64,
    /// `E − E₀ − W` (J).
    pub joules: f64,
    /// The run's energy scale it was measured against (J).
    pub scale: f64,
    /// Kinetic energy of the whole structure (J).
    pub kinetic: f64,
    /// Potential energy of the whole structure (J).
    pub potential: f64,
}

/// The running balance of a run (module doc). Sized once; [`EnergyAudit::advance`]
/// does not allocate.
#[derive(Clone, Debug)]
pub struct EnergyAudit {
    /// The whole structure's energy at the start.
    e0: f64,
    /// What the prescribed dofs added to it at the start and at the last check.
    extra0: f64,
    extra: f64,
    /// Work done on the kept dofs so far by loads and the prescribed dofs' coupling (J).
    work: f64,
    /// Sum of the absolute work increments (J): the scale of what went in and out.
    work_abs: f64,
    /// Largest `|E|` and kinetic energy met at the checks (J).
    e_max: f64,
    /// The scale's floor from the scene's magnitudes ([`EnergyFloor`], J).
    floor: f64,
    /// `q` at the last step, kept only on the dofs loaded or coupled to prescribed ones.
    q_prev: Vec<f64>,
    /// Those dofs.
    rows: Vec<usize>,
    /// Scratch over the prescribed dofs.
    vp_a: Vec<f64>,
    vp_b: Vec<f64>,
    scratch: Vec<f64>,
}

impl EnergyAudit {
    /// Starts the balance at `(t, q, v)`, its scale floored at `floor`
    /// ([`EnergyFloor::joules`]).
    pub fn new(sys: &LinearSystem, t: f64, q: &[f64], v: &[f64], floor: f64) -> Self {
        let n = sys.ndof();
        let mut touched = vec![false; n];
        for l in &sys.loads {
            for &d in &l.dofs {
                touched[d] = true;
            }
        }
        let np = sys.prescribed.as_ref().map_or(0, |p| p.velocity.len());
        if let Some(p) = &sys.prescribed {
            let mut mark = |m: &crate::linalg::SparseMatrix| {
                for &r in m.as_ref().row_idx() {
                    touched[r] = true;
                }
            };
            mark(&p.mass);
            mark(&p.stiffness);
            if let Some(c) = &p.damping {
                mark(c);
            }
        }
        let rows: Vec<usize> = (0..n).filter(|&i| touched[i]).collect();
        let mut q_prev = vec![0.0; n];
        for &r in &rows {
            q_prev[r] = q[r];
        }
        let mut scratch = vec![0.0; 2 * np];
        let (k, u) = sys.prescribed_energy(t, q, v, &mut scratch);
        let extra0 = k + u;
        let e0 = sys.kinetic_energy(q, v) + sys.potential_energy(q) + extra0;
        EnergyAudit {
            e0,
            extra0,
            extra: extra0,
            work: 0.0,
            work_abs: 0.0,
            e_max: e0.abs(),
            floor: if floor.is_finite() {
                floor.max(0.0)
            } else {
                0.0
            },
            q_prev,
            rows,
            vp_a: vec![0.0; np],
            vp_b: vec![0.0; np],
            scratch,
        }
    }

    /// The scale's floor (J).
    pub fn floor(&self) -> f64 {
        self.floor
    }

    /// The energy at the start (J).
    pub fn initial(&self) -> f64 {
        self.e0
    }

    /// The work supplied so far by loads and prescribed motion (J), as of the last
    /// [`EnergyAudit::excess`].
    pub fn work(&self) -> f64 {
        self.work + self.extra - self.extra0
    }

    /// Adds the work of the step from `t` to `t + h` (θ-method at `theta`) that ended at
    /// `q`.
    pub fn advance(&mut self, sys: &LinearSystem, t: f64, h: f64, theta: f64, q: &[f64]) {
        let mut w = 0.0;
        let tt = t + theta * h;
        for l in &sys.loads {
            let phi = l.time.eval(tt);
            if phi != 0.0 {
                for (&d, &b) in l.dofs.iter().zip(&l.values) {
                    w += phi * b * (q[d] - self.q_prev[d]);
                }
            }
        }
        if let Some(p) = &sys.prescribed {
            // h F_c = −M_fp Δv_p − h C_fp v_p(t_{k+θ}) − h K_fp u_p(t_{k+θ}), column by
            // column, dotted with Δq on the rows it touches
            p.velocity_at(t, &mut self.vp_a);
            p.velocity_at(t + h, &mut self.vp_b);
            for (b, a) in self.vp_b.iter_mut().zip(&self.vp_a) {
                *b -= a;
            }
            let q_prev = &self.q_prev;
            let dot = |m: &crate::linalg::SparseMatrix, x: &[f64], s: f64| -> f64 {
                let m = m.as_ref();
                let mut acc = 0.0;
                for (j, &xj) in x.iter().enumerate() {
                    if xj != 0.0 {
                        for k in m.col_ptr()[j]..m.col_ptr()[j + 1] {
                            let r = m.row_idx()[k];
                            acc += m.val()[k] * xj * (q[r] - q_prev[r]);
                        }
                    }
                }
                s * acc
            };
            w += dot(&p.mass, &self.vp_b, -1.0 / h);
            p.velocity_at(tt, &mut self.vp_a);
            if let Some(c) = &p.damping {
                w += dot(c, &self.vp_a, -1.0);
            }
            p.displacement_at(tt, &mut self.vp_a);
            w += dot(&p.stiffness, &self.vp_a, -1.0);
        }
        for &r in &self.rows {
            self.q_prev[r] = q[r];
        }
        self.work += w;
        self.work_abs += w.abs();
    }

    /// `E − E₀ − W` at `(t, q, v)` (the end of the last [`EnergyAudit::advance`])
    /// relative to the run's energy scale `max(|E| met, kinetic energy met, Σ|ΔW|, floor)`;
    /// positive: energy appeared that nothing supplied. Also returns the absolute excess
    /// (J), the kinetic and the potential energy. Allocates nothing.
    pub fn excess(&mut self, sys: &LinearSystem, t: f64, q: &[f64], v: &[f64]) -> Excess {
        let (k, u) = sys.prescribed_energy(t, q, v, &mut self.scratch);
        let (kinetic, potential) = (sys.kinetic_energy(q, v) + k, sys.potential_energy(q) + u);
        let e = kinetic + potential;
        self.extra = k + u;
        self.e_max = self.e_max.max(e.abs()).max(kinetic);
        let scale = self
            .e_max
            .max(self.work_abs + (self.extra - self.extra0).abs())
            .max(self.floor)
            .max(f64::MIN_POSITIVE);
        let excess = e - self.e0 - self.work();
        Excess {
            relative: excess / scale,
            joules: excess,
            scale,
            kinetic,
            potential,
        }
    }

    /// The rounding of the energy at `(q, v)` (J): [`ROUNDOFF_RELATIVE`] times
    /// `½ |v|ᵀ|M||v| + ½ |q|ᵀ|K||q| + Σ|f_i q_i|` (the kept dofs' quadratic forms, where a
    /// rigid displacement cancels). Two passes over `M` and `K`; allocates nothing.
    pub fn roundoff(&self, sys: &LinearSystem, q: &[f64], v: &[f64]) -> f64 {
        use crate::linalg::abs_quadratic_form;
        let terms = 0.5 * abs_quadratic_form(sys.mass.as_ref(), v)
            + 0.5 * abs_quadratic_form(sys.stiffness.as_ref(), q)
            + sys
                .force
                .iter()
                .zip(q)
                .map(|(f, x)| (f * x).abs())
                .sum::<f64>();
        ROUNDOFF_RELATIVE * terms
    }

    /// The sums a checkpoint keeps: `E₀`, what the prescribed dofs added at the start and
    /// at the last check, the work, its absolute sum and the largest energy met.
    pub fn save(&self) -> [f64; 6] {
        [
            self.e0,
            self.extra0,
            self.extra,
            self.work,
            self.work_abs,
            self.e_max,
        ]
    }

    /// Restores [`EnergyAudit::save`]'s sums at the restored `q` (the last step's end).
    pub fn restore(&mut self, sums: [f64; 6], q: &[f64]) {
        [
            self.e0,
            self.extra0,
            self.extra,
            self.work,
            self.work_abs,
            self.e_max,
        ] = sums;
        for &r in &self.rows {
            self.q_prev[r] = q[r];
        }
    }
}
