//! Issue 16 §5: one run owns its output directory. Before, two runs into one `--out`
//! both ran, one exiting 0 beside the other's history.
//!
//! A long bar run holds `OUT/.signorini.lock` (the OS's advisory lock); a second run
//! into `OUT` is refused with exit code 2, names the holder's process id, and leaves the
//! first run's files alone. Once the holder is killed (SIGKILL: no chance to clean up),
//! the kernel has released the lock and a new run into `OUT` succeeds.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

#[test]
fn a_second_run_into_a_held_directory_is_refused_and_a_killed_holder_leaves_no_lock() {
    let bin = env!("CARGO_BIN_EXE_signorini");
    let out = std::env::temp_dir().join(format!("signorini-lock-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    // ~10⁷ steps: runs for minutes unless killed
    let mut first = Command::new(bin)
        .args([
            "bar",
            "--quiet",
            "--no-fields",
            "--no-plots",
            "--history-every",
            "100000",
            "--t-end",
            "2",
        ])
        .arg("--out")
        .arg(&out)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let lock = out.join(".signorini.lock");
    let history = out.join("history.csv.part");
    let t0 = Instant::now();
    // the lock names its holder once taken; the history streams into history.csv.part
    while !(std::fs::read_to_string(&lock).is_ok_and(|s| s.trim() == first.id().to_string())
        && history.exists())
    {
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "the first run never started"
        );
        assert!(
            first.try_wait().unwrap().is_none(),
            "the first run ended early"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    let second = Command::new(bin)
        .args(["bar", "--quiet", "--no-fields", "--no-plots"])
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let msg = String::from_utf8_lossy(&second.stderr);
    assert_eq!(second.status.code(), Some(2), "{msg}");
    assert!(
        msg.contains("another signorini run") && msg.contains(&first.id().to_string()),
        "{msg}"
    );
    // the refused run removed nothing of the first's
    assert!(
        history.exists(),
        "the refused run removed the holder's history"
    );
    assert!(
        first.try_wait().unwrap().is_none(),
        "the holder was disturbed"
    );
    first.kill().unwrap();
    first.wait().unwrap();
    let third = Command::new(bin)
        .args([
            "bar",
            "--quiet",
            "--no-fields",
            "--no-plots",
            "--t-end",
            "1e-4",
        ])
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        third.status.success(),
        "{}",
        String::from_utf8_lossy(&third.stderr)
    );
    assert!(Path::new(&out.join("summary.json")).exists());
    let _ = std::fs::remove_dir_all(&out);
}

/// The study_sweep flake of this session (issue 36's test run, under load): a sweep's
/// directory was refused as held by "another signorini run" whose process was the test
/// itself. A lock this process holds (here: a run's lock still alive, as a child process
/// between its fork and its exec would keep it) is waited for, then refused by a message
/// that says so, without the 26 stray blanks the message had (issue 37 §10); a lock
/// released during the wait is taken.
#[test]
fn a_lock_held_by_this_process_is_waited_for_and_named_as_ours() {
    use signorini::io::RunLock;
    let out = std::env::temp_dir().join(format!("signorini-selflock-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let held = RunLock::acquire(&out).unwrap();
    let t = Instant::now();
    let msg = RunLock::acquire(&out).unwrap_err().to_string();
    // the wait is `SELF_HELD_RETRY` (2 s); at least one second of it passed
    assert!(t.elapsed() >= Duration::from_secs(1), "{:?}", t.elapsed());
    assert!(
        msg.contains("another run in this process")
            && msg.contains(&std::process::id().to_string())
            && !msg.contains("  "),
        "{msg}"
    );
    // released while the second caller waits: it gets the lock
    let releaser = std::thread::spawn(move || {
        std::thread::sleep(Duration::from_millis(200));
        drop(held);
    });
    let again = RunLock::acquire(&out);
    releaser.join().unwrap();
    assert!(again.is_ok(), "{:?}", again.err());
    drop(again);
    let _ = std::fs::remove_dir_all(&out);
}
