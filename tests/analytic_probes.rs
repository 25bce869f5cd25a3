//! Displacement probes (`[[probes]]`, issue 19 §1) against closed forms: the impacting
//! bar's displacement field (`ImpactingBar::displacement`) at its free and contact
//! ends, and the centre of mass of the elastic block sliding under Coulomb friction
//! (`x = v0 t − μ g t²/2` until it stops at `v0/(μ g)`). A probe time between two steps
//! reads the θ-method's displacement, linear within the step (eq. 18).

use signorini::analytic::ImpactingBar;
use signorini::app::run_scene;
use signorini::run::Quiet;
use signorini::run::probes::ProbeSummary;
use signorini::scene::file::Scene;
use signorini::study::sweep::BAR_SCENE;

/// The reference bar (N = 1000, h = 5e-7, Algorithm 2) with `probes` appended.
fn bar_with(probes: &str) -> Vec<ProbeSummary> {
    let scene = Scene::from_toml(&format!("{BAR_SCENE}\n{probes}")).unwrap();
    run_scene(&scene, None, &mut Quiet).unwrap().summary.probes
}

const BAR: ImpactingBar = ImpactingBar::REFERENCE;

#[test]
fn the_bar_ends_move_as_the_closed_form_says() {
    let c0 = BAR.wave_speed();
    let p = bar_with(
        r#"
[[probes]]
name = "free end"
body = "bar"
nodes = "x1"
times = [1e-4, 3e-4]

[[probes]]
name = "contact end"
body = "bar"
nodes = "x0"
times = [1e-4, 2e-4, 3.5e-4]
"#,
    );
    assert_eq!(p.len(), 2);
    let (tip, end) = (&p[0], &p[1]);
    assert_eq!(tip.position, [1.0, 0.0, 0.0]);
    assert_eq!(tip.node_count, 1);
    // the summary's closed form is the analytic module's
    let a = tip.analytic.as_ref().expect("a rod of the bar reference");
    assert_eq!(a[0][0], BAR.displacement(1.0, 1e-4));
    // before the compression front reaches it (at L/c0 = 1.93e-4 s) the free end flies
    // at v0: the discrete front's precursor is exponentially small half a bar ahead of
    // it, so the round-off of 200 steps bounds the difference (measured 3e-16)
    let u = tip.displacement[0][0];
    assert!((u / (BAR.velocity * 1e-4) - 1.0).abs() < 1e-12, "{u:e}");
    // between the fronts' passages the tip moves back at −v0: the discrete fronts are
    // smeared over a few elements (measured 2.5e-4 of the value; 4× margin)
    let (u, exact) = (tip.displacement[1][0], BAR.displacement(1.0, 3e-4));
    assert!((u / exact - 1.0).abs() < 1e-3, "{u:e} against {exact:e}");
    assert!(3e-4 > 1.0 / c0 && 3e-4 < 2.0 / c0);
    // the contact end stays on the wall while in contact: Algorithm 2 projects to
    // machine accuracy (DESIGN.md §3), so |u| is at round-off of the 1e-5 m motion
    for (t, u) in end.times.iter().zip(&end.displacement) {
        assert!(u[0].abs() < 1e-20, "contact end at t = {t}: {:e}", u[0]);
    }
    assert!(
        end.analytic_error.is_none(),
        "zero reference: no relative error"
    );
}

#[test]
fn a_time_between_steps_reads_the_linear_displacement_of_the_step() {
    // h = 5e-7: 2.0000e-4 and 2.0005e-4 are step times (steps 400 and 401), 2.00025e-4
    // lies halfway; the free end's displacement is linear within the step (eq. 18)
    let p = bar_with(
        r#"
[[probes]]
name = "steps"
body = "bar"
nodes = "x1"
times = [2.0e-4, 2.0005e-4]

[[probes]]
name = "between"
body = "bar"
nodes = "x1"
times = [2.00025e-4]
"#,
    );
    let (a, b) = (p[0].displacement[0][0], p[0].displacement[1][0]);
    let mid = p[1].displacement[0][0];
    // the interpolation weight (t* − t_k)/(t_{k+1} − t_k) is formed from times near
    // 2e-4 s whose ulps (2.7e-20 s) are 1e-13 of the step: exact to 1e-9 of the step's
    // motion, plus the round-off of the sum
    let tol = 1e-9 * (b - a).abs() + 4.0 * f64::EPSILON * a.abs().max(b.abs());
    assert!(
        (mid - 0.5 * (a + b)).abs() <= tol,
        "{mid:e} against the mean of {a:e} and {b:e}"
    );
    assert!(a != b, "the tip moves within the step");
}

#[test]
fn the_sliding_block_centre_slides_as_coulomb_says() {
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/sliding_block.toml");
    let scene = Scene::from_file(&file).unwrap();
    let r = run_scene(&scene, None, &mut Quiet).unwrap();
    let p = &r.summary.probes[0];
    assert_eq!(p.name, "mean");
    assert_eq!(p.node_count, 75);
    let (v0, mu_g) = (1.0, 0.3 * 9.81);
    for (t, u) in p.times.iter().zip(&p.displacement) {
        let ts = t.min(v0 / mu_g);
        let x = v0 * ts - 0.5 * mu_g * ts * ts;
        // measured within 5e-7 m (the mean of the nodes is the centre of mass of this
        // uniform mesh; the block's rocking and the O(h) friction onset leave the rest);
        // 10× margin, against a 0.17 m slide
        assert!((u[0] - x).abs() < 5e-6, "t = {t}: x = {} against {x}", u[0]);
        // no lateral drift, and the gravity sag of a 10 MPa block (< 1 µm)
        assert!(u[1].abs() < 1e-9 && u[2] < 0.0 && u[2] > -1e-6, "{u:?}");
    }
}
