//! The 4-node (bilinear) quadrilateral on `[−1, 1]²`:
//! `N_a = ¼ (1 + r_a r)(1 + s_a s)`, nodes counter-clockwise from `(−1, −1)`; VTK type
//! 9, Gmsh type 3, the same node order in both.

use super::{Element, G2, Lumping, Rule};

/// The 4-node quadrilateral.
pub struct Quad4;

/// Reference coordinates (±1) of the corners (VTK / Gmsh node order).
pub const QUAD4_CORNERS: [[f64; 2]; 4] = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];

/// 2×2 Gauss points (degree 3: the consistent mass and the stiffness of a
/// parallelogram exactly).
const GAUSS: [([f64; 3], f64); 4] = [
    ([G2[0], G2[0], 0.0], 1.0),
    ([G2[0], G2[1], 0.0], 1.0),
    ([G2[1], G2[0], 0.0], 1.0),
    ([G2[1], G2[1], 0.0], 1.0),
];

impl Element for Quad4 {
    fn name(&self) -> &'static str {
        "quad4"
    }
    fn nodes(&self) -> usize {
        4
    }
    fn dim(&self) -> usize {
        2
    }
    fn vtk_type(&self) -> u8 {
        9
    }
    fn gmsh_type(&self) -> usize {
        3
    }
    fn reference_nodes(&self) -> &'static [[f64; 3]] {
        &[
            [-1.0, -1.0, 0.0],
            [1.0, -1.0, 0.0],
            [1.0, 1.0, 0.0],
            [-1.0, 1.0, 0.0],
        ]
    }
    fn faces(&self) -> &'static [&'static [usize]] {
        &[&[0, 1], &[1, 2], &[2, 3], &[3, 0]]
    }
    fn shape(&self, xi: [f64; 3], n: &mut [f64]) {
        let [r, s, _] = xi;
        n[..4].copy_from_slice(&[
            0.25 * (1.0 - r) * (1.0 - s),
            0.25 * (1.0 + r) * (1.0 - s),
            0.25 * (1.0 + r) * (1.0 + s),
            0.25 * (1.0 - r) * (1.0 + s),
        ]);
    }
    fn gradients(&self, xi: [f64; 3], g: &mut [[f64; 3]]) {
        let [r, s, _] = xi;
        g[..4].copy_from_slice(&[
            [-0.25 * (1.0 - s), -0.25 * (1.0 - r), 0.0],
            [0.25 * (1.0 - s), -0.25 * (1.0 + r), 0.0],
            [0.25 * (1.0 + s), 0.25 * (1.0 + r), 0.0],
            [-0.25 * (1.0 + s), 0.25 * (1.0 - r), 0.0],
        ]);
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
