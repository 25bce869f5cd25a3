//! The element kinds (issue 51): one type per kind behind [`Element`] — its nodes and
//! their reference coordinates, its faces (edges in 2-D) as node lists, its reference
//! shape functions and gradients, its quadrature rules, its VTK and Gmsh codes, its
//! lumping rule — and [`CellKind`], the registry that names them in meshes, scene files
//! and messages.
//!
//! Everything that needs to know a kind asks it here: the mesh readers (codes), the
//! frames (VTK code), the boundary facets (faces), the element kernels and the
//! hyperelastic forces (shape functions at the rules' points, [`points`]), the strains of
//! the frames (gradients at the centre). The kernels are compiled per cell size (fixed
//! nalgebra matrices, no allocation per cell): a `match` on [`CellKind`] in
//! `model::solid::element_matrices` and in `model::hyperelastic` picks the size.
//!
//! **Adding a kind**: its file here (a unit struct implementing [`Element`]) and its
//! line in the `registry!` list of this file (the variant of [`CellKind`] and its
//! element); the compiler then asks for its size's arm in the three `match`es that pick
//! a fixed-size kernel (`model::solid::element_matrices`, and
//! `model::hyperelastic::HyperBody`'s cell dispatch and `supports`), each one line; the unit tests of this module then check its shape
//! functions (partition of unity, Kronecker property at the nodes, gradients against
//! finite differences), its rules (reference volume) and its faces (outward, by the
//! centroid) without more code.

mod hex20;
mod hex27;
mod hex8;
mod quad4;
mod quad8;
mod quad9;
mod tet10;
mod tet4;
mod tri3;
mod tri6;

pub use hex8::{HEX8_CORNERS, Hex8};
pub use hex20::{HEX20_GMSH, Hex20};
pub use hex27::{HEX27_GMSH, Hex27};
pub use quad4::{QUAD4_CORNERS, Quad4};
pub use quad8::Quad8;
pub use quad9::Quad9;
pub use tet4::Tet4;
pub use tet10::Tet10;
pub use tri3::Tri3;
pub use tri6::Tri6;

/// The most nodes a cell of any kind has (fixed-size buffers of the kernels, the
/// readers and the frames).
pub const MAX_NODES: usize = 27;

/// The 2-point Gauss abscissae on `[−1, 1]` (weights 1).
pub(crate) const G2: [f64; 2] = [-0.577_350_269_189_625_8, 0.577_350_269_189_625_8];

/// The 3-point Gauss abscissae and weights on `[−1, 1]` (degree 5).
pub(crate) const G3: [(f64, f64); 3] = [
    (-0.774_596_669_241_483_4, 5.0 / 9.0),
    (0.0, 8.0 / 9.0),
    (0.774_596_669_241_483_4, 5.0 / 9.0),
];

/// 3×3 Gauss points on `[−1, 1]²`, `r` slowest: the consistent mass and the stiffness
/// of an undistorted quadratic quadrilateral exactly.
pub(crate) const GAUSS3_2D: [([f64; 3], f64); 9] = {
    let mut out = [([0.0; 3], 0.0); 9];
    let mut p = 0;
    while p < 9 {
        let (a, b) = (G3[p / 3], G3[p % 3]);
        out[p] = ([a.0, b.0, 0.0], a.1 * b.1);
        p += 1;
    }
    out
};

/// 3×3×3 Gauss points on `[−1, 1]³`, `r` slowest: the consistent mass and the stiffness
/// of an undistorted quadratic hexahedron exactly.
pub(crate) const GAUSS3_3D: [([f64; 3], f64); 27] = {
    let mut out = [([0.0; 3], 0.0); 27];
    let mut p = 0;
    while p < 27 {
        let (a, b, c) = (G3[p / 9], G3[(p / 3) % 3], G3[p % 3]);
        out[p] = ([a.0, b.0, c.0], a.1 * b.1 * c.1);
        p += 1;
    }
    out
};

/// Reference coordinates of the quadratic hexahedra's nodes in VTK's order: the
/// corners, the mid-edge nodes (edges 0–1, 1–2, 2–3, 3–0, 4–5, 5–6, 6–7, 7–4, 0–4,
/// 1–5, 2–6, 3–7), the face centres (x = −1, x = +1, y = −1, y = +1, z = −1, z = +1:
/// VTK's parametric coordinates of the triquadratic hexahedron, as meshio converts
/// Gmsh's) and the centre; hex20 has the first 20.
pub(crate) const HEX_NODES: [[f64; 3]; 27] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
    [0.0, -1.0, -1.0],
    [1.0, 0.0, -1.0],
    [0.0, 1.0, -1.0],
    [-1.0, 0.0, -1.0],
    [0.0, -1.0, 1.0],
    [1.0, 0.0, 1.0],
    [0.0, 1.0, 1.0],
    [-1.0, 0.0, 1.0],
    [-1.0, -1.0, 0.0],
    [1.0, -1.0, 0.0],
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
    [-1.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, -1.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, -1.0],
    [0.0, 0.0, 1.0],
    [0.0, 0.0, 0.0],
];

/// hex20's nodes: the first 20 of [`HEX_NODES`].
pub(crate) const HEX_EDGE_NODES: [[f64; 3]; 20] = {
    let mut out = [[0.0; 3]; 20];
    let mut i = 0;
    while i < 20 {
        out[i] = HEX_NODES[i];
        i += 1;
    }
    out
};

/// A rule on the reference tetrahedron exact to degree 4 (the consistent mass of an
/// affine tet10), with positive weights and every point inside: the conical product
/// (Stroud) of Gauss–Legendre rules through the collapse `r = u`, `s = v(1 − u)`,
/// `t = w(1 − u)(1 − v)`, whose Jacobian `(1 − u)²(1 − v)` raises the degree in `u` by
/// two and in `v` by one: 4 points in `u` (degree 7), 3 in `v` and `w` (degree 5),
/// 36 points. Written here rather than tabulated: every constant is the Gauss rules'.
pub(crate) fn conical_rule() -> Vec<([f64; 3], f64)> {
    const G4: [(f64, f64); 4] = [
        (-0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
        (-0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
        (0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
        (0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
    ];
    // Gauss–Legendre on [0, 1]
    let unit = |(x, w): (f64, f64)| (0.5 * (1.0 + x), 0.5 * w);
    let mut out = Vec::with_capacity(36);
    for &gu in &G4 {
        let (u, wu) = unit(gu);
        for &gv in &G3 {
            let (v, wv) = unit(gv);
            for &gw in &G3 {
                let (w, ww) = unit(gw);
                let jac = (1.0 - u) * (1.0 - u) * (1.0 - v);
                out.push((
                    [u, v * (1.0 - u), w * (1.0 - u) * (1.0 - v)],
                    wu * wv * ww * jac,
                ));
            }
        }
    }
    out
}

/// The 1-D quadratic Lagrange function of the node at `node` ∈ {−1, 0, 1} and its
/// derivative, at `x`.
pub(crate) fn lagrange2(node: f64, x: f64) -> (f64, f64) {
    if node == 0.0 {
        (1.0 - x * x, -2.0 * x)
    } else {
        (0.5 * x * (x + node), x + 0.5 * node)
    }
}

/// A boundary edge of a 2-D cell with `k` = 2 or 3 nodes (corners at ξ = −1 and 1, then
/// a mid-side node at 0): its shape functions and their derivatives at `xi` (the third
/// slot 0 on a 2-node edge). What contact rows, mortar integrals and pressures evaluate
/// on edges.
pub fn edge_shape(k: usize, xi: f64) -> ([f64; 3], [f64; 3]) {
    let (mut n, mut d) = ([0.0; 3], [0.0; 3]);
    for (b, node) in [-1.0, 1.0, 0.0].into_iter().enumerate().take(k) {
        (n[b], d[b]) = if k == 2 {
            (0.5 * (1.0 + node * xi), 0.5 * node)
        } else {
            lagrange2(node, xi)
        };
    }
    (n, d)
}

/// The 2-D kind whose shape functions a boundary face of a 3-D cell with `k` nodes has
/// (corners first, then mid-side nodes, then a centre): tri3, tri6, quad4, quad8, quad9;
/// `None` for any other count.
pub fn face_kind(k: usize) -> Option<CellKind> {
    match k {
        3 => Some(CellKind::Tri3),
        6 => Some(CellKind::Tri6),
        4 => Some(CellKind::Quad4),
        8 => Some(CellKind::Quad8),
        9 => Some(CellKind::Quad9),
        _ => None,
    }
}

/// Which quadrature rule a computation asks of an element.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rule {
    /// The small-strain kernels' rule: the consistent mass exactly on an undistorted
    /// cell, and the stiffness.
    Full,
    /// A rule with every point strictly inside the cell (the axisymmetric kernel divides
    /// by the radius there).
    Interior,
    /// The large-strain internal force, tangent and energy: the fewest points that
    /// integrate them exactly where the gradients are constant (simplices), the full rule
    /// otherwise.
    Energy,
}

/// How a lumped mass is formed from the element's consistent mass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lumping {
    /// Row sums: positive for the linear elements.
    RowSum,
    /// Hinton, Rock and Zienkiewicz (1976): the consistent diagonal scaled to keep the
    /// element's mass — positive where row sums are zero or negative (the corners of
    /// tri6, quad8, tet10, hex20).
    Hrz,
}

/// One element kind: what a kernel, a reader or a writer needs to know of it (module
/// doc). Reference coordinates have three components (zero past the element's
/// dimension).
pub trait Element: Send + Sync {
    /// The name in meshes, scene files and messages (`tri3`, `hex8`, …).
    fn name(&self) -> &'static str;
    /// Nodes per cell.
    fn nodes(&self) -> usize;
    /// Space dimension.
    fn dim(&self) -> usize;
    /// Polynomial order of the shape functions (1 linear, 2 quadratic).
    fn order(&self) -> usize {
        1
    }
    /// Vertex nodes (the first ones in the node order).
    fn corners(&self) -> usize {
        self.nodes()
    }
    /// The VTK cell type.
    fn vtk_type(&self) -> u8;
    /// The Gmsh element type (formats 2.2 and 4.1).
    fn gmsh_type(&self) -> usize;
    /// Where Gmsh's node order differs from ours (VTK's): our node `a` is the Gmsh
    /// cell's node `order[a]`. `None`: the same order.
    fn gmsh_order(&self) -> Option<&'static [usize]> {
        None
    }
    /// Reference coordinates of the nodes, in the node order (VTK's).
    fn reference_nodes(&self) -> &'static [[f64; 3]];
    /// The faces (edges in 2-D) as lists of the cell's local nodes.
    fn faces(&self) -> &'static [&'static [usize]];
    /// Shape function values at reference point `xi` into `n[..nodes]`.
    fn shape(&self, xi: [f64; 3], n: &mut [f64]);
    /// Reference gradients `∂N_a/∂ξ_j` at `xi` into `g[..nodes]`.
    fn gradients(&self, xi: [f64; 3], g: &mut [[f64; 3]]);
    /// Quadrature points and weights on the reference cell.
    fn rule(&self, rule: Rule) -> &'static [([f64; 3], f64)];
    /// Reference coordinates of the cell's centre (where the frames' strains are read).
    fn centre(&self) -> [f64; 3];
    /// The lumping rule.
    fn lumping(&self) -> Lumping;
}

/// Declares [`CellKind`] from one list — a variant and its element per line — with
/// [`CellKind::ALL`] and [`CellKind::element`] from the same list, so a kind cannot be
/// declared without being registered.
macro_rules! registry {
    ($($(#[$doc:meta])* $variant:ident => $element:ident,)*) => {
        /// The element kinds, for every material law.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
        #[serde(rename_all = "kebab-case")]
        pub enum CellKind {
            $($(#[$doc])* $variant,)*
        }

        impl CellKind {
            /// Every kind, in declaration order.
            pub const ALL: &'static [CellKind] = &[$(CellKind::$variant,)*];

            /// The kind's element.
            pub fn element(self) -> &'static dyn Element {
                match self {
                    $(CellKind::$variant => &$element,)*
                }
            }
        }
    };
}

// The registry: one line per kind.
registry! {
    /// 3-node triangle ([`Tri3`]).
    Tri3 => Tri3,
    /// 4-node quadrilateral, counter-clockwise ([`Quad4`]).
    Quad4 => Quad4,
    /// 4-node tetrahedron, positive volume ordering ([`Tet4`]).
    Tet4 => Tet4,
    /// 8-node hexahedron, VTK / Gmsh ordering ([`Hex8`]).
    Hex8 => Hex8,
    /// 6-node quadratic triangle ([`Tri6`]).
    Tri6 => Tri6,
    /// 8-node serendipity quadrilateral ([`Quad8`]).
    Quad8 => Quad8,
    /// 9-node Lagrange quadrilateral ([`Quad9`]).
    Quad9 => Quad9,
    /// 10-node quadratic tetrahedron ([`Tet10`]).
    Tet10 => Tet10,
    /// 20-node serendipity hexahedron ([`Hex20`]).
    Hex20 => Hex20,
    /// 27-node Lagrange hexahedron ([`Hex27`]).
    Hex27 => Hex27,
}

impl CellKind {
    /// Nodes per cell.
    pub fn nodes(self) -> usize {
        self.element().nodes()
    }
    /// Space dimension of the cell.
    pub fn dim(self) -> usize {
        self.element().dim()
    }
    /// Name as in meshes and messages.
    pub fn name(self) -> &'static str {
        self.element().name()
    }
    /// The names of the kinds of dimension `dim` (every kind for `None`), for messages:
    /// `tri3, quad4, …`.
    pub fn names(dim: Option<usize>) -> String {
        Self::ALL
            .iter()
            .filter(|k| dim.is_none_or(|d| k.dim() == d))
            .map(|k| k.name())
            .collect::<Vec<_>>()
            .join(", ")
    }
    /// The kind of VTK cell type `t`, if it is one of ours.
    pub fn from_vtk(t: u8) -> Option<CellKind> {
        Self::ALL
            .iter()
            .copied()
            .find(|k| k.element().vtk_type() == t)
    }
    /// A cell's nodes as a Gmsh file lists them, in our (VTK's) order; a list of another
    /// length than the kind's is returned as it is (the reader reports the count).
    pub fn from_gmsh_order(self, nodes: Vec<usize>) -> Vec<usize> {
        match self.element().gmsh_order() {
            Some(order) if nodes.len() == order.len() => order.iter().map(|&g| nodes[g]).collect(),
            _ => nodes,
        }
    }
    /// The kind of Gmsh element type `t`, if it is one of ours.
    pub fn from_gmsh(t: usize) -> Option<CellKind> {
        Self::ALL
            .iter()
            .copied()
            .find(|k| k.element().gmsh_type() == t)
    }
}

/// The corners of a facet (an edge in 2-D, a face in 3-D) of `len` nodes, corners
/// first: 2 for an edge (2 or 3 nodes), 3 for a triangle (3 or 6), 4 for a quadrilateral
/// (4, 8 or 9); `None` for any other count.
pub fn facet_corners(dim: usize, len: usize) -> Option<usize> {
    match (dim, len) {
        (2, 2 | 3) => Some(2),
        (3, 3 | 6) => Some(3),
        (3, 4 | 8 | 9) => Some(4),
        _ => None,
    }
}

/// The columns `∂x/∂ξ_j` of the Jacobian of a cell of `kind` with nodes at `x`, at
/// reference point `xi`; in 2-D the third column is `e_z`, so the 3 × 3 determinant is
/// the 2-D one. What the inverted-cell checks read at a curved cell's nodes.
pub fn jacobian_columns(kind: CellKind, x: &[[f64; 3]], xi: [f64; 3]) -> [[f64; 3]; 3] {
    let e = kind.element();
    let (d, nn) = (e.dim(), e.nodes());
    let mut g = [[0.0; 3]; MAX_NODES];
    e.gradients(xi, &mut g);
    std::array::from_fn(|j| {
        if j < d {
            std::array::from_fn(|i| {
                if i < d {
                    (0..nn).map(|a| x[a][i] * g[a][j]).sum()
                } else {
                    0.0
                }
            })
        } else {
            std::array::from_fn(|i| if i == j { 1.0 } else { 0.0 })
        }
    })
}

/// One integration point: shape values, reference gradients (the element's dimension
/// `D`), weight.
pub type Point<const NN: usize, const D: usize> = ([f64; NN], [[f64; D]; NN], f64);

/// The `P` points of `kind`'s `rule` with its shape values and gradients (`NN` nodes,
/// dimension `D`): what the fixed-size kernels integrate with. Panics if the sizes are
/// not the kind's (a programming error of a kernel dispatch, caught by every test that
/// assembles the kind).
pub fn points<const NN: usize, const D: usize, const P: usize>(
    kind: CellKind,
    rule: Rule,
) -> [Point<NN, D>; P] {
    let e = kind.element();
    let pts = e.rule(rule);
    assert!(
        e.nodes() == NN && e.dim() == D && pts.len() == P,
        "{}: {} nodes, dimension {}, {} points asked as {NN}, {D}, {P}",
        e.name(),
        e.nodes(),
        e.dim(),
        pts.len()
    );
    std::array::from_fn(|p| {
        let (xi, w) = pts[p];
        let mut n = [0.0; NN];
        let mut g3 = [[0.0; 3]; NN];
        e.shape(xi, &mut n);
        e.gradients(xi, &mut g3);
        (n, g3.map(|g| std::array::from_fn(|j| g[j])), w)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn simplex(e: &dyn Element) -> bool {
        e.corners() == e.dim() + 1
    }

    /// `∫ r^i s^j t^k` over the reference cell of `e`.
    fn monomial(e: &dyn Element, p: [u32; 3]) -> f64 {
        let fact = |n: u32| (1..=n).map(f64::from).product::<f64>();
        let d = e.dim();
        if simplex(e) {
            let sum: u32 = p[..d].iter().sum();
            p[..d].iter().map(|&i| fact(i)).product::<f64>() / fact(sum + d as u32)
        } else {
            p[..d]
                .iter()
                .map(|&i| {
                    if i % 2 == 1 {
                        0.0
                    } else {
                        2.0 / f64::from(i + 1)
                    }
                })
                .product()
        }
    }

    fn volume(kind: CellKind) -> f64 {
        monomial(kind.element(), [0; 3])
    }

    /// The full rule integrates every monomial of degree ≤ 2·order (the consistent mass
    /// of an undistorted cell) exactly: to 1e-14 relative to the cell's volume (the
    /// tabulated rules' constants carry 15 digits).
    #[test]
    fn the_full_rule_integrates_the_mass_exactly() {
        for &kind in CellKind::ALL {
            let e = kind.element();
            let deg = 2 * e.order() as u32;
            let d = e.dim();
            for i in 0..=deg {
                for j in 0..=deg - i {
                    for k in 0..=if d == 3 { deg - i - j } else { 0 } {
                        let q: f64 = e
                            .rule(Rule::Full)
                            .iter()
                            .map(|(x, w)| {
                                w * x[0].powi(i as i32) * x[1].powi(j as i32) * x[2].powi(k as i32)
                            })
                            .sum();
                        let exact = monomial(e, [i, j, k]);
                        assert!(
                            (q - exact).abs() < 1e-14 * volume(kind),
                            "{} r^{i} s^{j} t^{k}: {q} against {exact}",
                            e.name()
                        );
                    }
                }
            }
        }
    }

    /// Partition of unity and zero gradient sum at every rule point (to round-off:
    /// 1e-15), the Kronecker property at the nodes (exact for these kinds), gradients
    /// equal to central differences of the shape functions (1e-9: the difference's
    /// error is O(ε²) = 1e-12 for ε = 1e-6 times second derivatives of order one, plus
    /// round-off 1e-16/ε).
    #[test]
    fn shape_functions_interpolate_and_their_gradients_are_their_derivatives() {
        for &kind in CellKind::ALL {
            let e = kind.element();
            let nn = e.nodes();
            let (mut n, mut g) = (vec![0.0; nn], vec![[0.0; 3]; nn]);
            for (a, &x) in e.reference_nodes().iter().enumerate() {
                e.shape(x, &mut n);
                for (b, &v) in n.iter().enumerate() {
                    assert_eq!(v, if a == b { 1.0 } else { 0.0 }, "{} node {a}", e.name());
                }
            }
            for rule in [Rule::Full, Rule::Interior, Rule::Energy] {
                for &(x, _) in e.rule(rule) {
                    e.shape(x, &mut n);
                    e.gradients(x, &mut g);
                    assert!((n.iter().sum::<f64>() - 1.0).abs() < 1e-15, "{}", e.name());
                    for j in 0..3 {
                        let s: f64 = g.iter().map(|g| g[j]).sum();
                        assert!(s.abs() < 1e-15, "{} ∑∂N/∂ξ{j} = {s}", e.name());
                    }
                    let eps = 1e-6;
                    for j in 0..e.dim() {
                        let (mut np, mut nm) = (vec![0.0; nn], vec![0.0; nn]);
                        let (mut xp, mut xm) = (x, x);
                        xp[j] += eps;
                        xm[j] -= eps;
                        e.shape(xp, &mut np);
                        e.shape(xm, &mut nm);
                        for a in 0..nn {
                            let fd = (np[a] - nm[a]) / (2.0 * eps);
                            assert!((fd - g[a][j]).abs() < 1e-9, "{} N{a},{j}", e.name());
                        }
                    }
                }
            }
        }
    }

    /// Every rule's weights sum to the reference cell's measure (round-off: 1e-15
    /// relative), and every point of the interior rule is inside the cell.
    #[test]
    fn rules_integrate_the_reference_volume() {
        for &kind in CellKind::ALL {
            let e = kind.element();
            for rule in [Rule::Full, Rule::Interior, Rule::Energy] {
                let w: f64 = e.rule(rule).iter().map(|p| p.1).sum();
                assert!(
                    (w / volume(kind) - 1.0).abs() < 1e-15,
                    "{} {rule:?}",
                    e.name()
                );
            }
            for &(x, _) in e.rule(Rule::Interior) {
                let d = e.dim();
                let inside = if e.corners() == d + 1 {
                    x[..d].iter().all(|&v| v > 0.0) && x[..d].iter().sum::<f64>() < 1.0
                } else {
                    x[..d].iter().all(|v| v.abs() < 1.0)
                };
                assert!(inside, "{} point {x:?}", e.name());
            }
        }
    }

    /// Every face has a facet's node count ([`facet_corners`] knows it), every corner
    /// lies on some face, and no face is degenerate or through the centre (its normal by
    /// its corners has a non-zero component along the way out, which
    /// `Mesh::boundary_facets` uses to turn it outward).
    #[test]
    fn faces_cover_the_nodes_and_are_not_degenerate() {
        for &kind in CellKind::ALL {
            let e = kind.element();
            let x = e.reference_nodes();
            let c = e.centre();
            let mut seen = vec![false; e.nodes()];
            for f in e.faces() {
                let k = facet_corners(e.dim(), f.len());
                assert!(k.is_some(), "{} face {f:?}", e.name());
                f.iter().for_each(|&a| seen[a] = true);
                let d = |a: usize, b: usize| -> [f64; 3] {
                    std::array::from_fn(|i| x[f[a]][i] - x[f[b]][i])
                };
                let normal = if e.dim() == 2 {
                    let t = d(1, 0);
                    [t[1], -t[0], 0.0]
                } else {
                    let (u, v) = if k == Some(3) {
                        (d(1, 0), d(2, 0))
                    } else {
                        (d(2, 0), d(3, 1))
                    };
                    [
                        u[1] * v[2] - u[2] * v[1],
                        u[2] * v[0] - u[0] * v[2],
                        u[0] * v[1] - u[1] * v[0],
                    ]
                };
                let out: f64 = (0..3).map(|i| normal[i] * (x[f[0]][i] - c[i])).sum();
                assert!(out != 0.0, "{} face {f:?} is degenerate", e.name());
            }
            assert!(seen[..e.corners()].iter().all(|&s| s), "{}", e.name());
            // the mid-side nodes of a face sit at the middle of its edges, a face's centre
            // node at the mean of its corners (which checks the face lists' node order)
            for f in e.faces() {
                let k = facet_corners(e.dim(), f.len()).unwrap_or(f.len());
                let mid = |p: usize, q: usize| -> [f64; 3] {
                    std::array::from_fn(|i| 0.5 * (x[p][i] + x[q][i]))
                };
                let edges = if k == 2 { 1 } else { k };
                for i in 0..(f.len() - k).min(edges) {
                    assert_eq!(x[f[k + i]], mid(f[i], f[(i + 1) % k]), "{} {f:?}", e.name());
                }
                if f.len() == 2 * k + 1 {
                    let c: [f64; 3] = std::array::from_fn(|i| {
                        f[..k].iter().map(|&a| x[a][i]).sum::<f64>() / k as f64
                    });
                    assert_eq!(x[f[2 * k]], c, "{} {f:?}", e.name());
                }
            }
        }
    }

    /// The quadratic kinds' node order is VTK's: their reference nodes are VTK's own
    /// parametric coordinates (`vtkQuadraticTriangle`, `vtkQuadraticQuad`,
    /// `vtkBiQuadraticQuad`, `vtkQuadraticTetra`, `vtkQuadraticHexahedron`,
    /// `vtkTriQuadraticHexahedron` of VTK 9.7.2 from the Python package index,
    /// `GetParametricCoords()`, mapped from [0, 1] to [−1, 1] on quadrilaterals and
    /// hexahedra), exactly.
    #[test]
    fn quadratic_nodes_are_at_vtks_parametric_coordinates() {
        let vtk: [(CellKind, &[[f64; 3]]); 6] = [
            (
                CellKind::Tri6,
                &[
                    [0.0, 0.0, 0.0],
                    [1.0, 0.0, 0.0],
                    [0.0, 1.0, 0.0],
                    [0.5, 0.0, 0.0],
                    [0.5, 0.5, 0.0],
                    [0.0, 0.5, 0.0],
                ],
            ),
            (
                CellKind::Quad8,
                &[
                    [-1.0, -1.0, 0.0],
                    [1.0, -1.0, 0.0],
                    [1.0, 1.0, 0.0],
                    [-1.0, 1.0, 0.0],
                    [0.0, -1.0, 0.0],
                    [1.0, 0.0, 0.0],
                    [0.0, 1.0, 0.0],
                    [-1.0, 0.0, 0.0],
                ],
            ),
            (
                CellKind::Quad9,
                &[
                    [-1.0, -1.0, 0.0],
                    [1.0, -1.0, 0.0],
                    [1.0, 1.0, 0.0],
                    [-1.0, 1.0, 0.0],
                    [0.0, -1.0, 0.0],
                    [1.0, 0.0, 0.0],
                    [0.0, 1.0, 0.0],
                    [-1.0, 0.0, 0.0],
                    [0.0, 0.0, 0.0],
                ],
            ),
            (
                CellKind::Tet10,
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
                ],
            ),
            (
                CellKind::Hex20,
                &[
                    [-1.0, -1.0, -1.0],
                    [1.0, -1.0, -1.0],
                    [1.0, 1.0, -1.0],
                    [-1.0, 1.0, -1.0],
                    [-1.0, -1.0, 1.0],
                    [1.0, -1.0, 1.0],
                    [1.0, 1.0, 1.0],
                    [-1.0, 1.0, 1.0],
                    [0.0, -1.0, -1.0],
                    [1.0, 0.0, -1.0],
                    [0.0, 1.0, -1.0],
                    [-1.0, 0.0, -1.0],
                    [0.0, -1.0, 1.0],
                    [1.0, 0.0, 1.0],
                    [0.0, 1.0, 1.0],
                    [-1.0, 0.0, 1.0],
                    [-1.0, -1.0, 0.0],
                    [1.0, -1.0, 0.0],
                    [1.0, 1.0, 0.0],
                    [-1.0, 1.0, 0.0],
                ],
            ),
            (
                CellKind::Hex27,
                &[
                    [-1.0, -1.0, -1.0],
                    [1.0, -1.0, -1.0],
                    [1.0, 1.0, -1.0],
                    [-1.0, 1.0, -1.0],
                    [-1.0, -1.0, 1.0],
                    [1.0, -1.0, 1.0],
                    [1.0, 1.0, 1.0],
                    [-1.0, 1.0, 1.0],
                    [0.0, -1.0, -1.0],
                    [1.0, 0.0, -1.0],
                    [0.0, 1.0, -1.0],
                    [-1.0, 0.0, -1.0],
                    [0.0, -1.0, 1.0],
                    [1.0, 0.0, 1.0],
                    [0.0, 1.0, 1.0],
                    [-1.0, 0.0, 1.0],
                    [-1.0, -1.0, 0.0],
                    [1.0, -1.0, 0.0],
                    [1.0, 1.0, 0.0],
                    [-1.0, 1.0, 0.0],
                    [-1.0, 0.0, 0.0],
                    [1.0, 0.0, 0.0],
                    [0.0, -1.0, 0.0],
                    [0.0, 1.0, 0.0],
                    [0.0, 0.0, -1.0],
                    [0.0, 0.0, 1.0],
                    [0.0, 0.0, 0.0],
                ],
            ),
        ];
        for (kind, nodes) in vtk {
            assert_eq!(kind.element().reference_nodes(), nodes, "{kind:?}");
        }
    }

    /// The registry reads back: each kind's VTK and Gmsh codes name it.
    #[test]
    fn codes_name_their_kind() {
        for &kind in CellKind::ALL {
            let e = kind.element();
            assert_eq!(CellKind::from_vtk(e.vtk_type()), Some(kind));
            assert_eq!(CellKind::from_gmsh(e.gmsh_type()), Some(kind));
        }
        // a wedge is no kind of ours
        assert_eq!(CellKind::from_vtk(13), None);
        assert_eq!(CellKind::from_gmsh(6), None);
    }
}
