//! The 20-node (serendipity) hexahedron on `[−1, 1]³`: corners
//! `N_a = ⅛ (1 + r_a r)(1 + s_a s)(1 + t_a t)(r_a r + s_a s + t_a t − 2)`, mid-edge nodes
//! `¼ (1 − x²)` along their edge's direction times `(1 + y_a y)(1 + z_a z)` across it.
//! Node order VTK's (type 25): the corners as hex8, then the edges 0–1, 1–2, 2–3, 3–0,
//! 4–5, 5–6, 6–7, 7–4, 0–4, 1–5, 2–6, 3–7; Gmsh (type 17) orders the edges otherwise
//! ([`HEX20_GMSH`], meshio's conversion).

use super::{Element, GAUSS3_3D, HEX_EDGE_NODES, Lumping, Rule};

/// The 20-node hexahedron.
pub struct Hex20;

/// Our (VTK's) node `a` is Gmsh's node `HEX20_GMSH[a]`.
pub const HEX20_GMSH: [usize; 20] = [
    0, 1, 2, 3, 4, 5, 6, 7, 8, 11, 13, 9, 16, 18, 19, 17, 10, 12, 14, 15,
];

/// The faces: the hex8 faces' corners, then the mid-edge nodes of their edges in order.
pub(super) const HEX20_FACES: [&[usize]; 6] = [
    &[0, 1, 2, 3, 8, 9, 10, 11],
    &[4, 5, 6, 7, 12, 13, 14, 15],
    &[0, 1, 5, 4, 8, 17, 12, 16],
    &[1, 2, 6, 5, 9, 18, 13, 17],
    &[2, 3, 7, 6, 10, 19, 14, 18],
    &[3, 0, 4, 7, 11, 16, 15, 19],
];

/// Node `c`'s factors per direction at `xi` and their derivatives: `1 + c_i x_i` where
/// its coordinate is ±1, `1 − x_i²` where it is 0 (one direction at a mid-edge node).
fn factors(c: &[f64; 3], xi: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    (
        std::array::from_fn(|i| {
            if c[i] == 0.0 {
                1.0 - xi[i] * xi[i]
            } else {
                1.0 + c[i] * xi[i]
            }
        }),
        std::array::from_fn(|i| if c[i] == 0.0 { -2.0 * xi[i] } else { c[i] }),
    )
}

impl Element for Hex20 {
    fn name(&self) -> &'static str {
        "hex20"
    }
    fn nodes(&self) -> usize {
        20
    }
    fn dim(&self) -> usize {
        3
    }
    fn order(&self) -> usize {
        2
    }
    fn corners(&self) -> usize {
        8
    }
    fn vtk_type(&self) -> u8 {
        25
    }
    fn gmsh_type(&self) -> usize {
        17
    }
    fn gmsh_order(&self) -> Option<&'static [usize]> {
        Some(&HEX20_GMSH)
    }
    fn reference_nodes(&self) -> &'static [[f64; 3]] {
        &HEX_EDGE_NODES
    }
    fn faces(&self) -> &'static [&'static [usize]] {
        &HEX20_FACES
    }
    fn shape(&self, xi: [f64; 3], n: &mut [f64]) {
        for (n, c) in n.iter_mut().zip(&HEX_EDGE_NODES) {
            let (f, _) = factors(c, xi);
            *n = if c.contains(&0.0) {
                0.25 * f[0] * f[1] * f[2]
            } else {
                0.125 * f[0] * f[1] * f[2] * (c[0] * xi[0] + c[1] * xi[1] + c[2] * xi[2] - 2.0)
            };
        }
    }
    fn gradients(&self, xi: [f64; 3], g: &mut [[f64; 3]]) {
        for (g, c) in g.iter_mut().zip(&HEX_EDGE_NODES) {
            let (f, df) = factors(c, xi);
            // the product of the factors other than the i-th
            let others = |i: usize| -> f64 { (0..3).filter(|&j| j != i).map(|j| f[j]).product() };
            *g = if c.contains(&0.0) {
                std::array::from_fn(|i| 0.25 * df[i] * others(i))
            } else {
                let s = c[0] * xi[0] + c[1] * xi[1] + c[2] * xi[2] - 2.0;
                // ∂/∂x_i of ⅛ f_i · (the other two) · s: f_i' … s + f_i … c_i
                std::array::from_fn(|i| 0.125 * others(i) * (df[i] * s + f[i] * c[i]))
            };
        }
    }
    fn rule(&self, _rule: Rule) -> &'static [([f64; 3], f64)] {
        &GAUSS3_3D
    }
    fn centre(&self) -> [f64; 3] {
        [0.0; 3]
    }
    fn lumping(&self) -> Lumping {
        Lumping::Hrz
    }
}
