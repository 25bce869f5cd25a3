//! The 6-node (quadratic) triangle on the reference triangle `r, s ≥ 0, r + s ≤ 1`,
//! in the area coordinates `L = (1 − r − s, r, s)`: corners `N_a = L_a (2 L_a − 1)`,
//! mid-side nodes `N = 4 L_a L_b` on the edges 0–1, 1–2, 2–0 in that order; VTK type
//! 22, Gmsh type 9, the same node order in both.

use super::{Element, Lumping, Rule};

/// The 6-node triangle.
pub struct Tri6;

// Dunavant's degree-4 rule (6 points, positive weights): the consistent mass of an
// affine tri6 (degree 4) exactly; weights are for the reference area ½.
const W1: f64 = 0.5 * 0.223_381_589_678_011;
const W2: f64 = 0.5 * 0.109_951_743_655_322;
const A1: f64 = 0.445_948_490_915_965;
const B1: f64 = 0.108_103_018_168_070;
const A2: f64 = 0.091_576_213_509_771;
const B2: f64 = 0.816_847_572_980_459;
const FULL: [([f64; 3], f64); 6] = [
    ([A1, A1, 0.0], W1),
    ([B1, A1, 0.0], W1),
    ([A1, B1, 0.0], W1),
    ([A2, A2, 0.0], W2),
    ([B2, A2, 0.0], W2),
    ([A2, B2, 0.0], W2),
];

/// The area coordinates of `(r, s)` and their gradients.
fn area(xi: [f64; 3]) -> [f64; 3] {
    [1.0 - xi[0] - xi[1], xi[0], xi[1]]
}
const DL: [[f64; 2]; 3] = [[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]];
/// The corner pairs of the mid-side nodes 3, 4, 5.
const EDGES: [[usize; 2]; 3] = [[0, 1], [1, 2], [2, 0]];

impl Element for Tri6 {
    fn name(&self) -> &'static str {
        "tri6"
    }
    fn nodes(&self) -> usize {
        6
    }
    fn dim(&self) -> usize {
        2
    }
    fn order(&self) -> usize {
        2
    }
    fn corners(&self) -> usize {
        3
    }
    fn vtk_type(&self) -> u8 {
        22
    }
    fn gmsh_type(&self) -> usize {
        9
    }
    fn reference_nodes(&self) -> &'static [[f64; 3]] {
        &[
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.5, 0.0, 0.0],
            [0.5, 0.5, 0.0],
            [0.0, 0.5, 0.0],
        ]
    }
    fn faces(&self) -> &'static [&'static [usize]] {
        &[&[0, 1, 3], &[1, 2, 4], &[2, 0, 5]]
    }
    fn shape(&self, xi: [f64; 3], n: &mut [f64]) {
        let l = area(xi);
        for a in 0..3 {
            n[a] = l[a] * (2.0 * l[a] - 1.0);
        }
        for (m, [a, b]) in EDGES.iter().enumerate() {
            n[3 + m] = 4.0 * l[*a] * l[*b];
        }
    }
    fn gradients(&self, xi: [f64; 3], g: &mut [[f64; 3]]) {
        let l = area(xi);
        for a in 0..3 {
            let c = 4.0 * l[a] - 1.0;
            g[a] = [c * DL[a][0], c * DL[a][1], 0.0];
        }
        for (m, &[a, b]) in EDGES.iter().enumerate() {
            g[3 + m] = [
                4.0 * (l[b] * DL[a][0] + l[a] * DL[b][0]),
                4.0 * (l[b] * DL[a][1] + l[a] * DL[b][1]),
                0.0,
            ];
        }
    }
    fn rule(&self, _rule: Rule) -> &'static [([f64; 3], f64)] {
        &FULL
    }
    fn centre(&self) -> [f64; 3] {
        [1.0 / 3.0, 1.0 / 3.0, 0.0]
    }
    fn lumping(&self) -> Lumping {
        Lumping::Hrz
    }
}
