//! The linear structure, `F(t, q, v) = f(t) − C v − K q` (rods, linear-elastic solids):
//! `M̂ = M + hθC + h²θ²K` (eq. 47) is constant, formed and factored once per step size
//! ([`crate::integrators::step_matrix`]), and a step's
//! only structural work is the free velocity of eq. 18 with `P = 0`,
//!
//! `M̂ (v_free − v_k) = h f(t_{k+θ}) − h C v_k − h K (q_k + hθ v_k)`,
//!
//! one sparse solve. A rod's `K` is read as its three diagonals
//! ([`crate::linalg::TridiagonalRows`], the same sums bit for bit without a gather per
//! row), and a load that is `+0.0` everywhere (the bar) as the constant.

use super::{StepData, StructureModel, add_step_loads};
use crate::error::Error;
use crate::integrators::StepStats;
use crate::integrators::step_matrix::{
    StepAnalysis, StepForm, StepMatrix, analyse_spd_step, factor_step_matrix,
};
use crate::linalg::{LinearSolver, SparseMatrix, sym_spmv_add};
use crate::model::LinearSystem;

/// The linear structure's step data (module doc).
#[derive(Debug)]
pub struct LinearStructure {
    /// `K` as its three diagonals when it is a rod's: the free velocity's
    /// `K (q + hθ v)` without a gather per row.
    k_rows: Option<crate::linalg::TridiagonalRows>,
    /// The constant load is `+0.0` everywhere (the bar): read as the constant.
    unloaded: bool,
}

impl LinearStructure {
    /// The step data of the linear system `sys`.
    pub fn new(sys: &LinearSystem) -> Self {
        LinearStructure {
            k_rows: crate::linalg::TridiagonalRows::new(sys.stiffness.as_ref()),
            unloaded: crate::linalg::TridiagonalRows::is_positive_zero(&sys.force),
        }
    }
}

impl StructureModel for LinearStructure {
    fn step_matrix_constant(&self) -> bool {
        true
    }

    /// `M̂(h)` formed and analysed as an SPD matrix ([`analyse_spd_step`]).
    fn analyse(&self, sys: &LinearSystem, form: StepForm, h: f64) -> Result<StepAnalysis, Error> {
        analyse_spd_step(sys, form, h)
    }

    fn factor(
        &mut self,
        sys: &LinearSystem,
        (form, h): (StepForm, f64),
        _: (&[f64], &[f64]),
        planned: Option<StepMatrix>,
    ) -> Result<Box<dyn LinearSolver>, Error> {
        factor_step_matrix(sys, form, h, planned)
    }

    fn tangent<'a>(&'a self, sys: &'a LinearSystem) -> &'a SparseMatrix {
        &sys.stiffness
    }

    /// `v_free = v_k + M̂⁻¹ (h f − h K (q + hθ v) − h C v + loads)` (module doc); `K` and
    /// `C` are symmetric, so their CSC arrays are their CSR arrays and each row is a
    /// gather. `cx.work` is scratch afterwards.
    fn begin_step(&mut self, cx: &mut StepData<'_>, _: &mut StepStats) -> Result<bool, Error> {
        let (h, th) = (cx.h, cx.theta);
        let (s, sys) = (cx.state, cx.sys);
        if !cx.y_ready {
            for ((ql, q), v) in cx.q_lin.iter_mut().zip(&s.q).zip(&s.v) {
                *ql = q + h * th * v;
            }
        }
        if let Some(rows) = &self.k_rows {
            // the rods' K: the same sums without the gather (bit for bit)
            let f = (!self.unloaded).then_some(&sys.force[..]);
            rows.scaled_residual(h, f, cx.q_lin, cx.work);
        } else {
            let k = sys.stiffness.as_ref();
            let (kp, ki, kv) = (k.col_ptr(), k.row_idx(), k.val());
            for (i, (w, f)) in cx.work.iter_mut().zip(&sys.force).enumerate() {
                let r = kp[i]..kp[i + 1];
                let kx: f64 = ki[r.clone()]
                    .iter()
                    .zip(&kv[r])
                    .map(|(&j, &a)| a * cx.q_lin[j])
                    .sum();
                *w = h * (f - kx);
            }
        }
        add_step_loads(
            sys,
            (s.time, h, th),
            (&mut *cx.vp.0, &mut *cx.vp.1),
            cx.work,
        );
        if let Some(c) = &sys.damping {
            sym_spmv_add(c.as_ref(), -h, &s.v, cx.work);
        }
        cx.factor.solve_add(cx.work, &s.v, cx.v_free);
        Ok(false)
    }

    fn describe(&self, _: &LinearSystem, backend: &str, n: usize) -> String {
        format!("M̂ = M + hθC + h²θ²K factored once ({backend}, n = {n})")
    }
}
