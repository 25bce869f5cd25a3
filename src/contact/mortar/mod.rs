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
//! **Segments.** In 2-D (`edges.rs`) each master edge's shadow on a slave edge is the
//! interval between the closest points of its two corners, split at a 3-node edge's
//! middle where its `Φ_a` kink; 3 Gauss points a piece integrate the polynomial
//! integrand exactly on straight edges (degree ≤ 4 with a ring's `r`). Edges of 2 and 3
//! nodes; plane strain, plane stress with its thickness, axisymmetric rings with `2πr`.
//! In 3-D (`faces.rs`) each master face's corners are projected into the slave face's
//! reference plane and the polygon is clipped against the pieces of the slave face on
//! which `Φ_a` is polynomial, then integrated by triangles. Faces tri3, quad4, tri6, quad8
//! and quad9 on either side (quad8's `Φ_a`: the hats of its four corner triangles and of
//! the diamond between its mid-side nodes).
//!
//! Hand-written: no crate offers mortar integrals on these element faces.

use crate::error::Error;
use crate::model::solid::Formulation;

mod edges;
mod faces;

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
    /// `(1/A_a) ∫ Φ_a N_b` per slave node, in the order of `slave`: with the row's
    /// tangents, its tangential rows (friction).
    pub slave_weights: Vec<f64>,
    /// `−(1/A_a) ∫ Φ_a N_m` per master node, in the order of `master`.
    pub master_weights: Vec<f64>,
    /// `g̃_a` at the reference positions.
    pub gap: f64,
}

/// The mortar rows of the slave `facets` (outward, [`crate::model::solid::Mesh::boundary_facets`])
/// against the master facets, each side with its node coordinates, for bodies of
/// `formulation`. Rows of slave nodes with no master face under them are left out.
pub fn mortar_rows(
    formulation: Formulation,
    slave: (&[Vec<usize>], &[[f64; 3]]),
    master: (&[Vec<usize>], &[[f64; 3]]),
) -> Result<Vec<MortarRow>, Error> {
    let dim = formulation.dim();
    for f in slave.0.iter().chain(master.0) {
        if crate::model::element::facet_corners(dim, f.len()).is_none() {
            return Err(Error::invalid(
                "rule",
                "surface",
                &format!(
                    "takes facets of the element kinds; a facet has {} nodes",
                    f.len()
                ),
            ));
        }
    }
    let mut acc = Rows::default();
    if dim == 2 {
        edges::edge_rows(&mut acc, formulation, slave, master);
    } else {
        faces::face_rows(&mut acc, slave, master);
    }
    Ok(acc.finish())
}

/// The mortar integrals as they are summed, per slave node: `A_a`, `∫ Φ_a g`, and the
/// two gradients (sorted by node).
#[derive(Default)]
struct Rows(std::collections::BTreeMap<usize, Acc>);

/// The multiplier weights of a surface against a rigid plane (the surface rule of a
/// body's triangle faces, [`crate::contact::surface`]): per face node `a`, the weights
/// `(1/A_a) ∫ Φ_a N_b dΓ` of the face nodes `b` (they sum to one), so that its row's gap
/// is `Σ_b w_ab g_b`, the weighted gap of the faces, exact for the affine gap of a
/// plane. 3-D faces of 3, 4, 6 or 9 nodes.
pub fn plane_weights(
    facets: &[Vec<usize>],
    points: &[[f64; 3]],
) -> Vec<(usize, Vec<(usize, f64)>)> {
    let mut acc = Rows::default();
    faces::face_weights(&mut acc, facets, points);
    acc.finish()
        .into_iter()
        .map(|r| {
            let w = r.slave.iter().map(|s| s.0).zip(r.slave_weights).collect();
            (r.node, w)
        })
        .collect()
}

/// Per node: the normal-weighted integral's three components, then the scalar one.
type Terms = std::collections::BTreeMap<usize, [f64; 4]>;

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
                v[3] += dw * pa * nb;
            }
            for (&m, &nmm) in fm.iter().zip(nm) {
                let v = e.master.entry(m).or_default();
                for i in 0..3 {
                    v[i] -= dw * pa * nmm * n[i];
                }
                v[3] -= dw * pa * nmm;
            }
        }
    }

    /// The rows, each divided by its `A_a` (rows with no master face under them, `A_a =
    /// 0`, are left out).
    fn finish(self) -> Vec<MortarRow> {
        type Scaled = (Vec<(usize, [f64; 3])>, Vec<f64>);
        let scale = |terms: Terms, area: f64| -> Scaled {
            terms
                .into_iter()
                .map(|(k, v)| ((k, [v[0] / area, v[1] / area, v[2] / area]), v[3] / area))
                .unzip()
        };
        self.0
            .into_iter()
            .filter(|(_, e)| e.area > 0.0)
            .map(|(node, e)| {
                let (slave, slave_weights) = scale(e.slave, e.area);
                let (master, master_weights) = scale(e.master, e.area);
                MortarRow {
                    node,
                    slave,
                    master,
                    slave_weights,
                    master_weights,
                    gap: e.gap / e.area,
                }
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
