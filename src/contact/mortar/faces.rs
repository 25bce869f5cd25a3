//! 3-D mortar integrals: slave faces (tri3, quad4, tri6, quad9) against master faces
//! (those and quad8), clipped in the slave face's reference plane (the module doc of
//! [`super`]).
//!
//! **Segments.** A master face's corners are projected onto the slave face (its
//! closest points, in the slave's reference coordinates `ξ`), and that polygon is
//! clipped (Sutherland–Hodgman) against each piece of the slave face on which the
//! multiplier basis is polynomial: the whole face for tri3 and quad4, its four
//! quadrants for quad9, its four sub-triangles for tri6. Each clipped polygon is a fan of
//! triangles integrated by a collapsed 4 × 4 Gauss rule (exact to total degree 6:
//! `Φ_a N_b` on quad9, degree 2 + 4). Exact where the maps are affine — flat triangles
//! and parallelograms, as generated boxes and their interfaces have —; on a distorted or
//! curved face the master polygon's edges are straight in `ξ` only to first order, as in
//! every segment-based mortar code.
//!
//! Every slave face is clipped against every master face whose box lies within the two
//! faces' sizes and whose outward normal faces it: `O(slave × master)` faces, set up once
//! (small sliding).

use super::Rows;
use crate::model::element::{CellKind, MAX_NODES, face_kind};

/// 4-point Gauss abscissae and weights on `[0, 1]`.
const G4: [(f64, f64); 4] = [
    (0.069_431_844_202_973_7, 0.173_927_422_568_726_9),
    (0.330_009_478_207_571_9, 0.326_072_577_431_273_1),
    (0.669_990_521_792_428_1, 0.326_072_577_431_273_1),
    (0.930_568_155_797_026_3, 0.173_927_422_568_726_9),
];

/// A face of `k` nodes as the element kind whose shape functions it has (the callers'
/// facets are the boundary facets of 3-D cells).
fn kind(k: usize) -> CellKind {
    face_kind(k).expect("a 3-D boundary facet")
}

/// A face at `xi`: shape values, position and the two tangents `x_ξ`, `x_η`.
struct At {
    n: [f64; MAX_NODES],
    x: [f64; 3],
    t: [[f64; 3]; 2],
}

fn at(f: &[usize], points: &[[f64; 3]], xi: [f64; 2]) -> At {
    let e = kind(f.len()).element();
    let mut n = [0.0; MAX_NODES];
    let mut g = [[0.0; 3]; MAX_NODES];
    e.shape([xi[0], xi[1], 0.0], &mut n);
    e.gradients([xi[0], xi[1], 0.0], &mut g);
    let mut x = [0.0; 3];
    let mut t = [[0.0; 3]; 2];
    for (b, &v) in f.iter().enumerate() {
        for i in 0..3 {
            x[i] += n[b] * points[v][i];
            t[0][i] += g[b][0] * points[v][i];
            t[1][i] += g[b][1] * points[v][i];
        }
    }
    At { n, x, t }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| a[i] - b[i])
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Solves the 2 × 2 system `[a b; c d] x = r`.
fn solve2([a, b, c, d]: [f64; 4], r: [f64; 2]) -> [f64; 2] {
    let det = a * d - b * c;
    [(d * r[0] - b * r[1]) / det, (a * r[1] - c * r[0]) / det]
}

/// The reference coordinates of the point of face `f` closest to `p` (Gauss–Newton from
/// the face's centre; not clamped).
fn closest(f: &[usize], points: &[[f64; 3]], p: [f64; 3]) -> [f64; 2] {
    let c = kind(f.len()).element().centre();
    let mut xi = [c[0], c[1]];
    for _ in 0..30 {
        let a = at(f, points, xi);
        let r = sub(p, a.x);
        let step = solve2(
            [
                dot(a.t[0], a.t[0]),
                dot(a.t[0], a.t[1]),
                dot(a.t[1], a.t[0]),
                dot(a.t[1], a.t[1]),
            ],
            [dot(a.t[0], r), dot(a.t[1], r)],
        );
        xi = [xi[0] + step[0], xi[1] + step[1]];
        if step[0].abs() + step[1].abs() < 1e-14 {
            break;
        }
    }
    xi
}

/// Where the line through `p` along `n` meets face `f`: its reference coordinates
/// (Newton on `x(η) − p − s n = 0`; not clamped).
fn along(f: &[usize], points: &[[f64; 3]], p: [f64; 3], n: [f64; 3]) -> [f64; 2] {
    let c = kind(f.len()).element().centre();
    let mut eta = [c[0], c[1]];
    for _ in 0..30 {
        let a = at(f, points, eta);
        let r = sub(p, a.x);
        let (u, w) = (a.t[0], a.t[1]);
        // project onto the plane normal to n: (I − n nᵀ)(x(η) − p) = 0, least squares
        let pu = sub(u, n.map(|ni| ni * dot(u, n)));
        let pw = sub(w, n.map(|ni| ni * dot(w, n)));
        let pr = sub(r, n.map(|ni| ni * dot(r, n)));
        let step = solve2(
            [dot(pu, pu), dot(pu, pw), dot(pw, pu), dot(pw, pw)],
            [dot(pu, pr), dot(pw, pr)],
        );
        eta = [eta[0] + step[0], eta[1] + step[1]];
        if step[0].abs() + step[1].abs() < 1e-14 {
            break;
        }
    }
    eta
}

/// Whether reference point `eta` lies on a face of `k` nodes (within `tol`).
fn inside(k: usize, eta: [f64; 2], tol: f64) -> bool {
    if k == 3 || k == 6 {
        eta[0] >= -tol && eta[1] >= -tol && eta[0] + eta[1] <= 1.0 + tol
    } else {
        eta[0].abs() <= 1.0 + tol && eta[1].abs() <= 1.0 + tol
    }
}

/// The pieces of a slave face of `k` nodes on which its multiplier basis is a
/// polynomial, counter-clockwise in its reference plane.
fn pieces(k: usize) -> Vec<Vec<[f64; 2]>> {
    match k {
        3 => vec![vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]],
        6 => vec![
            vec![[0.0, 0.0], [0.5, 0.0], [0.0, 0.5]],
            vec![[0.5, 0.0], [1.0, 0.0], [0.5, 0.5]],
            vec![[0.0, 0.5], [0.5, 0.5], [0.0, 1.0]],
            vec![[0.5, 0.0], [0.5, 0.5], [0.0, 0.5]],
        ],
        4 => vec![vec![[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]],
        // quad8: the four corner triangles cut off by the mid-side nodes, and the diamond
        // between the mid-side nodes
        8 => vec![
            vec![[-1.0, -1.0], [0.0, -1.0], [-1.0, 0.0]],
            vec![[1.0, -1.0], [1.0, 0.0], [0.0, -1.0]],
            vec![[1.0, 1.0], [0.0, 1.0], [1.0, 0.0]],
            vec![[-1.0, 1.0], [-1.0, 0.0], [0.0, 1.0]],
            vec![[0.0, -1.0], [1.0, 0.0], [0.0, 1.0], [-1.0, 0.0]],
        ],
        _ => [[-1.0, -1.0], [0.0, -1.0], [-1.0, 0.0], [0.0, 0.0]]
            .iter()
            .map(|&[a, b]| vec![[a, b], [a + 1.0, b], [a + 1.0, b + 1.0], [a, b + 1.0]])
            .collect(),
    }
}

/// The multiplier basis `Φ_a` of a slave face of `k` nodes at `xi`: its shape functions
/// on tri3 and quad4; the hat functions of its split at the mid-side nodes on tri6
/// (`max(0, 2L_i − 1)` at corner `i`, `max(0, min(2L_i, 2L_j, 1 − 2L_k))` at the middle
/// of edge `ij`), quad9 (products of the 1-D hats at −1, 0, 1) and quad8 (the hats of its
/// corner triangles and of the bilinear diamond between its mid-side nodes); never
/// negative, and they sum to one.
fn basis(k: usize, xi: [f64; 2], n: &[f64; MAX_NODES]) -> [f64; MAX_NODES] {
    let mut phi = [0.0; MAX_NODES];
    match k {
        6 => {
            let l = [1.0 - xi[0] - xi[1], xi[0], xi[1]];
            for i in 0..3 {
                phi[i] = (2.0 * l[i] - 1.0).max(0.0);
                let (j, m) = ((i + 1) % 3, (i + 2) % 3);
                // node 3 + i is the middle of edge (i, i + 1)
                phi[3 + i] = (2.0 * l[i]).min(2.0 * l[j]).min(1.0 - 2.0 * l[m]).max(0.0);
            }
        }
        8 => {
            // corners 0–3 at (∓1, ∓1), mid-side node 4 + i between corners i and i + 1
            if xi[0].abs() + xi[1].abs() <= 1.0 {
                // the diamond: bilinear in (a, b), its corners the mid-side nodes
                // (clamped: a point on the diamond's edge rounds either way)
                let a = (0.5 * (1.0 + xi[0] - xi[1])).clamp(0.0, 1.0);
                let b = (0.5 * (1.0 + xi[0] + xi[1])).clamp(0.0, 1.0);
                phi[4] = a * (1.0 - b);
                phi[5] = a * b;
                phi[6] = (1.0 - a) * b;
                phi[7] = (1.0 - a) * (1.0 - b);
            } else {
                // a corner triangle: the corner's hat and its two mid-side nodes'
                let c = match (xi[0] < 0.0, xi[1] < 0.0) {
                    (true, true) => 0,
                    (false, true) => 1,
                    (false, false) => 2,
                    (true, false) => 3,
                };
                let (sx, sy) = (
                    if c == 1 || c == 2 { 1.0 } else { -1.0 },
                    if c >= 2 { 1.0 } else { -1.0 },
                );
                let (dx, dy) = (1.0 - sx * xi[0], 1.0 - sy * xi[1]);
                phi[c] = (1.0 - dx - dy).max(0.0);
                // the mid-side node at (0, sy) lies along x from the corner, (sx, 0) along y
                let along_x = if sy < 0.0 { 4 } else { 6 };
                let along_y = if sx > 0.0 { 5 } else { 7 };
                phi[along_x] = dx;
                phi[along_y] = dy;
            }
        }
        9 => {
            let e = CellKind::Quad9.element();
            let hat = |c: f64, x: f64| (1.0 - (x - c).abs()).max(0.0);
            for (a, r) in e.reference_nodes().iter().enumerate() {
                phi[a] = hat(r[0], xi[0]) * hat(r[1], xi[1]);
            }
        }
        _ => phi[..k].copy_from_slice(&n[..k]),
    }
    phi
}

/// Clips polygon `p` (counter-clockwise) by the convex counter-clockwise polygon `c`.
fn clip(mut p: Vec<[f64; 2]>, c: &[[f64; 2]]) -> Vec<[f64; 2]> {
    for (i, &a) in c.iter().enumerate() {
        let b = c[(i + 1) % c.len()];
        let side = |q: [f64; 2]| (b[0] - a[0]) * (q[1] - a[1]) - (b[1] - a[1]) * (q[0] - a[0]);
        let mut out = Vec::with_capacity(p.len() + 2);
        for (j, &q) in p.iter().enumerate() {
            let r = p[(j + 1) % p.len()];
            let (sq, sr) = (side(q), side(r));
            if sq >= 0.0 {
                out.push(q);
            }
            if (sq >= 0.0) != (sr >= 0.0) {
                let t = sq / (sq - sr);
                out.push([q[0] + t * (r[0] - q[0]), q[1] + t * (r[1] - q[1])]);
            }
        }
        p = out;
        if p.len() < 3 {
            return Vec::new();
        }
    }
    p
}

fn signed_area(p: &[[f64; 2]]) -> f64 {
    (0..p.len())
        .map(|i| {
            let (a, b) = (p[i], p[(i + 1) % p.len()]);
            a[0] * b[1] - a[1] * b[0]
        })
        .sum::<f64>()
        * 0.5
}

/// A face's box, grown by its largest extent.
fn reach(f: &[usize], points: &[[f64; 3]]) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for &v in f {
        for i in 0..3 {
            lo[i] = lo[i].min(points[v][i]);
            hi[i] = hi[i].max(points[v][i]);
        }
    }
    let size = (0..3).map(|i| hi[i] - lo[i]).fold(0.0f64, f64::max);
    (lo.map(|x| x - size), hi.map(|x| x + size))
}

/// Adds each face node's multiplier weights `∫ Φ_a N_b dΓ` over `facets` (no master:
/// the rows of a rigid plane, whose gap is affine in the face's position) to `acc`.
pub(super) fn face_weights(acc: &mut Rows, facets: &[Vec<usize>], points: &[[f64; 3]]) {
    for f in facets {
        let k = f.len();
        for piece in pieces(k) {
            for (xi, w) in fan_points(&piece) {
                let p = at(f, points, xi);
                let normal = cross(p.t[0], p.t[1]);
                let len = dot(normal, normal).sqrt();
                let phi = basis(k, xi, &p.n);
                acc.add(
                    w * len,
                    (f, &phi[..k], &p.n[..k]),
                    (&[], &[]),
                    [0.0; 3],
                    0.0,
                );
            }
        }
    }
}

/// Adds the mortar integrals of the slave faces against the master faces to `acc`.
pub(super) fn face_rows(
    acc: &mut Rows,
    (slave, slave_points): (&[Vec<usize>], &[[f64; 3]]),
    (master, master_points): (&[Vec<usize>], &[[f64; 3]]),
) {
    let boxes: Vec<_> = master.iter().map(|f| reach(f, master_points)).collect();
    for fs in slave {
        let (k, (lo, hi)) = (fs.len(), reach(fs, slave_points));
        let centre = kind(k).element().centre();
        let c = at(fs, slave_points, [centre[0], centre[1]]);
        let out = cross(c.t[0], c.t[1]);
        for (fm, (mlo, mhi)) in master.iter().zip(&boxes) {
            if (0..3).any(|i| mhi[i] < lo[i] || mlo[i] > hi[i]) {
                continue;
            }
            let mc = kind(fm.len()).element().centre();
            let m = at(fm, master_points, [mc[0], mc[1]]);
            if dot(out, cross(m.t[0], m.t[1])) >= 0.0 {
                continue;
            }
            // the master's corners in the slave's reference plane, counter-clockwise
            let corners = crate::model::element::facet_corners(3, fm.len()).unwrap_or(4);
            let mut poly: Vec<[f64; 2]> = fm[..corners]
                .iter()
                .map(|&v| closest(fs, slave_points, master_points[v]))
                .collect();
            if signed_area(&poly) < 0.0 {
                poly.reverse();
            }
            for piece in pieces(k) {
                let cut = clip(poly.clone(), &piece);
                for (xi, w) in fan_points(&cut) {
                    let sp = at(fs, slave_points, xi);
                    let normal = cross(sp.t[0], sp.t[1]);
                    let len = dot(normal, normal).sqrt();
                    let n = normal.map(|x| -x / len);
                    let eta = along(fm, master_points, sp.x, n);
                    if !inside(fm.len(), eta, 1e-9) {
                        continue;
                    }
                    let mp = at(fm, master_points, eta);
                    let gap = dot(sub(sp.x, mp.x), n);
                    let phi = basis(k, xi, &sp.n);
                    acc.add(
                        w * len,
                        (fs, &phi[..k], &sp.n[..k]),
                        (fm, &mp.n[..fm.len()]),
                        n,
                        gap,
                    );
                }
            }
        }
    }
}

/// The integration points of a convex polygon of the reference plane (a fan of
/// triangles from its first corner, each with the collapsed 4 × 4 Gauss rule, exact to
/// total degree 6): reference point and weight.
fn fan_points(poly: &[[f64; 2]]) -> impl Iterator<Item = ([f64; 2], f64)> + '_ {
    (1..poly.len().saturating_sub(1)).flat_map(move |i| {
        let (a, b, d) = (poly[0], poly[i], poly[i + 1]);
        let area2 = (b[0] - a[0]) * (d[1] - a[1]) - (b[1] - a[1]) * (d[0] - a[0]);
        // a degenerate sliver of the clipping carries nothing
        let area2 = area2.max(0.0);
        G4.iter().flat_map(move |&(u, wu)| {
            G4.iter().map(move |&(v, wv)| {
                let (s, t) = (u, (1.0 - u) * v);
                let xi = [
                    a[0] + s * (b[0] - a[0]) + t * (d[0] - a[0]),
                    a[1] + s * (b[1] - a[1]) + t * (d[1] - a[1]),
                ];
                (xi, wu * wv * (1.0 - u) * area2)
            })
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The multiplier bases of tri6, quad8 and quad9 are never negative and sum to one
    /// at every point of a fine grid of the reference face, and each node's is 1 at the
    /// node (tri6 and quad9: the hats; quad8: corner triangles and the diamond).
    #[test]
    fn multiplier_bases_are_nonnegative_partitions_of_unity() {
        for (k, kind) in [
            (6, CellKind::Tri6),
            (8, CellKind::Quad8),
            (9, CellKind::Quad9),
        ] {
            let e = kind.element();
            let n = [0.0; MAX_NODES];
            for i in 0..=40 {
                for j in 0..=40 {
                    let (a, b) = (i as f64 / 40.0, j as f64 / 40.0);
                    let xi = if k == 6 {
                        if a + b > 1.0 {
                            continue;
                        }
                        [a, b]
                    } else {
                        [2.0 * a - 1.0, 2.0 * b - 1.0]
                    };
                    let phi = basis(k, xi, &n);
                    let s: f64 = phi[..k].iter().sum();
                    assert!((s - 1.0).abs() < 1e-14, "{k} nodes at {xi:?}: {s}");
                    assert!(
                        phi[..k].iter().all(|&p| p >= 0.0),
                        "{k} nodes at {xi:?}: {:?}",
                        &phi[..k]
                    );
                }
            }
            for (a, r) in e.reference_nodes().iter().enumerate() {
                let phi = basis(k, [r[0], r[1]], &n);
                assert!((phi[a] - 1.0).abs() < 1e-14, "{k} nodes, node {a}: {phi:?}");
            }
        }
    }
}
