//! What an integrator is built for ([`Problem`]): the structure, its candidate contacts
//! and the initial state at `t = 0`, checked once ([`Problem::validate`]) and handed to
//! the scheme's constructor by value (issue 36: one type where six arguments travelled
//! through ten signatures).

use super::SchemeParams;
use crate::contact::ContactSet;
use crate::error::Error;
use crate::model::LinearSystem;

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
        }
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
        super::core::check_vector("initial displacement", q0, system.ndof())?;
        super::core::check_vector("initial velocity", v0, system.ndof())
    }
}
