#![allow(dead_code)]
//! Helpers of the bad-input tests: run the CLI, require an exit code, no panic, and
//! every expected piece of the message.

use std::path::Path;
use std::process::Command;

/// A valid scene: a hex8 box above a floor, contacts on its bottom face. `MESH` is the
/// mesh line, for tests that swap in a mesh file.
pub const BOX_ON_FLOOR: &str = r#"[time]
dt = 1e-4
t_end = 1e-3
[[bodies]]
name = "b"
MESH
material = { young = 1e6, poisson = 0.3, density = 1000.0 }
[[obstacles]]
name = "floor"
type = "plane"
point = [0.0, 0.0, -0.01]
normal = [0.0, 0.0, 1.0]
[[contacts]]
body = "b"
nodes = "z0"
obstacle = "floor"
"#;

/// The generated box's mesh line.
pub const BOX_MESH: &str =
    "mesh = { generator = \"box\", cell = \"hex8\", cells = [1, 1, 1], size = [0.1, 0.1, 0.1] }";

/// A fresh temporary directory for one test (removed when the test passes).
pub fn tmp(name: &str) -> super::scratch::Scratch {
    let d = super::scratch::Scratch::new("bad", name);
    std::fs::create_dir_all(&*d).unwrap();
    d
}

/// Runs `signorini args…` in `dir` (with `env`), returns (exit code, stderr).
pub fn cli(dir: &Path, args: &[&str], env: &[(&str, &str)]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_signorini"))
        .current_dir(dir)
        .args(args)
        .envs(env.iter().copied())
        .output()
        .expect("binary runs");
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(
        !stderr.contains("panicked") && !stderr.contains("RUST_BACKTRACE"),
        "{args:?} panicked: {stderr}"
    );
    (out.status.code().unwrap_or(-1), stderr)
}

/// Asserts exit `code` and that the message holds every needle; `class` names the case.
pub fn expect(class: &str, (code, err): (i32, String), want: i32, needles: &[&str]) {
    assert_eq!(code, want, "{class}: exit {code}: {err}");
    for n in needles {
        assert!(err.contains(n), "{class}: the message lacks {n:?}: {err}");
    }
    assert!(err.len() < 1200, "{class}: the message is too long: {err}");
}
