//! The 10-node (quadratic) tetrahedron on the reference tetrahedron (volume ⅙), in the
//! volume coordinates `L = (1 − r − s − t, r, s, t)`: corners `N_a = L_a (2 L_a − 1)`,
//! mid-edge nodes `N = 4 L_a L_b` on the edges 0–1, 1–2, 2–0, 0–3, 1–3, 2–3 in that
//! order (VTK type 24); Gmsh (type 11) lists the last two edges the other way round
//! (its nodes 8 and 9 are VTK's 9 and 8, as meshio converts them).

use std::sync::OnceLock;

use super::{Element, Lumping, Rule, conical_rule};

/// The 10-node tetrahedron.
pub struct Tet10;

/// The corner pairs of the mid-edge nodes 4 … 9.
const EDGES: [[usize; 2]; 6] = [[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]];
const DL: [[f64; 3]; 4] = [
    [-1.0, -1.0, -1.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
];

fn volume_coordinates(xi: [f64; 3]) -> [f64; 4] {
    [1.0 - xi[0] - xi[1] - xi[2], xi[0], xi[1], xi[2]]
}

impl Element for Tet10 {
    fn name(&self) -> &'static str {
        "tet10"
    }
    fn nodes(&self) -> usize {
        10
    }
    fn dim(&self) -> usize {
        3
    }
    fn order(&self) -> usize {
        2
    }
    fn corners(&self) -> usize {
        4
    }
    fn vtk_type(&self) -> u8 {
        24
    }
    fn gmsh_type(&self) -> usize {
        11
    }
    fn gmsh_order(&self) -> Option<&'static [usize]> {
        Some(&[0, 1, 2, 3, 4, 5, 6, 7, 9, 8])
    }
    fn reference_nodes(&self) -> &'static [[f64; 3]] {
        &[
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.5, 0.0, 0.0],
            [0.5, 0.5, 0.0],
            [0.0, 0.5, 0.0],
            [0.0, 0.0, 0.5],
            [0.5, 0.0, 0.5],
            [0.0, 0.5, 0.5],
        ]
    }
    fn faces(&self) -> &'static [&'static [usize]] {
        &[
            &[0, 1, 2, 4, 5, 6],
            &[0, 1, 3, 4, 8, 7],
            &[1, 2, 3, 5, 9, 8],
            &[0, 2, 3, 6, 9, 7],
        ]
    }
    fn shape(&self, xi: [f64; 3], n: &mut [f64]) {
        let l = volume_coordinates(xi);
        for a in 0..4 {
            n[a] = l[a] * (2.0 * l[a] - 1.0);
        }
        for (m, &[a, b]) in EDGES.iter().enumerate() {
            n[4 + m] = 4.0 * l[a] * l[b];
        }
    }
    fn gradients(&self, xi: [f64; 3], g: &mut [[f64; 3]]) {
        let l = volume_coordinates(xi);
        for a in 0..4 {
            let c = 4.0 * l[a] - 1.0;
            g[a] = DL[a].map(|d| c * d);
        }
        for (m, &[a, b]) in EDGES.iter().enumerate() {
            g[4 + m] = std::array::from_fn(|j| 4.0 * (l[b] * DL[a][j] + l[a] * DL[b][j]));
        }
    }
    fn rule(&self, _rule: Rule) -> &'static [([f64; 3], f64)] {
        static RULE: OnceLock<Vec<([f64; 3], f64)>> = OnceLock::new();
        RULE.get_or_init(conical_rule)
    }
    fn centre(&self) -> [f64; 3] {
        [0.25; 3]
    }
    fn lumping(&self) -> Lumping {
        Lumping::Hrz
    }
}
