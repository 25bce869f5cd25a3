//! Runs that must stop (issue 12 §2, §4): exit code 1 with the step, the time and the
//! contact when the state turns non-finite, the violation explodes or an iteration cap
//! is hit (unless the scene allows caps); exit code 2 for command-line values that are
//! wrong even when the options that use them are off, absurd sizes and memory; and a run
//! directory that held an older run keeps nothing of it.

mod common;

use common::bad::{cli, expect, tmp};

fn cylinder_scene(extra_scheme: &str) -> String {
    let src = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/block_on_cylinder.toml"),
    )
    .unwrap();
    src.replace("t_end = 0.3", "t_end = 0.05").replace(
        "kind = \"combined-projection\"",
        &format!("kind = \"combined-projection\"\n{extra_scheme}"),
    )
}

#[test]
fn a_newton_cap_fails_the_run_unless_the_scene_allows_caps() {
    let dir = tmp("caps");
    // one Newton iteration cannot follow the curved obstacle's G(q)
    let s = cylinder_scene("newton = { tol = 1e-12, max_iterations = 1 }");
    std::fs::write(dir.join("s.toml"), &s).unwrap();
    let r = cli(
        &dir,
        &["run", "s.toml", "--quiet", "--out", "o", "--no-plots"],
        &[],
    );
    expect(
        "Newton cap",
        r,
        1,
        &[
            "run failed at step",
            "t = ",
            "contact ",
            "cap",
            "allow_caps",
        ],
    );
    // the history up to the failure is kept
    assert!(dir.join("o/history.csv.part").exists());
    // two iterations: capped steps that keep the energy balance (one iteration with caps
    // allowed gains 4 % of the energy and fails: tests/regression_energy_balance.rs)
    let s = cylinder_scene("newton = { tol = 1e-12, max_iterations = 2 }\nallow_caps = true");
    std::fs::write(dir.join("s.toml"), &s).unwrap();
    let r = cli(
        &dir,
        &["run", "s.toml", "--quiet", "--out", "o", "--no-plots"],
        &[],
    );
    assert_eq!(r.0, 0, "{}", r.1);
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("o/summary.json")).unwrap()).unwrap();
    assert!(
        summary["caps_hit"].as_u64().unwrap() > 0,
        "caps are counted"
    );
}

/// A free body falling under gravity of 1e150 m/s² (the largest load accepted) at steps
/// of 1e79 s: `½ g t²` passes the largest double at the second step (2e308 m), and the
/// run stops there, naming the step and the time. (Loads and initial velocities of
/// 1e308 were the examples before issue 48; they are refused now at validation, past
/// `MAX_LOAD_MAGNITUDE`: `tests/bad_input_scene.rs`.) E = 1e-160 Pa keeps `M̂ = M +
/// h²θ²K` factorable at that step.
#[test]
fn a_non_finite_state_stops_the_run_with_step_and_time() {
    let dir = tmp("nonfinite");
    let scene = r#"[time]
dt = 1e79
t_end = 1e80
[[bodies]]
name = "b"
mesh = { generator = "box", cell = "hex8", cells = [1, 1, 1], size = [0.1, 0.1, 0.1] }
material = { young = 1e-160, poisson = 0.3, density = 1000.0 }
[loads]
gravity = [0.0, 0.0, -1e150]
"#;
    std::fs::write(dir.join("s.toml"), scene).unwrap();
    let r = cli(
        &dir,
        &["run", "s.toml", "--quiet", "--out", "o", "--no-plots"],
        &[],
    );
    expect(
        "non-finite state",
        r,
        1,
        &["run failed at step 2", "t = 2e79", "broke down"],
    );
}

/// A hyperelastic body crushed until a cell turns inside out stops the run (exit 1) with
/// the step, the time, the body and the cell's tag: a soft neo-Hookean cube hitting the
/// floor at 100 m/s, 30 times its wave speed.
/// A soft cube hitting the floor at 100 m/s inverts, under both large-deformation laws:
/// St. Venant–Kirchhoff's energy is defined at det F ≤ 0 and before issue 34 its runs
/// went on (a cube at 50 m/s ended 1.1 cm below the floor, exit 0).
#[test]
fn an_inverted_element_stops_the_run_naming_the_cell() {
    let dir = tmp("inverted");
    for model in ["neo-hookean", "svk"] {
        let scene = r#"[time]
dt = 1e-4
t_end = 1e-2
[[bodies]]
name = "soft"
mesh = { generator = "box", cell = "hex8", cells = [2, 2, 2], size = [0.1, 0.1, 0.1] }
material = { young = 1e4, poisson = 0.3, density = 1000.0, model = "MODEL" }
velocity = [0.0, 0.0, -100.0]
[[obstacles]]
name = "floor"
type = "plane"
point = [0.0, 0.0, -0.001]
normal = [0.0, 0.0, 1.0]
[[contacts]]
body = "soft"
nodes = "z0"
obstacle = "floor"
"#
        .replace("MODEL", model);
        std::fs::write(dir.join("s.toml"), scene).unwrap();
        let r = cli(
            &dir,
            &["run", "s.toml", "--quiet", "--out", "o", "--no-plots"],
            &[],
        );
        expect(
            model,
            r,
            1,
            &[
                "run failed at step",
                "body \"soft\"",
                "cell",
                "is inverted",
                "det F",
            ],
        );
    }
}

/// Issue 34: an SVK cube held at its base and pushed on its top with 5 E A (a load past
/// the law's limit point in compression, where its stress turns back) ended with its top
/// 0.39 m below its base at exit 0; it now stops on the first inverted cell.
#[test]
fn an_svk_cube_crushed_through_its_base_stops_the_run() {
    let dir = tmp("svk-crushed");
    let scene = r#"[time]
dt = 1e-3
t_end = 0.5
[[bodies]]
name = "cube"
mesh = { generator = "box", cell = "hex8", cells = [2, 2, 2], size = [0.1, 0.1, 0.1] }
material = { young = 1e4, poisson = 0.3, density = 1000.0, model = "svk" }
damping = { alpha = 0.0, beta = 1e-2 }
fixed = ["z0"]
[[forces]]
body = "cube"
nodes = "z1"
total = [0.0, 0.0, -500.0]
"#;
    std::fs::write(dir.join("s.toml"), scene).unwrap();
    let r = cli(
        &dir,
        &["run", "s.toml", "--quiet", "--out", "o", "--no-plots"],
        &[],
    );
    expect(
        "svk crushed",
        r,
        1,
        &[
            "run failed at step",
            "body \"cube\"",
            "is inverted",
            "det F",
        ],
    );
}

#[test]
fn an_exploding_violation_stops_the_run() {
    let dir = tmp("explode");
    // Moreau–Jean penetrates |v0|(1−θ)h = 5 m per step here, past the 1 m bar
    let r = cli(
        &dir,
        &[
            "bar",
            "--elements",
            "10",
            "--dt",
            "1e-3",
            "--t-end",
            "3e-3",
            "--velocity",
            "-1e4",
            "--scheme",
            "moreau-jean",
            "--quiet",
            "--out",
            "o",
            "--no-plots",
        ],
        &[],
    );
    expect(
        "exploding violation",
        r,
        1,
        &[
            "run failed at step",
            "contact 0",
            "penetration",
            "model's size",
        ],
    );
}

#[test]
fn an_unwritable_output_fails_the_run_with_exit_1() {
    let dir = tmp("unwritable");
    std::fs::write(dir.join("file"), "not a directory").unwrap();
    let r = cli(
        &dir,
        &[
            "--elements",
            "10",
            "--t-end",
            "1e-5",
            "--quiet",
            "--out",
            "file/out",
        ],
        &[],
    );
    expect("output under a file", r, 1, &["cannot write", "file/out"]);
}

#[test]
fn flags_are_checked_even_when_unused_and_sizes_before_allocating() {
    let dir = tmp("flags");
    let cases: &[(&str, &[&str], &[&str])] = &[
        (
            "negative PGS tolerance without PGS",
            &["--lcp-tol", "-1"],
            &["--lcp-tol", "-1"],
        ),
        (
            "gamma out of range with the free forecast",
            &["--gamma", "5"],
            &["--gamma", "5", "[0, 2]"],
        ),
        (
            "zero PGS sweeps without PGS",
            &["--lcp-max-sweeps", "0"],
            &["--lcp-max-sweeps"],
        ),
        (
            "zero frame stride",
            &["--save-every", "0"],
            &["--save-every"],
        ),
        (
            "zero history stride",
            &["--history-every", "0"],
            &["--history-every"],
        ),
        (
            "1e30 s of simulated time",
            &["--t-end", "1e30"],
            &["dt", "5.000e36 steps", "at most 1000000000"],
        ),
        (
            "a 1e-300 s step",
            &["--dt", "1e-300"],
            &["dt", "1e-300", "at most"],
        ),
        (
            "10^12 elements",
            &["--elements", "1000000000000"],
            &["elements", "1000000000000", "memory limit"],
        ),
    ];
    for (class, args, needles) in cases {
        let mut a = args.to_vec();
        a.extend(["--quiet", "--out", "o"]);
        expect(class, cli(&dir, &a, &[]), 2, needles);
        assert!(!dir.join("o/summary.json").exists(), "{class} wrote output");
    }
    // a memory limit set lower than a modest run needs
    let r = cli(
        &dir,
        &["--elements", "100000", "--quiet", "--out", "o"],
        &[("SIGNORINI_MEMORY_LIMIT", "1M")],
    );
    expect(
        "memory limit",
        r,
        2,
        &["elements", "100000", "memory limit 1.0 MiB"],
    );
}

/// Issue 34: `SIGNORINI_MEMORY_LIMIT` is parsed strictly by every command (`lots`, `-1G`,
/// `2GB` and an overflowing number were ignored silently), `bar` counts the process in
/// its ledger (a 1 MiB limit let the default bar run), and a mesh file is measured
/// against the limit after it is read, before it is assembled.
#[test]
fn memory_limits_are_parsed_strictly_and_applied_to_every_command() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = tmp("memory-limit");
    let out = dir.join("o");
    let out = out.to_str().unwrap();
    for value in ["lots", "-1G", "2GB", "99999999999999999999", "0"] {
        for args in [
            &["bar", "--quiet", "--no-plots", "--out", out][..],
            &["check", "meshes/bar.toml"][..],
            &["run", "meshes/bar.toml", "--quiet", "--out", out][..],
            &["example", "bouncing-ball", "--quiet", "--out", out][..],
        ] {
            expect(
                &format!("{value} / {}", args[0]),
                cli(root, args, &[("SIGNORINI_MEMORY_LIMIT", value)]),
                2,
                &[
                    "SIGNORINI_MEMORY_LIMIT",
                    &format!("{value:?}"),
                    "512M or 2G",
                ],
            );
        }
    }
    expect(
        "1M on the default bar",
        cli(
            root,
            &["bar", "--quiet", "--no-plots", "--out", out],
            &[("SIGNORINI_MEMORY_LIMIT", "1M")],
        ),
        2,
        &[
            "the process (binary, libraries, threads) 8.0 MiB",
            "memory limit 1.0 MiB",
        ],
    );
    expect(
        "a mesh file past the limit",
        cli(
            root,
            &["check", "meshes/ball_drop.toml"],
            &[("SIGNORINI_MEMORY_LIMIT", "2M")],
        ),
        2,
        &[
            "mesh.path",
            "ball.msh",
            "assembled dofs",
            "memory limit 2.0 MiB",
        ],
    );
    // the accepted spellings
    for value in ["2G", "2GiB", "2048M", "2147483648"] {
        let (code, err) = cli(
            root,
            &["check", "meshes/bar.toml"],
            &[("SIGNORINI_MEMORY_LIMIT", value)],
        );
        assert_eq!(code, 0, "{value}: {err}");
    }
}

#[test]
fn a_new_run_leaves_nothing_of_an_older_one() {
    let dir = tmp("older");
    let base = [
        "--elements",
        "20",
        "--dt",
        "1e-5",
        "--t-end",
        "5e-4",
        "--quiet",
        "--out",
        "o",
    ];
    assert_eq!(cli(&dir, &base, &[]).0, 0);
    assert!(dir.join("o/fields.pvd").exists() && dir.join("o/contact_force.png").exists());
    std::fs::write(dir.join("o/history.csv.part"), "step,time\n1,0.1").unwrap();
    std::fs::write(dir.join("o/fields/frame_000999.vtu.part"), "x").unwrap();
    // the same directory, now without fields or plots, and killed before its end
    let mut a = base.to_vec();
    a.extend([
        "--no-fields",
        "--no-plots",
        "--checkpoint-every",
        "10",
        "--no-hdf5",
    ]);
    let r = cli(&dir, &a, &[("SIGNORINI_ABORT_AFTER_STEP", "20")]);
    assert_ne!(r.0, 0);
    for stale in [
        "summary.json",
        "history.csv",
        "fields.pvd",
        "contact_force.png",
        "fields/frame_000000.vtu",
        "fields/frame_000999.vtu.part",
    ] {
        assert!(
            !dir.join("o").join(stale).exists(),
            "{stale} of the older run is still there"
        );
    }
    // the killed run's history ends with a complete row; a cut row would be skipped
    let h = std::fs::read_to_string(dir.join("o/history.csv.part")).unwrap();
    assert!(
        h.ends_with('\n') && h.lines().count() == 21,
        "{} rows",
        h.lines().count()
    );
}

#[test]
fn plot_bounds_extreme_histories_and_skips_a_cut_row() {
    let dir = tmp("plot");
    let header = "step,time,kinetic_energy,potential_energy,max_violation,newton_iterations,\
                  projection_iterations,index_set_iterations";
    std::fs::write(
        dir.join("history.csv"),
        format!("{header}\n1,0,1e308,-1e308,0,0,0,0\n2,1,-1e308,1e308,1e308,0,0,0\n"),
    )
    .unwrap();
    let t0 = std::time::Instant::now();
    let r = cli(&dir, &["plot", "."], &[]);
    assert_eq!(r.0, 0, "{}", r.1);
    assert!(t0.elapsed().as_secs() < 60, "plot took {:?}", t0.elapsed());
    // a killed run's .part: the last row, cut between two digits, still parses
    std::fs::remove_file(dir.join("history.csv")).unwrap();
    std::fs::write(
        dir.join("history.csv.part"),
        format!("{header}\n1,0,1,0,0,0,0,0\n2,1,2,0,0,0,0,0\n3,2,3.1"),
    )
    .unwrap();
    assert_eq!(cli(&dir, &["plot", "."], &[]).0, 0);
    let t = std::fs::read_to_string(dir.join("history.csv.part")).unwrap();
    let lines: Vec<&str> = signorini::plot::complete_lines(&t).collect();
    assert_eq!(lines.len(), 3, "header and two complete rows");
}

/// Issue 16 §6: a run failure advises only remedies that can help. A friction cap of one
/// sweep stops the sliding block at step 1 (exit 1); with `nsgs` and `prox` the message
/// suggests `auto` (which adds the Newton methods), with `auto` it does not (they already
/// ran), and all name the solver, the cap and the budget and step remedies.
#[test]
fn a_friction_cap_advises_only_what_was_not_tried() {
    let dir = tmp("friction-cap");
    let base = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/sliding_block.toml"),
    )
    .unwrap();
    for (solver, suggests_auto) in [("nsgs", true), ("prox", true), ("auto", false)] {
        let scene = base.replacen(
            "kind = \"combined-projection\"",
            &format!(
                "kind = \"combined-projection\"\n[scheme.friction]\nsolver = \"{solver}\"\nmax_iterations = 1"
            ),
            1,
        );
        let file = format!("{solver}.toml");
        std::fs::write(dir.join(&file), scene).unwrap();
        let (code, err) = cli(
            &dir,
            &["run", &file, "--quiet", "--no-plots", "--no-fields"],
            &[],
        );
        expect(
            solver,
            (code, err.clone()),
            1,
            &[
                "step 1",
                &format!("the {solver} friction solver stopped at its cap of 1 sweeps"),
                "raise scheme.friction.max_iterations",
                "lower the time step",
            ],
        );
        assert_eq!(
            err.contains("try scheme.friction.solver = \"auto\""),
            suggests_auto,
            "{solver}: {err}"
        );
    }
}

/// Issue 48 (no Rust debug text): a step matrix that is not positive definite (a free
/// body of density 1e-30, whose mass vanishes beside h²K) was reported with faer's
/// `NonPositivePivot { index: 20 }`; now in words, with the row.
#[test]
fn a_failed_factorization_is_reported_in_words() {
    let dir = tmp("not_spd");
    let scene = r#"[time]
dt = 1e-3
t_end = 1e-2
[[bodies]]
name = "b"
mesh = { generator = "box", cell = "hex8", cells = [1, 1, 1], size = [0.1, 0.1, 0.1] }
material = { young = 1e6, poisson = 0.3, density = 1e-30 }
"#;
    std::fs::write(dir.join("s.toml"), scene).unwrap();
    let (code, err) = cli(
        &dir,
        &["run", "s.toml", "--quiet", "--out", "o", "--no-plots"],
        &[],
    );
    expect(
        "not positive definite",
        (code, err.clone()),
        1,
        &["not positive definite", "a pivot ≤ 0 at row"],
    );
    assert!(!err.contains("{ index"), "debug text: {err}");
}
