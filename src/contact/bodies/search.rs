//! The candidate search: an R*-tree of the facets' boxes (rstar) grown by the Verlet
//! margin, rebuilt when a node may have moved past it, and each node's nearest facet.

use super::*;

impl NodesOnSurface {
    /// Builds the candidate lists at `q` with the boxes grown by `grow`.
    pub(super) fn build(&mut self, q: &[f64], grow: f64) -> Result<(), Error> {
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
    pub(super) fn tree(
        &self,
        q: &[f64],
        grow: f64,
    ) -> RTree<GeomWithData<Rectangle<[f64; 3]>, u32>> {
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
    pub(super) fn pair_at(&mut self, q: &[f64], check: bool) -> Result<bool, Error> {
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
    pub(super) fn nearest(&self, s: usize, x: &[f64; 3], q: &[f64]) -> Option<(usize, Projection)> {
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
    pub(super) fn box_distance(&self, f: &Facet, x: &[f64; 3], q: &[f64]) -> f64 {
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
}
