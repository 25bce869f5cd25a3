//! Issue 48: a linear body never rotates silently, and the corotational law turns.
//!
//! Small-strain elasticity is not invariant under rotation: a linear hex8 cube spun at
//! ω = 300 rad/s does not turn but stretches along its tangents, and one turned a
//! quarter turn by its `initial_displacement` starts with `2(λ + μ)V` of strain energy.
//! The run measures each linear cell's rotation (`run::rotations`) and stops past
//! `scheme.max_rotation` (0.05 rad); the corotational law (`model = "corotational"`: the
//! linear law of the Biot strain `U − I`, `F = RU`) turns the same cube rigidly.

use signorini::app::run_scene;
use signorini::run::Quiet;
use signorini::scene::file::Scene;

/// A 0.1 m steel cube (hex8, 4³ cells) spinning about z through its centre at 300 rad/s,
/// free, for `t_end` with step 1e-4 s, under the energy–momentum scheme (Gonzalez's
/// discrete gradient; the θ-method's midpoint force gains 2.7 % of the energy in 64 steps
/// here, where the cells' highest modes have ωh ≈ 40).
fn spinning_cube(model: &str, t_end: f64) -> String {
    format!(
        r#"
[time]
dt = 1e-4
t_end = {t_end}
[scheme]
energy_momentum = true
[[bodies]]
name = "cube"
mesh = {{ generator = "box", cell = "hex8", cells = [4, 4, 4], size = [0.1, 0.1, 0.1] }}
material = {{ young = 2.1e11, poisson = 0.3, density = 7800.0, model = "{model}" }}
angular_velocity = [0.0, 0.0, 300.0]
"#
    )
}

/// The linear cube stops at the first check (step 64, where it has "turned"
/// `atan(ωt) = 1.09 rad` by its straight-line tangential motion), exit 1, naming the
/// body, the cell, the angle and the remedy; nothing passes silently.
#[test]
fn a_spinning_linear_body_stops_the_run_naming_the_remedy() {
    let scene = Scene::from_toml(&spinning_cube("linear", 0.02)).unwrap();
    let Err(e) = run_scene(&scene, None, &mut Quiet) else {
        panic!("a spinning linear cube ran to the end");
    };
    let msg = e.to_string();
    assert_eq!(e.exit_code(), 1, "{msg}");
    for needle in [
        "body `cube`",
        "has turned",
        "scheme.max_rotation",
        "corotational",
    ] {
        assert!(msg.contains(needle), "{needle}: {msg}");
    }
    let signorini::Error::RunFailed { step, .. } = e else {
        panic!("{e:?}")
    };
    assert_eq!(step, signorini::run::ENERGY_CHECK_STRIDE);
}

/// A quarter turn given by `initial_displacement` to a linear cube (the rotation about z
/// through its centre, `u = (R − I)(X − c)`) is refused before the first step, exit 2,
/// naming the key; with `scheme.max_rotation = inf` it runs, and its starting strain
/// energy is the closed form `2(λ + μ)V` (the linear strain of `R − I` is `−1` on x and
/// y): 1923.08 J for E = 1e6, ν = 0.3, V = 1e-3 m³ (1e-9 relative, round-off).
#[test]
fn a_linear_body_turned_by_its_initial_displacement_is_refused() {
    let n = 3usize; // 2 cells a side: 3 × 3 × 3 points, generator order x fastest
    let mut rows = Vec::new();
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let (x, y) = (i as f64 * 0.05 - 0.05, j as f64 * 0.05 - 0.05);
                // R(90°) (x, y) − (x, y) = (−y − x, x − y)
                rows.push(format!("[{}, {}, 0.0]", -y - x, x - y));
                let _ = k;
            }
        }
    }
    let text = |extra: &str| {
        format!(
            r#"
[time]
dt = 1e-4
t_end = 1e-3
[scheme]
{extra}
[[bodies]]
name = "cube"
mesh = {{ generator = "box", cell = "hex8", cells = [2, 2, 2], size = [0.1, 0.1, 0.1] }}
material = {{ young = 1e6, poisson = 0.3, density = 1000.0 }}
initial_displacement = [{}]
"#,
            rows.join(", ")
        )
    };
    let scene = Scene::from_toml(&text("")).unwrap();
    let Err(e) = run_scene(&scene, None, &mut Quiet) else {
        panic!("a quarter turn of a linear body ran");
    };
    let msg = e.to_string();
    assert_eq!(e.exit_code(), 2, "{msg}");
    assert!(
        msg.contains("bodies[0].initial_displacement") && msg.contains("1.5708 rad"),
        "{msg}"
    );
    let scene = Scene::from_toml(&text("max_rotation = inf")).unwrap();
    let r = run_scene(&scene, None, &mut Quiet).unwrap();
    let (young, nu, volume) = (1e6, 0.3, 1e-3);
    let (lambda, mu) = (
        young * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
        young / (2.0 * (1.0 + nu)),
    );
    let want = 2.0 * (lambda + mu) * volume;
    let e0 = r.summary.energy[0];
    assert!((e0 - want).abs() <= 1e-9 * want, "{e0} vs {want}");
    assert!(
        r.summary.rotation.is_none(),
        "max_rotation = inf measures nothing"
    );
}

/// The corotational cube turns rigidly: after 0.02 s (0.95 of a turn) every node is at
/// its starting distance from the spin axis through the centre up to the centrifugal
/// stretch `ρω²r²/E` (2.5e-5 at the corners): the corner radius is kept to 1e-4 (the
/// linear law's straight-line motion would put it at `r√(1 + (ωt)²)`, +600 %), and it
/// agrees with the neo-Hookean cube's, the same small-strain law under large rotation,
/// to 1e-6 of the radius (they differ at second order in the 2.5e-5 strain). The centre
/// stays put (momentum 0) to 1e-10 m (what the Newton tolerance leaves: 8.6e-12 m
/// measured).
#[test]
fn the_corotational_law_turns_a_spinning_cube_rigidly() {
    let corner_radius = |model: &str| {
        let scene = Scene::from_toml(&spinning_cube(model, 0.02)).unwrap();
        let r = run_scene(&scene, None, &mut Quiet).unwrap_or_else(|e| panic!("{model}: {e}"));
        let b = &r.summary.bodies[0];
        for i in 0..3 {
            assert!(
                (b.last.centre[i] - 0.05).abs() <= 1e-10,
                "{model}: centre {:?}",
                b.last.centre
            );
        }
        // node 0 is the corner (0, 0, 0): x and y displacements are dofs 0 and 1
        let q = &r.state.q;
        let (x, y) = (0.0 + q[0] - 0.05, 0.0 + q[1] - 0.05);
        (x * x + y * y).sqrt()
    };
    let r0 = (2.0f64 * 0.05 * 0.05).sqrt();
    let rc = corner_radius("corotational");
    assert!(
        (rc - r0).abs() <= 1e-4 * r0,
        "corotational corner radius {rc} vs {r0}"
    );
    let rn = corner_radius("neo-hookean");
    assert!(
        (rc - rn).abs() <= 1e-6 * r0,
        "corotational {rc} vs neo-Hookean {rn}"
    );
}
