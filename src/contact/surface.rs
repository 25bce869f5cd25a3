//! The surface rule of a body's contact with an obstacle (issue 51 §3): rows at the
//! quadrature points of the body's boundary faces instead of its nodes. A row's gap is
//! the geometric gap of the face's point `x(ξ_q) = Σ_b N_b(ξ_q) x_b`, so its weights
//! `N_b(ξ_q)` sum to one and a face above the obstacle has every row's gap positive
//! (mortar-weighted nodal rows with the standard shape functions do not: on a quadratic
//! edge `∫ N_a N_c ds < 0` for its two corners, and a positive gap field reads negative —
//! the Hertz ball's pole started 2.6e-7 m "inside", measured).
//!
//! Points per face, as many as the face's nodes count once the faces are joined (so
//! that the rows do not outnumber the unknowns they constrain and the Delassus operator
//! keeps full rank): an edge of 2 nodes its middle, of 3 nodes its 2 Gauss points; a
//! quadrilateral of 4 nodes its centre, of 9 nodes its 2 × 2 Gauss points. Triangles
//! (tri3, tri6) and quad8 faces, which have more points per face than amortized nodes
//! under any rule that integrates them, get one row per face node instead, its gap the
//! faces' gap weighted by the node's mortar multiplier (`Σ_b w_ab g_b`, `w_ab = ∫ Φ_a N_b
//! / ∫ Φ_a`, [`crate::contact::mortar::plane_weights`]: never-negative multipliers, so an
//! open face never reads closed, and a quad8 corner's tensile share of a pressure, −A/12,
//! is carried by its neighbours' rows).
//!
//! Hand-written: the rows are this project's face kinds and rules, not a crate's.

use crate::error::Error;
use crate::model::element::{CellKind, G2, MAX_NODES, edge_shape, face_kind};

/// One row of the surface rule: the face node nearest its point (the node the outputs
/// name it by) and its weights `(node, N_b(ξ_q))`.
pub type SurfaceRow = (usize, Vec<(usize, f64)>);

/// Whether faces of `k` nodes in `dim` dimensions get rows per face node (triangles and
/// quad8: no collocation rule fits them) rather than rows at face points.
pub fn per_node(dim: usize, k: usize) -> bool {
    dim == 3 && matches!(k, 3 | 6 | 8)
}

/// The surface rule's rows on `facets` (corners first, then mid-side nodes, then a
/// centre) of a body of dimension `dim` at reference `points`.
pub fn collocation_rows(
    dim: usize,
    facets: &[Vec<usize>],
    points: &[[f64; 3]],
) -> Result<Vec<SurfaceRow>, Error> {
    let mut rows = Vec::new();
    let mut n = [0.0; MAX_NODES];
    for f in facets {
        let k = f.len();
        let (kind, xis): (Option<CellKind>, Vec<[f64; 3]>) = match (dim, k) {
            (2, 2) | (2, 3) => (
                None,
                if k == 2 {
                    vec![[0.0; 3]]
                } else {
                    G2.iter().map(|&g| [g, 0.0, 0.0]).collect()
                },
            ),
            (3, k) if per_node(3, k) => {
                // triangles and quad8: more points per face than the joined faces have
                // nodes under any rule that integrates them; rows per face node instead,
                // weighted by the mortar multipliers over the faces (once, for all)
                return Ok(crate::contact::mortar::plane_weights(facets, points));
            }
            (3, 4) => (face_kind(4), vec![[0.0; 3]]),
            (3, 9) => (
                face_kind(9),
                G2.iter()
                    .flat_map(|&a| G2.iter().map(move |&b| [a, b, 0.0]))
                    .collect(),
            ),
            _ => {
                return Err(Error::invalid(
                    "rule",
                    "surface",
                    &format!(
                        "takes faces of 2 or 3 nodes in 2-D and of 3, 4, 6, 8 or 9 nodes in \
                         3-D; this body has a face of {k} nodes"
                    ),
                ));
            }
        };
        for xi in xis {
            match kind {
                Some(kind) => kind.element().shape(xi, &mut n),
                None => n[..k].copy_from_slice(&edge_shape(k, xi[0]).0[..k]),
            }
            let at: [f64; 3] =
                std::array::from_fn(|i| (0..k).map(|b| n[b] * points[f[b]][i]).sum());
            let dist =
                |v: usize| -> f64 { (0..3).map(|i| (points[v][i] - at[i]).powi(2)).sum::<f64>() };
            let label = f
                .iter()
                .copied()
                .min_by(|&a, &b| dist(a).total_cmp(&dist(b)))
                .expect("a face has nodes");
            rows.push((label, (0..k).map(|b| (f[b], n[b])).collect()));
        }
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On the bottom of a box of 2 × 2 hex27 cells (four quad9 faces): 16 rows, each a
    /// point of the face (weights summing to one), labelled by a node of its face; 25
    /// face nodes, so the rows do not outnumber them.
    #[test]
    fn rows_are_points_of_the_faces() {
        let mesh = crate::model::generate::box_mesh(CellKind::Hex27, [2, 2, 1], [1.0, 1.0, 0.5]);
        let bottom = mesh.node_sets["z0"].clone();
        let facets = mesh.boundary_facets(&bottom);
        let rows = collocation_rows(3, &facets, &mesh.points).unwrap();
        assert_eq!((rows.len(), bottom.len()), (16, 25));
        for (label, w) in &rows {
            let s: f64 = w.iter().map(|x| x.1).sum();
            assert!((s - 1.0).abs() < 1e-15, "{s}");
            assert!(w.iter().any(|x| x.0 == *label));
        }
    }
}
