//! Every input with which fuzzing (`fuzz/`, cargo-fuzz) crashed a reader, kept as a
//! regression: each must now read or fail with an error naming the file, never panic.
//! `tests/data/fuzz/<target>/` holds them, one file per crash, named after its cause.

use std::path::{Path, PathBuf};

fn inputs(target: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/fuzz")
        .join(target);
    let mut v: Vec<PathBuf> = std::fs::read_dir(&dir)
        .map(|d| d.map(|e| e.unwrap().path()).collect())
        .unwrap_or_default();
    v.sort();
    v
}

#[test]
fn mesh_crashes_are_errors_now() {
    let mut n = 0;
    for target in ["msh", "vtk", "vtu"] {
        for p in inputs(target) {
            let bytes = std::fs::read(&p).unwrap();
            let name = Path::new("fuzz").with_extension(target);
            match signorini::io::mesh::parse_mesh(&name, &bytes) {
                Ok(_) => {}
                Err(e) => assert!(e.to_string().contains("fuzz."), "{}: {e}", p.display()),
            }
            n += 1;
        }
    }
    assert!(n >= 2, "the committed crashes are found ({n})");
}

#[test]
fn scene_and_fclib_crashes_are_errors_now() {
    for p in inputs("scene") {
        let text = String::from_utf8_lossy(&std::fs::read(&p).unwrap()).to_string();
        let _ = signorini::scene::file::Scene::from_toml(&text);
    }
    for p in inputs("fclib_dat") {
        let text = String::from_utf8_lossy(&std::fs::read(&p).unwrap()).to_string();
        let _ = signorini::io::fclib::parse_dat(Path::new("fuzz.dat"), &text);
    }
}
