//! A neo-Hookean ball dropped on a rigid plane at large strain (issue 17 §2, check (e)),
//! `meshes/ball_crush.toml`: the tet4 ball of `meshes/ball.msh` (R = 0.05 m, 672 cells), E = 2e5 Pa, ν = 0.3,
//! ρ = 1000 kg/m³, hitting the plane at 5 m/s (|v|/c ≈ 0.35), restitution 0, under
//! Algorithm 2 with full Newton. What must hold, with no closed form to compare with:
//!
//! * the ball is crushed by more than 30 % of its diameter (measured 37.6 %), where a
//!   linear material has no meaning;
//! * no penetration: Algorithm 2 projects every contact to machine accuracy (measured
//!   6.9e-18 m; asserted 1e-12 m);
//! * energy is lost only in the impact law: before the impact it is that of the start to
//!   round-off (a rigid translation: no strain), it never rises above it (1e-9 relative),
//!   and the impact with e = 0 removes some (measured 1.8 %; asserted > 0.5 %);
//! * Newton converges in every step (no cap) in a handful of iterations.

use signorini::integrators::Integrator;
use signorini::scene::file::Scene;

#[test]
fn neo_hookean_ball_crushed_by_a_third_keeps_its_contact_and_its_energy_budget() {
    let scene = Scene::from_file(
        &std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("meshes/ball_crush.toml"),
    )
    .unwrap();
    let (model, _) = scene.build().unwrap();
    let geo = model.geometry.clone();
    let mut integ = model.into_integrator(&scene.scheme, scene.time.dt).unwrap();
    let height = |q: &[f64]| {
        let z = geo
            .points
            .iter()
            .enumerate()
            .map(|(a, p)| p[2] + geo.dof_of[3 * a + 2].map_or(0.0, |d| q[d]));
        let (lo, hi) = z.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| {
            (l.min(x), h.max(x))
        });
        hi - lo
    };
    let energy = |i: &dyn Integrator| {
        let s = i.state();
        i.system().total_energy(s.time, &s.q, &s.v)
    };
    let (h0, e0) = (height(&integ.state().q), energy(integ.as_ref()));
    let (mut crush, mut violation, mut newton, mut e_max, mut touched) =
        (0.0_f64, 0.0_f64, 0, e0, false);
    for _ in 0..scene.steps() {
        let st = integ.step().unwrap();
        assert_eq!(st.caps_hit, 0, "step {}", integ.state().step);
        newton = newton.max(st.newton_iterations);
        violation = violation.max(st.max_violation);
        let e = energy(integ.as_ref());
        touched |= integ.state().impulse.iter().any(|&p| p > 0.0);
        if !touched {
            assert!(
                (e / e0 - 1.0).abs() <= 1e-12,
                "free flight: {e} against {e0}"
            );
        }
        e_max = e_max.max(e);
        crush = crush.max(1.0 - height(&integ.state().q) / h0);
    }
    let e_end = energy(integ.as_ref());
    eprintln!(
        "crushed by {:.1} %, violation {violation:e} m, energy {e0} → {e_end} (max {e_max}), \
         Newton ≤ {newton}",
        100.0 * crush
    );
    assert!(crush > 0.30, "compression {crush}");
    assert!(violation <= 1e-12, "violation {violation:e}");
    assert!(
        e_max <= e0 * (1.0 + 1e-9),
        "energy rose to {e_max} from {e0}"
    );
    assert!(
        e_end < 0.995 * e0,
        "the impact with e = 0 dissipates: {e_end} of {e0}"
    );
    assert!(newton <= 20, "Newton iterations {newton}");
}
