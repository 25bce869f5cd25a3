//! How large the θ-method's one-step workspaces are, and the checks of the inputs the
//! build and the plan both make: shared by [`super::core::ThetaCore::new`], the
//! Schatzman–Paoli build and the plan of `signorini check` ([`super::plan`]), and
//! below all three (a leaf: it imports no sibling but the parameters).

use super::SchemeParams;
use crate::contact::ContactSet;
use crate::error::Error;

/// Default cap on the rows of the dense one-step workspaces (4096² values = 128 MiB).
pub const DEFAULT_MAX_ACTIVE_ROWS: usize = 4096;

/// Active rows past which a one-step problem with a nonlinear `G` on the
/// per-active-column Delassus path is solved matrix-free: its columns would be re-solved
/// (two solves per row with the projection) at every linearization, where a matrix-free
/// solve takes a few tens of products (measured 21–25 per solve on the flat impact of
/// `tests/analytic_flat_impact.rs`); the same threshold as the dense re-forming of
/// [`crate::delassus::AUTO_DENSE_MAX_CONTACTS`].
pub const NONLINEAR_COLUMNS_MAX: usize = 64;

/// Active rows past which the θ-method core solves a one-step problem matrix-free: the
/// workspace rows `ws_cap`, or [`NONLINEAR_COLUMNS_MAX`] for a nonlinear `G` on the
/// per-active-column path (which would re-solve every stored column at each
/// linearization, where a matrix-free solve costs a few tens of products). Shared by
/// [`super::core::ThetaCore::new`] and the plan of `signorini check`.
pub(crate) fn matrix_free_rows(ws_cap: usize, g_constant: bool, dense: bool) -> usize {
    if !g_constant && !dense {
        NONLINEAR_COLUMNS_MAX.min(ws_cap)
    } else {
        ws_cap
    }
}

/// Rows of the dense blocks: `rows`, capped by `params.max_active_rows`.
pub(crate) fn workspace_cap(rows: usize, params: &SchemeParams) -> usize {
    match params.max_active_rows {
        0 => rows.min(DEFAULT_MAX_ACTIVE_ROWS),
        c => rows.min(c),
    }
}

/// The one-step workspaces of the θ-method core in a memory ledger: the dense blocks
/// (the gathered block and the MLCP's three, `scheme.max_active_rows` rows at most), the
/// coupled position problem (the velocity rows plus one τ per contact, capped alike),
/// the matrix-free vectors past the cap, and `auto`'s dense friction Newton fallback.
/// Shared by [`super::core::ThetaCore::new`] and the plan of `signorini check`.
pub(crate) fn workspace_ledger(
    rows: usize,
    m: usize,
    params: &SchemeParams,
    (friction, with_projection): (bool, bool),
    mem: &mut crate::limits::MemoryEstimate,
) {
    let ws_cap = workspace_cap(rows, params);
    let cap = ws_cap as u64;
    let cc = if with_projection && params.projection_feedback {
        (rows + m).min(ws_cap) as u64
    } else {
        0
    };
    mem.add("dense one-step workspaces (4 × rows²)", cap * cap, 32);
    mem.add("coupled position problem (unknowns²)", cc * cc, 8);
    if rows > ws_cap {
        // the matrix-free solves' vectors (`Workspace::gq`…, `GlobalSolver`)
        mem.add(
            "matrix-free one-step vectors (15 × rows)",
            rows as u64,
            15 * 8,
        );
    }
    // `auto`'s dense Newton fallback: W and J (solvers::newton::NewtonWork)
    let fn_rows = if friction {
        cap.min(crate::solvers::newton::STEP_NEWTON_ROWS as u64)
    } else {
        0
    };
    mem.add(
        "friction Newton workspace (2 × rows²)",
        fn_rows * fn_rows,
        16,
    );
}

/// Refuses a `max_active_rows` that cannot hold one contact block (the dense one-step
/// workspaces gather whole blocks).
pub(crate) fn check_block_rows(
    params: &SchemeParams,
    contacts: &dyn ContactSet,
) -> Result<(), Error> {
    let block = (0..contacts.len())
        .map(|a| contacts.dim(a))
        .max()
        .unwrap_or(1);
    if params.max_active_rows != 0 && params.max_active_rows < block {
        // issue 34: accepted before
        return Err(Error::invalid(
            "scheme.max_active_rows",
            params.max_active_rows,
            &format!(
                "must hold at least one contact block ({block} rows: the normal and the \
                 tangents of a frictional contact), or be 0 for the default"
            ),
        ));
    }
    Ok(())
}

/// Checks a user-given vector: length and finiteness.
pub(crate) fn check_vector(field: &str, x: &[f64], n: usize) -> Result<(), Error> {
    if x.len() != n {
        return Err(Error::invalid(
            field,
            format!("{} values", x.len()),
            &format!("needs {n} values (one per dof)"),
        ));
    }
    if let Some(i) = x.iter().position(|v| !v.is_finite()) {
        return Err(Error::invalid(
            &format!("{field}[{i}]"),
            x[i],
            "must be finite",
        ));
    }
    Ok(())
}
