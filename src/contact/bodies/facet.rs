//! A target facet's geometry: its nodes and outward normal, the closest point of a
//! triangle or a bilinear quadrilateral to a node, and the 3-vector helpers they use.

/// A boundary facet of the master body: its nodes (indices into the master nodes) in
/// the order that makes its normal point out of the body.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Facet {
    pub(super) nodes: [u32; 4],
    pub(super) len: u8,
    /// Outward normal of a 1-D point facet (±1); unused otherwise.
    pub(super) sign: f64,
}

impl Facet {
    /// A facet of 1 (1-D: a rod's end, outward along `sign`), 2 (a segment), 3 or 4
    /// nodes (a triangle or a bilinear quadrilateral, counter-clockwise seen from
    /// outside).
    pub fn new(nodes: &[usize], sign: f64) -> Self {
        let mut n = [0u32; 4];
        for (a, &b) in n.iter_mut().zip(nodes) {
            *a = b as u32;
        }
        Facet {
            nodes: n,
            // more than 4 nodes is kept as a count that `NodesOnSurface::new` refuses
            len: nodes.len().min(255) as u8,
            sign,
        }
    }

    /// Its nodes (the first four of a facet given more, which sets refuse).
    pub fn nodes(&self) -> impl Iterator<Item = usize> + '_ {
        self.nodes[..(self.len as usize).min(4)]
            .iter()
            .map(|&a| a as usize)
    }
}

/// One side of an interface: node dofs (`None` where fixed) and reference positions.
#[derive(Clone, Debug, Default)]
pub struct Side {
    /// Dofs of each node, one per space dimension (`None`: held fixed).
    pub dofs: Vec<[Option<usize>; 3]>,
    /// Reference coordinates (`x = X + u`); z = 0 in 2-D.
    pub reference: Vec<[f64; 3]>,
}

impl Side {
    /// Displacement of node `k` at `q` (0 on fixed components).
    pub(super) fn displacement(&self, k: usize, q: &[f64], dim: usize) -> [f64; 3] {
        let mut u = [0.0; 3];
        for (i, ui) in u.iter_mut().enumerate().take(dim) {
            if let Some(d) = self.dofs[k][i] {
                *ui = q[d];
            }
        }
        u
    }

    /// Position of node `k` at `q`.
    pub(super) fn position(&self, k: usize, q: &[f64], dim: usize) -> [f64; 3] {
        let u = self.displacement(k, q, dim);
        let x = self.reference[k];
        [x[0] + u[0], x[1] + u[1], x[2] + u[2]]
    }

    /// The closest point to `x` of facet `f` over this side's nodes at `q`.
    pub(super) fn project(&self, dim: usize, f: &Facet, x: &[f64; 3], q: &[f64]) -> Projection {
        let mut p = [[0.0; 3]; 4];
        for (k, node) in f.nodes().enumerate() {
            p[k] = self.position(node, q, dim);
        }
        let finish = |y: [f64; 3], normal: [f64; 3], weights: [f64; 4]| {
            let d = sub(x, &y);
            Projection {
                dist: norm(&d),
                gap: dot(&normal, &d),
                normal,
                weights,
            }
        };
        match f.len {
            1 => finish(p[0], [f.sign, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]),
            2 => {
                let t = sub(&p[1], &p[0]);
                let l2 = dot(&t, &t);
                let xi = (dot(&sub(x, &p[0]), &t) / l2).clamp(0.0, 1.0);
                let y = axpy(&p[0], xi, &t);
                let l = l2.sqrt();
                // counter-clockwise boundary of the body: the outward normal is t turned
                // by −90°
                let n = [t[1] / l, -t[0] / l, 0.0];
                finish(y, n, [1.0 - xi, xi, 0.0, 0.0])
            }
            3 => {
                let (e1, e2) = (sub(&p[1], &p[0]), sub(&p[2], &p[0]));
                let n = unit(&cross(&e1, &e2));
                let (b1, b2) = closest_on_triangle(x, &p[0], &e1, &e2);
                let y = axpy(&axpy(&p[0], b1, &e1), b2, &e2);
                finish(y, n, [1.0 - b1 - b2, b1, b2, 0.0])
            }
            _ => {
                let (xi, eta) = closest_on_quad(x, &p);
                let (w, dxi, deta) = bilinear(xi, eta);
                let mut y = [0.0; 3];
                let (mut a, mut b) = ([0.0; 3], [0.0; 3]);
                for k in 0..4 {
                    for j in 0..3 {
                        y[j] += w[k] * p[k][j];
                        a[j] += dxi[k] * p[k][j];
                        b[j] += deta[k] * p[k][j];
                    }
                }
                finish(y, unit(&cross(&a, &b)), w)
            }
        }
    }
}

/// The closest point of a facet to a slave node.
#[derive(Clone, Copy, Debug)]
pub(super) struct Projection {
    /// Distance from the node to the closest point.
    pub(super) dist: f64,
    /// Signed normal gap.
    pub(super) gap: f64,
    pub(super) normal: [f64; 3],
    /// Shape function values at the closest point.
    pub(super) weights: [f64; 4],
}

impl Projection {
    /// Whether the node lies behind the facet's interior (`x − x*` along the normal,
    /// pointing inward): inside the master body, where a clamped closest point (beside
    /// the surface) says nothing of the side.
    pub(super) fn inside(&self) -> bool {
        self.gap < 0.0 && -self.gap >= (1.0 - 1e-9) * self.dist
    }
}

/// Barycentric coordinates `(b1, b2)` of the point of the triangle `p0 + b1 e1 + b2 e2`
/// closest to `x`.
pub(super) fn closest_on_triangle(
    x: &[f64; 3],
    p0: &[f64; 3],
    e1: &[f64; 3],
    e2: &[f64; 3],
) -> (f64, f64) {
    let d = sub(x, p0);
    let (a11, a12, a22) = (dot(e1, e1), dot(e1, e2), dot(e2, e2));
    let (r1, r2) = (dot(e1, &d), dot(e2, &d));
    let det = a11 * a22 - a12 * a12;
    let b1 = (a22 * r1 - a12 * r2) / det;
    let b2 = (a11 * r2 - a12 * r1) / det;
    if b1 >= 0.0 && b2 >= 0.0 && b1 + b2 <= 1.0 {
        return (b1, b2);
    }
    // outside: the nearest point of the three edges
    let on = |a: [f64; 3], e: [f64; 3]| {
        let t = (dot(&sub(x, &a), &e) / dot(&e, &e)).clamp(0.0, 1.0);
        let y = axpy(&a, t, &e);
        let r = sub(x, &y);
        (dot(&r, &r), t)
    };
    let p1 = axpy(p0, 1.0, e1);
    let (d0, t0) = on(*p0, *e1);
    let (d1, t1) = on(p1, sub(e2, e1));
    let (d2, t2) = on(*p0, *e2);
    if d0 <= d1 && d0 <= d2 {
        (t0, 0.0)
    } else if d1 <= d2 {
        (1.0 - t1, t1)
    } else {
        (0.0, t2)
    }
}

/// Bilinear shape functions on `[−1, 1]²` (nodes counter-clockwise from `(−1, −1)`) and
/// their derivatives.
pub(super) fn bilinear(xi: f64, eta: f64) -> ([f64; 4], [f64; 4], [f64; 4]) {
    let s = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
    let mut w = [0.0; 4];
    let mut a = [0.0; 4];
    let mut b = [0.0; 4];
    for (k, (sx, sy)) in s.into_iter().enumerate() {
        w[k] = 0.25 * (1.0 + sx * xi) * (1.0 + sy * eta);
        a[k] = 0.25 * sx * (1.0 + sy * eta);
        b[k] = 0.25 * sy * (1.0 + sx * xi);
    }
    (w, a, b)
}

/// The natural coordinates of the point of a bilinear quadrilateral closest to `x`:
/// Gauss–Newton on `|x(ξ, η) − x|²`, clamped to the square (converges in one or two
/// iterations on the nearly flat facets of a mesh; 20 at most).
pub(super) fn closest_on_quad(x: &[f64; 3], p: &[[f64; 3]; 4]) -> (f64, f64) {
    let (mut xi, mut eta) = (0.0_f64, 0.0_f64);
    for _ in 0..20 {
        let (w, a_, b_) = bilinear(xi, eta);
        let (mut r, mut a, mut b) = ([0.0; 3], [0.0; 3], [0.0; 3]);
        for k in 0..4 {
            for j in 0..3 {
                r[j] += w[k] * p[k][j];
                a[j] += a_[k] * p[k][j];
                b[j] += b_[k] * p[k][j];
            }
        }
        let r = sub(&r, x);
        let (h11, h12, h22) = (dot(&a, &a), dot(&a, &b), dot(&b, &b));
        let (g1, g2) = (dot(&a, &r), dot(&b, &r));
        let det = h11 * h22 - h12 * h12;
        if det <= 0.0 {
            break;
        }
        let dxi = -(h22 * g1 - h12 * g2) / det;
        let deta = -(h11 * g2 - h12 * g1) / det;
        let (nx, ne) = ((xi + dxi).clamp(-1.0, 1.0), (eta + deta).clamp(-1.0, 1.0));
        let change = (nx - xi).abs().max((ne - eta).abs());
        (xi, eta) = (nx, ne);
        if change < 1e-14 {
            break;
        }
    }
    (xi, eta)
}

pub(super) fn sub(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
pub(super) fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
pub(super) fn norm(a: &[f64; 3]) -> f64 {
    dot(a, a).sqrt()
}
pub(super) fn axpy(a: &[f64; 3], s: f64, b: &[f64; 3]) -> [f64; 3] {
    [a[0] + s * b[0], a[1] + s * b[1], a[2] + s * b[2]]
}
pub(super) fn cross(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
pub(super) fn unit(a: &[f64; 3]) -> [f64; 3] {
    let l = norm(a);
    [a[0] / l, a[1] / l, a[2] / l]
}
