//! The Hertz ball in the accuracy mode (issue 50): the axisymmetric steel ball of
//! `meshes/hertz_ball.toml` (Moreau–Jean) asked TOL = 1e-2 from a largest step of
//! 4e-7 s missed it silently: its contact impulse history in time was 4.2e-2 off a run at
//! 1/16 of its smallest step while every window's estimate stayed below 1e-2, and it
//! exited 0. The error is made inside the ball (its deformation under the contact) and
//! met at the contact later, which no comparison from one window's start sees. The run's
//! companion (one step per kept window from its own state: `accuracy.companion`) sees it;
//! the run now says it missed and exits 1.

use signorini::app::run_scene;
use signorini::run::Quiet;
use signorini::scene::file::Scene;
use signorini::study::sweep::{ForceTrace, impulse_difference_in_time};

fn hertz(set: &[&str]) -> signorini::run::RunResult {
    let mut s = Scene::from_file_with(
        std::path::Path::new("meshes/hertz_ball.toml"),
        &set.iter().map(|x| x.to_string()).collect::<Vec<_>>(),
    )
    .unwrap();
    s.output.plots = false;
    s.output.fields = false;
    run_scene(&s, None, &mut Quiet).unwrap()
}

/// `∫|P − P_ref| dt / (P_ref(T) T)` of `r` against `reference` (the promised measure).
fn impulse_in_time(r: &signorini::run::RunResult, reference: &signorini::run::RunResult) -> f64 {
    let t_end = r.summary.t_end;
    let total: f64 = reference.force.iter().sum::<f64>() * reference.summary.dt;
    impulse_difference_in_time(trace(r), trace(reference), t_end) / (total * t_end)
}

fn trace(x: &signorini::run::RunResult) -> ForceTrace<'_> {
    ForceTrace {
        force: &x.force,
        dt: &x.dt,
        h: x.summary.dt,
    }
}

#[test]
fn a_hertz_ball_that_misses_its_accuracy_says_so() {
    // the reference: the scene's own step, 2.5e-8 s, 4 times below the run's smallest
    let reference = hertz(&[]);
    for (tol, misses) in [(1e-2, true), (1e-1, false)] {
        let r = hertz(&[&format!("time.accuracy={tol:e}"), "time.dt=4e-7"]);
        let a = r.summary.accuracy.as_ref().expect("an accuracy summary");
        let achieved = impulse_in_time(&r, &reference);
        eprintln!(
            "TOL {tol:e}: achieved {achieved:.3e}, estimated {:?}",
            a.estimated
        );
        assert_eq!(
            achieved > tol,
            misses,
            "TOL {tol:e}: achieved {achieved:.3e}"
        );
        // the run's verdict matches what it reached, and its estimate is not below it
        assert_eq!(a.met, !misses, "TOL {tol:e}: {a:?}");
        assert!(
            a.estimated.largest() >= achieved,
            "TOL {tol:e}: {achieved:.3e} {a:?}"
        );
    }
}
