//! Products through the zone flexibilities for a constant `G` past the dense path
//! (issue 35): where the one-step problems are solved matrix-free
//! ([`crate::solvers::global`]), every product `W x = Gᵀ Â⁻¹ G x` was one sparse solve
//! with the step matrix's factor. With `G = S B` (`S` the unit columns on the `z` dofs
//! the Jacobian touches) it is `Bᵀ F (B x)` with `F = SᵀÂ⁻¹S` (`z × z`), formed once at
//! set-up from the factor's `L⁻¹S` on the zone's elimination-tree paths
//! ([`crate::linalg::SpdFactor::zone_flexibilities`], no column solve): a product then
//! reads `z²` values instead of the whole factor. The 10⁶-dof rail on 10⁴ floor contacts
//! (`nnz(L)` = 7.3e8, `z` = 10 008): one product 1 s through the factor, a dense
//! `z × z` product tens of milliseconds.
//!
//! Taken when the problems go matrix-free, `F` fits the dense budget and the factor is
//! supernodal: under [`DelassusKind::Auto`] where `F` holds fewer values than the
//! factor (`z² ≤ nnz(L)`), under [`DelassusKind::Flexibility`] always;
//! `W_N` under the `M̂⁻¹` metric is `W` and uses it too; `W_D` (`Gᵀ Â⁻¹ K N G`) keeps its
//! solves (one product per step at most: the position correction's feedback).

use super::*;

/// `F` on the dofs of a constant `G` (those of its non-zero entries: `B x` is zero
/// elsewhere) and the scratch of its products.
#[derive(Debug)]
pub(super) struct ProductFlex {
    /// The dofs of `S`, sorted.
    dofs: Vec<usize>,
    /// `F = SᵀÂ⁻¹S`, `z × z` column-major.
    f: Vec<f64>,
    /// `B x` and `F B x` on the zone.
    zx: Vec<f64>,
    zy: Vec<f64>,
}

/// Whether [`Delassus::condense_products`] would form `F` for `z` dofs on a factor of
/// `entries` values: `F` fits the dense budget, and under [`DelassusKind::Auto`] a
/// product through `F` reads at most half what a solve does (`z² ≤ nnz(L)`; a solve
/// sweeps `L` twice); [`DelassusKind::Flexibility`] asks for `F` at any cost. Measured: the 1.02e6-dof rail (`z²` = 1.0e8, `nnz(L)` = 7.3e8) 295 → 14.9 s
/// per step; the 99 × 99 × 2 wide block without friction (`z²` = 1.0e8, `nnz(L)` =
/// 2.75e7) 4.99 s per step through the factor and 4.74 s through `F`, the same cost for
/// 5 s more set-up and 1.5 GiB more memory, so it keeps its solves. The plan's and the
/// build's one rule.
fn products_fit(kind: DelassusKind, z: usize, entries: u64) -> bool {
    let z2 = z.saturating_mul(z);
    let cheaper = match kind {
        DelassusKind::Auto => z2 as u64 <= entries,
        DelassusKind::Flexibility => true,
        DelassusKind::Dense | DelassusKind::Columns => false,
    };
    cheaper && z > 0 && z2.saturating_mul(8) <= AUTO_DENSE_MAX_BYTES
}

/// The path phrase's tail for products through the flexibilities of `z` dofs.
fn products_phrase(z: usize) -> String {
    format!(
        "; the flexibilities F = SᵀM̂⁻¹S of the {z} dofs G acts on, from L⁻¹S on their \
         tree paths, for the matrix-free products"
    )
}

/// The dofs of `jac`'s non-zero entries, sorted (a plane's normal rows: one dof per
/// node): the zone of [`Delassus::condense_products`], and of its plan.
pub fn acting_dofs(jac: &ContactJacobian) -> Vec<usize> {
    let (_, dofs, vals) = jac.entries();
    let mut zone: Vec<usize> = dofs
        .iter()
        .zip(vals)
        .filter(|&(_, &g)| g != 0.0)
        .map(|(&d, _)| d)
        .collect();
    zone.sort_unstable();
    zone.dedup();
    zone
}

impl DelassusPlan {
    /// Adds what [`Delassus::condense_products`] forms for a constant `G` touching `z`
    /// dofs whose problems go matrix-free, when it would (`supernodal`, `entries`: the
    /// planned factor's kind and `nnz(L)`): `F` (`z × z`) and its two `z`-vectors, and the phrase. Returns whether.
    pub fn add_products(
        &mut self,
        kind: DelassusKind,
        z: usize,
        (supernodal, entries): (bool, u64),
    ) -> bool {
        if self.dense || !supernodal || !products_fit(kind, z, entries) {
            return false;
        }
        self.bytes += (z as u64) * (z as u64 + 2) * 8;
        self.describe += &products_phrase(z);
        true
    }
}

/// Rows of `F x` one task computes: each entry of `F x` is summed over the columns in
/// the same order whatever the split, so the bits do not depend on the thread count.
const ROW_BLOCK: usize = 1024;
/// Zones of at least this many dofs split `F x` over rayon's threads.
const PAR_ROWS: usize = 2 * ROW_BLOCK;

/// `y += Σ_b x_b F[lo.., b]` over the non-zero `x_b` for the rows `lo .. lo + len(y)` of
/// the `z × z` column-major `F`: compiled by pulp's dispatch for the CPU's vector width,
/// with separate multiply and add.
struct Rows<'a> {
    cols: &'a [f64],
    z: usize,
    lo: usize,
    weights: &'a [f64],
    y: &'a mut [f64],
}

impl pulp::WithSimd for Rows<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        let (z, lo, hi) = (self.z, self.lo, self.lo + self.y.len());
        for (b, &xb) in self.weights.iter().enumerate() {
            if xb != 0.0 {
                axpy(xb, &self.cols[b * z + lo..b * z + hi], self.y);
            }
        }
    }
}

impl ProductFlex {
    /// The path phrase's tail.
    pub(super) fn phrase(&self) -> String {
        products_phrase(self.dofs.len())
    }
}

impl Delassus {
    /// For a constant `G` on the per-active-column path whose one-step problems are
    /// solved matrix-free: forms `F = SᵀÂ⁻¹S` on the dofs `G` touches from the factor
    /// (module doc), so that [`Delassus::product`] of `W` (and `W_N` under the `M̂⁻¹`
    /// metric) costs no solve. Returns whether it did: not for a nonlinear `G`, the
    /// dense path, [`DelassusKind::Dense`] or [`DelassusKind::Columns`], an `F` past the
    /// dense budget or (under [`DelassusKind::Auto`]) larger than the factor (a product
    /// through it would not be cheaper than a solve), or a factor that is not
    /// supernodal. Allocates: a set-up's work.
    pub fn condense_products(&mut self) -> bool {
        if !self.shape.g_constant || self.shape.dense || self.zone.is_some() {
            return false;
        }
        let zone = acting_dofs(&self.jac);
        let z = zone.len();
        let entries = self.factor.factor_entries().unwrap_or(0);
        if !products_fit(self.shape.kind, z, entries) || zone.iter().any(|&d| d >= self.shape.n) {
            return false;
        }
        let Some((f, _)) = self.factor.zone_flexibilities(&zone, None) else {
            return false;
        };
        self.pflex = Some(ProductFlex {
            dofs: zone,
            f,
            zx: vec![0.0; z],
            zy: vec![0.0; z],
        });
        true
    }

    /// `out += s Bᵀ F (B x)` when `F` is formed and `op` is `W` (or `W_N` under the
    /// `M̂⁻¹` metric); `false` (nothing done) otherwise. Allocation-free.
    pub(super) fn product_by_flexibility(
        &mut self,
        op: Op,
        s: f64,
        x: &[f64],
        out: &mut [f64],
    ) -> bool {
        if !matches!((op, self.shape.metric), (Op::W, _) | (Op::Wn, Metric::Mass)) {
            return false;
        }
        // taken out while `gather_g` borrows `self` (a move, no allocation)
        let Some(mut pf) = self.pflex.take() else {
            return false;
        };
        // G x on the n dofs: non-zero on the zone alone
        self.gather_g(x);
        for (v, &d) in pf.zx.iter_mut().zip(&pf.dofs) {
            *v = self.scratch.t1[d];
        }
        pf.zy.iter_mut().for_each(|v| *v = 0.0);
        let z = pf.dofs.len();
        let (f, zx) = (&pf.f[..], &pf.zx[..]);
        let rows = |(c, y): (usize, &mut [f64])| {
            pulp::Arch::new().dispatch(Rows {
                cols: f,
                z,
                lo: c * ROW_BLOCK,
                weights: zx,
                y,
            })
        };
        if z >= PAR_ROWS {
            use rayon::prelude::*;
            pf.zy.par_chunks_mut(ROW_BLOCK).enumerate().for_each(rows);
        } else {
            pf.zy.chunks_mut(ROW_BLOCK).enumerate().for_each(rows);
        }
        // S F B x: the zone entries replaced, every other entry of t1 is zero
        for (&v, &d) in pf.zy.iter().zip(&pf.dofs) {
            self.scratch.t1[d] = v;
        }
        self.pflex = Some(pf);
        for (a, o) in out.iter_mut().enumerate() {
            *o += s * self.jac.dot(a, &self.scratch.t1);
        }
        true
    }

    /// `F` is formed for the products ([`Delassus::condense_products`]).
    pub fn products_by_flexibility(&self) -> bool {
        self.pflex.is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rule at the sizes the module doc measures: the rail (10 008 dofs on a factor
    /// of 7.34e8 values) takes `F`; the 99 × 99 × 2 wide block (10 000 dofs, 2.75e7)
    /// keeps its solves under `auto` and takes `F` when asked; its frictional variant's
    /// 30 000 dofs (7.2 GB of `F`) exceed the budget; `dense` and `columns` never do.
    #[test]
    fn products_follow_the_cost_rule_and_the_budget() {
        use DelassusKind::*;
        assert!(products_fit(Auto, 10_008, 734_342_562));
        assert!(!products_fit(Auto, 10_000, 27_472_077));
        assert!(products_fit(Flexibility, 10_000, 27_472_077));
        assert!(!products_fit(Auto, 30_000, u64::MAX));
        assert!(!products_fit(Flexibility, 30_000, u64::MAX));
        assert!(!products_fit(Columns, 169, u64::MAX));
        assert!(!products_fit(Dense, 169, u64::MAX));
        assert!(!products_fit(Auto, 0, u64::MAX));
    }
}
