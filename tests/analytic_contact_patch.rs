//! The contact patch test (issue 51 §3): a block pressed on a rigid frictionless plane by
//! a uniform pressure `p` on its top face. The exact solution is a uniform uniaxial
//! stress `σ = −p` along the plane's normal (the sides free, the base sliding freely):
//! a displacement field linear in the coordinates, which every element kind represents
//! exactly, and a uniform contact pressure `p` on the base. A contact discretization
//! passes when that state is an equilibrium of the discrete system: started there at
//! rest (`initial_displacement` = the exact field, `v = 0`) under the default scheme
//! (Algorithm 2), the block stays there, its contact rows carrying exactly the
//! consistent nodal forces of the pressure.
//!
//! Measured: the largest departure of the displacement from the exact field over the
//! run, relative to the exact field's largest displacement, and the total contact
//! impulse of each step against `p A h`. Tolerance 1e-8: the state is exact, so what is
//! left is the round-off of the factorization and of the contact solvers' residuals
//! (1e-12 and below where it passes, measured), while a rule that cannot carry the
//! consistent forces departs by the forces it misses (the node rule on hex20's quad8
//! faces, whose corners would have to pull: −A/12 each) — 1e-3 and more.

use signorini::scene::file::{NodalField, Rows, Scene};

const E: f64 = 1e8;
const NU: f64 = 0.3;
const P: f64 = 1e5;
const STEPS: usize = 40;

/// The scene: a block of `cell`s on the plane through the origin normal to the last
/// axis, the pressure on its top face set `top`, the base set `base` in contact with
/// `rule`.
fn scene(dim_body: &str, cell: &str, cells: &str, rule: &str) -> Scene {
    let (mesh, obstacle, base, top, formulation) = match dim_body {
        "solid" => (
            format!(
                "{{ generator = \"box\", cell = \"{cell}\", cells = {cells}, size = [0.1, 0.08, 0.05] }}"
            ),
            "point = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]",
            "z0",
            "z1",
            "\"solid\"".to_string(),
        ),
        f => (
            format!(
                "{{ generator = \"rectangle\", cell = \"{cell}\", cells = {cells}, size = [0.1, 0.05] }}"
            ),
            "point = [0.0, 0.0]\nnormal = [0.0, 1.0]",
            "y0",
            "y1",
            if f == "plane-stress" {
                "{ plane-stress = { thickness = 0.01 } }".to_string()
            } else {
                format!("\"{f}\"")
            },
        ),
    };
    let text = format!(
        r#"
[time]
dt = 1e-5
t_end = {t_end}
[[bodies]]
name = "block"
mesh = {mesh}
formulation = {formulation}
material = {{ young = {E}, poisson = {NU}, density = 1000.0 }}
[[obstacles]]
name = "floor"
type = "plane"
{obstacle}
[[contacts]]
body = "block"
nodes = "{base}"
obstacle = "floor"
rule = "{rule}"
[[pressures]]
body = "block"
faces = "{top}"
pressure = {P}
"#,
        t_end = STEPS as f64 * 1e-5
    );
    Scene::from_toml(&text).unwrap()
}

/// The exact displacement at `x` (uniaxial stress `−p` along the last axis of the body,
/// lateral expansion about the block's centre line; the axisymmetric body about its axis
/// r = 0).
fn exact(formulation: &str, x: &[f64]) -> Vec<f64> {
    match formulation {
        "solid" => vec![
            NU * P * (x[0] - 0.05) / E,
            NU * P * (x[1] - 0.04) / E,
            -P * x[2] / E,
        ],
        "plane-strain" => vec![
            NU * (1.0 + NU) * P * (x[0] - 0.05) / E,
            -(1.0 - NU * NU) * P * x[1] / E,
        ],
        "plane-stress" => vec![NU * P * (x[0] - 0.05) / E, -P * x[1] / E],
        _ => vec![NU * P * x[0] / E, -P * x[1] / E],
    }
}

/// Runs the patch test on scene `s` (every body of `formulation`, the exact field of
/// [`exact`] over all of them, the pressed area `area`); returns (largest displacement
/// departure relative to the exact field's largest displacement, largest relative
/// departure of a step's total contact impulse on the plane from `p A h`: the entries
/// against an obstacle; 0 in a scene with none).
fn run_patch(mut s: Scene, formulation: &str, area: f64) -> (f64, f64) {
    let (model, _) = s.build().unwrap();
    let geometry = model.geometry.clone();
    let dim = geometry.dim;
    let u: Vec<Vec<f64>> = geometry
        .points
        .iter()
        .map(|x| exact(formulation, &x[..dim]))
        .collect();
    // each body's rows of the field: its points are contiguous, in body order
    let mut start = 0;
    for (b, body) in s.bodies.iter_mut().enumerate() {
        let end = 1 + geometry
            .cells
            .iter()
            .filter(|c| c.2 == b)
            .flat_map(|c| c.1.iter().copied())
            .max()
            .unwrap();
        body.initial_displacement = Some(NodalField::Rows(Rows::from_rows(&u[start..end])));
        start = end;
    }
    let (model, _) = s.build().unwrap();
    let h = s.time.dt;
    let on_plane: Vec<bool> = model
        .geometry
        .contacts
        .iter()
        .map(|c| s.contacts[c.entry].obstacle.is_some())
        .collect();
    let mut integ = model.into_integrator(&s.scheme, h).unwrap();
    let scale = u.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let (mut worst_u, mut worst_p) = (0.0f64, 0.0f64);
    for step in 0..STEPS {
        integ.prepare().unwrap();
        let st = integ.step().unwrap();
        assert_eq!(st.caps_hit, 0, "{formulation}");
        let state = integ.state();
        for (p, up) in u.iter().enumerate() {
            for (i, ui) in up.iter().enumerate() {
                if let Some(d) = geometry.dof_of[p * dim + i] {
                    worst_u = worst_u.max((state.q[d] - ui).abs() / scale);
                }
            }
        }
        let total: f64 = state
            .impulse
            .iter()
            .zip(&on_plane)
            .filter(|(_, on)| **on)
            .map(|(p, _)| p)
            .sum();
        // Schatzman–Paoli starts its two-step recurrence from `q₋₁ = q₀ − h v₀ + ½h²a₀`,
        // `a₀` without the contact force (unknown before the first step): started in a
        // loaded contact, its first step carries half the impulse, the state exact
        // (measured: 0.5, then 1e-14)
        let first_sp =
            step == 0 && s.scheme.kind == signorini::integrators::SchemeKind::SchatzmanPaoli;
        if on_plane.iter().any(|&on| on) && !first_sp {
            worst_p = worst_p.max((total / (P * area * h) - 1.0).abs());
        }
    }
    (worst_u, worst_p)
}

/// The pressed area of a block of `formulation`.
fn area(formulation: &str) -> f64 {
    match formulation {
        "solid" => 0.1 * 0.08,
        "axisymmetric" => std::f64::consts::PI * 0.1 * 0.1,
        "plane-stress" => 0.1 * 0.01,
        _ => 0.1,
    }
}

/// The patch test of one block on the plane.
fn patch(formulation: &str, cell: &str, cells: &str, rule: &str) -> (f64, f64) {
    run_patch(
        scene(formulation, cell, cells, rule),
        formulation,
        area(formulation),
    )
}

/// Asserts that the block of `cell`s with contact `rule` stays in the uniform state
/// (1e-8, above), printing its figures.
fn assert_passes(f: &str, cell: &str, cells: &str, rule: &str) {
    let (du, dp) = patch(f, cell, cells, rule);
    println!("{rule} {f} {cell}: displacement {du:.2e}, impulse {dp:.2e}");
    assert!(du < 1e-8 && dp < 1e-8, "{rule} {f} {cell}: {du:e} {dp:e}");
}

/// With the surface rule every face kind it takes transmits the uniform pressure
/// exactly: plane strain on quad4, tri3, quad8, quad9 and tri6 edges (2 and 3 nodes),
/// plane stress, the axisymmetric cylinder (ring faces, `2πr`), and the solid's quad4
/// and quad9 faces (hex8, hex27, rows at face points) and tri3, tri6 and quad8 faces
/// (tet4, tet10, hex20: rows per face node weighted by their mortar multipliers — the
/// quad8 corners' consistent forces, −A/12, are then carried by the rows of the face's
/// other nodes).
#[test]
fn the_surface_rule_passes_the_patch_test() {
    for (f, cell, cells) in [
        ("plane-strain", "quad4", "[4, 3]"),
        ("plane-strain", "tri3", "[4, 3]"),
        ("plane-strain", "quad8", "[3, 2]"),
        ("plane-strain", "quad9", "[3, 2]"),
        ("plane-strain", "tri6", "[3, 2]"),
        ("plane-stress", "quad9", "[3, 2]"),
        ("axisymmetric", "quad4", "[4, 3]"),
        ("axisymmetric", "quad9", "[3, 2]"),
        ("solid", "hex8", "[3, 2, 2]"),
        ("solid", "hex27", "[2, 2, 1]"),
        ("solid", "tet4", "[2, 2, 1]"),
        ("solid", "tet10", "[2, 2, 1]"),
        ("solid", "hex20", "[2, 2, 1]"),
    ] {
        assert_passes(f, cell, cells, "surface");
    }
}

/// The node rule passes where the consistent nodal forces of a uniform pressure are
/// non-negative at every node (edges of 2 and 3 nodes, quad4, quad9 and tri3/tri6
/// faces: tri6 corners carry 0), and fails on hex20's quad8 faces, whose corners would
/// have to carry −A/12: the block leaves the uniform state by more than 1e-3 of its
/// displacement within the run.
#[test]
fn the_node_rule_fails_only_where_a_corner_would_pull() {
    for (f, cell, cells) in [
        ("plane-strain", "quad4", "[4, 3]"),
        ("plane-strain", "quad8", "[3, 2]"),
        ("axisymmetric", "quad9", "[3, 2]"),
        ("solid", "hex8", "[3, 2, 2]"),
        ("solid", "tet4", "[2, 2, 1]"),
        ("solid", "tet10", "[2, 2, 1]"),
        ("solid", "hex27", "[2, 2, 1]"),
    ] {
        assert_passes(f, cell, cells, "nodes");
    }
    let (du, dp) = patch("solid", "hex20", "[2, 2, 1]", "nodes");
    println!("nodes solid hex20: displacement {du:.2e}, impulse {dp:.2e}");
    assert!(du > 1e-3, "hex20 with the node rule: {du:e}");
}

/// [`stacked`] in 3-D: boxes 0.1 × 0.08 (× 0.05 below, × 0.04 above).
fn stacked3(
    lower: (&str, &str),
    upper: (&str, &str),
    rule: &str,
) -> Result<Scene, signorini::Error> {
    two_blocks(None, lower, upper, rule)
}

/// Two blocks of one material stacked on the plane (2-D), their interface non-matching
/// (`cells` along x differ), the upper pressed on its top: the exact field of one block
/// holds across both. The lower block stands on the plane with the surface rule (exact,
/// above); the upper against the lower's top with `rule`.
fn stacked(
    formulation: &str,
    lower: (&str, &str),
    upper: (&str, &str),
    rule: &str,
) -> Result<Scene, signorini::error::Error> {
    two_blocks(Some(formulation), lower, upper, rule)
}

/// The two stacked blocks of [`stacked`] (a 2-D `formulation`) and [`stacked3`]
/// (`None`: solid).
fn two_blocks(
    formulation: Option<&str>,
    lower: (&str, &str),
    upper: (&str, &str),
    rule: &str,
) -> Result<Scene, signorini::error::Error> {
    // generator, the lower and upper sizes and origin, the vertical axis's sets, the plane
    let (generator, sizes, up, (base, top), plane, form) = match formulation {
        None => (
            "box",
            ("[0.1, 0.08, 0.05]", "[0.1, 0.08, 0.04]"),
            "[0.0, 0.0, 0.05]",
            ("z0", "z1"),
            "point = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]",
            String::new(),
        ),
        Some(f) => (
            "rectangle",
            ("[0.1, 0.05]", "[0.1, 0.04]"),
            "[0.0, 0.05]",
            ("y0", "y1"),
            "point = [0.0, 0.0]\nnormal = [0.0, 1.0]",
            if f == "plane-stress" {
                "formulation = { plane-stress = { thickness = 0.01 } }".to_string()
            } else {
                format!("formulation = \"{f}\"")
            },
        ),
    };
    // the lower block on the plane with the surface rule, or the node rule on
    // triangles (both exact there, above)
    let floor = match lower.0 {
        "tet4" | "tet10" => {
            format!("[[contacts]]\nbody = \"lower\"\nnodes = \"{base}\"\nobstacle = \"floor\"")
        }
        _ => format!(
            "[[contacts]]\nbody = \"lower\"\nnodes = \"{base}\"\nobstacle = \"floor\"\nrule = \"surface\""
        ),
    };
    let text = format!(
        r#"
[time]
dt = 1e-5
t_end = {t_end}
[[bodies]]
name = "lower"
mesh = {{ generator = "{generator}", cell = "{lc}", cells = {lcs}, size = {ls} }}
{form}
material = {{ young = {E}, poisson = {NU}, density = 1000.0 }}
[[bodies]]
name = "upper"
mesh = {{ generator = "{generator}", cell = "{uc}", cells = {ucs}, size = {us}, origin = {up} }}
{form}
material = {{ young = {E}, poisson = {NU}, density = 1000.0 }}
[[obstacles]]
name = "floor"
type = "plane"
{plane}
{floor}
[[contacts]]
body = "upper"
nodes = "{base}"
target = {{ body = "lower", surface = "{top}" }}
rule = "{rule}"
[[pressures]]
body = "upper"
faces = "{top}"
pressure = {P}
"#,
        t_end = STEPS as f64 * 1e-5,
        lc = lower.0,
        lcs = lower.1,
        uc = upper.0,
        ucs = upper.1,
        ls = sizes.0,
        us = sizes.1,
    );
    Scene::from_toml(&text)
}

/// Non-matching meshes pressed together (the other half of the patch test): with the
/// surface rule (mortar rows, [`signorini::contact::mortar`]) the two blocks stay in
/// the uniform state to round-off — linear and quadratic edges, plane strain, plane
/// stress and axisymmetric, the upper block's edges split 3 : 4 or 2 : 3 against the
/// lower's. Node-to-surface rows (`rule = "nodes"`) do not: the lower block's top
/// nodes get the upper nodes' forces split by where those fall on its edges, not the
/// consistent `p ∫ N_m`, and the blocks leave the uniform state by more than 1e-4 of
/// their displacement (node-to-surface rows on a quadratic target are refused).
#[test]
fn non_matching_blocks_pass_with_mortar_rows_and_fail_with_nodes() {
    for (f, lower, upper) in [
        ("plane-strain", ("quad4", "[4, 2]"), ("quad4", "[3, 2]")),
        ("plane-strain", ("tri3", "[4, 2]"), ("quad4", "[3, 2]")),
        ("plane-strain", ("quad9", "[3, 2]"), ("quad8", "[2, 2]")),
        ("plane-strain", ("quad4", "[4, 2]"), ("quad9", "[3, 2]")),
        ("plane-stress", ("quad4", "[4, 2]"), ("quad4", "[3, 2]")),
        ("axisymmetric", ("quad4", "[4, 2]"), ("quad4", "[3, 2]")),
        ("axisymmetric", ("quad9", "[3, 2]"), ("quad9", "[2, 2]")),
    ] {
        let (du, dp) = run_patch(stacked(f, lower, upper, "surface").unwrap(), f, area(f));
        println!("mortar {f} {lower:?} on {upper:?}: displacement {du:.2e}, impulse {dp:.2e}");
        assert!(
            du < 1e-8 && dp < 1e-8,
            "{f} {lower:?} {upper:?}: {du:e} {dp:e}"
        );
        if ["quad8", "quad9", "tri6"].contains(&lower.0) {
            // node-to-surface rows take straight target facets only: refused by name
            let e = stacked(f, lower, upper, "nodes")
                .and_then(|s| s.build().map(|_| ()))
                .unwrap_err();
            assert!(e.to_string().contains("quadratic cell"), "{e}");
            continue;
        }
        let (du, dp) = run_patch(stacked(f, lower, upper, "nodes").unwrap(), f, area(f));
        println!("nodes  {f} {lower:?} on {upper:?}: displacement {du:.2e}, impulse {dp:.2e}");
        assert!(
            du > 1e-4,
            "{f} {lower:?} {upper:?} with node-to-surface rows: {du:e}"
        );
    }
}

/// The 3-D patch test between non-matching blocks: mortar rows clipped face against face
/// (3 × 3 against 2 × 2 faces, and triangles against quadrilaterals) transmit the uniform
/// pressure to round-off on tri3, quad4, tri6 and quad9 slave faces and tri3, quad4,
/// quad8 and quad9 targets; node-to-surface rows leave it by more than 1e-4 between
/// the linear blocks (quadratic targets are refused).
#[test]
fn non_matching_boxes_pass_with_mortar_rows() {
    for (lower, upper) in [
        (("hex8", "[3, 3, 2]"), ("hex8", "[2, 2, 2]")),
        (("hex8", "[3, 3, 2]"), ("tet4", "[2, 2, 1]")),
        (("tet4", "[3, 3, 1]"), ("hex8", "[2, 2, 2]")),
        (("hex8", "[3, 3, 2]"), ("hex27", "[2, 2, 1]")),
        (("hex27", "[2, 2, 1]"), ("hex8", "[3, 3, 2]")),
        (("hex20", "[2, 2, 1]"), ("hex27", "[3, 3, 1]")),
        (("hex8", "[3, 3, 2]"), ("tet10", "[2, 2, 1]")),
        (("tet10", "[2, 2, 1]"), ("hex8", "[3, 3, 2]")),
        (("hex8", "[3, 3, 2]"), ("hex20", "[2, 2, 1]")),
    ] {
        let (du, dp) = run_patch(
            stacked3(lower, upper, "surface").unwrap(),
            "solid",
            area("solid"),
        );
        println!("mortar {lower:?} on {upper:?}: displacement {du:.2e}, impulse {dp:.2e}");
        assert!(du < 1e-8 && dp < 1e-8, "{lower:?} {upper:?}: {du:e} {dp:e}");
        // node-to-surface rows: refused on quadratic targets; on a quadratic slave face
        // they may pass by chance (hex27's 5 nodes a side over hex8's 4 do: the
        // face's Simpson-like weights integrate those hats exactly)
        if [lower.0, upper.0]
            .iter()
            .any(|k| ["hex20", "hex27", "tet10"].contains(k))
        {
            continue;
        }
        let (du, dp) = run_patch(
            stacked3(lower, upper, "nodes").unwrap(),
            "solid",
            area("solid"),
        );
        println!("nodes  {lower:?} on {upper:?}: displacement {du:.2e}, impulse {dp:.2e}");
        assert!(
            du > 1e-4,
            "{lower:?} {upper:?} with node-to-surface rows: {du:e}"
        );
    }
}

/// The patch tests under each of the five schemes (the rows feed every scheme as nodal
/// rows do): the 2-D quad9 block on the plane with the surface rule, and the 3-D
/// non-matching boxes with mortar rows, each within 1e-8 of the uniform state.
#[test]
fn the_patch_tests_pass_under_every_scheme() {
    use signorini::integrators::SchemeKind;
    for kind in SchemeKind::ALL {
        let mut plane = scene("plane-strain", "quad9", "[3, 2]", "surface");
        plane.scheme.kind = kind;
        let (du, dp) = run_patch(plane, "plane-strain", area("plane-strain"));
        let mut boxes = stacked3(("hex8", "[3, 3, 2]"), ("hex8", "[2, 2, 2]"), "surface").unwrap();
        boxes.scheme.kind = kind;
        let (bu, bp) = run_patch(boxes, "solid", area("solid"));
        println!(
            "{}: plane {du:.2e} {dp:.2e}, boxes {bu:.2e} {bp:.2e}",
            kind.name()
        );
        assert!(
            du < 1e-8 && dp < 1e-8 && bu < 1e-8 && bp < 1e-8,
            "{}: {du:e} {dp:e} {bu:e} {bp:e}",
            kind.name()
        );
    }
}
