//! The one traversal of the supernodal factor that forms the zone's `Z = L⁻¹PS`, the
//! tangent factor `D` (with `K`), `V = L⁻¹(DZ)` and their products into `F` and `F_E`
//! ([`Pass`], the module doc of `linalg::zone_flex`): per supernode, children first, on
//! rayon's threads by disjoint subtrees; the dense tangent of each supernode's block is
//! `tangent.rs`'s.

use faer::linalg::matmul::matmul_with_conj;
use faer::linalg::matmul::triangular::{self, BlockStructure};
use faer::linalg::triangular_solve::solve_lower_triangular_in_place_with_conj;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::cholesky::supernodal::SupernodalLltRef;
use faer::{Accum, Conj, MatMut, MatRef};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use super::tangent::tangent_block;
use super::tree::Tree;
use super::{NONE, Stiffness, par};

/// What a finished supernode leaves for its ancestors: its block of `D` (with `K`) and
/// its rows of `Z` and `V` (`size × width`, on a zone path), dropped once the last
/// supernode its pattern updates has read them.
#[derive(Default)]
struct Node {
    d: Vec<f64>,
    z: Vec<f64>,
    v: Vec<f64>,
}

/// The one traversal of the module doc: per supernode, children first, its block of
/// `D`, its rows of `Z` and `V`, and their products into `F` and `F_E` (lower
/// triangles). Disjoint subtrees are independent (a supernode reads only its
/// descendants' finished nodes and writes its own): the top of the tree runs its
/// subtrees on rayon's threads, each small subtree in order on one.
pub(super) struct Pass<'a> {
    llt: SupernodalLltRef<'a, usize, f64>,
    tree: &'a Tree,
    /// `K` in the factor's order of columns: `(fwd, inv)` and the matrix.
    k: Option<Stiffness<'a>>,
    /// Sorted zone columns `(factor row, zone index)` and each supernode's range.
    cols: &'a [(usize, usize)],
    ranges: &'a [(usize, usize)],
    /// Where the columns of each supernode's own rows start (in its range's tail).
    own_lo: &'a [usize],
    /// The supernodes `d` whose pattern meets each supernode's columns, ascending.
    updaters: Vec<Vec<usize>>,
    /// How many supernodes still have to read each node.
    pending: Vec<AtomicUsize>,
    nodes: Vec<Mutex<Node>>,
    f: Mutex<Vec<f64>>,
    fe: Mutex<Vec<f64>>,
}

/// Subtrees with fewer rows than this are visited in order by one task.
const SUBTREE_TASK_ROWS: usize = 2048;

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

impl<'a> Pass<'a> {
    pub(super) fn new(
        llt: SupernodalLltRef<'a, usize, f64>,
        tree: &'a Tree,
        k: Option<Stiffness<'a>>,
        cols: &'a [(usize, usize)],
        (ranges, own_lo): (&'a [(usize, usize)], &'a [usize]),
    ) -> Self {
        let ns = tree.end.len();
        let mut updaters: Vec<Vec<usize>> = vec![Vec::new(); ns];
        let mut pending = Vec::with_capacity(ns);
        for d in 0..ns {
            let (mut last, mut targets) = (NONE, 0);
            for &r in llt.supernode(d).pattern() {
                let t = tree.owner(r);
                if t != last {
                    updaters[t].push(d);
                    last = t;
                    targets += 1;
                }
            }
            pending.push(AtomicUsize::new(targets));
        }
        let z = cols.len();
        Pass {
            llt,
            tree,
            k,
            cols,
            ranges,
            own_lo,
            updaters,
            pending,
            nodes: (0..ns).map(|_| Mutex::new(Node::default())).collect(),
            f: Mutex::new(vec![0.0; z * z]),
            fe: Mutex::new(vec![0.0; if k.is_some() { z * z } else { 0 }]),
        }
    }

    pub(super) fn run(self) -> (Vec<f64>, Vec<f64>) {
        use rayon::prelude::*;
        let roots: Vec<usize> = (0..self.tree.end.len())
            .filter(|&s| self.tree.parent[s] == NONE)
            .collect();
        roots.par_iter().for_each(|&r| self.subtree(r));
        let z = self.cols.len();
        let mut out = [
            self.f.into_inner().unwrap_or_else(|e| e.into_inner()),
            self.fe.into_inner().unwrap_or_else(|e| e.into_inner()),
        ];
        for m in out.iter_mut().filter(|m| !m.is_empty()) {
            for j in 0..z {
                for i in j + 1..z {
                    m[j + i * z] = m[i + j * z];
                }
            }
        }
        let [f, fe] = out;
        (f, fe)
    }

    fn subtree(&self, s: usize) {
        let tree = self.tree;
        let kids = &tree.children[s];
        if tree.rows[s] < SUBTREE_TASK_ROWS || kids.is_empty() {
            let mut scratch = Vec::new();
            for &t in &tree.post[tree.first[s]..=tree.at[s]] {
                self.supernode(t, &mut scratch);
            }
        } else {
            use rayon::prelude::*;
            kids.par_iter().for_each(|&c| self.subtree(c));
            self.supernode(s, &mut Vec::new());
        }
    }

    /// Supernode `s`, its descendants finished.
    fn supernode(&self, s: usize, tmp: &mut Vec<f64>) {
        let with_d = self.k.is_some();
        let (lo, hi) = self.ranges[s];
        let w = hi - lo;
        if !with_d && w == 0 {
            return;
        }
        let sn = self.llt.supernode(s);
        let (ss, pat, ls) = (sn.start(), sn.pattern(), sn.val());
        let size = ls.ncols();
        let se = ss + size;
        let nr = size + pat.len();
        let mut node = Node::default();
        if let Some((k, perm)) = self.k {
            node.d = vec![0.0; nr * size];
            // the lower triangle of P K Pᵀ in the columns of s, scattered as faer
            // scatters Â
            for j in ss..se {
                let jj = perm.map_or(j, |(fwd, _)| fwd[j]);
                let col = &mut node.d[(j - ss) * nr..(j - ss + 1) * nr];
                for (ii, &v) in k.row_idx_of_col(jj).zip(k.val_of_col(jj)) {
                    let i = perm.map_or(ii, |(_, inv)| inv[ii]);
                    if i < j {
                        continue;
                    }
                    if i < se {
                        col[i - ss] += v;
                    } else if let Ok(p) = pat.binary_search(&i) {
                        col[size + p] += v;
                    }
                    // (outside the factor's pattern: K's pattern is inside Â's)
                }
            }
        }
        let mut zs = vec![0.0; size * w];
        let mut vs = vec![0.0; if with_d { size * w } else { 0 }];
        // the zone's unit columns whose row is in s
        for c in self.own_lo[s]..hi {
            zs[(c - lo) * size + self.cols[c].0 - ss] = 1.0;
        }
        let mut local = Vec::new();
        for &d in &self.updaters[s] {
            let (dlo, dhi) = self.ranges[d];
            let dw = dhi - dlo;
            if !with_d && dw == 0 {
                continue;
            }
            let dn = self.llt.supernode(d);
            let (dpat, ld) = (dn.pattern(), dn.val());
            let dsize = ld.ncols();
            let a = dpat.partition_point(|&r| r < ss);
            let mid = dpat[a..].partition_point(|&r| r < se);
            let rows = dpat.len() - a;
            let lmb = ld.subrows(dsize + a, rows);
            let lm = lmb.subrows(0, mid);
            let mut guard = lock(&self.nodes[d]);
            let dnode = &mut *guard;
            if with_d {
                // each updated row's place in the block of s
                local.clear();
                local.extend(dpat[a..a + mid].iter().map(|&r| r - ss));
                let mut from = 0;
                for &r in &dpat[a + mid..] {
                    from += pat[from..].partition_point(|&q| q < r);
                    local.push(size + from);
                }
                let dd = MatRef::from_column_major_slice(&dnode.d, dsize + dpat.len(), dsize);
                let dmb = dd.subrows(dsize + a, rows);
                let dm = dmb.subrows(0, mid);
                // R −= D_d L_dᵀ + L_d D_dᵀ on the rows and columns of s
                tmp.resize(rows * mid, 0.0);
                let mut t = MatMut::from_column_major_slice_mut(&mut tmp[..rows * mid], rows, mid);
                let p = par(rows * mid * dsize);
                // (the rows of s's columns: their lower triangle only)
                let (mut top, mut bot) = t.rb_mut().split_at_row_mut(mid);
                for (x, y, acc) in [(dmb, lm, Accum::Replace), (lmb, dm, Accum::Add)] {
                    let (xt, xb) = x.split_at_row(mid);
                    triangular::matmul(
                        top.rb_mut(),
                        BlockStructure::TriangularLower,
                        acc,
                        xt,
                        BlockStructure::Rectangular,
                        y.transpose(),
                        BlockStructure::Rectangular,
                        1.0,
                        p,
                    );
                    matmul_with_conj(
                        bot.rb_mut(),
                        acc,
                        xb,
                        Conj::No,
                        y.transpose(),
                        Conj::No,
                        1.0,
                        p,
                    );
                }
                for jj in 0..mid {
                    let dst = &mut node.d[local[jj] * nr..(local[jj] + 1) * nr];
                    let src = &tmp[jj * rows..(jj + 1) * rows];
                    for ii in jj..rows {
                        dst[local[ii]] -= src[ii];
                    }
                }
                if dw > 0 {
                    // V_s −= L_d V_d − D_d Z_d on the rows of s
                    let zd = MatRef::from_column_major_slice(&dnode.z, dsize, dw);
                    let vd = MatRef::from_column_major_slice(&dnode.v, dsize, dw);
                    tmp.resize(mid * dw, 0.0);
                    let mut t = MatMut::from_column_major_slice_mut(&mut tmp[..mid * dw], mid, dw);
                    let p = par(mid * dw * dsize);
                    matmul_with_conj(
                        t.rb_mut(),
                        Accum::Replace,
                        dm,
                        Conj::No,
                        zd,
                        Conj::No,
                        1.0,
                        p,
                    );
                    matmul_with_conj(t.rb_mut(), Accum::Add, lm, Conj::No, vd, Conj::No, -1.0, p);
                    scatter(tmp, &dpat[a..a + mid], ss, size, dlo - lo, &mut vs, 1.0);
                }
            }
            if dw > 0 {
                // Z_s −= L_d Z_d on the rows of s
                let zd = MatRef::from_column_major_slice(&dnode.z, dsize, dw);
                tmp.resize(mid * dw, 0.0);
                let mut t = MatMut::from_column_major_slice_mut(&mut tmp[..mid * dw], mid, dw);
                matmul_with_conj(
                    t.rb_mut(),
                    Accum::Replace,
                    lm,
                    Conj::No,
                    zd,
                    Conj::No,
                    1.0,
                    par(mid * dw * dsize),
                );
                scatter(tmp, &dpat[a..a + mid], ss, size, dlo - lo, &mut zs, -1.0);
            }
            // the last reader frees d's node
            if self.pending[d].fetch_sub(1, Ordering::AcqRel) == 1 {
                *dnode = Node::default();
            }
        }
        let (lt, lb) = ls.split_at_row(size);
        if with_d {
            tangent_block(lt, lb, &mut node.d, size, nr);
        }
        if w > 0 {
            let pz = par(size * size * w);
            let mut zm = MatMut::from_column_major_slice_mut(&mut zs, size, w);
            solve_lower_triangular_in_place_with_conj(lt, Conj::No, zm.rb_mut(), pz);
            let zm = zm.rb();
            let pf = par(w * w * size);
            {
                let mut f = lock(&self.f);
                let z = self.cols.len();
                let mut fm = MatMut::from_column_major_slice_mut(&mut f, z, z);
                triangular::matmul(
                    fm.rb_mut().submatrix_mut(lo, lo, w, w),
                    BlockStructure::TriangularLower,
                    Accum::Add,
                    zm.transpose(),
                    BlockStructure::Rectangular,
                    zm,
                    BlockStructure::Rectangular,
                    1.0,
                    pf,
                );
            }
            if with_d {
                let dt = MatRef::from_column_major_slice(&node.d, nr, size)
                    .split_at_row(size)
                    .0;
                let mut vm = MatMut::from_column_major_slice_mut(&mut vs, size, w);
                triangular::matmul(
                    vm.rb_mut(),
                    BlockStructure::Rectangular,
                    Accum::Add,
                    dt,
                    BlockStructure::TriangularLower,
                    zm,
                    BlockStructure::Rectangular,
                    1.0,
                    pz,
                );
                solve_lower_triangular_in_place_with_conj(lt, Conj::No, vm.rb_mut(), pz);
                let vm = vm.rb();
                let mut fe = lock(&self.fe);
                let z = self.cols.len();
                let mut fem = MatMut::from_column_major_slice_mut(&mut fe, z, z);
                let mut blk = fem.rb_mut().submatrix_mut(lo, lo, w, w);
                for (x, y) in [(zm, vm), (vm, zm)] {
                    triangular::matmul(
                        blk.rb_mut(),
                        BlockStructure::TriangularLower,
                        Accum::Add,
                        x.transpose(),
                        BlockStructure::Rectangular,
                        y,
                        BlockStructure::Rectangular,
                        1.0,
                        pf,
                    );
                }
            }
        }
        // kept for the ancestors (a root has none)
        if !pat.is_empty() {
            node.z = zs;
            node.v = vs;
            if !with_d {
                node.d = Vec::new();
            }
            *lock(&self.nodes[s]) = node;
        }
        let _ = lb;
    }
}

/// `x[rows, off..] += sign · t` for the `mid × w` block `t` whose row `i` is factor row
/// `rows[i]` of the supernode starting at `ss` (`x` is `size × ·`, column-major).
fn scatter(
    t: &[f64],
    rows: &[usize],
    ss: usize,
    size: usize,
    off: usize,
    x: &mut [f64],
    sign: f64,
) {
    let mid = rows.len();
    if mid == 0 {
        return;
    }
    for (c, src) in t.chunks_exact(mid).enumerate() {
        let dst = &mut x[(c + off) * size..(c + off + 1) * size];
        for (&r, &v) in rows.iter().zip(src) {
            dst[r - ss] += sign * v;
        }
    }
}
