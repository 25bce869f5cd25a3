//! Fill-reducing orders of a mesh's dofs, handed to the sparse Cholesky of `M̂`
//! (eq. 47) as candidates beside faer's AMD: the geometric nested dissection below
//! and, with the `metis` feature, METIS' multilevel nested dissection of the node
//! graph (`crate::linalg::metis`), which the scene asks for with
//! `scheme.ordering = "metis"` ([`OrderingKind`], [`candidate`]). A node's dofs stay
//! together, so the dof factor is the node graph's pattern with 3×3 blocks (the tests
//! compare orders there, `node_fill`, at a ninth of the cost).
//!
//! The geometric order splits the nodes recursively at the median coordinate along
//! the longest extent of the current part; the nodes of the upper half that share a
//! cell with the lower half form the separator, numbered after both halves; parts of
//! at most [`LEAF_NODES`] nodes keep their order. The dofs of each node follow its
//! position. Measured with faer's symbolic factorization (nnz of the Cholesky factor
//! of `K`): hex8 cube 31³ cells, 1.89e8 with AMD against 1.09e8; plate 63 × 63 × 8
//! cells, 1.45e8 against 0.77e8; slender bar 400 × 8 × 8 cells, 3.76e7 against
//! 3.49e7. METIS: 2.8 %, 7.2 %, 1.7 % fewer entries than the geometric order on free
//! hex8 cubes of 20³, 30³, 40³ cells, 10–15 % fewer on the two-cube scenes, 2.7 % on
//! the rail and the plate; but faer's supernodal solves on its factor are slower (the
//! two-cube steps 7–9 %), so it is not the default. [`crate::linalg::SpdFactor`] keeps
//! whichever of the candidate and AMD fills less.

use crate::linalg::DofOrdering;
use crate::model::geometry::{GeomCell, Geometry};

/// Parts of at most this many nodes are not split further.
pub const LEAF_NODES: usize = 64;

/// The name of the geometric order in the factor's path line.
pub const GEOMETRIC: &str = "nested dissection";

/// The name of METIS' order in the factor's path line.
pub const METIS: &str = "METIS nested dissection";

/// The node graph of `geom` (two nodes adjacent where they share a cell) in compressed
/// rows: the neighbours of node `v` are `adj[xadj[v]..xadj[v + 1]]`, sorted, without
/// repeats or `v` itself.
pub fn node_graph(geom: &Geometry) -> (Vec<usize>, Vec<usize>) {
    let np = geom.points.len();
    let mut deg = vec![0usize; np + 1];
    for (_, nodes, _) in &geom.cells {
        for &a in nodes {
            deg[a + 1] += nodes.len() - 1;
        }
    }
    for i in 0..np {
        deg[i + 1] += deg[i];
    }
    let mut adj = vec![0usize; deg[np]];
    let mut fill = deg.clone();
    for (_, nodes, _) in &geom.cells {
        for &a in nodes {
            for &b in nodes.iter().filter(|&&b| b != a) {
                adj[fill[a]] = b;
                fill[a] += 1;
            }
        }
    }
    // sort and drop the repeats row by row, compacting in place
    let mut xadj = vec![0usize; np + 1];
    let mut len = 0;
    for v in 0..np {
        let (lo, hi) = (deg[v], deg[v + 1]);
        adj[lo..hi].sort_unstable();
        let mut last = usize::MAX;
        for i in lo..hi {
            let u = adj[i];
            if u != last {
                adj[len] = u;
                len += 1;
                last = u;
            }
        }
        xadj[v + 1] = len;
    }
    adj.truncate(len);
    (xadj, adj)
}

/// The dofs of the `ndof`-dof system drawn by `geom`, in geometric nested-dissection
/// order (position → dof). Dofs that no point carries (none in a mesh model) come
/// last, in their natural order, so the result is always a permutation of `0..ndof`.
pub fn nested_dissection(geom: &Geometry, ndof: usize) -> Vec<usize> {
    let (xadj, adj) = node_graph(geom);
    node_dofs(geom, &geometric_order(geom, &xadj, &adj), ndof)
}

/// Which fill-reducing order a scene offers the Cholesky of `M̂` beside AMD (the
/// scene key `scheme.ordering`); the factorization keeps the candidate only where it
/// fills less than AMD, and the path line names the one kept.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum OrderingKind {
    /// The mesh's geometric nested dissection ([`nested_dissection`]; default): the
    /// fastest steps measured on the two-cube and rail scenes.
    #[default]
    Auto,
    /// METIS' multilevel nested dissection of the node graph (feature `metis`): 3–15 %
    /// fewer factor entries than the geometric order on the cubes, plate and rail,
    /// hence a smaller factor and a faster set-up, but steps up to a tenth slower
    /// (docs/bodies.md, "Orderings").
    Metis,
    /// AMD alone.
    Amd,
}

impl OrderingKind {
    /// The scene's name.
    pub fn name(self) -> &'static str {
        match self {
            OrderingKind::Auto => "auto",
            OrderingKind::Metis => "metis",
            OrderingKind::Amd => "amd",
        }
    }
}

/// The candidate order of `kind` for the `ndof`-dof system drawn by `geom` (`None`:
/// AMD alone). `Err` names what is missing: METIS in a build without it, or a graph
/// METIS refused.
pub fn candidate(
    kind: OrderingKind,
    geom: &Geometry,
    ndof: usize,
) -> Result<Option<DofOrdering>, String> {
    match kind {
        OrderingKind::Amd => Ok(None),
        OrderingKind::Auto => Ok(Some(DofOrdering {
            method: GEOMETRIC,
            perm: nested_dissection(geom, ndof),
        })),
        OrderingKind::Metis => metis_nested_dissection(geom, ndof).map(|perm| {
            Some(DofOrdering {
                method: METIS,
                perm,
            })
        }),
    }
}

/// The dofs in METIS' nested-dissection order of the node graph (position → dof), as
/// [`nested_dissection`] lays them out.
pub fn metis_nested_dissection(geom: &Geometry, ndof: usize) -> Result<Vec<usize>, String> {
    #[cfg(feature = "metis")]
    {
        let (xadj, adj) = node_graph(geom);
        let order = crate::linalg::metis::node_nd(&xadj, &adj).ok_or_else(|| {
            format!(
                "METIS could not order the node graph ({} nodes, {} adjacencies)",
                xadj.len() - 1,
                adj.len()
            )
        })?;
        Ok(node_dofs(geom, &order, ndof))
    }
    #[cfg(not(feature = "metis"))]
    {
        let _ = (geom, ndof);
        Err("this build has no METIS (cargo feature `metis`)".to_string())
    }
}

/// The entries of the Cholesky factor of the node graph's pattern (with its diagonal)
/// under `order` (position → node), from faer's symbolic analysis; `None` if it fails.
/// The tests' yardstick (the run compares orders at the dof level, `linalg::plan`).
#[cfg(test)]
fn node_fill(xadj: &[usize], adj: &[usize], order: &[usize]) -> Option<usize> {
    use faer::sparse::SymbolicSparseColMat;
    use faer::sparse::linalg::cholesky::{
        CholeskySymbolicParams, SymmetricOrdering, factorize_symbolic_cholesky,
    };
    let n = xadj.len().checked_sub(1)?;
    if order.len() != n || n == 0 {
        return None;
    }
    let mut col_ptr = Vec::with_capacity(n + 1);
    let mut rows = Vec::with_capacity(adj.len() + n);
    col_ptr.push(0);
    for v in 0..n {
        let nb = &adj[xadj[v]..xadj[v + 1]];
        let at = nb.partition_point(|&u| u < v);
        rows.extend_from_slice(&nb[..at]);
        rows.push(v);
        rows.extend_from_slice(&nb[at..]);
        col_ptr.push(rows.len());
    }
    let pattern = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, rows);
    let mut inv = vec![usize::MAX; n];
    for (i, &v) in order.iter().enumerate() {
        *inv.get_mut(v)? = i;
    }
    if inv.contains(&usize::MAX) {
        return None;
    }
    let perm = faer::perm::PermRef::new_checked(order, &inv, n);
    factorize_symbolic_cholesky(
        pattern.as_ref(),
        faer::Side::Lower,
        SymmetricOrdering::Custom(perm),
        CholeskySymbolicParams::default(),
    )
    .ok()
    .map(|s| s.len_val())
}

/// The nodes in geometric nested-dissection order (position → node).
fn geometric_order(geom: &Geometry, deg: &[usize], adj: &[usize]) -> Vec<usize> {
    let np = geom.points.len();
    let mut order = Vec::with_capacity(np);
    let mut side = vec![0u8; np];
    let mut keys = Vec::with_capacity(np);
    let mut stack = vec![Task::Split((0..np).collect())];
    // an explicit stack: (left, right, separator) are pushed in reverse so that the
    // left part is ordered first and the separator last
    while let Some(t) = stack.pop() {
        match t {
            Task::Emit(nodes) => order.extend(nodes),
            Task::Split(nodes) => match bisect(&nodes, geom, deg, adj, &mut side, &mut keys) {
                Some((left, right, sep)) => {
                    stack.push(Task::Emit(sep));
                    stack.push(Task::Split(right));
                    stack.push(Task::Split(left));
                }
                None => order.extend(nodes),
            },
        }
    }
    order
}

/// The dofs of the nodes in `order` (position → node), a node's dofs in its position;
/// dofs that no point carries last.
fn node_dofs(geom: &Geometry, order: &[usize], ndof: usize) -> Vec<usize> {
    let mut seen = vec![false; ndof];
    let mut perm = Vec::with_capacity(ndof);
    for &p in order {
        for c in 0..geom.dim {
            if let Some(&Some(d)) = geom.dof_of.get(p * geom.dim + c)
                && d < ndof
                && !seen[d]
            {
                seen[d] = true;
                perm.push(d);
            }
        }
    }
    perm.extend((0..ndof).filter(|&d| !seen[d]));
    perm
}

/// Whether `geom` has solid cells (a rod chain is tridiagonal and needs no ordering).
pub fn worth_ordering(geom: &Geometry) -> bool {
    geom.cells
        .iter()
        .any(|(k, _, _)| matches!(k, GeomCell::Solid(_)))
}

enum Task {
    Split(Vec<usize>),
    Emit(Vec<usize>),
}

type Parts = (Vec<usize>, Vec<usize>, Vec<usize>);

/// Splits `nodes` at the median of the longest axis; `None` for a leaf (small, or no
/// split possible because every node sits at the same coordinate).
fn bisect(
    nodes: &[usize],
    geom: &Geometry,
    deg: &[usize],
    adj: &[usize],
    side: &mut [u8],
    keys: &mut Vec<f64>,
) -> Option<Parts> {
    if nodes.len() <= LEAF_NODES {
        return None;
    }
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for &v in nodes {
        for d in 0..3 {
            lo[d] = lo[d].min(geom.points[v][d]);
            hi[d] = hi[d].max(geom.points[v][d]);
        }
    }
    let ax = (0..3)
        .max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))
        .expect("three axes");
    keys.clear();
    keys.extend(nodes.iter().map(|&v| geom.points[v][ax]));
    let mid = keys.len() / 2;
    let (_, &mut med, _) = keys.select_nth_unstable_by(mid, f64::total_cmp);
    for &v in nodes {
        side[v] = if geom.points[v][ax] < med { 1 } else { 2 };
    }
    let (mut left, mut right, mut sep) = (Vec::new(), Vec::new(), Vec::new());
    for &v in nodes {
        if side[v] == 1 {
            left.push(v);
        } else if adj[deg[v]..deg[v + 1]].iter().any(|&u| side[u] == 1) {
            sep.push(v);
        } else {
            right.push(v);
        }
    }
    for &v in nodes {
        side[v] = 0;
    }
    if left.is_empty() {
        return None; // every node at or above the median: no split along this axis
    }
    Some((left, right, sep))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::generate::box_mesh;
    use crate::model::solid::{CellKind, Formulation, Material};

    fn box_geometry(n: [usize; 3]) -> Geometry {
        let mesh = box_mesh(CellKind::Hex8, n, [2.0, 1.0, 1.0]);
        let mat = Material {
            young: 1.0,
            poisson: 0.3,
            density: 1.0,
            model: crate::model::solid::MaterialModel::LINEAR,
        };
        Geometry {
            dim: 3,
            dof_of: (0..3 * mesh.points.len()).map(Some).collect(),
            cells: mesh
                .cells
                .iter()
                .map(|(k, c)| (GeomCell::Solid(*k), c.clone(), 0))
                .collect(),
            bodies: vec![(mat, Formulation::Solid)],
            points: mesh.points,
            ..Geometry::default()
        }
    }

    /// The result is a permutation of every dof, a node's dofs stay together, and the
    /// last nodes are the top-level separator: the mid-plane of the longest axis.
    #[test]
    fn nested_dissection_is_a_permutation_ending_with_the_separator() {
        let g = box_geometry([12, 6, 6]);
        let ndof = 3 * g.points.len();
        let p = nested_dissection(&g, ndof);
        let mut sorted = p.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..ndof).collect::<Vec<_>>());
        for c in p.chunks_exact(3) {
            assert_eq!((c[1], c[2]), (c[0] + 1, c[0] + 2));
        }
        // the 7 × 7 nodes of the mid-plane x = 1 (x is the longest axis) close the order
        let last: Vec<usize> = p[ndof - 3 * 49..]
            .iter()
            .step_by(3)
            .map(|d| d / 3)
            .collect();
        assert!(
            last.iter().all(|&v| (g.points[v][0] - 1.0).abs() < 1e-12),
            "{last:?}"
        );
    }

    /// The node graph is sorted, symmetric and without self-loops; METIS' order is a
    /// permutation of the dofs with a node's dofs together, and on the node graphs of
    /// a 10³ cube and a slender 40 × 4 × 4 bar it fills less than the geometric order
    /// (measured 127 722 against 147 131 and 42 920 against 118 303 entries).
    #[test]
    fn metis_orders_the_node_graph() {
        for cells in [[10, 10, 10], [40, 4, 4]] {
            let g = box_geometry(cells);
            let ndof = 3 * g.points.len();
            let (xadj, adj) = node_graph(&g);
            for v in 0..g.points.len() {
                let row = &adj[xadj[v]..xadj[v + 1]];
                assert!(row.windows(2).all(|w| w[0] < w[1]) && !row.contains(&v));
                assert!(row.iter().all(|&u| adj[xadj[u]..xadj[u + 1]].contains(&v)));
            }
            // an interior hex8 node has 26 neighbours
            assert_eq!(
                (0..g.points.len()).map(|v| xadj[v + 1] - xadj[v]).max(),
                Some(26)
            );
            let Ok(perm) = metis_nested_dissection(&g, ndof) else {
                #[cfg(not(feature = "metis"))]
                continue;
                #[cfg(feature = "metis")]
                panic!("METIS refused the graph of {cells:?}");
            };
            let mut sorted = perm.clone();
            sorted.sort_unstable();
            assert_eq!(sorted, (0..ndof).collect::<Vec<_>>());
            for c in perm.chunks_exact(3) {
                assert_eq!((c[1], c[2]), (c[0] + 1, c[0] + 2));
            }
            let nodes: Vec<usize> = perm.chunks_exact(3).map(|c| c[0] / 3).collect();
            let metis = node_fill(&xadj, &adj, &nodes).unwrap() as f64;
            let geo = node_fill(&xadj, &adj, &geometric_order(&g, &xadj, &adj)).unwrap() as f64;
            eprintln!("{cells:?}: node fill METIS {metis}, geometric {geo}");
            assert!(metis < geo, "{cells:?}: METIS {metis} vs geometric {geo}");
        }
    }

    /// `scheme.ordering` picks the candidate: the geometric order, METIS' (or the
    /// error of a build without it), none for AMD.
    #[test]
    fn the_kind_picks_the_candidate() {
        let g = box_geometry([6, 6, 6]);
        let ndof = 3 * g.points.len();
        assert_eq!(candidate(OrderingKind::Amd, &g, ndof), Ok(None));
        let auto = candidate(OrderingKind::Auto, &g, ndof).unwrap().unwrap();
        assert_eq!(
            (auto.method, auto.perm),
            (GEOMETRIC, nested_dissection(&g, ndof))
        );
        match candidate(OrderingKind::Metis, &g, ndof) {
            Ok(Some(o)) => assert!(cfg!(feature = "metis") && o.method == METIS),
            Err(e) => assert!(
                !cfg!(feature = "metis") && e.contains("feature `metis`"),
                "{e}"
            ),
            Ok(None) => panic!("METIS gave no order"),
        }
    }

    /// Points all at one place cannot be split: the order is the natural one.
    #[test]
    fn degenerate_geometry_keeps_the_natural_order() {
        let mut g = box_geometry([4, 4, 4]);
        g.points.iter_mut().for_each(|p| *p = [0.0; 3]);
        let ndof = 3 * g.points.len();
        assert_eq!(nested_dissection(&g, ndof), (0..ndof).collect::<Vec<_>>());
    }

    /// On a 12 × 12 × 12 hex box the nested-dissection order fills less than AMD, is
    /// the one kept, and its factor solves `M + h²/4 K` to the same accuracy (relative
    /// residual below 1e-12: κ of this mass-dominated matrix is small).
    #[test]
    fn factor_keeps_nested_dissection_and_solves_accurately() {
        use crate::assembly::linear_combination;
        use crate::linalg::{SpdFactor, max_residual, spmv};
        use crate::model::MassKind;
        let g = box_geometry([12, 12, 12]);
        let mesh = box_mesh(CellKind::Hex8, [12, 12, 12], [2.0, 1.0, 1.0]);
        let mat = Material {
            young: 210e9,
            poisson: 0.3,
            density: 7800.0,
            model: crate::model::solid::MaterialModel::LINEAR,
        };
        let sys =
            crate::model::solid::assemble(&mesh, &mat, Formulation::Solid, MassKind::Consistent)
                .unwrap();
        let h = 1e-6;
        let a = linear_combination(&[(1.0, &sys.mass), (h * h / 4.0, &sys.stiffness)]);
        let n = sys.ndof();
        let order = DofOrdering {
            method: GEOMETRIC,
            perm: nested_dissection(&g, n),
        };
        let mut amd = SpdFactor::new(a.as_ref(), "M̂").unwrap();
        let mut nd = SpdFactor::with_ordering(a.as_ref(), "M̂", Some(&order)).unwrap();
        assert!(amd.backend_name().contains("AMD"), "{}", amd.backend_name());
        assert!(
            nd.backend_name().contains("nested dissection"),
            "{}",
            nd.backend_name()
        );
        let x_true: Vec<f64> = (0..n).map(|i| (i as f64 * 0.1).sin()).collect();
        let mut b = vec![0.0; n];
        spmv(a.as_ref(), &x_true, &mut b);
        for f in [&mut amd, &mut nd] {
            let mut x = b.clone();
            f.solve_in_place(&mut x);
            let res = max_residual(a.as_ref(), &x, &b);
            let scale = b.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            assert!(res / scale < 1e-12, "{}: {}", f.backend_name(), res / scale);
        }
    }
}
