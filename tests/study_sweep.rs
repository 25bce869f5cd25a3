//! `signorini sweep` (issue 19 §1–2): the grid, its records and table, sharding and
//! merging, resuming, and the errors of bad sweeps.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::sweeps::{Count, small_bar};

use signorini::study::sweep::{self, BAR_SCENE, Shard, Source, Sweep, SweepSpec};

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("signorini-sweep-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn spec() -> SweepSpec {
    SweepSpec {
        scheme: vec!["moreau-jean".into(), "combined-projection".into()],
        dt: vec![4e-6, 2e-6],
        refine: vec![1, 2],
        ..SweepSpec::default()
    }
}

fn sweep_into(dir: &Path, shard: Option<Shard>, resume: bool) -> (Vec<String>, usize) {
    let mut c = Count(0);
    let v = Sweep {
        source: Source::Bar,
        set: small_bar(),
        spec: spec(),
        dir: dir.to_path_buf(),
        resume,
        shard,
        jobs: 0,
    }
    .run(&mut c)
    .unwrap();
    (v, c.0)
}

fn table_without_timings(dir: &Path) -> String {
    sweep::csv(&sweep::table(sweep::read_records(dir).unwrap()), false)
}

/// The grid is the product of its axes (2 schemes × 2 steps × 2 refinements), each run
/// measured against the bar's closed form: the impulse trace ends at the run's total
/// impulse (its error against 2 ρ S L |v0| is the summary's own to 1e-9), the plateau
/// force of the finer runs is within 1 % of E S |v0|/c0 (the guide's bar runs (docs/bar.md) give
/// 0.01 %; 40–80 elements at Courant 0.4–1.7 stay below 1 %), and the projection scheme
/// does not penetrate (1e-12 m; Moreau–Jean penetrates |v0|(1−θ)h = 1e-7 m at h = 2e-6).
#[test]
fn the_bar_grid_measures_every_run_against_the_closed_form() {
    let dir = tmp("bar");
    let (verdicts, runs) = sweep_into(&dir, None, false);
    assert_eq!(runs, 8);
    let records = sweep::read_records(&dir).unwrap();
    assert_eq!(records.len(), 8);
    let total = 2.0 * 7800.0 * std::f64::consts::PI * 1e-4 * 1.0 * 0.1;
    for r in &records {
        assert_eq!(r.status, "ok", "{}", r.point.key);
        let a = r.analytic.expect("the bar has a closed form");
        let last = *r.impulse.last().unwrap();
        assert!(
            (last / total - 1.0 - a[3]).abs() < 1e-9,
            "{}: trace ends at {last}, summary error {}",
            r.point.key,
            a[3]
        );
        if r.point.refine == 2 {
            assert!(a[0].abs() < 1e-2, "{}: plateau error {}", r.point.key, a[0]);
        }
        let projection = r.point.values["scheme"].contains("combined");
        if projection {
            assert!(r.max_violation < 1e-12, "{}", r.point.key);
        } else {
            let expected = 0.1 * 0.5 * r.dt;
            assert!(
                (r.max_violation / expected - 1.0).abs() < 1e-6,
                "{}: {} vs {expected}",
                r.point.key,
                r.max_violation
            );
        }
    }
    let csv = std::fs::read_to_string(dir.join("sweep.csv")).unwrap();
    assert_eq!(csv.lines().count(), 9);
    assert!(csv.lines().next().unwrap().contains("front_accuracy"));
    for f in [
        "sweep-accuracy.png",
        "sweep-accuracy.svg",
        "verdict.txt",
        "grid.json",
    ] {
        assert!(dir.join(f).exists(), "{f}");
    }
    assert!(verdicts[0].contains("analytic"), "{}", verdicts[0]);
    assert!(
        verdicts.iter().any(|v| v.starts_with("sweep moreau-jean:")),
        "{verdicts:?}"
    );
    // every row on a front is not beaten by a cheaper one, per measure
    let rows = sweep::table(records);
    for (m, _) in sweep::MEASURES.iter().enumerate() {
        for r in rows.iter().filter(|r| r.front[m]) {
            assert!(!rows.iter().any(
                |o| o.record.wall_seconds < r.record.wall_seconds && o.errors[m] < r.errors[m]
            ));
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Three shards (as a Slurm array of three tasks would run them, into one --out) merge
/// into the unsharded table, timings aside; resuming runs only what is missing; a
/// merge with a shard unfinished is refused, naming what is missing.
#[test]
fn shards_merge_into_the_unsharded_table_and_resume_skips_recorded_runs() {
    let whole = tmp("whole");
    sweep_into(&whole, None, false);
    let sharded = tmp("sharded");
    let mut ran = 0;
    for i in 0..3 {
        let (_, n) = sweep_into(&sharded, Some(Shard { index: i, count: 3 }), false);
        ran += n;
        if i == 1 {
            let e = sweep::merge(&sharded).unwrap_err().to_string();
            assert!(e.contains("misses 2 of the grid's 8 runs"), "{e}");
        }
    }
    assert_eq!(ran, 8);
    sweep::merge(&sharded).unwrap();
    assert_eq!(
        table_without_timings(&whole),
        table_without_timings(&sharded)
    );
    assert!(sharded.join("sweep.csv").exists());

    // resume: one record removed, one run made, the same table
    std::fs::remove_file(whole.join("runs/000005.json")).unwrap();
    let before = table_without_timings(&sharded);
    let (_, n) = sweep_into(&whole, None, true);
    assert_eq!(n, 1);
    assert_eq!(table_without_timings(&whole), before);
    let (_, n) = sweep_into(&whole, None, true);
    assert_eq!(n, 0);

    // another grid into the same directory with --resume is refused
    let e = Sweep {
        source: Source::Bar,
        set: small_bar(),
        spec: SweepSpec {
            dt: vec![1e-6],
            ..spec()
        },
        dir: whole.clone(),
        resume: true,
        shard: None,
        jobs: 0,
    }
    .run(&mut Count(0))
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("grid.json") && e.contains("another sweep"),
        "{e}"
    );
    for d in [whole, sharded] {
        std::fs::remove_dir_all(&d).unwrap();
    }
}

/// Without an analytic reference the errors are taken against the finest run (most
/// refined, then smallest step): the finest run is the reference row, the others carry
/// impulse-history and energy errors, and the error shrinks as the step does (the
/// bar's `[reference]` removed from its scene text).
#[test]
fn without_a_closed_form_the_finest_run_is_the_reference() {
    let dir = tmp("finest");
    let text = BAR_SCENE.split("[reference").next().unwrap();
    let scene = dir.with_extension("toml");
    std::fs::create_dir_all(dir.parent().unwrap()).unwrap();
    std::fs::write(
        &scene,
        format!(
            "{text}\n[sweep]\nscheme = [\"combined-projection\"]\ndt = [8e-6, 4e-6, 2e-6, 1e-6]\n\
             [[probes]]\nname = \"tip\"\nbody = \"bar\"\nnodes = \"x1\"\ntimes = [1e-4, 3e-4]\n"
        ),
    )
    .unwrap();
    let mut c = Count(0);
    let spec = sweep::Source::File(scene.clone())
        .scene(&small_bar(), &sweep::points(&SweepSpec::default())[0])
        .unwrap()
        .sweep
        .unwrap();
    Sweep {
        source: Source::File(scene.clone()),
        set: small_bar(),
        spec,
        dir: dir.clone(),
        resume: false,
        shard: None,
        jobs: 0,
    }
    .run(&mut c)
    .unwrap();
    assert_eq!(c.0, 4);
    let rows = sweep::table(sweep::read_records(&dir).unwrap());
    let reference: Vec<_> = rows.iter().filter(|r| r.is_reference).collect();
    assert_eq!(reference.len(), 1);
    assert_eq!(reference[0].record.dt, 1e-6);
    assert!(reference[0].errors[0].is_nan());
    let acc: Vec<f64> = rows
        .iter()
        .filter(|r| !r.is_reference)
        .map(|r| r.errors[4])
        .collect();
    assert_eq!(acc.len(), 3);
    assert!(
        acc.windows(2).all(|w| w[1] < w[0]) && acc[0] > 0.0,
        "impulse history errors {acc:?} do not shrink with the step"
    );
    // the probe (the free end's displacement) against the finest run's: no closed form
    // without `[reference]`, so the finest run's values; shrinking with the step, and
    // part of the accuracy (the worst of impulse history, energy and probes)
    let probe: Vec<f64> = rows
        .iter()
        .filter(|r| !r.is_reference)
        .map(|r| r.errors[8])
        .collect();
    assert!(
        probe.windows(2).all(|w| w[1] < w[0]) && probe[2] > 0.0,
        "probe errors {probe:?} do not shrink with the step"
    );
    assert!(reference[0].errors[8].is_nan());
    assert_eq!(reference[0].record.probes.len(), 2);
    assert!(reference[0].record.probes_analytic.is_none());
    for r in rows.iter().filter(|r| !r.is_reference) {
        assert_eq!(r.errors[0], r.errors[4].max(r.errors[6]).max(r.errors[8]));
    }
    let csv = std::fs::read_to_string(dir.join("sweep.csv")).unwrap();
    assert!(
        csv.contains("itself (the finest run)") && csv.contains("run 3"),
        "{csv}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
    std::fs::remove_file(&scene).unwrap();
}

/// Bad sweeps are refused before any run, naming the value: a negative step, a scheme
/// that does not exist (with the point), a refinement of a mesh file, a shard out of
/// range, Slurm variables that are not numbers.
#[test]
fn bad_sweeps_are_named_before_any_run() {
    let run = |spec: SweepSpec, source: Source| {
        let dir = tmp("bad");
        let mut c = Count(0);
        let set = match source {
            Source::Bar => small_bar(),
            Source::File(_) => Vec::new(),
        };
        let e = Sweep {
            source,
            set,
            spec,
            dir,
            resume: false,
            shard: None,
            jobs: 0,
        }
        .run(&mut c)
        .unwrap_err();
        assert_eq!(c.0, 0);
        assert_eq!(e.exit_code(), 2);
        e.to_string()
    };
    let e = run(
        SweepSpec {
            dt: vec![1e-6, -1e-6],
            ..SweepSpec::default()
        },
        Source::Bar,
    );
    assert!(e.contains("sweep.dt[1]") && e.contains("-0.000001"), "{e}");
    let e = run(
        SweepSpec {
            scheme: vec!["moreau-jean".into(), "euler".into()],
            ..SweepSpec::default()
        },
        Source::Bar,
    );
    assert!(e.contains("euler") && e.contains("sweep point 1"), "{e}");
    let e = run(
        SweepSpec {
            refine: vec![1, 2],
            ..SweepSpec::default()
        },
        Source::File(PathBuf::from("meshes/ball_drop.toml")),
    );
    assert!(
        e.contains("bodies[0].mesh") && e.contains("cannot refine"),
        "{e}"
    );
    for bad in ["3/3", "1", "a/2", "0/0"] {
        let e = Shard::parse(bad).unwrap_err().to_string();
        assert!(e.contains("--shard") && e.contains(bad), "{e}");
    }
    let env = |id: &'static str, min: Option<&'static str>| {
        move |k: &str| match k {
            "SLURM_ARRAY_TASK_ID" => Some(id.to_string()),
            "SLURM_ARRAY_TASK_COUNT" => Some("4".to_string()),
            "SLURM_ARRAY_TASK_MIN" => min.map(str::to_string),
            _ => None,
        }
    };
    assert_eq!(
        Shard::from_slurm(env("4", Some("1"))).unwrap(),
        Some(Shard { index: 3, count: 4 })
    );
    assert_eq!(
        Shard::from_slurm(env("2", None)).unwrap(),
        Some(Shard { index: 2, count: 4 })
    );
    let e = Shard::from_slurm(env("x", None)).unwrap_err().to_string();
    assert!(e.contains("SLURM_ARRAY_TASK_ID"), "{e}");
    assert_eq!(Shard::from_slurm(|_| None).unwrap(), None);
}

/// The commands a cluster user types: two shards by `--shard`, one by Slurm's
/// variables, then `sweep merge`; exit codes 0, and 2 for a merge of nothing.
#[test]
fn the_cli_shards_and_merges() {
    let dir = tmp("cli");
    let bin = env!("CARGO_BIN_EXE_signorini");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let base = [
        "sweep",
        "bar",
        "--set",
        "bodies[0].mesh.elements=40",
        "--set",
        "time.t_end=4.5e-4",
        "--scheme",
        "moreau-jean,combined-projection",
        "--dt",
        "4e-6,2e-6",
        "--quiet",
        "--out",
    ];
    for (shard, slurm) in [("0/3", None), ("1/3", None), ("", Some("3"))] {
        let mut c = Command::new(bin);
        c.current_dir(root).args(base).arg(&dir);
        if let Some(id) = slurm {
            c.env("SLURM_ARRAY_TASK_ID", id)
                .env("SLURM_ARRAY_TASK_MIN", "1")
                .env("SLURM_ARRAY_TASK_COUNT", "3");
        } else {
            c.args(["--shard", shard]);
        }
        let o = c.output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        // quiet: one line per run of the shard, nothing else
        let lines = String::from_utf8_lossy(&o.stderr).lines().count();
        assert!(
            (1..=2).contains(&lines),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    assert!(dir.join("shard-2-of-3/runs").is_dir());
    let o = Command::new(bin)
        .args(["sweep", "merge"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(dir.join("sweep.csv")).unwrap();
    assert_eq!(csv.lines().count(), 5);
    let empty = tmp("cli-empty");
    std::fs::create_dir_all(&empty).unwrap();
    let o = Command::new(bin)
        .args(["sweep", "merge"])
        .arg(&empty)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("no shard-i-of-N"));
    for d in [dir, empty] {
        std::fs::remove_dir_all(&d).unwrap();
    }
}

/// With the `hdf5` feature the table is also `sweep.h5`: one dataset per column of
/// `sweep.csv` under `/table`, numbers equal to the CSV's (its shortest round-trip
/// decimals), text columns as strings.
#[cfg(feature = "hdf5")]
#[test]
fn the_hdf5_table_holds_the_csv_columns() {
    let dir = tmp("h5");
    sweep_into(&dir, None, false);
    let csv = std::fs::read_to_string(dir.join("sweep.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let f = hdf5::File::open(dir.join("sweep.h5")).unwrap();
    let g = f.group("table").unwrap();
    let k = header.iter().position(|h| *h == "accuracy").unwrap();
    let acc: Vec<f64> = g.dataset("accuracy").unwrap().read_raw().unwrap();
    assert_eq!(acc.len(), rows.len());
    for (a, r) in acc.iter().zip(&rows) {
        assert_eq!(*a, r[k].parse::<f64>().unwrap());
    }
    let k = header.iter().position(|h| *h == "scheme").unwrap();
    let schemes: Vec<hdf5::types::VarLenUnicode> = g.dataset("scheme").unwrap().read_raw().unwrap();
    for (s, r) in schemes.iter().zip(&rows) {
        assert_eq!(s.as_str(), r[k]);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--mpi` from a build without the `mpi` feature is bad input naming the feature.
#[cfg(not(feature = "mpi"))]
#[test]
fn mpi_without_the_feature_is_refused() {
    let o = Command::new(env!("CARGO_BIN_EXE_signorini"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(["sweep", "bar", "--dt", "1e-6", "--mpi", "--quiet", "--out"])
        .arg(tmp("no-mpi"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("--mpi") && e.contains("`mpi` cargo feature"),
        "{e}"
    );
}

/// With the bar's closed form, probes on the rod are compared with `u(x, t)` (not with
/// the finest run): `probe_error` is the record's own distance to the closed form, the
/// reference row has one too, and it enters the accuracy with the contact errors.
#[test]
fn probes_on_the_bar_are_compared_with_the_closed_form() {
    let dir = tmp("probes-analytic");
    let scene = dir.with_extension("toml");
    std::fs::create_dir_all(dir.parent().unwrap()).unwrap();
    std::fs::write(
        &scene,
        format!(
            "{BAR_SCENE}\n[[probes]]\nname = \"tip\"\nbody = \"bar\"\nnodes = \"x1\"\n\
             times = [1e-4, 3e-4]\n"
        ),
    )
    .unwrap();
    let spec = SweepSpec {
        scheme: vec!["combined-projection".into()],
        dt: vec![4e-6, 2e-6],
        ..SweepSpec::default()
    };
    Sweep {
        source: Source::File(scene.clone()),
        set: small_bar(),
        spec,
        dir: dir.clone(),
        resume: false,
        shard: None,
        jobs: 0,
    }
    .run(&mut Count(0))
    .unwrap();
    let rows = sweep::table(sweep::read_records(&dir).unwrap());
    assert_eq!(rows.len(), 2);
    let bar = signorini::analytic::ImpactingBar::REFERENCE;
    for r in &rows {
        let a = r.record.probes_analytic.as_ref().expect("a rod of the bar");
        assert_eq!(
            a,
            &vec![bar.displacement(1.0, 1e-4), bar.displacement(1.0, 3e-4)]
        );
        let u = &r.record.probes;
        let want = (u[0] - a[0]).abs().max((u[1] - a[1]).abs()) / a[0].abs().max(a[1].abs());
        assert_eq!(
            r.errors[8], want,
            "the reference row too: {}",
            r.is_reference
        );
        assert!(want > 0.0 && want < 0.05, "40 elements: {want}");
        assert_eq!(
            r.errors[0],
            r.errors[1]
                .max(r.errors[2])
                .max(r.errors[3])
                .max(r.errors[8])
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
    std::fs::remove_file(&scene).unwrap();
}
