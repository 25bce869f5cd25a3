//! What a scheme carries from step to step ([`State`]: `q`, `v`, the contact-space
//! values at `t_k`) and what a step reports ([`StepStats`]: iterations, residuals,
//! violations, caps hit, as data).

use super::*;

/// Positions, velocities and contact quantities at time `t_k`.
///
/// Contact quantities are per contact for the normal part (`gap`, `local_velocity`,
/// `impulse`, `projection`) and, in frictional scenes, per contact and tangent for the
/// tangential part (`tangent_velocity`, `tangent_impulse`, `tangent_dim` values per
/// contact, zero for frictionless contacts), with a [`ContactStatus`] per contact.
/// `impulse_rows` is the whole impulse in the rows of `G` (block by block, normal
/// first), so that `G impulse_rows / h` is the contact force in dof space.
#[derive(Clone, Debug, Default)]
pub struct State {
    /// Index of the last completed step (0 before the first step).
    pub step: usize,
    /// Time `t_k` (s).
    pub time: f64,
    /// Generalized coordinates `q_k` (nodal displacements, m).
    pub q: Vec<f64>,
    /// Generalized velocities `v_k` (m/s).
    pub v: Vec<f64>,
    /// Gaps `g(q_k)` per contact (m; negative means penetration).
    pub gap: Vec<f64>,
    /// Local normal velocities `U_N = G_Nᵀ v_k` per contact (m/s).
    pub local_velocity: Vec<f64>,
    /// Normal contact impulse `P_N` over the last step per contact (N·s); force = `P/h`.
    pub impulse: Vec<f64>,
    /// Position projection multiplier `τ` of the last step per contact (eq. 28; units
    /// of the projection metric: m for Euclidean, kg·m for `M̂⁻¹`).
    pub projection: Vec<f64>,
    /// Tangents per contact in `tangent_velocity` and `tangent_impulse`: 0 in a
    /// frictionless scene, 1 in 2-D, 2 in 3-D.
    pub tangent_dim: usize,
    /// Tangential (slip) velocities `U_T` per contact (m/s), `tangent_dim` each.
    pub tangent_velocity: Vec<f64>,
    /// Tangential impulses `P_T` over the last step (N·s), `tangent_dim` each.
    pub tangent_impulse: Vec<f64>,
    /// Open / stick / slip per contact (frictional scenes; empty otherwise).
    pub status: Vec<ContactStatus>,
    /// The impulse in the rows of `G` (normal and tangential parts).
    pub impulse_rows: Vec<f64>,
}

impl State {
    /// Copies this state into `dst`, reusing `dst`'s buffers: no allocation when `dst`
    /// has this state's sizes (a writer thread's copy of the step's state).
    pub fn copy_to(&self, dst: &mut State) {
        dst.step = self.step;
        dst.time = self.time;
        dst.tangent_dim = self.tangent_dim;
        for (d, s) in [
            (&mut dst.q, &self.q),
            (&mut dst.v, &self.v),
            (&mut dst.gap, &self.gap),
            (&mut dst.local_velocity, &self.local_velocity),
            (&mut dst.impulse, &self.impulse),
            (&mut dst.projection, &self.projection),
            (&mut dst.tangent_velocity, &self.tangent_velocity),
            (&mut dst.tangent_impulse, &self.tangent_impulse),
            (&mut dst.impulse_rows, &self.impulse_rows),
        ] {
            d.clone_from(s);
        }
        dst.status.clone_from(&self.status);
    }

    /// The state at `t = 0` with `m` frictionless contacts (contact quantities zero
    /// until the integrator evaluates them).
    pub fn initial(q0: &[f64], v0: &[f64], m: usize) -> Self {
        State::with_layout(q0, v0, m, 0, m)
    }

    /// The state at `t = 0` with `m` contacts of `tangent_dim` tangents each in the
    /// state arrays and `rows` rows of `G` in all.
    pub fn with_layout(q0: &[f64], v0: &[f64], m: usize, tangent_dim: usize, rows: usize) -> Self {
        State {
            step: 0,
            time: 0.0,
            q: q0.to_vec(),
            v: v0.to_vec(),
            gap: vec![0.0; m],
            local_velocity: vec![0.0; m],
            impulse: vec![0.0; m],
            projection: vec![0.0; m],
            tangent_dim,
            tangent_velocity: vec![0.0; m * tangent_dim],
            tangent_impulse: vec![0.0; m * tangent_dim],
            status: vec![ContactStatus::Open; if tangent_dim > 0 { m } else { 0 }],
            impulse_rows: vec![0.0; rows],
        }
    }
}

impl State {
    /// The vectors every scheme's state holds, for a checkpoint.
    pub fn save(&self, scheme: &str) -> crate::integrators::saved::IntegratorState {
        let mut s = crate::integrators::saved::IntegratorState::default();
        self.save_into(scheme, &mut s);
        s
    }

    /// [`State::save`] into `s`, reusing its buffers: no allocation once `s` holds a
    /// state of this size (a snapshot taken at every step of an adaptive run).
    pub fn save_into(&self, scheme: &str, s: &mut crate::integrators::saved::IntegratorState) {
        use crate::integrators::saved::{Bits, Floats};
        s.scheme.clear();
        s.scheme.push_str(scheme);
        s.step = self.step;
        s.time = Bits(self.time);
        for (name, v) in [
            ("q", &self.q),
            ("v", &self.v),
            ("local_velocity", &self.local_velocity),
            ("impulse", &self.impulse),
            ("projection", &self.projection),
            ("tangent_velocity", &self.tangent_velocity),
            ("tangent_impulse", &self.tangent_impulse),
            ("impulse_rows", &self.impulse_rows),
        ] {
            match s.vectors.get_mut(name) {
                Some(f) => f.0.clone_from(v),
                None => {
                    s.vectors.insert(name.to_string(), Floats(v.clone()));
                }
            }
        }
        s.status.clear();
        s.status.extend(self.status.iter().map(|c| c.code()));
        s.dt = None;
        s.impulse_dt = None;
        s.origin = None;
    }

    /// Restores the vectors of [`State::save`] (same sizes) into this state.
    pub fn restore(
        &mut self,
        scheme: &str,
        s: &crate::integrators::saved::IntegratorState,
    ) -> Result<(), Error> {
        if s.scheme != scheme {
            return Err(Error::invalid(
                "checkpoint integrator.scheme",
                &s.scheme,
                &format!("the run's scheme is {scheme}"),
            ));
        }
        for (name, v) in [
            ("q", &mut self.q),
            ("v", &mut self.v),
            ("local_velocity", &mut self.local_velocity),
            ("impulse", &mut self.impulse),
            ("projection", &mut self.projection),
            ("tangent_velocity", &mut self.tangent_velocity),
            ("tangent_impulse", &mut self.tangent_impulse),
            ("impulse_rows", &mut self.impulse_rows),
        ] {
            let saved = s.vector(name, v.len())?;
            v.copy_from_slice(saved);
        }
        if s.status.len() != self.status.len()
            || s.status
                .iter()
                .any(|&c| ContactStatus::from_code(c).is_none())
        {
            return Err(Error::invalid(
                "checkpoint integrator.status",
                format!("{} codes", s.status.len()),
                &format!("expected {} codes in 0..=3", self.status.len()),
            ));
        }
        for (st, &c) in self.status.iter_mut().zip(&s.status) {
            *st = ContactStatus::from_code(c).unwrap_or_default();
        }
        self.step = s.step;
        self.time = s.time.0;
        Ok(())
    }
}

/// Statistics of one step, as the paper's Table 3 reports them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct StepStats {
    /// Newton iterations (eq. 42–51), summed over the index-set rounds.
    pub newton_iterations: usize,
    /// Newton iterations in which a non-zero position correction `τ` was applied.
    pub projection_iterations: usize,
    /// Rounds of the activation loop of Algorithm 2 (eq. 66), including the free round.
    pub index_set_iterations: usize,
    /// LCP/MLCP pivots or sweeps, summed over all one-step problems.
    pub lcp_iterations: usize,
    /// Largest LCP complementarity residual met in the step.
    pub lcp_residual: f64,
    /// Final Newton convergence measure (dimensionless; ≤ the tolerance unless capped).
    pub newton_residual: f64,
    /// Largest penetration `max(0, −g(q_{k+1}))` over the contacts (m).
    pub max_violation: f64,
    /// The step `h` this step was taken at (s): the accuracy mode varies it.
    pub dt: f64,
    /// Number of iteration caps hit in this step (Newton, activation, growth).
    pub caps_hit: usize,
    /// Friction problems solved in the step (0 in a frictionless scene).
    pub friction_solves: usize,
    /// NSGS sweeps over all friction problems of the step.
    pub friction_iterations: usize,
    /// Largest final friction residual of the step (the velocity residual,
    /// [`crate::solvers::friction::Measure::Velocity`]).
    pub friction_residual: f64,
    /// Friction solves of the step that NSGS did not finish (`auto` fell back on the
    /// Newton methods or PROX; [`crate::solvers::friction::FrictionInfo::solver`]).
    pub friction_fallbacks: usize,
    /// Friction solves of the step that hit the sweep cap (also in `caps_hit`).
    pub friction_caps: usize,
    /// Coupled position solves (eq. 53–55 on the current contact states) that replaced
    /// a slowly contracting decoupled iterate ([`core`] module doc).
    pub coupled_solves: usize,
    /// Newton loops that ended by stagnation (no 10 % gain in 5 iterations) at a
    /// residual within √tol: converged as far as the contact problem's accuracy allows;
    /// `newton_residual` holds the level reached.
    pub newton_stalls: usize,
    /// Algorithm 2: contacts whose final `P` is 0 but which stay projected with `τ < 0`
    /// (eq. 65 had no solution with them as complementarity rows; see
    /// [`core`]'s position problem), in the last index-set round of the step.
    pub held_rows: usize,
    /// Nonlinear structures: factorizations of the iteration matrix `M̂ⁿ` in the step
    /// (0 on the linear path, where `M̂` is factored once at set-up).
    pub factorizations: usize,
    /// Nonlinear structures: wall time of the step spent evaluating `F` and `Kⁿ`
    /// (element kernels and assembly) and forming `M̂ⁿ` (s).
    pub assembly_seconds: f64,
    /// Nonlinear structures: wall time of the step spent refactoring `M̂ⁿ` (s).
    pub factorization_seconds: f64,
    /// Algorithm 2: index-set rounds redone with Algorithm 1's position rule
    /// (`0 ≤ g ⊥ τ ≥ 0` on every active row) because the combined rule (eq. 67–70)
    /// hit the Newton cap or left held rows.
    pub complementarity_fallbacks: usize,
    /// One-step problems solved matrix-free because their active rows exceeded the dense
    /// workspaces (`max_active_rows`; [`crate::solvers::global`]).
    pub global_solves: usize,
    /// Products with the Delassus operator those solves took (each one sparse solve
    /// through the factor when the columns are not stored, none when they go through
    /// the flexibilities of `G`'s dofs, `Delassus::condense_products`).
    pub global_products: usize,
}
