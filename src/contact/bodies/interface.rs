//! Building an interface from meshes: the target surface's facets, their checks, and the
//! starting distances between the bodies.

use super::*;

/// Checks that every facet has the node count of its dimension (1 in 1-D, 2 in 2-D, 3
/// or 4 in 3-D) over the `nodes` master nodes.
pub(super) fn check_facets(dim: usize, facets: &[Facet], nodes: usize) -> Result<(), Error> {
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

impl Interface<'_> {
    /// The master nodes the facets use (sorted) and the facets over their positions in
    /// that list; a 1-D facet's outward direction points away from the master body's
    /// centroid.
    pub(super) fn master(&self) -> (Vec<usize>, Vec<Facet>) {
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
    pub(super) fn facet_sizes(&self) -> (f64, f64) {
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
/// constant-`G` pairs of matching meshes ([`super::super::linear::LinearContacts`]): each slave
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
            let t = super::super::frame::tangents(&n[..dim]);
            t[..dim - 1].iter().map(row).collect()
        } else {
            Vec::new()
        };
        contacts.push(super::super::linear::LinearContact {
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
        Box::new(super::super::linear::LinearContacts::new(contacts)?),
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
