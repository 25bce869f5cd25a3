//! Issue 16 §1: Algorithms 1 and 2 on undamped frictional elastic contact.
//!
//! The undamped hex8 block (10 × 10 × 5 cm, E = 1e8 Pa, ν = 0, ρ = 1000 kg/m³, 4 × 4 × 2
//! cells) launched at 1 m/s on a rigid plane with μ = 0.3: its centre of mass decelerates
//! at μ g and stops after v0/(μ g) = 0.3398 s, v0²/(2 μ g) = 0.1699 m.
//!
//! Before this test, Algorithm 2 stopped at step 2 373 of h = 1e-4 at the Newton cap:
//! the decoupled iteration of eq. 56–58 contracts by (ωhθ)²/(1 + (ωhθ)²) per iteration
//! on a mode of frequency ω (0.74 there, 0.97 at h = 5e-4), and equality rows dropped at
//! selection were never reconsidered when the projection of their neighbours moved them
//! (violations of 7e-8 m and cycling at h = 1e-5). The coupled position solve, the
//! reconsidered equality rows and a friction-aware tolerance (module doc of
//! `integrators::core`) remove both. Where the combined rule (eq. 67–70) still capped
//! (4 caps in 900 steps at h = 5e-4) or ended with rows held at g = 0 with P = 0 and
//! τ < 0 (5 steps of 4 056 at h = 1e-4), the index-set round is redone with Algorithm
//! 1's rule `0 ≤ g ⊥ τ ≥ 0` (`StepStats::complementarity_fallbacks`): no cap, and τ ≥ 0
//! wherever the final P is 0 (`held_rows` = 0, asserted) on every step below.

mod common;

use common::blocks::{momentum_x, undamped_block};
use signorini::integrators::{Integrator, SchemeKind};
use signorini::scene::file::Scene;

const G: f64 = 9.81;
const MU: f64 = 0.3;

fn block(kind: SchemeKind, h: f64, theta: f64) -> Box<dyn Integrator> {
    let scene = Scene::from_toml(&undamped_block(h, 0.45, kind.name(), theta, MU)).unwrap();
    let (model, _) = scene.build().unwrap();
    model.into_integrator(&scene.scheme, scene.time.dt).unwrap()
}

/// What a slide to t = 0.45 s measured.
struct Slide {
    /// Stop time: the crossing of 0.1 v0 plus 0.1 v0/(μ g) (NaN: no crossing). After that the undamped
    /// block's elastic vibration dominates the centre-of-mass speed, whose first drop
    /// below 1e-3 v0 then moves by up to 10 % between schemes.
    stop: f64,
    /// Distance travelled by the centre of mass (m).
    distance: f64,
    caps: usize,
    violation: f64,
    newton_max: usize,
    held_steps: usize,
    fallbacks: usize,
}

fn slide(kind: SchemeKind, h: f64, theta: f64) -> Slide {
    let mut integ = block(kind, h, theta);
    let (_, mass) = momentum_x(integ.as_ref());
    let (mut x, mut v, mut t10) = (0.0, 1.0, None);
    let mut out = Slide {
        stop: 0.0,
        distance: 0.0,
        caps: 0,
        violation: 0.0,
        newton_max: 0,
        held_steps: 0,
        fallbacks: 0,
    };
    while integ.state().time < 0.45 - 0.5 * h {
        let st = integ.step().unwrap();
        out.caps += st.caps_hit;
        out.violation = out.violation.max(st.max_violation);
        out.newton_max = out.newton_max.max(st.newton_iterations);
        out.held_steps += usize::from(st.held_rows > 0);
        out.fallbacks += st.complementarity_fallbacks;
        let vn = momentum_x(integ.as_ref()).0 / mass;
        x += 0.5 * (v + vn) * h;
        v = vn;
        if v <= 0.1 && t10.is_none() {
            t10 = Some(integ.state().time - 0.5 * h);
        }
    }
    // NaN when the block never slowed below 0.1 v0 (Algorithm 1 at h = 5e-4)
    out.stop = t10.map_or(f64::NAN, |t| t + 0.1 / (MU * G));
    out.distance = x;
    eprintln!(
        "{kind:?} h = {h:e} θ = {theta}: stop {:.5} s ({:+.3} %), distance {:.5} m ({:+.3} %), \
         caps {}, violation {:.2e} m, Newton max {}, steps with held rows {}, fallbacks {}",
        out.stop,
        100.0 * (out.stop * MU * G - 1.0),
        out.distance,
        100.0 * (out.distance * 2.0 * MU * G - 1.0),
        out.caps,
        out.violation,
        out.newton_max,
        out.held_steps,
        out.fallbacks
    );
    out
}

fn check(kind: SchemeKind, h: f64, theta: f64, tol: f64) {
    let (t_ref, d_ref) = (1.0 / (MU * G), 1.0 / (2.0 * MU * G));
    let s = slide(kind, h, theta);
    assert_eq!(s.caps, 0, "{kind:?} h = {h}: caps");
    assert_eq!(
        s.held_steps, 0,
        "{kind:?} h = {h}: steps with τ < 0 where P = 0"
    );
    if kind != SchemeKind::MoreauJean {
        assert!(
            s.violation <= 1e-12,
            "{kind:?} h = {h}: violation {:e} m",
            s.violation
        );
    }
    assert!(
        (s.stop / t_ref - 1.0).abs() < tol && (s.distance / d_ref - 1.0).abs() < tol,
        "{kind:?} h = {h}: stop {} s (analytic {t_ref}), distance {} m (analytic {d_ref})",
        s.stop,
        s.distance
    );
}

/// h = 1e-5 (34 000 steps): Algorithms 1 and 2 finish with no cap and stop at the
/// closed form within 1 % (the issue's tolerance; measured 0.1–0.2 %, Moreau–Jean 0.12 %).
#[test]
fn fine_steps_finish_without_caps_and_stop_at_v0_over_mu_g() {
    for kind in [SchemeKind::DirectProjection, SchemeKind::CombinedProjection] {
        check(kind, 1e-5, 0.5, 0.01);
    }
}

/// h = 1e-4, the issue's case: every scheme finishes with no cap. Algorithm 2 (default
/// rules, issue 33) slides 0.77 % too far (1 % asserted; under the paper's rules 1.2 %,
/// 38 complementarity rounds: undamped, it left 6 times more vibration energy in the
/// block than Moreau–Jean, and the rocking lowers the mean friction). Moreau–Jean slides
/// 0.76 % too far (1 % asserted; 0.15 % under the paper's rules: a base node caught
/// while lifting off now takes e = 1 instead of 0, which adds no energy but keeps the
/// vibration the e = 0 catch dissipated). Algorithm 1 within 0.71 % (2 % asserted: under
/// the paper's rules it chatters, sec. 4.4, and lands within 0.8–1.2 % depending on its
/// iterates' path). With
/// θ = 0.6, whose dissipation damps the vibration, Algorithm 2 stops at the closed form
/// within 0.01 % (0.1 % asserted).
#[test]
fn issue_step_finishes_without_caps_under_every_scheme() {
    check(SchemeKind::MoreauJean, 1e-4, 0.5, 0.01);
    check(SchemeKind::DirectProjection, 1e-4, 0.5, 0.02);
    check(SchemeKind::CombinedProjection, 1e-4, 0.5, 0.01);
    check(SchemeKind::CombinedProjection, 1e-4, 0.6, 0.001);
}

/// h = 2e-4 and 5e-4: the highest modes have ωhθ of 2.5 and 6 (the decoupled iteration
/// alone contracts by 0.86 and 0.97 per iteration). Algorithms 1 and 2 finish with no
/// cap and no violation at both steps. The accuracy is the step's: Moreau–Jean itself
/// slides 4.8 % and 6.6 % too far there, so only a loose 10 % on Algorithm 2 (measured
/// 0.44 % and 0.18 %). Algorithm 2 at 5e-4 hit 4 caps in 900 steps where eq. 65 has no
/// solution for the index set; those rounds are now redone with complementarity (7 in
/// the run; docs/friction.md, "Algorithm 2 with friction").
#[test]
fn coarse_steps_finish_without_caps_under_the_projection_schemes() {
    for (h, kind) in [
        (2e-4, SchemeKind::DirectProjection),
        (2e-4, SchemeKind::CombinedProjection),
        (5e-4, SchemeKind::DirectProjection),
        (5e-4, SchemeKind::CombinedProjection),
    ] {
        let s = slide(kind, h, 0.5);
        assert_eq!(s.caps, 0, "{kind:?} h = {h}: caps");
        assert_eq!(
            s.held_steps, 0,
            "{kind:?} h = {h}: steps with τ < 0 where P = 0"
        );
        assert!(
            s.violation <= 1e-12,
            "{kind:?} h = {h}: violation {:e}",
            s.violation
        );
        if kind == SchemeKind::CombinedProjection {
            let d_ref = 1.0 / (2.0 * MU * G);
            assert!(
                (s.distance / d_ref - 1.0).abs() < 0.1,
                "h = {h}: {}",
                s.distance
            );
        }
    }
}
