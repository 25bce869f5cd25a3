//! Issue 16 §6: Schatzman–Paoli's start-up `q_{−1} = q_0 − h v_0 + h²/2 a_0` took `a_0`
//! from the constant loads only, so a `[[forces]]` load active at t = 0 was missing from
//! it: the run started with a velocity error `h F / (2m)` and the position error grew
//! linearly. A free rod (its wall far away) pulled by a constant end force F: the
//! centre of mass must follow `F t² / (2m)`. The scheme's centre-of-mass recurrence is
//! exact for a constant force (`1ᵀK = 0`), so the tolerance is round-off (1e-9
//! relative); without the load in `a_0` it was 1/N of the distance after N steps
//! (measured: 6.474e-4 m against 6.410e-4 m after 100 steps, +1.0 %).

use signorini::integrators::{SchemeKind, SchemeParams};
use signorini::scene::file::Scene;

#[test]
fn a_load_active_at_t0_enters_the_start_up() {
    let scene = Scene::from_toml(
        r#"[time]
dt = 1e-5
t_end = 1e-3
[scheme]
kind = "schatzman-paoli"
[[bodies]]
name = "rod"
mesh = { generator = "rod", elements = 20, length = 1.0, area = 1e-4 }
material = { young = 2.1e11, poisson = 0.0, density = 7800.0 }
[[obstacles]]
name = "wall"
type = "plane"
point = [-1.0]
normal = [1.0]
[[contacts]]
body = "rod"
nodes = "x0"
obstacle = "wall"
[[forces]]
body = "rod"
nodes = "x1"
total = [1000.0]
"#,
    )
    .unwrap();
    let (model, _) = scene.build().unwrap();
    let mass = model.problem.system.total_mass();
    let params = SchemeParams {
        kind: SchemeKind::SchatzmanPaoli,
        ..SchemeParams::default()
    };
    let h = 1e-5;
    let sys = model.problem.system.clone();
    let mut integ = model.into_integrator(&params, h).unwrap();
    let steps = 100;
    for _ in 0..steps {
        integ.step().unwrap();
    }
    let t = steps as f64 * h;
    let x = sys.momentum(&integ.state().q) / mass;
    let want = 1000.0 * t * t / (2.0 * mass);
    assert!(
        (x / want - 1.0).abs() < 1e-9,
        "centre of mass at {x:e} m, F t²/2m = {want:e} m"
    );
}
