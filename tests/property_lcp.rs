//! Property tests of the one-step solvers on random problems with P-matrices
//! (`M = AᵀA + εI`, symmetric positive definite, and diagonally dominant
//! nonsymmetric matrices): feasibility and complementarity to 1e-10.

use proptest::prelude::*;
use signorini::solvers::lcp::{BlockPivoting, LcpSolver, Lemke, Pgs};
use signorini::solvers::mlcp::Mlcp;

/// Column-major k×k SPD matrix AᵀA + 0.1 I from entries in [-1, 1].
fn spd(k: usize, a: &[f64]) -> Vec<f64> {
    let mut m = vec![0.0; k * k];
    for i in 0..k {
        for j in 0..k {
            let mut s = 0.0;
            for p in 0..k {
                s += a[p + i * k] * a[p + j * k];
            }
            m[i + j * k] = s + if i == j { 0.1 } else { 0.0 };
        }
    }
    m
}

/// Row-diagonally dominant (hence P) nonsymmetric matrix.
fn dominant(k: usize, a: &[f64]) -> Vec<f64> {
    let mut m: Vec<f64> = a[..k * k].to_vec();
    for i in 0..k {
        let off: f64 = (0..k).filter(|&j| j != i).map(|j| m[i + j * k].abs()).sum();
        m[i + i * k] = off + 0.5 + a[i].abs();
    }
    m
}

fn check(m: &[f64], k: usize, q: &[f64], z: &[f64], tol: f64) {
    let scale = 1.0 + q.iter().fold(0.0_f64, |a, x| a.max(x.abs()));
    for i in 0..k {
        let w: f64 = q[i] + (0..k).map(|j| m[i + j * k] * z[j]).sum::<f64>();
        assert!(z[i] >= -tol * scale, "z[{i}] = {}", z[i]);
        assert!(w >= -tol * scale, "w[{i}] = {w}");
        assert!(
            (z[i] * w).abs() <= tol * scale * scale,
            "z w = {}",
            z[i] * w
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn lemke_solves_spd_lcps(k in 1usize..12, a in prop::collection::vec(-1.0f64..1.0, 144),
                             q in prop::collection::vec(-10.0f64..10.0, 12)) {
        let m = spd(k, &a);
        let mut l = Lemke::with_capacity(12);
        let (mut z, mut w) = (vec![0.0; k], vec![0.0; k]);
        let info = l.solve(&m, k, &q[..k], &mut z, &mut w).unwrap();
        check(&m, k, &q[..k], &z, 1e-10);
        prop_assert!(info.residual <= 1e-10 * (1.0 + q.iter().fold(0.0_f64, |a, x| a.max(x.abs()))));
    }

    #[test]
    fn block_pivoting_solves_spd_lcps_from_any_warm_start(k in 1usize..12,
            a in prop::collection::vec(-1.0f64..1.0, 144),
            q in prop::collection::vec(-10.0f64..10.0, 12),
            warm in prop::collection::vec(-1.0f64..1.0, 12)) {
        let m = spd(k, &a);
        let mut b = BlockPivoting::with_capacity(12);
        let (mut z, mut w) = (warm[..k].to_vec(), vec![0.0; k]);
        b.solve(&m, k, &q[..k], &mut z, &mut w).unwrap();
        check(&m, k, &q[..k], &z, 1e-10);
    }

    #[test]
    fn lemke_solves_nonsymmetric_p_lcps(k in 1usize..12, a in prop::collection::vec(-1.0f64..1.0, 144),
                                        q in prop::collection::vec(-10.0f64..10.0, 12)) {
        let m = dominant(k, &a);
        let mut l = Lemke::with_capacity(12);
        let (mut z, mut w) = (vec![0.0; k], vec![0.0; k]);
        l.solve(&m, k, &q[..k], &mut z, &mut w).unwrap();
        check(&m, k, &q[..k], &z, 1e-10);
    }

    #[test]
    fn pgs_agrees_with_lemke_on_spd(k in 1usize..8, a in prop::collection::vec(-1.0f64..1.0, 64),
                                    q in prop::collection::vec(-10.0f64..10.0, 8)) {
        let m = spd(k, &a);
        let (mut z, mut w) = (vec![0.0; k], vec![0.0; k]);
        // PGS converges for SPD matrices; the cap is generous because AᵀA + 0.1 I can
        // have a condition number of 10³ and PGS converges linearly.
        let pgs = Pgs { tol: 1e-13, max_sweeps: 200_000 };
        pgs.solve(&m, k, &q[..k], &mut z, &mut w).unwrap();
        check(&m, k, &q[..k], &z, 1e-10);
        let mut l = Lemke::with_capacity(8);
        let (mut z2, mut w2) = (vec![0.0; k], vec![0.0; k]);
        l.solve(&m, k, &q[..k], &mut z2, &mut w2).unwrap();
        // SPD ⇒ unique solution; both solvers find it (to the PGS tolerance, amplified
        // by at most the condition number ≤ 1e3·…).
        for i in 0..k {
            prop_assert!((z[i] - z2[i]).abs() <= 1e-6 * (1.0 + z2[i].abs()), "{} vs {}", z[i], z2[i]);
        }
    }

    #[test]
    fn mlcp_meets_equalities_and_complementarity(k in 1usize..10,
            a in prop::collection::vec(-1.0f64..1.0, 100),
            q in prop::collection::vec(-10.0f64..10.0, 10),
            eq in prop::collection::vec(any::<bool>(), 10)) {
        let m = spd(k, &a);
        let mut lcp = LcpSolver::Lemke(Lemke::with_capacity(10));
        let mut s = Mlcp::with_capacity(10);
        let (mut z, mut w) = (vec![0.0; k], vec![0.0; k]);
        s.solve(&m, k, &q[..k], &eq[..k], &mut lcp, &mut z, &mut w).unwrap();
        let scale = 1.0 + q.iter().fold(0.0_f64, |a, x| a.max(x.abs()));
        for i in 0..k {
            let wi: f64 = q[i] + (0..k).map(|j| m[i + j * k] * z[j]).sum::<f64>();
            if eq[i] {
                prop_assert!(wi.abs() <= 1e-10 * scale, "equality row {i}: w = {wi}");
            } else {
                prop_assert!(z[i] >= 0.0 && wi >= -1e-10 * scale && (z[i] * wi).abs() <= 1e-10 * scale * scale);
            }
        }
    }
}
