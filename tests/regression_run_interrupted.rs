//! A run asked to stop (`Progress::cancelled`, the Python package's Ctrl-C) ends with
//! `Error::Interrupted` (exit code 1) after the step it was at, and leaves its output
//! directory readable: `history.csv` holds exactly the rows up to that step (each a
//! row of the uninterrupted run's file, byte for byte), `fields.pvd` lists the frames
//! written so far, and no `summary.json` claims a finished run.

use signorini::run::{self, Output, Progress};
use signorini::scene::bar::BarScene;

struct StopAt(usize);

impl Progress for StopAt {
    fn update(&mut self, step: usize, _: usize) {
        if step >= self.0 {
            self.0 = 0;
        }
    }
    fn cancelled(&mut self) -> bool {
        self.0 == 0
    }
}

fn bar() -> BarScene {
    BarScene {
        elements: 100,
        dt: 2e-6,
        t_end: 1e-3,
        ..BarScene::default()
    }
}

#[test]
fn an_interrupted_run_leaves_a_readable_directory() {
    let base = std::env::temp_dir().join(format!("signorini-interrupt-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&base);
    let options = signorini::io::OutputOptions::default();
    let full = base.join("full");
    signorini::app::run_bar(
        &bar(),
        Some(Output {
            dir: &full,
            options: &options,
        }),
        &mut run::Quiet,
    )
    .unwrap();
    let cut = base.join("cut");
    let Err(e) = signorini::app::run_bar(
        &bar(),
        Some(Output {
            dir: &cut,
            options: &options,
        }),
        &mut StopAt(120),
    ) else {
        panic!("the run was asked to stop")
    };
    // 500 steps: progress every step, so the run stops right after step 120
    assert!(
        matches!(e, signorini::Error::Interrupted { step: 120, .. }),
        "{e}"
    );
    assert_eq!(e.exit_code(), 1);
    let a = std::fs::read_to_string(full.join("history.csv")).unwrap();
    let b = std::fs::read_to_string(cut.join("history.csv")).unwrap();
    let rows: Vec<&str> = b.lines().collect();
    assert_eq!(rows.len(), 1 + 120, "header and 120 rows");
    for (x, y) in a.lines().zip(&rows) {
        assert_eq!(x, *y);
    }
    let pvd = std::fs::read_to_string(cut.join("fields.pvd")).unwrap();
    assert!(pvd.trim_end().ends_with("</VTKFile>"), "{pvd}");
    let listed = pvd.matches("<DataSet ").count();
    let files = std::fs::read_dir(cut.join("fields")).unwrap().count();
    assert!(
        listed >= 1 && listed == files,
        "{listed} listed, {files} files"
    );
    assert!(!cut.join("summary.json").exists());
    let _ = std::fs::remove_dir_all(&base);
}
