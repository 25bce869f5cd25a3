//! The 8-node (trilinear) hexahedron on `[−1, 1]³`:
//! `N_a = ⅛ (1 + r_a r)(1 + s_a s)(1 + t_a t)`, the bottom face counter-clockwise from
//! `(−1, −1, −1)` then the top face above it; VTK type 12, Gmsh type 5, the same node
//! order in both.

use super::{Element, G2, Lumping, Rule};

/// The 8-node hexahedron.
pub struct Hex8;

/// Reference coordinates (±1) of the corners (VTK / Gmsh node order).
pub const HEX8_CORNERS: [[f64; 3]; 8] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
];

/// 2×2×2 Gauss points, `r` slowest (degree 3 in each direction).
const GAUSS: [([f64; 3], f64); 8] = {
    let mut out = [([0.0; 3], 1.0); 8];
    let mut p = 0;
    while p < 8 {
        out[p].0 = [G2[p / 4], G2[(p / 2) % 2], G2[p % 2]];
        p += 1;
    }
    out
};

impl Element for Hex8 {
    fn name(&self) -> &'static str {
        "hex8"
    }
    fn nodes(&self) -> usize {
        8
    }
    fn dim(&self) -> usize {
        3
    }
    fn vtk_type(&self) -> u8 {
        12
    }
    fn gmsh_type(&self) -> usize {
        5
    }
    fn reference_nodes(&self) -> &'static [[f64; 3]] {
        &HEX8_CORNERS
    }
    fn faces(&self) -> &'static [&'static [usize]] {
        &[
            &[0, 1, 2, 3],
            &[4, 5, 6, 7],
            &[0, 1, 5, 4],
            &[1, 2, 6, 5],
            &[2, 3, 7, 6],
            &[3, 0, 4, 7],
        ]
    }
    fn shape(&self, xi: [f64; 3], n: &mut [f64]) {
        let [r, s, u] = xi;
        for (n, c) in n.iter_mut().zip(&HEX8_CORNERS) {
            *n = 0.125 * (1.0 + c[0] * r) * (1.0 + c[1] * s) * (1.0 + c[2] * u);
        }
    }
    fn gradients(&self, xi: [f64; 3], g: &mut [[f64; 3]]) {
        let [r, s, u] = xi;
        for (g, c) in g.iter_mut().zip(&HEX8_CORNERS) {
            *g = [
                0.125 * c[0] * (1.0 + c[1] * s) * (1.0 + c[2] * u),
                0.125 * c[1] * (1.0 + c[0] * r) * (1.0 + c[2] * u),
                0.125 * c[2] * (1.0 + c[0] * r) * (1.0 + c[1] * s),
            ];
        }
    }
    fn rule(&self, _rule: Rule) -> &'static [([f64; 3], f64)] {
        &GAUSS
    }
    fn centre(&self) -> [f64; 3] {
        [0.0; 3]
    }
    fn lumping(&self) -> Lumping {
        Lumping::RowSum
    }
}
