//! The bouncing ball of eq. 7 (Ballard's example: f = −2, m = 1, e = 1/2, q0 = 1,
//! v0 = 0) against its closed form, and the paper's finding on chattering (Fig. 4):
//! after the accumulation at t = 3, Algorithm 1 with the explicit forecast keeps
//! switching the contact, while Algorithm 2 and the free forecast bring the ball to rest.
//! These reproductions run the paper's rules ([`SchemeParams::paper_rules`]); the last
//! test holds the default rules (docs/bar.md, "Algorithm 2's position rule") to the same
//! closed form.

use signorini::analytic::ball::BouncingBall;
use signorini::contact::plane::NodesOnPlane;
use signorini::integrators::{self, Forecast, SchemeKind, SchemeParams};
use signorini::model::point_mass::point_mass;

struct Run {
    t: Vec<f64>,
    q: Vec<f64>,
    v: Vec<f64>,
    p: Vec<f64>,
}

fn run(kind: SchemeKind, forecast: Forecast, h: f64, t_end: f64) -> Run {
    let params = SchemeParams {
        kind,
        forecast,
        ..SchemeParams::default()
    }
    .paper_rules();
    run_with(&params, h, t_end)
}

fn run_with(params: &SchemeParams, h: f64, t_end: f64) -> Run {
    let b = BouncingBall::ballard();
    let sys = point_mass(1, b.mass, &[b.force]).unwrap();
    // gap = q0 + u (the reference position is the initial height)
    let contact = NodesOnPlane::new(
        vec![vec![0]],
        vec![vec![b.q0]],
        vec![1.0],
        0.0,
        b.restitution,
    )
    .unwrap();
    let mut integ = integrators::build(params, sys, Box::new(contact), &[0.0], &[b.v0], h).unwrap();
    let mut r = Run {
        t: vec![],
        q: vec![],
        v: vec![],
        p: vec![],
    };
    for _ in 0..(t_end / h).round() as usize {
        integ.step().unwrap();
        let s = integ.state();
        r.t.push(s.time);
        r.q.push(b.q0 + s.q[0]);
        r.v.push(s.v[0]);
        r.p.push(s.impulse[0]);
    }
    r
}

/// Contact switches (impulse turning positive or zero) after time `t0`.
fn switches_after(r: &Run, t0: f64) -> usize {
    let closed: Vec<bool> = r.p.iter().map(|&p| p > 0.0).collect();
    (1..closed.len())
        .filter(|&k| r.t[k] > t0 && closed[k] != closed[k - 1])
        .count()
}

/// Algorithm 2 follows the closed form: at h = 1e-3 the first impacts (t = 1, 2, 2.5,
/// 2.75) are caught in the step that contains them, the position is exact to O(h)
/// (1e-2 allows the impact's position within one step of a 2 m/s fall), the ball never
/// penetrates (projection to machine accuracy), and after t = 3.05 it is at rest.
#[test]
fn algorithm_2_follows_ballard_and_rests_after_the_accumulation() {
    let h = 1e-3;
    let r = run(SchemeKind::CombinedProjection, Forecast::Free, h, 5.0);
    let exact = BouncingBall::ballard();
    for t_imp in exact.impact_times(2.8, 4) {
        let k =
            r.p.iter()
                .enumerate()
                .position(|(k, &p)| p > 0.0 && r.t[k] >= t_imp - h);
        let k = k.unwrap();
        assert!(
            (r.t[k] - t_imp).abs() <= 2.0 * h,
            "impact at {t_imp}: step ends {}",
            r.t[k]
        );
    }
    for k in 0..r.t.len() {
        assert!(r.q[k] >= -1e-14, "penetration {} at t = {}", r.q[k], r.t[k]);
        let (qe, _) = exact.state(r.t[k]);
        if r.t[k] < 2.9 {
            assert!(
                (r.q[k] - qe).abs() < 1e-2,
                "t = {}: q {} vs {qe}",
                r.t[k],
                r.q[k]
            );
        }
        if r.t[k] > 3.05 {
            assert!(
                r.v[k].abs() <= 1e-10 && r.q[k].abs() <= 1e-12,
                "t = {}",
                r.t[k]
            );
            // resting: the impulse carries the weight, P = −f h
            assert!((r.p[k] - 2.0 * h).abs() < 1e-12, "P = {}", r.p[k]);
        }
    }
}

/// Fig. 4: at h = 5e-2 the direct projection with the explicit forecast (γ = 1)
/// chatters after the accumulation (it settles into a 2-step cycle, v = +1/30, −2/30,
/// with an impulse every other step); Algorithm 2 and Algorithm 1 with the free
/// forecast switch no more after t = 3.5 and come to rest.
///
/// What "rest" means in discrete time: the velocity-level law `U⁺ + e U⁻ ≥ 0` of
/// eq. 6 keeps the contact closed but lets the velocity alternate in sign, shrinking by
/// `e` per step (measured: |v| = 3.8e-7 at t = 3.5, 9.3e-11 at t = 4.1, round-off
/// 1.4e-17 from t = 5). So |v| ≤ 1e-10 holds from t = 4.2 on (t = 5.0 for Algorithm 1
/// with the free forecast, whose tail starts later), not from t = 3.5 as issue 5
/// states; the paper's Fig. 4 shows this tail below its plot resolution.
/// Algorithm 2 rests exactly on the line (q = 0 to 1e-15); Algorithm 1 with the free
/// forecast rests 6.1e-4 m above it (its velocity-level constraint is activated by the
/// forecast before the gap closes), which is O(h²) = 2.5e-3.
#[test]
fn explicit_forecast_chatters_where_algorithm_2_rests() {
    let h = 5e-2;
    let chat = run(
        SchemeKind::DirectProjection,
        Forecast::Explicit { gamma: 1.0 },
        h,
        10.0,
    );
    let n = switches_after(&chat, 3.5);
    assert!(
        n > 100,
        "Algorithm 1 with the explicit forecast should chatter: {n}"
    );
    // (scheme, forecast, largest resting gap, time from which |v| ≤ 1e-10)
    for (kind, forecast, rest_gap, rest_time) in [
        (SchemeKind::CombinedProjection, Forecast::Free, 1e-15, 4.2),
        (SchemeKind::DirectProjection, Forecast::Free, h * h, 5.0),
    ] {
        let r = run(kind, forecast, h, 10.0);
        assert_eq!(switches_after(&r, 3.5), 0, "{kind:?} switches after 3.5");
        for k in 1..r.t.len() {
            if r.t[k] > 3.5 {
                let (a, b) = (r.v[k].abs(), r.v[k - 1].abs());
                assert!(
                    a <= 0.5 * b + 1e-16,
                    "{kind:?} t = {}: |v| {a} after {b}",
                    r.t[k]
                );
                assert!(
                    r.q[k] >= -1e-15 && r.q[k] <= rest_gap,
                    "{kind:?} q = {}",
                    r.q[k]
                );
            }
            if r.t[k] > rest_time {
                assert!(
                    r.v[k].abs() <= 1e-10,
                    "{kind:?} t = {}: v = {}",
                    r.t[k],
                    r.v[k]
                );
            }
        }
    }
}

/// The default rules on Ballard's ball (h = 1e-3): a first impulse is not pulled onto
/// the ground (`ProjectionRule::Persistent`), so each bounce starts up to h|v|(1 − e)/2
/// above it (1.5e-3 m at the 2 m/s impact of t = 1, the largest position error measured
/// before the accumulation), and the impacts after it come late
/// by a few steps (measured: 1, 2 and 4 at t = 2, 2.5, 2.75; 5 allowed); a ball that separates and is caught again takes
/// e = 1 (`energy_consistent_restitution`). Still: never below the ground, the position
/// within 1e-2 of the closed form before the accumulation (as the paper's rules), at rest
/// on the ground exactly (q = 0 to 1e-12, the weight carried, P = 2h) from t = 3.1 on
/// (measured from 3.04), and the energy never above its start (1e-12).
#[test]
fn default_rules_follow_ballard_and_rest_on_the_ground() {
    let h = 1e-3;
    let params = SchemeParams::default();
    let r = run_with(&params, h, 5.0);
    let exact = BouncingBall::ballard();
    for t_imp in exact.impact_times(2.8, 4) {
        let k =
            r.p.iter()
                .enumerate()
                .position(|(k, &p)| p > 0.0 && r.t[k] >= t_imp - h)
                .unwrap();
        assert!(
            (r.t[k] - t_imp).abs() <= 5.0 * h + 1e-12,
            "impact at {t_imp}: step ends {}",
            r.t[k]
        );
    }
    let e0 = exact.q0 * 2.0;
    let mut worst: f64 = 0.0;
    for k in 0..r.t.len() {
        assert!(r.q[k] >= -1e-14, "penetration {} at t = {}", r.q[k], r.t[k]);
        let e = 0.5 * r.v[k] * r.v[k] + 2.0 * r.q[k];
        assert!(e <= e0 + 1e-12, "t = {}: energy {e} above {e0}", r.t[k]);
        let (qe, _) = exact.state(r.t[k]);
        if r.t[k] < 2.9 {
            worst = worst.max((r.q[k] - qe).abs());
            assert!(
                (r.q[k] - qe).abs() < 1e-2,
                "t = {}: q {} vs {qe}",
                r.t[k],
                r.q[k]
            );
        }
        if r.t[k] > 3.1 {
            assert!(
                r.v[k].abs() <= 1e-10 && r.q[k].abs() <= 1e-12,
                "t = {}: q {} v {}",
                r.t[k],
                r.q[k],
                r.v[k]
            );
            assert!((r.p[k] - 2.0 * h).abs() < 1e-12, "P = {}", r.p[k]);
        }
    }
    let rest = (0..r.t.len())
        .find(|&k| (k..r.t.len()).all(|j| r.v[j].abs() <= 1e-10 && r.q[j].abs() <= 1e-12))
        .map_or(f64::NAN, |k| r.t[k]);
    eprintln!(
        "default rules: largest position error before 2.9 {worst:.3e} m, at rest from {rest}"
    );
}
