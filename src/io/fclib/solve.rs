//! Solving a read problem with one of [`crate::solvers::friction`]'s solvers, once or
//! repeated for timing, with the solution's measures.

use super::*;

/// A solved problem: what `signorini fclib --solution` writes.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Solution {
    /// Reactions, contact by contact, normal first.
    pub r: Vec<f64>,
    /// Velocities `W r + q`, same layout.
    pub u: Vec<f64>,
    /// The residual reached, by [`Solution::measure`].
    pub residual: f64,
    /// Which residual: Siconos' (default) or the step loop's velocity residual.
    pub measure: crate::solvers::friction::Measure,
    /// NSGS sweeps (summed over the proximal iterations for PROX).
    pub iterations: usize,
    /// Proximal iterations (PROX only).
    pub prox_iterations: usize,
    /// The residual reached the tolerance.
    pub converged: bool,
    /// Wall time of the solve (s).
    pub seconds: f64,
    /// The solver asked for.
    pub solver: String,
    /// The solver that produced `r` (for `auto`, the stage that finished).
    pub solved_by: String,
    /// The Newton methods factored a sparse Jacobian.
    pub sparse_jacobian: bool,
}

/// Solves `prob` from `r = 0` (or the file's guess when `warm`) with `params`.
pub fn solve(
    prob: &FrictionContactProblem,
    params: &crate::solvers::friction::FrictionParams,
    warm: bool,
) -> Result<Solution, Error> {
    solve_repeated(prob, params, Measure::Siconos, warm, 1)
}

/// As [`solve`], stopping on `measure`, `repeat` times from the same start; `seconds`
/// is the median (warm caches, as a benchmark in one process measures the other code).
pub fn solve_repeated(
    prob: &FrictionContactProblem,
    params: &crate::solvers::friction::FrictionParams,
    measure: Measure,
    warm: bool,
    repeat: usize,
) -> Result<Solution, Error> {
    let mut times = Vec::with_capacity(repeat.max(1));
    let mut last = None;
    for _ in 0..repeat.max(1) {
        let s = solve_once(prob, params, measure, warm)?;
        times.push(s.seconds);
        last = Some(s);
    }
    times.sort_by(f64::total_cmp);
    let mut s = last.expect("at least one solve");
    s.seconds = times[times.len() / 2];
    Ok(s)
}

pub(super) fn solve_once(
    prob: &FrictionContactProblem,
    params: &crate::solvers::friction::FrictionParams,
    measure: Measure,
    warm: bool,
) -> Result<Solution, Error> {
    use crate::solvers::friction::{Block, FrictionProblem, FrictionSolver};
    use crate::solvers::operator::DenseOperator;
    let n = prob.rows();
    let blocks: Vec<Block> = prob
        .mu
        .iter()
        .enumerate()
        .map(|(a, &mu)| Block {
            offset: a * prob.dim,
            dim: prob.dim,
            mu,
        })
        .collect();
    let mut r = match (&prob.guess, warm) {
        (Some(g), true) => g.clone(),
        _ => vec![0.0; n],
    };
    let mut u = vec![0.0; n];
    let mut solver = FrictionSolver::for_one_step(n).with_measure(measure);
    let op = DenseOperator::new(n, &prob.w);
    let t0 = std::time::Instant::now();
    let info = solver
        .solve(
            FrictionProblem {
                w: &op,
                q: &prob.q,
                blocks: &blocks,
            },
            params,
            &mut r,
            &mut u,
        )
        .map_err(|e| Error::Numerical(e.to_string()))?;
    let seconds = t0.elapsed().as_secs_f64();
    Ok(Solution {
        r,
        u,
        residual: info.residual,
        measure,
        iterations: info.iterations,
        prox_iterations: info.prox_iterations,
        converged: info.converged,
        seconds,
        solver: params.solver.name().to_string(),
        solved_by: info.solver.name().to_string(),
        sparse_jacobian: info.sparse_jacobian,
    })
}
