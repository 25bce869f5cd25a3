//! Contact nodes on symmetry planes (issue 51's 3-D Hertz ball): the node rule used to
//! refuse a contact node with any held component ("is fixed and cannot be a contact
//! node"), so a quarter model whose pole lies on both symmetry planes could not use it.
//! Against a plane whose normal is free at the node, the node now gets its row on its
//! free dofs.

use signorini::scene::file::Scene;

fn block(quarter: bool, friction: f64) -> String {
    let (cells, size, origin, symmetry) = if quarter {
        (
            "[2, 2, 2]",
            "[0.05, 0.05, 0.05]",
            "[0.0, 0.0, 0.001]",
            "[[prescribed]]\nbody = \"block\"\nnodes = \"x0\"\nvelocity = [0.0, 0.0, 0.0]\ncomponents = [0]\n\
             [[prescribed]]\nbody = \"block\"\nnodes = \"y0\"\nvelocity = [0.0, 0.0, 0.0]\ncomponents = [1]\n",
        )
    } else {
        ("[4, 4, 2]", "[0.1, 0.1, 0.05]", "[-0.05, -0.05, 0.001]", "")
    };
    format!(
        r#"
[time]
dt = 2e-6
t_end = 2e-3
[[bodies]]
name = "block"
mesh = {{ generator = "box", cell = "hex8", cells = {cells}, size = {size}, origin = {origin} }}
material = {{ young = 1e8, poisson = 0.3, density = 1000.0 }}
velocity = [0.0, 0.0, -2.0]
{symmetry}
[[obstacles]]
name = "floor"
type = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
[[contacts]]
body = "block"
nodes = "z0"
obstacle = "floor"
friction = {friction}
"#
    )
}

/// The total contact impulse of each step and the kinetic energy at the end.
fn run(text: &str) -> (Vec<f64>, f64) {
    let scene = Scene::from_toml(text).unwrap();
    let (model, _) = scene.build().unwrap();
    let mut integ = model.into_integrator(&scene.scheme, scene.time.dt).unwrap();
    let mut impulses = Vec::new();
    for _ in 0..scene.steps() {
        integ.prepare().unwrap();
        let st = integ.step().unwrap();
        assert_eq!(st.caps_hit, 0);
        impulses.push(integ.state().impulse.iter().sum());
    }
    let s = integ.state();
    (impulses, integ.system().kinetic_energy(&s.q, &s.v))
}

/// A hex8 block dropped at 2 m/s on a plane (Algorithm 2, node rule; frictionless and
/// μ = 0.3), whole and as the quarter x ≥ 0, y ≥ 0 with its symmetry planes held: the
/// quarter's contact impulses are a quarter of the whole block's at every step, and its
/// kinetic energy at the end a quarter, to 1e-9 of the largest (the two runs solve
/// different one-step problems, 25 and 9 contact nodes, whose round-off differs).
#[test]
fn a_quarter_model_on_its_symmetry_planes_is_a_quarter_of_the_whole() {
    for mu in [0.0, 0.3] {
        let (full, kf) = run(&block(false, mu));
        let (quarter, kq) = run(&block(true, mu));
        let scale = full.iter().fold(0.0f64, |m, p| m.max(p.abs()));
        assert!(scale > 0.0, "the block never touched");
        for (k, (a, b)) in full.iter().zip(&quarter).enumerate() {
            assert!(
                (a - 4.0 * b).abs() <= 1e-9 * scale,
                "μ = {mu}, step {k}: {a} against 4 × {b}"
            );
        }
        assert!(
            (kf - 4.0 * kq).abs() <= 1e-9 * kf.max(1e-30),
            "μ = {mu}: {kf} against 4 × {kq}"
        );
    }
}
