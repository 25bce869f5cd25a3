//! Exact solves of one contact block (2-D by enumeration of the law's cases, 3-D by a
//! damped Alart–Curnier Newton), the inner step of the Gauss–Seidel sweeps.

use super::project_on_cone;

/// Solves one block exactly: `u = W r + q` (W is `d × d`, row-major in a 3×3 array)
/// with `C* ∋ û ⊥ r ∈ C`. `r` holds the warm start (used by the 3-D Newton). Returns
/// false when no case of the 2-D law is consistent (`W_αα` not positive definite, or
/// round-off on a sign): `r` is then the least inconsistent case, and the caller counts
/// it ([`FrictionInfo::inconsistent_local_solves`](super::FrictionInfo::inconsistent_local_solves)).
pub fn solve_local(
    w: &[f64; 9],
    q: &[f64; 3],
    mu: f64,
    d: usize,
    max_it: usize,
    r: &mut [f64; 3],
) -> bool {
    match d {
        1 => {
            r[0] = if q[0] >= 0.0 || w[0] <= 0.0 {
                0.0
            } else {
                -q[0] / w[0]
            };
            true
        }
        2 => solve_local_2d(w, q, mu, r),
        _ => {
            solve_local_3d(w, q, mu, max_it, r);
            true
        }
    }
}

/// The 2-D law in closed form: the first consistent case of open, stick, slip with
/// `u_T > 0` (`r_T = −μ r_N`), slip with `u_T < 0` (`r_T = μ r_N`).
fn solve_local_2d(w: &[f64; 9], q: &[f64; 3], mu: f64, r: &mut [f64; 3]) -> bool {
    let (wnn, wnt, wtn, wtt) = (w[0], w[1], w[3], w[4]);
    let (qn, qt) = (q[0], q[1]);
    r[2] = 0.0;
    if qn >= 0.0 {
        r[0] = 0.0;
        r[1] = 0.0;
        return true;
    }
    // stick: W r = −q
    let det = wnn * wtt - wnt * wtn;
    if det > 0.0 {
        let rn = (-qn * wtt + qt * wnt) / det;
        let rt = (-qt * wnn + qn * wtn) / det;
        if rn >= 0.0 && rt.abs() <= mu * rn {
            r[0] = rn;
            r[1] = rt;
            return true;
        }
    }
    // slip: r_T = −s μ r_N with s = sign(u_T)
    let mut best = (f64::INFINITY, 0.0, 0.0);
    for s in [1.0, -1.0] {
        let den = wnn - s * mu * wnt;
        if den <= 0.0 {
            continue;
        }
        let rn = -qn / den;
        let rt = -s * mu * rn;
        let ut = wtn * rn + wtt * rt + qt;
        if rn >= 0.0 && s * ut >= 0.0 {
            r[0] = rn;
            r[1] = rt;
            return true;
        }
        // keep the least inconsistent case (round-off on a sign)
        let viol = (-s * ut).max(0.0);
        if viol < best.0 {
            best = (viol, rn, rt);
        }
    }
    r[0] = best.1;
    r[1] = best.2;
    false
}

/// The Alart–Curnier function of a 3-D block and (optionally) one element of its
/// generalized Jacobian (row-major 3×3), with `ρ_N = 1/W_NN`, `ρ_T = 2/(W_T1T1 + W_T2T2)`.
fn alart_curnier(
    w: &[f64; 9],
    q: &[f64; 3],
    mu: f64,
    rho: (f64, f64),
    r: &[f64; 3],
    jac: Option<&mut [f64; 9]>,
) -> [f64; 3] {
    let mut u = [0.0; 3];
    for i in 0..3 {
        u[i] = q[i] + w[3 * i] * r[0] + w[3 * i + 1] * r[1] + w[3 * i + 2] * r[2];
    }
    let (rn_, rt_) = rho;
    let xn = r[0] - rn_ * u[0];
    let pn = xn.max(0.0);
    let xt = [r[1] - rt_ * u[1], r[2] - rt_ * u[2]];
    let nx = (xt[0] * xt[0] + xt[1] * xt[1]).sqrt();
    let rad = mu * pn;
    let inside = nx <= rad;
    let (pt0, pt1) = if inside {
        (xt[0], xt[1])
    } else {
        (rad * xt[0] / nx, rad * xt[1] / nx)
    };
    let phi = [r[0] - pn, r[1] - pt0, r[2] - pt1];
    if let Some(j) = jac {
        // dΦ_N
        if xn > 0.0 {
            for c in 0..3 {
                j[c] = rn_ * w[c];
            }
        } else {
            j[0] = 1.0;
            j[1] = 0.0;
            j[2] = 0.0;
        }
        // dx_T/dr = [0 I] − ρ_T W_T
        let mut dxt = [[0.0; 3]; 2];
        for a in 0..2 {
            for c in 0..3 {
                dxt[a][c] = -rt_ * w[3 * (a + 1) + c];
            }
            dxt[a][a + 1] += 1.0;
        }
        if inside {
            for a in 0..2 {
                for c in 0..3 {
                    j[3 * (a + 1) + c] = -dxt[a][c];
                }
                j[3 * (a + 1) + a + 1] += 1.0;
            }
        } else {
            // dR/dr = μ dp_N/dr
            let mut dr = [0.0; 3];
            if xn > 0.0 {
                for c in 0..3 {
                    dr[c] = -mu * rn_ * w[c];
                }
                dr[0] += mu;
            }
            let xh = [xt[0] / nx, xt[1] / nx];
            let f = rad / nx;
            for a in 0..2 {
                for c in 0..3 {
                    let mut proj = 0.0;
                    for b in 0..2 {
                        let pab = if a == b { 1.0 } else { 0.0 } - xh[a] * xh[b];
                        proj += pab * dxt[b][c];
                    }
                    j[3 * (a + 1) + c] = -xh[a] * dr[c] - f * proj;
                }
                j[3 * (a + 1) + a + 1] += 1.0;
            }
        }
    }
    phi
}

/// Semismooth Newton on Alart–Curnier with an Armijo line search on `½‖Φ‖²`, then
/// the projected fixed point if Newton did not reach round-off.
fn solve_local_3d(w: &[f64; 9], q: &[f64; 3], mu: f64, max_it: usize, r: &mut [f64; 3]) {
    if q[0] >= 0.0 {
        // û_N ≥ u_N = q_N ≥ 0 at r = 0: the block opens
        *r = [0.0; 3];
        return;
    }
    // stick, exactly: W r = −q with r inside the cone (u = 0, so û = 0). Tried first:
    // with a large μ every block sticks, and there the Alart–Curnier Newton, whose
    // residual weighs u_T by μ, stalled (μ = 1e3 and 1e6 failed the sliding block at
    // step 1 before this test).
    if let Some(s) = solve3(w, &[-q[0], -q[1], -q[2]])
        && s[0] > 0.0
        && (s[1] * s[1] + s[2] * s[2]).sqrt() <= mu * s[0]
    {
        *r = s;
        return;
    }
    let rho = (
        1.0 / w[0].max(f64::MIN_POSITIVE),
        2.0 / (w[4] + w[8]).max(f64::MIN_POSITIVE),
    );
    let scale = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt() * rho.0.max(rho.1);
    let target = 1e-15 * scale.max(f64::MIN_POSITIVE);
    let mut jac = [0.0; 9];
    let mut phi = alart_curnier(w, q, mu, rho, r, Some(&mut jac));
    let mut f = 0.5 * (phi[0] * phi[0] + phi[1] * phi[1] + phi[2] * phi[2]);
    for _ in 0..max_it {
        if f.sqrt() <= target {
            return;
        }
        let Some(dx) = solve3(&jac, &[-phi[0], -phi[1], -phi[2]]) else {
            break;
        };
        let mut t = 1.0;
        let mut accepted = false;
        for _ in 0..30 {
            let trial = [r[0] + t * dx[0], r[1] + t * dx[1], r[2] + t * dx[2]];
            let p = alart_curnier(w, q, mu, rho, &trial, None);
            let ft = 0.5 * (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
            if ft <= (1.0 - 1e-4 * t) * f {
                *r = trial;
                accepted = true;
                break;
            }
            t *= 0.5;
        }
        if !accepted {
            break;
        }
        phi = alart_curnier(w, q, mu, rho, r, Some(&mut jac));
        f = 0.5 * (phi[0] * phi[0] + phi[1] * phi[1] + phi[2] * phi[2]);
    }
    if f.sqrt() <= target {
        return;
    }
    // fallback: r ← P_C(r − ρ û), ρ = 1/λmax estimate (the largest Gershgorin bound)
    let lam = (0..3)
        .map(|i| (0..3).map(|j| w[3 * i + j].abs()).sum::<f64>())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let rho = 1.0 / lam;
    for _ in 0..20 * max_it {
        let mut u = [0.0; 3];
        for i in 0..3 {
            u[i] = q[i] + w[3 * i] * r[0] + w[3 * i + 1] * r[1] + w[3 * i + 2] * r[2];
        }
        let ut = (u[1] * u[1] + u[2] * u[2]).sqrt();
        let mut x = [
            r[0] - rho * (u[0] + mu * ut),
            r[1] - rho * u[1],
            r[2] - rho * u[2],
        ];
        project_on_cone(&mut x, mu);
        let step = ((x[0] - r[0]).powi(2) + (x[1] - r[1]).powi(2) + (x[2] - r[2]).powi(2)).sqrt();
        *r = x;
        if step <= 1e-16 * (r[0].abs() + r[1].abs() + r[2].abs()).max(f64::MIN_POSITIVE) {
            break;
        }
    }
}

/// Solves the 3×3 system `a x = b` (row-major) by Gaussian elimination with partial
/// pivoting; `None` when singular. Ours rather than nalgebra's fixed-size LU (tried, issue
/// 16 §7): the same algorithm with other roundings, which moved the NSGS iterate that
/// `auto`'s plain Newton stage continues from, and on spheres-in-a-box that Newton then
/// took 1 089 iterations and 2.2 s instead of 125 and 0.40 s (the plain Newton is that
/// sensitive to the last bits of its start, as Siconos' NSN_AC is to those of `W`).
fn solve3(a: &[f64; 9], b: &[f64; 3]) -> Option<[f64; 3]> {
    let mut m = [
        [a[0], a[1], a[2], b[0]],
        [a[3], a[4], a[5], b[1]],
        [a[6], a[7], a[8], b[2]],
    ];
    let amax = a.iter().fold(0.0_f64, |s, x| s.max(x.abs()));
    for c in 0..3 {
        let p = (c..3)
            .max_by(|&i, &j| m[i][c].abs().total_cmp(&m[j][c].abs()))
            .expect("rows");
        if m[p][c].abs() <= 1e-14 * amax {
            return None;
        }
        m.swap(c, p);
        for i in c + 1..3 {
            let f = m[i][c] / m[c][c];
            for j in c..4 {
                m[i][j] -= f * m[c][j];
            }
        }
    }
    let mut x = [0.0; 3];
    for i in (0..3).rev() {
        let mut s = m[i][3];
        for j in i + 1..3 {
            s -= m[i][j] * x[j];
        }
        x[i] = s / m[i][i];
    }
    Some(x)
}
