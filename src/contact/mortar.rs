//! The surface rule between two bodies (issue 51 §3, `rule = "surface"` with a
//! `target`): mortar rows, one per slave node, integrated over the slave faces segment
//! by segment against the master faces under them. Small sliding: the segments, the
//! normal and the weights are those of the reference configuration, so the rows are
//! linear in `q` and the integrators factor once, as for node-to-node pairing.
//!
//! **The rows.** With `n(ξ)` the normal of the slave face turned inwards (the master
//! surface's outward direction when the faces touch), `x_m(ξ)` the point of the master
//! face that the line through the slave point `x_s(ξ)` along `n` meets, `N_b` the slave
//! faces' shape functions and `Φ_a` their multiplier basis, row `a` is the weighted gap
//!
//! `g̃_a = (1/A_a) ∫_Γs Φ_a (x_s − x_m)·n dΓ`,  `A_a = ∫_Γs Φ_a dΓ`,
//!
//! over the part of the slave surface `Γs` that has master faces under it: its
//! gradient is `(1/A_a) ∫ Φ_a N_b n` on slave node `b` and `−(1/A_a) ∫ Φ_a N_m(x_m) n` on
//! master node `m` (the mortar matrices `D` and `M` of the segment-to-segment
//! literature, Puso & Laursen, CMAME 193, 2004, row-scaled by `A_a` so that a row's gap
//! is a length and its impulse a force times the step, as a node's are). `Φ_a = N_a` on
//! linear faces; on quadratic ones, the hat functions of the face split at its mid-side
//! nodes (never negative, as the quadratic `N_a` are: with them a corner's weighted gap
//! reads negative where every point of the face is open, and `∫ N_a 2πr` vanishes at a
//! ring edge's corner on the axis). Any multiplier basis that sums to one transmits a
//! uniform pressure exactly: uniform impulses `P_a = p A_a h` give each slave node
//! `p ∫ N_b n` and each master node `−p ∫ N_m n`, the consistent forces of the pressure
//! on both sides, however the two meshes' nodes fall — the contact patch test
//! (`tests/analytic_contact_patch.rs`), which node-to-surface rows fail on non-matching
//! meshes.
//!
//! **Segments.** Each master face's shadow on a slave face is the interval between the
//! closest points of its two corners on the slave face, split at a 3-node edge's middle
//! where its `Φ_a` kink; over each piece the integrand is a polynomial on straight
//! faces (degree ≤ 4 with a ring's `r`), which 3 Gauss points integrate exactly. Edges of 2 and 3 nodes in 2-D (plane strain, plane stress
//! with its thickness, axisymmetric rings with `2πr`); faces in 3-D need the polygon
//! clipping of the two meshes' faces and are refused with the reason for now.
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
    /// `(1/A_a) ∫ Φ_a N_b n` per slave node `b`.
    pub slave: Vec<(usize, [f64; 3])>,
    /// `−(1/A_a) ∫ Φ_a N_m n` per master node `m`.
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
    let mut acc = Rows::default();
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
                        w * half * len * ring(xs[0]),
                        (fs, &phi[..k], &ns[..k]),
                        (fm, &nm[..fm.len()]),
                        n,
                        gap,
                    );
                }
            }
        }
    }
    Ok(acc.finish())
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

/// The mortar integrals as they are summed, per slave node: `A_a`, `∫ Φ_a g`, and the
/// two gradients (sorted by node).
#[derive(Default)]
struct Rows(std::collections::BTreeMap<usize, Acc>);

type Terms = std::collections::BTreeMap<usize, [f64; 3]>;

#[derive(Default)]
struct Acc {
    area: f64,
    gap: f64,
    slave: Terms,
    master: Terms,
}

impl Rows {
    /// Adds one integration point of weight `dw`: the slave face's nodes with their
    /// multiplier basis `Φ` and shape functions `N` there, the master face's nodes with
    /// their shape functions at the point under it, the normal `n` into the slave and the
    /// gap.
    fn add(
        &mut self,
        dw: f64,
        (fs, phi, ns): (&[usize], &[f64], &[f64]),
        (fm, nm): (&[usize], &[f64]),
        n: [f64; 3],
        gap: f64,
    ) {
        for (&a, &pa) in fs.iter().zip(phi) {
            if pa == 0.0 {
                continue;
            }
            let e = self.0.entry(a).or_default();
            e.area += dw * pa;
            e.gap += dw * pa * gap;
            for (&b, &nb) in fs.iter().zip(ns) {
                let v = e.slave.entry(b).or_default();
                for i in 0..3 {
                    v[i] += dw * pa * nb * n[i];
                }
            }
            for (&m, &nmm) in fm.iter().zip(nm) {
                let v = e.master.entry(m).or_default();
                for i in 0..3 {
                    v[i] -= dw * pa * nmm * n[i];
                }
            }
        }
    }

    /// The rows, each divided by its `A_a` (rows with no master face under them, `A_a =
    /// 0`, are left out).
    fn finish(self) -> Vec<MortarRow> {
        let scale = |terms: Terms, area: f64| -> Vec<(usize, [f64; 3])> {
            terms
                .into_iter()
                .map(|(k, v)| (k, v.map(|x| x / area)))
                .collect()
        };
        self.0
            .into_iter()
            .filter(|(_, e)| e.area > 0.0)
            .map(|(node, e)| MortarRow {
                node,
                slave: scale(e.slave, e.area),
                master: scale(e.master, e.area),
                gap: e.gap / e.area,
            })
            .collect()
    }
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

    /// A straight 3-node slave edge at 45° over a flat master, touching it at one corner
    /// (height 0 at x = 0, 1 at x = 1): with the hat basis the touching corner's weighted
    /// height is `∫₀^½ (1 − 2x)·x dx / ¼ = 1/6`, open as the edge is; the quadratic `N_a`
    /// would give `∫ N_a g = 0` there, a contact read closed while every point but one is
    /// open. The mid-side row reads ½, the far corner 5/6.
    #[test]
    fn a_tilted_quadratic_edge_reads_open() {
        let sp = [[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.5, 0.5, 0.0]];
        let mp = [[-1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
        // the slave's body on the left of 0 → 1 (above the line); the master's below
        let rows = mortar_rows(
            Formulation::PlaneStrain,
            (&[vec![0, 1, 2]], &sp),
            (&[vec![1, 0]], &mp),
        )
        .unwrap();
        let gap = |node: usize| rows.iter().find(|r| r.node == node).unwrap().gap;
        // measured along the slave's inward normal (−1, 1)/√2, the gap at height y is
        // √2·y (the line through x_s along n meets y = 0 at x = 2y)
        let s2 = 2f64.sqrt();
        for (node, want) in [(0, 1.0 / 6.0), (2, 0.5), (1, 5.0 / 6.0)] {
            assert!(
                (gap(node) - want * s2).abs() < 1e-12,
                "node {node}: {}",
                gap(node)
            );
        }
    }
}
