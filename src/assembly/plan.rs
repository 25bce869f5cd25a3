//! [`AssemblyPlan`]: a matrix and a vector refilled many times on one pattern (the
//! tangents and forces of a large-deformation body at every Newton iterate): the cells
//! batched, each task owning a range of nodes, nothing reserved per call, the same bits
//! on any thread count.

use super::*;

/// One task of an [`AssemblyPlan`]: a range of nodes and where its cells start.
pub(super) struct PlanTask {
    pub(super) nodes: std::ops::Range<usize>,
    pub(super) cells: std::ops::Range<usize>,
}

/// The parallel assembly of a matrix and a vector on a mesh's fixed pattern, planned
/// once (the pattern, the cut of the nodes into task ranges, each task's cells in
/// increasing order), so that [`AssemblyPlan::assemble`] reserves nothing: the Newton
/// loop of a nonlinear structure fills its tangent `K_t` and internal force `f_int`
/// at every iterate. Each column and each row of the vector receives its terms in cell
/// order whatever the cut, so the result does not depend on the thread count
/// (the scheme of [`PatternAssembler::par_assemble_pair`]).
pub struct AssemblyPlan {
    pub(super) n: usize,
    pub(super) dim: usize,
    pub(super) col_ptr: Vec<usize>,
    pub(super) row_idx: Vec<usize>,
    pub(super) tasks: Vec<PlanTask>,
    pub(super) task_cells: Vec<usize>,
    /// Nodes of every cell, compressed: cell `c`'s are `cell_nodes[cell_ptr[c]..cell_ptr[c + 1]]`.
    pub(super) cell_ptr: Vec<usize>,
    pub(super) cell_nodes: Vec<usize>,
}

/// Cells evaluated per batch of [`AssemblyPlan::assemble_batched`].
pub const ELEMENT_BATCH: usize = 1024;

/// Element buffers of [`AssemblyPlan::assemble_batched`]: the forces and matrices of
/// one batch of cells, sized once.
#[derive(Debug)]
pub struct ElementBatch {
    pub(super) nd: usize,
    pub(super) cap: usize,
    pub(super) fe: Vec<f64>,
    pub(super) ke: Vec<f64>,
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
    pub(super) fn scatter_batch(
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
    pub(super) fn split_vector(
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
    pub(super) fn split<E: Send>(
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
