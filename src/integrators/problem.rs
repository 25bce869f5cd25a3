//! What an integrator is built for ([`Problem`]): the structure, its candidate contacts
//! and the initial state at `t = 0`, checked once ([`Problem::validate`]) and handed to
//! the scheme's constructor by value (issue 36: one type where six arguments travelled
//! through ten signatures).
//!
//! A run plans before it builds ([`Problem::plan`]: the paths and the memory ledger,
//! checked against the limit before anything is factored). The plan validates the
//! problem and forms and analyses the step matrix `M + aK + bC`; the problem keeps both
//! facts, so the build that follows neither validates again nor forms and analyses the
//! matrix again (issue 36 §2: each was done twice). What was planned is tied to the
//! scheme's parameters, the step and a fingerprint of the structure's matrices and the
//! initial state: a problem changed after its plan is validated and assembled afresh.

use super::SchemeParams;
use super::plan::Plan;
use super::step_matrix::StepMatrix;
use super::structure::StructureModel;
use crate::contact::ContactSet;
use crate::error::Error;
use crate::linalg::SparseMatrix;
use crate::model::LinearSystem;

/// What [`Problem::plan`] established for the build: validated for `(params, h)` on the
/// problem whose fingerprint is `print`, with the step matrix (linear structures).
struct Planned {
    params: SchemeParams,
    h: f64,
    print: u64,
    step: Option<StepMatrix>,
    /// [`Problem::validate_once`] found the problem unchanged just before the build: the
    /// step matrix is taken without hashing the problem again.
    checked: bool,
}

/// The structure model a [`Problem`] holds: one its caller gave
/// ([`Problem::with_structure`]), or the default of the system
/// ([`super::structure::for_system`]) made for a scheme's Newton settings and
/// energy–momentum option (made again when the build asks for other ones).
struct HeldStructure {
    model: Box<dyn StructureModel>,
    /// `None`: the caller's; otherwise the `(modified Newton, energy–momentum)` of the
    /// default it is.
    made_for: Option<(bool, bool)>,
}

/// The structure, its contacts and the initial state of a run.
pub struct Problem {
    /// The assembled structure (after Dirichlet elimination).
    pub system: LinearSystem,
    /// The candidate contacts.
    pub contacts: Box<dyn ContactSet>,
    /// Initial displacement (one value per free dof).
    pub q0: Vec<f64>,
    /// Initial velocity (one value per free dof).
    pub v0: Vec<f64>,
    /// What the last [`Problem::plan`] established (module doc).
    planned: Option<Planned>,
    /// The structure model of the step ([`Problem::with_structure`]), made once for the
    /// plan and the build.
    structure: Option<HeldStructure>,
}

impl Problem {
    /// The problem of `system` with `contacts` from `(q0, v0)`.
    pub fn new(
        system: LinearSystem,
        contacts: Box<dyn ContactSet>,
        q0: Vec<f64>,
        v0: Vec<f64>,
    ) -> Problem {
        Problem {
            system,
            contacts,
            q0,
            v0,
            planned: None,
            structure: None,
        }
    }

    /// The problem stepped through `model` instead of the default structure model of its
    /// system ([`super::structure::for_system`]): the plan asks it for the step matrix's
    /// analysis and the build steps with it (a new structure plugs in here, with no edit
    /// to the core, the plan or the driver).
    pub fn with_structure(mut self, model: Box<dyn StructureModel>) -> Problem {
        self.structure = Some(HeldStructure {
            model,
            made_for: None,
        });
        self.planned = None;
        self
    }

    /// Makes the structure model for `params` unless the problem holds it: the caller's
    /// is kept, the system's default is made for `params`' Newton settings.
    fn ensure_structure(&mut self, params: &SchemeParams) {
        let key = (params.newton.modified, params.energy_momentum);
        let fresh = match &self.structure {
            Some(h) => h.made_for.is_some_and(|k| k != key),
            None => true,
        };
        if fresh {
            self.structure = Some(HeldStructure {
                model: super::structure::for_system(
                    &self.system,
                    &params.newton,
                    params.energy_momentum,
                ),
                made_for: Some(key),
            });
        }
    }

    /// The plan of `params` at `h` on the held structure model ([`super::plan::plan_kept`]).
    fn plan_held(
        &mut self,
        params: &SchemeParams,
        h: f64,
    ) -> Result<(Plan, Option<StepMatrix>), Error> {
        self.ensure_structure(params);
        let structure = self.structure.as_ref().expect("made above").model.as_ref();
        super::plan::plan_kept(params, structure, &self.system, self.contacts.as_ref(), h)
    }

    /// Takes the structure model for `params` out of the problem, for the build.
    pub(crate) fn take_structure(&mut self, params: &SchemeParams) -> Box<dyn StructureModel> {
        self.ensure_structure(params);
        self.structure.take().expect("made above").model
    }

    /// [`Problem::plan`] for a problem that will not be built (what `signorini check`
    /// costs): validated and planned, no step matrix kept.
    pub fn plan_only(&mut self, params: &SchemeParams, h: f64) -> Result<Plan, Error> {
        self.validate(params, h)?;
        self.plan_held(params, h).map(|(plan, _)| plan)
    }

    /// Validates the problem for `params` at step `h` and plans its run
    /// ([`super::plan::plan`]), keeping the validation and the step matrix for the build
    /// (module doc).
    pub fn plan(&mut self, params: &SchemeParams, h: f64) -> Result<Plan, Error> {
        self.planned = None;
        self.validate(params, h)?;
        let (plan, step) = self.plan_held(params, h)?;
        self.planned = Some(Planned {
            params: *params,
            h,
            print: self.fingerprint(),
            step,
            checked: false,
        });
        Ok(plan)
    }

    /// Whether the last [`Problem::plan`] validated this problem, unchanged, for
    /// `params` at step `h`.
    pub fn planned_for(&self, params: &SchemeParams, h: f64) -> bool {
        self.planned.as_ref().is_some_and(|p| {
            p.params == *params && p.h.to_bits() == h.to_bits() && p.print == self.fingerprint()
        })
    }

    /// Validates the problem for `params` at step `h` unless its plan did (the build's
    /// check: one hash of the problem instead of a second validation).
    pub(crate) fn validate_once(&mut self, params: &SchemeParams, h: f64) -> Result<(), Error> {
        if self.planned_for(params, h) {
            if let Some(p) = self.planned.as_mut() {
                p.checked = true;
            }
            return Ok(());
        }
        self.planned = None;
        self.validate(params, h)
    }

    /// The step matrix the plan formed and analysed, when the problem is still the one
    /// planned (the build takes it: [`StepMatrix`] is matched on its coefficients).
    pub(crate) fn take_step_matrix(&mut self) -> Option<StepMatrix> {
        let p = self.planned.take()?;
        (p.checked || p.print == self.fingerprint())
            .then_some(p.step)
            .flatten()
    }

    /// A hash of what validation and the step matrix read: the matrices' patterns and
    /// values, the ordering, the initial state, the parts, prescribed dofs and friction
    /// (one pass over the arrays: milliseconds where the factorization takes seconds).
    fn fingerprint(&self) -> u64 {
        let mut h = Fnv(0xcbf2_9ce4_8422_2325);
        let s = &self.system;
        let mut matrix = |m: Option<&SparseMatrix>| match m {
            None => h.word(u64::MAX),
            Some(m) => {
                let m = m.as_ref();
                h.word(m.nrows() as u64);
                m.col_ptr().iter().for_each(|&x| h.word(x as u64));
                m.row_idx().iter().for_each(|&x| h.word(x as u64));
                m.val().iter().for_each(|x| h.word(x.to_bits()));
            }
        };
        matrix(Some(&s.mass));
        matrix(Some(&s.stiffness));
        matrix(s.damping.as_ref());
        for o in s.ordering.iter().flat_map(|o| &o.perm) {
            h.word(*o as u64);
        }
        for x in self.q0.iter().chain(&self.v0) {
            h.word(x.to_bits());
        }
        h.word(self.q0.len() as u64);
        h.word(s.nonlinear.len() as u64);
        h.word(s.prescribed.is_some() as u64);
        h.word(self.contacts.has_friction() as u64);
        h.0
    }

    /// The structure, the contacts, `q0` and `v0`, for a constructor that takes them apart.
    pub fn into_parts(self) -> (LinearSystem, Box<dyn ContactSet>, Vec<f64>, Vec<f64>) {
        (self.system, self.contacts, self.q0, self.v0)
    }

    /// Everything [`build_problem`](super::build_problem) checks before it factors
    /// anything: the parameters, the step, the free dofs, the scheme against the
    /// structure, prescribed motion and friction, and the initial state's length and
    /// finiteness. `signorini check` runs it with the plan
    /// ([`plan::plan`](super::plan::plan)) instead of building.
    pub fn validate(&self, params: &SchemeParams, h: f64) -> Result<(), Error> {
        let (system, contacts, q0, v0) = (&self.system, self.contacts.as_ref(), &self.q0, &self.v0);
        params.validate()?;
        crate::error::require_positive("dt", h)?;
        if system.ndof() == 0 {
            return Err(Error::invalid(
                "bodies",
                "0 free degrees of freedom",
                "every node is fixed or prescribed: there is nothing to integrate (free some \
                 nodes of `fixed`, or drop the [[prescribed]] entries that cover every node)",
            ));
        }
        let caps = params.kind.capabilities();
        if system.linearity() != crate::model::system::Linearity::Linear && !caps.nonlinear {
            return Err(Error::invalid(
                "scheme.kind",
                params.kind.name(),
                "integrates linear structures only (a body has a nonlinear material); use a \
                 θ-method scheme (moreau-jean, direct-projection, combined-projection)",
            ));
        }
        if system.prescribed.is_some() && !caps.prescribed {
            return Err(Error::invalid(
                "scheme.kind",
                params.kind.name(),
                "does not take prescribed velocities ([[prescribed]]); use a θ-method scheme",
            ));
        }
        if contacts.has_friction() && !caps.friction {
            return Err(Error::invalid(
                "scheme.kind",
                params.kind.name(),
                "does not support Coulomb friction (a contact has friction > 0); use \
                 moreau-jean, direct-projection or combined-projection",
            ));
        }
        super::sizing::check_vector("initial displacement", q0, system.ndof())?;
        super::sizing::check_vector("initial velocity", v0, system.ndof())
    }
}

/// FNV-1a taken a 64-bit word at a time, rotated so that high bits reach the low ones
/// (the fingerprint of [`Problem`]; not cryptographic: it tells a changed problem from
/// the planned one, at about a nanosecond a word).
struct Fnv(u64);

impl Fnv {
    fn word(&mut self, w: u64) {
        self.0 = (self.0 ^ w)
            .wrapping_mul(0x0000_0100_0000_01b3)
            .rotate_left(29);
    }
}
