//! Issue 16 §2: a run whose energy grows beyond what its loads and prescribed motion
//! supply stops as failed (exit code 1), as a non-finite state does; the balance counts
//! the work of `[[forces]]` and of prescribed dofs (`model::energy`); a body at rest keeps it
//! (issue 48: the scale's floor from the scene's magnitudes).
//!
//! Tolerances: for θ = ½ without contact the θ-method's discrete energy identity is exact,
//! so the balance closes to round-off (1e-10 of the energy scale asserted; measured below
//! 1e-12); with contacts, friction and damping the excess is at most round-off (every
//! shipped scene and scheme measured at most 1.4e-13 of its scale; 1e-9 asserted).

use signorini::Error;
use signorini::app::run_scene;
use signorini::contact::ContactJacobian;
use signorini::integrators::saved::IntegratorState;
use signorini::integrators::{Integrator, State, StepStats};
use signorini::model::LinearSystem;
use signorini::model::energy::EnergyAudit;
use signorini::run::Quiet;
use signorini::scene::file::Scene;

fn meshes(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("meshes")
        .join(name)
}

/// A free elastic block (no contact, no gravity, undamped, θ = ½) pushed on one face by a
/// `[[forces]]` ramp, or dragged by a prescribed velocity ramp on that face: the energy it
/// holds at every step equals the work supplied, to round-off, and that work is positive.
#[test]
fn the_work_of_forces_and_prescribed_motion_closes_the_balance_of_a_free_block() {
    let base = r#"
[time]
dt = 1e-4
t_end = 0.05
[scheme]
kind = "combined-projection"
[[bodies]]
name = "block"
mesh = { generator = "box", cell = "hex8", cells = [3, 3, 2], size = [0.1, 0.1, 0.05] }
material = { young = 1e7, poisson = 0.3, density = 1000.0 }
"#;
    let drives = [
        "[[forces]]\nbody = \"block\"\nnodes = \"x1\"\ntotal = [4.0, 1.0, 0.0]\ntime = [[0.0, 0.0], [0.02, 1.0], [0.03, 1.0], [0.04, 0.0]]\n",
        "[[prescribed]]\nbody = \"block\"\nnodes = \"x0\"\nvelocity = [0.5, 0.0, 0.2]\ntime = [[0.0, 0.0], [0.02, 1.0], [0.05, 1.0]]\n",
    ];
    for drive in drives {
        let scene = Scene::from_toml(&format!("{base}{drive}")).unwrap();
        let (model, _) = scene.build().unwrap();
        let mut integ = model.into_integrator(&scene.scheme, scene.time.dt).unwrap();
        let s = integ.state();
        let mut audit = EnergyAudit::new(integ.system(), s.time, &s.q, &s.v, 0.0);
        let h = integ.dt();
        let mut worst: f64 = 0.0;
        for _ in 0..scene.steps() {
            integ.step().unwrap();
            let (s, sys) = (integ.state(), integ.system());
            audit.advance(sys, s.time - h, h, 0.5, &s.q);
            let x = audit.excess(sys, s.time, &s.q, &s.v);
            worst = worst.max(x.relative.abs());
        }
        eprintln!(
            "{}: work {:.6e} J, largest |E − E0 − W| / scale {worst:.2e}",
            drive.lines().next().unwrap(),
            audit.work()
        );
        assert!(audit.work() > 1e-3, "{drive}: work {}", audit.work());
        assert!(
            worst <= 1e-10,
            "{drive}: balance off by {worst:e} of the scale"
        );
    }
}

/// Every shipped scene that has loads, prescribed motion, contact or friction keeps its
/// balance: the excess the run reports stays at round-off, far below the failure level.
#[test]
fn shipped_scenes_keep_their_energy_balance() {
    for name in [
        "pushed_block.toml",
        "dragged_block.toml",
        "sliding_block.toml",
        "ball_drop.toml",
        "block_on_cylinder.toml",
    ] {
        let scene = Scene::from_file(&meshes(name)).unwrap();
        let r = run_scene(&scene, None, &mut Quiet).unwrap();
        let b = r
            .summary
            .energy_balance
            .expect("a θ-method run has a balance");
        eprintln!(
            "{name}: supplied {:.4e} J, excess {:.2e}",
            b.supplied_work, b.excess_max
        );
        assert!(b.excess_max <= 1e-9, "{name}: {b:?}");
        if name == "pushed_block.toml" || name == "dragged_block.toml" {
            assert!(b.supplied_work > 0.0, "{name}: {b:?}");
        }
    }
}

/// A real way to gain energy: one Newton iteration per step on the curved obstacle of
/// `meshes/block_on_cylinder.toml` (G(q) is not followed) with caps allowed, under the
/// paper's rules (the default ones no longer gain energy this way: the separating
/// corners caught again take e = 1). The run used to end with exit 0; it now fails with
/// exit 1 at the first check past 1 % (step 500, 4.4 % measured), its history kept.
#[test]
fn an_unconverged_newton_loop_that_gains_energy_fails_the_run() {
    let text = std::fs::read_to_string(meshes("block_on_cylinder.toml"))
        .unwrap()
        .replace("t_end = 0.3", "t_end = 0.05")
        .replace(
            "kind = \"combined-projection\"",
            "kind = \"combined-projection\"\nnewton = { tol = 1e-12, max_iterations = 1 }\nallow_caps = true\nprojection_rule = \"paper\"\nenergy_consistent_restitution = false",
        );
    let scene = Scene::from_toml(&text).unwrap();
    let Err(err) = run_scene(&scene, None, &mut Quiet) else {
        panic!("the run that gains energy passed");
    };
    let msg = err.to_string();
    assert_eq!(err.exit_code(), 1, "{msg}");
    // the remedy names the caps the scene allowed
    assert!(
        msg.contains("the energy grew by") && msg.contains("do not allow caps"),
        "{msg}"
    );
}

/// An integrator that multiplies the velocity by 1.01 after step 100: energy from
/// nowhere, which the run must refuse (exit code 1, [`Error::RunFailed`]) within the
/// check stride, naming the energy and the work supplied.
struct Leaky(Box<dyn Integrator>);

impl Integrator for Leaky {
    fn kind(&self) -> signorini::integrators::SchemeKind {
        self.0.kind()
    }
    fn step(&mut self) -> Result<StepStats, Error> {
        let st = self.0.step()?;
        if self.0.state().step > 100 {
            let mut s = self.0.save();
            let v = s.vectors.get_mut("v").unwrap();
            v.0.iter_mut().for_each(|x| *x *= 1.01);
            self.0.restore(&s)?;
        }
        Ok(st)
    }
    fn state(&self) -> &State {
        self.0.state()
    }
    fn system(&self) -> &LinearSystem {
        self.0.system()
    }
    fn shared_system(&self) -> std::sync::Arc<LinearSystem> {
        self.0.shared_system()
    }
    fn dt(&self) -> f64 {
        self.0.dt()
    }
    fn path(&self) -> String {
        self.0.path()
    }
    fn jacobian(&self) -> &ContactJacobian {
        self.0.jacobian()
    }
    fn starting_gaps(&self, q: &[f64], gap: &mut [f64]) {
        self.0.starting_gaps(q, gap)
    }
    fn save(&self) -> IntegratorState {
        self.0.save()
    }
    fn restore(&mut self, s: &IntegratorState) -> Result<(), Error> {
        self.0.restore(s)
    }
}

#[test]
fn a_run_whose_energy_grows_from_nowhere_fails() {
    let scene = Scene::from_file(&meshes("sliding_block.toml")).unwrap();
    let (model, _) = scene.build().unwrap();
    let size = model.geometry.size();
    let mut integ = Leaky(model.into_integrator(&scene.scheme, scene.time.dt).unwrap());
    let checks = signorini::run::RunChecks::new(&scene.scheme, size);
    let Err(err) = signorini::run::run(
        &mut integ,
        scene.steps(),
        1,
        scene.scheme.theta,
        &checks,
        None,
        serde_json::Value::Null,
        None,
        &mut Quiet,
    ) else {
        panic!("energy from nowhere was accepted");
    };
    let msg = err.to_string();
    eprintln!("{msg}");
    assert_eq!(err.exit_code(), 1, "{msg}");
    // caps are not allowed there: no remedy about them
    assert!(
        msg.contains("the energy grew by")
            && msg.contains("supplied by loads and prescribed")
            && !msg.contains("caps"),
        "{msg}"
    );
    // within one check stride of the first 1 % excess: 1.01² per step gains 2 % of the
    // kinetic energy per step, so the check after step 128 already sees it
    let Error::RunFailed { step, .. } = err else {
        panic!("{err:?}")
    };
    assert!(
        step <= 100 + 2 * signorini::run::ENERGY_CHECK_STRIDE,
        "{step}"
    );
}

/// A block clamped at its top (`z1` fixed) whose bottom rests on a floor under gravity:
/// every kept node sits on the floor, so the block holds nothing but round-off and its
/// energy scale, measured on itself, was that round-off (issue 48: "the energy grew by
/// 2.2e-20 J (1.000e0 of the run's energy scale)", exit 1 at the last step under direct
/// projection). The scale's floor is the work gravity does over the model's size,
/// `L Σ|f|`: the kept dofs are the bottom layer, whose consistent-mass rows sum to half
/// the block's mass, so the floor is `½ m g L` (closed form to 1e-12, round-off of the
/// sums); every scheme of the θ-method runs 2 000 steps at exit 0 with an excess at
/// round-off of that floor (1e-12 asserted; 6.7e-21 measured).
#[test]
fn a_body_at_rest_keeps_its_energy_balance() {
    let scene_text = |kind: &str| {
        format!(
            r#"
[time]
dt = 1e-4
t_end = 0.2
[scheme]
kind = "{kind}"
[[bodies]]
name = "block"
mesh = {{ generator = "box", cell = "hex8", cells = [2, 2, 1], size = [0.1, 0.1, 0.1] }}
material = {{ young = 1e7, poisson = 0.3, density = 1000.0 }}
fixed = ["z1"]
[loads]
gravity = [0.0, 0.0, -9.81]
[[obstacles]]
name = "floor"
type = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
[[contacts]]
body = "block"
nodes = "z0"
obstacle = "floor"
"#
        )
    };
    let floor = 0.5 * 1.0 * 9.81 * (3.0f64 * 0.01).sqrt();
    for kind in ["direct-projection", "combined-projection", "moreau-jean"] {
        let scene = Scene::from_toml(&scene_text(kind)).unwrap();
        let r = run_scene(&scene, None, &mut Quiet)
            .unwrap_or_else(|e| panic!("{kind}: a body at rest failed: {e}"));
        let b = r.summary.energy_balance.expect("θ-method balance");
        assert!(
            (b.scale_floor - floor).abs() <= 1e-12 * floor,
            "{kind}: floor {} vs ½ m g L = {floor}",
            b.scale_floor
        );
        assert!(b.excess_max <= 1e-12, "{kind}: excess {}", b.excess_max);
    }
}

/// A neo-Hookean cube displaced rigidly by 0.5 m through `initial_displacement`, then
/// pushed by a force ramped from 0 at 5 ms to 1 N at 20 ms (issue 48: stopped at step 64,
/// "1.7e-12 J (2.5e-1 of the run's energy scale)", the ramp's work so far being the
/// scale). The floor is the ramp's work over the model's size, `max|φ| |F| L = 1 N ×
/// √3 · 0.1 m` (closed form to 1e-12); the run ends at exit 0 with an excess well
/// inside the θ-method's limit for large deformation (1e-2; 1.1e-11 measured, 1e-8
/// asserted).
#[test]
fn a_body_displaced_rigidly_and_pushed_keeps_its_energy_balance() {
    let rows = vec!["[0.5, 0.0, 0.0]"; 27].join(", ");
    let text = format!(
        r#"
[time]
dt = 1e-4
t_end = 0.02
[[bodies]]
name = "cube"
mesh = {{ generator = "box", cell = "hex8", cells = [2, 2, 2], size = [0.1, 0.1, 0.1] }}
material = {{ young = 1e6, poisson = 0.3, density = 1000.0, model = "neo-hookean" }}
initial_displacement = [{rows}]
[[forces]]
body = "cube"
nodes = "x1"
total = [1.0, 0.0, 0.0]
time = [[0.005, 0.0], [0.02, 1.0]]
"#
    );
    let scene = Scene::from_toml(&text).unwrap();
    let r = run_scene(&scene, None, &mut Quiet).unwrap_or_else(|e| panic!("{e}"));
    let b = r.summary.energy_balance.expect("θ-method balance");
    let floor = 1.0 * (3.0f64 * 0.01).sqrt();
    assert!(
        (b.scale_floor - floor).abs() <= 1e-12 * floor,
        "floor {} vs F L = {floor}",
        b.scale_floor
    );
    assert!(b.supplied_work > 0.0, "{}", b.supplied_work);
    assert!(b.excess_max <= 1e-8, "excess {}", b.excess_max);
}

/// A cube displaced rigidly by 0.5 m through `initial_displacement`, at rest, with no
/// load: its energy `½ qᵀKq` is the difference of terms of about `½ |q|ᵀ|K||q|`, whose
/// rounding (2.6e-12 J measured on the neo-Hookean cube) is all the energy it holds, and
/// the scene has no load or gravity to floor the scale with. The check bounds the
/// energy's rounding (`EnergyAudit::roundoff`: 1e4 ε of the absolute terms) and the runs
/// end at exit 0: 2 000 steps of the neo-Hookean cube (excess 9.3e-8 of the limit-floored
/// scale measured over 10⁴ steps; 1e-4 asserted, the limit being 1e-2) and of the linear
/// one (1.5e-11 over 10⁶ steps; 1e-9 asserted, the limit being 1e-6).
#[test]
fn a_body_displaced_rigidly_at_rest_keeps_its_energy_balance() {
    let rows = vec!["[0.5, 0.0, 0.0]"; 27].join(", ");
    for (model, bound) in [("neo-hookean", 1e-4), ("linear", 1e-9)] {
        let text = format!(
            r#"
[time]
dt = 1e-4
t_end = 0.2
[[bodies]]
name = "cube"
mesh = {{ generator = "box", cell = "hex8", cells = [2, 2, 2], size = [0.1, 0.1, 0.1] }}
material = {{ young = 1e6, poisson = 0.3, density = 1000.0, model = "{model}" }}
initial_displacement = [{rows}]
"#
        );
        let scene = Scene::from_toml(&text).unwrap();
        let r = run_scene(&scene, None, &mut Quiet).unwrap_or_else(|e| panic!("{model}: {e}"));
        let b = r.summary.energy_balance.expect("θ-method balance");
        assert!(b.excess_max <= bound, "{model}: excess {}", b.excess_max);
    }
}
