//! The 3-node triangle: linear shape functions `N = (1 − r − s, r, s)` on the
//! reference triangle `r, s ≥ 0, r + s ≤ 1` (area ½); VTK type 5, Gmsh type 2, the
//! same node order in both.

use super::{Element, Lumping, Rule};

/// The 3-node triangle.
pub struct Tri3;

/// The 3 edge-midpoint rule (degree 2): the consistent mass exactly.
const FULL: [([f64; 3], f64); 3] = [
    ([0.5, 0.0, 0.0], 1.0 / 6.0),
    ([0.5, 0.5, 0.0], 1.0 / 6.0),
    ([0.0, 0.5, 0.0], 1.0 / 6.0),
];

/// Three interior points `(1/6, 1/6)` and permutations (degree 2): `r > 0` at every
/// point, which the axisymmetric kernel needs on a cell with an edge on the axis.
const INTERIOR: [([f64; 3], f64); 3] = [
    ([1.0 / 6.0, 1.0 / 6.0, 0.0], 1.0 / 6.0),
    ([2.0 / 3.0, 1.0 / 6.0, 0.0], 1.0 / 6.0),
    ([1.0 / 6.0, 2.0 / 3.0, 0.0], 1.0 / 6.0),
];

/// The centroid (constant gradients: force, tangent and energy exactly).
const ENERGY: [([f64; 3], f64); 1] = [([1.0 / 3.0, 1.0 / 3.0, 0.0], 0.5)];

impl Element for Tri3 {
    fn name(&self) -> &'static str {
        "tri3"
    }
    fn nodes(&self) -> usize {
        3
    }
    fn dim(&self) -> usize {
        2
    }
    fn vtk_type(&self) -> u8 {
        5
    }
    fn gmsh_type(&self) -> usize {
        2
    }
    fn reference_nodes(&self) -> &'static [[f64; 3]] {
        &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    }
    fn faces(&self) -> &'static [&'static [usize]] {
        &[&[0, 1], &[1, 2], &[2, 0]]
    }
    fn shape(&self, xi: [f64; 3], n: &mut [f64]) {
        let [r, s, _] = xi;
        n[..3].copy_from_slice(&[1.0 - r - s, r, s]);
    }
    fn gradients(&self, _xi: [f64; 3], g: &mut [[f64; 3]]) {
        g[..3].copy_from_slice(&[[-1.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    }
    fn rule(&self, rule: Rule) -> &'static [([f64; 3], f64)] {
        match rule {
            Rule::Full => &FULL,
            Rule::Interior => &INTERIOR,
            Rule::Energy => &ENERGY,
        }
    }
    fn centre(&self) -> [f64; 3] {
        [1.0 / 3.0, 1.0 / 3.0, 0.0]
    }
    fn lumping(&self) -> Lumping {
        Lumping::RowSum
    }
}
