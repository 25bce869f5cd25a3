//! Issue 34: sweeps that mislabelled runs, dropped axes, compared runs of different
//! lengths sample by sample, ran one point twice, mixed records of two grids, deleted a
//! user's file, or read their own numbers back one ulp off. Each is refused (exit 2,
//! naming what the user wrote) or handled as the user guide states (docs/sweeps.md).

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::sweeps::{Count, small_bar};

use signorini::study::sweep::{self, RunRecord, Shard, Source, Sweep, SweepSpec};

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("signorini-sweep34-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn sweep(dir: &Path, set: Vec<String>, spec: SweepSpec, source: Source) -> Result<usize, String> {
    let mut c = Count(0);
    Sweep {
        source,
        set,
        spec,
        dir: dir.to_path_buf(),
        resume: false,
        shard: None,
        jobs: 0,
    }
    .run(&mut c)
    .map(|_| c.0)
    .map_err(|e| {
        assert_eq!(e.exit_code(), 2, "{e}");
        e.to_string()
    })
}

fn axis(key: &str, vals: &[&str]) -> std::collections::BTreeMap<String, Vec<toml::Value>> {
    let t: toml::Table = toml::from_str(&format!("v = [{}]", vals.join(", "))).unwrap();
    let toml::Value::Array(a) = t["v"].clone() else {
        unreachable!()
    };
    [(key.to_string(), a)].into_iter().collect()
}

#[test]
fn a_flag_an_axis_and_a_set_on_one_key_are_refused() {
    let dir = tmp("keys");
    // --dt 4e-6,2e-6 --axis 'time.dt=[1e-6]': the runs were labelled 4e-6 and 2e-6
    let e = sweep(
        &dir,
        small_bar(),
        SweepSpec {
            dt: vec![4e-6, 2e-6],
            axes: axis("time.dt", &["1e-6"]),
            ..SweepSpec::default()
        },
        Source::Bar,
    )
    .unwrap_err();
    assert!(e.contains("time.dt") && e.contains("`dt`"), "{e}");
    let e = sweep(
        &dir,
        small_bar(),
        SweepSpec {
            scheme: vec!["moreau-jean".into()],
            axes: axis("scheme.kind", &["\"combined-projection\""]),
            ..SweepSpec::default()
        },
        Source::Bar,
    )
    .unwrap_err();
    assert!(e.contains("scheme.kind") && e.contains("`scheme`"), "{e}");
    // a --set on an axis' key: every point overrode it
    let mut set = small_bar();
    set.push("time.dt=1e-6".into());
    let e = sweep(
        &dir,
        set,
        SweepSpec {
            dt: vec![4e-6, 2e-6],
            ..SweepSpec::default()
        },
        Source::Bar,
    )
    .unwrap_err();
    assert!(e.contains("--set") && e.contains("time.dt=1e-6"), "{e}");
    // two --axis on one key: the first was dropped
    let o = Command::new(env!("CARGO_BIN_EXE_signorini"))
        .args(["sweep", "bar", "--axis", "scheme.theta=[0.5]", "--axis"])
        .args(["scheme.theta=[1.0]", "--quiet", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("--axis") && err.contains("`scheme.theta` has an --axis already"),
        "{err}"
    );
    assert!(!dir.join("runs").exists(), "nothing ran");
}

#[test]
fn refine_needs_a_mesh() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let e = sweep(
        &tmp("refine"),
        Vec::new(),
        SweepSpec {
            refine: vec![1, 2],
            ..SweepSpec::default()
        },
        Source::File(root.join("meshes/bouncing_ball.toml")),
    )
    .unwrap_err();
    assert!(
        e.contains("sweep.refine") && e.contains("no mesh to refine"),
        "{e}"
    );
}

/// Two runs of the same trajectory to 3e-4 and 4.5e-4 s: compared by time, the shorter
/// run's impulse history matches the longer one's to round-off (the traces are sampled
/// at different times, so the interpolation between samples of the same piecewise-linear
/// trace is exact where the samples fall within one step: bounded here by 1e-3 of the
/// total, the trace's curvature over one sample interval); index by index it read 0.63.
/// The final energies and peak forces of different spans are not compared (empty).
#[test]
fn an_axis_on_t_end_is_compared_by_time() {
    let dir = tmp("t_end");
    sweep(
        &dir,
        vec!["bodies[0].mesh.elements=40".into(), "time.dt=2e-6".into()],
        SweepSpec {
            axes: axis("time.t_end", &["4.5e-4", "3e-4"]),
            ..SweepSpec::default()
        },
        Source::Bar,
    )
    .unwrap();
    let rows = sweep::table(sweep::read_records(&dir).unwrap());
    assert_eq!(rows.len(), 2);
    let short = rows.iter().find(|r| !r.is_reference).unwrap();
    assert!((short.record.t_end - 3e-4).abs() < 1e-15);
    let e = short.errors[4];
    assert!(e < 1e-3, "impulse history error {e}");
    assert!(short.errors[5].is_nan() && short.errors[6].is_nan());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A record written and read back is the same to the bit (serde_json's float_roundtrip:
/// 1.6533333333333333 came back 1.653333333333333), so a table from disk equals the
/// table of the runs in memory.
#[test]
fn records_read_back_bit_for_bit() {
    let spec = SweepSpec {
        dt: vec![3e-6],
        ..SweepSpec::default()
    };
    let p = &sweep::points(&spec)[0];
    let r = sweep::run_point(&Source::Bar, &small_bar(), p, 1).unwrap();
    let back: RunRecord = serde_json::from_str(&serde_json::to_string(&r).unwrap()).unwrap();
    assert_eq!(back, r);
    let bits = |r: &RunRecord| {
        r.impulse
            .iter()
            .chain(&r.energy)
            .chain(r.analytic.iter().flatten())
            .map(|x| x.to_bits())
            .collect::<Vec<u64>>()
    };
    assert_eq!(bits(&back), bits(&r));
    assert_eq!(
        sweep::csv(&sweep::table(vec![back]), false),
        sweep::csv(&sweep::table(vec![r]), false)
    );
}

/// A new sweep removes the records of an older one and nothing else; `sweep merge`
/// refuses a record of another grid and leaves no stale record beside its grid.json.
#[test]
fn sweeps_touch_only_their_own_records() {
    let dir = tmp("own");
    let spec = SweepSpec {
        dt: vec![4e-6, 2e-6],
        ..SweepSpec::default()
    };
    sweep(&dir, small_bar(), spec.clone(), Source::Bar).unwrap();
    std::fs::write(dir.join("runs/notes.json"), "{\"mine\": true}").unwrap();
    std::fs::write(dir.join("runs/README"), "my notes").unwrap();
    // a new, smaller grid: the old 000001.json goes, the user's files stay
    sweep(
        &dir,
        small_bar(),
        SweepSpec {
            dt: vec![4e-6],
            ..SweepSpec::default()
        },
        Source::Bar,
    )
    .unwrap();
    assert!(dir.join("runs/notes.json").exists() && dir.join("runs/README").exists());
    assert!(!dir.join("runs/000001.json").exists());
    assert_eq!(sweep::read_records(&dir).unwrap().len(), 1);

    // two shards of a 2-point grid, one with a record of another grid planted
    let sh = tmp("merge");
    for i in 0..2 {
        let mut c = Count(0);
        Sweep {
            source: Source::Bar,
            set: small_bar(),
            spec: spec.clone(),
            dir: sh.clone(),
            resume: false,
            shard: Some(Shard { index: i, count: 2 }),
            jobs: 0,
        }
        .run(&mut c)
        .unwrap();
    }
    // stale records of an older sweep in the merge directory
    std::fs::create_dir_all(sh.join("runs")).unwrap();
    std::fs::copy(dir.join("runs/000000.json"), sh.join("runs/000007.json")).unwrap();
    sweep::merge(&sh).unwrap();
    assert!(!sh.join("runs/000007.json").exists(), "stale record kept");
    assert_eq!(sweep::read_records(&sh).unwrap().len(), 2);
    // a foreign record: point 2 of a 3-point grid in a shard of this 2-point one
    let mut foreign: RunRecord = serde_json::from_str(
        &std::fs::read_to_string(sh.join("shard-0-of-2/runs/000000.json")).unwrap(),
    )
    .unwrap();
    foreign.point.id = 2;
    foreign.point.key = "dt=1e-6".into();
    std::fs::write(
        sh.join("shard-0-of-2/runs/000002.json"),
        serde_json::to_string(&foreign).unwrap(),
    )
    .unwrap();
    let e = sweep::merge(&sh).unwrap_err().to_string();
    assert!(
        e.contains("000002.json") && e.contains("not a point of the grid"),
        "{e}"
    );
    for d in [dir, sh] {
        std::fs::remove_dir_all(&d).unwrap();
    }
}

/// A Slurm task index past the array's count is named in Slurm's terms (it was reported
/// as a `--shard` the user never passed).
#[test]
fn a_slurm_index_past_the_count_is_named_as_such() {
    let env = |k: &str| match k {
        "SLURM_ARRAY_TASK_ID" => Some("7".to_string()),
        "SLURM_ARRAY_TASK_COUNT" => Some("3".to_string()),
        _ => None,
    };
    let e = Shard::from_slurm(env).unwrap_err().to_string();
    assert!(
        e.contains("SLURM_ARRAY_TASK_ID")
            && e.contains("task 7 of an array of SLURM_ARRAY_TASK_COUNT = 3")
            && !e.contains("--shard"),
        "{e}"
    );
}
