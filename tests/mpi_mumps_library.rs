//! The MUMPS backend as a library (cargo feature `mumps`; issue 19 §2), in this
//! process: an MPI singleton of one rank (its own test binary: the singleton's
//! environment must not reach the `mpirun` launches of `tests/mpi_mumps.rs`).
#![cfg(feature = "mumps")]

/// A 3-D Laplacian plus a mass shift (the shape of `M̂`) factored by MUMPS. Columns
/// solved "independently" in one call equal the same columns solved one by one, bit
/// for bit (the Delassus operator's contract: a resumed run recomputes its active
/// columns in one batch and must find the same values); the blocked solve agrees with
/// them to 1e-13 relative and every column's residual is below 1e-12 (a direct factor
/// of a matrix of condition number ~1e2 with entries of order 1: a few ulps).
#[test]
fn mumps_columns_solved_together_equal_columns_solved_alone() {
    use faer::sparse::Triplet;
    use signorini::linalg::mumps::{Role, start};
    use signorini::linalg::{SolverKind, SparseMatrix, solver::factor};
    let Role::Host(_guard) = start("test").unwrap() else {
        panic!("one process is rank 0")
    };
    let s = 12;
    let n = s * s * s;
    let id = |i: usize, j: usize, k: usize| (i * s + j) * s + k;
    let mut t = Vec::new();
    for i in 0..s {
        for j in 0..s {
            for k in 0..s {
                let p = id(i, j, k);
                t.push(Triplet::new(p, p, 6.0 + 0.1));
                for (di, dj, dk) in [(1, 0, 0), (0, 1, 0), (0, 0, 1)] {
                    let (a, b, c) = (i + di, j + dj, k + dk);
                    if a < s && b < s && c < s {
                        let q = id(a, b, c);
                        t.push(Triplet::new(p, q, -1.0));
                        t.push(Triplet::new(q, p, -1.0));
                    }
                }
            }
        }
    }
    let a = SparseMatrix::try_new_from_triplets(n, n, &t).unwrap();
    let mut mumps = factor(a.as_ref(), "A", SolverKind::Cholesky, None).unwrap();
    assert!(
        mumps.backend_name().contains("MUMPS"),
        "{}",
        mumps.backend_name()
    );
    let k = 40;
    let rhs: Vec<f64> = (0..n * k)
        .map(|i| ((i * 7919) % 1000) as f64 / 500.0 - 1.0)
        .collect();
    let mut together = rhs.clone();
    mumps.solve_columns_independently(&mut together, k);
    let mut alone = rhs.clone();
    for col in alone.chunks_exact_mut(n) {
        mumps.solve_in_place(col);
    }
    assert!(
        together
            .iter()
            .zip(&alone)
            .all(|(x, y)| x.to_bits() == y.to_bits()),
        "a column solved with others differs from the same column alone"
    );
    let mut block = rhs.clone();
    mumps.solve_block_in_place(&mut block, k);
    let scale = alone.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let worst = block
        .iter()
        .zip(&alone)
        .fold(0.0_f64, |m, (x, y)| m.max((x - y).abs()));
    assert!(
        worst <= 1e-13 * scale,
        "block against columns: {worst:e} of {scale:e}"
    );
    for (c, x) in alone.chunks_exact(n).enumerate() {
        let mut r = rhs[c * n..(c + 1) * n].to_vec();
        for (j, col) in (0..n).map(|j| (j, a.as_ref().col_range(j))) {
            for p in col {
                r[a.row_idx()[p]] -= a.val()[p] * x[j];
            }
        }
        let res = r.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        assert!(res <= 1e-12, "column {c}: residual {res:e}");
    }
    drop(mumps);
}
