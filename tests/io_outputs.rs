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

/// Many contacts (a 16 × 16-cell face: 289 frictional contacts, past `auto`'s 256): the
/// CSV keeps the sums (`closed_contacts`, `total_impulse`, `min_gap`,
/// `total_projection`, `total_tangent_impulse_{t}`, `sticking`, `slipping`) instead of
/// 289 groups of columns, and they equal the sums of the per-contact columns that
/// `contact_columns = "all"` writes for the same run (to 1e-12 relative: the same
/// impulses summed in the same order; the counts exactly).
#[test]
fn many_contacts_keep_their_sums_in_the_csv() {
    use signorini::app::run_scene;
    use signorini::io::{ContactColumns, OutputOptions};
    use signorini::run::Output;
    use signorini::run::Quiet;
    use signorini::scene::file::Scene;
    let scene = Scene::from_toml(
        r#"
[time]
dt = 1e-4
t_end = 2e-3
[scheme]
kind = "combined-projection"
[[bodies]]
name = "block"
mesh = { generator = "box", cell = "hex8", cells = [16, 16, 1], size = [0.16, 0.16, 0.01] }
material = { young = 1e7, poisson = 0.3, density = 1000.0 }
velocity = [0.3, 0.0, -0.01]
[loads]
gravity = [0.0, 0.0, -9.81]
[[obstacles]]
name = "floor"
type = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
[[contacts]]
body = "block"
nodes = "z0"
obstacle = "floor"
friction = 0.3
"#,
    )
    .unwrap();
    let read = |cols: ContactColumns| -> (Vec<String>, Vec<Vec<f64>>) {
        let dir = std::env::temp_dir().join(format!(
            "signorini-io-columns-{cols:?}-{}",
            std::process::id()
        ));
        let _ = std::fs::remove_dir_all(&dir);
        let options = OutputOptions {
            fields: false,
            plots: true,
            hdf5: Some(false),
            contact_columns: cols,
            ..OutputOptions::default()
        };
        let out = Output {
            dir: &dir,
            options: &options,
        };
        run_scene(&scene, Some(out), &mut Quiet).unwrap();
        let csv = std::fs::read_to_string(dir.join("history.csv")).unwrap();
        assert!(
            dir.join("contact_force.png").exists(),
            "the force plot reads the sums"
        );
        let _ = std::fs::remove_dir_all(&dir);
        let mut lines = csv.lines();
        let header = lines.next().unwrap().split(',').map(String::from).collect();
        let rows = lines
            .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
            .collect();
        (header, rows)
    };
    let (sh, sums) = read(ContactColumns::Auto);
    assert_eq!(
        sh[8..].join(","),
        "closed_contacts,total_impulse,min_gap,total_projection,total_tangent_impulse_0,\
         total_tangent_impulse_1,sticking,slipping,friction_iterations,friction_residual,\
         centre_0_0,centre_0_1,centre_0_2,momentum_0_0,momentum_0_1,momentum_0_2,\
         angular_momentum_0_0,angular_momentum_0_1,angular_momentum_0_2"
    );
    let (ah, all) = read(ContactColumns::All);
    // the per-contact columns, the friction sweeps and residual, the body's nine
    assert_eq!(ah.len(), 8 + 289 * 9 + 2 + 9);
    let col = |name: &str| ah.iter().position(|h| h == name).unwrap();
    let mut touched = 0;
    for (s, a) in sums.iter().zip(&all) {
        let p: Vec<f64> = (0..289).map(|c| a[col(&format!("impulse_{c}"))]).collect();
        let closed = p.iter().filter(|&&x| x > 0.0).count() as f64;
        let total: f64 = p.iter().sum();
        let min_gap = (0..289)
            .map(|c| a[col(&format!("gap_{c}"))])
            .fold(f64::INFINITY, f64::min);
        let tx: f64 = (0..289)
            .map(|c| a[col(&format!("tangent_impulse_{c}_0"))])
            .sum();
        let status = |k: f64| {
            (0..289)
                .filter(|c| a[col(&format!("status_{c}"))] == k)
                .count()
        };
        assert_eq!(s[8], closed);
        assert!((s[9] - total).abs() <= 1e-12 * total.abs().max(1e-30));
        assert_eq!(s[10], min_gap);
        assert!((s[12] - tx).abs() <= 1e-12 * tx.abs().max(1e-30));
        assert_eq!(s[14] as usize, status(1.0));
        assert_eq!(s[15] as usize, status(2.0));
        touched += usize::from(closed > 0.0);
    }
    assert!(touched > 5, "the block touched the floor in {touched} rows");
}
