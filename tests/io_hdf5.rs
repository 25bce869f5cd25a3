//! HDF5 output (feature `hdf5`): `fields.vtkhdf` read back with the hdf5 crate and
//! compared bit for bit with the `.vtu` frames (read by vtkio) and with `history.csv`.
#![cfg(feature = "hdf5")]

use std::path::PathBuf;

mod common;

use signorini::app::run_bar;
use signorini::io::OutputOptions;
use signorini::run::{Output, Quiet};
use signorini::scene::bar::BarScene;

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("signorini-h5-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

#[test]
fn vtkhdf_and_history_hold_what_the_vtu_and_csv_hold() {
    let scene = BarScene {
        elements: 50,
        dt: 4e-6,
        t_end: 5e-4,
        ..BarScene::default()
    };
    let dir = tmp("bar");
    let options = OutputOptions {
        stride: 25,
        ..OutputOptions::default()
    };
    let r = run_bar(
        &scene,
        Some(Output {
            dir: &dir,
            options: &options,
        }),
        &mut Quiet,
    )
    .unwrap();
    let f = hdf5::File::open(dir.join("fields.vtkhdf")).unwrap();
    let root = f.group("VTKHDF").unwrap();
    let version: Vec<i64> = root.attr("Version").unwrap().read_raw().unwrap();
    assert_eq!(version, vec![2, 2]);
    let ty: hdf5::types::FixedAscii<16> = root.attr("Type").unwrap().read_scalar().unwrap();
    assert_eq!(ty.as_str(), "UnstructuredGrid");
    let nsteps: i64 = root
        .group("Steps")
        .unwrap()
        .attr("NSteps")
        .unwrap()
        .read_scalar()
        .unwrap();
    assert_eq!(nsteps as usize, r.summary.frames);
    let np = 51;
    let disp: Vec<f64> = root
        .dataset("PointData/displacement")
        .unwrap()
        .read_raw()
        .unwrap();
    assert_eq!(disp.len(), 3 * np * r.summary.frames);
    let times: Vec<f64> = root.dataset("Steps/Values").unwrap().read_raw().unwrap();
    let offsets: Vec<i64> = root
        .dataset("Steps/PointDataOffsets/displacement")
        .unwrap()
        .read_raw()
        .unwrap();
    // every frame equals its .vtu twin, bit for bit
    let pvd = std::fs::read_to_string(dir.join("fields.pvd")).unwrap();
    let files: Vec<&str> = pvd
        .lines()
        .filter_map(|l| l.split("file=\"").nth(1))
        .map(|s| s.trim_end_matches("\"/>"))
        .collect();
    assert_eq!(files.len(), times.len());
    for (k, file) in files.iter().enumerate() {
        let v = &common::read_frame(&dir.join(file)).point["displacement"];
        let o = offsets[k] as usize * 3;
        assert_eq!(&disp[o..o + 3 * np], &v[..], "frame {k}");
    }
    // /history equals history.csv column by column
    let csv = std::fs::read_to_string(dir.join("history.csv")).unwrap();
    let rows: Vec<Vec<f64>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    let hist = f.group("history").unwrap();
    let time: Vec<f64> = hist.dataset("time").unwrap().read_raw().unwrap();
    let step: Vec<i64> = hist.dataset("step").unwrap().read_raw().unwrap();
    let impulse: Vec<f64> = hist.dataset("impulse").unwrap().read_raw().unwrap();
    let ke: Vec<f64> = hist.dataset("kinetic_energy").unwrap().read_raw().unwrap();
    let newton: Vec<i64> = hist
        .dataset("newton_iterations")
        .unwrap()
        .read_raw()
        .unwrap();
    assert_eq!(time.len(), rows.len());
    for (i, r) in rows.iter().enumerate() {
        assert_eq!(step[i] as f64, r[0]);
        assert_eq!(time[i], r[1]);
        assert_eq!(ke[i], r[2]);
        assert_eq!(newton[i] as f64, r[5]);
        assert_eq!(impulse[i], r[10]);
    }
    let dt: f64 = hist.attr("dt").unwrap().read_scalar().unwrap();
    assert_eq!(dt, scene.dt);
    // each row's own step (constant here; the accuracy mode's vary)
    let steps: Vec<f64> = hist.dataset("dt").unwrap().read_raw().unwrap();
    assert_eq!(steps.len(), rows.len());
    assert!(steps.iter().all(|&h| h == scene.dt), "{steps:?}");
    let params: hdf5::types::VarLenUnicode =
        hist.attr("parameters").unwrap().read_scalar().unwrap();
    let p: serde_json::Value = serde_json::from_str(params.as_str()).unwrap();
    assert_eq!(p["elements"], 50);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A child process spawned while the run's file is open inherits its descriptor (HDF5
/// opens without `O_CLOEXEC`); with HDF5's `flock` advisory lock on, that child held
/// the writer's exclusive lock and a reader failed with `errno = 11` until the child
/// exited (CI, `study_sweep`, where another test spawned the CLI). The files are
/// written without the lock: the reader opens while the child still lives.
#[test]
fn a_child_process_spawned_mid_write_does_not_lock_readers_out() {
    let dir = tmp("lock");
    std::fs::create_dir_all(&dir).unwrap();
    let file = signorini::io::h5::RunFile::create(&dir).unwrap();
    let mut child = std::process::Command::new("sleep")
        .arg("30")
        .spawn()
        .unwrap();
    drop(file);
    let opened = hdf5::File::open(dir.join("fields.vtkhdf"));
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(
        opened.is_ok(),
        "reader locked out: {:?}",
        opened.err().map(|e| e.to_string())
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
