//! The 9-node (Lagrange) quadrilateral on `[−1, 1]²`: `N_a = ℓ_{r_a}(r) ℓ_{s_a}(s)` with
//! the 1-D quadratics `ℓ₋₁(x) = x(x − 1)/2`, `ℓ₀(x) = 1 − x²`, `ℓ₁(x) = x(x + 1)/2`;
//! corners, mid-side nodes on the edges 0–1, 1–2, 2–3, 3–0, then the centre; VTK type
//! 28, Gmsh type 10, the same node order in both.

use super::{Element, GAUSS3_2D, Lumping, Rule, lagrange2};

/// The 9-node quadrilateral.
pub struct Quad9;

/// Reference coordinates of the nodes.
const NODES: [[f64; 3]; 9] = [
    [-1.0, -1.0, 0.0],
    [1.0, -1.0, 0.0],
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
    [0.0, -1.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [-1.0, 0.0, 0.0],
    [0.0, 0.0, 0.0],
];

impl Element for Quad9 {
    fn name(&self) -> &'static str {
        "quad9"
    }
    fn nodes(&self) -> usize {
        9
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
        28
    }
    fn gmsh_type(&self) -> usize {
        10
    }
    fn reference_nodes(&self) -> &'static [[f64; 3]] {
        &NODES
    }
    fn faces(&self) -> &'static [&'static [usize]] {
        &[&[0, 1, 4], &[1, 2, 5], &[2, 3, 6], &[3, 0, 7]]
    }
    fn shape(&self, xi: [f64; 3], n: &mut [f64]) {
        for (n, c) in n.iter_mut().zip(&NODES) {
            *n = lagrange2(c[0], xi[0]).0 * lagrange2(c[1], xi[1]).0;
        }
    }
    fn gradients(&self, xi: [f64; 3], g: &mut [[f64; 3]]) {
        for (g, c) in g.iter_mut().zip(&NODES) {
            let (lr, dr) = lagrange2(c[0], xi[0]);
            let (ls, ds) = lagrange2(c[1], xi[1]);
            *g = [dr * ls, lr * ds, 0.0];
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
