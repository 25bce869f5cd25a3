//! Issue 49 §1: the step `h` is a per-step parameter. A run whose `h` changes from `h₁`
//! to `h₂` at step `k` ([`Integrator::set_dt`]) is, bit for bit, the run at `h₁` to step
//! `k` resumed from its checkpoint by an integrator built at `h₂` (the reference for a
//! change of step: everything the next step reads is either saved or a function of the
//! saved state and `h`). Checked on the four paths `M̂(h)` can take:
//!
//! - the bar (a rod, one contact, constant `G`: the dense path, a tridiagonal factor);
//! - a hex8 block sliding with Coulomb friction on a plane (a sparse Cholesky factor,
//!   frictional warm starts);
//! - the same block neo-Hookean (no constant `M̂`: `M̂ⁿ` formed at every step, only
//!   the new `h` to take);
//! - two linear cubes meeting over a face (a moving `G`: the contact zone's condensation
//!   on the new factor).
//!
//! And back to `h₁`: the cache gives the first factor again (no factorization counted),
//! the clock continues from the change, `t = t_o + (k − k_o)·h`.

use signorini::integrators::{Integrator, SchemeKind};
use signorini::scene::bar::BarScene;
use signorini::scene::file::Scene;

mod common;

/// A fresh integrator of `scene` at step `h`.
fn build(scene: &Scene, h: f64) -> Box<dyn Integrator> {
    let (model, _) = scene.build().unwrap();
    model.into_integrator(&scene.scheme, h).unwrap()
}

/// Everything a step leaves in the state, as bits.
fn bits(integ: &dyn Integrator) -> Vec<u64> {
    let s = integ.state();
    let mut out = vec![s.step as u64, s.time.to_bits()];
    for v in [
        &s.q,
        &s.v,
        &s.gap,
        &s.impulse,
        &s.projection,
        &s.tangent_impulse,
        &s.impulse_rows,
    ] {
        out.extend(v.iter().map(|x| x.to_bits()));
    }
    out
}

/// Runs `make(h₁)` `k` steps, changes to `h₂` for `j` steps and back to `h₁` for `l`
/// steps; checks each segment against an integrator built at that segment's step and
/// restored from the checkpoint at the change, and the cache and clock figures.
fn check_change(label: &str, make: &dyn Fn(f64) -> Box<dyn Integrator>, h1: f64, h2: f64) {
    let (k, j, l) = (6, 5, 4);
    let mut a = make(h1);
    for _ in 0..k {
        a.step().unwrap();
    }
    let at_k = a.save();
    let t_k = a.state().time;
    a.set_dt(h2).unwrap();
    assert_eq!(a.dt(), h2);
    let mut b = make(h2);
    b.restore(&at_k).unwrap();
    for i in 0..j {
        let sa = a.step().unwrap();
        b.step().unwrap();
        assert_eq!(
            bits(a.as_ref()),
            bits(b.as_ref()),
            "{label}: step {} at h₂",
            k + i + 1
        );
        if i == 0 {
            // a constant M̂ is factored again for h₂ (a nonlinear one at every step)
            assert!(sa.factorizations >= 1, "{label}: {sa:?}");
        }
    }
    // the clock restarted at the change: t = t_k + j·h₂ (as the bits of `b`)
    let expect = t_k + j as f64 * h2;
    assert_eq!(a.state().time.to_bits(), expect.to_bits(), "{label}");
    let at_kj = a.save();
    a.set_dt(h1).unwrap();
    let mut c = make(h1);
    c.restore(&at_kj).unwrap();
    for i in 0..l {
        let sa = a.step().unwrap();
        let sc = c.step().unwrap();
        assert_eq!(
            bits(a.as_ref()),
            bits(c.as_ref()),
            "{label}: step {} back at h₁",
            k + j + i + 1
        );
        // back at h₁ the cached factor serves: no more factorizations than the run
        // resumed at h₁ (which factored at its build)
        assert_eq!(sa.factorizations, sc.factorizations, "{label}");
    }
}

#[test]
fn the_bar_changes_step_as_a_resumed_run_would() {
    for kind in ["combined-projection", "moreau-jean", "direct-projection"] {
        let bar = BarScene {
            elements: 100,
            ..BarScene::default()
        };
        let mut params = bar.scheme;
        params.kind = SchemeKind::parse(kind).unwrap();
        let h1 = 2e-6;
        let make = |h: f64| {
            let model = bar.build().unwrap();
            model.into_integrator(&params, h).unwrap()
        };
        // the bar starts at its wall: it hits in the first steps
        check_change(&format!("bar, {kind}"), &make, h1, 0.5 * h1);
    }
}

#[test]
fn a_frictional_block_changes_step_as_a_resumed_run_would() {
    let text = common::blocks::undamped_block(1e-4, 0.01, "combined-projection", 0.5, 0.3);
    let scene = Scene::from_text_with(&text, &[]).unwrap();
    check_change("block, μ = 0.3", &|h| build(&scene, h), 1e-4, 4e-5);
}

#[test]
fn a_neo_hookean_block_changes_step_as_a_resumed_run_would() {
    let text = common::blocks::undamped_block(1e-4, 0.01, "combined-projection", 0.5, 0.3).replace(
        "density = 1000.0 }",
        "density = 1000.0, model = \"neo-hookean\" }",
    );
    let scene = Scene::from_text_with(&text, &[]).unwrap();
    check_change("neo-Hookean block", &|h| build(&scene, h), 1e-4, 2.5e-5);
}

#[test]
fn two_cubes_change_step_on_their_contact_zone() {
    let scene = Scene::from_text_with(&common::blocks::two_cubes(1e-3, "auto"), &[]).unwrap();
    check_change("two cubes", &|h| build(&scene, h), 1e-5, 3e-6);
}

/// Schatzman–Paoli is a two-step scheme (`q_{k−1}` at the same `h`): it refuses another
/// step with the key, the value and its own, and keeps stepping at its own.
#[test]
fn schatzman_paoli_refuses_another_step() {
    let bar = BarScene {
        elements: 20,
        ..BarScene::default()
    };
    let mut params = bar.scheme;
    params.kind = SchemeKind::SchatzmanPaoli;
    let mut integ = bar.build().unwrap().into_integrator(&params, 1e-5).unwrap();
    integ.set_dt(1e-5).unwrap();
    let e = integ.set_dt(5e-6).unwrap_err();
    assert_eq!(e.exit_code(), 2);
    let msg = e.to_string();
    assert!(
        msg.contains("`dt`") && msg.contains("0.000005") && msg.contains("h = 1e-5 s"),
        "{msg}"
    );
    integ.step().unwrap();
    assert_eq!(integ.state().time, 1e-5);
}

/// A step that is not positive and finite is refused before anything changes.
#[test]
fn a_bad_step_is_refused_and_changes_nothing() {
    let bar = BarScene {
        elements: 20,
        ..BarScene::default()
    };
    let mut integ = bar
        .build()
        .unwrap()
        .into_integrator(&bar.scheme, 1e-5)
        .unwrap();
    for h in [0.0, -1e-5, f64::NAN, f64::INFINITY] {
        let e = integ.set_dt(h).unwrap_err();
        assert_eq!(e.exit_code(), 2, "{h}");
        assert!(e.to_string().contains("dt"), "{e}");
    }
    assert_eq!(integ.dt(), 1e-5);
}
