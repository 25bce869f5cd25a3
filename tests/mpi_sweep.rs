//! `signorini sweep --mpi` on 1, 2 and 4 ranks of Debian's Open MPI (cargo feature
//! `mpi`; issue 19 §2): the table gathered on rank 0 equals the sweep on one process
//! (timings aside), and each launch really ran that many ranks: every rank made its
//! share of the runs (a launcher that does not match the library would start N
//! independent copies of rank 0, each making every run as worker 0).
#![cfg(feature = "mpi")]

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::Command;

use signorini::study::sweep::{self, Source, Sweep, SweepSpec};

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("signorini-mpi-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

const SET: [&str; 2] = ["bodies[0].mesh.elements=40", "time.t_end=4.5e-4"];

struct Quiet;

impl sweep::SweepProgress for Quiet {
    fn run(&mut self, _: usize, _: usize, _: &sweep::RunRecord, _: f64) {}
}

fn table_without_timings(dir: &Path) -> String {
    sweep::csv(&sweep::table(sweep::read_records(dir).unwrap()), false)
}

#[test]
fn the_gathered_table_is_independent_of_the_rank_count() {
    let one = tmp("one");
    Sweep {
        source: Source::Bar,
        set: SET.iter().map(|s| s.to_string()).collect(),
        spec: SweepSpec {
            scheme: vec!["moreau-jean".into(), "combined-projection".into()],
            dt: vec![4e-6, 2e-6],
            refine: vec![1, 2],
            ..SweepSpec::default()
        },
        dir: one.clone(),
        resume: false,
        shard: None,
        jobs: 0,
    }
    .run(&mut Quiet)
    .unwrap();
    let expected = table_without_timings(&one);
    for np in [1usize, 2, 4] {
        let dir = tmp(&format!("np{np}"));
        let mut c = Command::new("mpirun");
        c.env("OMPI_ALLOW_RUN_AS_ROOT", "1")
            .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
            .args(["--oversubscribe", "-np", &np.to_string()])
            .arg(env!("CARGO_BIN_EXE_signorini"))
            .args(["sweep", "bar"]);
        for s in SET {
            c.args(["--set", s]);
        }
        let o = c
            .args([
                "--scheme",
                "moreau-jean,combined-projection",
                "--dt",
                "4e-6,2e-6",
                "--refine",
                "1,2",
                "--mpi",
                "--quiet",
                "--out",
            ])
            .arg(&dir)
            .output()
            .expect("mpirun (Debian's openmpi-bin) runs");
        assert!(
            o.status.success(),
            "np {np}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let records = sweep::read_records(&dir).unwrap();
        assert_eq!(records.len(), 8, "np {np}");
        let workers: BTreeSet<usize> = records.iter().map(|r| r.worker).collect();
        assert_eq!(
            workers,
            (0..np).collect::<BTreeSet<_>>(),
            "np {np}: the runs were made by ranks {workers:?}"
        );
        for r in &records {
            assert_eq!(r.worker, r.point.id % np, "np {np}: {}", r.point.key);
        }
        assert_eq!(table_without_timings(&dir), expected, "np {np}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
    std::fs::remove_dir_all(&one).unwrap();
}
