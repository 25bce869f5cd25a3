//! Every knob of every scheme with its documented default ([`SchemeParams`], one struct
//! as rapier's `IntegrationParameters`): the scheme's kind and what it can do
//! ([`SchemeKind::capabilities`]), θ, the forecast, the projection rule, the Newton
//! settings and the energy-excess limit, each validated with the key it came from.

use super::*;

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
            variable_step: theta,
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
    /// The step may change between steps ([`crate::integrators::Integrator::set_dt`]): a
    /// one-step scheme; the accuracy mode needs it.
    pub variable_step: bool,
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

/// Algorithm 2's position rule on the active set `Iᵛ` (eq. 65 and 67–70): which active
/// rows are held at `g_{k+1} = 0` with a free `τ`; the others take `0 ≤ g ⊥ τ ≥ 0`.
///
/// The paper holds every row whose impulse is positive in the step. A row that carries
/// its first impulse (an impact, a node joining a growing contact patch) may end the
/// velocity solve above the obstacle; holding it at `g = 0` then pulls it down (`τ < 0`),
/// and on elastic bodies that pull, fed back through `−hθK N G τ` (eq. 56a), throws the
/// node off at tens of m/s (1 m/s Hertz impact). On contact between bodies eq. 65 then
/// often has no solution for the set and the round is redone with complementarity: 20–40
/// Newton iterations a step where the default takes 8 (docs/bar.md, "Algorithm 2's position
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
    /// The fill-reducing order offered to the Cholesky of `M̂` beside AMD (default
    /// `auto`: the mesh's geometric nested dissection; `metis`: METIS', which fills
    /// less and sets up faster but steps slower; `amd`: AMD alone). Meshes only.
    pub ordering: crate::model::ordering::OrderingKind,
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
    /// θ-method, whose energy error is bounded but not round-off. Measured (docs/bar.md,
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
    /// Largest rotation (rad) a cell of a body with the linear law may take before the
    /// run stops as failed (exit code 1; a starting state past it is refused): the small
    /// strain is not invariant under rotation, a rigid turn of φ strains the body by
    /// `1 − cos φ` (`run::rotations`). Default [`DEFAULT_MAX_ROTATION`] (0.05 rad, 2.9°:
    /// a spurious strain of 1.25e-3); `inf` turns the check off. Bodies with a
    /// large-deformation or the corotational law are not measured.
    pub max_rotation: f64,
}

/// The rotation check's default limit ([`SchemeParams::max_rotation`]): 0.05 rad, where
/// the linear law's spurious strain `1 − cos φ` reaches 1.25e-3.
pub const DEFAULT_MAX_ROTATION: f64 = 0.05;

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
            ordering: crate::model::ordering::OrderingKind::Auto,
            delassus_pool: 0,
            max_active_rows: 0,
            friction: crate::solvers::friction::FrictionParams::default(),
            allow_caps: false,
            max_energy_excess: None,
            energy_momentum: false,
            max_rotation: DEFAULT_MAX_ROTATION,
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
    /// The step matrix the scheme factors ([`super::step_matrix::StepForm`]).
    pub fn step_form(&self) -> super::step_matrix::StepForm {
        use super::step_matrix::StepForm;
        match self.kind {
            SchemeKind::SchatzmanPaoli => StepForm::SchatzmanPaoli { theta: self.theta },
            _ => StepForm::Theta { theta: self.theta },
        }
    }

    /// The energy check's limit on a structure that is `linear` or not
    /// ([`SchemeParams::max_energy_excess`]).
    pub fn energy_excess_limit(&self, linear: bool) -> f64 {
        energy_excess_limit(self.max_energy_excess, self.energy_momentum, linear)
    }

    /// These parameters with the paper's rules where the defaults depart from them
    /// (docs/bar.md, "Algorithm 2's position rule"): Algorithm 2 holds every row with
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
        if self.max_rotation.is_nan() || self.max_rotation <= 0.0 {
            return Err(Error::invalid(
                "max_rotation",
                crate::error::num(self.max_rotation),
                "must be an angle > 0 in radians (inf: no rotation check)",
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
