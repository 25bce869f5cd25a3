//! The surface rule between two bodies (issue 51 §3, `rule = "surface"` with a
//! `target`): mortar rows, one per slave node, integrated over the slave faces segment
//! by segment against the master faces under them. Small sliding: the segments, the
//! normal and the weights are those of the reference configuration, so the rows are
//! linear in `q` and the integrators factor once, as for node-to-node pairing.
//!
//! **The rows.** With `n(ξ)` the normal of the slave face turned inwards (the master
//! surface's outward direction when the faces touch), `x_m(ξ)` the point of the master
//! face that the line through the slave point `x_s(ξ)` along `n` meets, and `N_a` the
//! slave faces' shape functions, row `a` is the weighted gap
//!
//! `g̃_a = (1/A_a) ∫_Γs N_a (x_s − x_m)·n dΓ`,  `A_a = ∫_Γs N_a dΓ`,
//!
//! over the part of the slave surface `Γs` that has master faces under it: its
//! gradient is `(1/A_a) ∫ N_a N_b n` on slave node `b` and `−(1/A_a) ∫ N_a N_m(x_m) n` on
//! master node `m` (the standard mortar matrices `D` and `M` of the segment-to-segment
//! literature, Puso & Laursen, CMAME 193, 2004, row-scaled by `A_a` so that a row's gap
//! is a length and its impulse a force times the step, as a node's are). Uniform impulses
//! `P_a = p A_a h` give each slave node `p ∫ N_b n` and each master node `−p ∫ N_m n`
//! (the shape functions sum to one): the consistent forces of a uniform pressure on both
//! sides, however the two meshes' nodes fall — the contact patch test
//! (`tests/analytic_contact_patch.rs`), which node-to-surface rows fail on non-matching
//! meshes.
//!
//! **Segments.** Each master face's shadow on a slave face is the interval between the
//! closest points of its two corners on the slave face; over each shadow the integrand
//! is a polynomial on straight faces (degree ≤ 4 with 3-node edges), which 3 Gauss
//! points integrate exactly. Edges of 2 and 3 nodes in 2-D (plane strain, plane stress
//! with its thickness, axisymmetric rings with `2πr`); faces in 3-D need the polygon
//! clipping of the two meshes' faces and are refused with the reason for now.
//!
//! A row whose `A_a` vanishes — the corner of a 3-node ring edge on the axis `r = 0`,
//! where `∫ N_a 2πr dΓ = 0` — is scaled by `∫ |N_a|` instead (its gap is then a
//! weighted one, not a length): it cannot be left out, the other rows' shape functions
//! would no longer sum to one and the patch test fails (0.22, measured).
//!
//! Hand-written: no crate offers mortar integrals on these element faces.

use crate::error::Error;
use crate::model::element::{G3, lagrange2};
use crate::model::solid::Formulation;

/// One mortar row: the slave node it belongs to (the node the outputs name it by), its
/// gradient on slave nodes and on master nodes (`(node, vector)`, a vector per node),
/// and its gap at the reference configuration (m).
#[derive(Clone, Debug, PartialEq)]
pub struct MortarRow {
    /// The slave node.
    pub node: usize,
    /// `(1/A_a) ∫ N_a N_b n` per slave node `b`.
    pub slave: Vec<(usize, [f64; 3])>,
    /// `−(1/A_a) ∫ N_a N_m n` per master node `m`.
    pub master: Vec<(usize, [f64; 3])>,
    /// `g̃_a` at the reference positions.
    pub gap: f64,
}

/// A 2-D edge of 2 or 3 nodes (corners at ξ = ∓1, a mid-side node at 0) at `xi`: shape
/// values, position and tangent `dx/dξ`.
fn edge(f: &[usize], points: &[[f64; 3]], xi: f64) -> ([f64; 3], [f64; 2], [f64; 2]) {
    let mut n = [0.0; 3];
    let (mut x, mut t) = ([0.0; 2], [0.0; 2]);
    for (b, &node) in [-1.0, 1.0, 0.0].iter().enumerate().take(f.len()) {
        let (nb, db) = if f.len() == 2 {
            (0.5 * (1.0 + node * xi), 0.5 * node)
        } else {
            lagrange2(node, xi)
        };
        n[b] = nb;
        for i in 0..2 {
            x[i] += nb * points[f[b]][i];
            t[i] += db * points[f[b]][i];
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

/// The mortar rows of the slave `facets` (outward, [`crate::model::solid::Mesh::boundary_facets`])
/// against the master facets, each side with its node coordinates, for bodies of
/// `formulation`. Rows of slave nodes with no master face under them are left out.
pub fn mortar_rows(
    formulation: Formulation,
    (slave, slave_points): (&[Vec<usize>], &[[f64; 3]]),
    (master, master_points): (&[Vec<usize>], &[[f64; 3]]),
) -> Result<Vec<MortarRow>, Error> {
    if formulation.dim() != 2 {
        return Err(Error::invalid(
            "rule",
            "surface",
            "between two bodies takes 2-D bodies (edges) for now: 3-D faces need the \
             clipping of the two meshes' faces (rule = \"nodes\" takes them)",
        ));
    }
    for f in slave.iter().chain(master) {
        if !(2..=3).contains(&f.len()) {
            return Err(Error::invalid(
                "rule",
                "surface",
                &format!("takes edges of 2 or 3 nodes; a facet has {}", f.len()),
            ));
        }
    }
    let ring = |r: f64| match formulation {
        Formulation::Axisymmetric => std::f64::consts::TAU * r,
        f => f.thickness(),
    };
    // per slave node: A_a, the gap integral, and the two gradients (sorted by node)
    type Terms = std::collections::BTreeMap<usize, [f64; 3]>;
    let mut acc: std::collections::BTreeMap<usize, (f64, f64, f64, Terms, Terms)> =
        Default::default();
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
            if hi - lo <= 1e-12 {
                continue;
            }
            let (mid, half) = (0.5 * (lo + hi), 0.5 * (hi - lo));
            for &(g, w) in &G3 {
                let xi = mid + half * g;
                let (ns, xs, t) = edge(fs, slave_points, xi);
                let len = t[0].hypot(t[1]);
                // the slave's outward normal is t turned by −90°; n points into the slave
                let n = [-t[1] / len, t[0] / len];
                let eta = along(fm, master_points, xs, n);
                if !(-1.0 - 1e-9..=1.0 + 1e-9).contains(&eta) {
                    continue;
                }
                let (nm, xm, _) = edge(fm, master_points, eta);
                let gap = (xs[0] - xm[0]) * n[0] + (xs[1] - xm[1]) * n[1];
                let dw = w * half * len * ring(xs[0]);
                for (ai, &a) in fs.iter().enumerate() {
                    let e = acc.entry(a).or_default();
                    e.0 += dw * ns[ai];
                    e.1 += dw * ns[ai].abs();
                    e.2 += dw * ns[ai] * gap;
                    for (bi, &b) in fs.iter().enumerate() {
                        let v = e.3.entry(b).or_default();
                        for i in 0..2 {
                            v[i] += dw * ns[ai] * ns[bi] * n[i];
                        }
                    }
                    for (mi, &m) in fm.iter().enumerate() {
                        let v = e.4.entry(m).or_default();
                        for i in 0..2 {
                            v[i] -= dw * ns[ai] * nm[mi] * n[i];
                        }
                    }
                }
            }
        }
    }
    let scale = |terms: Terms, area: f64| -> Vec<(usize, [f64; 3])> {
        terms
            .into_iter()
            .map(|(k, v)| (k, v.map(|x| x / area)))
            .collect()
    };
    Ok(acc
        .into_iter()
        .filter(|(_, (_, abs, ..))| *abs > 0.0)
        .map(|(node, (area, abs, gap, s, m))| (node, (area.max(0.0), abs, gap, s, m)))
        // a row whose `A_a` vanishes (the corner of a 3-node ring edge on the axis r = 0:
        // `∫ N_a 2πr = 0`) is scaled by `∫ |N_a|` instead, its gap a weighted one: it
        // cannot be left out, the other rows' weights would no longer sum to one
        .map(|(node, (area, abs, gap, s, m))| {
            (
                node,
                (if area > 1e-3 * abs { area } else { abs }, gap, s, m),
            )
        })
        .map(|(node, (area, gap, s, m))| MortarRow {
            node,
            slave: scale(s, area),
            master: scale(m, area),
            gap: gap / area,
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two flat interfaces at y = 0.001 (slave, 3 edges over [0, 3]) and y = 0
    /// (master, 2 edges over [0, 3]): every row's gap is 1 mm, its slave weights sum to
    /// `n = (0, 1)` and its master weights to `−n`; summed with the weights `A_a`, the
    /// master nodes get `∫ N_m` of the covered length.
    #[test]
    fn non_matching_flat_edges_weigh_exactly() {
        let sp: Vec<[f64; 3]> = (0..4).map(|i| [i as f64, 0.001, 0.0]).collect();
        // each body on its edges' left: the slave above runs left to right, the master
        // below right to left
        let sf: Vec<Vec<usize>> = (0..3).map(|i| vec![i, i + 1]).collect();
        let mp = [[0.0, 0.0, 0.0], [1.5, 0.0, 0.0], [3.0, 0.0, 0.0]];
        let mf = vec![vec![1, 0], vec![2, 1]];
        let rows = mortar_rows(Formulation::PlaneStrain, (&sf, &sp), (&mf, &mp)).unwrap();
        assert_eq!(rows.len(), 4);
        let mut master = [0.0; 3];
        for r in &rows {
            assert!((r.gap - 0.001).abs() < 1e-15, "{r:?}");
            let s: f64 = r.slave.iter().map(|(_, v)| v[1]).sum();
            let m: f64 = r.master.iter().map(|(_, v)| v[1]).sum();
            assert!((s - 1.0).abs() < 1e-14 && (m + 1.0).abs() < 1e-14, "{r:?}");
            let area = if r.node == 0 || r.node == 3 { 0.5 } else { 1.0 };
            for (k, v) in &r.master {
                master[*k] -= area * v[1];
            }
        }
        for (k, want) in [0.75, 1.5, 0.75].iter().enumerate() {
            assert!((master[k] - want).abs() < 1e-14, "master {k}: {master:?}");
        }
    }
}
