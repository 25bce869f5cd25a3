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

mod facet;
mod interface;
mod search;

use facet::*;
pub use facet::{Facet, Side};
use interface::*;
pub use interface::{Interface, box_distances, build};

/// Candidate facets kept per slave node by default (the R*-tree query's results within
/// twice the search distance: 9 to 25 quads of a uniform face with the default search,
/// about twice as many triangles; 64 leaves room for graded and distorted surfaces).
pub const DEFAULT_CAPACITY: usize = 64;

/// A slave paired with no facet.
const NO_FACET: u32 = u32::MAX;

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

/// The slave body's name, the master body's name, and how a slave body node is named.
pub type NodeNames<'a> = (&'a str, &'a str, &'a dyn Fn(usize) -> String);

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
