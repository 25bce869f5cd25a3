//! A free body for the large-deformation tests: a linear system with a hyperelastic part
//! and Moreau–Jean at θ = 1/2, with one contact on a plane far below that never closes.

use signorini::contact::plane::NodesOnPlane;
use signorini::integrators::{Integrator, SchemeKind, SchemeParams, build};
use signorini::model::MassKind;
use signorini::model::hyperelastic::{HyperBody, Hyperelastic};
use signorini::model::solid::{Formulation, Material, Mesh, assemble};
use signorini::model::system::HyperelasticPart;

/// `mesh` of `mat` under `law` (`None`: the linear solid), from `(q0, v0)` with step `h`.
pub fn free_body(
    mesh: &Mesh,
    mat: &Material,
    law: Option<Hyperelastic>,
    (q0, v0): (&[f64], &[f64]),
    h: f64,
) -> Box<dyn Integrator> {
    free_body_with(mesh, mat, law, (q0, v0), h, (false, 1e-10))
}

/// [`free_body`] with the energy–momentum option of the schemes and a Newton tolerance.
pub fn free_body_with(
    mesh: &Mesh,
    mat: &Material,
    law: Option<Hyperelastic>,
    (q0, v0): (&[f64], &[f64]),
    h: f64,
    (energy_momentum, tol): (bool, f64),
) -> Box<dyn Integrator> {
    let n = 3 * mesh.points.len();
    let mut sys = assemble(mesh, mat, Formulation::Solid, MassKind::Consistent).unwrap();
    if let Some(law) = law {
        let body = HyperBody::new(mesh, law).unwrap();
        let part =
            HyperelasticPart::new("body", body, (0..n).map(Some).collect(), Vec::new()).unwrap();
        sys.add_nonlinear_part(std::sync::Arc::new(part));
    }
    let far = NodesOnPlane::new(
        vec![vec![0, 1, 2]],
        vec![mesh.points[0].to_vec()],
        vec![0.0, 0.0, 1.0],
        -100.0,
        0.0,
    )
    .unwrap();
    let mut params = SchemeParams {
        kind: SchemeKind::MoreauJean,
        energy_momentum,
        ..SchemeParams::default()
    };
    params.newton.tol = tol;
    build(&params, sys, Box::new(far), q0, v0, h).unwrap()
}
