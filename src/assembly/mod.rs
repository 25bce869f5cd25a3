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

/// One task of an [`AssemblyPlan`]: a range of nodes and where its cells start.
struct PlanTask {
    nodes: std::ops::Range<usize>,
    cells: std::ops::Range<usize>,
}

/// The parallel assembly of a matrix and a vector on a mesh's fixed pattern, planned
/// once (the pattern, the cut of the nodes into task ranges, each task's cells in
/// increasing order), so that [`AssemblyPlan::assemble`] reserves nothing: the Newton
/// loop of a nonlinear structure fills its tangent `K_t` and internal force `f_int`
/// at every iterate. Each column and each row of the vector receives its terms in cell
/// order whatever the cut, so the result does not depend on the thread count
/// (the scheme of [`PatternAssembler::par_assemble_pair`]).
pub struct AssemblyPlan {
    n: usize,
    dim: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    tasks: Vec<PlanTask>,
    task_cells: Vec<usize>,
    /// Nodes of every cell, compressed: cell `c`'s are `cell_nodes[cell_ptr[c]..cell_ptr[c + 1]]`.
    cell_ptr: Vec<usize>,
    cell_nodes: Vec<usize>,
}

/// Cells evaluated per batch of [`AssemblyPlan::assemble_batched`].
pub const ELEMENT_BATCH: usize = 1024;

/// Element buffers of [`AssemblyPlan::assemble_batched`]: the forces and matrices of
/// one batch of cells, sized once.
#[derive(Debug)]
pub struct ElementBatch {
    nd: usize,
    cap: usize,
    fe: Vec<f64>,
    ke: Vec<f64>,
}

impl AssemblyPlan {
    /// Plans the assembly of `cells` (node lists) over `nodes` nodes with `dim` dofs
    /// each, in four tasks per thread of the current rayon pool.
    pub fn new(nodes: usize, dim: usize, cells: &[&[usize]]) -> Self {
        let pattern = PatternAssembler::new(nodes, dim, cells);
        let (start, of_node) = cells_of_nodes(nodes, cells);
        let chunks = (4 * rayon::current_num_threads()).clamp(1, nodes.max(1));
        let mut tasks = Vec::with_capacity(chunks);
        let mut task_cells = Vec::new();
        for c in 0..chunks {
            let (a, b) = (c * nodes / chunks, (c + 1) * nodes / chunks);
            let first = task_cells.len();
            let mut ids: Vec<usize> = of_node[start[a]..start[b]].to_vec();
            ids.sort_unstable();
            ids.dedup();
            task_cells.extend_from_slice(&ids);
            tasks.push(PlanTask {
                nodes: a..b,
                cells: first..task_cells.len(),
            });
        }
        let mut cell_ptr = Vec::with_capacity(cells.len() + 1);
        cell_ptr.push(0);
        let mut cell_nodes = Vec::with_capacity(cells.iter().map(|c| c.len()).sum());
        for c in cells {
            cell_nodes.extend_from_slice(c);
            cell_ptr.push(cell_nodes.len());
        }
        AssemblyPlan {
            n: pattern.n,
            dim,
            col_ptr: pattern.col_ptr,
            row_idx: pattern.row_idx,
            tasks,
            task_cells,
            cell_ptr,
            cell_nodes,
        }
    }

    /// Buffers for [`AssemblyPlan::assemble_batched`] with element matrices of up to
    /// `nd` dofs (`nd²` values per cell, [`ELEMENT_BATCH`] cells).
    pub fn batch(&self, nd: usize) -> ElementBatch {
        let cap = ELEMENT_BATCH.min(self.cell_ptr.len() - 1).max(1);
        ElementBatch {
            nd,
            cap,
            fe: vec![0.0; cap * nd],
            ke: vec![0.0; cap * nd * nd],
        }
    }

    /// Like [`AssemblyPlan::assemble`], but every cell is evaluated once: cells are
    /// evaluated in parallel a batch at a time into `batch` (`cell(id, fe, ke)` writes
    /// the element vector and, when `values` is given, the column-major element matrix,
    /// ordered as the cell's nodes, `dim` dofs each), then each task adds the batch's
    /// terms to the columns and rows of its nodes. Every column and row receives its
    /// terms in cell order, so the sums are those of [`AssemblyPlan::assemble`], bit for
    /// bit, on any thread count. The first error in cell order is returned. Reserves
    /// nothing.
    pub fn assemble_batched<E: Send>(
        &self,
        mut values: Option<&mut [f64]>,
        vector: &mut [f64],
        batch: &mut ElementBatch,
        cell: impl Fn(usize, &mut [f64], Option<&mut [f64]>) -> Result<(), E> + Sync,
    ) -> Result<(), (usize, E)> {
        use rayon::prelude::*;
        assert_eq!(vector.len(), self.n, "a vector of the plan's order");
        if let Some(v) = values.as_deref_mut() {
            assert_eq!(v.len(), self.row_idx.len(), "values on the plan's pattern");
            v.fill(0.0);
        }
        vector.fill(0.0);
        let cells = self.cell_ptr.len() - 1;
        let (nd, cap, with_matrix) = (batch.nd, batch.cap, values.is_some());
        let mut c0 = 0;
        while c0 < cells {
            let c1 = (c0 + cap).min(cells);
            let k = c1 - c0;
            let fe = &mut batch.fe[..k * nd];
            let ke = &mut batch.ke[..if with_matrix { k * nd * nd } else { 0 }];
            let err = if with_matrix {
                fe.par_chunks_mut(nd)
                    .zip(ke.par_chunks_mut(nd * nd))
                    .enumerate()
                    .find_map_first(|(i, (f, m))| {
                        cell(c0 + i, f, Some(m)).err().map(|e| (c0 + i, e))
                    })
            } else {
                fe.par_chunks_mut(nd)
                    .enumerate()
                    .find_map_first(|(i, f)| cell(c0 + i, f, None).err().map(|e| (c0 + i, e)))
            };
            if let Some(e) = err {
                return Err(e);
            }
            let (fe, ke) = (&batch.fe[..], &batch.ke[..]);
            match values.as_deref_mut() {
                Some(v) => {
                    let run = |t: &PlanTask, vals: &mut [f64], vec: &mut [f64]| {
                        self.scatter_batch(t, (c0, c1), (fe, ke, nd), vals, vec);
                        None::<(usize, E)>
                    };
                    self.split(&self.tasks, v, vector, &run);
                }
                None => {
                    let run = |t: &PlanTask, vec: &mut [f64]| {
                        self.scatter_batch(t, (c0, c1), (fe, ke, nd), &mut [], vec);
                    };
                    self.split_vector(&self.tasks, vector, &run);
                }
            }
            c0 = c1;
        }
        Ok(())
    }

    /// Adds the terms of cells `c0..c1` (evaluated into `fe`, `ke`) that fall in task
    /// `t`'s rows and, unless `vals` is empty, columns, in cell order.
    fn scatter_batch(
        &self,
        t: &PlanTask,
        (c0, c1): (usize, usize),
        (fe, ke, nd): (&[f64], &[f64], usize),
        vals: &mut [f64],
        vec: &mut [f64],
    ) {
        let with_matrix = !vals.is_empty();
        let dim = self.dim;
        let ids = &self.task_cells[t.cells.clone()];
        let lo = ids.partition_point(|&c| c < c0);
        let hi = ids.partition_point(|&c| c < c1);
        let (col0, row0) = (self.col_ptr[t.nodes.start * dim], t.nodes.start * dim);
        for &id in &ids[lo..hi] {
            let i = id - c0;
            let nodes = &self.cell_nodes[self.cell_ptr[id]..self.cell_ptr[id + 1]];
            let ne = dim * nodes.len();
            let f = &fe[i * nd..i * nd + ne];
            for (a, &v) in nodes.iter().enumerate() {
                if !t.nodes.contains(&v) {
                    continue;
                }
                for c in 0..dim {
                    vec[dim * v + c - row0] += f[dim * a + c];
                }
                if !with_matrix {
                    continue;
                }
                let m = &ke[i * nd * nd..(i + 1) * nd * nd];
                for c in 0..dim {
                    let (lc, j) = (dim * a + c, dim * v + c);
                    let r = self.col_ptr[j]..self.col_ptr[j + 1];
                    let rows = &self.row_idx[r.clone()];
                    for (b, &w) in nodes.iter().enumerate() {
                        // the node's rows are contiguous in the sorted column
                        let k = rows.partition_point(|&x| x < dim * w);
                        for d in 0..dim {
                            vals[r.start + k + d - col0] += m[(dim * b + d) + lc * ne];
                        }
                    }
                }
            }
        }
    }

    /// [`AssemblyPlan::split`] for a vector alone (no matrix values).
    fn split_vector(
        &self,
        tasks: &[PlanTask],
        vector: &mut [f64],
        run: &(impl Fn(&PlanTask, &mut [f64]) + Sync),
    ) {
        match tasks {
            [] => {}
            [t] => run(t, vector),
            _ => {
                let (left, right) = tasks.split_at(tasks.len() / 2);
                let border = right[0].nodes.start * self.dim;
                let row0 = left[0].nodes.start * self.dim;
                let (xa, xb) = vector.split_at_mut(border - row0);
                rayon::join(
                    || self.split_vector(left, xa, run),
                    || self.split_vector(right, xb, run),
                );
            }
        }
    }

    /// Order of the matrix (`nodes · dim`).
    pub fn order(&self) -> usize {
        self.n
    }

    /// Entries of the pattern (the length of the values [`AssemblyPlan::assemble`] fills).
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// The matrix of `values` on this pattern (allocates: for set-ups and checks).
    pub fn matrix(&self, values: &[f64]) -> SparseMatrix {
        let sym = SymbolicSparseColMat::new_checked(
            self.n,
            self.n,
            self.col_ptr.clone(),
            None,
            self.row_idx.clone(),
        );
        SparseMatrix::new(sym, values.to_vec())
    }

    /// Zeroes `values` (`nnz` entries) and `vector` (`dim` entries), then calls
    /// `cell(id, matrix, vector)` for every cell in parallel; the closure adds the whole
    /// element matrix and vector and keeps what falls in its task's columns and rows.
    /// The first error in cell order is returned. Reserves nothing.
    pub fn assemble<E: Send>(
        &self,
        values: &mut [f64],
        vector: &mut [f64],
        cell: impl Fn(usize, &mut ColumnSlab, &mut RowSlab) -> Result<(), E> + Sync,
    ) -> Result<(), (usize, E)> {
        assert_eq!(
            values.len(),
            self.row_idx.len(),
            "values on the plan's pattern"
        );
        assert_eq!(vector.len(), self.n, "a vector of the plan's order");
        values.fill(0.0);
        vector.fill(0.0);
        let (dim, col_ptr, row_idx) = (self.dim, &self.col_ptr[..], &self.row_idx[..]);
        let run = |t: &PlanTask, vals: &mut [f64], vec: &mut [f64]| {
            let cols = t.nodes.start * dim..t.nodes.end * dim;
            let mut m = ColumnSlab {
                col_ptr,
                row_idx,
                offset: col_ptr[cols.start],
                cols: cols.clone(),
                values: vals,
            };
            let mut v = RowSlab {
                rows: cols,
                values: vec,
            };
            self.task_cells[t.cells.clone()]
                .iter()
                .find_map(|&id| cell(id, &mut m, &mut v).err().map(|e| (id, e)))
        };
        let err = self.split(&self.tasks, values, vector, &run);
        match err {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    /// Runs `run` on every task: halves the task list, cuts the values and the vector at
    /// the halves' border and recurses on both with `rayon::join` (stack jobs only, no
    /// heap); the first error in cell order wins.
    fn split<E: Send>(
        &self,
        tasks: &[PlanTask],
        values: &mut [f64],
        vector: &mut [f64],
        run: &(impl Fn(&PlanTask, &mut [f64], &mut [f64]) -> Option<(usize, E)> + Sync),
    ) -> Option<(usize, E)> {
        match tasks {
            [] => None,
            [t] => run(t, values, vector),
            _ => {
                let (left, right) = tasks.split_at(tasks.len() / 2);
                let border = right[0].nodes.start * self.dim;
                let col0 = left[0].nodes.start * self.dim;
                let (va, vb) = values.split_at_mut(self.col_ptr[border] - self.col_ptr[col0]);
                let (xa, xb) = vector.split_at_mut(border - col0);
                let (ea, eb) = rayon::join(
                    || self.split(left, va, xa, run),
                    || self.split(right, vb, xb, run),
                );
                match (ea, eb) {
                    (Some(a), Some(b)) => Some(if a.0 <= b.0 { a } else { b }),
                    (a, b) => a.or(b),
                }
            }
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
