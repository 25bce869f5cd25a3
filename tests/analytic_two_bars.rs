//! Two elastic bars meeting end to end (contact between bodies, `contact::bodies`),
//! against the 1-D wave solution.
//!
//! **The reference.** A striker of length `L₁` at `v₀` hits a target of length `L₂` at
//! rest, same `E`, `ρ`, `S`, `c = √(E/ρ)`. At contact both ends take the interface
//! velocity `v₀/2` (equal impedances `ρcS`), so the force is `F = ρcS·v₀/2 = ESv₀/(2c)`
//! (635.736 N for Table 1's bar at v₀ = 0.1 m/s: half the rigid-wall force) and a
//! compression wave of particle velocity `−v₀/2` relative to each bar runs into both.
//! The shorter bar's wave comes back from its free end as an unloading wave and
//! reaches the interface at `T = 2 min(L₁, L₂)/c`, when the force drops to zero.
//! - `L₁ = L₂`: exact exchange: the striker stops, the target leaves at `v₀`.
//! - `L₁ < L₂`: the striker is at rest after `T`; the target carries a pulse of length
//!   `2L₁`, and by momentum its mean velocity is `v₀ L₁/L₂`.
//! - `L₁ > L₂`: at `T` the target is stress-free at `v₀` throughout and leaves as a
//!   rigid body at exactly `v₀`; the striker keeps the mean `v₀(1 − L₂/L₁)`.
//!
//! The meshes are the rod of eq. 71 with the paper's element size (1 mm) and
//! `h = 2e-7 s`, about one element transit time (`Δx/c = 1.93e-7 s`).

use signorini::scene::file::Scene;

const E: f64 = 210e9;
const RHO: f64 = 7800.0;
const AREA: f64 = std::f64::consts::PI * 1e-4;
const V0: f64 = 0.1;

fn c0() -> f64 {
    (E / RHO).sqrt()
}

/// A two-rod scene: striker `[−l1, 0]` at `V0`, target `[0, l2]` at rest, 1 mm elements.
fn scene(l1: f64, l2: f64, kind: &str, pairing: &str, t_end: f64) -> Scene {
    let text = format!(
        r#"
[time]
dt = 2e-7
t_end = {t_end}
[scheme]
kind = "{kind}"
[[bodies]]
name = "striker"
mesh = {{ generator = "rod", elements = {n1}, length = {l1}, area = {AREA}, origin = {o1} }}
material = {{ young = {E}, poisson = 0.0, density = {RHO} }}
velocity = [{V0}]
[[bodies]]
name = "target"
mesh = {{ generator = "rod", elements = {n2}, length = {l2}, area = {AREA} }}
material = {{ young = {E}, poisson = 0.0, density = {RHO} }}
[[contacts]]
body = "striker"
nodes = "x1"
target = {{ body = "target", surface = "x0", pairing = "{pairing}" }}
"#,
        n1 = (l1 * 1000.0).round() as usize,
        n2 = (l2 * 1000.0).round() as usize,
        o1 = -l1,
    );
    Scene::from_toml(&text).unwrap()
}

struct Outcome {
    /// Contact force per step (N).
    force: Vec<f64>,
    /// Mean velocities of striker and target at the end (momentum / mass).
    mean_velocity: [f64; 2],
    /// Velocity range (min, max) over each bar's nodes at the end.
    spread: [(f64, f64); 2],
    h: f64,
}

fn run(s: &Scene) -> Outcome {
    let (model, _) = s.build().unwrap();
    let n1 = model.problem.v0.iter().filter(|&&v| v != 0.0).count();
    let mut integ = model.into_integrator(&s.scheme, s.time.dt).unwrap();
    let h = integ.dt();
    let mut force = Vec::with_capacity(s.steps());
    for _ in 0..s.steps() {
        integ.prepare().unwrap();
        integ.step().unwrap();
        force.push(integ.state().impulse[0] / h);
    }
    // momenta through the consistent mass matrix, body by body (striker dofs first)
    let m = &integ.system().mass;
    let v = &integ.state().v;
    let n = v.len();
    let (cp, ri, val) = (m.col_ptr(), m.row_idx(), m.val());
    let (mut p, mut mass) = ([0.0; 2], [0.0; 2]);
    for j in 0..n {
        for k in cp[j]..cp[j + 1] {
            let b = usize::from(ri[k] >= n1);
            p[b] += val[k] * v[j];
            mass[b] += val[k];
        }
    }
    let spread = |r: std::ops::Range<usize>| {
        v[r].iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            })
    };
    Outcome {
        force,
        mean_velocity: [p[0] / mass[0], p[1] / mass[1]],
        spread: [spread(0..n1), spread(n1..n)],
        h,
    }
}

/// Plateau (mean over the middle 80 % of the contact) and duration (force above 1 %
/// of the analytic plateau).
fn plateau(o: &Outcome) -> (f64, f64) {
    let f_ref = E * AREA * V0 / (2.0 * c0());
    let on: Vec<usize> = (0..o.force.len())
        .filter(|&k| o.force[k] > 0.01 * f_ref)
        .collect();
    let (a, b) = (on[0], *on.last().unwrap());
    let dur = (b - a + 1) as f64 * o.h;
    let lo = a + (b - a) / 10;
    let hi = b - (b - a) / 10;
    let mean = o.force[lo..=hi].iter().sum::<f64>() / (hi - lo + 1) as f64;
    (mean, dur)
}

/// The largest difference between two force histories and the largest force of the
/// first.
fn largest_difference(a: &[f64], b: &[f64]) -> (f64, f64) {
    let scale = a.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let diff = a
        .iter()
        .zip(b)
        .fold(0.0_f64, |m, (x, y)| m.max((x - y).abs()));
    (diff, scale)
}

#[test]
fn equal_bars_exchange_their_velocities() {
    let f_ref = E * AREA * V0 / (2.0 * c0());
    assert!((f_ref - 635.736).abs() < 1e-3, "{f_ref}");
    let t_ref = 2.0 / c0();
    assert!((t_ref - 3.8545e-4).abs() < 1e-8);
    for kind in ["moreau-jean", "combined-projection"] {
        let o = run(&scene(1.0, 1.0, kind, "node-to-surface", 6e-4));
        let (f, t) = plateau(&o);
        eprintln!(
            "{kind}: plateau {f:.6} N, duration {t:.4e} s, mean velocities {:?}, spreads {:?}",
            o.mean_velocity, o.spread
        );
        // the P1 rod carries the step wave without dispersion error in its plateau
        // (measured 635.73604 and 635.73603): 1e-5 of the analytic value
        assert!((f / f_ref - 1.0).abs() < 1e-5, "{kind}: plateau {f}");
        // the release is smeared over a few steps by the discrete wave's tail: 1 %
        assert!((t / t_ref - 1.0).abs() < 0.01, "{kind}: duration {t}");
        // exchange: momentum moves whole to the target (to 1e-3 of v0: the residual
        // dispersion of the discrete wave)
        assert!(
            o.mean_velocity[0].abs() < 2e-3 * V0,
            "{kind}: striker {:?}",
            o.mean_velocity
        );
        assert!(
            (o.mean_velocity[1] / V0 - 1.0).abs() < 2e-3,
            "{kind}: target {:?}",
            o.mean_velocity
        );
        // after separation the force is zero
        assert!(o.force[o.force.len() - 100..].iter().all(|&x| x == 0.0));
    }
}

#[test]
fn unequal_bars_follow_the_wave_solution() {
    let f_ref = E * AREA * V0 / (2.0 * c0());
    // (L₁, L₂, mean velocities after): the shorter striker stops and the target carries
    // v₀ L₁/L₂; the longer striker keeps v₀(1 − L₂/L₁) and the target leaves at v₀. Both
    // last 2 · 0.5 m / c. A velocity expected 0 is checked to 2e-3 v₀, the others to
    // 2e-3 of themselves.
    for (l1, l2, want) in [(0.5, 1.0, [0.0, 0.5 * V0]), (1.0, 0.5, [0.5 * V0, V0])] {
        let o = run(&scene(
            l1,
            l2,
            "combined-projection",
            "node-to-surface",
            5e-4,
        ));
        let (f, t) = plateau(&o);
        eprintln!(
            "L1 = {l1}, L2 = {l2}: plateau {f:.6}, duration {t:.4e} (ref {:.4e}), means {:?}, \
             spreads {:?}",
            1.0 / c0(),
            o.mean_velocity,
            o.spread
        );
        assert!((f / f_ref - 1.0).abs() < 1e-4, "{l1}: plateau {f}");
        assert!((t * c0() - 1.0).abs() < 0.01, "{l1}: duration {t}");
        for (v, w) in o.mean_velocity.iter().zip(want) {
            let tol = 2e-3 * if w == 0.0 { V0 } else { w };
            assert!((v - w).abs() < tol, "{l1}: {:?}", o.mean_velocity);
        }
    }
}

#[test]
fn node_to_node_pairing_gives_the_node_to_surface_history() {
    let a = run(&scene(
        1.0,
        1.0,
        "combined-projection",
        "node-to-surface",
        5e-4,
    ));
    let b = run(&scene(
        1.0,
        1.0,
        "combined-projection",
        "node-to-node",
        5e-4,
    ));
    let (diff, scale) = largest_difference(&a.force, &b.force);
    // the same constraint written two ways (g = n·(x_s − x_m) against g₀ + n·(u_s − u_m)):
    // round-off apart
    assert!(diff <= 1e-9 * scale, "{diff} of {scale}");
}

/// `meshes/hex_bars.toml` coarsened (striker 100 × 1 × 1 hex8 cells, target 75 × 2 × 2:
/// non-matching at the interface, each of the striker's 4 end nodes against the
/// target's 4 end quads) at `h = 1e-6 s`, with `--set`-style overrides.
fn hex_scene(extra: &[&str]) -> Scene {
    let mut set: Vec<String> = [
        "bodies[0].mesh.cells=[100,1,1]",
        "bodies[1].mesh.cells=[75,2,2]",
        "time.dt=1e-6",
        "time.t_end=6e-4",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    set.extend(extra.iter().map(|s| s.to_string()));
    Scene::from_file_with(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/hex_bars.toml"),
        &set,
    )
    .unwrap()
}

#[test]
fn hex8_bars_meshed_non_matching_give_the_rod_plateau() {
    use signorini::app::run_scene;
    use signorini::run::Quiet;
    let f_ref = E * AREA * V0 / (2.0 * c0());
    let t_ref = 2.0 / c0();
    for kind in ["moreau-jean", "combined-projection"] {
        let s = hex_scene(&[&format!("scheme.kind=\"{kind}\"")]);
        let r = run_scene(&s, None, &mut Quiet).unwrap();
        let o = Outcome {
            force: r.force.clone(),
            mean_velocity: [0.0; 2],
            spread: [(0.0, 0.0); 2],
            h: s.time.dt,
        };
        let (f, t) = plateau(&o);
        let [e0, e1] = r.summary.energy;
        eprintln!(
            "{kind}: plateau {f:.4} N, duration {t:.4e} s, energy {e0:.9e} → {e1:.9e}, \
             violation {:e}",
            r.summary.max_violation
        );
        // ν = 0: plane sections stay plane and the 3-D bars carry the rods' waves; the
        // non-matching interface and the coarse mesh cost little (measured +2.2e-5 and
        // +0.9 %): issue 3's tolerances for the hex bar on a wall, 1 % and 2 %
        assert!((f / f_ref - 1.0).abs() < 0.01, "{kind}: plateau {f}");
        assert!((t / t_ref - 1.0).abs() < 0.02, "{kind}: duration {t}");
        // no damping, but the e = 0 impact law takes the interface nodes' relative
        // velocity when the discrete interface first closes (the consistent mass puts
        // mass on them): measured 4.1e-4 (Moreau–Jean) and 2.5e-4 (Algorithm 2), all of
        // it in the first step; then the energy is kept (4e-8)
        assert!(
            e1 < e0 && (e1 / e0 - 1.0).abs() < 1e-3,
            "{kind}: energy {e0} → {e1}"
        );
        if kind == "combined-projection" {
            assert!(r.summary.max_violation <= 1e-14, "{kind}");
        }
    }
}

#[test]
fn redistributed_mass_on_both_sides_removes_the_impact_loss() {
    use signorini::app::run_scene;
    use signorini::run::Quiet;
    // Khenous–Laborde–Renard: no mass on the contact nodes of either side, so the
    // closing interface has no inertia to lose. Algorithm 2, energy lost over the run:
    // consistent mass 2.5e-4, redistributed on the striker only 1.2e-4, on both sides
    // 5.0e-6 (measured)
    let loss = |extra: &[&str]| {
        let mut set = vec!["scheme.kind=\"combined-projection\""];
        set.extend_from_slice(extra);
        let r = run_scene(&hex_scene(&set), None, &mut Quiet).unwrap();
        let [e0, e1] = r.summary.energy;
        1.0 - e1 / e0
    };
    let both = loss(&[
        "bodies[0].mass=\"redistributed\"",
        "bodies[1].mass=\"redistributed\"",
    ]);
    let one = loss(&["bodies[0].mass=\"redistributed\""]);
    eprintln!("energy lost: both sides {both:e}, striker only {one:e}");
    assert!((0.0..2e-5).contains(&both), "{both}");
    assert!(one > 5.0 * both, "{one} against {both}");
}

#[test]
fn condensed_zone_and_per_column_delassus_agree() {
    use signorini::app::run_scene;
    use signorini::run::Quiet;
    // the zone condensation (auto, dense) against the columns path, which solves with
    // the factor for every column: the same iterates to round-off (measured 5e-15)
    let a = run_scene(&hex_scene(&[]), None, &mut Quiet).unwrap();
    let b = run_scene(
        &hex_scene(&["scheme.delassus=\"columns\""]),
        None,
        &mut Quiet,
    )
    .unwrap();
    assert!(
        a.summary.path.contains("contact zone"),
        "{}",
        a.summary.path
    );
    assert!(
        b.summary.path.contains("per-active-column"),
        "{}",
        b.summary.path
    );
    let (diff, scale) = largest_difference(&a.force, &b.force);
    assert!(diff <= 1e-9 * scale, "{diff} of {scale}");
}
