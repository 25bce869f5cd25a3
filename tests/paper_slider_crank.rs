//! The slider–crank of the paper's sec. 6.3.1 (Table 2, Table 3): a rigid multibody
//! system in minimal coordinates with a configuration-dependent mass, gyroscopic terms,
//! a nonsymmetric iteration matrix and four frictional corners whose gaps are nonlinear
//! in `q`. The h = 1e-4 row of Table 3 is pinned for each scheme, with the study's
//! settings (`signorini study slider-crank`, `src/study/slider_crank.rs`).

use signorini::integrators::SchemeKind;
use signorini::model::multibody::SliderCrankParams;
use signorini::study::slider_crank::{PAPER, SCHEMES, SPAN, params, run};

/// Table 3, h = 1e-4, J₂ = 8.9e-4 (the paper's Table 2).
///
/// - Moreau–Jean's violation is set by the fastest corner approach at an impact:
///   within a factor 1.25 of the paper's 1.324e-4 (measured here 1.334e-4, 0.8 % off;
///   the factor leaves room for the paper's unstated span and solver settings, which
///   move the impacts).
/// - The projected schemes keep every gap within the paper's violation tolerance 1e-10
///   (they project to round-off here: 1e-15).
/// - Newton iterations per step within a factor 2.5 of the paper's means (each code
///   counts and stops differently: 3.49, 3.26 and 4.24 here against 2.95, 1.96 and
///   2.15), and Algorithm 2's index-set iterations within 0.15 of 1.18 (1.27 here),
///   at most 2 as in the paper.
/// - Energy only decreases (impacts with e = 0.4 and friction; no energy created):
///   the final total is below the initial one, which is ½ q̇ᵀM(q)q̇ at q = 0 (8.3393 J).
#[test]
fn table3_rows_at_h_1e_4() {
    let mech = SliderCrankParams::default();
    for (si, &kind) in SCHEMES.iter().enumerate() {
        let r = run(&mech, &params(kind), 1e-4, SPAN).unwrap();
        let paper = PAPER[si][0];
        let (newton, _, index_set) = r.means();
        assert_eq!(r.steps, 2000);
        assert_eq!(r.caps, 0, "{}: no cap", kind.name());
        if kind == SchemeKind::MoreauJean {
            let ratio = r.violation / paper.violation;
            assert!(
                (0.8..1.25).contains(&ratio),
                "Moreau–Jean violation {:e} against the paper's {:e}",
                r.violation,
                paper.violation
            );
        } else {
            assert!(r.violation <= 1e-10, "{}: {:e}", kind.name(), r.violation);
        }
        let ratio = newton / paper.newton.0;
        assert!(
            (0.4..2.5).contains(&ratio),
            "{}: Newton {newton} per step against the paper's {}",
            kind.name(),
            paper.newton.0
        );
        if let Some((mean, max)) = paper.index_set {
            assert!((index_set - mean).abs() < 0.15, "index sets {index_set}");
            assert_eq!(r.index_set.1, max);
        }
        // the analytic kinetic energy at q = 0: ½(M₁₁θ̇₁² + 2M₁₂θ̇₁θ̇₂ + M₂₂θ̇₂²)
        let p = &mech;
        let m11 = p.j1 + (0.25 * p.m1 + p.m2 + p.m3) * p.l1 * p.l1;
        let m22 = p.j2 + (0.25 * p.m2 + p.m3) * p.l2 * p.l2;
        let m12 = (0.5 * p.m2 + p.m3) * p.l1 * p.l2;
        let (w1, w2) = (150.0, -75.0);
        let e0 = 0.5 * (m11 * w1 * w1 + 2.0 * m12 * w1 * w2 + m22 * w2 * w2);
        assert!(
            (r.energy.0 - e0).abs() < 1e-12 * e0,
            "{} vs {e0}",
            r.energy.0
        );
        assert!(r.energy.1 < r.energy.0, "{}: energy created", kind.name());
    }
}

/// Moreau–Jean's violation is O(h) (the paper: 1.324e-4 at 1e-4, 1.234e-5 at 1e-5):
/// dividing h by 10 divides it by 5 to 20 (15.3 measured; the largest impact velocity
/// shifts with the step).
#[test]
fn moreau_jean_violation_scales_with_h() {
    let mech = SliderCrankParams::default();
    let p = params(SchemeKind::MoreauJean);
    let coarse = run(&mech, &p, 1e-4, SPAN).unwrap().violation;
    let fine = run(&mech, &p, 1e-5, SPAN).unwrap().violation;
    let ratio = coarse / fine;
    assert!(
        (5.0..20.0).contains(&ratio),
        "{coarse:e} / {fine:e} = {ratio}"
    );
}

/// Without contact (clearance 0.5 m: the slider never reaches a guide) the mechanism is
/// conservative, and θ = 1/2 with `M(q_θ)` keeps its energy to second order: the largest
/// relative error over 0.2 s is below 2e-4 at h = 1e-4 (1.30e-4 measured) and falls by
/// 4 ± 0.5 when h is halved (3.98 measured). A wrong gyroscopic term or mass derivative
/// would drift at first order.
#[test]
fn free_mechanism_keeps_its_energy_to_second_order() {
    let mech = SliderCrankParams {
        c: 0.5,
        ..SliderCrankParams::default()
    };
    let drift = |h: f64| {
        let r = run(&mech, &params(SchemeKind::MoreauJean), h, SPAN).unwrap();
        assert!(r.samples.iter().all(|s| s.gap.iter().all(|&g| g > 0.0)));
        let sys = mech.system().unwrap();
        let e = |s: &signorini::study::slider_crank::Sample| {
            sys.kinetic_energy(&s.q, &s.v) + sys.potential_energy(&s.q)
        };
        let e0 = e(&r.samples[0]);
        r.samples
            .iter()
            .map(|s| (e(s) - e0).abs() / e0)
            .fold(0.0_f64, f64::max)
    };
    let (a, b) = (drift(1e-4), drift(5e-5));
    assert!(a < 2e-4, "{a:e}");
    assert!((3.5..4.5).contains(&(a / b)), "{a:e} / {b:e}");
}
