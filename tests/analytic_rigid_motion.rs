//! Rigid-motion initial states and each body's momentum (issue 37): a scene's
//! `angular_velocity` and `rotation_center`, and [`BodyMeasures`], against the closed
//! forms of a rigid box.
//!
//! References: a homogeneous box `a × b × c` of mass `m = ρabc` has its centre of mass
//! at its middle and the inertia tensor `I = m/12 diag(b² + c², a² + c², a² + b²)` there;
//! in the rigid motion `v(x) = v₀ + ω × (x − p)` its momentum is
//! `m (v₀ + ω × (c − p))`, its angular momentum about the centre `I ω` and its kinetic
//! energy `½ m |v_c|² + ½ ωᵀ I ω`. A plane body `a × b` of unit thickness: `m = ρab`,
//! `L_z = ω m (a² + b²)/12`. Hex8 and quad4 cells with the consistent mass integrate
//! `ρ N_i N_j` exactly (2 Gauss points per direction for a degree-2 integrand), and the
//! rigid field is linear, so the finite-element values equal these to round-off:
//! tolerance 1e-12 relative (sums of a few thousand terms of one sign).

use signorini::model::{BodyMeasures, BodyState};
use signorini::scene::file::Scene;

const RHO: f64 = 1000.0;

fn box_scene(extra: &str) -> String {
    format!(
        r#"
[time]
dt = 1e-5
t_end = 2e-3

[scheme]
kind = "moreau-jean"

[[bodies]]
name = "box"
mesh = {{ generator = "box", cell = "hex8", cells = [4, 2, 2], size = [0.4, 0.2, 0.1] }}
material = {{ young = 1e7, poisson = 0.3, density = {RHO} }}
{extra}
"#
    )
}

/// The body states of `text`'s model in its initial state.
fn initial_states(text: &str) -> (Vec<BodyState>, f64) {
    let scene = Scene::from_toml(text).unwrap();
    let (model, _) = scene.build().unwrap();
    let p = &model.problem;
    let mut bm = BodyMeasures::new(&model.geometry, p.q0.len()).expect("a mesh model");
    let mut out = vec![BodyState::default(); bm.bodies()];
    bm.measure(&p.system.mass, &p.q0, &p.v0, &mut out);
    let ke = p.system.kinetic_energy(&p.q0, &p.v0);
    (out, ke)
}

fn close(a: f64, b: f64, scale: f64) -> bool {
    (a - b).abs() <= 1e-12 * scale
}

/// A spin about the centre of mass (the default centre) with a translation.
#[test]
fn spinning_box_about_its_centre_of_mass() {
    let (a, b, c) = (0.4, 0.2, 0.1);
    let m = RHO * a * b * c;
    let (v0, w) = (0.5, 3.0);
    let (s, ke) = initial_states(&box_scene(
        "velocity = [0.5, 0.0, 0.0]\nangular_velocity = [0.0, 0.0, 3.0]",
    ));
    let s = s[0];
    let izz = m * (a * a + b * b) / 12.0;
    assert!(close(s.mass, m, m), "{} vs {m}", s.mass);
    for (d, want) in [a / 2.0, b / 2.0, c / 2.0].into_iter().enumerate() {
        assert!(close(s.centre[d], want, a), "{:?}", s.centre);
    }
    let p = [m * v0, 0.0, 0.0];
    let l = [0.0, 0.0, izz * w];
    for d in 0..3 {
        assert!(close(s.momentum[d], p[d], m * v0), "{:?}", s.momentum);
        assert!(
            close(s.angular_momentum[d], l[d], izz * w),
            "{:?}",
            s.angular_momentum
        );
    }
    let want = 0.5 * m * v0 * v0 + 0.5 * izz * w * w;
    assert!(close(ke, want, want), "kinetic energy {ke} vs {want}");
}

/// A general angular velocity about a point that is not the centre: the momentum
/// carries the transport `ω × (c − p)`, the angular momentum about the centre is `I ω`.
#[test]
fn general_rotation_about_a_given_point() {
    let (a, b, c) = (0.4, 0.2, 0.1);
    let m = RHO * a * b * c;
    let w = [1.0, -2.0, 3.0];
    let p = [0.0, 0.0, 0.0];
    let (s, ke) = initial_states(&box_scene(
        "angular_velocity = [1.0, -2.0, 3.0]\nrotation_center = [0.0, 0.0, 0.0]",
    ));
    let s = s[0];
    let cen = [a / 2.0, b / 2.0, c / 2.0];
    let r = [cen[0] - p[0], cen[1] - p[1], cen[2] - p[2]];
    let vc = [
        w[1] * r[2] - w[2] * r[1],
        w[2] * r[0] - w[0] * r[2],
        w[0] * r[1] - w[1] * r[0],
    ];
    let inertia = [
        m * (b * b + c * c) / 12.0,
        m * (a * a + c * c) / 12.0,
        m * (a * a + b * b) / 12.0,
    ];
    let scale_p = m * 1.0;
    let scale_l = inertia[2] * 3.0;
    for d in 0..3 {
        assert!(close(s.momentum[d], m * vc[d], scale_p), "{:?}", s.momentum);
        assert!(
            close(s.angular_momentum[d], inertia[d] * w[d], scale_l),
            "{:?} vs {:?}",
            s.angular_momentum,
            [0, 1, 2].map(|k| inertia[k] * w[k])
        );
    }
    let want = 0.5 * m * vc.iter().map(|x| x * x).sum::<f64>()
        + 0.5 * (0..3).map(|d| inertia[d] * w[d] * w[d]).sum::<f64>();
    assert!(close(ke, want, want), "kinetic energy {ke} vs {want}");
}

/// A plane-strain rectangle (unit thickness) spinning about its centre: one value of
/// `angular_velocity`, about z.
#[test]
fn spinning_plane_body() {
    let (a, b) = (0.3, 0.1);
    let m = RHO * a * b;
    let w = 2.0;
    let text = format!(
        r#"
[time]
dt = 1e-5
t_end = 1e-4

[[bodies]]
name = "plate"
formulation = "plane-strain"
mesh = {{ generator = "rectangle", cell = "quad4", cells = [6, 2], size = [{a}, {b}] }}
material = {{ young = 1e7, poisson = 0.3, density = {RHO} }}
angular_velocity = [{w}]
"#
    );
    let (s, ke) = initial_states(&text);
    let s = s[0];
    let izz = m * (a * a + b * b) / 12.0;
    assert!(close(s.mass, m, m));
    assert!(close(s.angular_momentum[2], izz * w, izz * w), "{:?}", s);
    assert!(
        s.momentum.iter().all(|p| p.abs() <= 1e-12 * m * w * a),
        "{:?}",
        s
    );
    assert!(close(ke, 0.5 * izz * w * w, 0.5 * izz * w * w), "{ke}");
}

/// Over a free flight (no contact, no load) the θ-method at θ = 1/2 keeps the linear
/// momentum (the elastic forces of a rigid translation sum to zero, `Σ_i (K q)_i = 0`
/// per component) and moves the centre of mass at `p/m` exactly: checked after 200
/// steps to 1e-12 relative. The angular momentum of a linear solid is not conserved
/// (its small strain is not invariant under rotation), so it is not asserted here.
#[test]
fn free_flight_keeps_the_momentum_and_moves_the_centre_at_p_over_m() {
    let text = box_scene("velocity = [0.5, -0.2, 0.1]\nangular_velocity = [0.0, 0.0, 3.0]");
    let scene = Scene::from_toml(&text).unwrap();
    let (model, _) = scene.build().unwrap();
    let mut bm = BodyMeasures::new(&model.geometry, model.problem.q0.len()).unwrap();
    let mut integ = model.into_integrator(&scene.scheme, scene.time.dt).unwrap();
    let mut s0 = [BodyState::default()];
    {
        let s = integ.state();
        bm.measure(&integ.system().mass, &s.q, &s.v, &mut s0);
    }
    for _ in 0..200 {
        integ.step().unwrap();
    }
    let mut s1 = [BodyState::default()];
    let s = integ.state();
    bm.measure(&integ.system().mass, &s.q, &s.v, &mut s1);
    let (s0, s1) = (s0[0], s1[0]);
    let m = s0.mass;
    for d in 0..3 {
        assert!(
            close(s1.momentum[d], s0.momentum[d], m * 0.5),
            "{:?} vs {:?}",
            s1.momentum,
            s0.momentum
        );
        let want = s0.centre[d] + s.time * s0.momentum[d] / m;
        assert!(close(s1.centre[d], want, 0.4), "{:?} vs {want}", s1.centre);
    }
    assert!((s.time - 2e-3).abs() < 1e-15);
}

/// What a rigid motion cannot be given: the error names the key, the value and what
/// was expected.
#[test]
fn bad_rigid_motions_are_refused_with_the_key() {
    let cases = [
        (
            "angular_velocity = [1.0, 2.0]",
            "angular_velocity",
            "3 finite values",
        ),
        (
            "angular_velocity = [0.0, 0.0, nan]",
            "angular_velocity",
            "3 finite values",
        ),
        (
            "rotation_center = [0.0, 0.0, 0.0]",
            "rotation_center",
            "give angular_velocity",
        ),
        (
            "angular_velocity = [0.0, 0.0, 1.0]\nrotation_center = [0.0, 0.0]",
            "rotation_center",
            "3 finite values",
        ),
    ];
    for (extra, key, expect) in cases {
        let scene = Scene::from_toml(&box_scene(extra)).unwrap();
        let e = scene.build().err().expect(extra).to_string();
        assert!(e.contains(key) && e.contains(expect), "{extra}: {e}");
        assert!(e.contains("bodies[0]"), "{extra}: {e}");
    }
    // a rod cannot turn in its own model
    let rod = r#"
[time]
dt = 1e-6
t_end = 1e-5

[[bodies]]
name = "bar"
mesh = { generator = "rod", elements = 10, length = 1.0, area = 1e-4 }
material = { young = 2.1e11, poisson = 0.0, density = 7800.0 }
angular_velocity = [1.0]
"#;
    let e = Scene::from_toml(rod)
        .unwrap()
        .build()
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("angular_velocity") && e.contains("rod"), "{e}");
}

/// The history of a scene with a solid body ends each row with the body's centre,
/// momentum and angular momentum (`centre_0_0` … `angular_momentum_0_2`): over 100 free
/// steps at θ = 1/2 the momentum stays `m v₀` and the centre moves at `v₀` (both
/// exact, 1e-12 relative), the angular momentum about the centre starts within
/// `I_zz ω h`-order of `I_zz ω` (the first row is after one step; checked to 1e-3); the
/// summary's `bodies` hold the initial values exactly. With the `hdf5` feature,
/// `/history/centre`, `momentum`, `angular_momentum` (`[rows, 3]`) equal the CSV's
/// columns bit for bit.
#[test]
fn the_history_has_each_body_s_centre_and_momenta() {
    let (a, b, c) = (0.4, 0.2, 0.1);
    let m = RHO * a * b * c;
    let izz = m * (a * a + b * b) / 12.0;
    let dir = std::env::temp_dir().join(format!("signorini-rigid-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("spin.toml");
    std::fs::write(
        &scene,
        box_scene("velocity = [0.5, 0.0, 0.0]\nangular_velocity = [0.0, 0.0, 3.0]")
            .replace("t_end = 2e-3", "t_end = 1e-3"),
    )
    .unwrap();
    let out = dir.join("out");
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_signorini"))
        .args(["run", "--quiet", "--no-fields", "--no-plots", "--out"])
        .arg(&out)
        .arg(&scene)
        .status()
        .unwrap();
    assert!(status.success());
    let csv = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 100);
    let col = |name: &str| header.iter().position(|h| *h == name).expect(name);
    let names = ["centre", "momentum", "angular_momentum"];
    let first = col("centre_0_0");
    assert_eq!(header.len(), first + 9, "the body columns close the row");
    for (k, q) in names.iter().enumerate() {
        for d in 0..3 {
            assert_eq!(header[first + 3 * k + d], format!("{q}_0_{d}"));
        }
    }
    for r in &rows {
        let t = r[col("time")];
        assert!(close(r[col("momentum_0_0")], m * 0.5, m * 0.5), "{r:?}");
        assert!(close(r[col("centre_0_0")], a / 2.0 + 0.5 * t, a), "{r:?}");
        assert!(close(r[col("centre_0_1")], b / 2.0, a), "{r:?}");
    }
    let lz0 = rows[0][col("angular_momentum_0_2")];
    assert!(
        (lz0 / (izz * 3.0) - 1.0).abs() < 1e-3,
        "{lz0} vs {}",
        izz * 3.0
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let body = &summary["bodies"][0];
    assert_eq!(body["name"], "box");
    let l0 = body["initial"]["angular_momentum"][2].as_f64().unwrap();
    assert!(close(l0, izz * 3.0, izz * 3.0), "{l0}");
    let last = rows.last().unwrap();
    for (k, q) in names.iter().enumerate() {
        for d in 0..3 {
            let v = body["final"][q][d].as_f64().unwrap();
            assert_eq!(v, last[first + 3 * k + d], "{q} {d}: summary vs last row");
        }
    }
    #[cfg(feature = "hdf5")]
    {
        let f = hdf5::File::open(out.join("fields.vtkhdf")).unwrap();
        let hist = f.group("history").unwrap();
        for (k, q) in names.iter().enumerate() {
            let ds = hist.dataset(q).unwrap();
            assert_eq!(ds.shape(), vec![rows.len(), 3], "{q}");
            let v: Vec<f64> = ds.read_raw().unwrap();
            for (i, r) in rows.iter().enumerate() {
                assert_eq!(
                    &v[3 * i..3 * i + 3],
                    &r[first + 3 * k..first + 3 * k + 3],
                    "{q} row {i}"
                );
            }
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// An axisymmetric body is not measured: the summed radial components of its half
/// section would be no momentum of the revolved ring (a silently wrong column).
#[test]
fn axisymmetric_scenes_have_no_body_measures() {
    let text = r#"
[time]
dt = 1e-5
t_end = 1e-4

[[bodies]]
name = "disc"
formulation = "axisymmetric"
mesh = { generator = "rectangle", cell = "quad4", cells = [4, 2], size = [0.1, 0.02] }
material = { young = 1e7, poisson = 0.3, density = 1000.0 }
velocity = [0.0, -1.0]
"#;
    let (model, _) = Scene::from_toml(text).unwrap().build().unwrap();
    assert!(BodyMeasures::new(&model.geometry, model.problem.q0.len()).is_none());
}

/// The rows of `model`'s initial velocity, one per point (`dof_of` maps each point's
/// components to its dofs; every one is kept in these scenes).
fn velocity_rows(model: &signorini::scene::Model) -> Vec<Vec<f64>> {
    let g = &model.geometry;
    (0..g.points.len())
        .map(|p| {
            (0..g.dim)
                .map(|d| model.problem.v0[g.dof_of[p * g.dim + d].expect("free")])
                .collect()
        })
        .collect()
}

/// A per-node `initial_velocity` (issue 37), inline or from a file, reproduces a rigid
/// motion's initial velocities bit for bit when given its values (written in Rust's
/// shortest round-trip form), so its mass, momentum and angular momentum `I ω` are the
/// closed form's (1e-12, as above); a file with comments, commas and blank lines reads
/// the same.
#[test]
fn a_nodal_velocity_field_gives_the_rigid_motion() {
    let (a, b, c) = (0.4, 0.2, 0.1);
    let m = RHO * a * b * c;
    let w = 3.0;
    let rigid = box_scene("velocity = [0.5, 0.0, 0.0]\nangular_velocity = [0.0, 0.0, 3.0]");
    let (model, _) = Scene::from_toml(&rigid).unwrap().build().unwrap();
    let rows = velocity_rows(&model);
    let inline = format!(
        "initial_velocity = [{}]",
        rows.iter()
            .map(|r| format!("{r:?}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    let dir = std::env::temp_dir().join(format!("signorini-nodal-field-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut file = String::from("# vx, vy, vz per node\n\n");
    for r in &rows {
        file.push_str(&format!("{:?}, {:?}\t{:?}  # node\n", r[0], r[1], r[2]));
    }
    std::fs::write(dir.join("v0.csv"), file).unwrap();
    for extra in [
        inline,
        r#"initial_velocity = { file = "v0.csv" }"#.to_string(),
    ] {
        let mut scene = Scene::from_toml(&box_scene(&extra)).unwrap();
        scene.base_dir = dir.clone();
        let (field, _) = scene.build().unwrap();
        assert_eq!(field.problem.v0, model.problem.v0, "{}", &extra[..40]);
        let p = &field.problem;
        let mut bm = BodyMeasures::new(&field.geometry, p.q0.len()).unwrap();
        let mut out = vec![BodyState::default(); 1];
        bm.measure(&p.system.mass, &p.q0, &p.v0, &mut out);
        let izz = m * (a * a + b * b) / 12.0;
        assert!(close(out[0].mass, m, m));
        assert!(close(out[0].momentum[0], m * 0.5, m * 0.5));
        assert!(close(out[0].angular_momentum[2], izz * w, izz * w));
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// What a per-node field cannot be: each error names the key (or the file and line),
/// the value and what was expected.
#[test]
fn bad_nodal_velocity_fields_are_refused_with_the_key_or_line() {
    let dir = std::env::temp_dir().join(format!("signorini-bad-field-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // the 4 × 2 × 2 box has 45 nodes
    let ok_row = "0.0, 0.0, 1.0\n";
    std::fs::write(dir.join("short.csv"), ok_row.repeat(44)).unwrap();
    std::fs::write(dir.join("long.csv"), ok_row.repeat(46)).unwrap();
    std::fs::write(dir.join("cols.csv"), ok_row.repeat(3) + "1.0 2.0\n").unwrap();
    std::fs::write(dir.join("word.csv"), ok_row.repeat(7) + "1.0 fast 2.0\n").unwrap();
    let rows = |n: usize, row: &str| format!("initial_velocity = [{}]", vec![row; n].join(", "));
    let cases = [
        (rows(44, "[0.0, 0.0, 1.0]"), "initial_velocity", "44 rows"),
        (
            rows(45, "[0.0, 1.0]"),
            "initial_velocity[0]",
            "3 finite values",
        ),
        (
            rows(44, "[0.0, 0.0, 1.0]").replace("= [", "= [[0.0, nan, 0.0], "),
            "initial_velocity[0]",
            "finite",
        ),
        (
            rows(45, "[0.0, 0.0, 1.0]") + "\nvelocity = [1.0, 0.0, 0.0]",
            "initial_velocity",
            "one initial motion per body",
        ),
        (
            rows(45, "[0.0, 0.0, 1.0]") + "\nfixed = [\"z0\"]",
            "initial_velocity",
            "is 0 where `fixed` holds",
        ),
        (
            r#"initial_velocity = { file = "absent.csv" }"#.into(),
            "absent.csv",
            "",
        ),
        (
            r#"initial_velocity = { file = "short.csv" }"#.into(),
            "short.csv",
            "44 rows",
        ),
        (
            r#"initial_velocity = { file = "long.csv" }"#.into(),
            "line 46",
            "past the 45",
        ),
        (
            r#"initial_velocity = { file = "cols.csv" }"#.into(),
            "line 4",
            "2 values",
        ),
        (
            r#"initial_velocity = { file = "word.csv" }"#.into(),
            "line 8",
            "`fast` is not a finite number",
        ),
    ];
    for (extra, key, expect) in cases {
        let mut scene = Scene::from_toml(&box_scene(&extra)).unwrap();
        scene.base_dir = dir.clone();
        let e = scene.build().err().expect(key).to_string();
        assert!(e.contains(key) && e.contains(expect), "{key}: {e}");
        // a file's errors name the file (and the line); the others the key path
        assert!(e.contains("bodies[0]") || e.contains(".csv"), "{key}: {e}");
    }
    // a checkpoint verifies the field's file with the mesh files
    let scene = Scene::from_toml(&box_scene(r#"initial_velocity = { file = "v0.csv" }"#)).unwrap();
    assert_eq!(scene.data_files(), vec![std::path::PathBuf::from("v0.csv")]);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A per-node `initial_displacement` (issue 37): a free steel rod stretched by the
/// linear field `u = ε x` stores `½ E A L ε²`, exactly for P1 elements (the field is in
/// their space; 1e-12 relative, round-off), and the run keeps that energy (θ = 1/2 on a
/// linear system conserves it: 1e-9 asserted over 200 steps, −2.0e-15 measured); the starting
/// gaps are checked at the displaced state: a box lowered 1 mm into its floor is
/// refused naming the floor and the depth, raised 1 mm it starts 1 mm clear; a value on
/// a fixed component is refused.
#[test]
fn a_nodal_displacement_field_is_the_initial_state() {
    let (e, a, l, eps) = (2.1e11, 1e-4, 1.0, 1e-4);
    let n = 20;
    let rows: Vec<String> = (0..=n)
        .map(|i| format!("[{:?}]", eps * l * i as f64 / n as f64))
        .collect();
    let rod = format!(
        r#"
[time]
dt = 1e-7
t_end = 2e-5

[scheme]
kind = "moreau-jean"

[[bodies]]
name = "bar"
mesh = {{ generator = "rod", elements = {n}, length = {l}, area = {a} }}
material = {{ young = {e}, poisson = 0.0, density = 7800.0 }}
initial_displacement = [{}]
"#,
        rows.join(", ")
    );
    let scene = Scene::from_toml(&rod).unwrap();
    let (model, _) = scene.build().unwrap();
    let p = &model.problem;
    let u = 0.5 * e * a * l * eps * eps;
    let e0 = p.system.potential_energy(&p.q0);
    assert!((e0 / u - 1.0).abs() < 1e-12, "{e0} vs {u}");
    let r = signorini::app::run_scene(&scene, None, &mut signorini::run::Quiet).unwrap();
    let [first, last] = r.summary.energy;
    assert!((first / u - 1.0).abs() < 1e-12, "{first}");
    assert!((last / first - 1.0).abs() < 1e-9, "{last} vs {first}");

    let floor = |dz: f64| {
        let rows = vec![format!("[0.0, 0.0, {dz:?}]"); 45].join(", ");
        box_scene(&format!(
            "initial_displacement = [{rows}]\n\n[[obstacles]]\nname = \"floor\"\ntype = \
             \"plane\"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]\n\n[[contacts]]\n\
             body = \"box\"\nnodes = \"z0\"\nobstacle = \"floor\""
        ))
    };
    let e = Scene::from_toml(&floor(-1e-3))
        .unwrap()
        .build()
        .err()
        .expect("sunk into the floor")
        .to_string();
    assert!(
        e.contains("1.000e-3 m inside") && e.contains("floor"),
        "{e}"
    );
    let (raised, _) = Scene::from_toml(&floor(1e-3)).unwrap().build().unwrap();
    let p = &raised.problem;
    let mut gap = vec![0.0; p.contacts.len()];
    p.contacts.starting_gaps(&p.q0, &mut gap);
    assert!(gap.iter().all(|&g| (g - 1e-3).abs() < 1e-15), "{gap:?}");

    let rows = vec!["[0.0, 0.0, 1e-3]"; 45].join(", ");
    let fixed = box_scene(&format!(
        "initial_displacement = [{rows}]\nfixed = [\"x0\"]"
    ));
    let e = Scene::from_toml(&fixed)
        .unwrap()
        .build()
        .err()
        .expect("a fixed node moved")
        .to_string();
    assert!(
        e.contains("initial_displacement") && e.contains("is 0 where `fixed`"),
        "{e}"
    );
}
