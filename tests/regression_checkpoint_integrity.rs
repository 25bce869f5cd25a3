//! Issue 16 §4: a checkpoint cannot splice two runs. `signorini resume` refuses, with
//! exit code 2 and a message naming the file and what differs: an edited scene, a moved
//! mesh node, a checkpoint copied into another directory, one written by another build,
//! `every = 0`, arrays that disagree, a history cursor inside a row. Each case starts
//! from a real checkpoint of a killed run and changes one thing; the untouched copy
//! resumes (exit 0), so each refusal is due to the change alone.

mod common;

use common::scratch::Scratch;
use std::path::{Path, PathBuf};
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_signorini"))
}

fn tmp(name: &str) -> Scratch {
    Scratch::new("ckint", name)
}

/// A ball-drop run (scene and mesh copied into `work`) killed after step 30 of its
/// checkpointed run into `work/out`; returns the scene and mesh paths.
fn killed_scene_run(work: &Path) -> (PathBuf, PathBuf) {
    std::fs::create_dir_all(work).unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes");
    let scene = work.join("ball_drop.toml");
    let mesh = work.join("ball.msh");
    let text = std::fs::read_to_string(root.join("ball_drop.toml")).unwrap();
    std::fs::write(&scene, text).unwrap();
    std::fs::copy(root.join("ball.msh"), &mesh).unwrap();
    let o = bin()
        .args([
            "run",
            scene.to_str().unwrap(),
            "--quiet",
            "--no-plots",
            "--no-fields",
        ])
        .args([
            "--checkpoint-every",
            "10",
            "--out",
            work.join("out").to_str().unwrap(),
        ])
        .env("SIGNORINI_ABORT_AFTER_STEP", "30")
        .output()
        .unwrap();
    assert!(!o.status.success(), "the run was not killed");
    assert!(work.join("out/checkpoint.json").exists());
    (scene, mesh)
}

fn resume(dir: &Path) -> std::process::Output {
    bin()
        .args(["resume", dir.to_str().unwrap(), "--quiet"])
        .output()
        .unwrap()
}

fn refused(dir: &Path, words: &[&str]) {
    let o = resume(dir);
    let e = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(o.status.code(), Some(2), "{e}");
    for w in words {
        assert!(e.contains(w), "`{w}` not in: {e}");
    }
}

fn copy_dir(a: &Path, b: &Path) {
    std::fs::create_dir_all(b).unwrap();
    for e in std::fs::read_dir(a).unwrap() {
        let e = e.unwrap();
        if e.file_type().unwrap().is_file() {
            std::fs::copy(e.path(), b.join(e.file_name())).unwrap();
        }
    }
}

fn edit_checkpoint(dir: &Path, f: impl FnOnce(&mut serde_json::Value)) {
    let p = dir.join("checkpoint.json");
    let mut c: serde_json::Value = serde_json::from_slice(&std::fs::read(&p).unwrap()).unwrap();
    f(&mut c);
    std::fs::write(&p, serde_json::to_vec(&c).unwrap()).unwrap();
}

#[test]
fn edited_inputs_are_refused_and_restored_inputs_resume() {
    let work = tmp("inputs");
    let (scene, mesh) = killed_scene_run(&work);
    let out = work.join("out");
    let keep = std::fs::read(out.join("checkpoint.json")).unwrap();
    // an edited scene file (one more comment line)
    let text = std::fs::read_to_string(&scene).unwrap();
    std::fs::write(&scene, format!("# edited\n{text}")).unwrap();
    refused(
        &out,
        &["checkpoint.json", "`inputs`", "ball_drop.toml changed"],
    );
    std::fs::write(&scene, &text).unwrap();
    // a moved node: one digit of the mesh file changed
    let m = std::fs::read(&mesh).unwrap();
    let at = m.windows(2).position(|w| w == b"0.").expect("a coordinate") + 2;
    let mut moved = m.clone();
    moved[at] = if moved[at] == b'1' { b'2' } else { b'1' };
    std::fs::write(&mesh, &moved).unwrap();
    refused(&out, &["ball.msh changed", "SHA-256"]);
    std::fs::write(&mesh, &m).unwrap();
    // a removed mesh file
    std::fs::remove_file(&mesh).unwrap();
    refused(&out, &["ball.msh is gone"]);
    std::fs::write(&mesh, &m).unwrap();
    // restored: the refusals changed nothing, and the run finishes
    assert_eq!(std::fs::read(out.join("checkpoint.json")).unwrap(), keep);
    let o = resume(&out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let _ = std::fs::remove_dir_all(&work);
}

/// One change to a checkpoint's JSON.
type Edit = Box<dyn Fn(&mut serde_json::Value)>;

#[test]
fn foreign_and_inconsistent_checkpoints_are_refused() {
    let work = tmp("foreign");
    killed_scene_run(&work);
    let out = work.join("out");
    // copied beside another run's history (a splice of two runs): refused
    let other = work.join("other");
    copy_dir(&out, &other);
    let part = other.join("history.csv.part");
    // another run's rows: one digit of the first row changed
    let mut h = std::fs::read(&part).unwrap();
    let row = h.iter().position(|&b| b == b'\n').unwrap() + 1;
    let at = row + h[row..].iter().position(u8::is_ascii_digit).unwrap();
    h[at] = if h[at] == b'1' { b'2' } else { b'1' };
    std::fs::write(&part, &h).unwrap();
    refused(
        &other,
        &[
            "history.csv.part",
            "are not the history the checkpoint continues",
            "SHA-256",
        ],
    );
    // each change on a fresh copy of the original directory
    let cases: Vec<(&str, Edit, Vec<&str>)> = vec![
        (
            "build",
            Box::new(|c| c["build"] = "signorini 0.0.0 (elsewhere)".into()),
            vec!["`build`", "signorini 0.0.0 (elsewhere)"],
        ),
        (
            "every",
            Box::new(|c| c["every"] = 0.into()),
            vec!["`every`", "0"],
        ),
        (
            "arrays",
            Box::new(|c| {
                c["run"]["contact_min_gap"] = "AAAAAAAAAAA=".into();
                c["run"]["contact_force"] = "".into();
            }),
            vec!["`run.contact_min_gap`", "go together"],
        ),
        (
            "cursor",
            Box::new(|c| {
                let b = c["run"]["history_bytes"].as_u64().unwrap();
                c["run"]["history_bytes"] = (b - 3).into();
            }),
            // an edited checkpoint: its digest refuses it before the history's cursor
            // check runs (which still guards a history damaged beside an intact
            // checkpoint)
            vec!["`digest`", "edited or damaged"],
        ),
        (
            "rows",
            Box::new(|c| {
                let r = c["run"]["history_rows"].as_u64().unwrap();
                c["run"]["history_rows"] = (r - 1).into();
            }),
            vec!["`digest`", "edited or damaged"],
        ),
        // issue 34: edits that every field check lets through, refused by the digest
        (
            "nan-time",
            Box::new(|c| c["integrator"]["time"] = "7ff8000000000000".into()),
            vec!["`digest`", "edited or damaged"],
        ),
        (
            "step",
            Box::new(|c| {
                let k = c["integrator"]["step"].as_u64().unwrap();
                c["integrator"]["step"] = (k + 1).into();
            }),
            vec!["`digest`", "edited or damaged"],
        ),
        (
            "digest",
            Box::new(|c| c["digest"] = "0".repeat(64).into()),
            vec!["`digest`"],
        ),
    ];
    for (name, edit, words) in cases {
        let dir = work.join(format!("case-{name}"));
        // the checkpoint names its own directory: rewrite it for the copy
        copy_dir(&out, &dir);
        let canon = std::fs::canonicalize(&dir).unwrap();
        edit_checkpoint(&dir, |c| {
            c["out_dir"] = canon.to_str().unwrap().into();
            edit(c);
        });
        refused(&dir, &words);
    }
    // an intact checkpoint beside a damaged history: two rows joined into one
    let dir = work.join("case-history");
    copy_dir(&out, &dir);
    let canon = std::fs::canonicalize(&dir).unwrap();
    edit_checkpoint(&dir, |c| c["out_dir"] = canon.to_str().unwrap().into());
    let part = dir.join("history.csv.part");
    let mut h = std::fs::read(&part).unwrap();
    let nl = h.iter().position(|&b| b == b'\n').unwrap();
    h[nl] = b',';
    std::fs::write(&part, &h).unwrap();
    refused(
        &dir,
        &[
            "history.csv.part",
            "are not the history the checkpoint continues",
        ],
    );
    // the unchanged copy (directory rewritten only) resumes
    let dir = work.join("case-none");
    copy_dir(&out, &dir);
    let canon = std::fs::canonicalize(&dir).unwrap();
    edit_checkpoint(&dir, |c| c["out_dir"] = canon.to_str().unwrap().into());
    let o = resume(&dir);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let _ = std::fs::remove_dir_all(&work);
}

/// Issue 16 §4: a checkpoint does not grow with the run. Each checkpoint held the whole
/// per-step force trace so far (about 20 bytes a step), so a run's checkpoints wrote
/// bytes quadratic in its length. The bar of 20 000 steps (its contact interval, which
/// the summary measures, ends after 2L/c0), with its field frames, checkpointed at step
/// 1 000 and at step 19 000: the two files may differ only by the digits of their
/// numbers (tolerance 1 %; with the trace: 17 517 bytes at step 1 000, 209 523 at step
/// 19 000, without frames; the frames' times, one per frame, are now read back from the
/// `.pvd` on resume).
#[test]
fn checkpoint_size_does_not_grow_with_the_run() {
    let size = |at: usize| {
        let dir = tmp(&format!("size-{at}"));
        let o = bin()
            .args(["bar", "--elements", "50", "--dt", "2e-6", "--t-end", "4e-2"])
            .args([
                "--checkpoint-every",
                "1000",
                "--quiet",
                "--no-plots",
                "--no-fields",
            ])
            .arg("--out")
            .arg(&dir)
            .env("SIGNORINI_ABORT_AFTER_STEP", (at + 1).to_string())
            .output()
            .unwrap();
        assert!(!o.status.success(), "the abort hook did not stop the run");
        std::fs::metadata(dir.join("checkpoint.json"))
            .unwrap()
            .len() as f64
    };
    let (early, late) = (size(1000), size(19_000));
    assert!(
        (late - early).abs() <= 0.01 * early,
        "checkpoints of one run: {early} bytes at step 1 000, {late} at step 19 000"
    );
}

/// Issue 48: a run directory moved whole (`mv out out2`) was refused ("the checkpoint
/// belongs to the run in …/out") though nothing was spliced: the checkpoint named its
/// directory by path. It is tied to its history's content now, so the moved directory
/// resumes and finishes; the checkpoint is removed and the summary written.
#[test]
fn a_run_directory_moved_whole_resumes() {
    let work = tmp("moved");
    killed_scene_run(&work);
    let moved = work.join("moved-elsewhere");
    std::fs::rename(work.join("out"), &moved).unwrap();
    let o = resume(&moved);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(moved.join("summary.json").exists());
    assert!(!moved.join("checkpoint.json").exists());
    let _ = std::fs::remove_dir_all(&work);
}
