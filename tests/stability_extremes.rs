//! Every scheme at the extremes the brief names: one element, tiny and huge time
//! steps (Courant numbers from 5e-8 to 5e3), soft and stiff materials, e = 0 and
//! e = 1. Each run must finish without a cap, with finite results, no energy growth,
//! and the projection schemes without penetration.

use signorini::app::run_bar;
use signorini::integrators::SchemeKind;
use signorini::run::Quiet;
use signorini::scene::bar::BarScene;
use signorini::study::bar::{extreme_cases, extreme_failure};

/// The extremes of `signorini study extremes` that fit the test budget (all but the
/// 10⁶-element bar, which the study runs).
fn cases() -> Vec<(&'static str, BarScene)> {
    extreme_cases()
        .into_iter()
        .filter(|(_, s)| s.elements <= 1000)
        .collect()
}

/// Each run must finish without a cap, with finite forces, with no energy growth
/// beyond 1e-6 (θ = 1/2 conserves the bulk energy and the impact law with e ≤ 1 only
/// dissipates; projection may add O(h), Fig. 7, never seen above 1e-9 here) and the
/// projection schemes without penetration beyond 1e-14 m ([`extreme_failure`]).
#[test]
fn every_scheme_is_stable_at_the_extremes() {
    assert_eq!(cases().len(), extreme_cases().len() - 1);
    for kind in SchemeKind::ALL {
        for (name, mut s) in cases() {
            s.scheme.kind = kind;
            let r = run_bar(&s, None, &mut Quiet)
                .unwrap_or_else(|e| panic!("{} / {name}: {e}", kind.name()));
            if let Some(f) = extreme_failure(kind, &r.summary, &r.force) {
                panic!("{} / {name}: {f}", kind.name());
            }
        }
    }
}

#[test]
fn resolved_soft_and_stiff_bars_carry_the_analytic_force() {
    // Courant numbers 0.36 and 0.036: well resolved, so the plateau is within 1 %.
    for (name, s) in cases().into_iter().filter(|(n, _)| n.contains("material")) {
        for kind in [SchemeKind::MoreauJean, SchemeKind::CombinedProjection] {
            let mut s = s.clone();
            s.scheme.kind = kind;
            let c = run_bar(&s, None, &mut Quiet)
                .unwrap()
                .summary
                .contact
                .unwrap();
            let rel = c.plateau_force / c.analytic_force - 1.0;
            assert!(rel.abs() < 0.01, "{name} {}: {rel}", kind.name());
        }
    }
}

fn scene_path(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("meshes")
        .join(name)
}

/// `signorini study extremes SCENE` (issue 33 §5) on the committed bar scene: the 13
/// cells of the default scheme (step ×1/8 … ×8, e = 0 and 1, θ = 1/2 and 1, stiffness
/// ×1e-3 and ×1e3) are all `stable`, and the study writes its table and plot.
#[test]
fn scene_extremes_of_the_default_scheme_are_stable_on_the_bar_scene() {
    let dir = std::env::temp_dir().join(format!("signorini-extremes-{}", std::process::id()));
    let v = signorini::study::run_on_scene(
        "extremes",
        &scene_path("bar.toml"),
        &[],
        &[SchemeKind::CombinedProjection],
        &[],
        &dir,
    )
    .unwrap();
    assert_eq!(v.len(), 13, "{v:?}");
    for line in &v {
        assert!(line.contains(": stable ("), "{line}");
    }
    let csv = std::fs::read_to_string(dir.join("extremes.csv")).unwrap();
    assert_eq!(csv.lines().count(), 14);
    assert!(dir.join("extremes-energy.png").is_file());
    let _ = std::fs::remove_dir_all(&dir);
}

/// The verdicts name what failed: the paper's rules on the Hertz ball at 4× its step
/// gain energy (the run stops on the energy check: `energy gain`, issue 33), and
/// Schatzman–Paoli refuses friction (`not applicable`, with why).
#[test]
fn scene_extremes_verdicts_name_what_failed() {
    use signorini::scene::file::Scene;
    use signorini::study::extremes::{Extreme, Verdict, run_cell};
    let o: Vec<String> = [
        "scheme.projection_rule=\"paper\"",
        "scheme.energy_consistent_restitution=false",
        "time.t_end=4e-5",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let hertz = Scene::from_file_with(&scene_path("hertz_ball.toml"), &o).unwrap();
    let c = run_cell(&hertz, Extreme::Step(4.0), SchemeKind::CombinedProjection);
    assert_eq!(c.verdict, Verdict::EnergyGain, "{c:?}");
    // refused while the integrator is built: the scene's own end time costs nothing
    let slide = Scene::from_file(&scene_path("sliding_block.toml")).unwrap();
    let c = run_cell(&slide, Extreme::Step(1.0), SchemeKind::SchatzmanPaoli);
    assert_eq!(c.verdict, Verdict::NotApplicable, "{c:?}");
    assert!(c.detail.contains("friction"), "{}", c.detail);
}

/// Issue 48: `study extremes` on the paper's examples reported the `h×1` cell's numbers
/// under the labels `e=0`, `e=1`, `E×1e-3` and `E×1e3`, which it never applied. Now the
/// restitution is the example's own key, the oscillator's spring stiffness is its
/// modulus, and the rigid examples' `E×` cells are `not applicable` with the reason. The
/// bouncing ball at e = 1 (Ballard's f = −2, q0 = 1) keeps bouncing: after `t_end = 5 s`
/// it is in flight, never at the rest at q = 0 that e = ½ reaches at t = 3 (closed form).
#[test]
fn scene_extremes_apply_every_cell_they_report_on_the_examples() {
    use signorini::scene::example::ExampleSpec;
    use signorini::scene::file::Scene;
    use signorini::study::extremes::{Extreme, Verdict, run_cell};
    let ball = Scene::from_file(&scene_path("bouncing_ball.toml")).unwrap();
    let elastic = Extreme::Restitution(1.0).apply(&ball).unwrap();
    match elastic.example {
        Some(ExampleSpec::BouncingBall { restitution, .. }) => assert_eq!(restitution, 1.0),
        ref e => panic!("{e:?}"),
    }
    let r = signorini::app::run_scene(&elastic, None, &mut Quiet).unwrap();
    let q_end = r.state.q[0];
    assert!(q_end > 1e-3, "e = 1 came to rest: q = {q_end}");
    let c = run_cell(
        &ball,
        Extreme::Stiffness(1e3),
        SchemeKind::CombinedProjection,
    );
    assert_eq!(c.verdict, Verdict::NotApplicable, "{c:?}");
    assert!(c.detail.contains("rigid"), "{}", c.detail);
    let osc = Scene::from_file(&scene_path("oscillator.toml")).unwrap();
    match Extreme::Stiffness(1e3).apply(&osc).unwrap().example {
        Some(ExampleSpec::Oscillator { stiffness, .. }) => {
            let k = 4.0 * std::f64::consts::PI * std::f64::consts::PI * 1e3;
            assert!((stiffness - k).abs() <= 1e-12 * k, "{stiffness}");
        }
        ref e => panic!("{e:?}"),
    }
}
