//! The 4-node tetrahedron: linear shape functions `N = (1 − r − s − t, r, s, t)` on
//! the reference tetrahedron (volume ⅙); VTK type 10, Gmsh type 4, the same node order
//! in both (positive volume: node 3 on the side of `(x₁ − x₀) × (x₂ − x₀)`).

use super::{Element, Lumping, Rule};

/// The 4-node tetrahedron.
pub struct Tet4;

const A: f64 = 0.585_410_196_624_968_5;
const B: f64 = 0.138_196_601_125_010_5;

/// The 4-point rule of degree 2: the consistent mass exactly.
const FULL: [([f64; 3], f64); 4] = [
    ([B, B, B], 1.0 / 24.0),
    ([A, B, B], 1.0 / 24.0),
    ([B, A, B], 1.0 / 24.0),
    ([B, B, A], 1.0 / 24.0),
];

/// The centroid (constant gradients: force, tangent and energy exactly, at a quarter
/// of the cost of the mass's rule).
const ENERGY: [([f64; 3], f64); 1] = [([0.25, 0.25, 0.25], 1.0 / 6.0)];

impl Element for Tet4 {
    fn name(&self) -> &'static str {
        "tet4"
    }
    fn nodes(&self) -> usize {
        4
    }
    fn dim(&self) -> usize {
        3
    }
    fn vtk_type(&self) -> u8 {
        10
    }
    fn gmsh_type(&self) -> usize {
        4
    }
    fn reference_nodes(&self) -> &'static [[f64; 3]] {
        &[
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ]
    }
    fn faces(&self) -> &'static [&'static [usize]] {
        &[&[0, 1, 2], &[0, 1, 3], &[1, 2, 3], &[0, 2, 3]]
    }
    fn shape(&self, xi: [f64; 3], n: &mut [f64]) {
        let [r, s, t] = xi;
        n[..4].copy_from_slice(&[1.0 - r - s - t, r, s, t]);
    }
    fn gradients(&self, _xi: [f64; 3], g: &mut [[f64; 3]]) {
        g[..4].copy_from_slice(&[
            [-1.0, -1.0, -1.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ]);
    }
    fn rule(&self, rule: Rule) -> &'static [([f64; 3], f64)] {
        match rule {
            Rule::Full | Rule::Interior => &FULL,
            Rule::Energy => &ENERGY,
        }
    }
    fn centre(&self) -> [f64; 3] {
        [0.25, 0.25, 0.25]
    }
    fn lumping(&self) -> Lumping {
        Lumping::RowSum
    }
}
