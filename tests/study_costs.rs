//! `signorini study costs` (issue 35 §5): the per-size costs in one command. Timings are
//! not asserted (no timed tests); what is: every run of the series is there with its
//! size, steps and dofs, each cost is a finite positive number, and each phase is the one
//! named by its mean contact force: the bar in contact at its closed-form plateau
//! E·S·|v0|/c0 = 1271.472 N, nothing in flight.

use signorini::study::costs::{self, bar_steps};

#[test]
fn costs_cover_both_series_and_phases() {
    let dir = std::env::temp_dir().join(format!("signorini-costs-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let lines = costs::costs_at(&dir, &[1_000, 10_000], &[4]).unwrap();
    // 2 cube runs (contact, flight) and 2 × 2 × 2 bar runs
    assert_eq!(lines.len(), 10);
    let text = std::fs::read_to_string(dir.join("costs.csv")).unwrap();
    let mut rows = text.lines();
    let header: Vec<&str> = rows.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<String>> = rows
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    assert_eq!(rows.len(), 10);
    let plateau = signorini::analytic::ImpactingBar::REFERENCE.contact_force();
    for r in &rows {
        let num = |name: &str| r[col(name)].parse::<f64>().unwrap();
        for c in ["us_per_step", "ns_per_dof_step", "setup_seconds"] {
            assert!(num(c).is_finite() && num(c) >= 0.0, "{c} of {r:?}");
        }
        assert!(num("us_per_step") > 0.0, "{r:?}");
        assert!(num("memory_planned_bytes") > 0.0, "{r:?}");
        let force = num("mean_contact_force_n");
        match (r[col("series")].as_str(), r[col("phase")].as_str()) {
            ("bar", phase) => {
                let n: usize = r[col("size")].parse().unwrap();
                assert_eq!(num("dofs") as usize, n + 1);
                assert_eq!(num("steps") as usize, bar_steps(n));
                if phase == "contact" {
                    // the onset overshoot of a step or two (DESIGN.md §7) over at
                    // least 1800 steps: within 0.5 %
                    assert!(
                        (force / plateau - 1.0).abs() < 5e-3,
                        "{force} against {plateau}"
                    );
                } else {
                    assert_eq!(force, 0.0, "{r:?}");
                }
            }
            ("cube", phase) => {
                assert_eq!(num("dofs") as usize, 3 * 5 * 5 * 5);
                assert_eq!(phase == "contact", force > 0.0, "{r:?}");
            }
            (s, _) => panic!("unknown series {s}"),
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
