//! Residuals of the frictional contact law: the projection on Coulomb's cone, the
//! natural map of De Saxcé's form (FCLIB's measure, eq. 13–15) and the Alart–Curnier map
//! the step loop's solvers stop on.

use super::super::operator::DelassusOperator;
use super::Block;

/// Projection of `x = (x_N, x_T)` on the cone `‖x_T‖ ≤ μ x_N` (in place).
pub fn project_on_cone(x: &mut [f64], mu: f64) {
    let xn = x[0];
    if x.len() == 1 || mu == 0.0 {
        x[0] = xn.max(0.0);
        x[1..].iter_mut().for_each(|t| *t = 0.0);
        return;
    }
    let nt = norm(&x[1..]);
    if nt <= mu * xn {
        return;
    }
    if mu * nt <= -xn {
        x.iter_mut().for_each(|t| *t = 0.0);
        return;
    }
    let rn = (mu * nt + xn) / (1.0 + mu * mu);
    let s = mu * rn / nt;
    x[0] = rn;
    x[1..].iter_mut().for_each(|t| *t *= s);
}

pub(in crate::solvers) fn norm(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum::<f64>().sqrt()
}

/// Squared natural-map error of one block: `‖r − P_C(r − û)‖²`, `û = u + μ‖u_T‖ e_N`.
pub(super) fn block_error2(r: &[f64], u: &[f64], mu: f64) -> f64 {
    let d = r.len();
    let mut x = [0.0; 3];
    let ut = norm(&u[1..d]);
    x[0] = r[0] - (u[0] + mu * ut);
    for i in 1..d {
        x[i] = r[i] - u[i];
    }
    project_on_cone(&mut x[..d], mu);
    (0..d).map(|i| (r[i] - x[i]).powi(2)).sum()
}

/// Siconos' residual `‖r − P_C(r − û)‖ / max(‖q‖, ‖r‖, ‖u‖)` for `u` already equal to
/// `W r + q`.
pub fn residual(blocks: &[Block], q: &[f64], r: &[f64], u: &[f64]) -> f64 {
    let e2: f64 = blocks
        .iter()
        .map(|b| {
            let s = b.offset..b.offset + b.dim;
            block_error2(&r[s.clone()], &u[s], b.mu)
        })
        .sum();
    relative(e2.sqrt(), blocks, q, r, u)
}

/// `e / max(‖q‖, ‖r‖, ‖u‖)` over the rows of `blocks` (no division when that maximum is
/// at most machine epsilon), the scale of Siconos' residual.
pub(super) fn relative(e: f64, blocks: &[Block], q: &[f64], r: &[f64], u: &[f64]) -> f64 {
    let k = blocks.last().map_or(0, |b| b.offset + b.dim);
    let scale = norm(&q[..k]).max(norm(&r[..k])).max(norm(&u[..k]));
    if scale <= f64::EPSILON { e } else { e / scale }
}

/// Where [`residual`] is at most `tol`, raises it to the take-off error
/// `max |u_N| / max(‖q‖, ‖r‖, ‖u‖)` over the blocks with `r_N ≤ 0` and `u_N < 0`.
/// De Saxcé's complementarity accepts `r = 0` with `u_N < 0` when `μ‖u_T‖` is large
/// (`û ∈ C*` as soon as `u_N ≥ ‖u_T‖ (1/μ − μ)`): Siconos' residual then reads 0 at
/// `r = 0` (μ = 1e300 reported "converged, residual 0" with `u_N = −1`), while
/// Coulomb's law with Signorini's condition requires `u_N ≥ 0` on an open contact.
pub fn checked_residual(blocks: &[Block], q: &[f64], r: &[f64], u: &[f64], tol: f64) -> f64 {
    let res = residual(blocks, q, r, u);
    if res.is_nan() || res > tol {
        return res;
    }
    let worst = blocks
        .iter()
        .filter(|b| r[b.offset] <= 0.0 && u[b.offset] < 0.0)
        .map(|b| -u[b.offset])
        .fold(0.0, f64::max);
    if worst == 0.0 {
        return res;
    }
    res.max(relative(worst, blocks, q, r, u))
}

/// `‖Φ_α‖²` of one block's Alart–Curnier map with `ρ` on every row:
/// `Φ_N = r_N − max(0, r_N − ρ u_N)`, `Φ_T = r_T − P_{B(μ p_N)}(r_T − ρ u_T)` with
/// `p_N = max(0, r_N − ρ u_N)` (the `Φ` of [`super::newton`]). It states Coulomb's law
/// itself, not De Saxcé's: a sticking block reads `ρ‖u‖` whatever μ, where the natural
/// map of [`residual`] reads `‖u + μ‖u_T‖ e_N‖`, `μ` times the round-off of `u_T`
/// (μ = 1e6: a floor near 1e-10 that no solver can pass), and a block taking off with
/// `u_N < 0` reads `ρ|u_N|`, so no take-off check is needed.
pub(in crate::solvers) fn ac_map2(r: &[f64], u: &[f64], mu: f64, rho: f64) -> f64 {
    let d = r.len();
    let xn = r[0] - rho * u[0];
    let pn = xn.max(0.0);
    let mut e2 = (r[0] - pn).powi(2);
    if d == 1 {
        return e2;
    }
    let mut xt = [0.0; 2];
    for t in 0..d - 1 {
        xt[t] = r[1 + t] - rho * u[1 + t];
    }
    let nx = norm(&xt[..d - 1]);
    let rad = mu * pn;
    let f = if nx <= rad { 1.0 } else { rad / nx };
    for t in 0..d - 1 {
        e2 += (r[1 + t] - f * xt[t]).powi(2);
    }
    e2
}

/// The residual of the step loop's friction solves, in velocity units and relative:
/// `(Σ_α ‖Φ_α‖² / ρ_α²)^½ / max(‖q‖, ‖u‖, ‖D r‖)` with [`ac_map2`]'s `Φ_α` at
/// `ρ_α = 1/W_NN` of the block and `D` the blocks' `W_NN` (`diag`, the 3×3 diagonal
/// blocks, row-major, indexed by offset). Every term is a velocity, so one tolerance
/// means the same for a 10 kg body and a 1 mg node, and μ does not amplify the
/// round-off of `u_T` (module doc of [`residual`]'s difference). Blocks with
/// `W_NN ≤ 0` read infinitely wrong.
pub(in crate::solvers) fn velocity_residual_diag(
    blocks: &[Block],
    diag: &[[f64; 9]],
    q: &[f64],
    r: &[f64],
    u: &[f64],
) -> f64 {
    let (mut e2, mut dr2) = (0.0, 0.0);
    for b in blocks {
        let s = b.offset..b.offset + b.dim;
        let wnn = diag[b.offset][0];
        if wnn.is_nan() || wnn <= 0.0 {
            return f64::INFINITY;
        }
        e2 += ac_map2(&r[s.clone()], &u[s.clone()], b.mu, 1.0 / wnn) * wnn * wnn;
        dr2 += r[s].iter().map(|x| (wnn * x).powi(2)).sum::<f64>();
    }
    let k = blocks.last().map_or(0, |b| b.offset + b.dim);
    let scale = norm(&q[..k]).max(norm(&u[..k])).max(dr2.sqrt());
    if scale <= f64::MIN_POSITIVE {
        e2.sqrt()
    } else {
        e2.sqrt() / scale
    }
}

/// [`Measure::Velocity`](super::Measure::Velocity)'s residual of `(r, u)` (`u = W r + q`) for the operator `w`:
/// the form the step loop's solvers stop on (`velocity_residual_diag`). Allocates its
/// diagonal: for checks outside the solvers.
pub fn velocity_residual<W: DelassusOperator + ?Sized>(
    w: &W,
    blocks: &[Block],
    q: &[f64],
    r: &[f64],
    u: &[f64],
) -> f64 {
    let k = blocks.last().map_or(0, |b| b.offset + b.dim);
    let mut diag = vec![[0.0; 9]; k];
    for b in blocks {
        diag[b.offset][0] = w.entry(b.offset, b.offset);
    }
    velocity_residual_diag(blocks, &diag, q, r, u)
}

/// The velocity accuracy of a solution, in m/s: the largest over the blocks of
/// `‖Φ_α‖ / ρ` with `ac_map2`'s Alart–Curnier map at `ρ = 1/W_NN` of the block, so
/// that an impulse error counts by the velocity it makes. Unlike [`residual`], which
/// adds impulses and velocities, it means the same for a 10 kg body and a 1 mg node,
/// and μ does not amplify it; the step loop derives its Newton stopping floor from it
/// ([`crate::integrators::core`]). Blocks with `W_NN ≤ 0` count as infinitely wrong.
pub fn velocity_error<W: DelassusOperator + ?Sized>(
    w: &W,
    blocks: &[Block],
    r: &[f64],
    u: &[f64],
) -> f64 {
    let mut worst: f64 = 0.0;
    for b in blocks {
        let s = b.offset..b.offset + b.dim;
        let wnn = w.entry(b.offset, b.offset);
        if wnn.is_nan() || wnn <= 0.0 {
            return f64::INFINITY;
        }
        worst = worst.max(ac_map2(&r[s.clone()], &u[s], b.mu, 1.0 / wnn).sqrt() * wnn);
    }
    worst
}
