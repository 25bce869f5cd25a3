//! Hertz impact (issue 17 §2, check (d)): a steel ball (R = 1 cm, E = 210 GPa, ν = 0.3,
//! ρ = 7800 kg/m³) at 1 m/s onto a rigid plane, `meshes/hertz_ball.toml`: an
//! axisymmetric quad4 section graded to 4e-5 m at the pole (a tenth of the contact radius
//! a = √(R δ_max) = 4.2e-4 m), Moreau–Jean with e = 0 at the nodes.
//!
//! Hertz (quasi-static, frictionless): `E* = E/(1 − ν²)`,
//! `δ_max = (15 m v² / (16 E* √R))^{2/5}`, `F_max = (4/3) E* √R δ_max^{3/2}`,
//! `t_c = 2.9432 δ_max / v`: 2300.9 N and 5.224e-5 s with m = (4/3)πR³ρ. The issue asks
//! for both within 3 %. Measured (docs/scenes.md, "Hertz impact"): on this mesh at h = 2.5e-8 s
//! the peak force is 1.86 % above and the contact 1.80 % shorter; halving the pole size
//! twice moves them by 0.4 %, while the step matters more (6.2 % at h = 1e-7, 3.2 % at
//! 5e-8, 2.2 % at 2.5e-8, 1.9 % at 1.25e-8 on the 2 655-node mesh): the discrete
//! contact is stiffer by an amount that falls with h, which this test also pins.

use std::path::Path;

use signorini::integrators::{Integrator, StepStats};
use signorini::scene::file::Scene;

const R: f64 = 0.01;
const RHO: f64 = 7800.0;

/// Hertz's peak force (N) and contact time (s) for the ball at 1 m/s.
fn hertz() -> (f64, f64) {
    let (e, nu, v) = (210e9, 0.3, 1.0);
    let m = 4.0 / 3.0 * std::f64::consts::PI * R.powi(3) * RHO;
    let es = e / (1.0 - nu * nu);
    let delta = (15.0 * m * v * v / (16.0 * es * R.sqrt())).powf(0.4);
    (
        4.0 / 3.0 * es * R.sqrt() * delta.powf(1.5),
        2.9432 * delta / v,
    )
}

/// Peak total contact force, contact duration (first to last step with a force), kinetic
/// energy before and after, at step `h`.
fn impact(h: f64) -> (f64, f64, f64, f64) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/hertz_ball.toml");
    let mut scene = Scene::from_file(&path).unwrap();
    scene.time.dt = h;
    run_impact(&scene, "hertz_ball.toml")
}

/// [`impact`]'s four figures for `scene`, every step without a cap.
fn run_impact(scene: &Scene, name: &str) -> (f64, f64, f64, f64) {
    let h = scene.time.dt;
    let (model, _) = scene.build().unwrap();
    let mut integ = model.into_integrator(&scene.scheme, h).unwrap();
    let kinetic = |i: &dyn Integrator| {
        let s = i.state();
        i.system().kinetic_energy(&s.q, &s.v)
    };
    let e0 = kinetic(integ.as_ref());
    let (mut peak, mut first, mut last) = (0.0_f64, None, 0.0);
    for _ in 0..scene.steps() {
        integ.prepare().unwrap();
        let st: StepStats = integ.step().unwrap();
        assert_eq!(st.caps_hit, 0, "{name}");
        let s = integ.state();
        let force: f64 = s.impulse.iter().sum::<f64>() / h;
        if force > 0.0 {
            peak = peak.max(force);
            first.get_or_insert(s.time - h);
            last = s.time;
        }
    }
    let e1 = kinetic(integ.as_ref());
    (peak, last - first.expect("no contact"), e0, e1)
}

#[test]
fn peak_force_and_contact_time_follow_hertz() {
    let (f_hertz, t_hertz) = hertz();
    assert!((f_hertz - 2300.9).abs() < 1.0 && (t_hertz - 5.224e-5).abs() < 1e-8);
    let (peak, duration, e0, e1) = impact(2.5e-8);
    let (ef, et) = (peak / f_hertz - 1.0, duration / t_hertz - 1.0);
    assert!(
        ef.abs() < 0.03,
        "peak {peak} N against {f_hertz} N ({ef:+e})"
    );
    assert!(
        et.abs() < 0.03,
        "contact {duration} s against {t_hertz} s ({et:+e})"
    );
    // the mesh's ring mass is the ball's within its faceting (0.23 % light)
    let m = 4.0 / 3.0 * std::f64::consts::PI * R.powi(3) * RHO;
    assert!(
        (2.0 * e0 / m - 1.0).abs() < 5e-3,
        "{} kg against {m}",
        2.0 * e0
    );
    // Hertz's impact is elastic: the ball leaves with its kinetic energy (1e-6 measured;
    // 1e-3 leaves room for the vibrations the impact excites)
    assert!((e1 / e0 - 1.0).abs() < 1e-3, "{e1} J after, {e0} J before");
    // the discrete contact is stiffer at a coarser step: 4 h gives a larger error
    let (coarse, _, _, _) = impact(1e-7);
    assert!(
        coarse / f_hertz - 1.0 > ef,
        "{coarse} at 1e-7, {peak} at 2.5e-8"
    );
}

/// Peak summed contact force and contact duration of a scene of `meshes/` under `kind`.
fn scene_impact(file: &str, kind: &str) -> (f64, f64) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("meshes")
        .join(file);
    let scene = Scene::from_file_with(&path, &[format!("scheme.kind=\"{kind}\"")]).unwrap();
    let (peak, duration, _, _) = run_impact(&scene, &format!("{file} {kind}"));
    (peak, duration)
}

/// Two equal balls in head-on impact (issue 18, contact between bodies):
/// `meshes/hertz_spheres.toml`, the ball of `hertz_ball.toml` at 0.5 m/s against its
/// mirror image at −0.5 m/s, the upper ball's surface nodes against the lower one's
/// surface segments. Hertz for two equal spheres, `E* = E/(2(1 − ν²))`, `R* = R/2`,
/// `m* = m/2` at 1 m/s relative, is the single ball at 0.5 m/s on a rigid frictionless
/// wall (the symmetry plane): peak force `2300.9 · 0.5^{6/5}` = 1001.5 N and contact time
/// `5.224e-5 · 0.5^{−1/5}` = 6.001e-5 s. The issue asks for 5 %. Measured at
/// h = 2.5e-8 s: Moreau–Jean +1.71 % and −1.68 %, Algorithm 2 +1.56 % and −1.18 %
/// (docs/bodies.md, "Contact between bodies"); the step error falls with h as for one ball
/// (+6.3 %, +3.1 %, +1.7 %, +1.4 % on the peak at h = 1e-7, 5e-8, 2.5e-8, 1.25e-8): 3 %
/// here.
#[test]
fn two_equal_balls_meet_with_the_hertz_force_and_duration() {
    let (f1, t1) = hertz();
    // the same law at half the speed: F ∝ v^{6/5}, t_c ∝ v^{−1/5}
    let (f_ref, t_ref) = (f1 * 0.5f64.powf(1.2), t1 * 0.5f64.powf(-0.2));
    assert!((f_ref - 1001.5).abs() < 0.1 && (t_ref - 6.001e-5).abs() < 1e-8);
    for kind in ["moreau-jean", "combined-projection"] {
        let (peak, dur) = scene_impact("hertz_spheres.toml", kind);
        eprintln!(
            "{kind}: peak {peak:.1} N ({:+.2} %), contact {dur:.4e} s ({:+.2} %)",
            100.0 * (peak / f_ref - 1.0),
            100.0 * (dur / t_ref - 1.0)
        );
        assert!((peak / f_ref - 1.0).abs() < 0.03, "{kind}: peak {peak}");
        assert!((dur / t_ref - 1.0).abs() < 0.03, "{kind}: duration {dur}");
    }
}

/// The ball at 1 m/s on a thick elastic plate of the same steel
/// (`meshes/hertz_ball_on_plate.toml`: the axisymmetric plate section r ≤ 4 cm, 4 cm
/// thick, bottom held, graded to 4e-5 m under the ball; 80 contact radii stand for the
/// half-space). Hertz with `E* = E/(2(1 − ν²))` (both bodies deform), `R`, `m` of the
/// ball: 1743.8 N and 6.893e-5 s, half the stiffness of the rigid plane's `E*`. Measured
/// (Moreau–Jean): +4.64 / +2.32 / +1.54 / +1.37 % on the peak and −5.85 / −2.88 / −1.50
/// / −1.12 % on the duration at h = 1e-7 / 5e-8 / 2.5e-8 / 1.25e-8 s; Algorithm 2 at
/// 2.5e-8: +1.45 %, −1.13 %. 3 % at the scene's h = 2.5e-8 s.
#[test]
fn ball_on_a_thick_plate_meets_the_hertz_force_and_duration() {
    let (e, nu, v) = (210e9, 0.3, 1.0);
    let m = 4.0 / 3.0 * std::f64::consts::PI * R.powi(3) * RHO;
    let es = e / (2.0 * (1.0 - nu * nu));
    let delta = (15.0 * m * v * v / (16.0 * es * R.sqrt())).powf(0.4);
    let (f_ref, t_ref) = (
        4.0 / 3.0 * es * R.sqrt() * delta.powf(1.5),
        2.9432 * delta / v,
    );
    assert!((f_ref - 1743.8).abs() < 0.1 && (t_ref - 6.893e-5).abs() < 1e-8);
    let (peak, dur) = scene_impact("hertz_ball_on_plate.toml", "moreau-jean");
    eprintln!(
        "peak {peak:.1} N ({:+.2} %), contact {dur:.4e} s ({:+.2} %)",
        100.0 * (peak / f_ref - 1.0),
        100.0 * (dur / t_ref - 1.0)
    );
    assert!((peak / f_ref - 1.0).abs() < 0.03, "peak {peak}");
    assert!((dur / t_ref - 1.0).abs() < 0.03, "duration {dur}");
}
