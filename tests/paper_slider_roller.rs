//! The paper's slider and roller (sec. 4.5, Fig. 8; issue 11 §5). The figure is lost, so
//! the set-up is derived from the text and chosen here:
//!
//! - a roller of radius R = 1 m turning about its fixed axis (angle φ, inertia
//!   J = 0.5 kg·m², a uniform disk of 1 kg) under a torque Γ;
//! - a slider of mass m = 1 kg guided vertically above it (height y of its flat bottom),
//!   under gravity g = 9.81, dropped from 5 cm above the roller's top;
//! - one contact at the top of the roller: gap `y − R`, normal row [1, 0], tangential row
//!   [0, −R] (the slip velocity is the roller's surface speed), Newton's law e = 0.5,
//!   Coulomb μ = 0.3. The guide takes the friction force on the slider.
//!
//! Static equilibrium (slider resting, roller held by friction) exists iff
//! `Γ ≤ μ m g R` (the text's "torque less than μmg" at R = 1). With Γ = μ m g R / 2:
//! Moreau–Jean and Algorithm 2 reach it (after the bounces accumulate, about 0.3 s, the
//! roller stops and stays stopped: |φ̇| ≤ 1e-9 rad/s over the last second, the contact
//! stuck); Algorithm 1 with the explicit forecast (γ = 0, the index set of the paper's
//! analysis; with the free forecast it settles too, as for the bouncing ball) keeps the
//! slider bouncing, and every flight lets the roller slip: it never stops. Above the
//! limit (Γ = 1.5 μ m g R) the roller slips under the resting slider with angular
//! acceleration (Γ − μ m g R)/J, within 1 %. The runs take the paper's rules
//! (`SchemeParams::paper_rules`): with the default closure of its active set Algorithm 1
//! no longer bounces here.

use signorini::contact::linear::{LinearContact, LinearContacts};
use signorini::contact::{ContactLaw, ContactStatus};
use signorini::integrators::{self, Forecast, Integrator, SchemeKind, SchemeParams};
use signorini::model::point_mass::diagonal;

const G: f64 = 9.81;
const MU: f64 = 0.3;
const J: f64 = 0.5;

fn build(kind: SchemeKind, forecast: Forecast, torque: f64, h: f64) -> Box<dyn Integrator> {
    let sys = diagonal(&[1.0, J], &[-G, torque]).unwrap();
    let c = LinearContacts::new(vec![LinearContact {
        dofs: vec![0, 1],
        offset: -1.0,
        normal: vec![1.0, 0.0],
        tangents: vec![vec![0.0, -1.0]],
        law: ContactLaw {
            restitution: 0.5,
            friction: MU,
        },
    }])
    .unwrap();
    let p = SchemeParams {
        kind,
        forecast,
        ..SchemeParams::default()
    }
    .paper_rules();
    integrators::build(&p, sys, Box::new(c), &[1.05, 0.0], &[0.0, 0.0], h).unwrap()
}

/// Runs to `t_end`; returns (largest |φ̇| over the last second, open steps over the last
/// second, final status).
fn run(integ: &mut dyn Integrator, t_end: f64) -> (f64, usize, ContactStatus) {
    let (mut wmax, mut open) = (0.0_f64, 0);
    while integ.state().time < t_end - 1e-12 {
        integ.step().unwrap();
        let s = integ.state();
        if s.time > t_end - 1.0 {
            wmax = wmax.max(s.v[1].abs());
            if s.impulse[0] <= 0.0 {
                open += 1;
            }
        }
    }
    (wmax, open, integ.state().status[0])
}

#[test]
fn below_the_friction_limit_moreau_jean_and_algorithm_2_reach_static_equilibrium() {
    let torque = 0.5 * MU * G;
    for kind in [SchemeKind::MoreauJean, SchemeKind::CombinedProjection] {
        let mut integ = build(kind, Forecast::Free, torque, 1e-3);
        let (wmax, open, status) = run(integ.as_mut(), 3.0);
        assert!(
            wmax <= 1e-9,
            "{kind:?}: roller still turns at {wmax:e} rad/s"
        );
        assert_eq!(open, 0, "{kind:?}: the slider still leaves the roller");
        assert_eq!(status, ContactStatus::Stick, "{kind:?}");
        let s = integ.state();
        // resting: the normal impulse carries the weight, friction the torque
        let h = integ.dt();
        assert!((s.impulse[0] / (G * h) - 1.0).abs() < 1e-9, "{kind:?}");
        assert!(
            (s.tangent_impulse[0].abs() / (h * torque) - 1.0).abs() < 1e-9,
            "{kind:?}"
        );
        if kind == SchemeKind::CombinedProjection {
            assert!(s.gap[0].abs() <= 1e-12, "gap {}", s.gap[0]);
        }
    }
}

#[test]
fn algorithm_1_with_the_explicit_forecast_keeps_bouncing_and_slipping() {
    let torque = 0.5 * MU * G;
    let mut integ = build(
        SchemeKind::DirectProjection,
        Forecast::Explicit { gamma: 0.0 },
        torque,
        1e-3,
    );
    let (wmax, open, _) = run(integ.as_mut(), 3.0);
    assert!(open > 10, "only {open} open steps in the last second");
    assert!(wmax > 1e-3, "the roller stopped ({wmax:e} rad/s)");
}

#[test]
fn above_the_friction_limit_the_roller_slips_at_the_coulomb_rate() {
    let torque = 1.5 * MU * G;
    for kind in [SchemeKind::MoreauJean, SchemeKind::CombinedProjection] {
        let mut integ = build(kind, Forecast::Free, torque, 1e-3);
        run(integ.as_mut(), 2.0);
        let w1 = integ.state().v[1];
        run(integ.as_mut(), 3.0);
        let w2 = integ.state().v[1];
        let want = (torque - MU * G) / J;
        assert!(
            ((w2 - w1) / want - 1.0).abs() < 0.01,
            "{kind:?}: {} rad/s² (want {want})",
            w2 - w1
        );
        assert_eq!(integ.state().status[0], ContactStatus::Slip);
    }
}

/// Algorithm 1 with the free forecast (eq. 62, the default) settles like Moreau–Jean: the
/// chattering is the explicit forecast's, as on the bouncing ball (`study chattering`).
#[test]
fn algorithm_1_with_the_free_forecast_settles() {
    let mut integ = build(
        SchemeKind::DirectProjection,
        Forecast::Free,
        0.5 * MU * G,
        1e-3,
    );
    let (wmax, open, status) = run(integ.as_mut(), 3.0);
    assert!(wmax <= 1e-9 && open == 0, "|φ̇| {wmax:e}, {open} open steps");
    assert_eq!(status, ContactStatus::Stick);
}
