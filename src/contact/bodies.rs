//! Contact between two deformable bodies: nodes of one body (the *slave* side) against
//! the boundary facets of another (the *master* side): points in 1-D (a rod's end),
//! segments in 2-D, triangles and quadrilaterals in 3-D. Both sides move with `q`.
//!
//! **Gap and Jacobian (eq. 1, 5, 11).** For a slave node at `x_s` and a master facet
//! `x(ξ) = Σ_i N_i(ξ) x_i` with outward unit normal `n(ξ)`, the closest point `ξ*`
//! minimizes `|x_s − x(ξ)|` over the facet (clamped to its edges) and
//! `g = n(ξ*)·(x_s − x(ξ*))`, positive when the node is outside the master body. Its
//! gradient is `n` on the slave's dofs and `−N_i(ξ*) n` on master node `i`'s: exact at
//! an interior closest point (there `x_s − x(ξ*) ∥ n`, so the variations of `ξ*` and
//! `n` do not enter to first order); at a clamped point the normal's variation is left
//! out, as the paper's semi-Newton leaves out the derivative of `G` (sec. 4.3). The
//! tangential rows of a frictional block (eq. 11) are `t_k` on the slave and `−N_i t_k`
//! on the master, so `U_α = G_αᵀ v` is the slave's velocity relative to the material
//! point of the facet under it, in the frame `(n, t₁, t₂)`. Each column has room for the
//! slave's dofs and the dofs of the largest facet; the facet, hence the dofs, change
//! as a node slides (unused entries hold a slave dof with the value 0).
//!
//! **Tangent frames that do not jump.** In 2-D `t = n` turned by +90° ([`super::frame`]).
//! In 3-D each slave node keeps the direction `t_ref` it was given at set-up (the
//! first tangent of [`super::frame::tangents`] for the normal of the facet nearest to it,
//! so the nodes of a flat interface share one frame) and
//! `t₁ = (t_ref − (t_ref·n) n)/|…|`, `t₂ = n × t₁`:
//! a function of `q` alone (so a resumed run rebuilds it exactly) that is continuous in
//! `n`, also from one facet to the next, where the global "least aligned axis" rule of
//! [`super::frame::tangents`] jumps. It falls back to that rule only if the normal turns
//! within about 6° of `t_ref` (a contact rolled by 84°).
//!
//! **Which facet (broad and narrow phase).** The candidate facets of each slave node
//! come from an R*-tree of the facets' bounding boxes (the `rstar` crate), grown by
//! twice the search distance `s`, queried with the slave's position; they are rebuilt
//! only when some node of either side has moved more than `s/2` since the last build
//! (a Verlet list). Between builds every facet within `s` of a slave is therefore among
//! its candidates. At the start of each step ([`ContactSet::update`]) each slave is
//! paired with the nearest of them at `q_k` (the lowest facet index on a tie), so the
//! pairing does not depend on when the lists were built and a resumed run pairs alike;
//! the pairing holds through the step's Newton iterations, where the closest point moves
//! on the paired facet (clamped to its edges) and the normal turns with it. Re-pairing
//! inside the Newton loop ping-pongs between the two segments at a vertex of a convex
//! master surface: the two Hertz balls of `meshes/hertz_spheres.toml` stopped at the
//! Newton cap at step 877 that way. A slave with no facet within `s` has the gap `s`
//! and a column on its own dofs along the normal of its set-up facet: it cannot close
//! within the step (the rebuild rule guarantees that no facet is nearer than `s/2`).
//! Each slave holds at most [`NodesOnSurface::capacity`] candidates; a build that
//! finds more is an error naming `search` (a smaller search distance or a coarser
//! master surface). A node that moves more than `s/2` in one step could cross a facet
//! its list missed: that is an error naming `search` too (a larger search distance or
//! a smaller step). A resumed run restarts the search from the restored `q`
//! ([`ContactSet::restart`]). `cargo bench --bench contact` times the rebuild, the
//! pairing and the evaluation on flat faces of 10⁴ and 9·10⁴ quads. Measured crates (research notes, 180 000 facets, 100 000 nodes):
//! `rstar` builds in 40 ms and answers the queries in 100–180 ms, `bvh` 75–99 and
//! 130–160 ms, `parry3d-f64` 80–110 and 90–120 ms; a rebuild is a fresh bulk load, so
//! `rstar`'s build time decides, and it brings no second linear-algebra crate.
//!
//! **Linearity.** A 1-D pair (a rod's end node against another rod's end) has a fixed
//! normal and one facet: `g` is affine in `q`, `G` constant, and the integrators factor
//! once and precompute the Delassus operator. In 2-D and 3-D the normal and the closest
//! point move with `q`, so the Newton loop re-linearizes (eq. 42–51). Self-contact (a
//! body's nodes against its own surface) is not modelled.

use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{AABB, RTree};

use super::{ContactJacobian, ContactLaw, ContactSet, check_friction, check_restitution};
use crate::error::{Error, require_positive};

/// Candidate facets kept per slave node by default (the R*-tree query's results within
/// twice the search distance: 9 to 25 quads of a uniform face with the default search,
/// about twice as many triangles; 64 leaves room for graded and distorted surfaces).
pub const DEFAULT_CAPACITY: usize = 64;

/// A slave paired with no facet.
const NO_FACET: u32 = u32::MAX;

/// A boundary facet of the master body: its nodes (indices into the master nodes) in
/// the order that makes its normal point out of the body.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Facet {
    nodes: [u32; 4],
    len: u8,
    /// Outward normal of a 1-D point facet (±1); unused otherwise.
    sign: f64,
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
    fn displacement(&self, k: usize, q: &[f64], dim: usize) -> [f64; 3] {
        let mut u = [0.0; 3];
        for (i, ui) in u.iter_mut().enumerate().take(dim) {
            if let Some(d) = self.dofs[k][i] {
                *ui = q[d];
            }
        }
        u
    }

    /// Position of node `k` at `q`.
    fn position(&self, k: usize, q: &[f64], dim: usize) -> [f64; 3] {
        let u = self.displacement(k, q, dim);
        let x = self.reference[k];
        [x[0] + u[0], x[1] + u[1], x[2] + u[2]]
    }

    /// The closest point to `x` of facet `f` over this side's nodes at `q`.
    fn project(&self, dim: usize, f: &Facet, x: &[f64; 3], q: &[f64]) -> Projection {
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
struct Projection {
    /// Distance from the node to the closest point.
    dist: f64,
    /// Signed normal gap.
    gap: f64,
    normal: [f64; 3],
    /// Shape function values at the closest point.
    weights: [f64; 4],
}

impl Projection {
    /// Whether the node lies behind the facet's interior (`x − x*` along the normal,
    /// pointing inward): inside the master body, where a clamped closest point (beside
    /// the surface) says nothing of the side.
    fn inside(&self) -> bool {
        self.gap < 0.0 && -self.gap >= (1.0 - 1e-9) * self.dist
    }
}

/// Slave nodes against the boundary facets of a master body (see the module doc).
#[derive(Clone, Debug)]
pub struct NodesOnSurface {
    dim: usize,
    slave: Side,
    master: Side,
    facets: Vec<Facet>,
    laws: Vec<ContactLaw>,
    block: usize,
    search: f64,
    capacity: usize,
    /// Dofs per Jacobian column: the slave's and the largest facet's.
    width: usize,
    /// Candidate facets of slave `s`: `cand[s * capacity..][..count[s]]`, by facet index.
    cand: Vec<u32>,
    count: Vec<u32>,
    /// Displacements of the slave then the master nodes at the last build, and at the
    /// last update (the motion of a step).
    built: Vec<[f64; 3]>,
    last: Vec<[f64; 3]>,
    /// Whether the lists were ever built.
    ready: bool,
    /// The facet each slave is paired with for the step ([`NO_FACET`]: none within the
    /// search distance).
    pair: Vec<u32>,
    /// Normal and tangent reference of each slave's set-up facet.
    rest_normal: Vec<[f64; 3]>,
    t_ref: Vec<[f64; 3]>,
    builds: usize,
    /// How errors name the bodies and the slave nodes.
    names: Option<Box<Names>>,
}

/// The names a [`NodesOnSurface`] gives in its errors.
#[derive(Clone, Debug)]
struct Names {
    slave: String,
    master: String,
    labels: Vec<String>,
}

impl NodesOnSurface {
    /// Slave nodes `slave` against the `facets` over the nodes `master`, in `dim`
    /// dimensions, with restitution `e`, friction `mu` and search distance `search`
    /// (m); candidate lists hold `capacity` facets per slave.
    pub fn new(
        dim: usize,
        slave: Side,
        master: Side,
        facets: Vec<Facet>,
        (e, mu): (f64, f64),
        search: f64,
        capacity: usize,
    ) -> Result<Self, Error> {
        check_restitution("restitution", e)?;
        check_friction("friction", mu)?;
        require_positive("target.search", search)?;
        if !(1..=3).contains(&dim) {
            return Err(Error::invalid("dimension", dim, "must be 1, 2 or 3"));
        }
        if mu > 0.0 && dim < 2 {
            return Err(Error::invalid(
                "friction",
                crate::error::num(mu),
                "a 1-D contact has no tangential direction, so Coulomb friction does not \
                 apply: set friction = 0, or model the bodies in 2-D or 3-D",
            ));
        }
        if facets.is_empty() {
            return Err(Error::invalid(
                "target.surface",
                "(no facet)",
                "the target surface has no boundary facet",
            ));
        }
        if slave
            .dofs
            .iter()
            .any(|d| d[..dim].iter().any(Option::is_none))
        {
            return Err(Error::invalid(
                "nodes",
                "a fixed node",
                "slave nodes must be free (a fixed node cannot be a contact node)",
            ));
        }
        check_facets(dim, &facets, master.dofs.len())?;
        let width = dim * (1 + facets.iter().map(|f| f.len as usize).max().unwrap_or(1));
        let m = slave.dofs.len();
        let block = if mu > 0.0 { dim } else { 1 };
        let nodes = m + master.dofs.len();
        let cap = capacity.max(1);
        let mut need = crate::limits::MemoryEstimate::default();
        need.add("candidate lists", (m as u64).saturating_mul(cap as u64), 4)
            .add(
                "facet tree",
                master.dofs.len() as u64 + facets.len() as u64,
                64,
            );
        need.check("target.capacity", cap)?;
        let mut set = NodesOnSurface {
            dim,
            laws: vec![
                ContactLaw {
                    restitution: e,
                    friction: mu,
                };
                m
            ],
            block,
            search,
            capacity: cap,
            width,
            cand: vec![0; m * cap],
            count: vec![0; m],
            built: vec![[0.0; 3]; nodes],
            last: vec![[0.0; 3]; nodes],
            ready: false,
            pair: vec![0; m],
            rest_normal: vec![[0.0; 3]; m],
            t_ref: vec![[0.0; 3]; m],
            builds: 0,
            names: None,
            slave,
            master,
            facets,
        };
        // the set-up facet of each slave: the facet whose box is nearest at q = 0
        let q0 = vec![0.0; set.max_dof() + 1];
        let tree = set.tree(&q0, 0.0);
        for s in 0..m {
            let x = set.slave.position(s, &q0, dim);
            let f = tree.nearest_neighbor(x).map_or(0, |h| h.data as usize);
            let p = set.master.project(dim, &set.facets[f], &x, &q0);
            set.rest_normal[s] = p.normal;
            set.t_ref[s] = super::frame::tangents(&p.normal)[0];
        }
        set.build(&q0, 2.0 * search)?;
        set.pair_at(&q0, false)?;
        Ok(set)
    }

    fn max_dof(&self) -> usize {
        self.slave
            .dofs
            .iter()
            .chain(&self.master.dofs)
            .flat_map(|d| d.iter().flatten().copied())
            .max()
            .unwrap_or(0)
    }

    /// Displacement of node `k` in the slave-then-master numbering of
    /// [`NodesOnSurface::built`].
    fn node_displacement(&self, k: usize, q: &[f64]) -> [f64; 3] {
        let m = self.slave.dofs.len();
        if k < m {
            self.slave.displacement(k, q, self.dim)
        } else {
            self.master.displacement(k - m, q, self.dim)
        }
    }

    /// Candidate facets kept per slave node.
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// How many times the candidate lists were built.
    pub fn builds(&self) -> usize {
        self.builds
    }

    /// The largest candidate count over the slave nodes at the last build.
    pub fn max_candidates(&self) -> usize {
        self.count.iter().copied().max().unwrap_or(0) as usize
    }

    /// Facets of the master surface.
    pub fn facets(&self) -> usize {
        self.facets.len()
    }

    /// Whether every facet is a candidate of every slave anyway (one facet): no tree.
    fn trivial(&self) -> bool {
        self.facets.len() == 1
    }

    /// Builds the candidate lists at `q` with the boxes grown by `grow`.
    fn build(&mut self, q: &[f64], grow: f64) -> Result<(), Error> {
        let dim = self.dim;
        let m = self.slave.dofs.len();
        self.builds += 1;
        for k in 0..self.built.len() {
            self.built[k] = self.node_displacement(k, q);
        }
        if self.trivial() {
            self.count.iter_mut().for_each(|c| *c = 1);
            self.cand.iter_mut().for_each(|c| *c = 0);
            return Ok(());
        }
        let tree = self.tree(q, grow);
        let cap = self.capacity;
        for s in 0..m {
            let x = self.slave.position(s, q, dim);
            let list = &mut self.cand[s * cap..(s + 1) * cap];
            let mut n = 0;
            let mut overflow = 0;
            for hit in tree.locate_in_envelope_intersecting(AABB::from_point(x)) {
                if n < cap {
                    list[n] = hit.data;
                    n += 1;
                } else {
                    overflow += 1;
                }
            }
            if overflow > 0 {
                return Err(Error::invalid(
                    "target.search",
                    crate::error::num(self.search),
                    &format!(
                        "slave node {s} has {} candidate facets within twice the search \
                         distance, more than the {cap} kept per node (target.capacity): \
                         give a smaller search distance (it need only exceed the largest \
                         motion of a node in a step) or a larger capacity",
                        n + overflow
                    ),
                ));
            }
            list[..n].sort_unstable();
            self.count[s] = n as u32;
        }
        self.ready = true;
        Ok(())
    }

    /// The R*-tree of the facets' boxes at `q`, grown by `grow`.
    fn tree(&self, q: &[f64], grow: f64) -> RTree<GeomWithData<Rectangle<[f64; 3]>, u32>> {
        let dim = self.dim;
        let boxes: Vec<GeomWithData<Rectangle<[f64; 3]>, u32>> = self
            .facets
            .iter()
            .enumerate()
            .map(|(i, f)| {
                let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
                for k in f.nodes() {
                    let x = self.master.position(k, q, dim);
                    for j in 0..3 {
                        lo[j] = lo[j].min(x[j]);
                        hi[j] = hi[j].max(x[j]);
                    }
                }
                for j in 0..dim {
                    lo[j] -= grow;
                    hi[j] += grow;
                }
                GeomWithData::new(Rectangle::from_corners(lo, hi), i as u32)
            })
            .collect();
        RTree::bulk_load(boxes)
    }

    /// Pairs each slave with its nearest candidate facet at `q` (none beyond the search
    /// distance); `true` when a pairing changed. With `check`, a slave that loses its
    /// facet while behind it (inside the other body, deeper than the search distance)
    /// is a run failure naming the bodies and the node: the contact law no longer sees
    /// it, and it would pass through silently (issue 34).
    fn pair_at(&mut self, q: &[f64], check: bool) -> Result<bool, Error> {
        let mut changed = false;
        for s in 0..self.len() {
            let x = self.slave.position(s, q, self.dim);
            let f = if self.trivial() {
                0
            } else {
                self.nearest(s, &x, q)
                    .filter(|(_, p)| p.dist <= self.search)
                    .map_or(NO_FACET, |(f, _)| f as u32)
            };
            let old = self.pair[s];
            if check && f == NO_FACET && old != NO_FACET {
                let p = self
                    .master
                    .project(self.dim, &self.facets[old as usize], &x, q);
                if p.inside() {
                    let (a, b, node) = match &self.names {
                        Some(n) => (n.slave.as_str(), n.master.as_str(), n.labels[s].clone()),
                        None => ("slave", "master", format!("slave node {s}")),
                    };
                    return Err(Error::Numerical(format!(
                        "{node} of body \"{a}\" is {:.3e} m inside body \"{b}\", deeper than \
                         the search distance {:.3e} m: the contact no longer holds it \
                         (lower the time step, or give target.search more than the \
                         deepest penetration)",
                        -p.gap, self.search
                    )));
                }
            }
            changed |= f != old;
            self.pair[s] = f;
        }
        Ok(changed)
    }

    /// The nearest candidate facet of slave `s` at `x` and its projection.
    fn nearest(&self, s: usize, x: &[f64; 3], q: &[f64]) -> Option<(usize, Projection)> {
        let cap = self.capacity;
        let mut best: Option<(usize, Projection)> = None;
        for &f in &self.cand[s * cap..s * cap + self.count[s] as usize] {
            let facet = &self.facets[f as usize];
            // the distance to the facet's box bounds the distance to the facet: a facet
            // that cannot come strictly nearer is not projected (the choice, lowest index
            // on a tie, is the same)
            if let Some((_, b)) = best
                && self.box_distance(facet, x, q) >= b.dist
            {
                continue;
            }
            let p = self.master.project(self.dim, facet, x, q);
            if best.is_none_or(|(_, b)| p.dist < b.dist) {
                best = Some((f as usize, p));
            }
        }
        best
    }

    /// The distance from `x` to facet `f`'s bounding box at `q`.
    fn box_distance(&self, f: &Facet, x: &[f64; 3], q: &[f64]) -> f64 {
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for k in f.nodes() {
            let y = self.master.position(k, q, self.dim);
            for j in 0..3 {
                lo[j] = lo[j].min(y[j]);
                hi[j] = hi[j].max(y[j]);
            }
        }
        let mut d2 = 0.0;
        for j in 0..3 {
            let e = (lo[j] - x[j]).max(x[j] - hi[j]).max(0.0);
            d2 += e * e;
        }
        d2.sqrt()
    }

    /// The tangents of normal `n` for slave `s` (see the module doc).
    fn tangents(&self, s: usize, n: &[f64; 3]) -> [[f64; 3]; 2] {
        if self.dim == 2 {
            return [[-n[1], n[0], 0.0], [0.0; 3]];
        }
        let r = self.t_ref[s];
        let t = axpy(&r, -dot(&r, n), n);
        let l = norm(&t);
        if l < 0.1 {
            return super::frame::tangents(n);
        }
        let t1 = [t[0] / l, t[1] / l, t[2] / l];
        [t1, cross(n, &t1)]
    }

    /// Writes slave `s`'s block: gap, and its columns from row `row` on.
    fn write(
        &self,
        s: usize,
        row: usize,
        hit: Option<(usize, Projection)>,
        gap: &mut f64,
        jac: &mut ContactJacobian,
    ) {
        let dim = self.dim;
        let sd = self.slave.dofs[s];
        let (normal, facet, weights) = match hit {
            Some((f, p)) => {
                *gap = p.gap;
                (p.normal, Some(&self.facets[f]), p.weights)
            }
            None => {
                *gap = self.search;
                (self.rest_normal[s], None, [0.0; 4])
            }
        };
        let t = self.tangents(s, &normal);
        for c in 0..self.block {
            let dir = if c == 0 { normal } else { t[c - 1] };
            let (dofs, vals) = jac.col_mut(row + c);
            let mut k = 0;
            for i in 0..dim {
                dofs[k] = sd[i].expect("free slave");
                vals[k] = dir[i];
                k += 1;
            }
            if let Some(f) = facet {
                for (node, w) in f.nodes().zip(weights) {
                    for i in 0..dim {
                        if let Some(d) = self.master.dofs[node][i] {
                            dofs[k] = d;
                            vals[k] = -w * dir[i];
                            k += 1;
                        }
                    }
                }
            }
            for j in k..self.width {
                dofs[j] = dofs[0];
                vals[j] = 0.0;
            }
        }
    }
}

impl ContactSet for NodesOnSurface {
    fn len(&self) -> usize {
        self.slave.dofs.len()
    }
    fn coordinate_scale(&self) -> f64 {
        self.slave
            .reference
            .iter()
            .chain(&self.master.reference)
            .flatten()
            .fold(0.0, |a: f64, x| a.max(x.abs()))
    }
    fn is_linear(&self) -> bool {
        self.dim == 1 && self.trivial()
    }
    fn dim(&self, _alpha: usize) -> usize {
        self.block
    }
    fn pattern(&self) -> Vec<Vec<usize>> {
        (0..self.len())
            .flat_map(|s| {
                let d0 = self.slave.dofs[s][0].expect("free slave");
                (0..self.block).map(move |_| vec![d0; self.width])
            })
            .collect()
    }
    fn evaluate(&self, q: &[f64], gap: &mut [f64], jac: &mut ContactJacobian) {
        let dim = self.dim;
        for s in 0..self.len() {
            let f = self.pair[s];
            let hit = (f != NO_FACET).then(|| {
                let x = self.slave.position(s, q, dim);
                (
                    f as usize,
                    self.master
                        .project(self.dim, &self.facets[f as usize], &x, q),
                )
            });
            self.write(s, s * self.block, hit, &mut gap[s], jac);
        }
    }
    fn starting_gaps(&self, q: &[f64], gap: &mut [f64]) {
        // the nearest facet of the whole surface (boxes in order of distance, stopped
        // once a box is farther than the best facet); the signed gap where the closest
        // point is inside the facet (`x − x*` along the normal: behind it means inside
        // the body), the distance where it is clamped to an edge (beside the surface)
        let tree = self.tree(q, 0.0);
        for (s, g) in gap.iter_mut().enumerate().take(self.len()) {
            let x = self.slave.position(s, q, self.dim);
            let mut best: Option<Projection> = None;
            for (hit, d2) in tree.nearest_neighbor_iter_with_distance_2(x) {
                if best.is_some_and(|b| d2 > b.dist * b.dist) {
                    break;
                }
                let p = self
                    .master
                    .project(self.dim, &self.facets[hit.data as usize], &x, q);
                if best.is_none_or(|b| p.dist < b.dist) {
                    best = Some(p);
                }
            }
            *g = best.map_or(f64::INFINITY, |p| if p.inside() { p.gap } else { p.dist });
        }
    }
    fn condensed(&self) -> bool {
        true
    }
    fn zone(&self) -> Vec<usize> {
        let mut z: Vec<usize> = self
            .slave
            .dofs
            .iter()
            .chain(&self.master.dofs)
            .flat_map(|d| d[..self.dim].iter().flatten().copied())
            .collect();
        z.sort_unstable();
        z.dedup();
        z
    }
    fn restart(&mut self, q: &[f64]) {
        for k in 0..self.last.len() {
            self.last[k] = self.node_displacement(k, q);
        }
        self.ready = false;
    }
    fn update(&mut self, q: &[f64]) -> Result<bool, Error> {
        if self.trivial() {
            return Ok(false);
        }
        let limit = 0.25 * self.search * self.search;
        let (mut stale, mut step) = (!self.ready, 0.0_f64);
        for k in 0..self.last.len() {
            let u = self.node_displacement(k, q);
            let (d, e) = (sub(&u, &self.built[k]), sub(&u, &self.last[k]));
            stale |= dot(&d, &d) > limit;
            step = step.max(dot(&e, &e));
            self.last[k] = u;
        }
        // a node that moves more than s/2 in one step may cross a facet the lists missed
        if step > limit {
            return Err(Error::invalid(
                "target.search",
                crate::error::num(self.search),
                &format!(
                    "a node moved {:.3e} m in one step, more than half the search distance: \
                     give a larger search distance or a smaller time step",
                    step.sqrt()
                ),
            ));
        }
        if stale {
            self.build(q, 2.0 * self.search)?;
        } else if step == 0.0 {
            // nothing moved since the last pairing (the step's `prepare` ran): the same
            // pairs
            return Ok(false);
        }
        self.pair_at(q, true)
    }
    fn laws(&self) -> &[ContactLaw] {
        &self.laws
    }
}

/// Barycentric coordinates `(b1, b2)` of the point of the triangle `p0 + b1 e1 + b2 e2`
/// closest to `x`.
fn closest_on_triangle(x: &[f64; 3], p0: &[f64; 3], e1: &[f64; 3], e2: &[f64; 3]) -> (f64, f64) {
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
fn bilinear(xi: f64, eta: f64) -> ([f64; 4], [f64; 4], [f64; 4]) {
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
fn closest_on_quad(x: &[f64; 3], p: &[[f64; 3]; 4]) -> (f64, f64) {
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

fn sub(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn norm(a: &[f64; 3]) -> f64 {
    dot(a, a).sqrt()
}
fn axpy(a: &[f64; 3], s: f64, b: &[f64; 3]) -> [f64; 3] {
    [a[0] + s * b[0], a[1] + s * b[1], a[2] + s * b[2]]
}
fn cross(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn unit(a: &[f64; 3]) -> [f64; 3] {
    let l = norm(a);
    [a[0] / l, a[1] / l, a[2] / l]
}

/// Checks that every facet has the node count of its dimension (1 in 1-D, 2 in 2-D, 3
/// or 4 in 3-D) over the `nodes` master nodes.
fn check_facets(dim: usize, facets: &[Facet], nodes: usize) -> Result<(), Error> {
    let want = match dim {
        1 => 1..=1,
        2 => 2..=2,
        _ => 3..=4,
    };
    for f in facets {
        if !want.contains(&(f.len as usize)) || f.nodes().any(|k| k >= nodes) {
            return Err(Error::invalid(
                "target.surface",
                format!("a facet of {} nodes", f.len),
                &format!("needs {want:?} nodes of the target body in {dim}-D"),
            ));
        }
    }
    Ok(())
}

/// The two sides of an interface as a scene gives them: the slave nodes and the master
/// facets over their bodies' node numbers, with each node's dofs (`None`: fixed).
pub struct Interface<'a> {
    /// Space dimension.
    pub dim: usize,
    /// Slave nodes (numbers in the slave body's mesh).
    pub slave: &'a [usize],
    /// The slave body's node coordinates.
    pub slave_points: &'a [[f64; 3]],
    /// Dofs of a slave body node.
    pub slave_dofs: &'a dyn Fn(usize) -> [Option<usize>; 3],
    /// Master facets, outward ([`crate::model::solid::Mesh::boundary_facets`]; in 1-D a
    /// rod's end node).
    pub facets: &'a [Vec<usize>],
    /// The master body's node coordinates.
    pub master_points: &'a [[f64; 3]],
    /// Dofs of a master body node.
    pub master_dofs: &'a dyn Fn(usize) -> [Option<usize>; 3],
    /// The slave and master bodies' names and how errors name a slave body node (its
    /// file tag), for a node found inside the other body during a run; `None`: by
    /// index.
    pub names: Option<NodeNames<'a>>,
}

/// The slave body's name, the master body's name, and how a slave body node is named.
pub type NodeNames<'a> = (&'a str, &'a str, &'a dyn Fn(usize) -> String);

impl Interface<'_> {
    /// The master nodes the facets use (sorted) and the facets over their positions in
    /// that list; a 1-D facet's outward direction points away from the master body's
    /// centroid.
    fn master(&self) -> (Vec<usize>, Vec<Facet>) {
        let mut nodes: Vec<usize> = self.facets.iter().flatten().copied().collect();
        nodes.sort_unstable();
        nodes.dedup();
        let centroid =
            self.master_points.iter().map(|p| p[0]).sum::<f64>() / self.master_points.len() as f64;
        let facets = self
            .facets
            .iter()
            .map(|f| {
                let local: Vec<usize> = f
                    .iter()
                    .map(|v| nodes.binary_search(v).expect("a facet node"))
                    .collect();
                let sign = if self.master_points[f[0]][0] >= centroid {
                    1.0
                } else {
                    -1.0
                };
                Facet::new(&local, sign)
            })
            .collect();
        (nodes, facets)
    }

    /// Smallest and mean edge length of the master facets (1-D: both a twentieth of
    /// the master rod's length).
    fn facet_sizes(&self) -> (f64, f64) {
        let (mut small, mut sum, mut n) = (f64::INFINITY, 0.0, 0usize);
        for f in self.facets {
            if f.len() < 2 {
                continue;
            }
            for k in 0..f.len() {
                let (a, b) = (
                    self.master_points[f[k]],
                    self.master_points[f[(k + 1) % f.len()]],
                );
                let l = norm(&sub(&a, &b));
                small = small.min(l);
                sum += l;
                n += 1;
                if f.len() == 2 {
                    break;
                }
            }
        }
        if n > 0 && small > 0.0 {
            (small, sum / n as f64)
        } else {
            let (lo, hi) = self
                .master_points
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
                    (l.min(p[0]), h.max(p[0]))
                });
            let l = 0.05 * (hi - lo).max(f64::MIN_POSITIVE);
            (l, l)
        }
    }
}

/// The contact set of an interface: [`NodesOnSurface`], or with `node_to_node` the
/// constant-`G` pairs of matching meshes ([`super::linear::LinearContacts`]): each slave
/// node with the nearest master surface node, along the surface's mean outward normal
/// there, refused when the pair is apart tangentially by more than 1e-6 of the facet
/// size (the meshes do not match) or normally by more than the search distance.
/// `search` defaults to half the smallest facet edge (a graded surface keeps few
/// candidates per node where it is fine). Returns the set and a line
/// that describes it (for `signorini check`).
pub fn build(
    side: Interface<'_>,
    node_to_node: bool,
    (e, mu): (f64, f64),
    search: Option<f64>,
    capacity: usize,
) -> Result<(Box<dyn ContactSet>, String), Error> {
    let dim = side.dim;
    let (smallest, size) = side.facet_sizes();
    let search = search.unwrap_or(0.5 * smallest);
    let (master_nodes, facets) = side.master();
    let slave = Side {
        dofs: side.slave.iter().map(|&v| (side.slave_dofs)(v)).collect(),
        reference: side.slave.iter().map(|&v| side.slave_points[v]).collect(),
    };
    if let Some(k) = slave
        .dofs
        .iter()
        .position(|d| d[..dim].iter().any(Option::is_none))
    {
        return Err(Error::invalid(
            "nodes",
            side.names.map_or_else(
                || format!("node {}", side.slave[k]),
                |(_, _, label)| label(side.slave[k]),
            ),
            "is fixed and cannot be a contact node",
        ));
    }
    let master = Side {
        dofs: master_nodes
            .iter()
            .map(|&v| (side.master_dofs)(v))
            .collect(),
        reference: master_nodes
            .iter()
            .map(|&v| side.master_points[v])
            .collect(),
    };
    if !node_to_node {
        let mut set = NodesOnSurface::new(dim, slave, master, facets, (e, mu), search, capacity)?;
        if let Some((a, b, label)) = side.names {
            set.names = Some(Box::new(Names {
                slave: a.to_string(),
                master: b.to_string(),
                labels: side.slave.iter().map(|&v| label(v)).collect(),
            }));
        }
        let line = format!(
            "{} facets (node-to-surface{}; search {search:.3e} m, {})",
            set.facets(),
            if set.is_linear() {
                ": a rod's end, constant G"
            } else {
                ""
            },
            if set.trivial() {
                "one facet: no tree".to_string()
            } else {
                format!(
                    "R*-tree of the facets' boxes, up to {} of {capacity} candidates per node \
                     at set-up, rebuilt when a node moves {:.3e} m",
                    set.max_candidates(),
                    0.5 * search
                )
            }
        );
        return Ok((Box::new(set), line));
    }
    // node-to-node: the mean outward normal at each master node (the facets' normals at
    // their centroids, in the reference configuration)
    check_facets(dim, &facets, master.dofs.len())?;
    let q0 = vec![
        0.0;
        master
            .dofs
            .iter()
            .flat_map(|d| d.iter().flatten().copied())
            .max()
            .map_or(0, |d| d + 1)
    ];
    let mut normal = vec![[0.0; 3]; master_nodes.len()];
    for f in &facets {
        let mut mid = [0.0; 3];
        for node in f.nodes() {
            for j in 0..3 {
                mid[j] += master.reference[node][j] / f.len as f64;
            }
        }
        let n = master.project(dim, f, &mid, &q0).normal;
        for node in f.nodes() {
            for j in 0..3 {
                normal[node][j] += n[j];
            }
        }
    }
    let points: Vec<GeomWithData<[f64; 3], usize>> = master
        .reference
        .iter()
        .enumerate()
        .map(|(k, p)| GeomWithData::new(*p, k))
        .collect();
    let tree = RTree::bulk_load(points);
    let mut contacts = Vec::with_capacity(slave.dofs.len());
    for (s, x) in slave.reference.iter().enumerate() {
        let k = tree.nearest_neighbor(*x).expect("a master node").data;
        let n = unit(&normal[k]);
        let d = sub(x, &master.reference[k]);
        let g0 = dot(&n, &d);
        let off = norm(&axpy(&d, -g0, &n));
        if off > 1e-6 * size || g0.abs() > search {
            return Err(Error::invalid(
                "target.pairing",
                "node-to-node",
                &format!(
                    "slave node {} is {off:.3e} m (tangentially) and {g0:.3e} m (normally) \
                     from the nearest target node: the meshes do not match there (allowed \
                     {:.3e} and the search distance {search:.3e}); use node-to-surface",
                    side.slave[s],
                    1e-6 * size
                ),
            ));
        }
        let mut dofs: Vec<usize> = slave.dofs[s][..dim].iter().flatten().copied().collect();
        let free: Vec<(usize, usize)> = (0..dim)
            .filter_map(|i| master.dofs[k][i].map(|d| (i, d)))
            .collect();
        dofs.extend(free.iter().map(|&(_, d)| d));
        let row = |dir: &[f64; 3]| -> Vec<f64> {
            (0..dim)
                .map(|i| dir[i])
                .chain(free.iter().map(|&(i, _)| -dir[i]))
                .collect()
        };
        let tangents = if mu > 0.0 {
            let t = super::frame::tangents(&n[..dim]);
            t[..dim - 1].iter().map(row).collect()
        } else {
            Vec::new()
        };
        contacts.push(super::linear::LinearContact {
            dofs,
            offset: g0,
            normal: row(&n),
            tangents,
            law: ContactLaw {
                restitution: e,
                friction: mu,
            },
        });
    }
    let line = format!(
        "{} nodes (node-to-node, matching meshes: constant G)",
        master_nodes.len()
    );
    Ok((
        Box::new(super::linear::LinearContacts::new(contacts)?),
        line,
    ))
}

/// For each point, the distance to the nearest of the facets' bounding boxes (a lower
/// bound of its distance to the surface), through an R*-tree.
pub fn box_distances(
    points: impl Iterator<Item = [f64; 3]>,
    facets: &[Vec<usize>],
    master_points: &[[f64; 3]],
) -> Vec<f64> {
    let boxes: Vec<Rectangle<[f64; 3]>> = facets
        .iter()
        .map(|f| {
            let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            for &v in f {
                for j in 0..3 {
                    lo[j] = lo[j].min(master_points[v][j]);
                    hi[j] = hi[j].max(master_points[v][j]);
                }
            }
            Rectangle::from_corners(lo, hi)
        })
        .collect();
    let tree = RTree::bulk_load(boxes);
    points
        .map(|x| {
            tree.nearest_neighbor_with_distance_2(x)
                .map_or(f64::INFINITY, |(_, d2)| d2.sqrt())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::generate::box_mesh;
    use crate::model::solid::CellKind;

    /// One slave node over one warped quad (both free): the gap is the distance along
    /// the normal and its Jacobian column is the central difference of the gap, to
    /// 1e-7 (an interior closest point: the column is exact, the difference has error
    /// O(ε²) with ε = 1e-6 m).
    #[test]
    fn gap_gradient_matches_central_differences_on_a_warped_quad() {
        let master = Side {
            dofs: (0..4)
                .map(|k| [Some(3 + 3 * k), Some(4 + 3 * k), Some(5 + 3 * k)])
                .collect(),
            reference: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.1, 0.05],
                [1.1, 1.0, -0.02],
                [-0.1, 0.9, 0.08],
            ],
        };
        let slave = Side {
            dofs: vec![[Some(0), Some(1), Some(2)]],
            reference: vec![[0.4, 0.55, 0.2]],
        };
        let set = NodesOnSurface::new(
            3,
            slave,
            master,
            vec![Facet::new(&[0, 1, 2, 3], 0.0)],
            (0.0, 0.3),
            1.0,
            4,
        )
        .unwrap();
        let q: Vec<f64> = (0..15).map(|i| 1e-3 * ((i * 7 % 5) as f64 - 2.0)).collect();
        let mut jac = ContactJacobian::for_set(&set);
        let mut gap = [0.0];
        set.evaluate(&q, &mut gap, &mut jac);
        assert!(gap[0] > 0.1 && gap[0] < 0.3, "{}", gap[0]);
        let (dofs, vals) = jac.col(0);
        let mut grad = [0.0; 15];
        for (&d, &v) in dofs.iter().zip(vals) {
            grad[d] += v;
        }
        let eps = 1e-6;
        for (i, &gi) in grad.iter().enumerate() {
            let (mut qp, mut qm) = (q.clone(), q.clone());
            qp[i] += eps;
            qm[i] -= eps;
            let (mut gp, mut gm) = ([0.0], [0.0]);
            let mut scratch = ContactJacobian::for_set(&set);
            set.evaluate(&qp, &mut gp, &mut scratch);
            set.evaluate(&qm, &mut gm, &mut scratch);
            let fd = (gp[0] - gm[0]) / (2.0 * eps);
            assert!((fd - gi).abs() < 1e-7, "dof {i}: {gi} against {fd}");
        }
        // the frame: unit normal first, orthonormal tangents
        let col = |c: usize| {
            let mut v = [0.0; 3];
            let (d, x) = jac.col(c);
            for (&d, &x) in d.iter().zip(x) {
                if d < 3 {
                    v[d] += x;
                }
            }
            v
        };
        let (n, t1, t2) = (col(0), col(1), col(2));
        for (a, b, want) in [
            (n, n, 1.0),
            (t1, t1, 1.0),
            (t2, t2, 1.0),
            (n, t1, 0.0),
            (t1, t2, 0.0),
        ] {
            assert!((dot(&a, &b) - want).abs() < 1e-12);
        }
    }

    /// The boundary facets of a box point out of it, and the closest points of nodes
    /// beyond an edge clamp to it: a node outside the face's footprint still gets the
    /// gap along the face's normal.
    #[test]
    fn box_faces_point_outward_and_clamp_at_their_edges() {
        let mesh = box_mesh(CellKind::Hex8, [2, 2, 2], [1.0, 1.0, 1.0]);
        let all: Vec<usize> = (0..mesh.points.len()).collect();
        let facets = mesh.boundary_facets(&all);
        assert_eq!(facets.len(), 24);
        let centre = [0.5, 0.5, 0.5];
        for f in &facets {
            let p: Vec<[f64; 3]> = f.iter().map(|&v| mesh.points[v]).collect();
            let n = cross(&sub(&p[2], &p[0]), &sub(&p[3], &p[1]));
            let mid = [0, 1, 2].map(|j| p.iter().map(|x| x[j]).sum::<f64>() / 4.0);
            assert!(dot(&n, &sub(&mid, &centre)) > 0.0, "{f:?} points inward");
        }
        // the top face against a node beyond its edge, 0.1 above
        let top: Vec<usize> = (0..mesh.points.len())
            .filter(|&v| mesh.points[v][2] == 1.0)
            .collect();
        let faces = mesh.boundary_facets(&top);
        assert_eq!(faces.len(), 4);
        let (set, _) = build(
            Interface {
                dim: 3,
                slave: &[0],
                slave_points: &[[1.2, 0.5, 1.1]],
                slave_dofs: &|_| [Some(0), Some(1), Some(2)],
                facets: &faces,
                master_points: &mesh.points,
                master_dofs: &|v| [Some(3 + 3 * v), Some(4 + 3 * v), Some(5 + 3 * v)],
                names: None,
            },
            false,
            (0.0, 0.0),
            Some(1.0),
            DEFAULT_CAPACITY,
        )
        .unwrap();
        let q = vec![0.0; 3 + 3 * mesh.points.len()];
        let mut jac = ContactJacobian::for_set(set.as_ref());
        let mut gap = [0.0];
        set.evaluate(&q, &mut gap, &mut jac);
        assert!((gap[0] - 0.1).abs() < 1e-15, "{}", gap[0]);
        let (_, vals) = jac.col(0);
        assert_eq!(&vals[..3], &[0.0, 0.0, 1.0]);
    }

    /// A slave node against the top face (z = 1) of a 2 × 2 × 2 unit cube, search 0.1.
    fn node_over_the_top(x: [f64; 3]) -> Box<dyn ContactSet> {
        let mesh = box_mesh(CellKind::Hex8, [2, 2, 2], [1.0, 1.0, 1.0]);
        let top: Vec<usize> = (0..mesh.points.len())
            .filter(|&v| mesh.points[v][2] == 1.0)
            .collect();
        let faces = mesh.boundary_facets(&top);
        build(
            Interface {
                dim: 3,
                slave: &[0],
                slave_points: &[x],
                slave_dofs: &|_| [Some(0), Some(1), Some(2)],
                facets: &faces,
                master_points: &mesh.points,
                master_dofs: &|v| [Some(3 + 3 * v), Some(4 + 3 * v), Some(5 + 3 * v)],
                names: Some(("upper", "cube", &|_| "node 7 (tag in a.msh)".to_string())),
            },
            false,
            (0.0, 0.0),
            Some(0.1),
            DEFAULT_CAPACITY,
        )
        .unwrap()
        .0
    }

    /// Issue 34: a node 0.3 m under the top face (3× the search distance) reads −0.3 as
    /// its starting gap, where the step's gap reads the search distance; a node beside
    /// the face and below its level (the closest point clamped to an edge) reads its
    /// distance, not a depth; a node above reads its height.
    #[test]
    fn starting_gaps_see_nodes_inside_beyond_the_search_distance() {
        let n = 3 + 3 * 27;
        for (x, want) in [
            ([0.4, 0.6, 0.7], -0.3),
            ([1.3, 0.5, 0.6], 0.5),
            ([0.5, 0.5, 1.25], 0.25),
        ] {
            let set = node_over_the_top(x);
            let mut g = [0.0];
            set.starting_gaps(&vec![0.0; n], &mut g);
            assert!(
                (g[0] - want).abs() < 1e-12,
                "{x:?}: {} against {want}",
                g[0]
            );
        }
        let set = node_over_the_top([0.4, 0.6, 0.7]);
        let mut jac = ContactJacobian::for_set(set.as_ref());
        let mut g = [0.0];
        set.evaluate(&vec![0.0; n], &mut g, &mut jac);
        assert_eq!(g[0], 0.1, "the step's gap of an unpaired node");
    }

    /// Issue 34: a node pushed through the top face 0.04 m per step (under half the
    /// search distance, so the motion check lets it) is lost by its facet once deeper
    /// than the search distance: a run failure naming the bodies and the node.
    #[test]
    fn a_node_lost_inside_the_other_body_fails_the_run() {
        let mut set = node_over_the_top([0.4, 0.6, 1.02]);
        let mut q = vec![0.0; 3 + 3 * 27];
        let mut err = None;
        for _ in 0..10 {
            q[2] -= 0.04;
            if let Err(e) = set.update(&q) {
                err = Some(e);
                break;
            }
        }
        let e = err.expect("the lost node is reported").to_string();
        assert!(
            q[2] < -0.1 && q[2] > -0.2,
            "found at depth {}",
            -q[2] - 0.02
        );
        for needle in [
            "node 7 (tag in a.msh)",
            "\"upper\"",
            "\"cube\"",
            "target.search",
        ] {
            assert!(e.contains(needle), "{needle}: {e}");
        }
    }
}
