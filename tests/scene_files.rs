//! Scene files: every committed scene in `meshes/` builds and runs to its reference,
//! and bad scenes are rejected with the key path.

use std::path::Path;

use signorini::app::{run_bar, run_scene};
use signorini::run::Quiet;
use signorini::scene::bar::BarScene;
use signorini::scene::file::Scene;

fn load(name: &str) -> Scene {
    Scene::from_file(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("meshes")
            .join(name),
    )
    .unwrap()
}

#[test]
fn committed_scenes_build_with_the_expected_sizes() {
    for (file, dofs, contacts, linear) in [
        ("bar.toml", 1001, 1, true),
        ("hex_bar.toml", 201 * 4 * 3, 4, true),
        ("block_on_cylinder.toml", 21 * 6 * 2, 21, false),
        // contacts between bodies: a rod's end on a rod's end is linear, the rest not
        ("two_bars.toml", 2 * 1001, 1, true),
        ("hex_bars.toml", (201 * 9 + 151 * 16) * 3, 9, false),
        ("hertz_spheres.toml", 3860, 42, false),
        ("hertz_ball_on_plate.toml", 4326, 43, false),
        ("sliding_block_on_slab.toml", 1143, 25, false),
        ("block_stack.toml", 594, 66, false),
        // past the dense workspaces: the matrix-free path (tests/analytic_flat_impact.rs)
        ("wide_block.toml", 100 * 100 * 3 * 3, 100 * 100, true),
    ] {
        let (_, report) = load(file).build().unwrap();
        assert_eq!(report.dofs, dofs, "{file}");
        assert_eq!(report.contacts, contacts, "{file}");
        assert_eq!(report.linear_contacts, linear, "{file}");
    }
}

#[test]
fn bar_scene_file_reproduces_the_built_in_bar() {
    let from_file = run_scene(&load("bar.toml"), None, &mut Quiet).unwrap();
    let built_in = run_bar(
        &BarScene {
            dt: 5e-7,
            ..BarScene::default()
        },
        None,
        &mut Quiet,
    )
    .unwrap();
    // Same model, same scheme: bit-identical force history.
    assert_eq!(from_file.force, built_in.force);
}

#[test]
fn hex_bar_scene_matches_the_rod_plateau() {
    let r = run_scene(&load("hex_bar.toml"), None, &mut Quiet).unwrap();
    let c = r.summary.contact.unwrap();
    // Issue 3's tolerances: 1 % on the force, 2 % on the duration (measured 2e-6, 0.3 %).
    assert!((c.plateau_force / c.analytic_force - 1.0).abs() < 0.01);
    assert!((c.duration / c.analytic_duration - 1.0).abs() < 0.02);
    assert!(r.summary.max_violation <= 1e-14);
}

#[test]
fn block_on_a_curved_obstacle_never_penetrates() {
    let mut s = load("block_on_cylinder.toml");
    s.time.t_end = 0.1; // first impact at about t = 0.045 s
    let r = run_scene(&s, None, &mut Quiet).unwrap();
    // Algorithm 2 with Newton on the curved gap: penetration at rounding level.
    assert!(
        r.summary.max_violation <= 1e-12,
        "{:e}",
        r.summary.max_violation
    );
    assert!(
        r.summary.iterations.newton.max > 2,
        "Newton must iterate on the cylinder"
    );
    assert_eq!(r.summary.caps_hit, 0);
    assert!(
        r.force.iter().any(|&f| f > 0.0),
        "the block must hit the cylinder"
    );
}

#[test]
fn elastic_ball_from_gmsh_drops_and_rebounds_without_penetrating() {
    let s = load("ball_drop.toml");
    let (_, report) = s.build().unwrap();
    // "surface" nodes within 2 cm of the floor (1 cm below the ball)
    assert_eq!(report.contacts, 18);
    let dir = std::env::temp_dir().join(format!("signorini-ball-{}", std::process::id()));
    let options = signorini::io::OutputOptions::default();
    let out = signorini::run::Output {
        dir: &dir,
        options: &options,
    };
    let r = run_scene(&s, Some(out), &mut Quiet).unwrap();
    assert!(
        r.summary.max_violation <= 1e-12,
        "{:e}",
        r.summary.max_violation
    );
    // impact at about 0.045 s (free fall of 1 cm), then the ball leaves the floor
    let first = r.force.iter().position(|&f| f > 0.0).unwrap() as f64 * s.time.dt;
    assert!(
        (first - (2.0 * 0.01 / 9.81f64).sqrt()).abs() < 5e-3,
        "first contact {first}"
    );
    let last = r.force.iter().rposition(|&f| f > 0.0).unwrap();
    assert!(last + 100 < r.force.len(), "the ball must rebound");
    // energy history is written: kinetic + potential stays within 1 % of the drop
    // energy m g h (θ = 1/2 conserves; e = 0 contacts dissipate a little)
    let csv = std::fs::read_to_string(dir.join("history.csv")).unwrap();
    let rows: Vec<Vec<f64>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    let e0 = rows[0][2] + rows[0][3];
    let drop = rows.iter().map(|r| r[2]).fold(0.0, f64::max);
    for r in &rows {
        assert!(
            (r[2] + r[3] - e0).abs() < 0.01 * drop,
            "energy drift at t = {}",
            r[1]
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn boundary_nodes_are_found_from_the_cells() {
    use signorini::model::generate::box_mesh;
    use signorini::model::solid::CellKind;
    for kind in [CellKind::Hex8, CellKind::Tet4] {
        let m = box_mesh(kind, [3, 3, 3], [1.0, 1.0, 1.0]);
        // 4³ nodes, 2³ interior
        assert_eq!(m.boundary_nodes().len(), 64 - 8, "{kind:?}");
    }
}

fn bad(text: &str) -> String {
    Scene::from_toml(text)
        .and_then(|s| s.build().map(|_| ()))
        .unwrap_err()
        .to_string()
}

const GOOD: &str = r#"
[time]
dt = 1e-6
t_end = 1e-4
[[bodies]]
name = "b"
mesh = { generator = "box", cell = "hex8", cells = [4, 1, 1], size = [1.0, 0.1, 0.1] }
material = { young = 1e9, poisson = 0.3, density = 1000.0 }
[[obstacles]]
name = "wall"
type = "plane"
point = [0.0, 0.0, 0.0]
normal = [1.0, 0.0, 0.0]
[[contacts]]
body = "b"
nodes = "x0"
obstacle = "wall"
"#;

#[test]
fn bad_scenes_name_the_key() {
    assert!(Scene::from_toml(GOOD).unwrap().build().is_ok());
    let cases = [
        (GOOD.replace("dt = 1e-6", "dt = 1e-6\ndtt = 2"), "time"),
        (GOOD.replace("dt = 1e-6", "dt = -1e-6"), "time.dt"),
        (GOOD.replace("young = 1e9", "young = -1e9"), "young"),
        (GOOD.replace("poisson = 0.3", "poisson = 0.7"), "poisson"),
        (
            GOOD.replace(r#"nodes = "x0""#, r#"nodes = "front""#),
            "front",
        ),
        (
            GOOD.replace(r#"obstacle = "wall""#, r#"obstacle = "floor""#),
            "contacts[0].obstacle",
        ),
        (
            GOOD.replace(r#"type = "plane""#, r#"type = "cone""#),
            "obstacles",
        ),
        (
            GOOD.replace(r#"cell = "hex8""#, r#"cell = "hex64""#),
            "bodies",
        ),
        (
            GOOD.replace("[[contacts]]", "[scheme]\ntheta = 2.0\n[[contacts]]"),
            "theta",
        ),
        (
            GOOD.replace(r#"material = {"#, "fixed = [\"x0\"]\nmaterial = {"),
            "fixed and cannot be a contact node",
        ), // the same node against the same obstacle through two contacts: two equal rows
        // of G (Algorithm 2 broke down on them: "equality block not positive definite")
        (
            format!("{GOOD}[[contacts]]\nbody = \"b\"\nnodes = \"x0\"\nobstacle = \"wall\"\n"),
            "contacts[1].nodes`: node 0 (index in the generated mesh) (already meets obstacle \"wall\" through contacts[0]",
        ),
    ];
    for (text, needle) in cases {
        let e = bad(&text);
        assert!(e.contains(needle), "expected {needle:?} in: {e}");
    }
}

#[test]
fn meshio_plate_and_gmsh_ball_on_a_cylinder_run_without_penetration() {
    let dir = env!("CARGO_MANIFEST_DIR");
    // plane-stress plate read from meshio's .vtu, its "bottom" point-data flag as the
    // contact set; and the Gmsh ball against the outside of a cylinder (nonlinear gap),
    // its computed boundary within 2 cm as candidates. The soft ball's contact cells turn
    // 0.148 rad at the impact (strains of v/c = 3 %), past the linear law's default
    // `max_rotation` (issue 48): accepted here, the test being about the meshes and the
    // gap.
    let plate = format!(
        "[time]\ndt = 1e-4\nt_end = 0.05\n[[bodies]]\nname = \"plate\"\nformulation = {{ plane-stress = {{ thickness = 0.01 }} }}\nmesh = {{ generator = \"file\", path = \"{dir}/meshes/plate.vtu\" }}\nmaterial = {{ young = 1e7, poisson = 0.3, density = 1000.0 }}\nvelocity = [0.0, -1.0]\n[[obstacles]]\nname = \"floor\"\ntype = \"plane\"\npoint = [0.0, -0.001]\nnormal = [0.0, 1.0]\n[[contacts]]\nbody = \"plate\"\nnodes = \"bottom\"\nobstacle = \"floor\"\n"
    );
    let ball = format!(
        "[time]\ndt = 1e-4\nt_end = 0.05\n[scheme]\nmax_rotation = 0.2\n[[bodies]]\nname = \"ball\"\nmesh = {{ generator = \"file\", path = \"{dir}/meshes/ball.msh\" }}\nmaterial = {{ young = 1e6, poisson = 0.3, density = 1000.0 }}\nvelocity = [0.0, 0.0, -1.0]\n[[obstacles]]\nname = \"pipe\"\ntype = \"cylinder\"\npoint = [0.0, 0.0, -0.1]\naxis = [1.0, 0.0, 0.0]\nradius = 0.1\n[[contacts]]\nbody = \"ball\"\nnodes = \"boundary\"\nwithin = 0.02\nobstacle = \"pipe\"\n"
    );
    for (name, text, contacts) in [("plate", plate, 9), ("ball on cylinder", ball, 28)] {
        let s = Scene::from_toml(&text).unwrap();
        assert_eq!(s.build().unwrap().1.contacts, contacts, "{name}");
        let r = run_scene(&s, None, &mut Quiet).unwrap();
        // exact projection on the plane; Newton-converged on the cylinder
        assert!(
            r.summary.max_violation <= 1e-12,
            "{name}: {:e}",
            r.summary.max_violation
        );
        assert_eq!(r.summary.caps_hit, 0, "{name}");
        assert!(r.force.iter().any(|&f| f > 0.0), "{name}: no impact");
    }
}

/// The academic examples as scene files: the ball's impulses fall within five steps of
/// the closed-form impacts (1, 2, 2.5, 2.75; the default rules start each bounce up to
/// h|v| above the ground, so later impacts come a few steps late:
/// `paper_bouncing_ball::default_rules_follow_ballard_and_rest_on_the_ground`) and it rests after t = 4.05 (the e-per-step
/// tail of `paper_bouncing_ball`); the oscillator's first four impacts are those of
/// its closed form, impact i within i + 1 steps; the block ends flat at rest with energy m g l/2. Bad example
/// scenes name the key.
#[test]
fn academic_examples_run_from_scene_files() {
    use signorini::app::run_scene;
    use signorini::run::Quiet;
    let ball = load("bouncing_ball.toml");
    let r = run_scene(&ball, None, &mut Quiet).unwrap();
    let h = ball.time.dt;
    let closed = signorini::analytic::ball::BouncingBall::ballard();
    for t in closed.impact_times(2.8, 4) {
        let k = (t / h).ceil() as usize - 1;
        assert!(
            (k.saturating_sub(1)..=k + 5).any(|j| r.force[j] > 0.0),
            "no impulse near t = {t}"
        );
    }
    let settled = (4.05 / h) as usize;
    assert!(
        r.force[settled..].iter().all(|&f| (f - 2.0).abs() < 1e-9),
        "resting force 2 N"
    );
    let osc = load("oscillator.toml");
    let r = run_scene(&osc, None, &mut Quiet).unwrap();
    let exact = signorini::analytic::oscillator::Oscillator::example().impact_times(2.0, 4);
    // numerical impact: the end of the first step of each run of nonzero impulses; each
    // impact is caught within a step and shifts the later ones by up to a step (O(h),
    // order 1 of Fig. 2): impact i (from 0) within i + 1 steps (measured 0.4, 1.4,
    // 2.3, 3.2 ms at h = 1 ms)
    let hits: Vec<f64> = (0..r.force.len())
        .filter(|&k| r.force[k] != 0.0 && (k == 0 || r.force[k - 1] == 0.0))
        .map(|k| (k + 1) as f64 * osc.time.dt)
        .filter(|&t| t <= 2.0)
        .collect();
    assert_eq!(hits.len(), exact.len(), "{hits:?} vs {exact:?}");
    for (i, (a, b)) in hits.iter().zip(&exact).enumerate() {
        assert!(
            (a - b).abs() <= (i + 1) as f64 * osc.time.dt,
            "{hits:?} vs {exact:?}"
        );
    }
    let block = load("rocking_block.toml");
    let r = run_scene(&block, None, &mut Quiet).unwrap();
    assert!(r.summary.max_violation <= 1e-12);
    assert!(
        (r.summary.energy[1] / (9.81 * 0.75) - 1.0).abs() < 1e-9,
        "{:?}",
        r.summary.energy
    );
    // bad example scenes
    let e = Scene::from_toml("[example]\nkind = \"pendulum\"\n[time]\ndt = 1e-3\nt_end = 1.0\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("example") && e.contains("pendulum"), "{e}");
    let e = Scene::from_toml(
        "[example]\nkind = \"bouncing-ball\"\nmass = -1.0\n[time]\ndt = 1e-3\nt_end = 1.0\n",
    )
    .unwrap()
    .build()
    .err()
    .unwrap()
    .to_string();
    assert!(e.contains("example.mass") && e.contains("-1"), "{e}");
}

/// `[[forces]]` and `[[prescribed]]` entries that are wrong are refused with their key path,
/// the value and what was expected.
#[test]
fn bad_forces_and_prescribed_entries_are_refused() {
    use signorini::scene::file::Scene;
    let base = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/dragged_block.toml"),
    )
    .unwrap();
    for (from, to, expect) in [
        (
            "body = \"block\"\nnodes = \"z1\"\nvelocity",
            "body = \"brick\"\nnodes = \"z1\"\nvelocity",
            "prescribed[0].body",
        ),
        (
            "velocity = [0.01, 0.0, 0.0]",
            "velocity = [0.01, 0.0]",
            "prescribed[0].velocity",
        ),
        (
            "components = [0]",
            "components = [3]",
            "prescribed[0].components",
        ),
        (
            "time = [[0.1, 0.0], [1.1, 1.0]]",
            "time = [[0.1, 0.0], [0.1, 1.0]]",
            "prescribed[0].time[1]",
        ),
        (
            "time = [[0.1, 0.0], [1.1, 1.0]]",
            "time = []",
            "prescribed[0].time",
        ),
        ("nodes = \"z1\"", "nodes = \"top\"", "no such node set"),
        (
            "[[obstacles]]",
            "[[forces]]\nbody = \"block\"\nnodes = \"z1\"\ntotal = [1.0, 0.0, nan]\n\n[[obstacles]]",
            "forces[0].total",
        ),
        (
            "[[obstacles]]",
            "[[prescribed]]\nbody = \"block\"\nnodes = \"z1\"\nvelocity = [0.0, 0.0, 0.0]\ncomponents = [0]\n\n[[obstacles]]",
            "already fixed or prescribed",
        ),
    ] {
        assert!(base.contains(from), "{from}");
        let text = base.replacen(from, to, 1);
        let err = Scene::from_toml(&text)
            .and_then(|s| s.build().map(|_| ()))
            .err()
            .unwrap_or_else(|| panic!("accepted: {to}"))
            .to_string();
        assert!(err.contains(expect), "{to}: {err}");
    }
}

/// A mesh given as arrays (`generator = "arrays"`: the scene a notebook builds from
/// numpy) is the generator's mesh when given its points, cells and node sets: a 3 × 2 ×
/// 2 hex8 block dropped on a floor runs the same 60 steps bit for bit (same numbering,
/// so the same matrices, ordering and factor).
#[test]
fn a_mesh_given_as_arrays_runs_as_the_generated_one() {
    use signorini::model::generate::box_mesh;
    use signorini::model::solid::CellKind;
    let m = box_mesh(CellKind::Hex8, [3, 2, 2], [0.3, 0.2, 0.2]);
    let points: Vec<String> = m
        .points
        .iter()
        .map(|p| format!("[{:?}, {:?}, {:?}]", p[0], p[1], p[2]))
        .collect();
    let cells: Vec<String> = m.cells.iter().map(|(_, c)| format!("{c:?}")).collect();
    let sets: Vec<String> = m
        .node_sets
        .iter()
        .map(|(k, v)| format!("{k} = {v:?}"))
        .collect();
    let scene = |mesh: &str| {
        format!(
            r#"[time]
dt = 1e-4
t_end = 6e-3
[[bodies]]
name = "b"
mesh = {mesh}
material = {{ young = 1e6, poisson = 0.3, density = 1000.0 }}
velocity = [0.0, 0.0, -1.0]
[[obstacles]]
name = "floor"
type = "plane"
point = [0.0, 0.0, -0.001]
normal = [0.0, 0.0, 1.0]
[[contacts]]
body = "b"
nodes = "z0"
obstacle = "floor"
"#
        )
    };
    let generated =
        scene(r#"{ generator = "box", cell = "hex8", cells = [3, 2, 2], size = [0.3, 0.2, 0.2] }"#);
    let arrays = scene(&format!(
        r#"{{ generator = "arrays", points = [{}], cells = {{ hex8 = [{}] }}, node_sets = {{ {} }} }}"#,
        points.join(", "),
        cells.join(", "),
        sets.join(", ")
    ));
    let run = |text: &str| {
        let s = Scene::from_toml(text).unwrap();
        let (model, _) = s.build().unwrap();
        let mut integ = model.into_integrator(&s.scheme, s.time.dt).unwrap();
        let mut closed = 0;
        for _ in 0..s.steps() {
            integ.step().unwrap();
            closed += integ.state().impulse.iter().filter(|&&p| p > 0.0).count();
        }
        (integ.state().q.clone(), integ.state().v.clone(), closed)
    };
    let (qa, va, ca) = run(&arrays);
    let (qg, vg, cg) = run(&generated);
    assert!(cg > 0, "the block reaches the floor");
    assert_eq!(ca, cg);
    assert!(qa.iter().zip(&qg).all(|(a, b)| a.to_bits() == b.to_bits()));
    assert!(va.iter().zip(&vg).all(|(a, b)| a.to_bits() == b.to_bits()));
}

/// A scene built in code (issue 48, the Python package's route: its tables as TOML
/// values, the mesh as flat arrays, no text) equals the same scene read from TOML text:
/// the same tables written back, the same `check` report; overrides apply as `--set`
/// does, and a bad value is refused with its key path.
#[test]
fn a_scene_from_tables_and_flat_arrays_equals_the_one_from_text() {
    use signorini::model::generate::box_mesh;
    use signorini::model::solid::CellKind;
    use signorini::scene::file::{MeshSpec, Rows};
    use std::collections::BTreeMap;
    let m = box_mesh(CellKind::Hex8, [3, 2, 2], [0.3, 0.2, 0.2]);
    let rows = |v: &[usize]| format!("{v:?}");
    let text = format!(
        r#"[time]
dt = 1e-4
t_end = 6e-3
[[bodies]]
name = "b"
mesh = {{ generator = "arrays", points = [{}], cells = {{ hex8 = [{}] }}, node_sets = {{ {} }} }}
material = {{ young = 1e6, poisson = 0.3, density = 1000.0 }}
velocity = [0.0, 0.0, -1.0]
[[obstacles]]
name = "floor"
type = "plane"
point = [0.0, 0.0, -0.001]
normal = [0.0, 0.0, 1.0]
[[contacts]]
body = "b"
nodes = "z0"
obstacle = "floor"
"#,
        m.points
            .iter()
            .map(|p| format!("[{:?}, {:?}, {:?}]", p[0], p[1], p[2]))
            .collect::<Vec<_>>()
            .join(", "),
        m.cells
            .iter()
            .map(|(_, c)| rows(c))
            .collect::<Vec<_>>()
            .join(", "),
        m.node_sets
            .iter()
            .map(|(k, v)| format!("{k} = {}", rows(v)))
            .collect::<Vec<_>>()
            .join(", ")
    );
    let from_text = Scene::from_toml(&text).unwrap();
    // the tables without the arrays, which are handed over flat afterwards
    let mut table: toml::Table = toml::from_str(&text).unwrap();
    let body = table["bodies"].as_array_mut().unwrap()[0]
        .as_table_mut()
        .unwrap();
    let mesh = body["mesh"].as_table_mut().unwrap();
    for key in ["points", "cells", "node_sets"] {
        mesh.remove(key);
    }
    mesh.insert("points".into(), toml::Value::Array(Vec::new()));
    mesh.insert("cells".into(), toml::Value::Table(toml::Table::new()));
    let mut from_code = Scene::from_table(table.clone(), &[]).unwrap();
    let flat: Vec<f64> = m.points.iter().flatten().copied().collect();
    let cells: Vec<usize> = m.cells.iter().flat_map(|(_, c)| c.clone()).collect();
    from_code.bodies[0].mesh = MeshSpec::Arrays {
        points: Rows::from_flat(flat, 3).unwrap(),
        cells: BTreeMap::from([("hex8".to_string(), Rows::from_flat(cells, 8).unwrap())]),
        node_sets: m.node_sets.clone(),
    };
    from_code.validate().unwrap();
    assert_eq!(
        toml::to_string(&from_code).unwrap(),
        toml::to_string(&from_text).unwrap()
    );
    assert_eq!(
        serde_json::to_string(&from_code.check().unwrap()).unwrap(),
        serde_json::to_string(&from_text.check().unwrap()).unwrap()
    );
    // overrides of a scene held in memory (`with_overrides`, the arrays set aside and
    // put back, or overridden themselves) give the scene of the text with them
    for set in [
        vec!["time.t_end=1e-3", "bodies[0].material.young=2e6"],
        vec!["bodies[0].mesh.node_sets.top=[0, 1]"],
        vec![
            "bodies[0].velocity=[0.0, 0.0, -2.0]",
            "bodies[0].mesh.points[0]=[0.0, 0.0, 0.0]",
        ],
    ] {
        let set: Vec<String> = set.into_iter().map(String::from).collect();
        assert_eq!(
            toml::to_string(&from_code.with_overrides(&set).unwrap()).unwrap(),
            toml::to_string(&Scene::from_text_with(&text, &set).unwrap()).unwrap(),
            "{set:?}"
        );
    }
    // overrides as `--set`; a bad value named by its key path
    let set = Scene::from_table(table.clone(), &["time.t_end=1e-3".to_string()]).unwrap();
    assert_eq!(set.steps(), 10);
    let mut bad = table;
    bad["bodies"].as_array_mut().unwrap()[0]
        .as_table_mut()
        .unwrap()
        .insert(
            "material".into(),
            toml::Value::Table(toml::from_str("young = true").unwrap()),
        );
    let e = Scene::from_table(bad, &[]).unwrap_err().to_string();
    assert!(e.contains("bodies[0].material.young"), "{e}");
    assert!(e.contains("boolean"), "{e}");
}

/// Issue 48: `within` is measured at the starting positions (reference plus
/// `initial_displacement`): a box lifted 1 cm above its floor and displaced down by
/// 9.5 mm has its four bottom nodes within 1 mm of the floor, its top ones 10.05 cm
/// away; measured at the reference, no node was within and the scene was refused.
#[test]
fn within_is_measured_at_the_displaced_start() {
    let scene = |u: f64| {
        let rows: Vec<String> = (0..8).map(|_| format!("[0.0, 0.0, {u:?}]")).collect();
        format!(
            "[time]\ndt = 1e-4\nt_end = 1e-3\n[[bodies]]\nname = \"b\"\n\
             mesh = {{ generator = \"box\", cell = \"hex8\", cells = [1, 1, 1], size = [0.1, 0.1, 0.1] }}\n\
             material = {{ young = 1e6, poisson = 0.3, density = 1000.0 }}\n\
             initial_displacement = [{}]\n\
             [[obstacles]]\nname = \"floor\"\ntype = \"plane\"\npoint = [0.0, 0.0, -0.01]\n\
             normal = [0.0, 0.0, 1.0]\n\
             [[contacts]]\nbody = \"b\"\nnodes = \"all\"\nobstacle = \"floor\"\nwithin = 1e-3\n",
            rows.join(", ")
        )
    };
    let (_, report) = Scene::from_toml(&scene(-0.0095)).unwrap().build().unwrap();
    assert_eq!(
        report.contacts, 4,
        "the bottom face, 0.5 mm above the floor"
    );
    // not displaced: 1 cm away, none within 1 mm (the nearest named)
    let err = match Scene::from_toml(&scene(0.0)).unwrap().build() {
        Ok(_) => panic!("built with no node within"),
        Err(e) => e.to_string(),
    };
    assert!(
        err.contains("within") && err.contains("1.000e-2 m away"),
        "{err}"
    );
}

/// Issue 48: an axisymmetric tube (r from 10 to 20 mm, 50 mm long) in a coaxial bore of
/// radius 20.5 mm and on a coaxial shaft of radius 9.5 mm, each given as a line parallel
/// to the axis (`normal = [∓1, 0]`, which revolves into the cylinder) and as a coaxial
/// `cylinder`: every outer node starts at the closed-form gap R_bore − r_out = 0.5 mm,
/// every inner node at r_in − R_shaft = 0.5 mm, in both writings, to round-off; the
/// tube runs outward into the bore without passing it. A cone (an oblique line) and an
/// off-axis cylinder are refused with the reason.
#[test]
fn a_tube_in_a_coaxial_bore_and_on_a_shaft() {
    use signorini::contact::ContactJacobian;
    let scene = |bore: &str, shaft: &str, extra: &str| {
        format!(
            "[time]\ndt = 1e-5\nt_end = 2e-3\n[[bodies]]\nname = \"tube\"\n\
             formulation = \"axisymmetric\"\n\
             mesh = {{ generator = \"rectangle\", cell = \"quad4\", cells = [2, 5], size = [0.01, 0.05], origin = [0.01, 0.0] }}\n\
             material = {{ young = 1e6, poisson = 0.3, density = 1000.0 }}\n{extra}\
             [[obstacles]]\nname = \"bore\"\n{bore}\n\
             [[obstacles]]\nname = \"shaft\"\n{shaft}\n\
             [[contacts]]\nbody = \"tube\"\nnodes = \"x1\"\nobstacle = \"bore\"\n\
             [[contacts]]\nbody = \"tube\"\nnodes = \"x0\"\nobstacle = \"shaft\"\n"
        )
    };
    let lines = (
        "type = \"plane\"\npoint = [0.0205, 0.0]\nnormal = [-1.0, 0.0]",
        "type = \"plane\"\npoint = [0.0095, 0.0]\nnormal = [1.0, 0.0]",
    );
    let cylinders = (
        "type = \"cylinder\"\npoint = [0.0, 0.0]\naxis = [0.0, 1.0]\nradius = 0.0205\nside = \"inside\"",
        "type = \"cylinder\"\npoint = [0.0, 0.3]\naxis = [0.0, -2.0]\nradius = 0.0095",
    );
    for (bore, shaft) in [lines, cylinders] {
        let s = Scene::from_toml(&scene(bore, shaft, "")).unwrap();
        let (model, report) = s.build().unwrap();
        assert_eq!(report.contacts, 12, "6 outer and 6 inner nodes");
        let c = &model.problem.contacts;
        let mut gap = vec![0.0; c.len()];
        let mut jac = ContactJacobian::for_set(c.as_ref());
        c.evaluate(&model.problem.q0, &mut gap, &mut jac);
        for g in gap {
            assert!(
                (g - 5e-4).abs() < 1e-15,
                "{bore}: gap {g}, closed form 5e-4"
            );
        }
        // pushed outward at 3 m/s (a free ring would swing out 1.4 mm): the bore stops
        // it, and its outer nodes end at r ≤ R_bore
        let v: Vec<String> = (0..18).map(|_| "[3.0, 0.0]".to_string()).collect();
        let s = Scene::from_toml(&scene(
            bore,
            shaft,
            &format!("initial_velocity = [{}]\n", v.join(", ")),
        ))
        .unwrap();
        let r = run_scene(&s, None, &mut Quiet).unwrap();
        assert!(
            r.summary.max_violation < 1e-9,
            "{bore}: the tube passed the bore by {}",
            r.summary.max_violation
        );
        assert!(
            r.force.iter().any(|&f| f > 0.0),
            "{bore}: the tube never met the bore"
        );
        let q = &r.state.q;
        assert!(q.iter().any(|&u| u > 4e-4), "the tube moved out");
    }
    // what revolves into no cylinder is refused, with why
    for (bore, key, why) in [
        (
            "type = \"plane\"\npoint = [0.0205, 0.0]\nnormal = [-0.6, 0.8]",
            "obstacles[0].normal",
            "revolves into a cone",
        ),
        (
            "type = \"plane\"\npoint = [0.0, 0.0]\nnormal = [-1.0, 0.0]",
            "obstacles[0].point",
            "radius point[0] = r, which must be > 0",
        ),
        (
            "type = \"cylinder\"\npoint = [0.0, 0.0]\naxis = [1.0, 0.0]\nradius = 0.0205\nside = \"inside\"",
            "obstacles[0].axis",
            "is coaxial",
        ),
        (
            "type = \"cylinder\"\npoint = [0.001, 0.0]\naxis = [0.0, 1.0]\nradius = 0.0205\nside = \"inside\"",
            "obstacles[0].point",
            "passes through the axis of revolution",
        ),
    ] {
        let err = match Scene::from_toml(&scene(bore, lines.1, "")) {
            Ok(_) => panic!("{bore}: accepted"),
            Err(e) => e.to_string(),
        };
        assert!(err.contains(key) && err.contains(why), "{err}");
    }
}
