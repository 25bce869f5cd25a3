//! Regression: `signorini check SCENE | head -1` panicked ("failed printing to stdout:
//! Broken pipe") once the reader had gone. Printing now ignores a closed pipe, so the
//! command ends normally and a run keeps writing its files.

use std::process::{Command, Stdio};

#[test]
#[cfg(unix)]
fn closed_stdout_is_not_a_panic() {
    for args in [
        vec!["check", "meshes/bar.toml"],
        vec![
            "bar",
            "--elements",
            "50",
            "--t-end",
            "2e-5",
            "--no-plots",
            "--out",
        ],
    ] {
        let dir = std::env::temp_dir().join(format!("signorini-pipe-{}", std::process::id()));
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_signorini"));
        cmd.args(&args);
        if args[0] == "bar" {
            cmd.arg(&dir);
        }
        let mut child = cmd
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // close the read end before the program prints anything
        drop(child.stdout.take());
        let out = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
        assert!(out.status.success(), "{args:?}: {:?} {stderr}", out.status);
        if args[0] == "bar" {
            assert!(dir.join("summary.json").exists());
            std::fs::remove_dir_all(&dir).unwrap();
        }
    }
}
