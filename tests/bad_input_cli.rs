//! Bad command-line input: a clear error naming the flag and value, exit code 2, no
//! panic, no output files.

use std::process::Command;

fn signorini(args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_signorini"))
        .args(args)
        .output()
        .expect("binary runs");
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(!stderr.contains("panicked"), "panic: {stderr}");
    (out.status.code().unwrap_or(-1), stderr)
}

#[test]
fn invalid_numbers_name_the_field_and_value() {
    let dir = std::env::temp_dir().join("signorini-bad-input");
    let out = dir.to_str().unwrap();
    let cases: &[(&[&str], &[&str])] = &[
        (&["--dt", "-1e-7"], &["dt", "-1e-7"]),
        (&["--dt", "0"], &["dt", "0"]),
        (&["--young", "nan"], &["young", "NaN"]),
        (&["--density", "-7800"], &["density", "-7800"]),
        (&["--area", "inf"], &["area", "inf"]),
        (&["--elements", "0"], &["elements", "0"]),
        (&["--theta", "0.3"], &["theta", "0.3"]),
        (&["--gamma", "3", "--forecast", "explicit"], &["gamma", "3"]),
        (&["--restitution", "1.5"], &["restitution", "1.5"]),
        (&["--gap", "-0.1"], &["gap", "-0.1"]),
        (&["--t-end", "1e-9"], &["t-end"]),
        (&["--velocity", "nan"], &["velocity", "NaN"]),
    ];
    for (args, needles) in cases {
        let mut a = args.to_vec();
        a.extend(["--out", out, "--quiet"]);
        let (code, err) = signorini(&a);
        assert_eq!(code, 2, "{args:?}: exit {code}, {err}");
        for n in *needles {
            assert!(err.contains(n), "{args:?}: message lacks {n:?}: {err}");
        }
        assert!(
            !dir.join("summary.json").exists(),
            "{args:?} left a summary behind"
        );
    }
}

#[test]
fn unknown_names_are_rejected_by_the_parser() {
    for args in [
        &["--scheme", "newmark"][..],
        &["--metric", "l2"][..],
        &["--mass", "heavy"][..],
        &["--no-such-flag"][..],
        &["bar", "--elements", "ten"][..],
    ] {
        let (code, err) = signorini(args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains("error"), "{err}");
    }
}

#[test]
fn unknown_study_and_missing_run_dir_are_named() {
    let (code, err) = signorini(&["study", "bogus", "--out", "/tmp/signorini-bad-study"]);
    assert_eq!(code, 2);
    assert!(
        err.contains("study") && err.contains("bogus") && err.contains("convergence"),
        "{err}"
    );
    let (code, err) = signorini(&["plot", "/nonexistent/signorini-run"]);
    assert_eq!(code, 2);
    assert!(
        err.contains("/nonexistent/signorini-run/history.csv"),
        "{err}"
    );
}

/// Issue 16 §6: `signorini example NAME` spliced NAME into TOML, so
/// `bouncing-ball"⏎restitution = 0.9⏎#` ran the ball with e = 0.9, exit 0. The name is
/// now a value: that name is unknown (exit 2), and the real names still run.
#[test]
fn example_names_are_values_not_toml() {
    let out = std::env::temp_dir().join(format!("signorini-exname-{}", std::process::id()));
    let run = |name: &str| {
        std::process::Command::new(env!("CARGO_BIN_EXE_signorini"))
            .args(["example", name, "--quiet", "--out"])
            .arg(&out)
            .output()
            .unwrap()
    };
    let o = run("bouncing-ball\"\nrestitution = 0.9\n#");
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("unknown example"), "{e}");
    let o = run("bouncing-ball");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let _ = std::fs::remove_dir_all(&out);
}

/// `--help` is read by users, not rustdoc: no intra-doc link (`` [`…`] ``) of a doc
/// comment may leak into it (the solver and Delassus choices printed
/// `[`super::newton::STEP_NEWTON_ROWS`]`), and the figures written out in their place
/// are the constants'.
#[test]
fn help_texts_carry_no_rustdoc_links() {
    let mut all = String::new();
    for cmd in [
        "bar", "run", "check", "example", "study", "resume", "plot", "fclib",
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_signorini"))
            .args([cmd, "--help"])
            .output()
            .expect("binary runs");
        assert_eq!(out.status.code(), Some(0), "{cmd} --help");
        let text = String::from_utf8_lossy(&out.stdout).to_string();
        assert!(
            !text.contains("[`"),
            "{cmd} --help shows a rustdoc link:\n{text}"
        );
        all.push_str(&text);
    }
    let rows = signorini::solvers::newton::STEP_NEWTON_ROWS;
    assert!(all.contains(&format!("up to {rows} contact rows")), "{all}");
    let dense = signorini::delassus::AUTO_DENSE_MAX_CONTACTS;
    assert!(all.contains(&format!("are at most {dense})")), "{all}");
}

#[cfg(not(feature = "mumps"))]
#[test]
fn mumps_without_its_feature_names_the_feature() {
    let (code, err) = signorini(&["--mumps", "--quiet", "--t-end", "1e-6"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("--mumps") && err.contains("--features mumps"),
        "{err}"
    );
}

/// Issue 34: a global flag before the subcommand (`signorini --mumps run SCENE`) was
/// refused by the parser as "the subcommand 'run' cannot be used with '--mumps'"; it
/// now reaches the command, which names what is missing in this build (the `mumps`
/// feature), as `signorini run SCENE --mumps` does.
#[cfg(not(feature = "mumps"))]
#[test]
fn a_global_flag_before_the_subcommand_reaches_it() {
    let root = env!("CARGO_MANIFEST_DIR");
    for args in [
        &["--mumps", "check", "meshes/bar.toml"][..],
        &["check", "meshes/bar.toml", "--mumps"][..],
    ] {
        let o = Command::new(env!("CARGO_BIN_EXE_signorini"))
            .current_dir(root)
            .args(args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains("--mumps") && err.contains("without the `mumps` cargo feature"),
            "{args:?}: {err}"
        );
    }
    // and --portable-arithmetic before `check` is taken as the flag it is
    let o = Command::new(env!("CARGO_BIN_EXE_signorini"))
        .current_dir(root)
        .args(["--portable-arithmetic", "check", "meshes/bar.toml"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// Issue 48: a negative count (`--jobs -1`, `--max-iter -1`, …) was read as an unknown
/// flag `-1` ("unexpected argument '-1'"); it is now the flag's value, refused (exit 2)
/// naming the flag, the value and what a count is.
#[test]
fn negative_counts_name_the_flag_and_value() {
    for (args, flag, want) in [
        (
            &["sweep", "bar", "--jobs", "-1"][..],
            "--jobs",
            "positive integer",
        ),
        (
            &["fclib", "p.dat", "--max-iter", "-1"][..],
            "--max-iter",
            "positive integer",
        ),
        (
            &["fclib", "p.dat", "--repeat", "2.5"][..],
            "--repeat",
            "positive integer",
        ),
        (
            &["bar", "--elements", "-3"][..],
            "--elements",
            "whole number",
        ),
        (
            &["bar", "--newton-max-iterations", "-1"][..],
            "--newton-max-iterations",
            "positive integer",
        ),
        (
            &["bar", "--checkpoint-every", "-10"][..],
            "--checkpoint-every",
            "whole number",
        ),
    ] {
        let (code, err) = signorini(args);
        assert_eq!(code, 2, "{args:?}: {err}");
        let value = args[args.len() - 1];
        assert!(
            err.contains(flag) && err.contains(&format!("'{value}'")) && err.contains(want),
            "{args:?}: {err}"
        );
        assert!(!err.contains("unexpected argument"), "{args:?}: {err}");
    }
}

/// Issue 48: `signorini study NAME` with an unknown NAME created its `--out` (or
/// `out/study-NAME`) before refusing the name; nothing is created now.
#[test]
fn an_unknown_study_creates_nothing() {
    let dir = std::env::temp_dir().join(format!("signorini-study48-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for args in [
        &["study", "bogus", "--out", "made"][..],
        &["study", "bogus"][..],
        &["study", "bogus", "scene.toml"][..],
    ] {
        let o = Command::new(env!("CARGO_BIN_EXE_signorini"))
            .current_dir(&dir)
            .args(args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains("bogus") && err.contains("unknown study"),
            "{err}"
        );
        let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
        assert!(left.is_empty(), "{args:?} created {left:?}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 48: a plot that cannot be written was reported with the drawing backend's
/// Rust debug text (`ImageError(IoError(Os { code: 21, … }))`); now the path and the
/// operating system's reason.
#[test]
fn an_unwritable_plot_is_named_plainly() {
    let dir = std::env::temp_dir().join(format!("signorini-plot48-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let o = Command::new(env!("CARGO_BIN_EXE_signorini"))
        .args([
            "bar",
            "--elements",
            "50",
            "--dt",
            "2e-6",
            "--t-end",
            "1e-4",
            "--quiet",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for stem in ["energy.png", "energy.svg"] {
        let p = dir.join(stem);
        let _ = std::fs::remove_file(&p);
        std::fs::create_dir(&p).unwrap();
        let (code, err) = signorini(&["plot", dir.to_str().unwrap()]);
        assert_eq!(code, 1, "{err}");
        assert!(
            err.contains(&format!("cannot write {}", p.display())),
            "{err}"
        );
        assert!(err.contains("directory"), "{err}");
        for debug in ["Os {", "IoError", "ImageError", "kind:", "backend error"] {
            assert!(!err.contains(debug), "debug text {debug:?}: {err}");
        }
        std::fs::remove_dir(&p).unwrap();
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 48: a sweep point that only its build refuses (a node set on an axis) stopped
/// the sweep after the points before it had run; every point is built first.
#[test]
fn every_sweep_point_is_checked_before_the_first_runs() {
    let root = env!("CARGO_MANIFEST_DIR");
    let dir = std::env::temp_dir().join(format!("signorini-sweep48-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let o = Command::new(env!("CARGO_BIN_EXE_signorini"))
        .current_dir(root)
        .args([
            "sweep",
            "meshes/bar.toml",
            "--set",
            "time.t_end=1e-4",
            "--axis",
            "contacts[0].nodes=[\"x1\", \"nope\"]",
            "--quiet",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("contacts[0].nodes") && err.contains("nope") && err.contains("sweep point 1"),
        "{err}"
    );
    assert!(
        !dir.exists(),
        "the sweep ran before refusing: {}",
        dir.display()
    );
}

/// Issue 48: the inputs were read under the flush of subnormals, so a W entry of
/// 1e-320 was refused as "is 0e0, expected > 0". It is read as written now: refused as
/// subnormal (which the solve would flush to 0) naming the remedy, and taken with
/// `--ieee-subnormals`.
#[test]
fn a_subnormal_input_is_named_as_written() {
    let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/fclib/FrictionContact3D_1c.dat");
    let text = std::fs::read_to_string(src).unwrap();
    let mut lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[10], "15", "W[0,0] of the 1-contact problem");
    lines[10] = "1e-320";
    let dir = std::env::temp_dir().join(format!("signorini-sub48-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("w.dat");
    std::fs::write(&file, lines.join("\n") + "\n").unwrap();
    let (code, err) = signorini(&["fclib", file.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("W_NN = W[0,0] is 1e-320")
            && err.contains("subnormal")
            && err.contains("--ieee-subnormals"),
        "{err}"
    );
    let (code, err) = signorini(&["fclib", file.to_str().unwrap(), "--ieee-subnormals"]);
    assert_ne!(code, 2, "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
