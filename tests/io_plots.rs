//! Plots: written next to the data at the end of a run, redrawn by `signorini plot`,
//! from a killed run's `history.csv.part` too; a missing history is a clear error.

use std::path::PathBuf;

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("signorini-plots-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// Width and height from a PNG's IHDR chunk.
fn png_size(p: &std::path::Path) -> (u32, u32) {
    let b = std::fs::read(p).unwrap();
    assert_eq!(&b[1..4], b"PNG", "{}", p.display());
    let be = |i: usize| u32::from_be_bytes(b[i..i + 4].try_into().unwrap());
    (be(16), be(20))
}

#[test]
fn bar_run_draws_three_plots_with_the_analytic_force() {
    let dir = tmp("bar");
    let st = std::process::Command::new(env!("CARGO_BIN_EXE_signorini"))
        .args([
            "bar",
            "--elements",
            "100",
            "--dt",
            "2e-6",
            "--quiet",
            "--out",
        ])
        .arg(&dir)
        .status()
        .unwrap();
    assert!(st.success());
    for stem in ["contact_force", "energy", "violation"] {
        assert_eq!(png_size(&dir.join(format!("{stem}.png"))), (1000, 600));
        let svg = std::fs::read_to_string(dir.join(format!("{stem}.svg"))).unwrap();
        assert!(svg.starts_with("<svg"), "{stem}.svg");
    }
    // the analytic plateau is drawn and named with its value (E S |v0| / c0)
    let svg = std::fs::read_to_string(dir.join("contact_force.svg")).unwrap();
    assert!(svg.contains("1271.472 N"), "analytic legend missing");
    // `signorini plot` redraws from the files alone
    std::fs::remove_file(dir.join("energy.png")).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_signorini"))
        .arg("plot")
        .arg(&dir)
        .output()
        .unwrap();
    assert!(out.status.success());
    assert!(dir.join("energy.png").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn plot_reads_a_killed_runs_partial_history_and_names_a_missing_one() {
    let dir = tmp("partial");
    std::fs::create_dir_all(&dir).unwrap();
    // a .part whose last line was cut mid-write
    std::fs::write(
        dir.join("history.csv.part"),
        "step,time,kinetic_energy,potential_energy,max_violation,newton_iterations,projection_iterations,index_set_iterations,gap_0,velocity_0,impulse_0,projection_0\n\
         1,1e-6,1.0,0.0,0,1,0,0,0,0,1e-3,0\n2,2e-6,0.9,0.1,0,1,0,0,0,0,1e-3,0\n3,3e-6,0.8",
    )
    .unwrap();
    let files = signorini::plot::plot_run(&dir).unwrap();
    assert_eq!(files.len(), 6);
    let empty = tmp("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let e = signorini::plot::plot_run(&empty).unwrap_err().to_string();
    assert!(e.contains("history.csv"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
    std::fs::remove_dir_all(&empty).unwrap();
}
