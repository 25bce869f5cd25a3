//! Integration points of the four linear cells: shape functions, their reference
//! gradients and weights (2×2 (×2) Gauss points on quadrilaterals and hexahedra, the
//! constant-strain point and the interior points of triangles and tetrahedra).

pub(super) const G2: [f64; 2] = [-0.577_350_269_189_625_8, 0.577_350_269_189_625_8];

/// One integration point: shape values, reference gradients, weight.
pub(in crate::model) type Point<const NN: usize, const D: usize> = ([f64; NN], [[f64; D]; NN], f64);

/// Quadrature of the triangle: constant gradients; the 3 edge-midpoint rule (degree 2)
/// integrates the consistent mass exactly.
pub(in crate::model) fn tri3_points() -> [Point<3, 2>; 3] {
    let g = [[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]];
    [[0.5, 0.0], [0.5, 0.5], [0.0, 0.5]].map(|[r, s]| ([1.0 - r - s, r, s], g, 1.0 / 6.0))
}

/// Three interior points of the triangle (degree 2, at `(1/6, 1/6)` and permutations):
/// the axisymmetric kernel needs `r > 0` at every point, which the edge-midpoint rule
/// of [`tri3_points`] misses on a cell with an edge on the axis.
pub(super) fn tri3_interior_points() -> [Point<3, 2>; 3] {
    let g = [[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]];
    let (a, b) = (1.0 / 6.0, 2.0 / 3.0);
    [[a, a], [b, a], [a, b]].map(|[r, s]| ([1.0 - r - s, r, s], g, 1.0 / 6.0))
}

/// 2×2 Gauss points of the bilinear quadrilateral.
pub(in crate::model) fn quad4_points() -> [Point<4, 2>; 4] {
    std::array::from_fn(|p| {
        let (r, s) = (G2[p / 2], G2[p % 2]);
        (
            [
                0.25 * (1.0 - r) * (1.0 - s),
                0.25 * (1.0 + r) * (1.0 - s),
                0.25 * (1.0 + r) * (1.0 + s),
                0.25 * (1.0 - r) * (1.0 + s),
            ],
            [
                [-0.25 * (1.0 - s), -0.25 * (1.0 - r)],
                [0.25 * (1.0 - s), -0.25 * (1.0 + r)],
                [0.25 * (1.0 + s), 0.25 * (1.0 + r)],
                [-0.25 * (1.0 + s), 0.25 * (1.0 - r)],
            ],
            1.0,
        )
    })
}

/// The tetrahedron's 4-point rule of degree 2 (exact for the consistent mass).
pub(in crate::model) fn tet4_points() -> [Point<4, 3>; 4] {
    let g = [
        [-1.0, -1.0, -1.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    let (a, b) = (0.585_410_196_624_968_5, 0.138_196_601_125_010_5);
    [[b, b, b], [a, b, b], [b, a, b], [b, b, a]]
        .map(|[r, s, u]| ([1.0 - r - s - u, r, s, u], g, 1.0 / 24.0))
}

/// Reference coordinates (±1) of the bilinear quadrilateral's corners (VTK / Gmsh node
/// order).
pub const QUAD4_CORNERS: [[f64; 2]; 4] = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];

/// Reference coordinates (±1) of the trilinear hexahedron's corners (VTK / Gmsh node
/// order).
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

/// 2×2×2 Gauss points of the trilinear hexahedron (VTK / Gmsh node order).
pub(in crate::model) fn hex8_points() -> [Point<8, 3>; 8] {
    const SGN: [[f64; 3]; 8] = HEX8_CORNERS;
    std::array::from_fn(|p| {
        let (r, s, u) = (G2[p / 4], G2[(p / 2) % 2], G2[p % 2]);
        (
            SGN.map(|c| 0.125 * (1.0 + c[0] * r) * (1.0 + c[1] * s) * (1.0 + c[2] * u)),
            SGN.map(|c| {
                [
                    0.125 * c[0] * (1.0 + c[1] * s) * (1.0 + c[2] * u),
                    0.125 * c[1] * (1.0 + c[0] * r) * (1.0 + c[2] * u),
                    0.125 * c[2] * (1.0 + c[0] * r) * (1.0 + c[1] * s),
                ]
            }),
            1.0,
        )
    })
}
