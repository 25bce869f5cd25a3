//! The force oscillations of sec. 6.2 and DESIGN.md §3 on the bar (N = 1000).
//!
//! Measured at h = 5e-6 (std of the force over the middle 80 % of the contact):
//! Moreau–Jean 4.7 N; Algorithm 2 with the `M̂⁻¹` metric 3.3 N; Euclidean metric 11 N
//! with the velocity feedback of eq. 56a and 229 N without it (Siconos' practice,
//! which DESIGN.md reports at 229 N); trapezoidal rule with position-level contact
//! (Fig. 11) 280 N at h = 5e-7.

use signorini::app::run_bar;
use signorini::integrators::{Metric, SchemeKind};
use signorini::run::Quiet;
use signorini::scene::bar::BarScene;

fn plateau_std(kind: SchemeKind, dt: f64, f: impl FnOnce(&mut BarScene)) -> f64 {
    let mut s = BarScene {
        dt,
        t_end: 1e-3,
        ..BarScene::default()
    };
    s.scheme.kind = kind;
    f(&mut s);
    let r = run_bar(&s, None, &mut Quiet).unwrap();
    r.summary.contact.unwrap().plateau_std
}

#[test]
fn mass_metric_projection_is_no_noisier_than_moreau_jean() {
    let mj = plateau_std(SchemeKind::MoreauJean, 5e-6, |_| {});
    let mass = plateau_std(SchemeKind::CombinedProjection, 5e-6, |_| {});
    eprintln!("std: MJ {mj} N, Algorithm 2 (M̂⁻¹) {mass} N");
    assert!(mass <= mj, "M̂⁻¹ metric {mass} N vs Moreau–Jean {mj} N");
}

#[test]
fn euclidean_projection_excites_the_highest_modes() {
    let mass = plateau_std(SchemeKind::CombinedProjection, 5e-6, |_| {});
    let euclid = plateau_std(SchemeKind::CombinedProjection, 5e-6, |s| {
        s.scheme.metric = Metric::Euclidean
    });
    // Siconos' practice kicks the tip node: the bar gains 15 % of its energy by step 64,
    // which the run's energy check refuses (exit 1) unless the scene accepts it
    let siconos = plateau_std(SchemeKind::CombinedProjection, 5e-6, |s| {
        s.scheme.metric = Metric::Euclidean;
        s.scheme.projection_feedback = false;
        s.scheme.max_energy_excess = Some(f64::INFINITY);
    });
    let mut refused = BarScene {
        dt: 5e-6,
        t_end: 1e-3,
        ..BarScene::default()
    };
    refused.scheme.metric = Metric::Euclidean;
    refused.scheme.projection_feedback = false;
    let Err(e) = run_bar(&refused, None, &mut Quiet) else {
        panic!("the energy gained without feedback was accepted");
    };
    assert!(e.to_string().contains("the energy grew by"), "{e}");
    eprintln!("std: M̂⁻¹ {mass} N, Euclidean {euclid} N, Euclidean without feedback {siconos} N");
    // The tip kick of the Euclidean projection shows in the force (measured 3.4×).
    assert!(euclid > 2.0 * mass, "{euclid} vs {mass}");
    // Without the eq. 56a feedback the kick is undamped: DESIGN.md's 229 N, within 10 %.
    assert!((siconos / 229.0 - 1.0).abs() < 0.1, "{siconos}");
}

#[test]
fn trapezoid_with_position_contact_oscillates_fig_11() {
    let mj = plateau_std(SchemeKind::MoreauJean, 5e-7, |_| {});
    let tr = plateau_std(SchemeKind::TrapezoidPosition, 5e-7, |_| {});
    eprintln!("std: MJ {mj} N, trapezoid {tr} N");
    // Fig. 11: the index-3 position constraint makes the force jump step to step,
    // by hundreds of newtons, where Moreau–Jean is flat to a fraction of a newton.
    assert!(tr > 100.0 && tr > 1000.0 * mj, "{tr} vs {mj}");
}
