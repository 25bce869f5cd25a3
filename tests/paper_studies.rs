//! The paper's findings on the bouncing ball (eq. 7, Ballard's example), pinned through
//! the library functions behind `signorini study`. Tolerances: ±0.15 on fitted orders
//! and slopes (issue 5; the fits span h = 2.7e-4 … 1.4e-2, twelve steps). Every run
//! takes the paper's rules (`SchemeParams::paper_rules`, as the studies do): with the
//! default closure of its active set Algorithm 1 neither chatters after the accumulation
//! nor gains energy with e = 1, which is what the paper's findings are about.

use signorini::analytic::ball::BouncingBall;
use signorini::integrators::{Forecast, SchemeKind, SchemeParams};
use signorini::study::{
    STUDY_FORECAST, ball_run, chatter, chattering_cases, convergence_orders, projection_multipliers,
};

/// Fig. 2: position converges at order 1 in every norm; velocity at order 0 in the
/// uniform norm (an impact missed by a step leaves an O(1) error at one sample), 1 in
/// l1 and 1/2 in l2, for Moreau–Jean, Schatzman–Paoli and Algorithm 1, on the ball and
/// on the damped impacting oscillator (whose closed form is checked in
/// `analytic::oscillator`).
#[test]
fn convergence_orders_are_those_of_fig_2() {
    let (orders, _) = convergence_orders().unwrap();
    assert_eq!(orders.len(), 6);
    for o in orders {
        for (got, want) in o.q.iter().zip([1.0, 1.0, 1.0]) {
            assert!(
                (got - want).abs() <= 0.15,
                "{:?} position {:?}",
                o.kind,
                o.q
            );
        }
        for (got, want) in o.v.iter().zip([0.0, 1.0, 0.5]) {
            assert!(
                (got - want).abs() <= 0.15,
                "{:?} velocity {:?}",
                o.kind,
                o.v
            );
        }
    }
}

/// Fig. 3 and eq. 37: the projection multiplier of Algorithm 1 is O(h), on the ball
/// and on the oscillator.
#[test]
fn projection_multiplier_is_order_h() {
    let res = projection_multipliers().unwrap();
    assert_eq!(res.len(), 2);
    for (x, pts, slope) in res {
        assert!(
            pts.iter().all(|p| p.1 > 0.0),
            "{x}: τ must be used at every h"
        );
        assert!((slope - 1.0).abs() <= 0.15, "{x}: slope {slope}");
    }
}

/// Fig. 7: with e = 1 the position projection creates energy (it lifts a penetrated
/// ball back onto the line without touching its velocity); Moreau–Jean, which does not
/// project, conserves the energy to round-off (1e-12 relative), and Algorithm 2 creates
/// none (its activation closes the contact before the gap does).
#[test]
fn projection_creates_energy_in_the_elastic_case() {
    let b = BouncingBall {
        restitution: 1.0,
        ..BouncingBall::ballard()
    };
    let e0 = -b.force * b.q0;
    let max_energy = |kind, forecast| {
        let p = SchemeParams {
            kind,
            forecast,
            ..SchemeParams::default()
        }
        .paper_rules();
        let r = ball_run(&b, &p, 1e-2, 10.0).unwrap();
        (0..r.t.len())
            .map(|k| 0.5 * b.mass * r.v[k] * r.v[k] - b.force * r.q[k])
            .fold(f64::MIN, f64::max)
    };
    let a1 = max_energy(SchemeKind::DirectProjection, STUDY_FORECAST);
    assert!(a1 > 1.01 * e0, "Algorithm 1: {a1} J against {e0} J");
    let mj = max_energy(SchemeKind::MoreauJean, STUDY_FORECAST);
    assert!((mj / e0 - 1.0).abs() < 1e-12, "Moreau–Jean: {mj}");
    let a2 = max_energy(SchemeKind::CombinedProjection, Forecast::Free);
    assert!(a2 <= e0 * (1.0 + 1e-12), "Algorithm 2: {a2}");
}

/// Fig. 4 across the study's cases: every explicit forecast (γ = 0, 1, 2) chatters after
/// the accumulation at h = 5e-2; the free forecast and Algorithm 2 never switch again.
#[test]
fn chattering_study_cases() {
    let b = BouncingBall::ballard();
    for (label, kind, forecast) in chattering_cases() {
        let p = SchemeParams {
            kind,
            forecast,
            ..SchemeParams::default()
        }
        .paper_rules();
        let c = chatter(&ball_run(&b, &p, 5e-2, 10.0).unwrap(), 3.5);
        match forecast {
            Forecast::Explicit { .. } => assert!(c.switches > 50, "{label}: {c:?}"),
            Forecast::Free => {
                assert_eq!(c.switches, 0, "{label}: {c:?}");
                assert!(c.rest.is_some_and(|t| t <= 5.0), "{label}: {c:?}");
            }
        }
    }
}
