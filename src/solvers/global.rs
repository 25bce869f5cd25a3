//! Matrix-free one-step solvers for active sets past the dense workspaces: they touch the
//! Delassus operator `W` only through products `W x` ([`DelassusOperator::mul_add`]),
//! never through its entries, so `W` need not exist as a matrix. In the step loop a
//! product is `Gᵀ Â⁻¹ (G x)`, one sparse solve with the step matrix's factor
//! ([`crate::delassus::Delassus::product`]); the global form of the contact problem
//! (`Â v = G r + f`, `u = Gᵀ v`) is solved without condensing `W`.
//!
//! * [`GlobalSolver::solve_box`]: the LCP `0 ≤ z ⊥ w = A z + q ≥ 0` of eq. 57 (and the
//!   projection LCP of eq. 58), with equality rows (`w = 0`, `z` free) for Algorithm 2's
//!   MLCP (eq. 68). For a symmetric positive semi-definite `A` it is the bound-constrained
//!   quadratic program `min ½zᵀAz + qᵀz`, `z_i ≥ 0` off the equality rows, solved by
//!   Dostál's MPRGP (modified proportioning with reduced gradient projections; Z. Dostál,
//!   *Optimal Quadratic Programming Algorithms*, Springer 2009, ch. 5): conjugate
//!   gradients on the free rows, expansion steps `P(z − ᾱ φ)` when a step would leave
//!   the bounds, proportioning steps that free the rows whose gradient points inside.
//!   Its rate is that of CG, `√κ(A)` iterations per digit, one product each.
//! * [`GlobalSolver::solve_friction`]: Coulomb's law (eq. 15, De Saxcé's modified velocity
//!   of eq. 13) by the fixed point on `s = ‖u_T‖` of Acary, Cadoux, Lemaréchal and
//!   Malick (*A formulation of the linear discrete Coulomb friction problem via convex
//!   optimization*, ZAMM 2011): for fixed `s` the problem is the second-order-cone
//!   quadratic program `min ½rᵀAr + (q + μ s e_N)ᵀr`, `r_α ∈ C_α`, solved by Nesterov's
//!   accelerated projected gradient with gradient restarts (O'Donoghue–Candès 2015; the
//!   APGD of Mazhar, Heyn, Negrut and Tasora, ACM TOG 2015), one product per iteration;
//!   `s` is then updated from `u = A r + q` until the Alart–Curnier residual vanishes.
//!
//! Both estimate the largest eigenvalue `L` of `A` by a few power iterations (the step
//! `1/L`; an objective that rises doubles `L`). They stop on a relative residual in
//! velocity units, `‖w^P‖ / max(‖q‖, ‖A z‖)` with the projected gradient `w^P`
//! (MPRGP), or the Alart–Curnier map at `ρ = 1/L` divided by `ρ` (friction), and report
//! products, residual and whether they converged as data. A run of them in the step loop
//! costs `products` sparse solves, against the dense path's one column per active row
//! and a dense factorization of the active block: they are the path for thousands of
//! active rows (a body resting on a face of 10⁴ nodes), not for the tens of the bar.
//!
//! Written here: no Rust crate offers bound- or cone-constrained QP solvers that take a
//! product callback (checked on crates.io: `clarabel` and `osqp` need the matrix).
//! All buffers are sized once ([`GlobalSolver::with_capacity`]); solving does not
//! allocate.

use super::friction::{Block, ac_map2, project_on_cone};
use super::operator::DelassusOperator;

/// Power iterations for the estimate of `‖A‖` (the step length of the projections).
const POWER_ITERATIONS: usize = 10;
/// Iterations of MPRGP between recomputations of the gradient from a product (the
/// recurrence `g ← g − α A p` drifts by round-off).
const REFRESH: usize = 50;
/// MPRGP's proportioning constant Γ (Dostál's default 1).
const GAMMA: f64 = 1.0;

/// What a global solve reports.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GlobalInfo {
    /// Products with the operator (each one sparse solve in the step loop).
    pub products: usize,
    /// Relative residual reached (module doc).
    pub residual: f64,
    /// Outer fixed-point iterations on `s` (friction; 0 for the LCP).
    pub outer: usize,
    /// The residual reached the tolerance.
    pub converged: bool,
    /// Velocity accuracy in m/s (the residual times its scale): the step loop's
    /// counterpart of [`super::friction::velocity_error`].
    pub accuracy: f64,
}

/// Buffers of the global solvers, sized once for `capacity` rows.
#[derive(Debug, Default)]
pub struct GlobalSolver {
    cap: usize,
    g: Vec<f64>,
    p: Vec<f64>,
    ap: Vec<f64>,
    x: Vec<f64>,
    ax: Vec<f64>,
    y: Vec<f64>,
    ay: Vec<f64>,
    qs: Vec<f64>,
}

impl GlobalSolver {
    /// Buffers for problems of up to `capacity` rows.
    pub fn with_capacity(capacity: usize) -> Self {
        let v = || vec![0.0; capacity];
        GlobalSolver {
            cap: capacity,
            g: v(),
            p: v(),
            ap: v(),
            x: v(),
            ax: v(),
            y: v(),
            ay: v(),
            qs: v(),
        }
    }

    /// Rows the buffers hold.
    pub fn capacity(&self) -> usize {
        self.cap
    }

    /// Largest eigenvalue of `A` (rows `0..k`) by [`POWER_ITERATIONS`] power iterations
    /// from the all-ones vector, raised by a tenth (power iteration approaches from below).
    fn norm_estimate<A: DelassusOperator + ?Sized>(&mut self, a: &A, k: usize) -> (f64, usize) {
        let (x, ax) = (&mut self.x[..k], &mut self.ax[..k]);
        x.iter_mut().for_each(|v| *v = 1.0 / (k as f64).sqrt());
        let mut lambda = 0.0;
        let mut products = 0;
        for _ in 0..POWER_ITERATIONS {
            ax.iter_mut().for_each(|v| *v = 0.0);
            a.mul_add(1.0, x, ax);
            products += 1;
            let nrm = norm(ax);
            if nrm.is_nan() || nrm <= 0.0 || nrm.is_infinite() {
                break;
            }
            lambda = nrm;
            for (xi, &v) in x.iter_mut().zip(ax.iter()) {
                *xi = v / nrm;
            }
        }
        (1.1 * lambda, products)
    }

    /// Solves `w = A z + q` with `0 ≤ z_i ⊥ w_i ≥ 0` for the rows with `eq[i]` false and
    /// `w_i = 0` (free `z_i`) where it is true, for a symmetric positive semi-definite `A`
    /// (MPRGP, module doc). `z` is the warm start (projected on the bounds first); on
    /// return `w = A z + q` from a fresh product. Stops when `‖w^P‖∞ ≤ tol · max(‖q‖∞,
    /// ‖Az‖∞)` or after `max_products` products.
    #[allow(clippy::too_many_arguments)]
    pub fn solve_box<A: DelassusOperator + ?Sized>(
        &mut self,
        a: &A,
        q: &[f64],
        eq: &[bool],
        z: &mut [f64],
        w: &mut [f64],
        tol: f64,
        max_products: usize,
    ) -> GlobalInfo {
        let k = q.len();
        assert!(
            k <= self.cap,
            "global solver: {k} rows for {} buffers",
            self.cap
        );
        let mut info = GlobalInfo::default();
        for (zi, &e) in z.iter_mut().zip(eq) {
            if !e {
                *zi = zi.max(0.0);
            }
        }
        let (lmax, used) = self.norm_estimate(a, k);
        info.products += used;
        let abar = if lmax > 0.0 { 1.0 / lmax } else { 1.0 };
        let qn = q.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let (g, p, ap) = (&mut self.g[..k], &mut self.p[..k], &mut self.ap[..k]);
        let gradient = |z: &[f64], g: &mut [f64], info: &mut GlobalInfo| {
            g.copy_from_slice(q);
            a.mul_add(1.0, z, g);
            info.products += 1;
        };
        gradient(z, g, &mut info);
        // φ: the gradient on the free rows; β: the part that frees an active row
        let free = |i: usize, z: &[f64]| eq[i] || z[i] > 0.0;
        let chop = |z: &[f64], g: &[f64], p: &mut [f64]| {
            for i in 0..k {
                p[i] = if free(i, z) { g[i] } else { 0.0 };
            }
        };
        let projected = |z: &[f64], g: &[f64]| -> f64 {
            (0..k)
                .map(|i| {
                    if free(i, z) {
                        g[i].abs()
                    } else {
                        (-g[i]).max(0.0)
                    }
                })
                .fold(0.0, f64::max)
        };
        let scale = |g: &[f64]| -> f64 {
            // ‖A z‖∞ = ‖g − q‖∞
            g.iter()
                .zip(q)
                .fold(qn, |m, (gi, qi)| m.max((gi - qi).abs()))
        };
        chop(z, g, p);
        let mut since = 0;
        loop {
            let s = scale(g);
            let r = projected(z, g);
            info.residual = if s > 0.0 { r / s } else { r };
            info.accuracy = r;
            if info.residual <= tol || r == 0.0 {
                info.converged = true;
                break;
            }
            if info.products >= max_products {
                break;
            }
            if since >= REFRESH {
                gradient(z, g, &mut info);
                chop(z, g, p);
                since = 0;
                continue;
            }
            since += 1;
            // proportional iterate: ‖β‖² ≤ Γ² φ̃ᵀφ
            let (mut b2, mut pf) = (0.0, 0.0);
            for i in 0..k {
                if free(i, z) {
                    let phi = g[i];
                    let red = if eq[i] || phi <= 0.0 {
                        phi
                    } else {
                        phi.min(z[i] / abar)
                    };
                    pf += red * phi;
                } else {
                    let b = g[i].min(0.0);
                    b2 += b * b;
                }
            }
            if b2 <= GAMMA * GAMMA * pf {
                ap.iter_mut().for_each(|v| *v = 0.0);
                a.mul_add(1.0, p, ap);
                info.products += 1;
                let pap = dot(p, ap);
                if pap.is_nan() || pap <= 0.0 {
                    // no curvature along p (round-off): a projected gradient step
                    expansion(z, g, eq, abar);
                    gradient(z, g, &mut info);
                    chop(z, g, p);
                    since = 0;
                    continue;
                }
                let acg = dot(g, p) / pap;
                // largest feasible step along −p
                let (mut af, mut block) = (f64::INFINITY, usize::MAX);
                for i in 0..k {
                    if !eq[i] && p[i] > 0.0 {
                        let t = z[i] / p[i];
                        if t < af {
                            af = t;
                            block = i;
                        }
                    }
                }
                if acg <= af {
                    // conjugate gradient step (a row the step brings to its bound to
                    // the last digit is held there: no impulse of −1e-20)
                    for i in 0..k {
                        z[i] -= acg * p[i];
                        g[i] -= acg * ap[i];
                        if !eq[i] && z[i] < 0.0 {
                            z[i] = 0.0;
                        }
                    }
                    let mut phi_ap = 0.0;
                    for i in 0..k {
                        if free(i, z) {
                            phi_ap += g[i] * ap[i];
                        }
                    }
                    let gamma = phi_ap / pap;
                    for i in 0..k {
                        let phi = if free(i, z) { g[i] } else { 0.0 };
                        p[i] = phi - gamma * p[i];
                    }
                } else {
                    // expansion: to the bound, then a projected gradient step
                    for i in 0..k {
                        z[i] -= af * p[i];
                        g[i] -= af * ap[i];
                        if !eq[i] && z[i] < 0.0 {
                            z[i] = 0.0;
                        }
                    }
                    z[block] = 0.0;
                    expansion(z, g, eq, abar);
                    gradient(z, g, &mut info);
                    chop(z, g, p);
                    since = 0;
                }
            } else {
                // proportioning: d = β frees the active rows whose gradient is negative
                for i in 0..k {
                    p[i] = if free(i, z) { 0.0 } else { g[i].min(0.0) };
                }
                ap.iter_mut().for_each(|v| *v = 0.0);
                a.mul_add(1.0, p, ap);
                info.products += 1;
                let pap = dot(p, ap);
                if pap > 0.0 {
                    let acg = dot(g, p) / pap;
                    for i in 0..k {
                        z[i] -= acg * p[i];
                        g[i] -= acg * ap[i];
                    }
                } else {
                    expansion(z, g, eq, abar);
                    gradient(z, g, &mut info);
                    since = 0;
                }
                chop(z, g, p);
            }
        }
        // w from a fresh product
        w[..k].copy_from_slice(q);
        a.mul_add(1.0, z, w);
        info.products += 1;
        let r = projected(z, w);
        let s = scale(w);
        info.accuracy = r;
        info.residual = if s > 0.0 { r / s } else { r };
        info.converged = info.residual <= tol || r == 0.0;
        info
    }

    /// Solves the Coulomb problem `u = A r + q`, `C* ∋ û ⊥ r ∈ C` over `blocks`
    /// (De Saxcé's `û = u + μ‖u_T‖ e_N`, eq. 13–15) by the fixed point on `s = ‖u_T‖`
    /// with an accelerated projected gradient inside (module doc). `r` is the warm
    /// start; on return `u = A r + q` from a fresh product. Stops when the relative
    /// Alart–Curnier residual at `ρ = 1/L` is at most `tol`, or after `max_products`.
    #[allow(clippy::too_many_arguments)]
    pub fn solve_friction<A: DelassusOperator + ?Sized>(
        &mut self,
        a: &A,
        q: &[f64],
        blocks: &[Block],
        r: &mut [f64],
        u: &mut [f64],
        tol: f64,
        max_products: usize,
    ) -> GlobalInfo {
        let k = q.len();
        assert!(
            k <= self.cap,
            "global solver: {k} rows for {} buffers",
            self.cap
        );
        let mut info = GlobalInfo::default();
        let (mut lmax, used) = self.norm_estimate(a, k);
        info.products += used;
        if lmax.is_nan() || lmax <= 0.0 {
            lmax = 1.0;
        }
        let project = |x: &mut [f64]| {
            for b in blocks {
                project_on_cone(&mut x[b.offset..b.offset + b.dim], b.mu);
            }
        };
        project(r);
        // u = A r + q
        let mul = |x: &[f64], out: &mut [f64], info: &mut GlobalInfo| {
            out.iter_mut().for_each(|v| *v = 0.0);
            a.mul_add(1.0, x, out);
            info.products += 1;
        };
        let (x, ax, y, ay, qs, g) = (
            &mut self.x[..k],
            &mut self.ax[..k],
            &mut self.y[..k],
            &mut self.ay[..k],
            &mut self.qs[..k],
            &mut self.g[..k],
        );
        mul(r, ax, &mut info);
        let outer_residual = |r: &[f64], ar: &[f64], lmax: f64| -> (f64, f64) {
            let rho = 1.0 / lmax;
            let (mut e2, mut su, mut sr) = (0.0, 0.0, 0.0);
            for b in blocks {
                let o = b.offset;
                let mut uu = [0.0; 3];
                for j in 0..b.dim {
                    uu[j] = ar[o + j] + q[o + j];
                    su += uu[j] * uu[j];
                    sr += (lmax * r[o + j]).powi(2);
                }
                e2 += ac_map2(&r[o..o + b.dim], &uu[..b.dim], b.mu, rho);
            }
            let e = e2.sqrt() / rho;
            let scale = norm(q).max(su.sqrt()).max(sr.sqrt());
            (if scale > 0.0 { e / scale } else { e }, e)
        };
        loop {
            let (res, acc) = outer_residual(r, ax, lmax);
            info.residual = res;
            info.accuracy = acc;
            if res <= tol || acc == 0.0 {
                info.converged = true;
                break;
            }
            if info.products >= max_products {
                break;
            }
            info.outer += 1;
            // s = ‖u_T‖ at the current r; q_s = q + μ s e_N
            qs.copy_from_slice(q);
            for b in blocks {
                let o = b.offset;
                let ut = (1..b.dim)
                    .map(|j| (ax[o + j] + q[o + j]).powi(2))
                    .sum::<f64>()
                    .sqrt();
                qs[o] += b.mu * ut;
            }
            // APGD on min ½rᵀAr + q_sᵀr over the cones, to a tenth of the outer residual
            let inner_tol = (0.1 * res).max(0.5 * tol);
            x.copy_from_slice(r);
            y.copy_from_slice(r);
            ay.copy_from_slice(ax);
            let mut theta = 1.0f64;
            let objective = |x: &[f64], ax: &[f64]| -> f64 {
                (0..k).map(|i| x[i] * (0.5 * ax[i] + qs[i])).sum()
            };
            let mut fx = objective(x, ax);
            loop {
                if info.products >= max_products {
                    break;
                }
                // r = P_C(y − (A y + q_s)/L)
                for i in 0..k {
                    g[i] = ay[i] + qs[i];
                    r[i] = y[i] - g[i] / lmax;
                }
                project(r);
                mul(r, u, &mut info);
                let fr = objective(r, u);
                let scale_f = fx.abs().max(f64::MIN_POSITIVE);
                if fr > fx + 1e-14 * scale_f && theta > 1.0 {
                    // the momentum overshot: restart from x
                    theta = 1.0;
                    y.copy_from_slice(x);
                    ay.copy_from_slice(ax);
                    continue;
                }
                if fr > fx + 1e-10 * scale_f {
                    // a plain projected gradient step rose: L was too small
                    lmax *= 2.0;
                    continue;
                }
                // inner residual at ρ = 1/L on the fixed-s problem
                let rho = 1.0 / lmax;
                let (mut e2, mut sc) = (0.0, norm(qs));
                let mut su = 0.0;
                for b in blocks {
                    let o = b.offset;
                    let mut uu = [0.0; 3];
                    for j in 0..b.dim {
                        uu[j] = u[o + j] + qs[o + j];
                        su += uu[j] * uu[j];
                    }
                    e2 += proj_map2(&r[o..o + b.dim], &uu[..b.dim], b.mu, rho);
                }
                sc = sc.max(su.sqrt());
                let inner = e2.sqrt() / rho / if sc > 0.0 { sc } else { 1.0 };
                // gradient restart: the step and the momentum disagree
                let mut gd = 0.0;
                for i in 0..k {
                    gd += g[i] * (r[i] - x[i]);
                }
                let theta_next = 0.5 * (1.0 + (1.0 + 4.0 * theta * theta).sqrt());
                let beta = if gd > 0.0 {
                    0.0
                } else {
                    (theta - 1.0) / theta_next
                };
                theta = if gd > 0.0 { 1.0 } else { theta_next };
                for i in 0..k {
                    y[i] = r[i] + beta * (r[i] - x[i]);
                    ay[i] = u[i] + beta * (u[i] - ax[i]);
                }
                x.copy_from_slice(r);
                ax.copy_from_slice(u);
                fx = fr;
                if inner <= inner_tol {
                    break;
                }
            }
            r.copy_from_slice(x);
        }
        // u from a fresh product
        mul(r, u, &mut info);
        ax.copy_from_slice(&u[..k]);
        for (ui, qi) in u.iter_mut().zip(q) {
            *ui += qi;
        }
        let (res, acc) = outer_residual(r, ax, lmax);
        info.residual = res;
        info.accuracy = acc;
        info.converged = res <= tol || acc == 0.0;
        info
    }
}

/// The projected gradient step of MPRGP's expansion: `z ← P(z − ᾱ φ)` with `φ` the
/// gradient `g` on the free rows (Dostál's form; equality rows unbounded).
fn expansion(z: &mut [f64], g: &[f64], eq: &[bool], abar: f64) {
    for i in 0..z.len() {
        if eq[i] || z[i] > 0.0 {
            z[i] -= abar * g[i];
            if !eq[i] && z[i] < 0.0 {
                z[i] = 0.0;
            }
        }
    }
}

/// `‖r − P_C(r − ρ v)‖²` of one block (the natural map of the cone problem with the
/// velocity `v` already modified).
fn proj_map2(r: &[f64], v: &[f64], mu: f64, rho: f64) -> f64 {
    let d = r.len();
    let mut x = [0.0; 3];
    for i in 0..d {
        x[i] = r[i] - rho * v[i];
    }
    project_on_cone(&mut x[..d], mu);
    (0..d).map(|i| (r[i] - x[i]).powi(2)).sum()
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn norm(x: &[f64]) -> f64 {
    dot(x, x).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solvers::friction::{FrictionParams, FrictionProblem, FrictionSolver};
    use crate::solvers::lcp::LcpSolver;
    use crate::solvers::mlcp::Mlcp;
    use crate::solvers::operator::DenseOperator;
    use crate::solvers::{LcpKind, affine};

    /// A symmetric positive definite `k × k` matrix `B Bᵀ + εI` from a fixed sequence,
    /// condition number in the hundreds (like the Delassus blocks of a resting body).
    fn spd(k: usize, seed: u64) -> Vec<f64> {
        let mut x = seed;
        let mut next = || {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((x >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let b: Vec<f64> = (0..k * k).map(|_| next()).collect();
        let mut a = vec![0.0; k * k];
        for i in 0..k {
            for j in 0..k {
                a[i + j * k] = (0..k).map(|l| b[i + l * k] * b[j + l * k]).sum::<f64>();
            }
            a[i + i * k] += 0.05;
        }
        a
    }

    /// `z` within `tol` of `exact` (relative to its largest entry), and the returned `w`
    /// equal to `A z + q` to round-off.
    fn assert_solution(a: &[f64], q: &[f64], (z, w): (&[f64], &[f64]), exact: &[f64], tol: f64) {
        let k = q.len();
        let scale = exact.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for i in 0..k {
            assert!(
                (z[i] - exact[i]).abs() <= tol * scale,
                "k = {k}, row {i}: {} vs {}",
                z[i],
                exact[i]
            );
        }
        let mut w2 = vec![0.0; k];
        affine(a, k, z, q, &mut w2);
        assert!(
            w.iter()
                .zip(&w2)
                .all(|(x, y)| (x - y).abs() <= 1e-12 * (1.0 + y.abs()))
        );
    }

    fn rhs(k: usize, seed: u64) -> Vec<f64> {
        (0..k)
            .map(|i| ((i as u64 * 7919 + seed * 104_729) % 1000) as f64 / 500.0 - 1.2)
            .collect()
    }

    /// MPRGP on LCPs with half their rows active reaches the exact pivoting solution
    /// (block pivoting, round-off exact) to 1e-9 relative: the solver stops on a
    /// residual of 1e-12 relative to ‖q‖, and the distance to the solution is at most
    /// the condition number (≈ 1e3 here) times that.
    #[test]
    fn box_qp_matches_pivoting() {
        for (k, seed) in [(12, 1), (40, 2), (90, 3)] {
            let a = spd(k, seed);
            let q = rhs(k, seed);
            let mut exact = vec![0.0; k];
            let mut w = vec![0.0; k];
            LcpSolver::new(LcpKind::BlockPivoting, k)
                .solve(&a, k, &q, &mut exact, &mut w)
                .unwrap();
            let active = exact.iter().filter(|&&z| z > 0.0).count();
            assert!(active > 0 && active < k, "k = {k}: {active} active");
            let mut z = vec![0.0; k];
            let mut gs = GlobalSolver::with_capacity(k);
            let info = gs.solve_box(
                &DenseOperator::new(k, &a),
                &q,
                &vec![false; k],
                &mut z,
                &mut w,
                1e-12,
                10_000,
            );
            assert!(info.converged, "k = {k}: {info:?}");
            assert_solution(&a, &q, (&z, &w), &exact, 1e-9);
        }
    }

    /// Equality rows (Algorithm 2's MLCP, eq. 68): the same solution as the Schur
    /// complement MLCP solver, to the same 1e-9 relative.
    #[test]
    fn box_qp_with_equalities_matches_mlcp() {
        let k = 30;
        let a = spd(k, 7);
        let q = rhs(k, 7);
        let eq: Vec<bool> = (0..k).map(|i| i % 3 == 0).collect();
        let (mut exact, mut w) = (vec![0.0; k], vec![0.0; k]);
        let mut lcp = LcpSolver::new(LcpKind::Lemke, k);
        Mlcp::with_capacity(k)
            .solve(&a, k, &q, &eq, &mut lcp, &mut exact, &mut w)
            .unwrap();
        assert!(
            exact.iter().zip(&eq).any(|(&z, &e)| e && z < 0.0),
            "an equality row pulls"
        );
        let mut z = vec![0.0; k];
        let info = GlobalSolver::with_capacity(k).solve_box(
            &DenseOperator::new(k, &a),
            &q,
            &eq,
            &mut z,
            &mut w,
            1e-12,
            10_000,
        );
        assert!(info.converged, "{info:?}");
        assert_solution(&a, &q, (&z, &w), &exact, 1e-9);
        for i in (0..k).filter(|&i| eq[i]) {
            assert!(w[i].abs() <= 1e-10, "equality row {i}: w = {:e}", w[i]);
        }
    }

    /// 3-D friction (μ = 0.3, blocks sticking, slipping and open): the accelerated
    /// projected gradient with the fixed point on ‖u_T‖ reaches NSGS's solution. Both
    /// stop on residuals of 1e-10; the unique solution of a positive definite
    /// problem at small μ is then matched to 1e-6 relative (the residuals' scale times
    /// the condition number).
    #[test]
    fn friction_matches_nsgs() {
        let nc = 20;
        let k = 3 * nc;
        let a = spd(k, 11);
        let mut q = rhs(k, 11);
        for c in 0..nc {
            q[3 * c] -= 0.3;
            if c % 2 == 0 {
                q[3 * c + 1] *= 0.02;
                q[3 * c + 2] *= 0.02;
            }
        }
        let blocks: Vec<Block> = (0..nc)
            .map(|c| Block {
                offset: 3 * c,
                dim: 3,
                mu: 0.3,
            })
            .collect();
        let op = DenseOperator::new(k, &a);
        let params = FrictionParams {
            tol: 1e-10,
            ..FrictionParams::default()
        };
        let (mut exact, mut u) = (vec![0.0; k], vec![0.0; k]);
        let fi = FrictionSolver::with_capacity(k)
            .solve(
                FrictionProblem {
                    w: &op,
                    q: &q,
                    blocks: &blocks,
                },
                &params,
                &mut exact,
                &mut u,
            )
            .unwrap();
        assert!(fi.converged);
        let open = blocks.iter().filter(|b| exact[b.offset] == 0.0).count();
        let slip = blocks
            .iter()
            .filter(|b| {
                let t = (exact[b.offset + 1].powi(2) + exact[b.offset + 2].powi(2)).sqrt();
                exact[b.offset] > 0.0 && t >= 0.999_999 * 0.3 * exact[b.offset]
            })
            .count();
        assert!(
            open > 0 && slip > 0 && open + slip < nc,
            "open {open}, slip {slip} of {nc}"
        );
        let mut r = vec![0.0; k];
        let info = GlobalSolver::with_capacity(k)
            .solve_friction(&op, &q, &blocks, &mut r, &mut u, 1e-10, 100_000);
        assert!(info.converged, "{info:?}");
        assert_solution(&a, &q, (&r, &u), &exact, 1e-6);
    }
}
