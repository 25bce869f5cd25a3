//! `signorini check` plans a run instead of building it (issue 18 §2: on a 30³ cube it
//! took 36 s and 2.5 GB building the integrator, now a symbolic analysis): the planned
//! paths are the ones the built integrator takes, scene by scene, and the memory ledger
//! is printed and checked against the limit before anything is factored.

mod common;

use std::path::Path;
use std::process::Command;

use common::bad::{cli, expect};
use signorini::scene::file::Scene;

fn scene(name: &str) -> Scene {
    Scene::from_file(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("meshes")
            .join(name),
    )
    .unwrap()
}

/// The plan's factor backend (with its fill) and Delassus path appear word for word in
/// the built integrator's path, for every kind of decision the shipped scenes take:
/// tridiagonal and supernodal factors, AMD and nested dissection, dense Delassus blocks,
/// the contact zone, per-active-column (hex8 on a curved obstacle), Schatzman–Paoli, a
/// nonlinear structure's LDLᵀ and a rigid mechanism's dense LU.
#[test]
fn planned_paths_are_the_built_ones() {
    for (file, kind) in [
        ("bar.toml", None),
        ("bar.toml", Some("schatzman-paoli")),
        ("hex_bar.toml", None),
        ("block_on_cylinder.toml", None),
        ("hex_bars.toml", None),
        // the contact zone keeping its flexibilities (auto), and Â⁻¹S (dense)
        ("hex_bars.toml", Some("dense")),
        ("hex_bars.toml", Some("schatzman-paoli")),
        ("sliding_block_on_slab.toml", None),
        ("block_stack.toml", None),
        ("hertz_ball.toml", None),
        // a nonlinear structure: LDLᵀ of M̂ⁿ, refactored in the step
        ("ball_crush.toml", None),
        // a rigid mechanism (nonsymmetric M̂ⁿ of a few dofs): dense LU
        ("slider_crank.toml", None),
    ] {
        let mut s = scene(file);
        match kind {
            Some("dense") => s.scheme.delassus = signorini::delassus::DelassusKind::Dense,
            Some(k) => s.scheme.kind = signorini::integrators::SchemeKind::parse(k).unwrap(),
            None => {}
        }
        let (mut model, _) = s.build().unwrap();
        // planned on its own (`plan_only` keeps nothing): the build analyses again
        let plan = model.plan_only(&s.scheme, s.time.dt).unwrap();
        let path = model.into_integrator(&s.scheme, s.time.dt).unwrap().path();
        assert!(
            path.contains(&plan.factor.backend),
            "{file}: planned factor {:?}, built {path}",
            plan.factor.backend
        );
        assert!(
            path.contains(&plan.delassus.describe),
            "{file}: planned {:?}, built {path}",
            plan.delassus.describe
        );
        if file == "hex_bars.toml" {
            assert_eq!(
                path.contains("not kept"),
                kind.is_none(),
                "{file} {kind:?}: {path}"
            );
        }
        assert!(
            plan.ledger.total() > 8 << 20,
            "{file}: the ledger counts the process"
        );
    }
}

/// Issue 36 §2: a run plans, then builds, and the build takes the plan's validation and
/// its step matrix (formed and analysed once). The integrator built after a plan steps
/// bit for bit as one built without (the same matrix, the same symbolic analysis), on a
/// tridiagonal rod (no analysis kept), a supernodal hex8 factor with nested dissection,
/// Schatzman–Paoli's own matrix, and a nonlinear structure (which keeps none).
#[test]
fn a_planned_build_steps_as_an_unplanned_one() {
    for (file, kind) in [
        ("bar.toml", None),
        ("hex_bars.toml", None),
        ("hex_bars.toml", Some("schatzman-paoli")),
        ("ball_crush.toml", None),
    ] {
        let mut s = scene(file);
        if let Some(k) = kind {
            s.scheme.kind = signorini::integrators::SchemeKind::parse(k).unwrap();
        }
        let run = |plan_first: bool| {
            let (mut model, _) = s.build().unwrap();
            if plan_first {
                model.plan(&s.scheme, s.time.dt).unwrap();
            }
            let mut integ = model.into_integrator(&s.scheme, s.time.dt).unwrap();
            for _ in 0..30 {
                integ.step().unwrap();
            }
            let st = integ.state();
            (integ.path(), st.q.clone(), st.v.clone(), st.impulse.clone())
        };
        let (planned, unplanned) = (run(true), run(false));
        assert_eq!(planned.0, unplanned.0, "{file} {kind:?}: paths");
        let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        for (name, a, b) in [
            ("q", &planned.1, &unplanned.1),
            ("v", &planned.2, &unplanned.2),
            ("impulse", &planned.3, &unplanned.3),
        ] {
            assert_eq!(bits(a), bits(b), "{file} {kind:?}: {name} after 30 steps");
        }
    }
}

/// What a plan established holds for the problem as planned only: changed after it (a
/// NaN in the initial velocity, a stiffer structure, another step), the build validates
/// and forms its matrix afresh, so a plan can never carry a wrong matrix or a stale check
/// into a run.
#[test]
fn a_problem_changed_after_its_plan_is_built_afresh() {
    let s = scene("hex_bars.toml");
    let (dt, p) = (s.time.dt, &s.scheme);
    // a NaN initial velocity after the plan: refused as without a plan
    let (mut model, _) = s.build().unwrap();
    model.plan(p, dt).unwrap();
    model.problem.v0[3] = f64::NAN;
    let err = model
        .into_integrator(p, dt)
        .err()
        .expect("a NaN v0 is refused");
    assert!(
        err.to_string().contains("initial velocity"),
        "the validation names the field: {err}"
    );
    // `q` after 20 steps of the scene, planned at `dt` or not, its stiffness scaled by
    // `k` after the plan, built at step `dt_build`
    let run = |plan: bool, k: f64, dt_build: f64| {
        let (mut model, _) = s.build().unwrap();
        if plan {
            model.plan(p, dt).unwrap();
        }
        let stiffness = model.problem.system.stiffness.val_mut();
        stiffness.iter_mut().for_each(|x| *x *= k);
        let mut integ = model.into_integrator(p, dt_build).unwrap();
        for _ in 0..20 {
            integ.step().unwrap();
        }
        let q = &integ.state().q;
        q.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
    };
    // the stiffness doubled after the plan: steps as the same problem built unplanned
    assert_eq!(
        run(true, 2.0, dt),
        run(false, 2.0, dt),
        "stiffness changed after the plan"
    );
    // planned at dt, built at dt/2: the matrix of dt/2
    assert_eq!(
        run(true, 1.0, dt / 2.0),
        run(false, 1.0, dt / 2.0),
        "built at another step than planned"
    );
}

/// `check` on the wide block (90 000 dofs, 30 000 contact rows) prints the planned
/// path (matrix-free past the workspaces) and the ledger; under a memory limit of
/// 1 GiB it exits 2 naming the scene's size, the limit and the Delassus data, without
/// factoring (the planned factor alone is 210 MiB, the Delassus pool 1.9 GiB).
#[test]
fn check_prints_the_ledger_and_refuses_what_does_not_fit() {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/wide_block.toml");
    let out = Command::new(env!("CARGO_BIN_EXE_signorini"))
        .arg("check")
        .arg(&file)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    assert!(text.contains("matrix-free past them"), "{text}");
    assert!(text.contains("nnz(L) = 27472077"), "{text}");
    let mem = text.lines().find(|l| l.starts_with("memory")).unwrap();
    for part in ["factor of M̂ 209.6 MiB", "Delassus data 1.9 GiB", "planned"] {
        assert!(mem.contains(part), "lacks {part:?}: {mem}");
    }
    let dir = std::env::temp_dir().join(format!("signorini-plan-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let r = cli(
        &dir,
        &["check", file.to_str().unwrap()],
        &[("SIGNORINI_MEMORY_LIMIT", "1G")],
    );
    expect(
        "ledger over the limit",
        r,
        2,
        &[
            "scene",
            "90000 dofs, 10000 contacts",
            "memory limit 1.0 GiB",
            "Delassus data 1.9 GiB",
        ],
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `check` names the cell kinds it built and counts them (issue 51: a mesh of quadratic
/// cells says so before it runs): the two hex bars with the striker in hex27 are 1 350
/// hex8 and 800 hex27 cells (150 × 3 × 3 and 200 × 2 × 2), as the CLI prints them.
#[test]
fn check_counts_the_cells_of_each_kind() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = Command::new(env!("CARGO_BIN_EXE_signorini"))
        .current_dir(root)
        .args([
            "check",
            "meshes/hex_bars.toml",
            "--set",
            "bodies[0].mesh.cell=\"hex27\"",
        ])
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("2150 cells (1350 hex8, 800 hex27)"), "{text}");
    let report = scene("bar.toml").check().unwrap();
    assert_eq!(report.cell_kinds, vec![("line".to_string(), 1000)]);
}
