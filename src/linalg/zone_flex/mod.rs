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
//!
//! By file: this one the entry points ([`SpdFactor::zone_flexibilities`], the memory
//! plan's `SpdAnalysis::zone_path_entries`) and what the others share (`par`, the
//! permutation types); `tree` the supernodal elimination tree and the zone's column
//! order; `pass` the traversal that forms `Z`, `D`, `V`, `F` and `F_E`; `tangent` the
//! dense tangent of one supernode's Cholesky block.

use faer::Par;
use faer::sparse::SparseColMatRef;
use faer::sparse::linalg::cholesky::SymbolicCholeskyRaw;
use faer::sparse::linalg::cholesky::supernodal::SupernodalLltRef;

use super::{Backend, SpdFactor};

mod pass;
mod tangent;
mod tree;

use pass::Pass;
use tree::Tree;

/// No supernode (a root's parent).
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
