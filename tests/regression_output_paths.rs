//! Issue 16 §5: write only regular files, remove only what this program wrote.
//!
//! Before: as root, `signorini fclib … --solution /dev/full` renamed its output over the
//! device node; a run removed every `*.part` file of its directory, a user's included;
//! an `--out` that named a file failed with a bare `File exists (os error 17)`.

use std::path::{Path, PathBuf};
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_signorini"))
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("signorini-outp-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn refused(o: std::process::Output, words: &[&str]) {
    let e = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(o.status.code(), Some(2), "{e}");
    for w in words {
        assert!(e.contains(w), "`{w}` not in: {e}");
    }
}

fn problem() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fclib/FrictionContact3D_RR_1c.dat")
}

fn fclib_to(solution: &Path) -> std::process::Output {
    bin()
        .arg("fclib")
        .arg(problem())
        .arg("--solution")
        .arg(solution)
        .output()
        .unwrap()
}

#[cfg(unix)]
#[test]
fn solutions_are_written_only_as_regular_files() {
    use std::os::unix::fs::FileTypeExt as _;
    let d = tmp("solution");
    // a device: refused, and still a device afterwards
    refused(
        fclib_to(Path::new("/dev/null")),
        &["--solution", "/dev/null", "a device"],
    );
    let md = std::fs::metadata("/dev/null").unwrap();
    assert!(md.file_type().is_char_device());
    // a FIFO
    let fifo = d.join("fifo");
    assert!(
        Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    refused(fclib_to(&fifo), &["a FIFO"]);
    // a symbolic link (to a regular file, which stays as it was)
    let target = d.join("target.json");
    std::fs::write(&target, "keep").unwrap();
    let link = d.join("link.json");
    std::os::unix::fs::symlink(&target, &link).unwrap();
    refused(fclib_to(&link), &["a symbolic link"]);
    assert_eq!(std::fs::read_to_string(&target).unwrap(), "keep");
    // a directory, and the problem file itself
    refused(fclib_to(&d), &["a directory"]);
    refused(fclib_to(&problem()), &["is the input"]);
    // a regular file is replaced, as before
    let ok = d.join("solution.json");
    std::fs::write(&ok, "old").unwrap();
    let o = fclib_to(&ok);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(std::fs::read_to_string(&ok).unwrap().contains("residual"));
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn an_out_that_is_not_a_directory_is_refused_and_a_users_part_files_stay() {
    let d = tmp("out");
    let file = d.join("a-file");
    std::fs::write(&file, "mine").unwrap();
    let bar = |out: &Path| {
        bin()
            .args([
                "bar",
                "--quiet",
                "--no-fields",
                "--no-plots",
                "--t-end",
                "1e-5",
            ])
            .arg("--out")
            .arg(out)
            .output()
            .unwrap()
    };
    refused(bar(&file), &["--out", "a regular file, not a directory"]);
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "mine");
    // a directory with an older run's leftovers and a user's own .part file
    let out = d.join("run");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("history.csv.part"), "step,time\n1,0.1").unwrap();
    std::fs::write(out.join("download.part"), "mine").unwrap();
    let o = bar(&out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(!out.join("history.csv.part").exists());
    assert!(out.join("history.csv").exists());
    assert_eq!(
        std::fs::read_to_string(out.join("download.part")).unwrap(),
        "mine"
    );
    let _ = std::fs::remove_dir_all(&d);
}
