//! Issue 16 §2: friction tolerances that mean something.
//!
//! Before, `scheme.friction.tol = 1e-8` failed Algorithm 2 at step 1 at the Newton cap
//! (the Newton loop asked the impulses for more than the friction solve delivered), and
//! `tol = 0.5` passed validation and let the block sink 0.6 mm with its energy doubled,
//! exit 0. Now the Newton floor and the position dead band follow the friction solve's
//! velocity accuracy, and tolerances above 1e-4 are refused.

mod common;

use common::blocks::momentum_x;
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

/// Large friction coefficients (issue 16 §2: μ = 1e3 and 1e6 failed the sliding block at
/// step 1). The 3-D local solve tries the exact stick solution first; the shipped block
/// (damped, h = 2e-4) launched at 1 m/s runs under Algorithm 2 with every μ of the
/// documented range's decades, 1 to 1e6, with no cap, and at μ = 1 its centre of mass
/// travels v0²/(2 μ g) within 1 % (measured 0.2 %). Three causes were removed, each
/// counted as data: from μ = 1e3 the combined rule's Newton loop cycled on the first
/// step (the round is redone with complementarity, `complementarity_fallbacks`); from
/// μ = 1e5 NSGS and PROX cycle (the dense Newton methods finish, `friction_fallbacks`);
/// and Siconos' residual multiplies the round-off of `u_T` by μ (the step loop stops on
/// the velocity residual, whose floor μ ε is the solve's tolerance where larger). From
/// μ = 10 on the base stops within the first 50 steps while the soft block (E = 1e7)
/// swings on: the centre of mass then ends 6–8 mm behind its start (the closed form of a
/// rigid block does not hold), so only the run is asserted there. That backward walk is
/// the soft block's rocking, not a solver's artefact: at h = 5e-5 Moreau–Jean and
/// Algorithms 1 and 2 agree on it (−14.7, −14.8 and −15.4 mm at μ = 10; −5.7, −5.4 and
/// −7.0 mm at μ = 1e6, measured).
#[test]
fn large_friction_coefficients_run_and_stop_at_v0_squared_over_2_mu_g() {
    for mu in [1.0, 10.0, 100.0, 300.0, 1e3, 1e4, 1e5, 1e6] {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/sliding_block.toml");
        let text = std::fs::read_to_string(path)
            .unwrap()
            .replace("friction = 0.3", &format!("friction = {mu:?}"))
            .replace("t_end = 0.4", "t_end = 0.12")
            .replace("times = [0.1, 0.2, 0.3, 0.4]", "times = [0.1]");
        let s = Scene::from_toml(&text).unwrap();
        let (model, _) = s.build().unwrap();
        let mut integ = model.into_integrator(&s.scheme, s.time.dt).unwrap();
        let h = s.time.dt;
        let (mut x, mut v, mut caps) = (0.0, 1.0, 0);
        let mass = momentum_x(integ.as_ref()).1;
        for _ in 0..s.steps() {
            caps += integ.step().unwrap().caps_hit;
            let vn = momentum_x(integ.as_ref()).0 / mass;
            x += 0.5 * (v + vn) * h;
            v = vn;
        }
        let d_ref = 1.0 / (2.0 * mu * 9.81);
        eprintln!(
            "μ = {mu}: caps {caps}, distance {x:.5e} m ({:+.2} %)",
            100.0 * (x / d_ref - 1.0)
        );
        assert_eq!(caps, 0, "μ = {mu}");
        if mu == 1.0 {
            assert!(
                (x / d_ref - 1.0).abs() < 0.01,
                "μ = {mu}: {x} m vs {d_ref} m"
            );
        }
    }
}
