//! The tangent `D = dL/dε` of a dense Cholesky block along `R` (the module doc of
//! `linalg::zone_flex`): `D_tt = L_tt Φ(L_tt⁻¹ R_tt L_tt⁻ᵀ)` on small blocks, by halves
//! on large ones, and `D_bt = (R_bt − L_bt D_ttᵀ) L_tt⁻ᵀ` below them; faer's triangular
//! kernels.

use faer::linalg::matmul::triangular::{self, BlockStructure};
use faer::linalg::triangular_solve::solve_lower_triangular_in_place_with_conj;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::{Accum, Conj, Mat, MatMut, MatRef, Par};

use super::par;

/// The block of `D` of one supernode from its accumulated `R` (`d`, `nr × size`,
/// column-major, the lower triangle of its top block meaningful):
/// `D_tt = L_tt Φ(L_tt⁻¹ R_tt L_tt⁻ᵀ)`, `D_bt = (R_bt − L_bt D_ttᵀ) L_tt⁻ᵀ`.
pub(super) fn tangent_block(
    lt: MatRef<'_, f64>,
    lb: MatRef<'_, f64>,
    d: &mut [f64],
    size: usize,
    nr: usize,
) {
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
