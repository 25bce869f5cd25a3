//! The output contract of a run: `summary.json` keys and `history.csv` columns, as
//! scripts rely on them, written by the real binary.

use std::process::Command;

#[test]
fn cli_run_writes_summary_and_history() {
    let dir = std::env::temp_dir().join(format!("signorini-io-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = Command::new(env!("CARGO_BIN_EXE_signorini"))
        .args([
            "bar",
            "--elements",
            "100",
            "--dt",
            "2e-6",
            "--t-end",
            "1e-3",
            "--quiet",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    for key in [
        "scheme",
        "elements",
        "dt",
        "theta",
        "steps",
        "wall_seconds",
        "seconds_per_step",
        "max_violation",
    ] {
        assert!(summary.get(key).is_some(), "summary lacks {key}");
    }
    assert_eq!(summary["scheme"], "combined-projection");
    assert_eq!(summary["steps"], 500);
    let c = &summary["contact"];
    for key in [
        "plateau_force",
        "analytic_force",
        "duration",
        "analytic_duration",
        "release_velocity",
        "total_impulse",
    ] {
        assert!(c[key].is_number(), "contact lacks {key}");
    }
    for key in ["newton", "projection", "index_set", "lcp"] {
        assert!(summary["iterations"][key]["mean"].is_number());
        assert!(summary["iterations"][key]["max"].is_number());
    }
    let csv = std::fs::read_to_string(dir.join("history.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next().unwrap(),
        "step,time,kinetic_energy,potential_energy,max_violation,newton_iterations,\
         projection_iterations,index_set_iterations,gap_0,velocity_0,impulse_0,projection_0"
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 500, "one row per step");
    // time is the end of the step
    assert_eq!(rows[0][0], 1.0);
    assert!((rows[0][1] - 2e-6).abs() < 1e-18);
    assert!((rows[499][1] - 1e-3).abs() < 1e-15);
    // the summed impulse over the rows is the summary's total impulse
    let total: f64 = rows.iter().map(|r| r[10]).sum();
    let s_total = c["total_impulse"].as_f64().unwrap();
    assert!((total / s_total - 1.0).abs() < 1e-12);
    // no .part file is left once the run completed
    assert!(!dir.join("history.csv.part").exists());
    assert!(!dir.join("summary.json.part").exists());
    let _ = std::fs::remove_dir_all(&dir);
}
