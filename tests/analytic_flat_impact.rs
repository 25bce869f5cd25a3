//! A block dropped flat on a rigid floor, its whole base face touching at once, solved on
//! the matrix-free path (`crate::solvers::global`): the active rows exceed the dense
//! one-step workspaces (`scheme.max_active_rows`, set here below the face's node count
//! so that the path runs on a mesh a test can afford; a 100 × 100-node face passes the
//! default cap of 4096 rows by itself, `meshes/wide_block.toml`).
//!
//! With ν = 0 the in-plane and the vertical motions decouple, and a block moving
//! uniformly down is a bundle of the paper's 1-D bars: contact force `E A |v0| / c0`
//! (`c0 = √(E/ρ)`) for `2H/c0`, then release at `+|v0|` (Table 1's solution, DESIGN.md
//! §7, with the face area `A`). Checked for every scheme, and against the dense path of
//! the same scheme (the exact pivoting solvers on the gathered block) step by step.

mod common;

use common::blocks::{contact_sums, undamped_block};
use signorini::integrators::{Integrator, SchemeKind};
use signorini::scene::file::Scene;

const E: f64 = 1e7;
const RHO: f64 = 1000.0;
const V0: f64 = 0.1;
/// Side of the square face and height (m).
const SIDE: f64 = 0.1;
const HEIGHT: f64 = 0.1;

fn c0() -> f64 {
    (E / RHO).sqrt()
}

/// The block of 4 × 4 × 50 hex8 cells (25 contact nodes) at `v0 = −0.1 m/s`, its base on
/// the floor, with `max_active_rows` (0: the default).
fn scene(kind: &str, dt: f64, t_end: f64, max_active_rows: usize) -> String {
    format!(
        r#"
[time]
dt = {dt:e}
t_end = {t_end:e}
[scheme]
kind = "{kind}"
max_active_rows = {max_active_rows}
[[bodies]]
name = "block"
mesh = {{ generator = "box", cell = "hex8", cells = [4, 4, 50], size = [{SIDE}, {SIDE}, {HEIGHT}] }}
material = {{ young = {E:e}, poisson = 0.0, density = {RHO} }}
velocity = [0.0, 0.0, -{V0}]
[[obstacles]]
name = "floor"
type = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
[[contacts]]
body = "block"
nodes = "z0"
obstacle = "floor"
"#
    )
}

struct Outcome {
    force: Vec<f64>,
    global_solves: usize,
    global_products: usize,
    vz: f64,
}

fn run(text: &str) -> Outcome {
    let scene = Scene::from_toml(text).unwrap();
    let (model, _) = scene.build().unwrap();
    let h = scene.time.dt;
    let steps = (scene.time.t_end / h).round() as usize;
    let mut integ = model.into_integrator(&scene.scheme, h).unwrap();
    let mut o = Outcome {
        force: Vec::new(),
        global_solves: 0,
        global_products: 0,
        vz: 0.0,
    };
    for _ in 0..steps {
        integ.prepare().unwrap();
        let st = integ.step().unwrap();
        assert_eq!(st.caps_hit, 0);
        o.global_solves += st.global_solves;
        o.global_products += st.global_products;
        o.force.push(contact_sums(integ.state(), h).0 / h);
    }
    o.vz = mean_vz(integ.as_ref());
    o
}

/// `max |a_i − b_i|` over two force histories.
fn largest_difference(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
}

/// The mass-weighted mean vertical velocity.
fn mean_vz(integ: &dyn Integrator) -> f64 {
    let sys = integ.system();
    let ones: Vec<f64> = sys
        .component
        .iter()
        .map(|&c| if c == 2 { 1.0 } else { 0.0 })
        .collect();
    let mut mv = vec![0.0; sys.ndof()];
    signorini::linalg::spmv(sys.mass.as_ref(), &integ.state().v, &mut mv);
    let p: f64 = mv.iter().zip(&ones).map(|(a, b)| a * b).sum();
    signorini::linalg::spmv(sys.mass.as_ref(), &ones, &mut mv);
    let m: f64 = mv.iter().zip(&ones).map(|(a, b)| a * b).sum();
    p / m
}

/// Mean force over the middle 80 % of the contact interval, and the interval's length.
fn plateau(force: &[f64], h: f64, f_ref: f64) -> (f64, f64) {
    let on: Vec<usize> = (0..force.len())
        .filter(|&k| force[k] > 0.01 * f_ref)
        .collect();
    let (a, b) = (on[0], *on.last().unwrap());
    let (lo, hi) = (a + (b - a) / 10, b - (b - a) / 10);
    let mean = force[lo..=hi].iter().sum::<f64>() / (hi - lo + 1) as f64;
    (mean, (b - a + 1) as f64 * h)
}

/// Every scheme on the matrix-free path: the bars' plateau `E A v0 / c0 = 100 N` within
/// 1 % and the contact time `2H/c0 = 2 ms` within 2 % (50 cells over the height: the
/// force rings around the plateau by a few per cent at onset, and the release is
/// resolved to a step or two of 10 µs; measured 0.1–0.3 % and 0.5–1.5 %), release at
/// `+v0` within 2 % (measured 1.6 %: the 50-cell bundle keeps part of its energy in
/// vibration, where the 1000-element bar of `analytic_bar` keeps under 1 %), 10 % for
/// Schatzman–Paoli (measured 8 %: its impact law acts on positions over two steps); and the dense
/// path of the same scheme step by step: forces equal to 1e-7 of the plateau (both
/// solve each step's problem, the dense one exactly, the matrix-free one to a residual
/// of 1e-12 relative; a missing row or a wrong product shows at 1e-2 and more).
#[test]
fn flat_impact_follows_the_bar_on_the_matrix_free_path() {
    let f_ref = E * SIDE * SIDE * V0 / c0();
    assert!((f_ref - 100.0).abs() < 1e-9);
    let t_ref = 2.0 * HEIGHT / c0();
    let h = 1e-5;
    let t_end = 2.4e-3;
    for kind in SchemeKind::ALL {
        let free = run(&scene(kind.name(), h, t_end, 16));
        assert!(
            free.global_solves > 0,
            "{}: the matrix-free path did not run",
            kind.name()
        );
        let (mean, dur) = plateau(&free.force, h, f_ref);
        assert!(
            (mean / f_ref - 1.0).abs() < 0.01,
            "{}: plateau {mean} N against {f_ref} N",
            kind.name()
        );
        assert!(
            (dur / t_ref - 1.0).abs() < 0.02,
            "{}: contact for {dur} s against {t_ref} s",
            kind.name()
        );
        let tol_v = if kind == SchemeKind::SchatzmanPaoli {
            0.1
        } else {
            0.02
        };
        assert!(
            (free.vz / V0 - 1.0).abs() < tol_v,
            "{}: leaves at {} m/s",
            kind.name(),
            free.vz
        );
        let dense = run(&scene(kind.name(), h, t_end, 0));
        assert_eq!(dense.global_solves, 0);
        let diff = largest_difference(&free.force, &dense.force);
        assert!(
            diff <= 1e-7 * f_ref,
            "{}: matrix-free and dense forces differ by {diff:e} N",
            kind.name()
        );
        eprintln!(
            "{}: plateau {mean:.4} N, {dur:.3e} s, leaves at {:.5} m/s; {} matrix-free \
             solves, {:.1} products each; largest difference to the dense path {diff:.2e} N",
            kind.name(),
            free.vz,
            free.global_solves,
            free.global_products as f64 / free.global_solves as f64
        );
    }
}

/// Coulomb friction on the matrix-free path (the accelerated projected gradient with
/// the fixed point on ‖u_T‖): the undamped block of issue 16 launched at 1 m/s with
/// μ = 0.3 (25 contacts, 75 rows, workspaces capped at 30 rows) decelerates at μg while
/// it slides, as on the dense path: the x-velocity after 0.1 s is `1 − μ g t` within
/// 1e-3 m/s, and within 1e-6 m/s of the dense path's (friction solves stop at 1e-12
/// relative in both; the slip is one state, so the two follow each other to that order
/// times the steps).
#[test]
fn sliding_block_decelerates_at_mu_g_on_the_matrix_free_path() {
    let (mu, g, t) = (0.3, 9.81, 0.1);
    let h = 1e-3;
    let mut v = Vec::new();
    for cap in [30, 0] {
        let text = undamped_block(h, t, "combined-projection", 0.5, mu).replace(
            "theta = 0.5",
            &format!("theta = 0.5\nmax_active_rows = {cap}"),
        );
        let scene = Scene::from_toml(&text).unwrap();
        let (model, _) = scene.build().unwrap();
        let mut integ = model.into_integrator(&scene.scheme, h).unwrap();
        let mut global = 0;
        for _ in 0..(t / h).round() as usize {
            integ.prepare().unwrap();
            let st = integ.step().unwrap();
            assert_eq!(st.caps_hit, 0);
            global += st.global_solves;
        }
        assert_eq!(
            global > 0,
            cap > 0,
            "cap {cap}: {global} matrix-free solves"
        );
        let (p, m) = common::blocks::momentum_x(integ.as_ref());
        v.push(p / m);
    }
    let expect = 1.0 - mu * g * t;
    assert!((v[0] - expect).abs() < 1e-3, "{} against {expect}", v[0]);
    assert!(
        (v[0] - v[1]).abs() < 1e-6,
        "matrix-free {} dense {}",
        v[0],
        v[1]
    );
}

/// Contact between bodies with a nonlinear `G`: two 8³-cell hex8 cubes meeting over a
/// full face (81 node-to-surface contacts, `benches/getfem_two_blocks.py`'s problem).
/// On the per-active-column path (`delassus = "columns"`) the problems past 64 active
/// rows are solved matrix-free instead of re-solving their columns at every
/// linearization (`integrators::core::NONLINEAR_COLUMNS_MAX`); against the dense path
/// condensed on the contact zone (exact solvers on `W = BᵀFB`) the summed contact force
/// agrees to 1e-7 of its peak every step (both solve each step's laws, the matrix-free
/// one to 1e-12 relative; a missing row or a stale column shows at 1e-2).
#[test]
fn two_blocks_on_the_matrix_free_path_match_the_zone_path() {
    let text = |delassus: &str| common::blocks::two_cubes(2e-4, delassus);
    let free = run(&text("columns"));
    let zone = run(&text("dense"));
    assert!(free.global_solves > 0, "the matrix-free path did not run");
    assert_eq!(zone.global_solves, 0);
    let peak = zone.force.iter().fold(0.0f64, |m, f| m.max(*f));
    assert!(peak > 0.0);
    let diff = largest_difference(&free.force, &zone.force);
    assert!(
        diff <= 1e-7 * peak,
        "matrix-free and zone forces differ by {diff:e} N (peak {peak} N)"
    );
    eprintln!(
        "two blocks: peak {peak:.3} N, largest difference {diff:.2e} N; {} matrix-free \
         solves, {:.1} products each",
        free.global_solves,
        free.global_products as f64 / free.global_solves as f64
    );
    // the zone keeping its flexibilities only (`F`, `F_E` bit for bit the same, the
    // corrections by one sparse solve instead of combinations of the columns of
    // `Â⁻¹S`): the same iterates up to the round-off of the corrections, which the
    // Newton loop and the exact solvers carry (1e-9 of the peak; measured below 1e-12)
    let flex = run(&text("flexibility"));
    assert_eq!(flex.global_solves, 0);
    let diff = largest_difference(&flex.force, &zone.force);
    assert!(
        diff <= 1e-9 * peak,
        "flexibility and full zone forces differ by {diff:e} N (peak {peak} N)"
    );
    assert!((flex.vz - zone.vz).abs() <= 1e-9 * zone.vz.abs().max(1e-3));
    eprintln!("two blocks: flexibility against full zone {diff:.2e} N");
}
