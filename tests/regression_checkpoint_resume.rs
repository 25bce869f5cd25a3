//! Issue 12 §5: a run killed at any point and finished by `signorini resume DIR` leaves
//! the directory an uninterrupted run leaves: `history.csv` and every frame byte for
//! byte, the same `.pvd`, the same physics in `summary.json` (timings aside). Kills are
//! simulated deterministically with the `SIGNORINI_ABORT_AFTER_STEP` hook (the process
//! aborts, as under SIGKILL: no destructor, no flush beyond what was written), at
//! several points, for every scheme, with and without friction, on a curved obstacle;
//! one test sends a real SIGKILL. Old and corrupt checkpoints get clear errors. With the
//! `hdf5` feature every dataset of `fields.vtkhdf` is compared too.

mod common;

use common::scratch::Scratch;
use std::path::{Path, PathBuf};
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_signorini"))
}

fn tmp(name: &str) -> Scratch {
    Scratch::new("ckpt", name)
}

/// Runs the CLI with `args` (the out dir appended), optionally aborting after a step.
fn run(args: &[&str], out: &Path, abort_after: Option<usize>) -> std::process::Output {
    let mut c = bin();
    c.args(args)
        .args(["--out", out.to_str().unwrap(), "--quiet", "--no-plots"]);
    if let Some(k) = abort_after {
        c.env("SIGNORINI_ABORT_AFTER_STEP", k.to_string());
    }
    c.output().expect("binary runs")
}

fn resume(dir: &Path) -> std::process::Output {
    bin()
        .args(["resume", dir.to_str().unwrap(), "--quiet"])
        .output()
        .expect("binary runs")
}

/// The uninterrupted and the resumed directories hold the same results.
fn assert_same_run(a: &Path, b: &Path) {
    let read = |d: &Path, f: &str| std::fs::read(d.join(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
    assert!(
        read(a, "history.csv") == read(b, "history.csv"),
        "history.csv differs ({} vs {})",
        a.display(),
        b.display()
    );
    if a.join("fields.pvd").exists() {
        assert_eq!(read(a, "fields.pvd"), read(b, "fields.pvd"), "fields.pvd");
        let names = |d: &Path| {
            let mut v: Vec<_> = std::fs::read_dir(d.join("fields"))
                .unwrap()
                .map(|e| e.unwrap().file_name())
                .collect();
            v.sort();
            v
        };
        let (na, nb) = (names(a), names(b));
        assert_eq!(na, nb, "frame files");
        for n in na {
            let f = Path::new("fields").join(&n);
            assert!(
                read(a, f.to_str().unwrap()) == read(b, f.to_str().unwrap()),
                "{} differs",
                f.display()
            );
        }
    }
    let summary = |d: &Path| -> serde_json::Value {
        serde_json::from_slice(&read(d, "summary.json")).unwrap()
    };
    let (mut sa, mut sb) = (summary(a), summary(b));
    for s in [&mut sa, &mut sb] {
        let o = s.as_object_mut().unwrap();
        for k in [
            "wall_seconds",
            "seconds_per_step",
            "output_seconds",
            "frame_seconds",
            "frame_wait_seconds",
            "model_seconds",
            "integrator_seconds",
            // a measurement of the process, like the times
            "peak_memory_bytes",
        ] {
            o.remove(k);
        }
        // the accuracy mode's comparison steps factor each step size once per process
        // (a resumed run starts with an empty cache), like the timings a measure of the
        // session, not of the run
        if let Some(a) = o.get_mut("accuracy").and_then(|n| n.as_object_mut()) {
            a.remove("trial_factorizations");
        }
        if let Some(n) = o.get_mut("nonlinear").and_then(|n| n.as_object_mut()) {
            n.remove("assembly_seconds");
            n.remove("factorization_seconds");
        }
    }
    assert_eq!(sa, sb, "summary.json physics");
    #[cfg(feature = "hdf5")]
    assert_same_hdf5(&a.join("fields.vtkhdf"), &b.join("fields.vtkhdf"));
    assert!(
        !b.join("checkpoint.json").exists(),
        "a finished run removes its checkpoint"
    );
    assert!(!b.join("history.csv.part").exists(), "no .part left");
}

/// Every dataset of the two HDF5 files (`/VTKHDF`, `/history`) holds the same values
/// (the files' layouts may differ: the resumed run cut its datasets and appended).
#[cfg(feature = "hdf5")]
fn assert_same_hdf5(a: &Path, b: &Path) {
    fn walk(ga: &hdf5::Group, gb: &hdf5::Group, path: &str, n: &mut usize) {
        let mut names = ga.member_names().unwrap();
        names.sort();
        let mut other = gb.member_names().unwrap();
        other.sort();
        assert_eq!(names, other, "{path}: members");
        for name in names {
            let p = format!("{path}/{name}");
            if let Ok(g) = ga.group(&name) {
                walk(&g, &gb.group(&name).unwrap(), &p, n);
                continue;
            }
            let (da, db) = (ga.dataset(&name).unwrap(), gb.dataset(&name).unwrap());
            assert_eq!(da.shape(), db.shape(), "{p}: shape");
            let same = match (da.read_raw::<f64>(), db.read_raw::<f64>()) {
                (Ok(x), Ok(y)) => x
                    .iter()
                    .map(|v| v.to_bits())
                    .eq(y.iter().map(|v| v.to_bits())),
                _ => da.read_raw::<i64>().unwrap() == db.read_raw::<i64>().unwrap(),
            };
            assert!(same, "{p} differs");
            *n += 1;
        }
    }
    let (fa, fb) = (hdf5::File::open(a).unwrap(), hdf5::File::open(b).unwrap());
    let mut n = 0;
    walk(&fa, &fb, "", &mut n);
    assert!(n > 20, "{n} datasets compared");
    let steps = |f: &hdf5::File| -> i64 {
        f.group("VTKHDF/Steps")
            .unwrap()
            .attr("NSteps")
            .unwrap()
            .read_scalar()
            .unwrap()
    };
    assert_eq!(steps(&fa), steps(&fb), "NSteps");
}

/// The `.pvd` of a killed run (issue 19 §3: it is no longer rewritten after every
/// frame, only after the first, at checkpoints, every few seconds and at the end) is a
/// whole collection document that lists at least the frames of the last checkpoint,
/// each of them a complete `.vtu` on disk.
fn assert_killed_collection_readable(dir: &Path) {
    let pvd = dir.join("fields.pvd");
    if !pvd.exists() {
        return;
    }
    let text = std::fs::read_to_string(&pvd).unwrap();
    assert!(
        text.starts_with("<?xml") && text.trim_end().ends_with("</VTKFile>"),
        "{}: not a whole document:\n{text}",
        pvd.display()
    );
    let files: Vec<&str> = text
        .lines()
        .filter_map(|l| l.split("file=\"").nth(1))
        .map(|r| r.split('"').next().unwrap())
        .collect();
    let ckpt: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("checkpoint.json")).unwrap())
            .unwrap();
    let frames = ckpt["run"]["frames"].as_u64().unwrap() as usize;
    assert!(
        files.len() >= frames,
        "{} lists {} frames, the checkpoint {frames}",
        pvd.display(),
        files.len()
    );
    for f in files {
        let vtu = std::fs::read_to_string(dir.join(f)).unwrap();
        assert!(
            vtu.trim_end().ends_with("</VTKFile>"),
            "{f} is not complete"
        );
    }
}

/// Kills `args` after each of `kills` steps, resumes, and compares with one
/// uninterrupted run.
fn check_resume(name: &str, args: &[&str], kills: &[usize]) -> serde_json::Value {
    let whole = tmp(&format!("{name}-whole"));
    let o = run(args, &whole, None);
    assert!(
        o.status.success(),
        "{name}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    for &k in kills {
        let dir = tmp(&format!("{name}-kill{k}"));
        let o = run(args, &dir, Some(k));
        assert!(
            !o.status.success(),
            "{name}: the abort hook did not stop the run at step {k}"
        );
        assert!(
            dir.join("checkpoint.json").exists(),
            "{name}: no checkpoint by step {k}"
        );
        assert_killed_collection_readable(&dir);
        let o = resume(&dir);
        assert!(
            o.status.success(),
            "{name} killed after {k}: resume failed: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert_same_run(&whole, &dir);
    }
    serde_json::from_slice(&std::fs::read(whole.join("summary.json")).unwrap()).unwrap()
}

#[test]
fn every_scheme_resumes_to_the_uninterrupted_bar() {
    for scheme in [
        "moreau-jean",
        "schatzman-paoli",
        "trapezoid-position",
        "direct-projection",
        "combined-projection",
    ] {
        // 500 steps, the contact from step 0 to about 190: kills before, during and
        // after it, right at a checkpoint (200) and between two (317, mid-stride)
        let args = [
            "bar",
            "--elements",
            "100",
            "--dt",
            "2e-6",
            "--t-end",
            "1e-3",
            "--scheme",
            scheme,
            "--checkpoint-every",
            "50",
        ];
        check_resume(scheme, &args, &[60, 200, 317, 499]);
    }
}

/// Issue 50: an accuracy run killed mid-ladder (its step varying between 1e-5 s and
/// 1e-5/2¹⁰ s) resumes to the uninterrupted run byte for byte: the checkpoint is written
/// between windows with the controller's state, the integrator's step and clock.
#[test]
fn accuracy_runs_resume_mid_ladder() {
    let args = [
        "bar",
        "--elements",
        "100",
        "--dt",
        "1e-5",
        "--accuracy",
        "1e-2",
        "--checkpoint-every",
        "40",
    ];
    let s = check_resume("accuracy", &args, &[45, 130, 333]);
    let a = &s["accuracy"];
    assert_eq!(a["met"], true, "{a}");
    assert!(
        a["dt_max_used"].as_f64().unwrap() >= 4.0 * a["dt_min_used"].as_f64().unwrap(),
        "the step varied: {a}"
    );
    assert!(s["steps"].as_u64().unwrap() > 333, "{s}");
}

/// The subnormal mode is part of the run (issue 35): a run started with
/// `--ieee-subnormals` and killed is resumed, without the flag, in IEEE arithmetic (its
/// summary, compared whole with the uninterrupted run's, says `ieee`), and the default
/// run's checkpoint records `flushed`.
#[test]
fn the_subnormal_mode_is_resumed_with_the_run() {
    let args = [
        "--ieee-subnormals",
        "bar",
        "--elements",
        "100",
        "--dt",
        "2e-6",
        "--t-end",
        "4e-4",
        "--checkpoint-every",
        "50",
    ];
    let s = check_resume("ieee", &args, &[120]);
    assert_eq!(s["subnormals"], "ieee");
    let dir = tmp("flushed-kill");
    let o = run(&args[1..], &dir, Some(120));
    assert!(!o.status.success());
    let c: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("checkpoint.json")).unwrap()).unwrap();
    assert_eq!(c["subnormals"], "flushed");
}

/// A scene copy with a shorter `t_end` (its probes' times moved within it), its mesh
/// paths kept: its directory (removed when dropped) and the scene file.
fn short_scene(name: &str, t_end: f64) -> (Scratch, PathBuf) {
    let src = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("meshes")
        .join(name);
    let text = std::fs::read_to_string(&src).unwrap();
    let mut out = String::new();
    for l in text.lines() {
        if l.starts_with("t_end") {
            out.push_str(&format!("t_end = {t_end}\n"));
        } else if l.starts_with("times") {
            // a probe's times within the shorter run: at a step, between two steps,
            // at the end (the sliding block's probe: values saved before a kill)
            let h = 2e-4;
            out.push_str(&format!(
                "times = [{}, {}, {t_end}]\n",
                0.25 * t_end,
                0.5277 * t_end + 0.5 * h
            ));
        } else {
            out.push_str(l);
            out.push('\n');
        }
    }
    let dir = tmp(&format!("scene-{name}"));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, out).unwrap();
    for mesh in ["ball.msh", "disk.msh"] {
        let _ = std::fs::copy(src.with_file_name(mesh), dir.join(mesh));
    }
    (dir, p)
}

#[test]
fn frictional_and_curved_scenes_resume_exactly() {
    // Coulomb friction (NSGS warm-started from the previous step's impulses), 3-D
    let (_slide_dir, slide) = short_scene("sliding_block.toml", 0.04);
    let args = ["run", slide.to_str().unwrap(), "--checkpoint-every", "37"];
    let s = check_resume("sliding", &args, &[40, 111, 199]);
    // its probe's three times were read (one before the kill at 111, kept in the
    // checkpoint), and resumed runs read the same values (`assert_same_run`)
    assert_eq!(s["probes"][0]["displacement"].as_array().unwrap().len(), 3);
    // a curved obstacle: G(q) and the Delassus data re-formed every step
    let (_cyl_dir, cyl) = short_scene("block_on_cylinder.toml", 0.03);
    let args = ["run", cyl.to_str().unwrap(), "--checkpoint-every", "64"];
    check_resume("cylinder", &args, &[70, 250]);
}

/// Contacts between bodies (issue 18): the block sliding on the deformable slab moves its
/// base nodes over the slab's facets and rebuilds its candidate lists every 6.25 mm of
/// travel (about every 30 steps here). A resumed run rebuilds them at the restored state,
/// at other steps than the uninterrupted run, and still picks the same facets: kills
/// between rebuilds resume bit for bit.
#[test]
fn contacts_between_bodies_resume_exactly() {
    let (_dir, slab) = short_scene("sliding_block_on_slab.toml", 0.04);
    let args = ["run", slab.to_str().unwrap(), "--checkpoint-every", "37"];
    check_resume("slab", &args, &[40, 111]);
}

/// A nonlinear structure (the neo-Hookean ball crushed at 5 m/s, `meshes/ball_crush.toml`
/// cut to 0.012 s, in contact from step 2 to about 100): full Newton refactors at every iterate; modified Newton forms M̂ⁿ at
/// each step's first iterate, so neither keeps anything across steps that a checkpoint
/// would have to hold: kills before, during and after the impact resume bit for bit.
#[test]
fn nonlinear_structures_resume_exactly() {
    let (_ball_dir, ball) = short_scene("ball_crush.toml", 0.012);
    for modified in ["false", "true"] {
        let set = format!("scheme.newton.modified={modified}");
        let args = [
            "run",
            ball.to_str().unwrap(),
            "--checkpoint-every",
            "20",
            "--set",
            &set,
        ];
        check_resume(&format!("ball-{modified}"), &args, &[25, 47, 101]);
    }
}

#[test]
fn a_real_sigkill_is_resumed() {
    let args = [
        "bar",
        "--elements",
        "400",
        "--dt",
        "1e-7",
        "--t-end",
        "2e-3",
        "--checkpoint-every",
        "500",
        "--save-every",
        "1000",
    ];
    let whole = tmp("sigkill-whole");
    assert!(run(&args, &whole, None).status.success());
    let dir = tmp("sigkill");
    let mut child = bin()
        .args(args)
        .args(["--out", dir.to_str().unwrap(), "--quiet", "--no-plots"])
        .spawn()
        .unwrap();
    // kill once the first checkpoint is there (or give up after 60 s)
    let t0 = std::time::Instant::now();
    while !dir.join("checkpoint.json").exists() && t0.elapsed().as_secs() < 60 {
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    std::thread::sleep(std::time::Duration::from_millis(30));
    let _ = child.kill(); // SIGKILL
    let status = child.wait().unwrap();
    if status.success() {
        eprintln!("the run finished before the kill: nothing to resume on this machine");
        return;
    }
    let o = resume(&dir);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_same_run(&whole, &dir);
}

#[test]
fn missing_old_and_corrupt_checkpoints_are_named() {
    let dir = tmp("bad");
    std::fs::create_dir_all(&dir).unwrap();
    let err = |d: &Path| {
        let o = resume(d);
        assert_eq!(o.status.code(), Some(2));
        String::from_utf8_lossy(&o.stderr).to_string()
    };
    let e = err(&dir);
    assert!(
        e.contains("checkpoint.json") && e.contains("no checkpoint"),
        "{e}"
    );
    let ck = dir.join("checkpoint.json");
    std::fs::write(&ck, "{\"format\": \"signorini-checkpoint\", \"vers").unwrap();
    let e = err(&dir);
    assert!(
        e.contains("truncated or corrupt") && e.contains("line 1"),
        "{e}"
    );
    std::fs::write(&ck, "{\"format\": \"something-else\", \"version\": 1}").unwrap();
    assert!(err(&dir).contains("not a signorini checkpoint"));
    std::fs::write(
        &ck,
        "{\"format\": \"signorini-checkpoint\", \"version\": 0}",
    )
    .unwrap();
    let e = err(&dir);
    assert!(
        e.contains("version 0") && e.contains("reads version 7"),
        "{e}"
    );
    // a real checkpoint with one vector cut short
    let good = tmp("bad-src");
    let o = run(
        &[
            "bar",
            "--elements",
            "50",
            "--dt",
            "1e-6",
            "--t-end",
            "1e-4",
            "--checkpoint-every",
            "10",
        ],
        &good,
        Some(30),
    );
    assert!(!o.status.success());
    let mut c: serde_json::Value =
        serde_json::from_slice(&std::fs::read(good.join("checkpoint.json")).unwrap()).unwrap();
    c["integrator"]["vectors"]["q"] = serde_json::Value::String("AAAAAAAAAAA=".into());
    std::fs::write(
        good.join("checkpoint.json"),
        serde_json::to_vec(&c).unwrap(),
    )
    .unwrap();
    // refused by the checkpoint's digest (version 5) before the restore's own length
    // check (`IntegratorState::vector`) would name the vector
    let e = err(&good);
    assert!(
        e.contains("`digest`") && e.contains("edited or damaged"),
        "{e}"
    );
}

/// Issue 16 §4: a block settling on a tilted plane, its bottom contacts activating a
/// row at a time (11, then 22–24, then 7–11 of 121 candidates), killed and resumed at
/// steps where the active set differs from the one whose Delassus columns were computed
/// together: on the per-active-column path with a supernodal factor the resumed history
/// differed from step k+1 (a restore recomputes every active column in one batch, and a
/// supernodal block solve's rounding follows the batch width). Every Delassus path
/// (dense, per-active-column) with both factor kinds (simplicial on the 4 × 4 × 2 block,
/// supernodal on the 10 × 10 × 6 one; `check` must say so) resumes byte for byte.
/// The block turns with the slope (its cells up to 0.063 rad on the simplicial mesh),
/// past the linear law's default `max_rotation` (issue 48): the scene accepts 0.1 rad,
/// the test being about the resume.
#[test]
fn every_delassus_path_and_factor_kind_resumes_exactly() {
    for (cells, factor) in [("[4, 4, 2]", "simplicial"), ("[10, 10, 6]", "supernodal")] {
        for delassus in ["dense", "columns"] {
            let name = format!("tilted-{factor}-{delassus}");
            let dir = tmp(&format!("scene-{name}"));
            std::fs::create_dir_all(&dir).unwrap();
            let scene = dir.join("tilted.toml");
            std::fs::write(
                &scene,
                format!(
                    r#"[time]
dt = 1e-4
t_end = 3e-2
[scheme]
kind = "combined-projection"
delassus = "{delassus}"
max_rotation = 0.1
[[bodies]]
name = "block"
mesh = {{ generator = "box", cell = "hex8", cells = {cells}, size = [0.1, 0.1, 0.06] }}
material = {{ young = 1e7, poisson = 0.3, density = 1000.0 }}
velocity = [0.2, 0.0, -0.3]
[loads]
gravity = [0.0, 0.0, -9.81]
[[obstacles]]
name = "slope"
type = "plane"
point = [0.0, 0.0, -0.0003]
normal = [0.05, 0.0, 1.0]
[[contacts]]
body = "block"
nodes = "z0"
obstacle = "slope"
friction = 0.3
"#
                ),
            )
            .unwrap();
            let o = bin().arg("check").arg(&scene).output().unwrap();
            let text = String::from_utf8_lossy(&o.stdout);
            assert!(
                text.contains(&format!("faer {factor} LLᵀ")),
                "{name}: not the {factor} factor: {text}"
            );
            let path = if delassus == "dense" {
                "Delassus dense"
            } else {
                "Delassus per-active-column"
            };
            assert!(text.contains(path), "{name}: not the {path} path: {text}");
            let args = ["run", scene.to_str().unwrap(), "--checkpoint-every", "10"];
            check_resume(&name, &args, &[99, 130]);
        }
    }
}

/// Since checkpoint version 3 the frames' times are read back from `fields.pvd` on
/// resume (the checkpoint keeps only their count): a `.pvd` that lists fewer frames than
/// the checkpoint, or other files, is refused with exit 2, naming it.
#[test]
fn a_changed_frame_collection_is_refused_on_resume() {
    let args = [
        "bar",
        "--elements",
        "50",
        "--dt",
        "1e-6",
        "--t-end",
        "4e-4",
        "--checkpoint-every",
        "100",
    ];
    for (case, edit) in [
        (
            "fewer",
            Box::new(|t: &str| {
                // drop every DataSet line but the first
                let mut seen = false;
                t.lines()
                    .filter(|l| {
                        let ds = l.contains("<DataSet");
                        let keep = !ds || !seen;
                        seen |= ds;
                        keep
                    })
                    .collect::<Vec<_>>()
                    .join("\n")
            }) as Box<dyn Fn(&str) -> String>,
        ),
        (
            "renamed",
            Box::new(|t: &str| t.replace("frame_000001.vtu", "frame_000009.vtu")),
        ),
    ] {
        let dir = tmp(&format!("pvd-{case}"));
        let o = run(&args, &dir, Some(250));
        assert!(
            !o.status.success(),
            "{case}: the abort hook did not stop the run"
        );
        let pvd = dir.join("fields.pvd");
        let text = std::fs::read_to_string(&pvd).unwrap();
        std::fs::write(&pvd, edit(&text)).unwrap();
        let o = resume(&dir);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{case}: {err}");
        assert!(
            err.contains("fields.pvd") && err.contains("the run directory was changed"),
            "{case}: {err}"
        );
    }
}
