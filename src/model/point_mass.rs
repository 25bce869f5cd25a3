//! A point mass in `d` dimensions under a constant force: `m v̇ = f + G λ`
//! (the bouncing ball of eq. 7 for `d = 1`; the particle in a circle for `d = 2`).

use super::LinearSystem;
use crate::assembly::{Accumulate, Assembler};
use crate::error::{Error, require_positive};

/// Builds the linear system of a free point mass.
pub fn point_mass(dim: usize, mass: f64, force: &[f64]) -> Result<LinearSystem, Error> {
    require_positive("mass", mass)?;
    if force.len() != dim || force.iter().any(|f| !f.is_finite()) {
        return Err(Error::invalid(
            "force",
            format!("{force:?}"),
            &format!("must hold {dim} finite components"),
        ));
    }
    let mut am = Assembler::new(dim, dim);
    let ak = Assembler::new(dim, 0);
    for i in 0..dim {
        am.add(i, i, mass);
    }
    Ok(LinearSystem {
        mass: am.finish(),
        stiffness: ak.finish(),
        damping: None,
        force: force.to_vec(),
        dofs_per_node: dim,
        component: super::interleaved_components(dim, dim),
    })
}
