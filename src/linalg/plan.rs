//! The symbolic analysis of the step matrix: the ordering kept (AMD or the mesh's
//! nested dissection, whichever fills less), the tridiagonal pattern test, the LDLᵀ
//! analysis, and the factor's size and scratch (per [`SOLVE_CHUNK`] right-hand sides),
//! known before any numeric work ([`FactorPlan`]). The factors (`spd.rs`, `solver.rs`)
//! build on what this file decides; it calls none of them.

use super::*;

/// Right-hand sides per faer call in [`SpdFactor::solve_block_in_place`]. A supernodal
/// solve streams the whole factor once per call, so on a large factor it is bound by
/// memory bandwidth, and more right-hand sides per pass cost little more than one:
/// on the 98 304-dof cube (nnz(L) = 1.9e8) the 1024 columns of `M̂⁻¹G` took 18.7 s in
/// calls of 16, 15.2 s in calls of 32, 12.9 s in calls of 64 and 13.1 s in calls of
/// 256 (one thread). [`SpdFactor::solve_block_in_place_par`] spreads the chunks over
/// rayon's threads, each with its own scratch: 8.4 s on two threads.
pub const SOLVE_CHUNK: usize = 64;

/// Whether every entry of `a` lies within one diagonal of the main one (the pattern the
/// tridiagonal `L D Lᵀ` of `spd.rs` factors).
pub(super) fn is_tridiagonal(a: SparseColMatRef<'_, usize, f64>) -> bool {
    let (cp, ri) = (a.col_ptr(), a.row_idx());
    (0..a.ncols()).all(|j| {
        ri[cp[j]..cp[j + 1]]
            .iter()
            .all(|&i| i + 1 >= j && i <= j + 1)
    })
}

/// The symbolic analysis [`SparseLdlt::new`](super::solver::SparseLdlt::new) factors on
/// (AMD), with the scratch of its numeric factorization and solves; [`analyse_ldlt`]
/// plans from it.
pub(crate) fn symbolic_ldlt(
    a: SparseColMatRef<'_, usize, f64>,
    what: &str,
) -> Result<(SymbolicCholesky<usize>, StackReq), Error> {
    let symbolic = factorize_symbolic_cholesky(
        a.symbolic(),
        Side::Lower,
        SymmetricOrdering::Amd,
        CholeskySymbolicParams::default(),
    )
    .map_err(|e| Error::Numerical(format!("{what}: symbolic LDLᵀ failed: {e:?}")))?;
    let req = StackReq::any_of(&[
        symbolic.factorize_numeric_ldlt_scratch::<f64>(Par::Seq, Default::default()),
        symbolic.solve_in_place_scratch::<f64>(SOLVE_CHUNK, Par::Seq),
    ]);
    Ok((symbolic, req))
}

/// A candidate fill-reducing order of the unknowns handed to the Cholesky of `M̂`
/// (eq. 47) beside AMD, and the method that made it (named in the backend's path line).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DofOrdering {
    /// What made the order, as the path line prints it (e.g. "nested dissection").
    pub method: &'static str,
    /// Position → unknown: a permutation of `0..n`.
    pub perm: Vec<usize>,
}

/// The symbolic Cholesky analysis [`SpdFactor::new_general`] keeps: AMD, or `ordering`
/// where its factor has fewer entries; with the ordering's name.
pub(super) fn symbolic_choice(
    a: SparseColMatRef<'_, usize, f64>,
    what: &str,
    ordering: Option<&DofOrdering>,
) -> Result<(SymbolicCholesky<usize>, &'static str), Error> {
    let n = a.nrows();
    // AMD always: faer 0.24.4's `SymmetricOrdering::Identity` path factors the
    // wrong matrix with `Side::Lower` (a 3×3 tridiagonal [4, −1] gave x = [1.14,
    // 1.55, 1.52] for x = [1, 1, 1]; pinned by a test below), so it is not offered.
    let mut symbolic = factorize_symbolic_cholesky(
        a.symbolic(),
        Side::Lower,
        SymmetricOrdering::Amd,
        CholeskySymbolicParams::default(),
    )
    .map_err(|e| Error::Numerical(format!("{what}: symbolic Cholesky failed: {e:?}")))?;
    let mut ordering_name = "AMD";
    if let Some((fwd, method)) = ordering
        .filter(|o| o.perm.len() == n && n > 0)
        .map(|o| (&o.perm[..], o.method))
    {
        let mut inv = vec![usize::MAX; n];
        for (i, &d) in fwd.iter().enumerate() {
            if d < n {
                inv[d] = i;
            }
        }
        if inv.iter().all(|&i| i != usize::MAX) {
            let perm = faer::perm::PermRef::new_checked(fwd, &inv, n);
            if let Ok(nd) = factorize_symbolic_cholesky(
                a.symbolic(),
                Side::Lower,
                SymmetricOrdering::Custom(perm),
                CholeskySymbolicParams::default(),
            ) && nd.len_val() < symbolic.len_val()
            {
                symbolic = nd;
                ordering_name = method;
            }
        }
    }
    Ok((symbolic, ordering_name))
}

/// Scratch of the numeric factorization (sequential and threaded) and of the solves.
pub(super) fn factor_scratch(symbolic: &SymbolicCholesky<usize>) -> StackReq {
    StackReq::any_of(&[
        symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
        symbolic.factorize_numeric_llt_scratch::<f64>(Par::rayon(0), Default::default()),
        symbolic.solve_in_place_scratch::<f64>(SOLVE_CHUNK, Par::Seq),
    ])
}

/// What [`SpdFactor::with_ordering`] would build for `a`, from the symbolic analysis
/// alone (no numeric factorization): the backend's name as
/// [`SpdFactor::backend_name`] gives it, the factor's entries and the scratch bytes.
/// What `signorini check` and the run's memory ledger cost.
pub fn analyse_spd(
    a: SparseColMatRef<'_, usize, f64>,
    what: &str,
    ordering: Option<&DofOrdering>,
) -> Result<FactorPlan, Error> {
    analyse_spd_kept(a, what, ordering).map(|(plan, _)| plan)
}

/// [`analyse_spd`], keeping the symbolic analysis for [`SpdFactor::with_analysis`]
/// (`None` for a tridiagonal matrix, which needs none): a run that plans then builds
/// analyses its step matrix once (issue 36 §2).
pub fn analyse_spd_kept(
    a: SparseColMatRef<'_, usize, f64>,
    what: &str,
    ordering: Option<&DofOrdering>,
) -> Result<(FactorPlan, Option<SpdAnalysis>), Error> {
    if is_tridiagonal(a) {
        let plan = FactorPlan {
            backend: "tridiagonal LDLᵀ".to_string(),
            entries: 2 * a.nrows() as u64,
            scratch_bytes: 0,
            supernodal: false,
        };
        return Ok((plan, None));
    }
    let (symbolic, name) = symbolic_choice(a, what, ordering)?;
    let plan = FactorPlan {
        backend: format!(
            "faer {} LLᵀ, {name}, nnz(L) = {}",
            if matches!(symbolic.raw(), SymbolicCholeskyRaw::Simplicial(_)) {
                "simplicial"
            } else {
                "supernodal"
            },
            symbolic.len_val()
        ),
        entries: symbolic.len_val() as u64,
        scratch_bytes: factor_scratch(&symbolic).unaligned_bytes_required() as u64,
        supernodal: matches!(symbolic.raw(), SymbolicCholeskyRaw::Supernodal(_)),
    };
    Ok((
        plan,
        Some(SpdAnalysis {
            symbolic: std::sync::Arc::new(symbolic),
            ordering: name,
            pattern: pattern_fingerprint(a),
        }),
    ))
}

/// The symbolic Cholesky analysis of an SPD pattern and the name of its ordering
/// ([`analyse_spd_kept`]), which [`SpdFactor::with_analysis`] factors on; shared by the
/// factors of every matrix of that pattern ([`super::LinearSolver::analysis`]: the
/// accuracy mode's `M̂(h)` of each step of its ladder), with a fingerprint of the
/// pattern that guards the sharing.
#[derive(Clone, Debug)]
pub struct SpdAnalysis {
    pub(super) symbolic: std::sync::Arc<SymbolicCholesky<usize>>,
    pub(super) ordering: &'static str,
    pub(super) pattern: u64,
}

/// What [`solver::SparseLdlt::new`] would build for `a` (AMD, no pivoting), from the
/// symbolic analysis alone: the factor of a nonlinear structure's symmetric `M̂ⁿ`.
pub fn analyse_ldlt(a: SparseColMatRef<'_, usize, f64>, what: &str) -> Result<FactorPlan, Error> {
    let (symbolic, req) = symbolic_ldlt(a, what)?;
    Ok(FactorPlan {
        backend: format!("faer LDLᵀ, AMD, nnz(L) = {}", symbolic.len_val()),
        entries: symbolic.len_val() as u64,
        scratch_bytes: req.unaligned_bytes_required() as u64,
        supernodal: false,
    })
}

/// The outcome of [`analyse_spd`].
#[derive(Clone, Debug, PartialEq)]
pub struct FactorPlan {
    /// The backend's description.
    pub backend: String,
    /// Entries of the factor (8 bytes each).
    pub entries: u64,
    /// Scratch of the factorization and the solves (bytes).
    pub scratch_bytes: u64,
    /// A supernodal Cholesky factor: the zone flexibilities come from it and its tangent
    /// (`linalg::zone_flex`, whose set-up holds up to `entries` more).
    pub supernodal: bool,
}

/// A fingerprint of `a`'s pattern (FNV-1a over its order, column pointers and row
/// indices): two matrices with the same fingerprint share a symbolic factorization
/// ([`SpdFactor::analysis`]).
pub(super) fn pattern_fingerprint(a: SparseColMatRef<'_, usize, f64>) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |x: usize| {
        h ^= x as u64;
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    };
    eat(a.nrows());
    a.col_ptr().iter().for_each(|&x| eat(x));
    a.row_idx().iter().for_each(|&x| eat(x));
    h
}
