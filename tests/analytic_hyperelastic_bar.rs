//! Large-deformation laws in their small-strain limit (issue 17 §2, check (c)): the
//! paper's bar (Table 1) as a hex8 solid (ν = 0, square section of area π·10⁻⁴ m²) and as
//! a plane-strain quad4 strip (section 0.0177 m², plateau 71 636 N) hitting the rigid
//! wall at 0.1 m/s, with St. Venant–Kirchhoff and neo-Hookean materials. The
//! strain is |v0|/c0 = 1.9e-5, so both give the linear solid's plateau E S |v0| / c0 =
//! 1271.472 N within 0.1 % (the issue's figure; measured 3e-6 to 1.6e-5 on 100 cells at
//! h = 2e-6 with Moreau–Jean and Algorithm 2), and that of the linear solid on the same
//! mesh and step within 1e-4 (measured 4.8e-6 neo-Hookean, 1.45e-5 SVK, the sign of each
//! law's stiffening or softening in compression: 1e-4 is about ten times the strain).

use signorini::app::run_scene;
use signorini::run::Quiet;
use signorini::scene::file::Scene;

/// The bar as a 3-D hex8 solid, or (`plane`) as a plane-strain quad4 strip of height
/// 0.0177 m and unit thickness (section 0.0177 m²: the plateau E S |v0| / c0 scales with
/// it).
fn bar(model: &str, scheme: &str, plane: bool) -> Scene {
    // (formulation and mesh, velocity, wall point and normal, section)
    let (body, velocity, point, normal, area) = if plane {
        (
            "formulation = \"plane-strain\"\nmesh = { generator = \"rectangle\", cell = \"quad4\", \
             cells = [100, 1], size = [1.0, 0.0177] }",
            "[-0.1, 0.0]",
            "[0.0, 0.0]",
            "[1.0, 0.0]",
            "0.0177",
        )
    } else {
        (
            "mesh = { generator = \"box\", cell = \"hex8\", cells = [100, 1, 1], \
             size = [1.0, 0.017724538509055159, 0.017724538509055159] }",
            "[-0.1, 0.0, 0.0]",
            "[0.0, 0.0, 0.0]",
            "[1.0, 0.0, 0.0]",
            "3.141592653589793e-4",
        )
    };
    let text = format!(
        r#"
[time]
dt = 2e-6
t_end = 6e-4
[scheme]
kind = "{scheme}"
[[bodies]]
name = "bar"
{body}
material = {{ young = 210e9, poisson = 0.0, density = 7800.0, model = "{model}" }}
velocity = {velocity}
[[obstacles]]
name = "wall"
type = "plane"
point = {point}
normal = {normal}
[[contacts]]
body = "bar"
nodes = "x0"
obstacle = "wall"
[reference.impacting_bar]
length = 1.0
area = {area}
young = 210e9
density = 7800.0
velocity = -0.1
"#
    );
    Scene::from_toml(&text).unwrap()
}

#[test]
fn nonlinear_solids_give_the_bar_plateau_at_small_strain() {
    for (scheme, plane) in [
        ("moreau-jean", false),
        ("combined-projection", false),
        ("combined-projection", true),
    ] {
        let lin = run_scene(&bar("linear", scheme, plane), None, &mut Quiet).unwrap();
        let fl = lin.summary.contact.unwrap().plateau_force;
        for model in ["svk", "neo-hookean"] {
            let r = run_scene(&bar(model, scheme, plane), None, &mut Quiet).unwrap();
            let c = r.summary.contact.unwrap();
            let (to_linear, to_exact) = (
                c.plateau_force / fl - 1.0,
                c.plateau_force / c.analytic_force - 1.0,
            );
            eprintln!(
                "{scheme} {model}{}: plateau {} N, {to_linear:+.2e} from the linear solid, \
                 {to_exact:+.2e} from E S |v0| / c0; Newton {:.2} per step",
                if plane { " (plane strain)" } else { "" },
                c.plateau_force,
                r.summary.iterations.newton.mean
            );
            assert!(to_linear.abs() <= 1e-4, "{scheme} {model}: {to_linear:e}");
            assert!(to_exact.abs() <= 1e-3, "{scheme} {model}: {to_exact:e}");
            assert!(
                (c.duration / c.analytic_duration - 1.0).abs() <= 0.02,
                "{scheme} {model}: duration {}",
                c.duration
            );
            if scheme == "combined-projection" {
                assert!(r.summary.max_violation <= 1e-14, "{scheme} {model}");
            }
        }
    }
}
