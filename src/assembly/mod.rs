//! Sparse assembly: element matrices to global compressed-column matrices.
//!
//! Two assemblers behind one [`Accumulate`] trait:
//! - [`Assembler`]: element contributions are pushed as triplets and handed to faer's
//!   triplet constructor (which sorts and sums duplicates). Used for small and one-off
//!   matrices: the rod, point masses, linear combinations of unlike patterns.
//!   (nalgebra-sparse's COO → CSC was measured about 2× faster on a 40³ Laplacian,
//!   DESIGN.md §6, but meshes go through the pattern assembler below, and faer's
//!   constructor removes a dependency.)
//! - [`PatternAssembler`]: for meshes, the CSC pattern is built once from the node
//!   adjacency and contributions are added in place (binary search in short sorted
//!   columns). On a 98k-dof hex8 box the COO route spent 0.41 s pushing and 0.82 s
//!   sorting per matrix.

use faer::sparse::{SymbolicSparseColMat, Triplet};

use crate::linalg::SparseMatrix;

mod plan;

pub use plan::*;

/// Something element matrices can be added into.
pub trait Accumulate {
    /// Adds `v` at `(i, j)`.
    fn add(&mut self, i: usize, j: usize, v: f64);
    /// Adds the dense element matrix `ke(a, b)` at the global dofs `dofs`.
    fn add_element(&mut self, dofs: &[usize], ke: impl Fn(usize, usize) -> f64) {
        for (a, &i) in dofs.iter().enumerate() {
            for (b, &j) in dofs.iter().enumerate() {
                let v = ke(a, b);
                if v != 0.0 {
                    self.add(i, j, v);
                }
            }
        }
    }
}

impl Accumulate for Assembler {
    fn add(&mut self, i: usize, j: usize, v: f64) {
        self.triplets.push(Triplet::new(i, j, v));
    }
}

/// A mesh matrix with its pattern fixed from the node adjacency: every dof of a node
/// couples with every dof of the nodes sharing a cell with it.
pub struct PatternAssembler {
    n: usize,
    dim: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    values: Vec<f64>,
}

impl PatternAssembler {
    /// The pattern of `cells` (node lists) over `nodes` nodes with `dim` dofs each.
    pub fn new(nodes: usize, dim: usize, cells: &[&[usize]]) -> Self {
        let mut adj: Vec<Vec<usize>> = vec![Vec::new(); nodes];
        for c in cells {
            for &a in *c {
                adj[a].extend_from_slice(c);
            }
        }
        let n = nodes * dim;
        let mut col_ptr = Vec::with_capacity(n + 1);
        col_ptr.push(0);
        let mut row_idx = Vec::new();
        for list in adj.iter_mut() {
            list.sort_unstable();
            list.dedup();
            for _ in 0..dim {
                for &u in list.iter() {
                    row_idx.extend((0..dim).map(|r| u * dim + r));
                }
                col_ptr.push(row_idx.len());
            }
        }
        let values = vec![0.0; row_idx.len()];
        PatternAssembler {
            n,
            dim,
            col_ptr,
            row_idx,
            values,
        }
    }

    /// A copy of the pattern with zero values (to assemble a second matrix).
    pub fn zeroed_like(&self) -> Self {
        PatternAssembler {
            n: self.n,
            dim: self.dim,
            col_ptr: self.col_ptr.clone(),
            row_idx: self.row_idx.clone(),
            values: vec![0.0; self.values.len()],
        }
    }

    /// Hands the arrays to faer (no copy).
    pub fn finish(self) -> SparseMatrix {
        let sym =
            SymbolicSparseColMat::new_checked(self.n, self.n, self.col_ptr, None, self.row_idx);
        SparseMatrix::new(sym, self.values)
    }
}

impl Accumulate for PatternAssembler {
    fn add(&mut self, i: usize, j: usize, v: f64) {
        let r = self.col_ptr[j]..self.col_ptr[j + 1];
        match self.row_idx[r.clone()].binary_search(&i) {
            Ok(k) => self.values[r.start + k] += v,
            Err(_) => panic!("PatternAssembler: ({i}, {j}) is outside the mesh pattern"),
        }
    }
}

/// The columns `cols` of a [`PatternAssembler`]'s values, lent to one assembly task:
/// contributions to other columns are skipped (another task owns them).
pub struct ColumnSlab<'a> {
    col_ptr: &'a [usize],
    row_idx: &'a [usize],
    cols: std::ops::Range<usize>,
    offset: usize,
    values: &'a mut [f64],
}

impl Accumulate for ColumnSlab<'_> {
    fn add(&mut self, i: usize, j: usize, v: f64) {
        if !self.cols.contains(&j) {
            return;
        }
        let r = self.col_ptr[j]..self.col_ptr[j + 1];
        match self.row_idx[r.clone()].binary_search(&i) {
            Ok(k) => self.values[r.start + k - self.offset] += v,
            Err(_) => panic!("PatternAssembler: ({i}, {j}) is outside the mesh pattern"),
        }
    }
}

impl PatternAssembler {
    /// Assembles two matrices of the same pattern (`self` and `other`, e.g. `K` and `M`)
    /// in parallel with rayon, without locks or atomics.
    ///
    /// The nodes are cut into contiguous ranges (four per thread); a task owns the
    /// columns of its range and visits, in increasing order, every cell touching one of
    /// its nodes, calling `cell(id, k, m)`, which adds the whole element matrix and keeps
    /// what falls in the task's columns. Cells on a range border are computed by each
    /// task that touches them (a few per cent of the cells for meshes numbered with
    /// locality, as generators and Gmsh number them). Every column receives its terms in
    /// cell order, so the result does not depend on the thread count. The first error in
    /// cell order is returned.
    pub fn par_assemble_pair<E: Send>(
        &mut self,
        other: &mut Self,
        cells: &[&[usize]],
        cell: impl Fn(usize, &mut ColumnSlab, &mut ColumnSlab) -> Result<(), E> + Sync,
    ) -> Result<(), (usize, E)> {
        use rayon::prelude::*;
        assert!(
            self.col_ptr == other.col_ptr,
            "both matrices share one pattern"
        );
        let nodes = self.n / self.dim.max(1);
        let (start, of_node) = cells_of_nodes(nodes, cells);
        let chunks = (4 * rayon::current_num_threads()).clamp(1, nodes.max(1));
        let bounds: Vec<usize> = (0..=chunks).map(|c| c * nodes / chunks).collect();
        let dim = self.dim;
        let col_ptr = &self.col_ptr;
        let row_idx = &self.row_idx;
        let mut slabs = Vec::with_capacity(chunks);
        let (mut rest_a, mut rest_b) = (&mut self.values[..], &mut other.values[..]);
        for w in bounds.windows(2) {
            let (c0, c1) = (w[0] * dim, w[1] * dim);
            let len = col_ptr[c1] - col_ptr[c0];
            let (a, ra) = std::mem::take(&mut rest_a).split_at_mut(len);
            let (b, rb) = std::mem::take(&mut rest_b).split_at_mut(len);
            rest_a = ra;
            rest_b = rb;
            slabs.push((w[0]..w[1], a, b));
        }
        let errors: Vec<(usize, E)> = slabs
            .into_par_iter()
            .filter_map(|(range, a, b)| {
                let cols = range.start * dim..range.end * dim;
                let offset = col_ptr[cols.start];
                let mut ids: Vec<usize> = of_node[start[range.start]..start[range.end]].to_vec();
                ids.sort_unstable();
                ids.dedup();
                let mut sa = ColumnSlab {
                    col_ptr,
                    row_idx,
                    cols: cols.clone(),
                    offset,
                    values: a,
                };
                let mut sb = ColumnSlab {
                    col_ptr,
                    row_idx,
                    cols,
                    offset,
                    values: b,
                };
                ids.into_iter()
                    .find_map(|id| cell(id, &mut sa, &mut sb).err().map(|e| (id, e)))
            })
            .collect();
        match errors.into_iter().min_by_key(|(id, _)| *id) {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }
}

/// Dofs of a vector lent to one assembly task: contributions to other rows are skipped
/// (another task owns them).
pub struct RowSlab<'a> {
    rows: std::ops::Range<usize>,
    values: &'a mut [f64],
}

impl RowSlab<'_> {
    /// Adds `v` at row `i` if this task owns it.
    pub fn add(&mut self, i: usize, v: f64) {
        if self.rows.contains(&i) {
            self.values[i - self.rows.start] += v;
        }
    }
}

/// The cells of every node in increasing cell order, as compressed rows: node `a`'s
/// cells are `of_node[start[a]..start[a + 1]]`.
fn cells_of_nodes(nodes: usize, cells: &[&[usize]]) -> (Vec<usize>, Vec<usize>) {
    let mut start = vec![0usize; nodes + 1];
    for c in cells {
        for &a in *c {
            start[a + 1] += 1;
        }
    }
    for a in 0..nodes {
        start[a + 1] += start[a];
    }
    let mut fill = start.clone();
    let mut of_node = vec![0usize; start[nodes]];
    for (id, c) in cells.iter().enumerate() {
        for &a in *c {
            of_node[fill[a]] = id;
            fill[a] += 1;
        }
    }
    (start, of_node)
}

/// Collects element contributions for one global matrix.
pub struct Assembler {
    n: usize,
    triplets: Vec<Triplet<usize, usize, f64>>,
}

impl Assembler {
    /// An empty `n × n` matrix with room for `capacity` triplets.
    pub fn new(n: usize, capacity: usize) -> Self {
        Assembler {
            n,
            triplets: Vec::with_capacity(capacity),
        }
    }

    /// Sums duplicates into faer's compressed columns.
    pub fn finish(self) -> SparseMatrix {
        // the indices were pushed below n by the callers' own dof maps
        SparseMatrix::try_new_from_triplets(self.n, self.n, &self.triplets)
            .expect("triplet indices below the matrix size")
    }
}

/// `a·A + b·B + c·C` for square matrices of the same size (used once per time step
/// size to form the iteration matrix `M̂ = M + hθC + h²θ²K`, eq. 47).
pub fn linear_combination(terms: &[(f64, &SparseMatrix)]) -> SparseMatrix {
    let n = terms[0].1.nrows();
    // Same pattern (mesh matrices from one PatternAssembler): combine the values.
    let first = terms[0].1.as_ref();
    let same = terms.iter().all(|(_, m)| {
        let m = m.as_ref();
        m.col_ptr() == first.col_ptr() && m.row_idx() == first.row_idx()
    });
    let has_diagonal =
        (0..n).all(|j| first.row_idx()[first.col_ptr()[j]..first.col_ptr()[j + 1]].contains(&j));
    if same && has_diagonal {
        let mut values = vec![0.0; first.val().len()];
        for (s, m) in terms {
            for (v, x) in values.iter_mut().zip(m.val()) {
                *v += s * x;
            }
        }
        let sym = SymbolicSparseColMat::new_checked(
            n,
            n,
            first.col_ptr().to_vec(),
            None,
            first.row_idx().to_vec(),
        );
        return SparseMatrix::new(sym, values);
    }
    let cap = terms.iter().map(|(_, m)| m.val().len()).sum();
    let mut asm = Assembler::new(n, cap);
    for (s, m) in terms {
        if *s == 0.0 {
            continue;
        }
        let m = m.as_ref();
        for j in 0..m.ncols() {
            for k in m.col_ptr()[j]..m.col_ptr()[j + 1] {
                asm.add(m.row_idx()[k], j, s * m.val()[k]);
            }
        }
    }
    // Keep the diagonal in the pattern even if every term is zero there, so the
    // symbolic factorization sees a structurally full diagonal.
    for i in 0..n {
        asm.add(i, i, 0.0);
    }
    asm.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn duplicates_are_summed_and_arrays_survive_the_move() {
        let mut a = Assembler::new(3, 8);
        a.add_element(&[0, 1], |i, j| if i == j { 1.0 } else { -1.0 });
        a.add_element(&[1, 2], |i, j| if i == j { 2.0 } else { -2.0 });
        let m = a.finish();
        let d = m.to_dense();
        assert_eq!(d[(1, 1)], 3.0);
        assert_eq!(d[(0, 1)], -1.0);
        assert_eq!(d[(2, 1)], -2.0);
        assert_eq!(d[(0, 2)], 0.0);
        assert_eq!(m.compute_nnz(), 7);
    }
}
