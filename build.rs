//! Records the git commit of the build (when built from a git checkout) for the
//! checkpoints' build identity (`signorini::checkpoint::build_id`), and with the feature
//! `mumps` generates the bindings of the system MUMPS' C interface (`dmumps_c.h`): the
//! struct is laid out by the installed header, so its fields always match the library.
fn main() {
    println!("cargo:rerun-if-changed=.git/HEAD");
    println!("cargo:rerun-if-changed=.git/refs/heads");
    let commit = std::process::Command::new("git")
        .args(["rev-parse", "--short=12", "HEAD"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .map(|s| s.trim().to_string())
        .filter(|s| !s.is_empty());
    if let Some(c) = commit {
        println!("cargo:rustc-env=SIGNORINI_COMMIT={c}");
    }
    #[cfg(feature = "mumps")]
    mumps_bindings();
}

#[cfg(feature = "mumps")]
fn mumps_bindings() {
    // Debian's libmumps-dev: headers in /usr/include, `libdmumps.so` linked to
    // `libmumps_common`, ScaLAPACK, PT-Scotch, METIS and Open MPI.
    let header = std::env::var("SIGNORINI_DMUMPS_H")
        .unwrap_or_else(|_| "/usr/include/dmumps_c.h".to_string());
    println!("cargo:rerun-if-env-changed=SIGNORINI_DMUMPS_H");
    println!("cargo:rerun-if-changed={header}");
    println!("cargo:rustc-link-lib=dmumps");
    println!("cargo:rustc-link-lib=mumps_common");
    let bindings = bindgen::Builder::default()
        .header(&header)
        .allowlist_function("dmumps_c")
        .allowlist_type("DMUMPS_STRUC_C")
        .derive_default(false)
        .layout_tests(false)
        .generate()
        .unwrap_or_else(|e| {
            panic!(
                "feature `mumps`: cannot read {header} ({e}); install Debian's libmumps-dev \
                 or point SIGNORINI_DMUMPS_H at dmumps_c.h"
            )
        });
    let out = std::path::PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    bindings
        .write_to_file(out.join("dmumps.rs"))
        .expect("OUT_DIR is writable");
}
