//! Setting the core up once: `M̂` formed and factored by the structure, the contacts
//! evaluated at `q0`, the Delassus data condensed (on the contact zone where `G` moves
//! on a constant `M̂`), the one-step workspaces sized against the memory limit; the
//! description of the path taken, and the checks of the inputs.

use super::*;

impl ThetaCore {
    /// Forms and factors `M̂`, evaluates the contacts at `q0` and condenses the
    /// Delassus operators. `with_projection` also prepares `W_D` and `W_N`.
    pub fn new(
        params: &SchemeParams,
        problem: Problem,
        h: f64,
        with_projection: bool,
    ) -> Result<Self, Error> {
        let mut problem = problem;
        let planned = problem.take_step_matrix();
        let mut structure = problem.take_structure(params);
        let (sys, contacts, q0, v0) = problem.into_parts();
        let (q0, v0) = (&q0[..], &v0[..]);
        check_block_rows(params, contacts.as_ref())?;
        // A nonsymmetric M̂ⁿ (gyroscopic terms) makes W nonsymmetric: `N = M̂⁻¹` is then
        // no metric (eq. 59 needs N positive definite) and block pivoting's Cholesky
        // does not apply, so the projection takes eq. 58's Euclidean metric and the
        // LCPs Lemke's method (which needs no symmetry).
        let adjusted;
        let params = if !sys.symmetric() {
            adjusted = SchemeParams {
                metric: crate::delassus::Metric::Euclidean,
                lcp: match params.lcp {
                    p @ crate::solvers::LcpKind::Pgs { .. } => p,
                    _ => crate::solvers::LcpKind::Lemke,
                },
                ..*params
            };
            &adjusted
        } else {
            params
        };
        let theta = params.theta;
        let factor = structure.factor(&sys, (params.step_form(), h), (q0, v0), planned)?;
        let n = sys.ndof();
        let np = sys.prescribed.as_ref().map_or(0, |p| p.dofs.len());
        let m = contacts.len();
        let jac = ContactJacobian::for_set(contacts.as_ref());
        let rows = jac.ncols();
        let mut off = Vec::with_capacity(m + 1);
        off.push(0);
        for a in 0..m {
            off.push(off[a] + contacts.dim(a));
        }
        assert_eq!(off[m], rows, "contact blocks and Jacobian columns disagree");
        let laws = contacts.laws();
        let mut e = vec![0.0; rows];
        let mut normal = vec![false; rows];
        for a in 0..m {
            e[off[a]] = laws[a].restitution;
            normal[off[a]] = true;
        }
        let mu: Vec<f64> = laws.iter().map(|l| l.friction).collect();
        let friction = rows > m;
        let tangent_dim = if friction {
            (0..m).map(|a| off[a + 1] - off[a] - 1).max().unwrap_or(0)
        } else {
            0
        };
        let g_constant = contacts.is_linear();
        let coordinate_scale = contacts.coordinate_scale();
        let operators_constant = g_constant && structure.step_matrix_constant();
        let state = State::with_layout(q0, v0, m, tangent_dim, rows);
        let del = Delassus::new(
            factor,
            jac,
            n,
            (params.delassus, params.delassus_pool),
            with_projection,
            params.metric,
            operators_constant,
        );
        // the dense one-step workspaces (module doc of `Workspace`): the gathered block
        // and the MLCP's three, plus the coupled position problem's matrix
        // the coupled problem has at most the velocity rows plus one τ per contact,
        // capped like the dense workspaces (beyond, the decoupled loop runs alone)
        let ws_cap = workspace_cap(rows, params);
        let mut del = del?;
        del.limit_columns(ws_cap);
        let coupled_cap =
            (with_projection && params.projection_feedback).then(|| (rows + m).min(ws_cap));
        let mut mem = crate::limits::MemoryEstimate::default();
        workspace_ledger(rows, m, params, (friction, with_projection), &mut mem);
        mem.check("scheme.max_active_rows", format!("{ws_cap} rows"))?;
        let mut core = ThetaCore {
            sys: std::sync::Arc::new(sys),
            contacts,
            h,
            structure,
            del,
            state,
            cfg: ThetaConfig {
                theta,
                n,
                m,
                rows,
                off,
                mu,
                friction,
                friction_params: params.friction,
                normal,
                e,
                with_projection,
                feedback: params.projection_feedback,
                restitution_floor: params
                    .energy_consistent_restitution
                    .then(|| ((1.0 - params.theta) / params.theta, !with_projection)),
                g_constant,
                coordinate_scale,
                operators_constant,
                newton: params.newton,
                projection_tolerance: params.projection_tolerance,
                step_form: params.step_form(),
                built: *params,
            },
            carry: StepCarry {
                u_rows: vec![0.0; rows],
                p_warm: vec![0.0; rows],
                y_ready: false,
                state_finite: None,
                last_converged: false,
                jac_at_qk: true,
                w_at_qk: false,
                origin: (0, 0.0),
                pending_factorizations: 0,
                warm_h: h,
                snapshot: Default::default(),
            },
            dofs: DofScratch {
                v_free: vec![0.0; n],
                work: vec![0.0; n],
                q_lin: vec![0.0; n],
                v_new: vec![0.0; n],
                q_new: vec![0.0; n],
                prescribed_a: vec![0.0; np],
                prescribed_b: vec![0.0; np],
            },
            rs: RowScratch {
                g_at_lin: vec![0.0; m],
                u_k: vec![0.0; rows],
                u_free: vec![0.0; rows],
                u_new: vec![0.0; rows],
                w_p: vec![0.0; rows],
                wn_tau: vec![0.0; rows],
                wd_tau: vec![0.0; rows],
                lcp_rhs: vec![0.0; rows],
                gap_unprojected: vec![0.0; rows],
                g_lin: vec![0.0; rows],
                p: vec![0.0; rows],
                tau: vec![0.0; rows],
                tau_prev: vec![0.0; rows],
                tau_used: vec![0.0; rows],
                dtau: vec![0.0; rows],
                vel_mask: vec![false; m],
                pos_mask: vec![false; m],
                eq_rows: vec![false; rows],
                velocity_accuracy: 0.0,
            },
            // (after the vectors above, as before issue 49: the workspaces' placement
            // after the step's vectors measured 5–12 % faster on meshes/hex_bars.toml,
            // whose K gather is memory-bound)
            ws: Workspace::new(rows, m, params, friction),
            coupled: coupled_cap.map(|c| Coupled::new(c, m)),
            step_cache: StepCache::new(),
            zone: ZoneScratch {
                dofs: Vec::new(),
                velocity_correction: Vec::new(),
                position_correction: Vec::new(),
                q_iterate: Vec::new(),
                q_last: Vec::new(),
                q_start: Vec::new(),
            },
        };
        core.contacts
            .evaluate(&core.state.q, &mut core.state.gap, &mut core.del.jac);
        if core.structure.step_matrix_constant() {
            core.condense(params);
            core.carry.w_at_qk = true;
        } else {
            // a nonlinear structure condenses with each step's first iteration matrix,
            // and carries the projection's feedback in F: W_D is never read
            core.del.without_wd();
            // with a constant M, positions are projected in the kinetic metric N = M⁻¹
            // (`delassus::kinetic`): M̂ⁿ⁻¹ would move nodes along a frictionless plane
            if with_projection
                && core.sys.linearity() == crate::model::system::Linearity::ConstantMass
            {
                core.del.use_kinetic_metric(&core.sys.mass)?;
            }
        }
        core.del
            .jac
            .transpose_mul(&core.state.v, &mut core.carry.u_rows);
        core.scatter_local_velocity();
        core.del.start_stepping();
        Ok(core)
    }

    /// A description of the linear-algebra path, for summaries.
    pub fn path(&self) -> String {
        let structure =
            self.structure
                .describe(&self.sys, &self.del.factor.backend_name(), self.cfg.n);
        format!(
            "{structure}; {} contact(s){}, {}; {}{}",
            self.cfg.m,
            if self.cfg.friction {
                format!(
                    " with Coulomb friction ({} rows; {} on the velocity problem)",
                    self.cfg.rows,
                    self.cfg.friction_params.solver.name()
                )
            } else {
                String::new()
            },
            if self.cfg.operators_constant {
                "linear gap: G and W constant (condensed once), one sparse solve per step; \
                 Newton iterations only re-solve the contact-space problem (eq. 56a)"
            } else if self.cfg.g_constant {
                "linear gap: G constant, W condensed again with each new M̂ⁿ"
            } else if !self.zone.dofs.is_empty() {
                "nonlinear gap: G(q) re-linearized every Newton iteration, which iterates on \
                 the contact zone's dofs (F B P, no sparse solve) and forms the state once"
            } else {
                "nonlinear gap: G(q) re-linearized every Newton iteration"
            },
            self.del.describe(),
            if self.cfg.with_projection {
                format!(
                    "; projection metric {}",
                    if self.del.kinetic() {
                        "mass (kinetic: N = M⁻¹, M factored once)"
                    } else {
                        self.del.metric().name()
                    }
                )
            } else {
                String::new()
            }
        ) + &self.ws.describe(self.del.products_by_flexibility())
    }
}
