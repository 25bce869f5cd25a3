//! The 8-node (serendipity) quadrilateral on `[−1, 1]²`: corners
//! `N_a = ¼ (1 + r_a r)(1 + s_a s)(r_a r + s_a s − 1)`, mid-side nodes
//! `½ (1 − r²)(1 + s_a s)` or `½ (1 + r_a r)(1 − s²)` on the edges 0–1, 1–2, 2–3, 3–0 in
//! that order; VTK type 23, Gmsh type 16, the same node order in both.

use super::{Element, GAUSS3_2D, Lumping, Rule};

/// The 8-node quadrilateral.
pub struct Quad8;

/// Reference coordinates of the nodes.
const NODES: [[f64; 3]; 8] = [
    [-1.0, -1.0, 0.0],
    [1.0, -1.0, 0.0],
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
    [0.0, -1.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [-1.0, 0.0, 0.0],
];

impl Element for Quad8 {
    fn name(&self) -> &'static str {
        "quad8"
    }
    fn nodes(&self) -> usize {
        8
    }
    fn dim(&self) -> usize {
        2
    }
    fn order(&self) -> usize {
        2
    }
    fn corners(&self) -> usize {
        4
    }
    fn vtk_type(&self) -> u8 {
        23
    }
    fn gmsh_type(&self) -> usize {
        16
    }
    fn reference_nodes(&self) -> &'static [[f64; 3]] {
        &NODES
    }
    fn faces(&self) -> &'static [&'static [usize]] {
        &[&[0, 1, 4], &[1, 2, 5], &[2, 3, 6], &[3, 0, 7]]
    }
    fn shape(&self, xi: [f64; 3], n: &mut [f64]) {
        let [r, s, _] = xi;
        for (n, c) in n.iter_mut().zip(&NODES) {
            let (ra, sa) = (c[0], c[1]);
            *n = if ra == 0.0 {
                0.5 * (1.0 - r * r) * (1.0 + sa * s)
            } else if sa == 0.0 {
                0.5 * (1.0 + ra * r) * (1.0 - s * s)
            } else {
                0.25 * (1.0 + ra * r) * (1.0 + sa * s) * (ra * r + sa * s - 1.0)
            };
        }
    }
    fn gradients(&self, xi: [f64; 3], g: &mut [[f64; 3]]) {
        let [r, s, _] = xi;
        for (g, c) in g.iter_mut().zip(&NODES) {
            let (ra, sa) = (c[0], c[1]);
            *g = if ra == 0.0 {
                [-r * (1.0 + sa * s), 0.5 * sa * (1.0 - r * r), 0.0]
            } else if sa == 0.0 {
                [0.5 * ra * (1.0 - s * s), -s * (1.0 + ra * r), 0.0]
            } else {
                [
                    0.25 * ra * (1.0 + sa * s) * (2.0 * ra * r + sa * s),
                    0.25 * sa * (1.0 + ra * r) * (ra * r + 2.0 * sa * s),
                    0.0,
                ]
            };
        }
    }
    fn rule(&self, _rule: Rule) -> &'static [([f64; 3], f64)] {
        &GAUSS3_2D
    }
    fn centre(&self) -> [f64; 3] {
        [0.0; 3]
    }
    fn lumping(&self) -> Lumping {
        Lumping::Hrz
    }
}
