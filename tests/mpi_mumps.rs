//! `signorini run … --mumps` under `mpirun -np 1, 2, 4` (cargo feature `mumps`; issue 19
//! §2): M̂ factored and solved by MUMPS over the ranks, the contact problems on rank 0.
//! Each launch's summary names the rank count MUMPS saw (a launcher that does not match
//! the library would start N independent one-rank jobs, each writing "over 1 MPI
//! rank(s)"), and its history equals the serial run's (faer's supernodal Cholesky, or
//! sparse `L D Lᵀ` on the nonlinear path) to the factor's round-off.
//!
//! Tolerances, per kind of history column (`tests/regression_golden_histories.rs` keeps
//! the same policy for the fused arithmetic): values within 1e-12 of their column kind's
//! largest magnitude (measured ≤ 2.5e-15 on the cube, ≤ 9.2e-14 on the neo-Hookean ball:
//! a direct factor's backward error is a few ulps times a growth factor, here two
//! different elimination orders); gaps and contact velocities that are themselves at
//! round-off under the projection (1e-22 m, 1e-16 m/s) to absolute bounds 1e-18 m and
//! 1e-12 m/s (1e-11 of `|v0| h` and of `|v0|`); iteration counts equal on the linear path
//! and within ±2 projections on the nonlinear one (the projection iterates to machine
//! accuracy: a last iteration depends on the last bits; measured ±2).
#![cfg(feature = "mumps")]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("signorini-mumps-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// An 8³-cell hex8 cube (2187 dofs) falling flat on a rigid floor with its 81 bottom
/// nodes, Algorithm 2 (a linear scene: M̂ factored once, SYM = 1).
const CUBE: &str = r#"
[time]
dt = 1e-6
t_end = 2e-5
[scheme]
kind = "combined-projection"
[[bodies]]
name = "cube"
mesh = { generator = "box", cell = "hex8", cells = [8, 8, 8], size = [1.0, 1.0, 1.0] }
material = { young = 210e9, poisson = 0.3, density = 7800.0 }
velocity = [0.0, 0.0, -0.1]
[[obstacles]]
name = "floor"
type = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
[[contacts]]
body = "cube"
nodes = "z0"
obstacle = "floor"
[output]
fields = false
plots = false
"#;

fn signorini(np: Option<usize>) -> Command {
    match np {
        None => Command::new(env!("CARGO_BIN_EXE_signorini")),
        Some(np) => {
            let mut c = Command::new("mpirun");
            c.env("OMPI_ALLOW_RUN_AS_ROOT", "1")
                .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
                .args(["--oversubscribe", "-np", &np.to_string()])
                .arg(env!("CARGO_BIN_EXE_signorini"));
            c
        }
    }
}

fn run(np: Option<usize>, args: &[&str], out: &Path) -> String {
    let mut c = signorini(np);
    c.args(args).args(["--quiet", "--out"]).arg(out);
    if np.is_some() {
        c.arg("--mumps");
    }
    let o = c.output().expect("mpirun (Debian's openmpi-bin) runs");
    assert!(
        o.status.success(),
        "{np:?} {args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    s["path"].as_str().unwrap().to_string()
}

type History = (Vec<String>, Vec<Vec<f64>>);

fn history(dir: &Path) -> History {
    let text = std::fs::read_to_string(dir.join("history.csv")).unwrap();
    let mut lines = text.lines();
    let head: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    (head, rows)
}

/// The column's kind: `gap_12` → `gap`; a body's columns by quantity, every body and
/// axis together (`angular_momentum_0_2` → `angular_momentum`).
fn kind(name: &str) -> &str {
    for q in ["centre", "momentum", "angular_momentum"] {
        if let Some(rest) = name.strip_prefix(q).and_then(|r| r.strip_prefix('_'))
            && rest
                .split('_')
                .all(|i| !i.is_empty() && i.chars().all(|c| c.is_ascii_digit()))
        {
            return q;
        }
    }
    match name.rsplit_once('_') {
        Some((k, i)) if i.chars().all(|c| c.is_ascii_digit()) => k,
        _ => name,
    }
}

/// Compares two histories by the module doc's policy; `projections` is the allowed
/// difference in projection iterations per row.
fn assert_close(what: &str, serial: &History, mumps: &History, projections: f64) {
    assert_eq!(serial.0, mumps.0, "{what}: columns");
    assert_eq!(serial.1.len(), mumps.1.len(), "{what}: rows");
    let mut scale: BTreeMap<&str, f64> = BTreeMap::new();
    for (j, name) in serial.0.iter().enumerate() {
        let m = serial.1.iter().map(|r| r[j].abs()).fold(0.0, f64::max);
        let e = scale.entry(kind(name)).or_insert(0.0);
        *e = e.max(m);
    }
    for (j, name) in serial.0.iter().enumerate() {
        let k = kind(name);
        let (tol, how) = match k {
            "step" | "time" | "index_set_iterations" => (0.0, "equal"),
            "newton_iterations" => (0.0, "equal"),
            "projection_iterations" => (projections, "± projections"),
            "gap" | "max_violation" => (1e-18_f64.max(1e-12 * scale[k]), "1e-18 m or 1e-12"),
            "velocity" => (1e-12_f64.max(1e-12 * scale[k]), "1e-12 m/s or 1e-12"),
            // a body that does not turn has an angular momentum of round-off: its scale
            // is the momentum's times the body's extent (the centres' scale)
            "angular_momentum" => (
                1e-12 * scale[k].max(scale["momentum"] * scale["centre"]),
                "1e-12 of max(|L|, |p| |c|)",
            ),
            _ => (1e-12 * scale[k], "1e-12 of the kind's scale"),
        };
        for (row, (a, b)) in serial.1.iter().zip(&mumps.1).enumerate() {
            assert!(
                (a[j] - b[j]).abs() <= tol,
                "{what}: {name} at row {row}: serial {} against MUMPS {} (tolerance {tol:e}, {how})",
                a[j],
                b[j]
            );
        }
    }
}

#[test]
fn mumps_on_1_2_and_4_ranks_gives_the_serial_history_of_a_cube() {
    let scene = tmp("cube").with_extension("toml");
    std::fs::write(&scene, CUBE).unwrap();
    let s = scene.to_str().unwrap();
    let serial_dir = tmp("cube-serial");
    let serial_path = run(None, &["run", s], &serial_dir);
    assert!(!serial_path.contains("MUMPS"), "{serial_path}");
    let serial = history(&serial_dir);
    for np in [1usize, 2, 4] {
        let dir = tmp(&format!("cube-np{np}"));
        let path = run(Some(np), &["run", s], &dir);
        assert!(
            path.contains("(MUMPS 5.") // Debian bookworm: 5.5.1
                && path.contains("(L D Lᵀ, positive definite, ")
                && path.contains(&format!("over {np} MPI rank(s)")),
            "np {np}: {path}"
        );
        assert_close(&format!("cube, {np} rank(s)"), &serial, &history(&dir), 0.0);
    }
}

#[test]
fn mumps_refactors_the_nonlinear_tangent_at_every_newton_iterate() {
    // the neo-Hookean ball of meshes/ball_crush.toml up to 13 steps of contact (its first
    // impulse at step 102): M̂ⁿ is symmetric indefinite (SYM = 2), refactored per iterate
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/meshes/ball_crush.toml");
    let args = [
        "run",
        scene,
        "--set",
        "time.t_end=0.0115",
        "--set",
        "output.fields=false",
        "--set",
        "output.plots=false",
    ];
    let serial_dir = tmp("ball-serial");
    run(None, &args, &serial_dir);
    let dir = tmp("ball-np2");
    let path = run(Some(2), &args, &dir);
    assert!(
        path.contains("refactored at every iterate (MUMPS")
            && path.contains("symmetric indefinite")
            && path.contains("over 2 MPI rank(s)"),
        "{path}"
    );
    let (serial, mumps) = (history(&serial_dir), history(&dir));
    let impulses = |h: &History| {
        h.1.iter()
            .filter(|r| {
                h.0.iter()
                    .zip(r.iter())
                    .any(|(n, v)| n.starts_with("impulse_") && *v > 0.0)
            })
            .count()
    };
    assert!(impulses(&serial) >= 10, "the ball reaches the floor");
    assert_close("neo-Hookean ball, 2 ranks", &serial, &mumps, 2.0);
}

#[test]
fn mumps_is_refused_with_a_sweep_over_mpi_ranks() {
    let o = signorini(None)
        .args(["sweep", "bar", "--mpi", "--mumps"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("--mumps") && e.contains("sweep --mpi"), "{e}");
}
