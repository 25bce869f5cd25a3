//! Property tests of the friction solvers (issue 11 §2) on random problems: `W = AᵀA + εI`
//! (symmetric positive definite; ε = 0.1 keeps the condition number below ~10⁴ for the
//! sizes drawn), random `q` that make contacts open, stick and slip, random μ ∈ [0, 1.5],
//! in 2-D and 3-D, with frictionless blocks mixed in.
//!
//! Checked on every problem:
//! - the solver reports convergence and its residual ≤ 1e-10 (the tolerance asked), both
//!   Siconos' (one-step solvers) and the velocity residual (the step loop's solvers):
//!   NSGS, PROX and Newton for μ ≤ 0.5; for μ up to 1.5 the Newton solver (NSGS is not
//!   guaranteed to converge for large μ — Coulomb's law is not associated — and CI found
//!   a 2-D case with μ ≈ 1.1 where it cycles at a residual of 0.09, pinned below);
//! - the cone conditions hold block by block to 1e-8 of the problem's scale:
//!   `r_N ≥ 0`, `‖r_T‖ ≤ μ r_N`, `u_N ≥ 0`, `r_N u_N = 0`, and where `u_T ≠ 0`,
//!   `r_T = −μ r_N u_T/‖u_T‖` (maximal dissipation);
//! - NSGS, PROX and the Newton solver agree on `u` to 1e-6 of its scale (`W` is SPD, so
//!   `u` is unique for small μ; the tolerance allows the 1e-10 residuals to differ).

use proptest::prelude::*;
use signorini::solvers::friction::{
    Block, FrictionParams, FrictionProblem, FrictionSolver, FrictionSolverKind, Measure, residual,
    velocity_residual,
};
use signorini::solvers::operator::DenseOperator;

fn spd(k: usize, a: &[f64]) -> Vec<f64> {
    let mut m = vec![0.0; k * k];
    for i in 0..k {
        for j in 0..k {
            let s: f64 = (0..k).map(|p| a[p + i * k] * a[p + j * k]).sum();
            m[i + j * k] = s + if i == j { 0.1 } else { 0.0 };
        }
    }
    m
}

fn solve(
    kind: FrictionSolverKind,
    w: &[f64],
    q: &[f64],
    blocks: &[Block],
) -> (Vec<f64>, Vec<f64>, f64) {
    solve_measured(kind, Measure::Siconos, w, q, blocks)
}

/// As [`solve`], stopping on `measure` (Siconos': the one-step solver; velocity: the
/// step loop's).
fn solve_measured(
    kind: FrictionSolverKind,
    measure: Measure,
    w: &[f64],
    q: &[f64],
    blocks: &[Block],
) -> (Vec<f64>, Vec<f64>, f64) {
    let k = q.len();
    let op = DenseOperator::new(k, w);
    let mut s = match measure {
        Measure::Siconos => FrictionSolver::for_one_step(k),
        Measure::Velocity => FrictionSolver::with_capacity(k),
    };
    assert_eq!(s.measure(), measure);
    let (mut r, mut u) = (vec![0.0; k], vec![0.0; k]);
    let params = FrictionParams {
        solver: kind,
        tol: 1e-10,
        max_iterations: 100_000,
        ..FrictionParams::default()
    };
    let info = s
        .solve(
            FrictionProblem { w: &op, q, blocks },
            &params,
            &mut r,
            &mut u,
        )
        .unwrap();
    assert!(info.converged, "{kind:?}: {info:?}");
    (r, u, info.residual)
}

fn check_cone(blocks: &[Block], q: &[f64], r: &[f64], u: &[f64]) {
    let scale = q
        .iter()
        .chain(r)
        .chain(u)
        .fold(0.0_f64, |a, x| a.max(x.abs()))
        .max(1.0);
    let tol = 1e-8 * scale;
    for b in blocks {
        let (o, d) = (b.offset, b.dim);
        let (rn, un) = (r[o], u[o]);
        let rt: f64 = (1..d).map(|i| r[o + i] * r[o + i]).sum::<f64>().sqrt();
        let ut: f64 = (1..d).map(|i| u[o + i] * u[o + i]).sum::<f64>().sqrt();
        assert!(rn >= -tol && un >= -tol, "r_N {rn}, u_N {un}");
        assert!((rn * un).abs() <= tol * scale, "r_N u_N = {}", rn * un);
        assert!(rt <= b.mu * rn + tol, "‖r_T‖ {rt} > μ r_N {}", b.mu * rn);
        if ut > 1e-6 * scale {
            for i in 1..d {
                let want = -b.mu * rn * u[o + i] / ut;
                assert!((r[o + i] - want).abs() <= 1e-6 * scale, "slip direction");
            }
        }
    }
}

/// Random blocks of dimension `dim` (a third of them frictionless when `mixed`).
fn blocks(dim: usize, n: usize, mus: &[f64], mixed: bool) -> (Vec<Block>, usize) {
    let mut out = Vec::new();
    let mut off = 0;
    for (a, &mu) in mus.iter().enumerate().take(n) {
        let d = if mixed && a % 3 == 2 { 1 } else { dim };
        out.push(Block {
            offset: off,
            dim: d,
            mu: if d == 1 { 0.0 } else { mu },
        });
        off += d;
    }
    (out, off)
}

proptest! {
    // a fixed seed: the same 96 problems on every run (a random seed made CI depend on
    // the draw; the regimes below are what the solvers guarantee)
    #![proptest_config(ProptestConfig {
        cases: 96,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x5167_6e6f_7269_6e69),
        ..ProptestConfig::default()
    })]

    #[test]
    fn friction_solvers_satisfy_the_cone_and_agree(
        dim in 2usize..=3,
        n in 1usize..=6,
        mixed in any::<bool>(),
        a in prop::collection::vec(-1.0f64..1.0, 18 * 18),
        q in prop::collection::vec(-1.0f64..1.0, 18),
        mus in prop::collection::vec(0.0f64..0.5, 6),
    ) {
        let (bl, k) = blocks(dim, n, &mus, mixed);
        let w = spd(k, &a);
        let q = &q[..k];
        let mut us = Vec::new();
        for kind in [FrictionSolverKind::Nsgs, FrictionSolverKind::Prox, FrictionSolverKind::Newton] {
            for measure in [Measure::Siconos, Measure::Velocity] {
                let (r, u, res) = solve_measured(kind, measure, &w, q, &bl);
                prop_assert!(res <= 1e-10);
                // the residual function agrees with the solver's report
                let own = match measure {
                    Measure::Siconos => residual(&bl, q, &r, &u),
                    Measure::Velocity => velocity_residual(&DenseOperator::new(k, &w), &bl, q, &r, &u),
                };
                prop_assert!((own - res).abs() <= 1e-12, "{measure:?}: {own} vs {res}");
                check_cone(&bl, q, &r, &u);
                us.push(u);
            }
        }
        let scale = us[0].iter().fold(1.0_f64, |a, x| a.max(x.abs()));
        // μ ≤ 0.5 with an SPD W: u is unique in practice, the three solvers agree
        for other in &us[1..] {
            for (x, y) in us[0].iter().zip(other) {
                prop_assert!((x - y).abs() <= 1e-6 * scale, "u differs: {x} vs {y}");
            }
        }
    }

    #[test]
    fn the_newton_solver_satisfies_the_cone_for_large_mu(
        dim in 2usize..=3,
        n in 1usize..=6,
        mixed in any::<bool>(),
        a in prop::collection::vec(-1.0f64..1.0, 18 * 18),
        q in prop::collection::vec(-1.0f64..1.0, 18),
        mus in prop::collection::vec(0.0f64..1.5, 6),
    ) {
        let (bl, k) = blocks(dim, n, &mus, mixed);
        let w = spd(k, &a);
        let (r, u, res) = solve(FrictionSolverKind::Newton, &w, &q[..k], &bl);
        prop_assert!(res <= 1e-10);
        check_cone(&bl, &q[..k], &r, &u);
    }
}

/// The 2-D problem (5 contacts, μ up to 1.14) on which CI drew NSGS cycling at a residual
/// of 0.09 after 100 000 sweeps: the Newton solver solves it.
#[test]
fn regression_nsgs_cycles_at_large_mu_and_newton_solves_it() {
    let mut a = vec![0.0; 18 * 18];
    for (i, v) in [
        (4, 0.8165665076399973),
        (7, -0.5900341850306401),
        (27, -0.8818304432586963),
        (31, -0.4940792591148648),
        (32, -0.17385621883248895),
        (33, -0.7166990865950665),
        (35, -0.8416874703829256),
        (37, -0.9869937046062907),
        (38, 0.36403976230362944),
        (39, -0.2164904361516896),
        (61, -0.8607313185199157),
        (62, -0.5615527806013167),
        (63, -0.7833938957501524),
        (65, -0.6946364292465236),
        (66, -0.4515630427250305),
        (71, 0.47902367873520824),
        (72, 0.4379596496284452),
        (77, -0.9460081179565561),
        (79, -0.37038959351362194),
    ] {
        a[i] = v;
    }
    let mut q = vec![0.0; 10];
    q[2] = -0.7060470102005962;
    q[7] = -0.8868022093269443;
    let mus = [0.0, 1.1437300054800537, 0.0, 1.0122038799626316, 0.0, 0.0];
    let (bl, k) = blocks(2, 5, &mus, false);
    assert_eq!(k, 10);
    let w = spd(k, &a);
    let (r, u, res) = solve(FrictionSolverKind::Newton, &w, &q, &bl);
    assert!(res <= 1e-10);
    check_cone(&bl, &q, &r, &u);
    // and NSGS indeed does not converge on it (the limitation docs/friction.md states)
    let op = DenseOperator::new(k, &w);
    let (mut r2, mut u2) = (vec![0.0; k], vec![0.0; k]);
    let info = FrictionSolver::with_capacity(k)
        .solve(
            FrictionProblem {
                w: &op,
                q: &q,
                blocks: &bl,
            },
            &FrictionParams {
                solver: FrictionSolverKind::Nsgs,
                tol: 1e-10,
                max_iterations: 20_000,
                ..FrictionParams::default()
            },
            &mut r2,
            &mut u2,
        )
        .unwrap();
    assert!(!info.converged && info.residual > 1e-3, "{info:?}");
}

/// The three regimes of one 3-D contact, by construction: open (`q_N > 0`), stick (small
/// tangential load), slip (large one), with the exact answers of a diagonal `W`.
#[test]
fn one_contact_open_stick_slip_closed_forms() {
    let w = [2.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 2.0];
    let bl = [Block {
        offset: 0,
        dim: 3,
        mu: 0.5,
    }];
    for kind in [
        FrictionSolverKind::Nsgs,
        FrictionSolverKind::Prox,
        FrictionSolverKind::Newton,
    ] {
        // open: r = 0, u = q
        let (r, u, _) = solve(kind, &w, &[0.3, 1.0, 0.0], &bl);
        assert!(r.iter().all(|x| x.abs() < 1e-12) && (u[1] - 1.0).abs() < 1e-12);
        // stick: r = −q/2 (inside the cone: ‖r_T‖ = 0.1 ≤ 0.5·0.5)
        let (r, u, _) = solve(kind, &w, &[-1.0, 0.2, 0.0], &bl);
        assert!(
            (r[0] - 0.5).abs() < 1e-9 && (r[1] + 0.1).abs() < 1e-9,
            "{kind:?} {r:?}"
        );
        assert!(u.iter().all(|x| x.abs() < 1e-9));
        // slip: r_N = 0.5, r_T = −μ r_N along x, u_T = q_T + 2 r_T = 4 − 0.5
        let (r, u, _) = solve(kind, &w, &[-1.0, 0.0, 4.0], &bl);
        assert!(
            (r[0] - 0.5).abs() < 1e-9 && (r[2] + 0.25).abs() < 1e-9,
            "{kind:?} {r:?}"
        );
        assert!((u[2] - 3.5).abs() < 1e-8 && u[0].abs() < 1e-9);
    }
}
