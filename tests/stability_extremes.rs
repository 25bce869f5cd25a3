//! Every scheme at the extremes the brief names: one element, tiny and huge time
//! steps (Courant numbers from 4e-7 to 5e3), soft and stiff materials, e = 0 and
//! e = 1. Each run must finish without a cap, with finite results, no energy growth,
//! and the projection schemes without penetration.

use signorini::integrators::SchemeKind;
use signorini::run::{Quiet, run_bar};
use signorini::scene::bar::BarScene;

fn cases() -> Vec<(&'static str, BarScene)> {
    let base = BarScene::default();
    vec![
        (
            "one element",
            BarScene {
                elements: 1,
                dt: 1e-5,
                ..base.clone()
            },
        ),
        (
            "tiny step",
            BarScene {
                elements: 10,
                dt: 1e-12,
                t_end: 1e-8,
                ..base.clone()
            },
        ),
        (
            "huge step",
            BarScene {
                elements: 1000,
                dt: 1e-3,
                t_end: 0.1,
                ..base.clone()
            },
        ),
        (
            "elastic impact",
            BarScene {
                dt: 1e-6,
                restitution: 1.0,
                ..base.clone()
            },
        ),
        (
            "soft material",
            BarScene {
                elements: 100,
                dt: 1e-2,
                t_end: 10.0,
                young: 1e3,
                ..base.clone()
            },
        ),
        (
            "stiff material",
            BarScene {
                elements: 100,
                dt: 1e-9,
                t_end: 1e-5,
                young: 1e15,
                ..base.clone()
            },
        ),
    ]
}

#[test]
fn every_scheme_is_stable_at_the_extremes() {
    for kind in SchemeKind::ALL {
        for (name, mut s) in cases() {
            s.scheme.kind = kind;
            let r = run_bar(&s, None, &mut Quiet)
                .unwrap_or_else(|e| panic!("{} / {name}: {e}", kind.name()));
            let sm = &r.summary;
            let what = format!("{} / {name}", kind.name());
            assert_eq!(sm.caps_hit, 0, "{what}: caps hit");
            assert!(
                r.force.iter().all(|f| f.is_finite()),
                "{what}: non-finite force"
            );
            let [e0, e1] = sm.energy;
            // θ = 1/2 conserves the bulk energy and the impact law with e ≤ 1 only
            // dissipates; projection may add O(h) (Fig. 7), never seen above 1e-9 here.
            assert!(
                e1.is_finite() && e1 <= e0 * (1.0 + 1e-6),
                "{what}: energy {e0} -> {e1}"
            );
            if matches!(
                kind,
                SchemeKind::DirectProjection | SchemeKind::CombinedProjection
            ) {
                assert!(
                    sm.max_violation <= 1e-14,
                    "{what}: violation {}",
                    sm.max_violation
                );
            }
        }
    }
}

#[test]
fn resolved_soft_and_stiff_bars_carry_the_analytic_force() {
    // Courant numbers 0.36 and 0.036: well resolved, so the plateau is within 1 %.
    for (name, s) in cases().into_iter().filter(|(n, _)| n.ends_with("material")) {
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
