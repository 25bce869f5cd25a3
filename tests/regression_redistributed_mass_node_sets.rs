//! Issue 12 §2: the redistributed mass (no mass on contact nodes) took the contact nodes
//! only from named node sets, so contacts on `boundary`, `all` or filtered by `within`
//! silently kept their mass. Now it uses the contacts' own nodes: their rows of M are
//! empty, and the body's mass is unchanged (ρ V, to round-off).

mod common;

use common::bad::BOX_ON_FLOOR;
use signorini::scene::file::Scene;

fn scene(nodes: &str, within: &str) -> String {
    BOX_ON_FLOOR
        .replace(
            "MESH",
            "mesh = { generator = \"box\", cell = \"hex8\", cells = [2, 2, 2], size = [0.1, 0.1, 0.1] }\n\
             mass = \"redistributed\"",
        )
        .replace("nodes = \"z0\"", &format!("nodes = \"{nodes}\"\n{within}"))
}

/// (mass on the bottom face's dofs, mass elsewhere, total mass of one component)
fn masses(text: &str) -> (f64, f64, f64) {
    let (model, _) = Scene::from_toml(text).unwrap().build().unwrap();
    let g = &model.geometry;
    let m = model.problem.system.mass.as_ref();
    let (mut bottom, mut rest) = (0.0, 0.0);
    for (k, d) in g.dof_of.iter().enumerate() {
        let Some(d) = *d else { continue };
        let z = g.points[k / g.dim][2];
        let row: f64 = (m.col_ptr()[d]..m.col_ptr()[d + 1])
            .map(|i| m.val()[i].abs())
            .sum();
        if z == 0.0 { bottom += row } else { rest += row }
    }
    (bottom, rest, model.problem.system.total_mass())
}

#[test]
fn contact_nodes_from_boundary_and_within_carry_no_mass() {
    let rho_v = 1000.0 * 1e-3;
    // the named set: the reference behaviour
    let (b, r, total) = masses(&scene("z0", ""));
    assert_eq!(b, 0.0);
    assert!(r > 0.0 && (total - rho_v).abs() < 1e-12 * rho_v, "{total}");
    // `boundary` within 1.5 cm of the floor selects the same 9 bottom nodes
    let (b, _, total) = masses(&scene("boundary", "within = 0.015"));
    assert_eq!(b, 0.0, "the bottom nodes kept mass {b}");
    assert!((total - rho_v).abs() < 1e-12 * rho_v, "{total}");
    // `all` within 1.5 cm: the same nodes
    let (b, _, total) = masses(&scene("all", "within = 0.015"));
    assert_eq!(b, 0.0, "the bottom nodes kept mass {b}");
    assert!((total - rho_v).abs() < 1e-12 * rho_v, "{total}");
    // the consistent mass, for contrast, does put mass there
    let (b, _, _) =
        masses(&scene("boundary", "within = 0.015").replace("mass = \"redistributed\"", ""));
    assert!(b > 0.0);
}
