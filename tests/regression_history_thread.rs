//! Issue 19 §3: from `run::history_thread::THREAD_MIN_DOFS` dofs the history rows (their
//! two energy quadratic forms and the CSV/HDF5 row) are formed on a thread of their own
//! from a copy of the state. The rows must be the loop thread's, byte for byte, in
//! order, also across a kill and `resume` (the checkpoint waits for the queued rows).
//! The threshold is lowered with the `SIGNORINI_HISTORY_THREAD_MIN_DOFS` test hook so
//! that small scenes take the thread.

mod common;

use common::scratch::Scratch;
use std::path::Path;
use std::process::Command;

/// Runs the CLI with `args`, into `out`, with the history on its own thread or not, and
/// optionally aborting after a step; returns whether it succeeded.
fn run(args: &[&str], out: &Path, thread: bool, abort_after: Option<usize>) -> bool {
    let mut c = Command::new(env!("CARGO_BIN_EXE_signorini"));
    c.args(args)
        .args(["--out", out.to_str().unwrap(), "--quiet", "--no-plots"])
        .env(
            "SIGNORINI_HISTORY_THREAD_MIN_DOFS",
            if thread { "0" } else { "1000000000" },
        );
    if let Some(k) = abort_after {
        c.env("SIGNORINI_ABORT_AFTER_STEP", k.to_string());
    }
    c.status().expect("binary runs").success()
}

fn read(d: &Path, f: &str) -> Vec<u8> {
    std::fs::read(d.join(f)).unwrap_or_else(|e| panic!("{}: {e}", d.join(f).display()))
}

#[test]
fn rows_from_the_history_thread_are_the_loop_threads() {
    let slide = Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/sliding_block.toml");
    let slide = slide.to_str().unwrap();
    for (name, args) in [
        // every step a row, frames between them (the frame writer flushes the history)
        (
            "bar",
            vec![
                "bar",
                "--elements",
                "200",
                "--dt",
                "1e-6",
                "--t-end",
                "6e-4",
            ],
        ),
        // 3-D, friction, gravity: per-contact tangential columns and the loads' work
        ("slide", vec!["run", slide, "--no-fields"]),
    ] {
        let (a, b) = (
            Scratch::new("hthread", &format!("{name}-inline")),
            Scratch::new("hthread", &format!("{name}-thread")),
        );
        assert!(run(&args, &a, false, None), "{name}: inline run");
        assert!(run(&args, &b, true, None), "{name}: threaded run");
        assert!(
            read(&a, "history.csv") == read(&b, "history.csv"),
            "{name}: history.csv differs between the loop and the history thread"
        );
        assert!(!read(&a, "history.csv").is_empty());
        // the summary says which path ran (the thread needs a second core)
        let summary = |d: &Path| -> serde_json::Value {
            serde_json::from_slice(&read(d, "summary.json")).unwrap()
        };
        let cores = std::thread::available_parallelism().map_or(1, |c| c.get());
        assert_eq!(summary(&a)["history_thread"], false);
        assert_eq!(summary(&b)["history_thread"], cores > 1);
    }
}

#[test]
fn a_killed_run_with_the_history_thread_resumes_byte_for_byte() {
    let args = [
        "bar",
        "--elements",
        "100",
        "--dt",
        "2e-6",
        "--t-end",
        "1e-3",
        "--checkpoint-every",
        "50",
    ];
    let whole = Scratch::new("hthread", "whole");
    assert!(run(&args, &whole, false, None));
    // kills at a checkpoint and between two: the rows queued at the kill are either in
    // the checkpoint's count (written before it) or redone by the resumed run
    for k in [200, 317] {
        let dir = Scratch::new("hthread", &format!("kill{k}"));
        assert!(
            !run(&args, &dir, true, Some(k)),
            "the hook did not stop the run"
        );
        let ok = Command::new(env!("CARGO_BIN_EXE_signorini"))
            .args(["resume", dir.to_str().unwrap(), "--quiet"])
            .env("SIGNORINI_HISTORY_THREAD_MIN_DOFS", "0")
            .status()
            .unwrap()
            .success();
        assert!(ok, "resume after {k}");
        assert!(
            read(&whole, "history.csv") == read(&dir, "history.csv"),
            "killed after {k}: the resumed history differs"
        );
    }
}
