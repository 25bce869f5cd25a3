//! Issue 16 §2: friction tolerances that mean something.
//!
//! Before, `scheme.friction.tol = 1e-8` failed Algorithm 2 at step 1 at the Newton cap
//! (the Newton loop asked the impulses for more than the friction solve delivered), and
//! `tol = 0.5` passed validation and let the block sink 0.6 mm with its energy doubled,
//! exit 0. Now the Newton floor and the position dead band follow the friction solve's
//! velocity accuracy, and tolerances above 1e-4 are refused.

use signorini::integrators::{Integrator, SchemeKind};
use signorini::scene::file::Scene;

fn scene(tol: f64, kind: SchemeKind) -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/sliding_block.toml");
    let mut scene = Scene::from_file(&path).unwrap();
    scene.scheme.kind = kind;
    scene.scheme.friction.tol = tol;
    scene
}

/// The shipped sliding block (0.4 s, 2000 steps) under Algorithms 1 and 2 runs to the end
/// with no cap for every tolerance from 1e-12 to 1e-4, and its largest penetration is a
/// `tol` fraction of the block's height of 5 cm (measured under Algorithm 2: 7.5e-16,
/// 6.8e-12 and 4.1e-7 m for 1e-12, 1e-8 and 1e-4).
#[test]
fn every_friction_tolerance_from_1e_12_to_1e_4_runs_with_an_accuracy_that_follows_it() {
    for kind in [SchemeKind::DirectProjection, SchemeKind::CombinedProjection] {
        for tol in [1e-12, 1e-10, 1e-8, 1e-6, 1e-4] {
            let s = scene(tol, kind);
            let (model, _) = s.build().unwrap();
            let mut integ: Box<dyn Integrator> =
                model.into_integrator(&s.scheme, s.time.dt).unwrap();
            let (mut caps, mut viol) = (0, 0.0_f64);
            for _ in 0..s.steps() {
                let st = integ.step().unwrap();
                caps += st.caps_hit;
                viol = viol.max(st.max_violation);
            }
            eprintln!("{kind:?} tol {tol:e}: caps {caps}, violation {viol:.2e} m");
            assert_eq!(caps, 0, "{kind:?} tol {tol:e}");
            assert!(
                viol <= 0.05 * tol,
                "{kind:?} tol {tol:e}: violation {viol:e} m"
            );
        }
    }
}

/// Tolerances the schemes cannot honour are refused, naming the key and the range.
#[test]
fn friction_tolerances_above_1e_4_or_not_positive_are_refused() {
    for tol in [0.5, 1.0, 1e-3, 0.0, -1e-8, f64::NAN] {
        let s = scene(tol, SchemeKind::CombinedProjection);
        let err = s
            .validate()
            .expect_err(&format!("tol {tol} accepted"))
            .to_string();
        assert!(
            err.contains("friction.tol") && err.contains("(0, 1e-4]"),
            "{err}"
        );
    }
}
