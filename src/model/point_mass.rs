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
        ordering: None,
        loads: Vec::new(),
        prescribed: None,
        nonlinear: Vec::new(),
    })
}

/// Builds the one-dof oscillator of eq. 8: `m q̈ + c q̇ + k q = f`.
pub fn oscillator(
    mass: f64,
    damping: f64,
    stiffness: f64,
    force: f64,
) -> Result<LinearSystem, Error> {
    crate::error::require_in("stiffness", stiffness, 0.0, f64::MAX)?;
    crate::error::require_in("damping", damping, 0.0, f64::MAX)?;
    let mut sys = point_mass(1, mass, &[force])?;
    let mut ak = Assembler::new(1, 1);
    ak.add(0, 0, stiffness);
    sys.stiffness = ak.finish();
    // C = (c/m) M: Rayleigh with α = c/m
    sys.with_rayleigh(damping / mass, 0.0)
}

/// Builds the rigid 2-D block of eq. 10: `q = [x, y, θ]`, `M = diag(m, m, I)` with
/// `I = m (l² + L²) / 12`, weight `−m g` on y, no stiffness.
pub fn rigid_block(mass: f64, length: f64, thickness: f64, g: f64) -> Result<LinearSystem, Error> {
    require_positive("mass", mass)?;
    require_positive("length", length)?;
    require_positive("thickness", thickness)?;
    crate::error::require_in("gravity", g, 0.0, f64::MAX)?;
    let inertia = mass * (length * length + thickness * thickness) / 12.0;
    let mut am = Assembler::new(3, 3);
    for (i, v) in [mass, mass, inertia].into_iter().enumerate() {
        am.add(i, i, v);
    }
    Ok(LinearSystem {
        mass: am.finish(),
        stiffness: Assembler::new(3, 0).finish(),
        damping: None,
        force: vec![0.0, -mass * g, 0.0],
        dofs_per_node: 3,
        component: vec![0, 1, 2],
        ordering: None,
        loads: Vec::new(),
        prescribed: None,
        nonlinear: Vec::new(),
    })
}

/// A rigid system with a diagonal mass matrix (`masses`: masses and inertias, one per
/// dof) under constant generalized forces: e.g. the slider (height) and roller (angle)
/// of the paper's Fig. 8.
pub fn diagonal(masses: &[f64], force: &[f64]) -> Result<LinearSystem, Error> {
    if masses.len() != force.len() || masses.is_empty() {
        return Err(Error::invalid(
            "masses",
            format!("{} masses, {} forces", masses.len(), force.len()),
            "needs one mass and one force per dof",
        ));
    }
    let n = masses.len();
    let mut am = Assembler::new(n, n);
    for (i, &m) in masses.iter().enumerate() {
        require_positive(&format!("masses[{i}]"), m)?;
        am.add(i, i, m);
    }
    if let Some(i) = force.iter().position(|f| !f.is_finite()) {
        return Err(Error::invalid(
            &format!("force[{i}]"),
            force[i],
            "must be finite",
        ));
    }
    Ok(LinearSystem {
        mass: am.finish(),
        stiffness: Assembler::new(n, 0).finish(),
        damping: None,
        force: force.to_vec(),
        dofs_per_node: n,
        component: (0..n).map(|i| i.min(2) as u8).collect(),
        ordering: None,
        loads: Vec::new(),
        prescribed: None,
        nonlinear: Vec::new(),
    })
}
