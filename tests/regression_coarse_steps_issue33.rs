//! Issue 33: a coarser step gives a coarser answer, never energy from nowhere, a
//! stop, or a penetration past the scheme's own bound.
//!
//! - Algorithm 2 (the default) on the committed impact scenes that failed at 2×–8× their
//!   step under the paper's rule (eq. 68): the two Hertz balls and the ball drop. The
//!   energy excess must stay at round-off (≤ 1e-6 of the run's energy scale: every clean
//!   run of `benches/projection_rule_matrix.py` stays below 2e-13), the position
//!   constraints at machine accuracy (1e-15 m: coordinates of up to 0.1 m round at
//!   1.4e-17 m per operation; measured ≤ 1.8e-18 m), no cap.
//! - The paper's rules on the same Hertz ball at 4× its step gain 22 % of the energy
//!   (the run stops with exit 1): what the default rules fix, kept selectable.
//! - Moreau–Jean on curved contact between bodies (the two Hertz spheres, 1 m/s closing)
//!   stays within 2× its bound `|U|(1 − θ)h` with the active set closed on the solution
//!   (measured 1.01×), where the forecast of eq. 62 alone lets a node at the edge of the
//!   growing patch sink 6.2× the bound.

use signorini::app::run_scene;
use signorini::run::Quiet;
use signorini::scene::file::Scene;

fn scene(name: &str, overrides: &[&str]) -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("meshes")
        .join(name);
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    Scene::from_file_with(&path, &o).unwrap()
}

#[test]
fn algorithm_2_keeps_the_energy_of_impacts_at_coarse_steps() {
    for (name, dt) in [
        ("hertz_ball.toml", "5e-8"),
        ("hertz_ball.toml", "1e-7"),
        ("hertz_ball_on_plate.toml", "1e-7"),
        ("ball_drop.toml", "8e-4"),
    ] {
        let dt_set = format!("time.dt={dt}");
        let s = scene(
            name,
            &["scheme.kind=\"combined-projection\"", dt_set.as_str()],
        );
        let r =
            run_scene(&s, None, &mut Quiet).unwrap_or_else(|e| panic!("{name} at h = {dt}: {e}"));
        let b = r
            .summary
            .energy_balance
            .expect("a θ-method run has a balance");
        eprintln!(
            "{name} h = {dt}: excess {:.2e}, violation {:.2e} m, Newton {:.2}",
            b.excess_max, r.summary.max_violation, r.summary.iterations.newton.mean
        );
        assert!(b.excess_max <= 1e-6, "{name} at h = {dt}: {b:?}");
        assert!(r.summary.max_violation <= 1e-15, "{name} at h = {dt}");
        assert_eq!(r.summary.caps_hit, 0, "{name} at h = {dt}");
    }
}

#[test]
fn the_papers_rules_gain_energy_on_the_hertz_ball_at_four_times_its_step() {
    let s = scene(
        "hertz_ball.toml",
        &[
            "scheme.kind=\"combined-projection\"",
            "time.dt=1e-7",
            "scheme.projection_rule=\"paper\"",
            "scheme.energy_consistent_restitution=false",
        ],
    );
    let Err(e) = run_scene(&s, None, &mut Quiet) else {
        panic!("the paper's rules kept the energy: the lead of issue 33 is gone");
    };
    assert_eq!(e.exit_code(), 1, "{e}");
    assert!(e.to_string().contains("the energy grew"), "{e}");
}

#[test]
fn moreau_jean_stays_within_its_bound_on_curved_contact_between_bodies() {
    let h = 1.25e-8;
    // |U|(1 − θ)h with the 1 m/s closing velocity and θ = 1/2
    let bound = 1.0 * 0.5 * h;
    let mut worst = [0.0; 2];
    for (i, closure) in ["true", "false"].into_iter().enumerate() {
        let c = format!("scheme.activation_closure={closure}");
        let s = scene(
            "hertz_spheres.toml",
            &["time.dt=1.25e-8", "time.t_end=3e-6", c.as_str()],
        );
        let r = run_scene(&s, None, &mut Quiet).unwrap();
        worst[i] = r.summary.max_violation / bound;
        let b = r.summary.energy_balance.unwrap();
        assert!(b.excess_max <= 1e-6, "closure {closure}: {b:?}");
    }
    eprintln!(
        "violation / bound: closed {:.3}, forecast alone {:.3}",
        worst[0], worst[1]
    );
    assert!(
        worst[0] <= 2.0,
        "closed active set: {} × the bound",
        worst[0]
    );
    assert!(worst[1] > 5.0, "forecast alone: {} × the bound", worst[1]);
}

/// Axisymmetric bodies: the edges of the half section on the axis r = 0 are not surfaces
/// of the revolved solid and never contact facets. The lower Hertz sphere's whole
/// `boundary` as the target surface: `check` reports its 56 axis edges left out, and
/// the impact runs as on the `surface` set (before: the upper pole paired with an axis
/// edge at gap 0 while 2 µm apart, nodes left at 20–270 m/s and the energy grew 4.5 %).
#[test]
fn axis_edges_of_axisymmetric_bodies_are_never_contact_facets() {
    let s = scene(
        "hertz_spheres.toml",
        &["contacts[0].target.surface=\"boundary\"", "time.t_end=3e-6"],
    );
    let report = s.check().unwrap();
    let line = report.interfaces.join("\n");
    assert!(
        line.contains("56 facet(s) of \"lower\" on the axis r = 0 left out"),
        "{line}"
    );
    let r = run_scene(&s, None, &mut Quiet).unwrap();
    // Moreau–Jean's bound |U|(1 − θ)h at 1 m/s closing, h = 2.5e-8
    let bound = 0.5 * 2.5e-8;
    assert!(
        r.summary.max_violation <= 2.0 * bound,
        "violation {:e} m",
        r.summary.max_violation
    );
    let b = r.summary.energy_balance.unwrap();
    assert!(b.excess_max <= 1e-6, "{b:?}");
}

/// Moreau–Jean on two aluminium balls (E = 70 GPa, ρ = 2700) closing at 2 m/s and
/// released, at h = 6.25e-9 s: a lasting contact that separates was caught by an
/// impulse with e = 0 and the run stopped on the energy check (a gain of 1.02e-6 of
/// the energy scale at step 7936). With the restitution floor on every separating row
/// under Moreau–Jean the balance holds exactly (measured excess 0) and the penetration
/// stays within 2× the bound `|U|(1 − θ)h` = 6.25e-9 m (measured 1.01×).
#[test]
fn moreau_jean_gains_no_energy_when_a_lasting_contact_separates() {
    let s = scene(
        "hertz_spheres.toml",
        &[
            "scheme.kind=\"moreau-jean\"",
            "time.dt=6.25e-9",
            "time.t_end=7e-5",
            "bodies[0].velocity=[0.0, -1.0]",
            "bodies[1].velocity=[0.0, 1.0]",
            "bodies[0].material.young=7e10",
            "bodies[1].material.young=7e10",
            "bodies[0].material.density=2700.0",
            "bodies[1].material.density=2700.0",
        ],
    );
    let r = run_scene(&s, None, &mut Quiet).unwrap();
    let b = r
        .summary
        .energy_balance
        .expect("a θ-method run has a balance");
    let bound = 2.0 * 0.5 * 6.25e-9;
    eprintln!(
        "excess {:.2e}, violation {:.3e} m = {:.3} × the bound",
        b.excess_max,
        r.summary.max_violation,
        r.summary.max_violation / bound
    );
    // round-off: every clean run of the matrix stays below 2e-13 of its scale
    assert!(b.excess_max <= 1e-12, "{b:?}");
    assert!(r.summary.max_violation <= 2.0 * bound);
}
