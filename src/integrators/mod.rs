//! Time integrators: the paper's five event-capturing schemes.
//!
//! | scheme | file | paper |
//! |---|---|---|
//! | Moreau–Jean | [`moreau_jean`] | eq. 18, forecasts eq. 61 (γ) and eq. 62 (free) |
//! | Schatzman–Paoli | [`schatzman_paoli`] | eq. 20–22 |
//! | trapezoidal rule, position-level contact | [`trapezoid`] | sec. 6.2, Fig. 11 |
//! | direct projection (Algorithm 1, decoupled) | [`direct_projection`] | eq. 28, 56–58, 60 |
//! | combined activation/projection (Algorithm 2) | [`combined_projection`] | eq. 65–70 |
//!
//! An integrator is built once (iteration matrix factored, Delassus operator
//! `W = Gᵀ M̂⁻¹ G` condensed, buffers sized) and stepped many times; [`Integrator::step`]
//! does not allocate and returns its [`StepStats`] as data.
//!
//! The θ-method schemes share [`core::ThetaCore`]: the free velocity of eq. 18/45,
//! the condensed operators of DESIGN.md §4, and the decoupled Newton loop of
//! eq. 56–58 written in contact space (for a linear system with constant `G` every
//! iterate is a small `m`-dimensional computation; `v` and `q` are formed once per
//! step).
//!
//! Erratum carried here: as printed, eq. 45, 48 and 56a give the stiffness terms
//! `+hθK(q_k − qⁿ + h(1−θ)v_k)` and `+hθK G τ`. Substituting the second line of eq. 44
//! into its first gives `−hθK(q_k − qⁿ + h(1−θ)v_k + hθvⁿ) − hθK G τ`; only this sign
//! reduces to the plain θ-method (eq. 18) when `τ = 0`. The code uses the derived form.

pub mod combined_projection;
pub mod core;
pub mod direct_projection;
pub mod moreau_jean;
pub mod plan;
pub mod problem;
pub mod saved;
pub mod schatzman_paoli;
pub mod structure;
pub mod trapezoid;

use serde::{Deserialize, Serialize};

use crate::contact::{ContactSet, ContactStatus};
use crate::error::Error;
use crate::model::LinearSystem;
use crate::solvers::LcpKind;

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
    /// through the factor when the columns are not stored).
    pub global_products: usize,
}

/// A time integrator for a linear structure with contacts. `Send`: a built integrator
/// can move to another thread (the Python package steps it with the GIL released).
pub trait Integrator: Send {
    /// Short name, as on the command line.
    fn name(&self) -> &'static str;
    /// Advances one step of size `h`. Does not allocate, unless the contact search had
    /// to be rebuilt in it (then [`Integrator::prepare`] was not called before).
    fn step(&mut self) -> Result<StepStats, Error>;
    /// Brings the contact search up to date before a step ([`ContactSet::update`]: the
    /// candidate facets of contacts between bodies), so that [`Integrator::step`] finds
    /// it fresh; [`crate::run::driver::drive`] calls it before every step. It may
    /// allocate (a rebuilt tree).
    ///
    /// [`ContactSet::update`]: crate::contact::ContactSet::update
    fn prepare(&mut self) -> Result<(), Error> {
        Ok(())
    }
    /// The current state.
    fn state(&self) -> &State;
    /// Whether every displacement and velocity of the state is finite, when the last
    /// step found out while forming it (`None`: not known, the caller scans). Saves
    /// the run's checks a pass over the state (issue 35).
    fn state_finite(&self) -> Option<bool> {
        None
    }
    /// The mechanical system being integrated.
    fn system(&self) -> &LinearSystem;
    /// The same system, shared: nothing changes it after the build, so a writer thread
    /// may read it while the run steps (the history's energies).
    fn shared_system(&self) -> std::sync::Arc<LinearSystem>;
    /// The time step `h` (s).
    fn dt(&self) -> f64;
    /// A one-line description of the solution path taken (factorization, Delassus
    /// data, Newton or not), for summaries.
    fn path(&self) -> String;
    /// The contact Jacobian `G` of the last evaluation (at the end of the last step;
    /// for nonlinear gaps, at the last Newton iterate), for the output of `G P / h`.
    fn jacobian(&self) -> &crate::contact::ContactJacobian;
    /// What the next step reads beyond the model, for a checkpoint
    /// ([`crate::run::checkpoint`]).
    fn save(&self) -> crate::integrators::saved::IntegratorState;
    /// Restores a state saved by an integrator built from the same model and parameters;
    /// the gaps, Jacobians and Delassus data are evaluated again at the restored `q`.
    fn restore(&mut self, s: &crate::integrators::saved::IntegratorState) -> Result<(), Error>;
}

impl State {
    /// The vectors every scheme's state holds, for a checkpoint.
    pub fn save(&self, scheme: &str) -> crate::integrators::saved::IntegratorState {
        use crate::integrators::saved::{Bits, Floats};
        let mut vectors = std::collections::BTreeMap::new();
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
            vectors.insert(name.to_string(), Floats(v.clone()));
        }
        crate::integrators::saved::IntegratorState {
            scheme: scheme.to_string(),
            step: self.step,
            time: Bits(self.time),
            vectors,
            status: self.status.iter().map(|s| s.code()).collect(),
        }
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

/// Which scheme to run (also the CLI's `--scheme` values).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum SchemeKind {
    /// Moreau–Jean (eq. 18).
    MoreauJean,
    /// Schatzman–Paoli (eq. 20–22).
    SchatzmanPaoli,
    /// θ-method with the contact at position level (Fig. 11).
    TrapezoidPosition,
    /// Algorithm 1.
    DirectProjection,
    /// Algorithm 2 (default).
    CombinedProjection,
}

impl SchemeKind {
    /// All schemes, in the paper's order.
    pub const ALL: [SchemeKind; 5] = [
        SchemeKind::MoreauJean,
        SchemeKind::SchatzmanPaoli,
        SchemeKind::TrapezoidPosition,
        SchemeKind::DirectProjection,
        SchemeKind::CombinedProjection,
    ];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            SchemeKind::MoreauJean => "moreau-jean",
            SchemeKind::SchatzmanPaoli => "schatzman-paoli",
            SchemeKind::TrapezoidPosition => "trapezoid-position",
            SchemeKind::DirectProjection => "direct-projection",
            SchemeKind::CombinedProjection => "combined-projection",
        }
    }

    /// Parses a command-line name.
    pub fn parse(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == s)
    }

    /// What the scheme can integrate and what it adds: the rules validation, the plan,
    /// the driver and the studies read instead of matching on the kind.
    pub fn capabilities(self) -> Capabilities {
        let theta = self != SchemeKind::SchatzmanPaoli;
        Capabilities {
            projection: matches!(
                self,
                SchemeKind::DirectProjection | SchemeKind::CombinedProjection
            ),
            // Schatzman–Paoli (eq. 20–22) and the position-level trapezoid state the
            // contact at position level, where Coulomb's law (a velocity-level law, eq.
            // 12–15) has no discrete counterpart in the paper
            friction: !matches!(
                self,
                SchemeKind::SchatzmanPaoli | SchemeKind::TrapezoidPosition
            ),
            prescribed: theta,
            nonlinear: theta,
            theta_energy: theta,
        }
    }
}

/// What a scheme supports ([`SchemeKind::capabilities`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Capabilities {
    /// A position projection after the velocity problem (Algorithms 1 and 2): the
    /// projection problems, `W_D`, and no penetration beyond round-off.
    pub projection: bool,
    /// Coulomb friction (eq. 12–15: a velocity-level law).
    pub friction: bool,
    /// Prescribed velocities (`[[prescribed]]`).
    pub prescribed: bool,
    /// Nonlinear structures (the θ-method Newton loop of eq. 41–48).
    pub nonlinear: bool,
    /// The θ-method's discrete energy balance holds (Schatzman–Paoli's velocity is a
    /// central difference, whose energy is not the θ-method's).
    pub theta_energy: bool,
}

/// Activation forecast `ḡ_{k+1}` for the velocity-level schemes (sec. 4.4).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Forecast {
    /// `ḡ = g_k + γ h U_k` (eq. 61), γ in [0, 2].
    Explicit {
        /// Extrapolation factor γ.
        gamma: f64,
    },
    /// `ḡ = g_k + h (θ U_free + (1 − θ) U_k)` (eq. 62).
    Free,
}

pub use crate::delassus::Metric;
pub use problem::Problem;

/// Algorithm 2's position rule on the active set `Iᵛ` (eq. 65 and 67–70): which active
/// rows are held at `g_{k+1} = 0` with a free `τ`; the others take `0 ≤ g ⊥ τ ≥ 0`.
///
/// The paper holds every row whose impulse is positive in the step. A row that carries
/// its first impulse (an impact, a node joining a growing contact patch) may end the
/// velocity solve above the obstacle; holding it at `g = 0` then pulls it down (`τ < 0`),
/// and on elastic bodies that pull, fed back through `−hθK N G τ` (eq. 56a), throws the
/// node off at tens of m/s (1 m/s Hertz impact). On contact between bodies eq. 65 then
/// often has no solution for the set and the round is redone with complementarity: 20–40
/// Newton iterations a step where the default takes 8 (README, "Algorithm 2's position
/// rule", has the matrix of scenes × steps that chose the default).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum ProjectionRule {
    /// Held where `P > 0` in this step and in the previous one (default): a contact that
    /// lasts sits on the constraint to machine accuracy (a body at rest, the bar's tip,
    /// the rocking block's corners); a first impulse only forbids penetration.
    #[default]
    Persistent,
    /// The paper's eq. 68: held where `P > 0` in this step (`I_cᵛ`, eq. 69/70).
    Paper,
    /// No row held: `0 ≤ g ⊥ τ ≥ 0` on all of `Iᵛ` (the projection only pushes out, as
    /// Algorithm 1's eq. 58, over the set Algorithm 2 activates). Never pulls, but a body
    /// can come to rest above the obstacle by `O(h²)`.
    Complementarity,
    /// Every row of `Iᵛ` held: Siconos' code, whose `P > 0` test is commented out.
    AllActive,
}

impl ProjectionRule {
    /// The scene-file and command-line name.
    pub fn name(self) -> &'static str {
        match self {
            ProjectionRule::Persistent => "persistent",
            ProjectionRule::Complementarity => "complementarity",
            ProjectionRule::Paper => "paper",
            ProjectionRule::AllActive => "all-active",
        }
    }

    /// Whether a row whose impulse is positive in this step is held at `g = 0`, given
    /// whether its impulse was positive in the previous step.
    pub(crate) fn holds(self, was_positive: bool) -> bool {
        match self {
            ProjectionRule::Persistent => was_positive,
            ProjectionRule::Paper | ProjectionRule::AllActive => true,
            ProjectionRule::Complementarity => false,
        }
    }
}

/// Newton loop controls shared by every scheme.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct NewtonParams {
    /// Relative tolerance of the Newton / fixed-point loop (default 1e-10): the loop
    /// stops when the last update changes the contact velocities and gaps by less than
    /// `tol` times the step's own scale (`|U|∞` and `h |U|∞`); for nonlinear contacts
    /// also when `q` moved by less than `tol` times the step increment.
    pub tol: f64,
    /// Iteration cap (default 50); reaching it is counted in [`StepStats::caps_hit`].
    pub max_iterations: usize,
    /// Nonlinear structures only: modified Newton, the iteration matrix `M̂ⁿ` formed at
    /// the step's first iterate and kept while the iterates contract (default false:
    /// full Newton, `M̂ⁿ` refactored at every iterate; [`structure`] module doc).
    pub modified: bool,
}

impl Default for NewtonParams {
    fn default() -> Self {
        NewtonParams {
            tol: 1e-10,
            max_iterations: 50,
            modified: false,
        }
    }
}

/// Every knob of every scheme, with the defaults of the reference runs.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SchemeParams {
    /// Which scheme.
    pub kind: SchemeKind,
    /// θ in [1/2, 1] (default 1/2: no numerical dissipation).
    pub theta: f64,
    /// Activation forecast for Moreau–Jean and Algorithm 1 (default: free, eq. 62).
    pub forecast: Forecast,
    /// Moreau–Jean and Algorithm 1: close the forecast's active set on the step's solution
    /// (default true): a contact whose end-of-step gap `g_k + h((1−θ)U_k + θU_{k+1})`
    /// (before any projection) is `≤ 0` joins the set and the step is solved again
    /// (module docs of [`moreau_jean`] and [`direct_projection`]). `false`: the forecast
    /// alone (eq. 61/62), which lets nodes at the edge of a growing patch between curved
    /// bodies penetrate several times `|U|(1−θ)h` under Moreau–Jean, and lets Algorithm
    /// 1's projection chatter between stacked bodies.
    pub activation_closure: bool,
    /// Projection metric for Algorithms 1 and 2 (default: `M̂⁻¹`, see DESIGN.md §3).
    pub metric: Metric,
    /// Algorithm 2's position rule on the active set (default `persistent`: `g = 0` held
    /// where `P > 0` in this step and the last; `paper` is eq. 68, `complementarity` holds
    /// none, `all-active` is Siconos' code; see [`ProjectionRule`]).
    pub projection_rule: ProjectionRule,
    /// The impact law of a normal row separating at the step's start (`U_k > 0`) takes
    /// the restitution `max(e, (1 − θ)/θ)`, so that no impulse adds energy to the
    /// θ-method's balance (default true; the `restitution` doc of `integrators::core`).
    /// `false`: Newton's law with `e` on every row, as eq. 18d writes it.
    pub energy_consistent_restitution: bool,
    /// Feed the projection back into the velocity update through the stiffness term
    /// `−hθK N G τⁿ` of eq. 56a (default `true`, the paper's decoupled scheme). `false`
    /// updates only `q`, as Siconos does; with the Euclidean metric that kicks the
    /// contact node and excites the highest modes of the bar (force plateau std about
    /// 229 N against 11 N with the feedback at N = 1000, h = 5e-6).
    pub projection_feedback: bool,
    /// Stop projecting when the violation is below this (m). 0 (default): project to
    /// machine accuracy.
    pub projection_tolerance: f64,
    /// LCP algorithm (default: Lemke up to 16 unknowns, block pivoting above).
    pub lcp: LcpKind,
    /// Newton loop controls.
    pub newton: NewtonParams,
    /// Delassus storage (default `auto`: dense while the blocks fit in 2 GiB and `G`
    /// is constant, per-active-column otherwise; see [`crate::delassus`]).
    pub delassus: crate::delassus::DelassusKind,
    /// Columns the per-active-column Delassus pool holds (0, default: as many as fit
    /// in 2 GiB, capped at the contact count). When full, the column of the contact
    /// inactive for longest is recomputed on demand; more contacts active in one step
    /// than the pool holds is an error.
    pub delassus_pool: usize,
    /// Rows of the contact space the one-step solvers' dense workspaces hold (0,
    /// default: all rows up to 4096, i.e. 128 MiB per dense block). The workspaces grow
    /// with the active contacts, never with the square of the candidates; a problem with
    /// more active rows than this is solved matrix-free ([`crate::solvers::global`]: MPRGP,
    /// or the accelerated projected gradient with friction, on products `W x` through
    /// the factor), to the friction tolerance `friction.tol` within
    /// `friction.max_iterations` products.
    pub max_active_rows: usize,
    /// Coulomb friction solver controls (used only when some contact has `μ > 0`).
    pub friction: crate::solvers::friction::FrictionParams,
    /// Count iteration caps (Newton, projection, LCP, friction) in the statistics and go
    /// on, instead of failing the run at the first one (default false: a cap hit means
    /// the step's solution is not the scheme's, and the run stops with exit code 1).
    pub allow_caps: bool,
    /// Largest growth of the energy beyond the work that loads and prescribed motion
    /// supplied, relative to the run's energy scale (`model::energy`), before the run is
    /// stopped as failed (exit code 1). `None` (default): [`DEFAULT_MAX_ENERGY_EXCESS`]
    /// (1e-6) where the scheme's discrete energy is exact — linear structures, and
    /// large-deformation bodies under `energy_momentum` — and
    /// [`THETA_METHOD_MAX_ENERGY_EXCESS`] (1e-2) for large-deformation bodies under the
    /// θ-method, whose energy error is bounded but not round-off. Measured (README,
    /// "Algorithm 2's position rule"): every committed scene at 1×–8× its step under every
    /// scheme that ends stays below 1.6e-13 of its scale; what grows more is not the
    /// scheme's solution (an impact law adding energy, an unconverged Newton loop with caps
    /// allowed, the Euclidean projection without feedback). `inf` accepts any growth.
    pub max_energy_excess: Option<f64>,
    /// Large-deformation bodies only, θ = 1/2: their internal force over a step is
    /// Gonzalez's discrete gradient of the strain energy between the step's ends instead
    /// of the force at the midpoint ([`crate::model::hyperelastic::Hyperelastic::discrete_gradient`]),
    /// so a free body keeps its energy to the Newton tolerance and its momenta to
    /// round-off (an energy–momentum scheme; default false: the paper's θ-method, whose
    /// energy error is bounded, second order). Linear bodies need nothing: θ = 1/2
    /// conserves their quadratic energy already.
    pub energy_momentum: bool,
}

impl Default for SchemeParams {
    fn default() -> Self {
        SchemeParams {
            kind: SchemeKind::CombinedProjection,
            theta: 0.5,
            forecast: Forecast::Free,
            activation_closure: true,
            metric: Metric::Mass,
            projection_rule: ProjectionRule::Persistent,
            energy_consistent_restitution: true,
            projection_feedback: true,
            projection_tolerance: 0.0,
            lcp: LcpKind::Auto,
            newton: NewtonParams::default(),
            delassus: crate::delassus::DelassusKind::Auto,
            delassus_pool: 0,
            max_active_rows: 0,
            friction: crate::solvers::friction::FrictionParams::default(),
            allow_caps: false,
            max_energy_excess: None,
            energy_momentum: false,
        }
    }
}

/// The energy check's default limit where the discrete energy is exact (linear
/// structures; large-deformation bodies with `energy_momentum`): far above round-off
/// (every clean run measured ≤ 1.6e-13 of its energy scale), far below any impact that
/// adds energy (the paper's rule on the Hertz plate: 1.7e-4 at exit 0 before).
pub const DEFAULT_MAX_ENERGY_EXCESS: f64 = 1e-6;

/// The energy check's default limit for large-deformation bodies under the θ-method,
/// whose midpoint force conserves no energy: its error is bounded, second order in `h`
/// (1.03e-3 of the energy on a free neo-Hookean body spinning at 20 rad/s,
/// `tests/hyperelastic_free_dynamics.rs`; 1.8e-7 on the neo-Hookean hex bar bouncing
/// with e = 1).
pub const THETA_METHOD_MAX_ENERGY_EXCESS: f64 = 1e-2;

/// The energy check's limit: `max` when set, else [`DEFAULT_MAX_ENERGY_EXCESS`] where
/// the discrete energy is exact (a `linear` structure, or `energy_momentum`) and
/// [`THETA_METHOD_MAX_ENERGY_EXCESS`] otherwise.
pub fn energy_excess_limit(max: Option<f64>, energy_momentum: bool, linear: bool) -> f64 {
    max.unwrap_or(if linear || energy_momentum {
        DEFAULT_MAX_ENERGY_EXCESS
    } else {
        THETA_METHOD_MAX_ENERGY_EXCESS
    })
}

impl SchemeParams {
    /// The energy check's limit on a structure that is `linear` or not
    /// ([`SchemeParams::max_energy_excess`]).
    pub fn energy_excess_limit(&self, linear: bool) -> f64 {
        energy_excess_limit(self.max_energy_excess, self.energy_momentum, linear)
    }

    /// These parameters with the paper's rules where the defaults depart from them
    /// (README, "Algorithm 2's position rule"): Algorithm 2 holds every row with
    /// `P > 0` at `g = 0` (eq. 68, [`ProjectionRule::Paper`]), Moreau–Jean's active set
    /// is the forecast's alone (eq. 61/62), and Newton's law takes `e` on every row
    /// (eq. 18d). The reproductions of the paper's figures and tables run with these.
    pub fn paper_rules(self) -> Self {
        SchemeParams {
            projection_rule: ProjectionRule::Paper,
            activation_closure: false,
            energy_consistent_restitution: false,
            ..self
        }
    }

    /// Checks the ranges; errors name the field.
    pub fn validate(&self) -> Result<(), Error> {
        crate::error::require_in("theta", self.theta, 0.5, 1.0)?;
        if let Forecast::Explicit { gamma } = self.forecast {
            crate::error::require_in("gamma", gamma, 0.0, 2.0)?;
        }
        crate::error::require_in(
            "projection_tolerance",
            self.projection_tolerance,
            0.0,
            1e300,
        )?;
        crate::error::require_in("newton.tol", self.newton.tol, 0.0, 1.0)?;
        if self.energy_momentum && self.theta != 0.5 {
            return Err(Error::invalid(
                "energy_momentum",
                "true",
                &format!(
                    "needs theta = 0.5 (the discrete gradient is a midpoint rule), not {}",
                    self.theta
                ),
            ));
        }
        if let Some(x) = self.max_energy_excess
            && (x.is_nan() || x < 0.0)
        {
            return Err(Error::invalid(
                "max_energy_excess",
                crate::error::num(x),
                "must be a number ≥ 0 (inf accepts any growth)",
            ));
        }
        if self.newton.max_iterations == 0 {
            return Err(Error::invalid(
                "newton.max_iterations",
                0,
                "must be at least 1",
            ));
        }
        self.friction.validate("friction.")?;
        if let LcpKind::Pgs { tol, max_sweeps } = self.lcp {
            crate::error::require_positive("lcp.tol", tol)?;
            if max_sweeps == 0 {
                return Err(Error::invalid("lcp.max_sweeps", 0, "must be at least 1"));
            }
        }
        Ok(())
    }
}

/// Builds the integrator chosen by `params` for `problem` with step `h`, after checking
/// them once ([`Problem::validate`]); nothing below checks them again.
pub fn build_problem(
    params: &SchemeParams,
    problem: Problem,
    h: f64,
) -> Result<Box<dyn Integrator>, Error> {
    // validated once: by the plan of this problem, or here
    if !problem.planned_for(params, h) {
        problem.validate(params, h)?;
    }
    Ok(match params.kind {
        SchemeKind::MoreauJean => Box::new(moreau_jean::MoreauJean::new(params, problem, h)?),
        SchemeKind::DirectProjection => Box::new(direct_projection::DirectProjection::new(
            params, problem, h,
        )?),
        SchemeKind::CombinedProjection => Box::new(combined_projection::CombinedProjection::new(
            params, problem, h,
        )?),
        SchemeKind::TrapezoidPosition => {
            Box::new(trapezoid::TrapezoidPosition::new(params, problem, h)?)
        }
        SchemeKind::SchatzmanPaoli => {
            Box::new(schatzman_paoli::SchatzmanPaoli::new(params, problem, h)?)
        }
    })
}

/// [`build_problem`] from the parts of a [`Problem`]: the structure `system`, its
/// `contacts`, the initial state `(q0, v0)` at `t = 0` (the form the tests, benches and
/// studies that assemble a system by hand use).
pub fn build(
    params: &SchemeParams,
    system: LinearSystem,
    contacts: Box<dyn ContactSet>,
    q0: &[f64],
    v0: &[f64],
    h: f64,
) -> Result<Box<dyn Integrator>, Error> {
    build_problem(
        params,
        Problem::new(system, contacts, q0.to_vec(), v0.to_vec()),
        h,
    )
}
