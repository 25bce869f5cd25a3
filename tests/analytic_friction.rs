//! Coulomb friction against closed forms (issue 11 §5), under Moreau–Jean, Algorithm 1
//! and Algorithm 2.
//!
//! - A body sliding on a horizontal plane at `v0` decelerates at `μ g`: it stops after
//!   `v0/(μ g)` s having travelled `v0²/(2 μ g)` m. Measured on a particle (2-D and 3-D)
//!   and on the rigid 2-D block of eq. 10 (two frictional corners, rotation free).
//!   Tolerance 1 % (the issue's): the discrete stop is resolved to one step `h`, and
//!   `h μ g / v0` is 0.03 % here.
//! - No lift-off while sliding: under Algorithm 2 the gap stays within 1e-12 m of 0.
//! - Incline of angle α (gravity tilted, plane fixed): sticks when `tan α < μ` (drift
//!   ≤ 1e-9 m over 1 s), slides with `a = g (sin α − μ cos α)` within 1 % otherwise.

mod common;

use common::blocks::{check_pushed, contact_sums, momentum_x};
use signorini::contact::block::BlockCorners;
use signorini::contact::plane::NodesOnPlane;
use signorini::contact::{ContactSet, ContactStatus};
use signorini::integrators::{self, Integrator, SchemeKind, SchemeParams};
use signorini::model::point_mass::{point_mass, rigid_block};

const G: f64 = 9.81;
const SCHEMES: [SchemeKind; 3] = [
    SchemeKind::MoreauJean,
    SchemeKind::DirectProjection,
    SchemeKind::CombinedProjection,
];

fn params(kind: SchemeKind) -> SchemeParams {
    SchemeParams {
        kind,
        ..SchemeParams::default()
    }
}

/// A particle of mass 1 on the plane `x_{d−1} = 0` (normal +e_{d−1}) with gravity
/// `force`, initial velocity `v0`, friction μ.
fn particle(
    kind: SchemeKind,
    dim: usize,
    force: &[f64],
    v0: &[f64],
    mu: f64,
    h: f64,
) -> Box<dyn Integrator> {
    let sys = point_mass(dim, 1.0, force).unwrap();
    let mut normal = vec![0.0; dim];
    normal[dim - 1] = 1.0;
    let plane = NodesOnPlane::new(
        vec![(0..dim).collect()],
        vec![vec![0.0; dim]],
        normal,
        0.0,
        0.0,
    )
    .unwrap()
    .with_friction(mu)
    .unwrap();
    integrators::build(&params(kind), sys, Box::new(plane), &vec![0.0; dim], v0, h).unwrap()
}

/// Steps until the tangential speed (dofs `tangent`) is ≤ 1e-9 m/s; returns the stop
/// time, the distance along dof `tangent[0]` and the largest |gap|.
fn slide_to_rest(integ: &mut dyn Integrator, tangent: &[usize], t_max: f64) -> (f64, f64, f64) {
    let h = integ.dt();
    let mut gap: f64 = 0.0;
    let mut caps = 0;
    while integ.state().time < t_max {
        let st = integ.step().unwrap();
        caps += st.caps_hit;
        let s = integ.state();
        gap = gap.max(s.gap.iter().fold(0.0_f64, |a, g| a.max(g.abs())));
        let speed = tangent.iter().map(|&i| s.v[i] * s.v[i]).sum::<f64>().sqrt();
        if speed <= 1e-9 {
            assert_eq!(caps, 0, "friction or Newton caps hit");
            // the stop lies within the last step: report its middle
            return (s.time - 0.5 * h, s.q[tangent[0]], gap);
        }
    }
    panic!("did not stop before {t_max} s");
}

#[test]
fn particle_sliding_on_a_plane_stops_at_v0_over_mu_g() {
    let (mu, v0, h) = (0.3, 1.0, 1e-4);
    let (t_ref, d_ref) = (v0 / (mu * G), v0 * v0 / (2.0 * mu * G));
    for kind in SCHEMES {
        for dim in [2, 3] {
            let mut force = vec![0.0; dim];
            force[dim - 1] = -G;
            let mut vel = vec![0.0; dim];
            vel[0] = v0;
            let mut integ = particle(kind, dim, &force, &vel, mu, h);
            let tang: Vec<usize> = (0..dim - 1).collect();
            let (t, d, gap) = slide_to_rest(integ.as_mut(), &tang, 2.0 * t_ref);
            assert!(
                (t / t_ref - 1.0).abs() < 0.01 && (d / d_ref - 1.0).abs() < 0.01,
                "{kind:?} {dim}-D: stop {t} s (analytic {t_ref}), distance {d} m (analytic {d_ref})"
            );
            // resting on the plane from t = 0: no lift-off, no penetration
            assert!(gap <= 1e-12, "{kind:?} {dim}-D: |gap| up to {gap:e} m");
            let s = integ.state();
            assert_eq!(
                s.status[0],
                ContactStatus::Stick,
                "{kind:?} {dim}-D at rest"
            );
            // at rest the impulse balances the weight over the step
            assert!((s.impulse[0] / (G * h) - 1.0).abs() < 1e-9);
        }
    }
}

#[test]
fn rigid_block_sliding_on_its_two_corners_stops_at_v0_over_mu_g() {
    let (mu, v0, h) = (0.4, 2.0, 1e-4);
    let (len, thick, m) = (1.0, 0.2, 1.0);
    let (t_ref, d_ref) = (v0 / (mu * G), v0 * v0 / (2.0 * mu * G));
    for kind in SCHEMES {
        let sys = rigid_block(m, len, thick, G).unwrap();
        let corners = BlockCorners::new(len, thick, 0.0)
            .unwrap()
            .with_friction(mu)
            .unwrap();
        assert_eq!(corners.rows(), 4);
        // resting flat: centre at height l/2
        let q0 = [0.0, 0.5 * thick, 0.0];
        let mut integ = integrators::build(
            &params(kind),
            sys,
            Box::new(corners),
            &q0,
            &[v0, 0.0, 0.0],
            h,
        )
        .unwrap();
        let (t, d, _) = slide_to_rest(integ.as_mut(), &[0], 2.0 * t_ref);
        assert!(
            (t / t_ref - 1.0).abs() < 0.01 && (d / d_ref - 1.0).abs() < 0.01,
            "{kind:?}: stop {t} s (analytic {t_ref}), distance {d} m (analytic {d_ref})"
        );
        let s = integ.state();
        // friction at the corners pitches the block, but it must not tip (θ small) and
        // both corners carry the weight at rest
        assert!(s.q[2].abs() < 1e-6, "{kind:?}: θ = {}", s.q[2]);
        let pn = s.impulse[0] + s.impulse[1];
        assert!(
            (pn / (m * G * h) - 1.0).abs() < 1e-6,
            "{kind:?}: ΣP_N = {pn}"
        );
    }
}

#[test]
fn incline_sticks_below_the_friction_angle_and_slides_above() {
    let (mu, h, t_end) = (0.5, 1e-4, 1.0);
    for kind in SCHEMES {
        for (alpha_deg, sticks) in [(20.0_f64, true), (35.0, false)] {
            let a = alpha_deg.to_radians();
            assert_eq!(a.tan() < mu, sticks);
            // plane y = 0 fixed, gravity tilted by α: down-slope is +x
            let force = [G * a.sin(), -G * a.cos()];
            let mut integ = particle(kind, 2, &force, &[0.0, 0.0], mu, h);
            let steps = (t_end / h).round() as usize;
            for _ in 0..steps {
                let st = integ.step().unwrap();
                assert_eq!(st.caps_hit, 0);
            }
            let s = integ.state();
            if sticks {
                assert!(
                    s.q[0].abs() <= 1e-9,
                    "{kind:?} α = {alpha_deg}°: drift {} m",
                    s.q[0]
                );
                assert_eq!(s.status[0], ContactStatus::Stick);
            } else {
                let acc = G * (a.sin() - mu * a.cos());
                let want = 0.5 * acc * t_end * t_end;
                assert!(
                    (s.q[0] / want - 1.0).abs() < 0.01
                        && (s.v[0] / (acc * t_end) - 1.0).abs() < 0.01,
                    "{kind:?} α = {alpha_deg}°: x = {} (analytic {want}), v = {}",
                    s.q[0],
                    s.v[0]
                );
                assert_eq!(s.status[0], ContactStatus::Slip);
            }
        }
    }
}

#[test]
fn schatzman_paoli_and_the_trapezoid_refuse_friction() {
    for kind in [SchemeKind::SchatzmanPaoli, SchemeKind::TrapezoidPosition] {
        let sys = point_mass(2, 1.0, &[0.0, -G]).unwrap();
        let plane = NodesOnPlane::new(
            vec![vec![0, 1]],
            vec![vec![0.0, 0.0]],
            vec![0.0, 1.0],
            0.0,
            0.0,
        )
        .unwrap()
        .with_friction(0.3)
        .unwrap();
        let err = integrators::build(
            &params(kind),
            sys,
            Box::new(plane),
            &[0.0; 2],
            &[0.0; 2],
            1e-3,
        )
        .err()
        .expect("refused");
        let msg = err.to_string();
        assert!(
            msg.contains("scheme.kind") && msg.contains(kind.name()) && msg.contains("friction"),
            "{msg}"
        );
    }
}

/// The elastic hex8 block of `meshes/sliding_block.toml`: its centre of mass stops
/// after `v0/(μ g)` and `v0²/(2 μ g)` within 1 % under the three schemes (stop: first
/// step with `v_G ≤ 1e-3 v0`, a step of 2e-4 s is 0.06 % of the stop time).
#[test]
fn elastic_hex8_block_sliding_on_a_plane_stops_at_v0_over_mu_g() {
    let (mu, v0) = (0.3, 1.0);
    let (t_ref, d_ref) = (v0 / (mu * G), v0 * v0 / (2.0 * mu * G));
    for kind in SCHEMES {
        let mut integ = scene_integrator("sliding_block", kind);
        let h = integ.dt();
        let (p0, mass) = momentum_x(integ.as_ref());
        assert!((p0 / mass - v0).abs() < 1e-12);
        let (mut x, mut v, mut caps, mut viol) = (0.0, v0, 0, 0.0_f64);
        let stop = loop {
            let st = integ.step().unwrap();
            caps += st.caps_hit;
            viol = viol.max(st.max_violation);
            let vn = momentum_x(integ.as_ref()).0 / mass;
            x += 0.5 * (v + vn) * h;
            v = vn;
            if v <= 1e-3 * v0 {
                break integ.state().time - 0.5 * h;
            }
            assert!(integ.state().time < 2.0 * t_ref, "{kind:?}: no stop");
        };
        assert_eq!(caps, 0, "{kind:?}");
        eprintln!("{kind:?}: stop {stop:.4} s, distance {x:.5} m, violation {viol:.1e} m");
        assert!(
            (stop / t_ref - 1.0).abs() < 0.01 && (x / d_ref - 1.0).abs() < 0.01,
            "{kind:?}: stop {stop} s (analytic {t_ref}), distance {x} m (analytic {d_ref})"
        );
        if kind != SchemeKind::MoreauJean {
            assert!(viol <= 1e-12, "{kind:?}: violation {viol:e} m");
        }
    }
}

/// A rigid rod (the block of eq. 10 with thickness 1e-6 of its length: inertia within
/// 1e-12 of m L²/12, corner lever arms within 1e-6 of the rod's) falls flat-footed at angle θ = 45° onto the ground, no gravity,
/// e = 0. Right after the impact its lower end sticks iff
/// `μ ≥ 3 sin θ cos θ / (1 + 3 sin² θ)` = 0.6 (impulse balance of the rod about its end);
/// then `|P_T| / P_N` equals that ratio, and below it the end slips with `|P_T| = μ P_N`.
/// Checked 0.05 on either side of the threshold, at the first step with an impulse.
#[test]
fn rigid_rod_falling_at_45_degrees_sticks_iff_mu_reaches_the_threshold() {
    let th = std::f64::consts::FRAC_PI_4;
    let ratio = 3.0 * th.sin() * th.cos() / (1.0 + 3.0 * th.sin().powi(2));
    assert!((ratio - 0.6).abs() < 1e-12);
    let (len, thick, h, v0) = (1.0, 1e-6, 1e-4, 1.0);
    for kind in SCHEMES {
        for (mu, sticks) in [(ratio + 0.05, true), (ratio - 0.05, false)] {
            let sys = rigid_block(1.0, len, thick, 0.0).unwrap();
            let corners = BlockCorners::new(len, thick, 0.0)
                .unwrap()
                .with_friction(mu)
                .unwrap();
            // corner B = (−L/2, −l/2) lowest, 1e-6 m above the ground
            let y = 0.5 * len * th.sin() + 0.5 * thick * th.cos() + 1e-6;
            let mut integ = integrators::build(
                &params(kind),
                sys,
                Box::new(corners),
                &[0.0, y, th],
                &[0.0, -v0, 0.0],
                h,
            )
            .unwrap();
            let s = loop {
                integ.step().unwrap();
                if integ.state().impulse[1] > 0.0 {
                    break integ.state().clone();
                }
                assert!(integ.state().time < 0.01, "{kind:?}: no impact");
            };
            let (pn, pt) = (s.impulse[1], s.tangent_impulse[1]);
            let want = if sticks {
                ContactStatus::Stick
            } else {
                ContactStatus::Slip
            };
            assert_eq!(
                s.status[1],
                want,
                "{kind:?} μ = {mu}: P_T/P_N = {}",
                pt / pn
            );
            let r = pt.abs() / pn;
            if sticks {
                // the implicit schemes take G at the end of the impact step, when the rod
                // has turned by ω h ≈ 1.6e-4 rad: the ratio is off by O(ω h) (6e-5 seen)
                assert!(
                    (r / ratio - 1.0).abs() < 1e-3,
                    "{kind:?} μ = {mu}: |P_T|/P_N = {r}"
                );
            } else {
                assert!(
                    (r / mu - 1.0).abs() < 1e-9,
                    "{kind:?} μ = {mu}: |P_T|/P_N = {r}"
                );
            }
        }
    }
}

/// The integrator of `meshes/NAME.toml` under `kind`.
fn scene_integrator(name: &str, kind: SchemeKind) -> Box<dyn Integrator> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("meshes")
        .join(format!("{name}.toml"));
    let mut scene = signorini::scene::file::Scene::from_file(&path).unwrap();
    scene.scheme.kind = kind;
    let (model, _) = scene.build().unwrap();
    model.into_integrator(&scene.scheme, scene.time.dt).unwrap()
}

/// `meshes/pushed_block.toml`: the hex8 block at rest on the floor (μ = 0.3), its top
/// face pushed along x by a force ramped from 0 (t = 0.1 s) to 3 N (t = 1.1 s). Closed
/// form: friction balances the push while it is below μ m g = 1.4715 N (until
/// t* = 0.5905 s), then the block slides with |ΣP_T| = μ ΣP_N. Checked within 1 %: the
/// summed tangential force equals the push over [0.15, 0.55] s and stays below μ ΣN; it
/// equals μ ΣN over [0.62, 1] s; it first reaches 0.99 μ ΣN within 1 % of t*; ΣN = m g
/// to 1e-3 from t = 0.1 s.
#[test]
fn pushed_hex8_block_sticks_until_the_push_reaches_mu_m_g_then_slides() {
    for kind in SCHEMES {
        let mut integ = scene_integrator("pushed_block", kind);
        check_pushed(integ.as_mut(), &format!("{kind:?}"), 1.0);
    }
}

/// `meshes/dragged_block.toml`: the hex8 block on the floor (μ = 0.3), its top face
/// dragged along x at a prescribed velocity ramp (`[[prescribed]]`, 0 at t = 0.1 s to
/// 0.01 m/s at 1.1 s). The block shears while the friction is below the cone, then
/// slides: from t = 0.15 s (all contacts slipping) the summed friction force is μ ΣN
/// within 1 % and the base slips at the drive's velocity (within 1 % from t = 0.3 s,
/// when the quasi-static shear has settled); ΣN = m g to 5e-3 throughout.
#[test]
fn dragged_hex8_block_shears_then_slides_at_mu_n_with_the_drive() {
    let (mu, m) = (0.3, 0.5);
    for kind in SCHEMES {
        let mut integ = scene_integrator("dragged_block", kind);
        let h = integ.dt();
        let mut stuck_below = false;
        while integ.state().time < 1.0 - 1e-12 {
            let st = integ.step().unwrap();
            assert_eq!(st.caps_hit, 0, "{kind:?}");
            let s = integ.state();
            let (t, td, nc) = (s.time, s.tangent_dim, s.impulse.len());
            let (pn, ft) = contact_sums(s, h);
            // the stick–slip transition near 0.12 s is a small dynamic event: ΣN moved by
            // up to 1.4e-3 of m g under Moreau–Jean
            if t >= 0.1 {
                assert!(
                    (pn / h / (m * G) - 1.0).abs() < 5e-3,
                    "{kind:?} t = {t}: ΣN/mg = {}",
                    pn / h / (m * G)
                );
            }
            if (0.1..0.11).contains(&t) && ft > 0.0 {
                // shearing: friction inside the cone, every contact stuck
                assert!(ft < mu * pn / h);
                assert!(
                    s.status.iter().all(|&x| x == ContactStatus::Stick),
                    "{kind:?} t = {t}"
                );
                stuck_below = true;
            }
            if t >= 0.15 {
                assert!(
                    (ft / (mu * pn / h) - 1.0).abs() < 0.01,
                    "{kind:?} t = {t}: |ΣT|/μΣN = {}",
                    ft / (mu * pn / h)
                );
            }
            if t >= 0.3 {
                let drive = 0.01 * (t - 0.1);
                let slip: f64 = (0..nc)
                    .map(|c| {
                        (0..td)
                            .map(|j| s.tangent_velocity[c * td + j].powi(2))
                            .sum::<f64>()
                            .sqrt()
                    })
                    .sum::<f64>()
                    / nc as f64;
                assert!(
                    (slip / drive - 1.0).abs() < 0.01,
                    "{kind:?} t = {t}: slip {slip}, drive {drive}"
                );
            }
        }
        assert!(stuck_below, "{kind:?}: no stick phase seen");
    }
}

#[test]
fn schatzman_paoli_refuses_prescribed_velocities() {
    use signorini::scene::file::Scene;
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/dragged_block.toml");
    let mut scene = Scene::from_file(&path).unwrap();
    scene.scheme.kind = SchemeKind::SchatzmanPaoli;
    scene.contacts[0].friction = 0.0;
    let (model, _) = scene.build().unwrap();
    let err = model
        .into_integrator(&scene.scheme, scene.time.dt)
        .err()
        .unwrap()
        .to_string();
    assert!(
        err.contains("scheme.kind") && err.contains("prescribed"),
        "{err}"
    );
}

/// Issue 16 §1: the incline on the undamped elastic block of
/// `tests/regression_alg2_friction_undamped.rs` (E = 1e8, ν = 0, no damping, h = 1e-4),
/// released at rest on a rigid floor under gravity tilted by α (down-slope +x), μ = 0.5,
/// under the three schemes; no cap, and the projection schemes exact at position level.
/// At α = 20° (tan α < μ) a rigid block would not move. The elastic one, loaded at once
/// and undamped, rings: its normal force swings between about 0 and 2 m g cos α, and in
/// the low phases the base slips a little. Measured drift of the centre of mass after
/// 0.2 s, every scheme, h = 1e-4, 5e-5, 2e-5: 1.2e-5 to 2.0e-4 m, not monotone in h, no
/// scheme an outlier (Algorithm 2: 1.6e-4, 1.3e-4, 6.1e-5 m); 5e-4 m asserted, 1.5 % of
/// the distance slid at 35°. At α = 35° it slides with `g (sin α − μ cos α)`: after
/// 0.2 s its centre of mass has travelled ½ a t² within 2 % (measured +0.50 % for
/// Moreau–Jean, +0.51 % for Algorithm 2, +1.59 % for Algorithm 1).
#[test]
fn undamped_elastic_block_on_an_incline_sticks_below_the_friction_angle_and_slides_above() {
    use signorini::scene::file::Scene;
    let (mu, h, t_end) = (0.5, 1e-4, 0.2);
    for kind in SCHEMES {
        for (alpha_deg, sticks) in [(20.0_f64, true), (35.0, false)] {
            let a = alpha_deg.to_radians();
            let text = common::blocks::undamped_block(h, t_end, kind.name(), 0.5, mu)
                .replace("velocity = [1.0, 0.0, 0.0]", "velocity = [0.0, 0.0, 0.0]")
                .replace(
                    "gravity = [0.0, 0.0, -9.81]",
                    &format!("gravity = [{:?}, 0.0, {:?}]", G * a.sin(), -G * a.cos()),
                );
            let scene = Scene::from_toml(&text).unwrap();
            let (model, _) = scene.build().unwrap();
            let mut integ = model.into_integrator(&scene.scheme, h).unwrap();
            let (_, mass) = momentum_x(integ.as_ref());
            let (mut x, mut v, mut caps, mut viol) = (0.0, 0.0, 0, 0.0_f64);
            for _ in 0..scene.steps() {
                let st = integ.step().unwrap();
                caps += st.caps_hit;
                viol = viol.max(st.max_violation);
                let vn = momentum_x(integ.as_ref()).0 / mass;
                x += 0.5 * (v + vn) * h;
                v = vn;
            }
            let acc = G * (a.sin() - mu * a.cos());
            let want = 0.5 * acc * t_end * t_end;
            eprintln!(
                "{kind:?} α = {alpha_deg}°: x = {x:.4e} m{}, caps {caps}, violation {viol:.1e} m",
                if sticks {
                    String::new()
                } else {
                    format!(" ({:+.3} % of ½ a t²)", 100.0 * (x / want - 1.0))
                }
            );
            assert_eq!(caps, 0, "{kind:?} α = {alpha_deg}°");
            if kind != SchemeKind::MoreauJean {
                assert!(
                    viol <= 1e-12,
                    "{kind:?} α = {alpha_deg}°: violation {viol:e}"
                );
            }
            if sticks {
                assert!(x.abs() <= 5e-4, "{kind:?} α = {alpha_deg}°: drift {x} m");
            } else {
                assert!(
                    (x / want - 1.0).abs() < 0.02,
                    "{kind:?} α = {alpha_deg}°: x = {x} m, analytic {want} m"
                );
            }
        }
    }
}
