//! 2-D mortar integrals: slave edges of 2 or 3 nodes against master edges, segment by
//! segment (the module doc of [`super`]).

use super::Rows;
use crate::model::element::{G3, edge_shape};
use crate::model::solid::Formulation;

/// Adds the mortar integrals of the slave `facets` (edges) against the master edges to
/// `acc`, weighted by `2πr` on an axisymmetric body and by the thickness in plane stress.
pub(super) fn edge_rows(
    acc: &mut Rows,
    formulation: Formulation,
    (slave, slave_points): (&[Vec<usize>], &[[f64; 3]]),
    (master, master_points): (&[Vec<usize>], &[[f64; 3]]),
) {
    for fs in slave {
        let (_, _, ts) = edge(fs, slave_points, 0.0);
        for fm in master {
            let (_, _, tm) = edge(fm, master_points, 0.0);
            // facing faces only (outward normals against each other: the tangents too)
            if ts[0] * tm[0] + ts[1] * tm[1] >= 0.0 {
                continue;
            }
            let p = |k: usize| [master_points[fm[k]][0], master_points[fm[k]][1]];
            let (a, b) = (
                closest(fs, slave_points, p(0)),
                closest(fs, slave_points, p(1)),
            );
            let (lo, hi) = (a.min(b).max(-1.0), a.max(b).min(1.0));
            // a 3-node edge's multiplier basis kinks at its middle: integrate each half
            let pieces: &[(f64, f64)] = if fs.len() == 3 {
                &[(lo, hi.min(0.0)), (lo.max(0.0), hi)]
            } else {
                &[(lo, hi)]
            };
            for &(lo, hi) in pieces {
                if hi - lo <= 1e-12 {
                    continue;
                }
                let (mid, half) = (0.5 * (lo + hi), 0.5 * (hi - lo));
                for &(g, w) in &G3 {
                    let xi = mid + half * g;
                    let (ns, xs, t) = edge(fs, slave_points, xi);
                    let len = t[0].hypot(t[1]);
                    // the slave's outward normal is t turned by −90°; n points into the
                    // slave
                    let n = [-t[1] / len, t[0] / len, 0.0];
                    let eta = along(fm, master_points, xs, [n[0], n[1]]);
                    if !(-1.0 - 1e-9..=1.0 + 1e-9).contains(&eta) {
                        continue;
                    }
                    let (nm, xm, _) = edge(fm, master_points, eta);
                    let gap = (xs[0] - xm[0]) * n[0] + (xs[1] - xm[1]) * n[1];
                    let phi = hats(fs.len(), xi);
                    let k = fs.len();
                    acc.add(
                        w * half * len * formulation.edge_weight(xs[0]),
                        (fs, &phi[..k], &ns[..k]),
                        (fm, &nm[..fm.len()]),
                        n,
                        gap,
                    );
                }
            }
        }
    }
}

/// A 2-D edge of 2 or 3 nodes (corners at ξ = ∓1, a mid-side node at 0) at `xi`: shape
/// values, position and tangent `dx/dξ`.
fn edge(f: &[usize], points: &[[f64; 3]], xi: f64) -> ([f64; 3], [f64; 2], [f64; 2]) {
    let (n, d) = edge_shape(f.len(), xi);
    let (mut x, mut t) = ([0.0; 2], [0.0; 2]);
    for (b, &v) in f.iter().enumerate() {
        for i in 0..2 {
            x[i] += n[b] * points[v][i];
            t[i] += d[b] * points[v][i];
        }
    }
    (n, x, t)
}

fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// The parameter of the point of edge `f` closest to `p` (Newton from the straight
/// chord's answer; not clamped).
fn closest(f: &[usize], points: &[[f64; 3]], p: [f64; 2]) -> f64 {
    let (a, b) = (points[f[0]], points[f[1]]);
    let c = [b[0] - a[0], b[1] - a[1]];
    let mut xi =
        2.0 * ((p[0] - a[0]) * c[0] + (p[1] - a[1]) * c[1]) / (c[0] * c[0] + c[1] * c[1]) - 1.0;
    if f.len() == 3 {
        for _ in 0..20 {
            let (_, x, t) = edge(f, points, xi);
            let h = 1e-7;
            let (_, _, t2) = edge(f, points, xi + h);
            let r = (x[0] - p[0]) * t[0] + (x[1] - p[1]) * t[1];
            // d/dξ of (x − p)·t = |t|² + (x − p)·t'
            let dt = [(t2[0] - t[0]) / h, (t2[1] - t[1]) / h];
            let dr = t[0] * t[0] + t[1] * t[1] + (x[0] - p[0]) * dt[0] + (x[1] - p[1]) * dt[1];
            let step = r / dr;
            xi -= step;
            if step.abs() < 1e-14 {
                break;
            }
        }
    }
    xi
}

/// Where the line through `p` along `n` meets edge `f`: its parameter (Newton from the
/// chord's answer on a 3-node edge; not clamped).
fn along(f: &[usize], points: &[[f64; 3]], p: [f64; 2], n: [f64; 2]) -> f64 {
    // (x(η) − p) × n = 0
    let mut eta = 0.0;
    for _ in 0..30 {
        let (_, x, t) = edge(f, points, eta);
        let r = cross([x[0] - p[0], x[1] - p[1]], n);
        let dr = cross(t, n);
        if dr == 0.0 {
            break;
        }
        let step = r / dr;
        eta -= step;
        if step.abs() < 1e-14 {
            break;
        }
    }
    eta
}

/// The multiplier basis `Φ_a` of a 2-D slave edge at `xi`: its shape functions on an
/// edge of 2 nodes; on an edge of 3 nodes the hat functions of its two halves (corners
/// at ξ = ∓1, the mid-side node at 0), which are never negative — the quadratic shape
/// functions are (`∫ N_a N_c < 0` for the two corners), and a weighted gap with them
/// reads negative where every point of the edge is open.
fn hats(k: usize, xi: f64) -> [f64; 3] {
    if k == 2 {
        [0.5 * (1.0 - xi), 0.5 * (1.0 + xi), 0.0]
    } else {
        [(-xi).max(0.0), xi.max(0.0), 1.0 - xi.abs()]
    }
}
