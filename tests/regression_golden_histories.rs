//! Golden histories: the frictionless runs of before the block contact layer (issue 11,
//! commit 784ef69) must give the same `history.csv`, value by value, to 1e-13 relative.
//!
//! The files in `tests/golden/` were written by the binary of 784ef69 with the commands
//! of [`CASES`], except `hex_bar.csv` and `ball_drop.csv`, rewritten by the fix of issue
//! 16 §1 (Algorithm 2 reconsiders an equality row dropped at selection once its
//! neighbours' projection moves it): there rows resting at g = 0 exactly are moved by
//! round-off (|g| ≤ 4e-23 m) and re-enter the projection, which changes the projection
//! columns (|τ| ≤ 2e-25) and, through them, energies and impulses by ≤ 2e-12 of their
//! scale; violations and iteration counts are unchanged. Tolerance: each value may differ from the golden one by 1e-13 times the
//! largest magnitude of its column (a relative test per value would fail on quantities
//! that are round-off around zero, such as a violation of 1e-40 m next to 0). Any change
//! of the arithmetic of the frictionless path beyond reordering shows up far above it.

use std::path::Path;
use std::process::Command;

/// (golden file, arguments after the binary).
const CASES: &[(&str, &[&str])] = &[
    ("bar-moreau-jean", &["bar", "--scheme", "moreau-jean"]),
    (
        "bar-schatzman-paoli",
        &["bar", "--scheme", "schatzman-paoli"],
    ),
    (
        "bar-trapezoid-position",
        &["bar", "--scheme", "trapezoid-position"],
    ),
    (
        "bar-direct-projection",
        &["bar", "--scheme", "direct-projection"],
    ),
    (
        "bar-combined-projection",
        &["bar", "--scheme", "combined-projection"],
    ),
    (
        "hex_bar",
        &["run", "meshes/hex_bar.toml", "--history-every", "10"],
    ),
    (
        "ball_drop",
        &["run", "meshes/ball_drop.toml", "--history-every", "10"],
    ),
    (
        "block_on_cylinder",
        &[
            "run",
            "meshes/block_on_cylinder.toml",
            "--history-every",
            "10",
        ],
    ),
];

/// The bar's arguments shared by the five bar cases.
const BAR: &[&str] = &["--elements", "100", "--dt", "2e-6", "--t-end", "6e-4"];

fn read(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(|x| x.parse::<f64>().unwrap()).collect())
        .collect();
    (header, rows)
}

#[test]
fn frictionless_histories_match_the_golden_files() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for (name, args) in CASES {
        let out =
            std::env::temp_dir().join(format!("signorini-golden-{}-{name}", std::process::id()));
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_signorini"));
        cmd.current_dir(root).args(*args);
        if args[0] == "bar" {
            cmd.args(BAR);
        }
        let status = cmd
            .args(["--quiet", "--no-fields", "--no-plots", "--out"])
            .arg(&out)
            .status()
            .unwrap();
        assert!(status.success(), "{name}: {status}");
        let (gh, gold) = read(&root.join("tests/golden").join(format!("{name}.csv")));
        let (h, now) = read(&out.join("history.csv"));
        // the new layer adds columns (tangential quantities) only for frictional scenes
        assert_eq!(h, gh, "{name}: header");
        assert_eq!(now.len(), gold.len(), "{name}: rows");
        let cols = gh.len();
        let scale: Vec<f64> = (0..cols)
            .map(|c| gold.iter().map(|r| r[c].abs()).fold(0.0, f64::max))
            .collect();
        let mut worst = (0.0, 0, 0);
        for (i, (a, b)) in now.iter().zip(&gold).enumerate() {
            for c in 0..cols {
                let d = (a[c] - b[c]).abs();
                let rel = if scale[c] > 0.0 { d / scale[c] } else { d };
                if rel > worst.0 {
                    worst = (rel, i, c);
                }
            }
        }
        assert!(
            worst.0 <= 1e-13,
            "{name}: row {} column {} differs by {:e} of the column's scale",
            worst.1,
            gh[worst.2],
            worst.0
        );
        let _ = std::fs::remove_dir_all(&out);
    }
}
