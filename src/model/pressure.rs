//! Uniform pressure on boundary faces (`[[pressures]]`): the consistent nodal forces
//! `f_b = −p ∫_Γ N_b n dΓ` of a pressure `p` (positive pushes into the body) over the
//! oriented boundary facets of a node set, in the reference configuration (a dead
//! load: neither the faces' area nor their normal follows the deformation).
//!
//! The facets are [`crate::model::solid::Mesh::boundary_facets`]'s (outward normals,
//! corners first, then mid-side nodes, then a centre), integrated with their own kinds'
//! rules: an edge of 2 nodes with 2 Gauss points, of 3 nodes with 3 (its Jacobian
//! `|x'(ξ)|` is not a polynomial on a curved edge; exact on a straight one); a face with
//! the rule of the matching 2-D element (tri3, tri6, quad4, quad8, quad9), `n dA = x_ξ ×
//! x_η dξ dη`. An axisymmetric body's faces are rings: the integrand carries `2π r`, as
//! its mass and stiffness do ([`crate::model::solid`]).
//!
//! These are the loads a contact patch test needs: a uniform pressure on a block's top
//! is balanced, in the exact solution, by a uniform contact pressure on its bottom, and
//! only consistent nodal forces leave the uniform stress state an equilibrium of the
//! discrete system (a force split evenly over the nodes, as `[[forces]]` does, is not).
//!
//! Hand-written: the faces and their rules are this project's element kinds
//! ([`crate::model::element`]).

use crate::error::Error;
use crate::model::element::{G3, MAX_NODES, Rule, edge_shape, face_kind, facet_corners};
use crate::model::solid::Formulation;

/// The nodal forces of a unit pressure (`p = 1` Pa) on `facets` of a body of
/// `formulation` with nodes at `points`: one `(node, force)` per facet node and facet (a
/// node on several facets appears once per facet; the caller sums). An axisymmetric
/// body's edges are weighted by `2π r` (`r = x`), a plane-stress body's by its
/// thickness.
pub fn unit_pressure_forces(
    formulation: Formulation,
    facets: &[Vec<usize>],
    points: &[[f64; 3]],
) -> Result<Vec<(usize, [f64; 3])>, Error> {
    let dim = formulation.dim();
    let mut out = Vec::new();
    let mut n = [0.0; MAX_NODES];
    let mut g = [[0.0; 3]; MAX_NODES];
    for f in facets {
        let k = f.len();
        let x = |b: usize| points[f[b]];
        match (dim, facet_corners(dim, k)) {
            (2, Some(_)) => {
                let mut f_loc = [[0.0; 3]; 3];
                for &(xi, w) in &G3 {
                    let (nb, db) = edge_shape(k, xi);
                    let (mut t, mut r) = ([0.0; 2], 0.0);
                    for b in 0..k {
                        t[0] += db[b] * x(b)[0];
                        t[1] += db[b] * x(b)[1];
                        r += nb[b] * x(b)[0];
                    }
                    // the body on the edge's left: outward `t` turned by −90°
                    let ring = formulation.edge_weight(r);
                    for (b, fb) in f_loc.iter_mut().enumerate().take(k) {
                        fb[0] -= w * ring * nb[b] * t[1];
                        fb[1] += w * ring * nb[b] * t[0];
                    }
                }
                out.extend((0..k).map(|b| (f[b], f_loc[b])));
            }
            (3, Some(_)) => {
                let e = face_kind(k)
                    .expect("a face kind of its corner count")
                    .element();
                let mut f_loc = [[0.0; 3]; 9];
                for &(xi, w) in e.rule(Rule::Full) {
                    e.shape(xi, &mut n);
                    e.gradients(xi, &mut g);
                    let col = |j: usize| -> [f64; 3] {
                        std::array::from_fn(|i| (0..k).map(|b| g[b][j] * x(b)[i]).sum())
                    };
                    let (a, c) = (col(0), col(1));
                    let normal = [
                        a[1] * c[2] - a[2] * c[1],
                        a[2] * c[0] - a[0] * c[2],
                        a[0] * c[1] - a[1] * c[0],
                    ];
                    for (b, fb) in f_loc.iter_mut().enumerate().take(k) {
                        for i in 0..3 {
                            fb[i] -= w * n[b] * normal[i];
                        }
                    }
                }
                out.extend((0..k).map(|b| (f[b], f_loc[b])));
            }
            _ => {
                return Err(Error::invalid(
                    "faces",
                    format!("a facet of {k} nodes in {dim}-D"),
                    "takes edges of 2 or 3 nodes (2-D) and faces of 3, 4, 6, 8 or 9 nodes (3-D)",
                ));
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn total(f: &[(usize, [f64; 3])]) -> [f64; 3] {
        f.iter()
            .fold([0.0; 3], |s, (_, v)| std::array::from_fn(|i| s[i] + v[i]))
    }

    /// A unit pressure on a flat face of area A pushes with A along −n, and each node
    /// gets its shape function's integral: quad9 corners A/36, mid-sides A/9, centre
    /// 4A/9; quad8 corners −A/12 and mid-sides A/3 (the tensile corners of a serendipity
    /// face); tri6 corners 0 and mid-sides A/3.
    #[test]
    fn a_flat_face_takes_its_shape_functions_integrals() {
        // a 2 × 3 rectangle at z = 1, counter-clockwise seen from +z (outward +z)
        let c = [
            [0.0, 0.0, 1.0],
            [2.0, 0.0, 1.0],
            [2.0, 3.0, 1.0],
            [0.0, 3.0, 1.0],
        ];
        let mid = |a: [f64; 3], b: [f64; 3]| std::array::from_fn(|i| 0.5 * (a[i] + b[i]));
        let mut pts = c.to_vec();
        for i in 0..4 {
            pts.push(mid(c[i], c[(i + 1) % 4]));
        }
        pts.push([1.0, 1.5, 1.0]);
        let area = 6.0;
        for (nodes, corner, side, centre) in [
            ((0..9).collect::<Vec<_>>(), 1.0 / 36.0, 1.0 / 9.0, 4.0 / 9.0),
            ((0..8).collect(), -1.0 / 12.0, 1.0 / 3.0, 0.0),
            ((0..4).collect(), 0.25, 0.0, 0.0),
        ] {
            let f = unit_pressure_forces(Formulation::Solid, std::slice::from_ref(&nodes), &pts)
                .unwrap();
            for (v, fv) in f {
                let want = match v {
                    0..4 => corner,
                    4..8 => side,
                    _ => centre,
                } * area;
                assert!(
                    (fv[2] + want).abs() < 1e-13,
                    "{} nodes, node {v}",
                    nodes.len()
                );
                assert!(fv[0].abs() < 1e-14 && fv[1].abs() < 1e-14);
            }
        }
        // tri6 on the first three corners' triangle (area 3)
        let t = vec![
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [2.0, 3.0, 0.0],
            [1.0, 0.0, 0.0],
            [2.0, 1.5, 0.0],
            [1.0, 1.5, 0.0],
        ];
        let f = unit_pressure_forces(Formulation::Solid, &[(0..6).collect()], &t).unwrap();
        for (v, fv) in f {
            let want = if v < 3 { 0.0 } else { 1.0 };
            assert!((fv[2] + want).abs() < 1e-13, "tri6 node {v}: {fv:?}");
        }
    }

    /// An axisymmetric ring face (the edge r ∈ [1, 2] at y = 0 of a body above it,
    /// 3 nodes) under a unit pressure: the total is the annulus area π(2² − 1²) along
    /// +y (into the body); an edge parallel to the axis (r = 1, y from 1 to 0, the body
    /// on its left at r > 1) has the outward normal −r and takes 2π·1·1 along +r.
    #[test]
    fn axisymmetric_faces_are_rings() {
        let pts = [[1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [1.5, 0.0, 0.0]];
        // the bottom edge of a body above y = 0 runs from r = 1 to r = 2 with the body
        // on its left (outward −y)
        let f = unit_pressure_forces(Formulation::Axisymmetric, &[vec![0, 1, 2]], &pts).unwrap();
        let s = total(&f);
        assert!((s[1] - std::f64::consts::PI * 3.0).abs() < 1e-12, "{s:?}");
        assert!(s[0].abs() < 1e-14);
        let pts = [[1.0, 1.0, 0.0], [1.0, 0.0, 0.0]];
        let f = unit_pressure_forces(Formulation::Axisymmetric, &[vec![0, 1]], &pts).unwrap();
        let s = total(&f);
        assert!((s[0] - std::f64::consts::TAU).abs() < 1e-12, "{s:?}");
    }
}
