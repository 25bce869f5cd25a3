//! Contacts with constant Jacobian blocks: `g^α(q) = g0^α + n^α·q` on a few dofs, with
//! constant tangential rows. The general linear contact of a rigid multibody system in
//! small motion (a slider on a roller, a mass on a guide): every row is given by the
//! caller, so the frame is whatever the mechanism's geometry makes it (the rows should be
//! orthonormal in the metric of the contact velocities for Coulomb's cone to mean what
//! it says; the constructor checks only sizes and finiteness).

use super::{ContactJacobian, ContactLaw, ContactSet, check_friction, check_restitution};
use crate::error::Error;

/// One contact of a [`LinearContacts`] set.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearContact {
    /// The dofs its rows touch.
    pub dofs: Vec<usize>,
    /// Gap at `q = 0` (m).
    pub offset: f64,
    /// Normal row `∇g` on `dofs`.
    pub normal: Vec<f64>,
    /// Tangential rows on `dofs` (none without friction; one in 2-D, two in 3-D).
    pub tangents: Vec<Vec<f64>>,
    /// Its law.
    pub law: ContactLaw,
}

/// A set of contacts with constant Jacobian blocks (linear gaps).
#[derive(Clone, Debug)]
pub struct LinearContacts {
    contacts: Vec<LinearContact>,
    laws: Vec<ContactLaw>,
}

impl LinearContacts {
    /// Checks every contact: finite rows of the length of `dofs`, a valid law, and
    /// tangential rows exactly when `μ > 0`.
    pub fn new(contacts: Vec<LinearContact>) -> Result<Self, Error> {
        for (a, c) in contacts.iter().enumerate() {
            let at = |f: &str| format!("contacts[{a}].{f}");
            check_restitution(&at("restitution"), c.law.restitution)?;
            check_friction(&at("friction"), c.law.friction)?;
            let rows = std::iter::once(&c.normal).chain(&c.tangents);
            for (k, r) in rows.enumerate() {
                if r.len() != c.dofs.len() || r.iter().any(|x| !x.is_finite()) {
                    return Err(Error::invalid(
                        &at(&format!("row {k}")),
                        format!("{r:?}"),
                        &format!("needs {} finite values (one per dof)", c.dofs.len()),
                    ));
                }
            }
            if !c.offset.is_finite() {
                return Err(Error::invalid(&at("offset"), c.offset, "must be finite"));
            }
            if (c.law.friction > 0.0) == c.tangents.is_empty() || c.tangents.len() > 2 {
                return Err(Error::invalid(
                    &at("tangents"),
                    c.tangents.len(),
                    "one or two tangential rows with friction > 0, none without",
                ));
            }
        }
        let laws = contacts.iter().map(|c| c.law).collect();
        Ok(LinearContacts { contacts, laws })
    }
}

impl ContactSet for LinearContacts {
    fn len(&self) -> usize {
        self.contacts.len()
    }
    fn is_linear(&self) -> bool {
        true
    }
    fn dim(&self, alpha: usize) -> usize {
        1 + self.contacts[alpha].tangents.len()
    }
    fn pattern(&self) -> Vec<Vec<usize>> {
        self.contacts
            .iter()
            .flat_map(|c| std::iter::repeat_n(c.dofs.clone(), 1 + c.tangents.len()))
            .collect()
    }
    fn evaluate(&self, q: &[f64], gap: &mut [f64], jac: &mut ContactJacobian) {
        let mut row = 0;
        for (a, c) in self.contacts.iter().enumerate() {
            gap[a] = c.offset
                + c.dofs
                    .iter()
                    .zip(&c.normal)
                    .map(|(&d, n)| n * q[d])
                    .sum::<f64>();
            jac.col_values_mut(row).copy_from_slice(&c.normal);
            for (k, t) in c.tangents.iter().enumerate() {
                jac.col_values_mut(row + 1 + k).copy_from_slice(t);
            }
            row += 1 + c.tangents.len();
        }
    }
    fn laws(&self) -> &[ContactLaw] {
        &self.laws
    }
}
