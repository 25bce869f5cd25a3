//! The 27-node (Lagrange) hexahedron on `[−1, 1]³`: `N_a = ℓ_{r_a}(r) ℓ_{s_a}(s)
//! ℓ_{t_a}(t)` with the 1-D quadratics of [`super::lagrange2`]. Node order VTK's (type
//! 29): hex20's, then the face centres of the faces x = −1, x = +1, y = −1, y = +1,
//! z = −1, z = +1, then the centre; Gmsh (type 12) orders edges and faces otherwise
//! ([`HEX27_GMSH`], meshio's conversion).

use super::hex20::HEX20_FACES;
use super::{Element, GAUSS3_3D, HEX_NODES, Lumping, Rule, lagrange2};

/// The 27-node hexahedron.
pub struct Hex27;

/// Our (VTK's) node `a` is Gmsh's node `HEX27_GMSH[a]`.
pub const HEX27_GMSH: [usize; 27] = [
    0, 1, 2, 3, 4, 5, 6, 7, 8, 11, 13, 9, 16, 18, 19, 17, 10, 12, 14, 15, 22, 23, 21, 24, 20, 25,
    26,
];

/// The faces: hex20's, each with its centre node last.
const FACES: [&[usize]; 6] = {
    const fn with(f: &[usize], c: usize) -> [usize; 9] {
        let mut out = [c; 9];
        let mut i = 0;
        while i < 8 {
            out[i] = f[i];
            i += 1;
        }
        out
    }
    const F: [[usize; 9]; 6] = [
        with(HEX20_FACES[0], 24),
        with(HEX20_FACES[1], 25),
        with(HEX20_FACES[2], 22),
        with(HEX20_FACES[3], 21),
        with(HEX20_FACES[4], 23),
        with(HEX20_FACES[5], 20),
    ];
    [&F[0], &F[1], &F[2], &F[3], &F[4], &F[5]]
};

impl Element for Hex27 {
    fn name(&self) -> &'static str {
        "hex27"
    }
    fn nodes(&self) -> usize {
        27
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
        29
    }
    fn gmsh_type(&self) -> usize {
        12
    }
    fn gmsh_order(&self) -> Option<&'static [usize]> {
        Some(&HEX27_GMSH)
    }
    fn reference_nodes(&self) -> &'static [[f64; 3]] {
        &HEX_NODES
    }
    fn faces(&self) -> &'static [&'static [usize]] {
        &FACES
    }
    fn shape(&self, xi: [f64; 3], n: &mut [f64]) {
        for (n, c) in n.iter_mut().zip(&HEX_NODES) {
            *n = (0..3).map(|i| lagrange2(c[i], xi[i]).0).product();
        }
    }
    fn gradients(&self, xi: [f64; 3], g: &mut [[f64; 3]]) {
        for (g, c) in g.iter_mut().zip(&HEX_NODES) {
            let l: [(f64, f64); 3] = std::array::from_fn(|i| lagrange2(c[i], xi[i]));
            *g = [
                l[0].1 * l[1].0 * l[2].0,
                l[0].0 * l[1].1 * l[2].0,
                l[0].0 * l[1].0 * l[2].1,
            ];
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
