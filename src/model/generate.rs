//! Built-in structured meshes: boxes of hex8, tet4, hex20, hex27 or tet10 cells,
//! rectangles of quad4, tri3, quad8, quad9 or tri6 cells, with the six (four) boundary faces as named node sets `x0, x1, y0, y1,
//! z0, z1`.

use super::solid::{CellKind, Mesh};

/// A `lx × ly × lz` box from the origin, `nx × ny × nz` hexahedra, each split into six
/// tetrahedra (Kuhn triangulation, conforming) when `kind` is [`CellKind::Tet4`] or
/// [`CellKind::Tet10`]. Quadratic kinds take their mid-edge (and hex27's face and
/// centre) nodes on the grid of half the spacing; a hex20 mesh has no node at the
/// cells' face centres and centres.
pub fn box_mesh(kind: CellKind, n: [usize; 3], l: [f64; 3]) -> Mesh {
    let s = kind.element().order();
    let [nx, ny, nz] = n;
    let [gx, gy, gz] = [s * nx, s * ny, s * nz];
    // hex20 leaves out the grid nodes with two or three odd coordinates
    let unused =
        |i: usize, j: usize, k: usize| kind == CellKind::Hex20 && (i % 2 + j % 2 + k % 2) >= 2;
    let mut index = vec![usize::MAX; (gx + 1) * (gy + 1) * (gz + 1)];
    let mut mesh = Mesh::default();
    for k in 0..=gz {
        for j in 0..=gy {
            for i in 0..=gx {
                if unused(i, j, k) {
                    continue;
                }
                index[(k * (gy + 1) + j) * (gx + 1) + i] = mesh.points.len();
                mesh.points.push([
                    l[0] * i as f64 / gx as f64,
                    l[1] * j as f64 / gy as f64,
                    l[2] * k as f64 / gz as f64,
                ]);
            }
        }
    }
    let id = |i: usize, j: usize, k: usize| index[(k * (gy + 1) + j) * (gx + 1) + i];
    // the hexahedron's corners on its own grid (offsets 0 or s)
    const CORNER: [[usize; 3]; 8] = [
        [0, 0, 0],
        [1, 0, 0],
        [1, 1, 0],
        [0, 1, 0],
        [0, 0, 1],
        [1, 0, 1],
        [1, 1, 1],
        [0, 1, 1],
    ];
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                // node at offsets o (each in 0..=s) of this cell's grid
                let at = |o: [usize; 3]| id(s * i + o[0], s * j + o[1], s * k + o[2]);
                let h: [usize; 8] = std::array::from_fn(|a| at(CORNER[a].map(|c| c * s)));
                match kind {
                    CellKind::Tet4 | CellKind::Tet10 => {
                        for t in [
                            [0, 1, 2, 6],
                            [0, 2, 3, 6],
                            [0, 3, 7, 6],
                            [0, 7, 4, 6],
                            [0, 4, 5, 6],
                            [0, 5, 1, 6],
                        ] {
                            let mut t = t;
                            let c: Vec<usize> = t.iter().map(|&a| h[a]).collect();
                            if signed_volume(&mesh.points, &c) < 0.0 {
                                t.swap(2, 3);
                            }
                            let mut c: Vec<usize> = t.iter().map(|&a| h[a]).collect();
                            if kind == CellKind::Tet10 {
                                // mid-edge nodes: the midpoints of the corners' offsets
                                for [a, b] in [[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]] {
                                    let (p, q) = (CORNER[t[a]], CORNER[t[b]]);
                                    c.push(at(std::array::from_fn(|x| p[x] + q[x])));
                                }
                            }
                            mesh.cells.push((kind, c));
                        }
                    }
                    CellKind::Hex20 | CellKind::Hex27 => {
                        let e = kind.element();
                        let c = e
                            .reference_nodes()
                            .iter()
                            .map(|x| at(x.map(|v| (v + 1.0) as usize)))
                            .collect();
                        mesh.cells.push((kind, c));
                    }
                    _ => mesh.cells.push((CellKind::Hex8, h.to_vec())),
                }
            }
        }
    }
    let faces: [(&str, usize, usize); 6] = [
        ("x0", 0, 0),
        ("x1", 0, gx),
        ("y0", 1, 0),
        ("y1", 1, gy),
        ("z0", 2, 0),
        ("z1", 2, gz),
    ];
    for (name, axis, at) in faces {
        let mut set = Vec::new();
        for k in 0..=gz {
            for j in 0..=gy {
                for i in 0..=gx {
                    if [i, j, k][axis] == at && !unused(i, j, k) {
                        set.push(id(i, j, k));
                    }
                }
            }
        }
        mesh.node_sets.insert(name.to_string(), set);
    }
    mesh
}

/// A `lx × ly` rectangle, `nx × ny` quadrilaterals, each split into two triangles when
/// `kind` is [`CellKind::Tri3`] or [`CellKind::Tri6`] (along the diagonal from the
/// lower left corner). Quadratic kinds take their mid-side (and quad9's centre) nodes on
/// the grid of half the spacing; a quad8 mesh has no node at the cells' centres.
pub fn rectangle_mesh(kind: CellKind, n: [usize; 2], l: [f64; 2]) -> Mesh {
    let s = kind.element().order();
    let [nx, ny] = n;
    let [gx, gy] = [s * nx, s * ny];
    // quad8 leaves the cells' centres out: no node may be left without mass
    let unused = |i: usize, j: usize| kind == CellKind::Quad8 && i % 2 == 1 && j % 2 == 1;
    let mut index = vec![usize::MAX; (gx + 1) * (gy + 1)];
    let mut mesh = Mesh::default();
    for j in 0..=gy {
        for i in 0..=gx {
            if unused(i, j) {
                continue;
            }
            index[j * (gx + 1) + i] = mesh.points.len();
            mesh.points.push([
                l[0] * i as f64 / gx as f64,
                l[1] * j as f64 / gy as f64,
                0.0,
            ]);
        }
    }
    let id = |i: usize, j: usize| index[j * (gx + 1) + i];
    for j in 0..ny {
        for i in 0..nx {
            // node (a, b) of the cell's own grid (a, b in 0..=s)
            let f = |a: usize, b: usize| id(s * i + a, s * j + b);
            let q = [f(0, 0), f(s, 0), f(s, s), f(0, s)];
            match kind {
                CellKind::Tri3 => {
                    mesh.cells.push((CellKind::Tri3, vec![q[0], q[1], q[2]]));
                    mesh.cells.push((CellKind::Tri3, vec![q[0], q[2], q[3]]));
                }
                CellKind::Tri6 => {
                    let c = f(1, 1);
                    mesh.cells
                        .push((kind, vec![q[0], q[1], q[2], f(1, 0), f(2, 1), c]));
                    mesh.cells
                        .push((kind, vec![q[0], q[2], q[3], c, f(1, 2), f(0, 1)]));
                }
                CellKind::Quad8 | CellKind::Quad9 => {
                    let mut c = q.to_vec();
                    c.extend([f(1, 0), f(2, 1), f(1, 2), f(0, 1)]);
                    if kind == CellKind::Quad9 {
                        c.push(f(1, 1));
                    }
                    mesh.cells.push((kind, c));
                }
                _ => mesh.cells.push((CellKind::Quad4, q.to_vec())),
            }
        }
    }
    let faces: [(&str, usize, usize); 4] =
        [("x0", 0, 0), ("x1", 0, gx), ("y0", 1, 0), ("y1", 1, gy)];
    for (name, axis, at) in faces {
        let set = (0..=gy)
            .flat_map(|j| (0..=gx).map(move |i| (i, j)))
            .filter(|&(i, j)| [i, j][axis] == at && !unused(i, j))
            .map(|(i, j)| id(i, j))
            .collect();
        mesh.node_sets.insert(name.to_string(), set);
    }
    mesh
}

fn signed_volume(p: &[[f64; 3]], c: &[usize]) -> f64 {
    let d = |a: usize| {
        [
            p[c[a]][0] - p[c[0]][0],
            p[c[a]][1] - p[c[0]][1],
            p[c[a]][2] - p[c[0]][2],
        ]
    };
    let (a, b, e) = (d(1), d(2), d(3));
    a[0] * (b[1] * e[2] - b[2] * e[1]) - a[1] * (b[0] * e[2] - b[2] * e[0])
        + a[2] * (b[0] * e[1] - b[1] * e[0])
}
