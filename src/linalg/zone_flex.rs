//! The contact zone's flexibilities from the supernodal factor, without a full sweep
//! (issue 35 §3): `F = SᵀÂ⁻¹S` and `F_E = SᵀÂ⁻¹KÂ⁻¹S` for the `z` unit columns `S`
//! of the zone (the condensed Delassus data of contacts between bodies, eq. 56–60 with
//! the `M̂⁻¹` metric: `W = BᵀFB`, `W_D = BᵀF_E B`).
//!
//! With `PÂPᵀ = LLᵀ` and `Z = L⁻¹PS`, `F = ZᵀZ`. The columns of `Z` are supported on
//! the elimination-tree paths from their zone rows to the root, so `Z` is computed by
//! forward sweeps that touch only those supernodes, and `F` supernode by supernode as
//! `Σ_s Z_sᵀZ_s` (the rows of `Z` in supernode `s` pair only the columns whose zone
//! row lies in the subtree of `s`).
//!
//! `F_E = −dF/dε` for `Â + εK`. Differentiating `LLᵀ = Â` along `K` gives the tangent
//! factor `D = dL/dε` (the pattern of `L`, `L Dᵀ + D Lᵀ = PKPᵀ`), supernode by
//! supernode as faer's left-looking factorization forms `L`:
//! `D_tt = L_tt Φ(L_tt⁻¹ R_tt L_tt⁻ᵀ)` (`Φ` the lower triangle with the diagonal
//! halved) and `D_bt = (R_bt − L_bt D_ttᵀ) L_tt⁻ᵀ`, where `R` is `PKPᵀ` less the
//! descendants' updates `D_d L_dᵀ + L_d D_dᵀ`. Then `dZ = −L⁻¹DZ`, and with
//! `V = L⁻¹(DZ)` (again supported on the paths of `Z`) `F_E = ZᵀV + VᵀZ`.
//!
//! The full-sweep form it replaces needs, per zone column, a backward sweep over the
//! whole factor (for `Â⁻¹S`) and a forward one (for `Â⁻¹K Â⁻¹S`); here the cost is one
//! more factorization's worth of dense kernels and the products on the zone's paths.
//! No subtraction of nearly equal terms enters (the tangent of a Cholesky factor is as
//! well conditioned as the factor), so small steps, where `h²θ²K ≪ M`, lose no digits.
//! Written here because faer differentiates no factorization; the kernels (triangular
//! solves, products) are faer's.

use faer::linalg::matmul::matmul_with_conj;
use faer::linalg::matmul::triangular::{self, BlockStructure};
use faer::linalg::triangular_solve::solve_lower_triangular_in_place_with_conj;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::SparseColMatRef;
use faer::sparse::linalg::cholesky::SymbolicCholeskyRaw;
use faer::sparse::linalg::cholesky::supernodal::SupernodalLltRef;
use faer::{Accum, Conj, Mat, MatMut, MatRef, Par};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use super::{Backend, SpdFactor};

const NONE: usize = usize::MAX;

/// A factor's permutation `(fwd, inv)` (`None`: the identity).
type Perm<'a> = Option<(&'a [usize], &'a [usize])>;

/// `K` with the factor's permutation.
type Stiffness<'a> = (SparseColMatRef<'a, usize, f64>, Perm<'a>);

/// Blocks with fewer multiply-adds than this run their kernels sequentially.
const PAR_WORK: usize = 1 << 22;

fn par(work: usize) -> Par {
    if work >= PAR_WORK {
        Par::rayon(0)
    } else {
        Par::Seq
    }
}

impl super::SpdAnalysis {
    /// Entries of `Z = L⁻¹PS` on the tree paths of the dofs `zone` (original indices):
    /// `Σ_s cols(s) · reach(s)` over the supernodes `s`, `reach(s)` the zone columns in
    /// the subtree of `s`; what [`SpdFactor::zone_flexibilities`] may hold beside `F`
    /// (its pass frees a block after its last reader, so this is an upper bound), for
    /// the memory plan. `None` for a simplicial analysis (no such pass).
    pub fn zone_path_entries(&self, zone: &[usize]) -> Option<u64> {
        let SymbolicCholeskyRaw::Supernodal(sym) = self.symbolic.raw() else {
            return None;
        };
        let ns = sym.n_supernodes();
        let begin = &sym.supernode_begin()[..ns];
        let end = &sym.supernode_end()[..ns];
        let owner = |r: usize| end.partition_point(|&e| e <= r);
        let perm = self.symbolic.perm().map(|p| p.arrays());
        let mut reach = vec![0u64; ns];
        for &d in zone {
            let c = perm.map_or(d, |(_, inv)| inv[d]);
            if c >= *end.last()? {
                return None;
            }
            reach[owner(c)] += 1;
        }
        let (ptr, rows) = (sym.col_ptr_for_row_idx(), sym.row_idx());
        let mut total = 0u64;
        for s in 0..ns {
            total += (end[s] - begin[s]) as u64 * reach[s];
            // the parent owns the first row below the supernode (indices grow upward)
            if ptr[s] < ptr[s + 1] {
                let p = owner(rows[ptr[s]]);
                if p > s && p < ns {
                    reach[p] += reach[s];
                }
            }
        }
        Some(total)
    }
}

impl SpdFactor {
    /// `F` and (when `k` is given) `F_E` of the module doc for the zone `zone`
    /// (original dof indices), both `z × z` column-major in the order of `zone`
    /// (`F_E` empty without `k`). `None` when the factor is not supernodal (the caller
    /// then sweeps). `k` must hold both triangles (as every stiffness here does) on a
    /// pattern inside `Â`'s. Allocates: a set-up's work.
    pub fn zone_flexibilities(
        &self,
        zone: &[usize],
        k: Option<SparseColMatRef<'_, usize, f64>>,
    ) -> Option<(Vec<f64>, Vec<f64>)> {
        let Backend::Faer(f) = &self.backend else {
            return None;
        };
        if f.simplicial.is_some() {
            return None;
        }
        let SymbolicCholeskyRaw::Supernodal(sym) = f.symbolic.raw() else {
            return None;
        };
        let llt = SupernodalLltRef::<usize, f64>::new(sym, &f.values);
        let perm = f.symbolic.perm().map(|p| p.arrays());
        let tree = Tree::new(llt)?;
        let inv = |d: usize| perm.map_or(d, |(_, inv)| inv[d]);
        // the zone's columns in the postorder of their supernodes: a subtree's zone
        // rows are then one range of columns
        let (cols, ranges, own_lo) = tree.sorted_columns(zone.iter().map(|&d| inv(d)));
        let with_k = k.is_some();
        let (fs, fes) =
            Pass::new(llt, &tree, k.map(|k| (k, perm)), &cols, (&ranges, &own_lo)).run();
        // back to the zone's order
        let z = zone.len();
        let unsort = |xs: &[f64]| {
            let mut out = vec![0.0; xs.len()];
            for (c2, &(_, k2)) in cols.iter().enumerate() {
                for (c1, &(_, k1)) in cols.iter().enumerate() {
                    out[k1 + k2 * z] = xs[c1 + c2 * z];
                }
            }
            out
        };
        let f = unsort(&fs);
        drop(fs);
        let fe = if with_k { unsort(&fes) } else { Vec::new() };
        Some((f, fe))
    }
}

/// The supernodal elimination tree: each supernode's end, parent and
/// children, a postorder of it (faer numbers supernodes children first, but a
/// subtree's supernodes need not be consecutive) and each subtree's rows.
struct Tree {
    end: Vec<usize>,
    parent: Vec<usize>,
    children: Vec<Vec<usize>>,
    /// The supernodes in postorder; the subtree of `s` is `post[first[s]..=at[s]]`.
    post: Vec<usize>,
    at: Vec<usize>,
    first: Vec<usize>,
    /// Rows of the factor in each subtree.
    rows: Vec<usize>,
}

impl Tree {
    fn new(llt: SupernodalLltRef<'_, usize, f64>) -> Option<Self> {
        let sym = llt.symbolic();
        let ns = sym.n_supernodes();
        let begin = sym.supernode_begin()[..ns].to_vec();
        let end = sym.supernode_end()[..ns].to_vec();
        let owner = |r: usize| end.partition_point(|&e| e <= r);
        let mut parent = Vec::with_capacity(ns);
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); ns];
        let mut rows: Vec<usize> = (0..ns).map(|s| end[s] - begin[s]).collect();
        for s in 0..ns {
            let p = llt
                .supernode(s)
                .pattern()
                .first()
                .map_or(NONE, |&r| owner(r));
            // the traversals visit children before parents
            if p != NONE && p <= s {
                return None;
            }
            if p != NONE {
                children[p].push(s);
                rows[p] += rows[s];
            }
            parent.push(p);
        }
        // postorder by an explicit stack (a tree can be thousands deep)
        let (mut post, mut at, mut first) = (Vec::with_capacity(ns), vec![0; ns], vec![0; ns]);
        let mut stack: Vec<(usize, usize)> = Vec::new();
        for root in (0..ns).filter(|&s| parent[s] == NONE) {
            stack.push((root, 0));
            first[root] = post.len();
            while let Some(&mut (s, ref mut next)) = stack.last_mut() {
                if let Some(&c) = children[s].get(*next) {
                    *next += 1;
                    first[c] = post.len();
                    stack.push((c, 0));
                } else {
                    at[s] = post.len();
                    post.push(s);
                    stack.pop();
                }
            }
        }
        Some(Tree {
            end,
            parent,
            children,
            post,
            at,
            first,
            rows,
        })
    }

    /// The supernode holding factor row `r`.
    fn owner(&self, r: usize) -> usize {
        self.end.partition_point(|&e| e <= r)
    }

    /// The zone's columns `(factor row, zone index)` sorted by the postorder of their
    /// supernodes (then by row), and for each supernode the range of them whose row
    /// lies in its subtree and the start of those in itself (the range's tail).
    #[allow(clippy::type_complexity)]
    fn sorted_columns(
        &self,
        rows: impl Iterator<Item = usize>,
    ) -> (Vec<(usize, usize)>, Vec<(usize, usize)>, Vec<usize>) {
        let ns = self.end.len();
        let mut cols: Vec<(usize, usize)> = rows.enumerate().map(|(c, p)| (p, c)).collect();
        cols.sort_unstable_by_key(|&(p, _)| (self.at[self.owner(p)], p));
        let mut own = vec![0usize; ns];
        for &(p, _) in &cols {
            own[self.owner(p)] += 1;
        }
        // a subtree's columns are those of its postorder range
        let mut before = vec![0usize; ns + 1];
        for (i, &s) in self.post.iter().enumerate() {
            before[i + 1] = before[i] + own[s];
        }
        let ranges = (0..ns)
            .map(|s| (before[self.first[s]], before[self.at[s] + 1]))
            .collect();
        let own_lo = (0..ns).map(|s| before[self.at[s]]).collect();
        (cols, ranges, own_lo)
    }
}

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
struct Pass<'a> {
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
    fn new(
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

    fn run(self) -> (Vec<f64>, Vec<f64>) {
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

/// The block of `D` of one supernode from its accumulated `R` (`d`, `nr × size`,
/// column-major, the lower triangle of its top block meaningful):
/// `D_tt = L_tt Φ(L_tt⁻¹ R_tt L_tt⁻ᵀ)`, `D_bt = (R_bt − L_bt D_ttᵀ) L_tt⁻ᵀ`.
fn tangent_block(lt: MatRef<'_, f64>, lb: MatRef<'_, f64>, d: &mut [f64], size: usize, nr: usize) {
    let ds = MatMut::from_column_major_slice_mut(d, nr, size);
    let (mut dt, mut db) = ds.split_at_row_mut(size);
    tangent_dense(lt, dt.rb_mut());
    let dt = dt.rb();
    let pb = par((nr - size) * size * size);
    triangular::matmul(
        db.rb_mut(),
        BlockStructure::Rectangular,
        Accum::Add,
        lb,
        BlockStructure::Rectangular,
        dt.transpose(),
        BlockStructure::TriangularUpper,
        -1.0,
        pb,
    );
    solve_lower_triangular_in_place_with_conj(lt, Conj::No, db.rb_mut().transpose_mut(), pb);
}

/// Dense blocks up to this order take the tangent by `Φ` directly; larger ones halve.
const TANGENT_LEAF: usize = 48;

/// The tangent `D` of the dense Cholesky factor `L` (`l`, lower) along the symmetric
/// `R` held in the lower triangle of `d`, overwritten by `D` (upper triangle zeroed):
/// `D = L Φ(L⁻¹ R L⁻ᵀ)` on small blocks; on larger ones by halves, as a blocked
/// Cholesky goes: `D₁₁` of `R₁₁`, `D₂₁ = (R₂₁ − L₂₁ D₁₁ᵀ) L₁₁⁻ᵀ`, then `D₂₂` of
/// `R₂₂ − D₂₁ L₂₁ᵀ − L₂₁ D₂₁ᵀ` (a third of the direct form's flops on large blocks).
fn tangent_dense(l: MatRef<'_, f64>, mut d: MatMut<'_, f64>) {
    let size = l.nrows();
    if size <= TANGENT_LEAF {
        let mut x = Mat::<f64>::zeros(size, size);
        for j in 0..size {
            for i in j..size {
                x[(i, j)] = d[(i, j)];
                x[(j, i)] = d[(i, j)];
            }
        }
        solve_lower_triangular_in_place_with_conj(l, Conj::No, x.as_mut(), Par::Seq);
        let mut phi = x.transpose().to_owned();
        solve_lower_triangular_in_place_with_conj(l, Conj::No, phi.as_mut(), Par::Seq);
        for j in 0..size {
            phi[(j, j)] *= 0.5;
            for i in 0..j {
                phi[(i, j)] = 0.0;
            }
        }
        triangular::matmul(
            d.rb_mut(),
            BlockStructure::Rectangular,
            Accum::Replace,
            l,
            BlockStructure::TriangularLower,
            phi.as_ref(),
            BlockStructure::TriangularLower,
            1.0,
            Par::Seq,
        );
        for j in 0..size {
            for i in 0..j {
                d[(i, j)] = 0.0;
            }
        }
        return;
    }
    let h = size / 2;
    let (l11, _, l21, l22) = l.split_at(h, h);
    let (mut d11, mut d12, mut d21, mut d22) = d.split_at_mut(h, h);
    tangent_dense(l11, d11.rb_mut());
    let d11 = d11.rb();
    let p = par(size * h * h);
    triangular::matmul(
        d21.rb_mut(),
        BlockStructure::Rectangular,
        Accum::Add,
        l21,
        BlockStructure::Rectangular,
        d11.transpose(),
        BlockStructure::TriangularUpper,
        -1.0,
        p,
    );
    solve_lower_triangular_in_place_with_conj(l11, Conj::No, d21.rb_mut().transpose_mut(), p);
    for (x, y) in [(d21.rb(), l21), (l21, d21.rb())] {
        triangular::matmul(
            d22.rb_mut(),
            BlockStructure::TriangularLower,
            Accum::Add,
            x,
            BlockStructure::Rectangular,
            y.transpose(),
            BlockStructure::Rectangular,
            -1.0,
            p,
        );
    }
    tangent_dense(l22, d22);
    d12.fill(0.0);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::SparseMatrix;
    use faer::sparse::Triplet;

    /// Two uncoupled bodies, each a 3-D grid with the 27-point coupling of a hex8 mesh:
    /// `K` a stencil, `Â = M + aK` with a diagonal `M`. `F` and `F_E` of the zone (one
    /// face of each body, in a scrambled order) against `SᵀÂ⁻¹S` and `SᵀÂ⁻¹KÂ⁻¹S` by
    /// full solves, at a coefficient where `aK` dominates and one where `M` does (the
    /// small-step case a subtraction would lose). Tolerance 1e-12 of the largest entry:
    /// both are backward-stable computations through the same factor, their difference
    /// a few hundred roundings of the factor's entries.
    #[test]
    fn flexibilities_match_full_solves() {
        let g = 11usize;
        let n = 2 * g * g * g;
        let id = crate::linalg::test_grids::grid_id(g);
        let kt = crate::linalg::test_grids::two_grids(
            g,
            |c| 26.5 + (c % 7) as f64,
            |c, o| -0.6 - ((c + o) % 3) as f64 * 0.1,
        );
        let mt: Vec<_> = (0..n)
            .map(|c| Triplet::new(c, c, 1.0 + (c % 5) as f64 * 0.1))
            .collect();
        let k = SparseMatrix::try_new_from_triplets(n, n, &kt).unwrap();
        let mut zone: Vec<usize> = (0..2)
            .flat_map(|b| (0..g).flat_map(move |i| (0..g).map(move |j| id(b, i, j, 0))))
            .collect();
        // a scrambled zone order: the results come back in it
        zone.reverse();
        zone.swap(3, 70);
        let z = zone.len();
        for a in [10.0, 1e-6] {
            let mut at = mt.clone();
            at.extend(kt.iter().map(|t| Triplet::new(t.row, t.col, a * t.val)));
            let ahat = SparseMatrix::try_new_from_triplets(n, n, &at).unwrap();
            let mut fac = SpdFactor::new(ahat.as_ref(), "test").unwrap();
            assert!(
                matches!(&fac.backend, Backend::Faer(ff) if ff.simplicial.is_none()),
                "the test needs a supernodal factor"
            );
            let (f, fe) = fac
                .zone_flexibilities(&zone, Some(k.as_ref()))
                .expect("supernodal, postordered");
            let (f1, fe1) = fac.zone_flexibilities(&zone, None).unwrap();
            assert_eq!(f, f1, "F does not depend on K");
            assert!(fe1.is_empty());
            // references by full solves
            let mut y = vec![0.0; n * z];
            for (c, &d) in zone.iter().enumerate() {
                y[c * n + d] = 1.0;
            }
            fac.solve_block_in_place(&mut y, z);
            let mut e = vec![0.0; n * z];
            for c in 0..z {
                crate::linalg::spmv(
                    k.as_ref(),
                    &y[c * n..(c + 1) * n],
                    &mut e[c * n..(c + 1) * n],
                );
            }
            fac.solve_block_in_place(&mut e, z);
            for (got, full, what) in [(&f, &y, "F"), (&fe, &e, "F_E")] {
                let scale = (0..z * z)
                    .map(|q| full[(q / z) * n + zone[q % z]].abs())
                    .fold(0.0_f64, f64::max);
                assert!(scale > 0.0);
                for c2 in 0..z {
                    for c1 in 0..z {
                        let want = full[c2 * n + zone[c1]];
                        let have = got[c1 + c2 * z];
                        assert!(
                            (want - have).abs() <= 1e-12 * scale,
                            "{what} a = {a} ({c1}, {c2}): {have} vs {want} (scale {scale})"
                        );
                    }
                }
            }
        }
    }
}
