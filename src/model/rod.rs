//! One-dimensional bar discretized by P1 rod elements (eq. 71).
//!
//! `Me = ρ S l/6 [[2,1],[1,2]]` (consistent) or `ρ S l/2 I` (lumped, row sums),
//! `Ke = E S/l [[1,−1],[−1,1]]`, `l = L/N`. Node 0 sits at `x = 0` and is the contact
//! node of the impacting-bar scene; node `N` at `x = L`.

use nalgebra::Matrix2;

use super::{LinearSystem, MassKind};
use crate::assembly::{Accumulate, Assembler};
use crate::error::{Error, require_positive};

/// A uniform elastic rod.
#[derive(Clone, Debug, PartialEq)]
pub struct Rod {
    /// Length `L` (m).
    pub length: f64,
    /// Cross-section area `S` (m²).
    pub area: f64,
    /// Young's modulus `E` (Pa).
    pub young: f64,
    /// Density `ρ` (kg/m³).
    pub density: f64,
    /// Number of elements `N`.
    pub elements: usize,
    /// Consistent or lumped mass.
    pub mass: MassKind,
}

impl Rod {
    /// Checks every parameter; the error names the field and value.
    pub fn validate(&self) -> Result<(), Error> {
        require_positive("length", self.length)?;
        require_positive("area", self.area)?;
        require_positive("young", self.young)?;
        require_positive("density", self.density)?;
        if self.elements == 0 {
            return Err(Error::invalid("elements", 0, "must be at least 1"));
        }
        Ok(())
    }

    /// Number of nodes (`N + 1`), one displacement dof each.
    pub fn nodes(&self) -> usize {
        self.elements + 1
    }

    /// Element length `l = L/N`.
    pub fn element_length(&self) -> f64 {
        self.length / self.elements as f64
    }

    /// Wave speed `c0 = √(E/ρ)` (m/s).
    pub fn wave_speed(&self) -> f64 {
        (self.young / self.density).sqrt()
    }

    /// Consistent element mass matrix (eq. 71).
    pub fn element_mass(&self) -> Matrix2<f64> {
        let m = self.density * self.area * self.element_length();
        Matrix2::new(2.0, 1.0, 1.0, 2.0) * (m / 6.0)
    }

    /// Element stiffness matrix (eq. 71).
    pub fn element_stiffness(&self) -> Matrix2<f64> {
        Matrix2::new(1.0, -1.0, -1.0, 1.0) * (self.young * self.area / self.element_length())
    }

    /// Assembles `M` and `K` (no damping, no external force).
    pub fn assemble(&self) -> Result<LinearSystem, Error> {
        self.validate()?;
        let n = self.nodes();
        let me = self.element_mass();
        let ke = self.element_stiffness();
        let mut am = Assembler::new(n, 4 * self.elements);
        let mut ak = Assembler::new(n, 4 * self.elements);
        for e in 0..self.elements {
            let dofs = [e, e + 1];
            // node 0 is the contact node of the bar scene (redistributed mass)
            super::add_element_mass(
                &mut am,
                (self.mass, super::element::Lumping::RowSum),
                &dofs,
                |a, b| me[(a, b)],
                |a| dofs[a] == 0,
            );
            ak.add_element(&dofs, |a, b| ke[(a, b)]);
        }
        Ok(LinearSystem {
            mass: am.finish(),
            stiffness: ak.finish(),
            damping: None,
            force: vec![0.0; n],
            dofs_per_node: 1,
            component: super::interleaved_components(n, 1),
            ordering: None,
            loads: Vec::new(),
            prescribed: None,
            nonlinear: Vec::new(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rod(mass: MassKind) -> Rod {
        Rod {
            length: 2.0,
            area: 0.5,
            young: 3.0,
            density: 4.0,
            elements: 7,
            mass,
        }
    }

    #[test]
    fn total_mass_is_rho_s_l_for_every_mass_kind() {
        for kind in [
            MassKind::Consistent,
            MassKind::Lumped,
            MassKind::Redistributed,
        ] {
            let s = rod(kind).assemble().unwrap();
            // ρ S L = 4 · 0.5 · 2 = 4 kg; sums of a few doubles are exact to rounding.
            assert!((s.total_mass() - 4.0).abs() < 1e-13);
        }
    }

    #[test]
    fn rigid_translation_has_no_elastic_force() {
        let s = rod(MassKind::Consistent).assemble().unwrap();
        let ones = vec![1.0; 8];
        let mut y = vec![0.0; 8];
        crate::linalg::spmv(s.stiffness.as_ref(), &ones, &mut y);
        assert!(y.iter().all(|v| v.abs() < 1e-12));
        // Uniform strain ε = 0.1: u = 0.1 x gives end forces ±E S ε = ±0.15 N.
        let u: Vec<f64> = (0..8).map(|i| 0.1 * i as f64 * 2.0 / 7.0).collect();
        crate::linalg::spmv(s.stiffness.as_ref(), &u, &mut y);
        assert!((y[0] + 0.15).abs() < 1e-12 && (y[7] - 0.15).abs() < 1e-12);
    }

    #[test]
    fn bad_parameters_name_the_field() {
        let mut r = rod(MassKind::Lumped);
        r.young = f64::NAN;
        let e = r.assemble().unwrap_err().to_string();
        assert!(e.contains("young") && e.contains("NaN"), "{e}");
        r.young = 1.0;
        r.elements = 0;
        assert!(r.assemble().unwrap_err().to_string().contains("elements"));
    }
}
