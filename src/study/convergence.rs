//! `convergence` (Fig. 2: errors in the uniform, l1 and l2 norms against h, with fitted
//! orders) and `projection-multiplier` (Fig. 3, eq. 37: max |τ| = O(h)) on the bouncing
//! ball and the impacting oscillator.

use super::*;

/// Least-squares slope of `log err` against `log h` (zero errors skipped).
pub fn fit_order(h: &[f64], err: &[f64]) -> f64 {
    let pts: Vec<(f64, f64)> = h
        .iter()
        .zip(err)
        .filter(|(_, e)| **e > 0.0)
        .map(|(h, e)| (h.ln(), e.ln()))
        .collect();
    let n = pts.len() as f64;
    let (sx, sy) = pts.iter().fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
    let (mx, my) = (sx / n, sy / n);
    let num: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let den: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    num / den
}

/// Uniform, l1 and l2 norms of `e` sampled every `h`.
pub(super) fn norms(e: &[f64], h: f64) -> [f64; 3] {
    let max = e.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let l1 = h * e.iter().map(|x| x.abs()).sum::<f64>();
    let l2 = (h * e.iter().map(|x| x * x).sum::<f64>()).sqrt();
    [max, l1, l2]
}

/// Steps of the convergence study: h₀ = 0.0137 s times 0.7^j, j = 0 … 11 (down to
/// 2.7e-4). h₀ divides no impact time and the ratio is not a power of 2, so the
/// distance from an impact to the grid varies from one h to the next instead of
/// repeating, which keeps the fitted slopes from aliasing.
pub fn convergence_steps() -> Vec<f64> {
    (0..12).map(|j| 0.0137 * 0.7f64.powi(j)).collect()
}

/// Horizon of the convergence study (s): three impacts (t = 1, 2, 2.5), before the
/// accumulation at t = 3.
pub const CONVERGENCE_T: f64 = 2.6;

/// The fitted orders of one scheme: position then velocity, each uniform / l1 / l2.
#[derive(Clone, Copy, Debug)]
pub struct Orders {
    /// Example (`ball` or `oscillator`).
    pub example: &'static str,
    /// Scheme.
    pub kind: SchemeKind,
    /// Position orders (uniform, l1, l2).
    pub q: [f64; 3],
    /// Velocity orders (uniform, l1, l2).
    pub v: [f64; 3],
}

/// One row of the convergence table: example, scheme, h, errors (q uniform, l1, l2,
/// v uniform, l1, l2).
pub type ErrorRow = (&'static str, SchemeKind, f64, [f64; 6]);

/// Runs the convergence study; returns the fitted orders and the table rows
/// (scheme, h, six errors).
pub fn convergence_orders() -> Result<(Vec<Orders>, Vec<ErrorRow>), Error> {
    let hs = convergence_steps();
    let mut rows = Vec::new();
    let mut orders = Vec::new();
    for x in [
        Example::Ball(BouncingBall::ballard()),
        Example::Oscillator(Oscillator::example()),
    ] {
        for kind in [
            SchemeKind::MoreauJean,
            SchemeKind::SchatzmanPaoli,
            SchemeKind::DirectProjection,
        ] {
            let mut errs = Vec::new();
            for &h in &hs {
                let r = example_run(&x, &params(kind, STUDY_FORECAST), h, CONVERGENCE_T)?;
                let exact = x.exact(&r.t);
                let eq: Vec<f64> = (0..r.t.len()).map(|k| r.q[k] - exact[k].0).collect();
                let ev: Vec<f64> = (0..r.t.len()).map(|k| r.v[k] - exact[k].1).collect();
                let (nq, nv) = (norms(&eq, h), norms(&ev, h));
                let e = [nq[0], nq[1], nq[2], nv[0], nv[1], nv[2]];
                rows.push((x.name(), kind, h, e));
                errs.push(e);
            }
            let col = |i: usize| errs.iter().map(|e| e[i]).collect::<Vec<_>>();
            orders.push(Orders {
                example: x.name(),
                kind,
                q: [0, 1, 2].map(|i| fit_order(&hs, &col(i))),
                v: [3, 4, 5].map(|i| fit_order(&hs, &col(i))),
            });
        }
    }
    Ok((orders, rows))
}

pub(super) fn convergence(dir: &Path) -> Result<Vec<String>, Error> {
    let (orders, rows) = convergence_orders()?;
    let mut csv = String::from("example,scheme,h,q_uniform,q_l1,q_l2,v_uniform,v_l1,v_l2\n");
    for (x, k, h, e) in &rows {
        let _ = writeln!(
            csv,
            "{x},{},{h},{},{},{},{},{},{}",
            k.name(),
            e[0],
            e[1],
            e[2],
            e[3],
            e[4],
            e[5]
        );
    }
    write_atomic(&dir.join("convergence.csv"), csv.as_bytes())?;
    for x in ["ball", "oscillator"] {
        let mut curves = Vec::new();
        for (label, c) in [("q uniform", 0), ("q l1", 1), ("v l1", 4), ("v l2", 5)] {
            for o in orders.iter().filter(|o| o.example == x) {
                curves.push(Curve {
                    name: format!("{} {label}", o.kind.name()),
                    points: rows
                        .iter()
                        .filter(|r| r.0 == x && r.1 == o.kind)
                        .map(|r| (r.2, r.3[c]))
                        .collect(),
                });
            }
        }
        lines(
            &dir.join(format!("convergence-{x}")),
            &format!("{x}: error against h (Fig. 2)"),
            "h (s)",
            "error",
            &curves,
            true,
        )?;
    }
    // expected (theory, Fig. 2): position order 1 in every norm; velocity order 0 in
    // the uniform norm (a jump missed by one step), 1 in l1 and 1/2 in l2
    let want_q = [1.0, 1.0, 1.0];
    let want_v = [0.0, 1.0, 0.5];
    let close = |a: &[f64; 3], b: &[f64; 3]| a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 0.15);
    Ok(orders
        .iter()
        .map(|o| {
            format!(
                "convergence {} {}: position orders {:.2}/{:.2}/{:.2} (uniform/l1/l2; expected 1), \
                 velocity {:.2}/{:.2}/{:.2} (expected 0/1/0.5): {}",
                o.example,
                o.kind.name(),
                o.q[0],
                o.q[1],
                o.q[2],
                o.v[0],
                o.v[1],
                o.v[2],
                if close(&o.q, &want_q) && close(&o.v, &want_v) {
                    "as in Fig. 2"
                } else {
                    "DIFFERS from Fig. 2's orders by more than 0.15"
                }
            )
        })
        .collect())
}

/// One example's projection-multiplier fit: name, points (h, max |τ|), slope.
pub type TauFit = (&'static str, Vec<(f64, f64)>, f64);

/// max |τ| of Algorithm 1 for each h of [`convergence_steps`] (up to t = 2.6) on the
/// ball and on the oscillator: per example, its name, the points (h, max |τ|) and the
/// fitted slope.
pub fn projection_multipliers() -> Result<Vec<TauFit>, Error> {
    let hs = convergence_steps();
    let mut out = Vec::new();
    for x in [
        Example::Ball(BouncingBall::ballard()),
        Example::Oscillator(Oscillator::example()),
    ] {
        let mut pts = Vec::new();
        for &h in &hs {
            let r = example_run(
                &x,
                &params(SchemeKind::DirectProjection, STUDY_FORECAST),
                h,
                CONVERGENCE_T,
            )?;
            pts.push((h, r.tau.iter().fold(0.0f64, |m, x| m.max(x.abs()))));
        }
        let slope = fit_order(&hs, &pts.iter().map(|p| p.1).collect::<Vec<_>>());
        out.push((x.name(), pts, slope));
    }
    Ok(out)
}

pub(super) fn projection_multiplier(dir: &Path) -> Result<Vec<String>, Error> {
    let res = projection_multipliers()?;
    let mut csv = String::from("example,h,max_abs_tau\n");
    for (x, pts, _) in &res {
        for (h, t) in pts {
            let _ = writeln!(csv, "{x},{h},{t}");
        }
    }
    write_atomic(&dir.join("projection-multiplier.csv"), csv.as_bytes())?;
    let curves: Vec<Curve> = res
        .iter()
        .map(|(x, pts, _)| Curve {
            name: format!("{x}: max |τ|"),
            points: pts.clone(),
        })
        .collect();
    lines(
        &dir.join("projection-multiplier"),
        "Algorithm 1: max |τ| against h (Fig. 3)",
        "h (s)",
        "max |τ| (kg·m, M̂⁻¹ metric)",
        &curves,
        true,
    )?;
    Ok(res
        .iter()
        .map(|(x, _, slope)| {
            format!(
                "projection-multiplier {x}: max |τ| = O(h^{slope:.2}) (expected slope 1, eq. 37): {}",
                if (slope - 1.0).abs() <= 0.15 {
                    "as in Fig. 3"
                } else {
                    "DIFFERS from Fig. 3"
                }
            )
        })
        .collect())
}
