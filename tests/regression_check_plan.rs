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
        let (model, _) = s.build().unwrap();
        let plan = model.plan(&s.scheme, s.time.dt).unwrap();
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
