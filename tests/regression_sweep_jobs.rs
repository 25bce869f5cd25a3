//! `signorini sweep --jobs` (issue 35 §4): points run at the same time, each on its
//! share of the cores, give every record bit for bit as one at a time (the measurements
//! of the process aside: times and peak memory), on the bar and on a 3-D scene; a bad
//! `--jobs` is refused.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::sweeps::{Count, small_bar};

use signorini::study::sweep::{self, Source, Sweep, SweepSpec};

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("signorini-jobs-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// The records of `dir` as JSON without the process's measurements, by point.
fn physics(dir: &Path) -> Vec<serde_json::Value> {
    sweep::read_records(dir)
        .unwrap()
        .into_iter()
        .map(|r| {
            let mut v = serde_json::to_value(&r).unwrap();
            let o = v.as_object_mut().unwrap();
            for k in [
                "wall_seconds",
                "walls",
                "setup_seconds",
                "peak_memory_bytes",
            ] {
                assert!(o.remove(k).is_some(), "{k} is a field of a record");
            }
            v
        })
        .collect()
}

fn sweep(source: Source, set: Vec<String>, spec: SweepSpec, dir: &Path, jobs: usize) -> usize {
    let mut c = Count(0);
    Sweep {
        source,
        set,
        spec,
        dir: dir.to_path_buf(),
        resume: false,
        shard: None,
        jobs,
    }
    .run(&mut c)
    .unwrap();
    c.0
}

/// The bar over 2 schemes × 2 steps × 2 refinements (8 points of different cost) with
/// one job, two (one core each on a 2-core machine) and three (more jobs than cores):
/// the same records and the same table but for its timing columns.
#[test]
fn bar_records_are_the_same_with_any_jobs() {
    let spec = SweepSpec {
        scheme: vec!["moreau-jean".into(), "combined-projection".into()],
        dt: vec![4e-6, 2e-6],
        refine: vec![1, 2],
        ..SweepSpec::default()
    };
    let one = tmp("bar-1");
    assert_eq!(sweep(Source::Bar, small_bar(), spec.clone(), &one, 1), 8);
    let reference = physics(&one);
    assert_eq!(reference.len(), 8);
    for jobs in [2, 3] {
        let dir = tmp(&format!("bar-{jobs}"));
        assert_eq!(sweep(Source::Bar, small_bar(), spec.clone(), &dir, jobs), 8);
        assert_eq!(physics(&dir), reference, "--jobs {jobs}");
        let table = |d: &Path| sweep::csv(&sweep::table(sweep::read_records(d).unwrap()), false);
        assert_eq!(table(&dir), table(&one), "--jobs {jobs}: the table");
        let _ = std::fs::remove_dir_all(&dir);
    }
    let _ = std::fs::remove_dir_all(&one);
}

/// A 3-D scene (two hex8 bars, node-to-surface contact between bodies, parallel
/// assembly) over two schemes and two steps: one job with every core against two jobs
/// of one core each.
#[test]
fn three_dimensional_records_are_the_same_with_any_jobs() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/hex_bars.toml");
    let spec = SweepSpec {
        scheme: vec!["moreau-jean".into(), "combined-projection".into()],
        dt: vec![2e-6, 1e-6],
        ..SweepSpec::default()
    };
    let set = vec!["time.t_end=4e-5".to_string()];
    let one = tmp("hex-1");
    let two = tmp("hex-2");
    sweep(
        Source::File(scene.clone()),
        set.clone(),
        spec.clone(),
        &one,
        1,
    );
    sweep(Source::File(scene), set, spec, &two, 2);
    let (a, b) = (physics(&one), physics(&two));
    assert_eq!(a.len(), 4);
    assert_eq!(a, b);
    for d in [one, two] {
        let _ = std::fs::remove_dir_all(d);
    }
}

/// `--jobs 0` and an absurd `--jobs` are refused (exit 2) naming the flag and the range.
#[test]
fn bad_jobs_are_refused() {
    for bad in ["0", "5000"] {
        let dir = tmp(&format!("bad-{bad}"));
        let o = Command::new(env!("CARGO_BIN_EXE_signorini"))
            .args(["sweep", "bar", "--jobs", bad, "--quiet", "--out"])
            .arg(&dir)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "--jobs {bad}");
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(
            e.contains("--jobs") && e.contains(bad) && e.contains("expected 1 to 1024"),
            "{e}"
        );
    }
}
