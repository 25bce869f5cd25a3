#![allow(dead_code)]
//! Helpers of the bad-input tests: run the CLI, require an exit code, no panic, and
//! every expected piece of the message.

use std::path::{Path, PathBuf};
use std::process::Command;

/// A fresh temporary directory for one test.
pub fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("signorini-bad-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
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
