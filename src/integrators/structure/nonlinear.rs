//! The structural side of the θ-method Newton loop for a nonlinear structure
//! ([`crate::model::system::Linearity::ConstantMass`] and
//! [`crate::model::system::Linearity::Nonlinear`]): eq. 41–48 with
//! `M(q) = M + ΔM(q)` and `F(t, q, v) = f(t) − Cv − Kq − r(q, v)`.
//!
//! The Newton unknown is the velocity `v` of the end of the step; positions follow from
//! eq. 18b with the projection of the last iterate, `q(v) = q_k + h(θv + (1−θ)v_k) + NGτ`,
//! and `F` is evaluated at the θ-point `q_θ = θq + (1−θ)q_k`, `v_θ = θv + (1−θ)v_k`
//! (eq. 41). At an iterate `vⁿ` the linearization of eq. 45 without contact gives the
//! free velocity of the iteration,
//!
//! `M̂ⁿ (v_freeⁿ − vⁿ) = −M(q_θⁿ)(vⁿ − v_k) + hF(t_{k+θ}, q_θⁿ, v_θⁿ)`,
//! `M̂ⁿ = M(q_θⁿ) + hθCⁿ + h²θ²Kⁿ` (eq. 47, `Kⁿ = K + ∂r/∂q`, `Cⁿ = C + ∂r/∂v` at the
//! θ-point; the derivative of `M(q)` is left out, the paper's semi-Newton of sec. 4.3),
//!
//! and the contact problem of the iteration (eq. 56–58) is solved on
//! `v = v_freeⁿ + M̂ⁿ⁻¹ G P` exactly as in the linear case, with `W = GᵀM̂ⁿ⁻¹G`. The
//! projection's feedback on the velocity (the `hθKⁿGτⁿ` term of eq. 56a) is already in
//! `F(q_θⁿ)`, whose `q` carries the last `τ`: nothing is added for it. For a linear `F`
//! one iteration from `v⁰ = v_k`, `τ⁰ = 0` gives the linear scheme's free velocity.
//!
//! Convergence (eq. 41, 49, sec. 4.3.2): the residual `R = M(v − v_k) − hF_θ − GP`
//! relative to the largest of its terms (the element forces that cancel at a node
//! included, which sets the rounding floor) below the Newton tolerance; with a
//! nonlinear `G` also the change of `q` between iterates relative to the step's increment
//! (the linearized gaps of eq. 49), as for a linear structure. Full Newton refactors `M̂ⁿ`
//! at every iterate; modified Newton ([`super::NewtonParams::modified`]) forms it at the
//! step's first iterate and keeps it while the iterates contract (each change at most
//! half the previous one), so a checkpoint needs nothing of it and a resume stays
//! bitwise. A later index-set round of Algorithm 2 restarts from the velocity the last
//! loop converged to, on the iteration matrix in hand. `W_D` is not formed: nothing
//! reads it on this path.
//!
//! With [`super::SchemeParams::energy_momentum`] (θ = 1/2) a part that offers it gives
//! its force as the discrete gradient between `q_k` and `q` instead of `r(q_θ)`
//! ([`crate::model::system::NonlinearPart::evaluate_discrete_gradient`]), with the
//! midpoint tangent in `Kⁿ` (an approximation of the exact Jacobian, good to `O(Δq)`:
//! the loop converges a little slower, to the same tolerance); then
//! `½v₁ᵀMv₁ − ½v₀ᵀMv₀ = −r·Δq = −ΔW` for a free body, exactly at convergence.
//!
//! Set-up builds one pattern, the union of `M`, `K`, `C` and the parts' tangents and
//! masses, with the position of every source entry in it; an iterate then only adds
//! values into buffers sized at set-up (no allocation in the step). A symmetric `M̂ⁿ`
//! is factored by sparse `L D Lᵀ`; a nonsymmetric one (gyroscopic terms) by LU, dense
//! below [`DENSE_MAX`] dofs (rigid multibody models), sparse above.

use faer::sparse::SymbolicSparseColMat;

use super::{StepData, StructureModel, add_step_loads};
use crate::error::Error;
use crate::integrators::StepStats;
use crate::integrators::step_matrix::{StepAnalysis, StepForm, StepMatrix};
use crate::linalg::{FactorPlan, LinearSolver, SolverKind, SparseMatrix};
use crate::model::LinearSystem;

/// The name of `M̂ⁿ` in errors and summaries.
pub const MATRIX_NAME: &str = "iteration matrix M(q) + hθCⁿ + h²θ²Kⁿ";

/// Largest structure factored by the dense LU when `M̂ⁿ` is nonsymmetric (module doc).
pub const DENSE_MAX: usize = 64;

/// Where each part's entries sit in the union pattern, and their values.
#[derive(Debug, Default)]
struct Entries {
    pos: Vec<Vec<usize>>,
    val: Vec<Vec<f64>>,
}

impl Entries {
    fn new(entries: &[Vec<(usize, usize)>], col_ptr: &[usize], row_idx: &[usize]) -> Self {
        Entries {
            pos: entries
                .iter()
                .map(|e| {
                    e.iter()
                        .map(|&(i, j)| position(col_ptr, row_idx, i, j))
                        .collect()
                })
                .collect(),
            val: entries.iter().map(|e| vec![0.0; e.len()]).collect(),
        }
    }

    /// `out += scale · values` at their positions.
    fn add_to(&self, scale: f64, out: &mut [f64]) {
        for (p, v) in self.pos.iter().zip(&self.val) {
            for (&k, &x) in p.iter().zip(v) {
                out[k] += scale * x;
            }
        }
    }

    fn is_empty(&self) -> bool {
        self.pos.iter().all(|p| p.is_empty())
    }
}

/// Set-up data and buffers of the structural Newton iteration (module doc).
#[derive(Debug)]
pub struct NonlinearStructure {
    /// `M`, `K`, `C` on the union pattern.
    mass: Vec<f64>,
    stiffness: Vec<f64>,
    damping: Vec<f64>,
    /// Each part's `∂r/∂q`, `∂r/∂v` and `ΔM(q)` entries.
    tan: Entries,
    damp: Entries,
    dmass: Entries,
    /// Some part has `ΔM(q)` entries.
    has_mass: bool,
    /// `M̂ⁿ` is symmetric (module doc).
    symmetric: bool,
    /// `M(q_θ)` on the union pattern (with a mass part).
    mass_now: Vec<f64>,
    /// `M(q_θ)(v − v_k)` (with a mass part).
    mdv: Vec<f64>,
    /// `Kⁿ` on the union pattern (the `K` of `W_D`).
    tangent: SparseMatrix,
    /// `M̂ⁿ` on the union pattern.
    step_matrix: SparseMatrix,
    /// Modified Newton (module doc).
    modified: bool,
    /// Discrete-gradient internal forces where a part has them (module doc).
    energy_momentum: bool,
    /// `K q_θ + r(q_θ)` of the last evaluation.
    internal: Vec<f64>,
    /// `|K| |q_θ|` (row sums of the magnitudes of the terms of `K q_θ`).
    size: Vec<f64>,
    /// `h f(t_{k+θ})` plus loads and prescribed-dof terms of the step.
    ext: Vec<f64>,
    /// `q_θ`, `v_θ`, `v − v_k` of the iterate.
    q_theta: Vec<f64>,
    v_theta: Vec<f64>,
    dv: Vec<f64>,
    /// The iterate's `−M(v − v_k) + hF_θ` (then `v_free − v`).
    rhs: Vec<f64>,
    /// Scale of the residual's terms at the last evaluation: the largest of `|M(v − v_k)|`,
    /// `|ext|`, `h|Cv_θ|`, `h|Kq_θ + r|` and `h |K||q_θ|` over the dofs (the last, the
    /// size of the element forces that cancel at a node, sets the rounding floor: on the
    /// hex8 bar at 2e-5 strain, relative to the net forces alone, the residual stalled at
    /// 2e-10 and the loop ran to its stagnation rule, 7 iterations per step).
    scale: f64,
    /// `rhs` is that of the current iterate (set by the residual check, used by a
    /// linearization without tangent).
    rhs_at_iterate: bool,
    /// The structure is linearized at the step's first iterate (`v = v_k`, `τ = 0`): a
    /// Newton loop starting now needs no new evaluation.
    at_first_iterate: bool,
}

/// Where entry `(i, j)` sits in the compressed columns `(col_ptr, row_idx)`.
fn position(col_ptr: &[usize], row_idx: &[usize], i: usize, j: usize) -> usize {
    let r = col_ptr[j]..col_ptr[j + 1];
    col_ptr[j]
        + row_idx[r]
            .binary_search(&i)
            .expect("entry in the union pattern")
}

impl NonlinearStructure {
    /// The union pattern of `sys`'s matrices and internal forces, and the buffers.
    pub fn new(sys: &LinearSystem, modified: bool, energy_momentum: bool) -> Self {
        let n = sys.ndof();
        let mut cols: Vec<Vec<usize>> = (0..n).map(|j| vec![j]).collect();
        let mats: Vec<&SparseMatrix> =
            [Some(&sys.mass), Some(&sys.stiffness), sys.damping.as_ref()]
                .into_iter()
                .flatten()
                .collect();
        for m in &mats {
            let m = m.as_ref();
            for (j, col) in cols.iter_mut().enumerate() {
                col.extend_from_slice(&m.row_idx()[m.col_ptr()[j]..m.col_ptr()[j + 1]]);
            }
        }
        let entries: Vec<Vec<(usize, usize)>> =
            sys.nonlinear.iter().map(|f| f.tangent_entries()).collect();
        let damping_entries: Vec<Vec<(usize, usize)>> =
            sys.nonlinear.iter().map(|f| f.damping_entries()).collect();
        let mass_entries: Vec<Vec<(usize, usize)>> =
            sys.nonlinear.iter().map(|f| f.mass_entries()).collect();
        for e in entries.iter().chain(&damping_entries).chain(&mass_entries) {
            for &(i, j) in e {
                cols[j].push(i);
            }
        }
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        for mut c in cols {
            c.sort_unstable();
            c.dedup();
            row_idx.extend_from_slice(&c);
            col_ptr.push(row_idx.len());
        }
        let nnz = row_idx.len();
        let on_pattern = |m: Option<&SparseMatrix>| {
            let mut v = vec![0.0; nnz];
            if let Some(m) = m {
                let m = m.as_ref();
                for j in 0..n {
                    for k in m.col_ptr()[j]..m.col_ptr()[j + 1] {
                        v[position(&col_ptr, &row_idx, m.row_idx()[k], j)] += m.val()[k];
                    }
                }
            }
            v
        };
        let mass = on_pattern(Some(&sys.mass));
        let stiffness = on_pattern(Some(&sys.stiffness));
        let damping = on_pattern(sys.damping.as_ref());
        let tan = Entries::new(&entries, &col_ptr, &row_idx);
        let damp = Entries::new(&damping_entries, &col_ptr, &row_idx);
        let dmass = Entries::new(&mass_entries, &col_ptr, &row_idx);
        let has_mass = !dmass.is_empty();
        let sym = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        NonlinearStructure {
            tangent: SparseMatrix::new(sym.clone(), stiffness.clone()),
            step_matrix: SparseMatrix::new(sym, mass.clone()),
            mass_now: if has_mass { mass.clone() } else { Vec::new() },
            mdv: vec![0.0; if has_mass { n } else { 0 }],
            mass,
            stiffness,
            damping,
            tan,
            damp,
            dmass,
            has_mass,
            symmetric: sys.symmetric(),
            modified,
            energy_momentum,
            internal: vec![0.0; n],
            size: vec![0.0; n],
            ext: vec![0.0; n],
            q_theta: vec![0.0; n],
            v_theta: vec![0.0; n],
            dv: vec![0.0; n],
            rhs: vec![0.0; n],
            scale: 0.0,
            rhs_at_iterate: false,
            at_first_iterate: false,
        }
    }

    /// Evaluates the iterate `(q, v)` of the step from `(q_k, v_k)` (`sys` the system the
    /// structure was built on): `rhs = −M(v − v_k)
    /// + ext − hCv_θ − h(Kq_θ + r(q_θ))` and the scale of its terms; with `tangent`,
    /// `Kⁿ` and `M̂ⁿ = M + h²θ²Kⁿ + hθC` too (not factored).
    fn evaluate(
        &mut self,
        sys: &LinearSystem,
        (h, th): (f64, f64),
        (q_k, v_k): (&[f64], &[f64]),
        (q, v): (&[f64], &[f64]),
        tangent: bool,
    ) -> Result<(), Error> {
        for i in 0..q.len() {
            self.q_theta[i] = th * q[i] + (1.0 - th) * q_k[i];
            self.v_theta[i] = th * v[i] + (1.0 - th) * v_k[i];
            self.dv[i] = v[i] - v_k[i];
        }
        // internal = K q_θ + r(q_θ); `size` = |K| |q_θ|, the size of the terms that
        // cancel in K q_θ (element forces balancing at a node), for the rounding floor
        self.internal.fill(0.0);
        self.size.fill(0.0);
        let k = sys.stiffness.as_ref();
        for j in 0..q.len() {
            let qj = self.q_theta[j];
            for p in k.col_ptr()[j]..k.col_ptr()[j + 1] {
                let (i, t) = (k.row_idx()[p], k.val()[p] * qj);
                self.internal[i] += t;
                self.size[i] += t.abs();
            }
        }
        for ((f, t), d) in sys
            .nonlinear
            .iter()
            .zip(self.tan.val.iter_mut())
            .zip(self.damp.val.iter_mut())
        {
            if self.energy_momentum && f.has_discrete_gradient() {
                f.evaluate_discrete_gradient(
                    q_k,
                    q,
                    &mut self.internal,
                    tangent.then_some(&mut t[..]),
                )?;
            } else {
                f.evaluate(
                    &self.q_theta,
                    &self.v_theta,
                    &mut self.internal,
                    tangent.then_some(&mut t[..]),
                    tangent.then_some(&mut d[..]),
                )?;
            }
        }
        if self.has_mass {
            // M(q_θ) (v − v_k), column by column on the union pattern
            for (f, m) in sys.nonlinear.iter().zip(self.dmass.val.iter_mut()) {
                f.mass(&self.q_theta, m);
            }
            self.mass_now.copy_from_slice(&self.mass);
            self.dmass.add_to(1.0, &mut self.mass_now);
            let p = self.step_matrix.as_ref();
            let (cp, ri) = (p.col_ptr(), p.row_idx());
            self.mdv.fill(0.0);
            for j in 0..q.len() {
                let dj = self.dv[j];
                for k in cp[j]..cp[j + 1] {
                    self.mdv[ri[k]] += self.mass_now[k] * dj;
                }
            }
        }
        // M and C are symmetric: their columns are their rows, each row a gather
        let row = |a: faer::sparse::SparseColMatRef<'_, usize, f64>, i: usize, x: &[f64]| {
            let r = a.col_ptr()[i]..a.col_ptr()[i + 1];
            a.row_idx()[r.clone()]
                .iter()
                .zip(&a.val()[r])
                .map(|(&j, &v)| v * x[j])
                .sum::<f64>()
        };
        let (m, c) = (sys.mass.as_ref(), sys.damping.as_ref().map(|c| c.as_ref()));
        let mut scale = 0.0_f64;
        for i in 0..q.len() {
            let md = if self.has_mass {
                self.mdv[i]
            } else {
                row(m, i, &self.dv)
            };
            let cv = h * c.map_or(0.0, |c| row(c, i, &self.v_theta));
            let int = h * self.internal[i];
            scale = scale
                .max(h * self.size[i])
                .max(md.abs())
                .max(cv.abs())
                .max(int.abs())
                .max(self.ext[i].abs());
            self.rhs[i] = self.ext[i] - cv - int - md;
        }
        self.scale = scale;
        if tangent {
            let t = self.tangent.val_mut();
            t.copy_from_slice(&self.stiffness);
            self.tan.add_to(1.0, t);
            let (a, b) = StepForm::Theta { theta: th }.coefficients(h);
            let t = self.tangent.val();
            let mass = if self.has_mass {
                &self.mass_now
            } else {
                &self.mass
            };
            for (((s, &mm), &kk), &cc) in self
                .step_matrix
                .val_mut()
                .iter_mut()
                .zip(mass)
                .zip(t)
                .zip(&self.damping)
            {
                *s = mm + a * kk + b * cc;
            }
            // hθ ∂r/∂v
            self.damp.add_to(b, self.step_matrix.val_mut());
        }
        Ok(())
    }

    /// Factors `M̂` at set-up (symmetric: sparse `L D Lᵀ`, which also takes the
    /// indefinite tangents of a body near buckling as long as no pivot vanishes;
    /// nonsymmetric: LU, dense up to [`DENSE_MAX`] dofs).
    fn factor_step_matrix(&self) -> Result<Box<dyn LinearSolver>, Error> {
        let kind = if self.symmetric {
            SolverKind::Ldlt
        } else if self.step_matrix.nrows() <= DENSE_MAX {
            SolverKind::Dense
        } else {
            SolverKind::Lu
        };
        crate::linalg::solver::factor(self.step_matrix.as_ref(), MATRIX_NAME, kind, None)
    }
}

impl NonlinearStructure {
    /// Linearizes at the step's first iterate `v⁰ = v_k`, `τ⁰ = 0` (`q⁰ = q_k + h v_k`):
    /// factors `M̂⁰` and sets the free velocity.
    fn first_iterate(&mut self, cx: &mut StepData<'_>, stats: &mut StepStats) -> Result<(), Error> {
        let s = cx.state;
        cx.v_new.copy_from_slice(&s.v);
        for ((qn, q), v) in cx.q_new.iter_mut().zip(&s.q).zip(&s.v) {
            *qn = q + cx.h * v;
        }
        self.linearize(cx, true, stats)?;
        self.at_first_iterate = true;
        Ok(())
    }

    /// Evaluates the structure at the iterate `(q_new, v_new)`: with `tangent` refactors
    /// `M̂ⁿ`; sets `v_free = vⁿ + M̂ⁿ⁻¹(−M(vⁿ − v_k) + hF_θⁿ)` (eq. 45 without contact
    /// impulse).
    fn linearize(
        &mut self,
        cx: &mut StepData<'_>,
        tangent: bool,
        stats: &mut StepStats,
    ) -> Result<(), Error> {
        if tangent || !self.rhs_at_iterate {
            self.evaluate_timed(cx, tangent, stats)?;
        }
        self.rhs_at_iterate = false;
        if tangent {
            let t0 = std::time::Instant::now();
            cx.factor.refactor(self.step_matrix.as_ref(), MATRIX_NAME)?;
            stats.factorizations += 1;
            stats.factorization_seconds += t0.elapsed().as_secs_f64();
        }
        cx.work.copy_from_slice(&self.rhs);
        cx.factor.solve_in_place(cx.work);
        for ((vf, v), w) in cx
            .v_free
            .iter_mut()
            .zip(cx.v_new.iter())
            .zip(cx.work.iter())
        {
            *vf = v + w;
        }
        self.at_first_iterate = false;
        Ok(())
    }

    /// [`NonlinearStructure::evaluate`] at the iterate `(q_new, v_new)` (with `tangent`,
    /// `Kⁿ` and `M̂ⁿ` too), timed into `stats`; an inverted cell is an error.
    fn evaluate_timed(
        &mut self,
        cx: &StepData<'_>,
        tangent: bool,
        stats: &mut StepStats,
    ) -> Result<(), Error> {
        let s = cx.state;
        let t0 = std::time::Instant::now();
        self.evaluate(
            cx.sys,
            (cx.h, cx.theta),
            (&s.q, &s.v),
            (cx.q_new, cx.v_new),
            tangent,
        )?;
        stats.assembly_seconds += t0.elapsed().as_secs_f64();
        Ok(())
    }
}

impl StructureModel for NonlinearStructure {
    fn step_matrix_constant(&self) -> bool {
        false
    }

    /// The pattern's symbolic analysis, on `M̂ⁿ` at the initial state (the mass alone is
    /// singular where `mass = "redistributed"` leaves contact nodes none, issue 34); the
    /// first step forms its own values.
    fn factor(
        &mut self,
        sys: &LinearSystem,
        (form, h): (StepForm, f64),
        (q0, v0): (&[f64], &[f64]),
        _: Option<StepMatrix>,
    ) -> Result<Box<dyn LinearSolver>, Error> {
        self.evaluate(sys, (h, form.theta()), (q0, v0), (q0, v0), true)?;
        self.factor_step_matrix()
    }

    /// The symbolic analysis of the structure's own pattern (the union of `M`, `K`, `C`
    /// and its parts' tangents), with the backend [`NonlinearStructure::factor`] takes:
    /// `LDLᵀ` when symmetric, dense LU up to [`DENSE_MAX`] dofs, sparse LU (its fill
    /// estimated by the symmetric pattern's) past them. Nothing is kept: each step
    /// forms its own values.
    fn analyse(&self, _: &LinearSystem, _: StepForm, _: f64) -> Result<StepAnalysis, Error> {
        let step = self.step_matrix.as_ref();
        let n = step.nrows();
        let factor = if self.symmetric {
            crate::linalg::analyse_ldlt(step, MATRIX_NAME)?
        } else if n <= DENSE_MAX {
            FactorPlan {
                backend: "dense LU".to_string(),
                entries: (n * n) as u64,
                scratch_bytes: 0,
                supernodal: false,
            }
        } else {
            let f = crate::linalg::analyse_ldlt(step, MATRIX_NAME)?;
            FactorPlan {
                backend: format!("faer LU (fill after pivoting; about {} entries)", f.entries),
                ..f
            }
        };
        Ok(StepAnalysis {
            factor,
            matrix_entries: step.val().len() as u64,
            kept: None,
        })
    }

    fn tangent<'a>(&'a self, _: &'a LinearSystem) -> &'a SparseMatrix {
        &self.tangent
    }

    /// The step's loads, then the first Newton iterate (`M̂⁰` factored).
    fn begin_step(&mut self, cx: &mut StepData<'_>, stats: &mut StepStats) -> Result<bool, Error> {
        let h = cx.h;
        for (e, f) in self.ext.iter_mut().zip(&cx.sys.force) {
            *e = h * f;
        }
        add_step_loads(
            cx.sys,
            (cx.state.time, h, cx.theta),
            (&mut *cx.vp.0, &mut *cx.vp.1),
            &mut self.ext,
        );
        self.first_iterate(cx, stats)?;
        Ok(true)
    }

    /// From the first iterate again when the last loop did not converge; otherwise from
    /// the velocity it converged to, with `τ = 0` (`q = q_k + h v_θ`), on the iteration
    /// matrix in hand: the same fixed point from a closer start and without a
    /// factorization (ball of `meshes/ball_crush.toml`, full Newton, Algorithm 2 at
    /// h = 1e-4: 3.32 → 2.56 factorizations per step, modified Newton 1.71 → 1.0).
    fn restart(
        &mut self,
        cx: &mut StepData<'_>,
        last_converged: bool,
        stats: &mut StepStats,
    ) -> Result<Option<bool>, Error> {
        if self.at_first_iterate {
            return Ok(None);
        }
        if !last_converged {
            self.first_iterate(cx, stats)?;
            return Ok(Some(true));
        }
        let (h, th) = (cx.h, cx.theta);
        let s = cx.state;
        for (((qn, q), v), vn) in cx.q_new.iter_mut().zip(&s.q).zip(&s.v).zip(cx.v_new.iter()) {
            *qn = q + h * (th * vn + (1.0 - th) * v);
        }
        self.linearize(cx, false, stats)?;
        Ok(Some(false))
    }

    /// Full Newton refactors at every iterate; modified Newton when the last change was
    /// not at most half the one before.
    fn relinearize(
        &mut self,
        cx: &mut StepData<'_>,
        (change, change_before): (f64, f64),
        stats: &mut StepStats,
    ) -> Result<bool, Error> {
        let tangent = !self.modified || change > 0.5 * change_before;
        self.linearize(cx, tangent, stats)?;
        Ok(tangent)
    }

    /// `‖M(v − v_k) − hF_θ − GP‖∞` relative to the largest of its terms (0 below 64 ulps
    /// of that scale).
    fn residual(
        &mut self,
        cx: &mut StepData<'_>,
        stats: &mut StepStats,
    ) -> Result<Option<f64>, Error> {
        self.evaluate_timed(cx, false, stats)?;
        // the next linearization, at this iterate, can reuse the right-hand side
        self.rhs_at_iterate = true;
        // work = −R = rhs + G P
        cx.work.copy_from_slice(&self.rhs);
        let mut gp = 0.0_f64;
        for (a, &p) in cx.p.iter().enumerate() {
            if p != 0.0 {
                cx.jac.axpy(a, p, cx.work);
                gp = gp.max(p.abs());
            }
        }
        let scale = self.scale.max(gp);
        let r = cx.work.iter().fold(0.0_f64, |a, x| a.max(x.abs()));
        Ok(Some(if r <= 64.0 * f64::EPSILON * scale {
            0.0
        } else {
            r / scale.max(f64::MIN_POSITIVE)
        }))
    }

    fn describe(&self, sys: &LinearSystem, backend: &str, n: usize) -> String {
        format!(
            "nonlinear structure ({}): {} Newton on eq. 41–48{}, M̂ⁿ = M(q) + hθCⁿ + \
             h²θ²Kⁿ refactored {} ({backend}, n = {n}){}",
            sys.nonlinear
                .iter()
                .map(|f| f.describe())
                .collect::<Vec<_>>()
                .join(", "),
            if self.modified { "modified" } else { "full" },
            if self.energy_momentum {
                " with discrete-gradient internal forces (energy–momentum)"
            } else {
                ""
            },
            if self.modified {
                "at each step's first iterate and when the iterates stop contracting"
            } else {
                "at every iterate"
            },
            if self.symmetric {
                ""
            } else {
                "; M̂ⁿ nonsymmetric: projection metric Euclidean, LCPs by Lemke"
            }
        )
    }
}
