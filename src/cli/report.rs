//! The summary a run prints: its path, iterations, contact figures, energy, memory and
//! files, from the run's returned statistics.

use super::*;

pub(crate) fn print_summary(s: &run::Summary, out: &std::path::Path) {
    out!("scheme              {}", s.scheme);
    out!("path                {}", s.path);
    out!(
        "steps               {} in {:.3} s ({:.3} µs/step, {:.2} ns/dof/step; output {:.0} % of it)",
        s.steps,
        s.wall_seconds,
        1e6 * s.seconds_per_step,
        1e9 * s.seconds_per_step / s.dofs as f64,
        100.0 * s.output_seconds / s.wall_seconds.max(1e-12)
    );
    if s.frames > 0 {
        out!(
            "frames              {} written in {:.3} s on the writer thread, alongside the steps (the loop waited {:.3} s for it)",
            s.frames,
            s.frame_seconds,
            s.frame_wait_seconds
        );
    }
    if let Some(a) = &s.accuracy {
        out!(
            "accuracy            asked {:.1e}: estimated impulse history {:.2e}, energy {:.2e}, gaps {:.2e}, state {:.2e} ({}; the step's error: the mesh's is not estimated); bounded by {}",
            a.target,
            a.estimated.impulse_history,
            a.estimated.energy,
            a.estimated.gaps,
            a.estimated.state,
            if a.met { "met" } else { "NOT met" },
            a.bounded_by
        );
        out!(
            "                    the windows' own: impulse history {:.2e}, energy {:.2e}, gaps {:.2e}, state {:.2e}; the companion run's: impulse history {:.2e}, energy {:.2e}, state {:.2e}{}",
            a.local.impulse_history,
            a.local.energy,
            a.local.gaps,
            a.local.state,
            a.companion.impulse_history,
            a.companion.energy,
            a.companion.state,
            if a.companion.resyncs > 0 {
                format!(" ({} restart(s) from the run's state)", a.companion.resyncs)
            } else {
                String::new()
            }
        );
        out!(
            "steps chosen        {} windows of two steps, {} rejected, {} steps taken in all; h from {:.3e} to {:.3e} s (ladder {:.3e} … {:.3e} s); {} window(s) at the floor",
            a.windows,
            a.rejected,
            a.steps_taken,
            a.dt_min_used,
            a.dt_max_used,
            a.ladder.first().copied().unwrap_or(f64::NAN),
            a.ladder.last().copied().unwrap_or(f64::NAN),
            a.floor_windows
        );
    }
    out!("max violation       {:.3e} m", s.max_violation);
    out!(
        "iterations          newton {:.3}/{}  projection {:.3}/{}  index-set {:.3}/{}  lcp {:.3}/{} (mean/max); caps hit {}",
        s.iterations.newton.mean,
        s.iterations.newton.max,
        s.iterations.projection.mean,
        s.iterations.projection.max,
        s.iterations.index_set.mean,
        s.iterations.index_set.max,
        s.iterations.lcp.mean,
        s.iterations.lcp.max,
        s.caps_hit
    );
    let l = &s.newton_loops;
    if l.coupled_solves + l.stalls + l.steps_with_held_rows + l.complementarity_fallbacks > 0 {
        out!(
            "newton loops        {} coupled position solves, {} stalls within √tol, {} steps with held rows, {} rounds redone with complementarity",
            l.coupled_solves,
            l.stalls,
            l.steps_with_held_rows,
            l.complementarity_fallbacks
        );
    }
    if let Some(n) = &s.nonlinear {
        out!(
            "nonlinear           {} factorizations of M̂ⁿ ({:.2} per step); {:.3} s assembling F and Kⁿ, {:.3} s factoring, of {:.3} s of steps",
            n.factorizations,
            n.factorizations_per_step,
            n.assembly_seconds,
            n.factorization_seconds,
            s.wall_seconds
        );
    }
    if let Some(f) = &s.friction {
        out!(
            "friction            {} solves ({} past NSGS), {:.2} sweeps each (max {} in a step), residual mean {:.2e} max {:.2e}; caps hit {}",
            f.solves,
            f.fallbacks,
            f.sweeps_mean,
            f.sweeps_max_per_step,
            f.residual_mean,
            f.residual_max,
            f.caps_hit
        );
    }
    if let Some(peak) = s.peak_memory_bytes {
        out!(
            "memory              {} peak resident, {} planned",
            signorini::limits::bytes(peak),
            signorini::limits::bytes(s.memory_planned_bytes)
        );
    }
    if let Some(g) = &s.matrix_free {
        out!(
            "matrix-free         {} one-step problems past the dense workspaces, {:.1} products with W each",
            g.solves,
            g.products_per_solve
        );
    }
    if let Some(c) = &s.contact {
        let rel = |a: f64, b: f64| 100.0 * (a / b - 1.0);
        out!("                    measured        analytic        difference");
        out!(
            "contact force       {:<12.3} N  {:<12.3} N  {:+.3} % (plateau std {:.2} N)",
            c.plateau_force,
            c.analytic_force,
            rel(c.plateau_force, c.analytic_force),
            c.plateau_std
        );
        out!(
            "contact duration    {:<12.4e} s  {:<12.4e} s  {:+.3} %",
            c.duration,
            c.analytic_duration,
            rel(c.duration, c.analytic_duration)
        );
        out!(
            "release velocity    {:<12.5} m/s {:<12.5} m/s {:+.3} %",
            c.release_velocity,
            c.analytic_release_velocity,
            rel(c.release_velocity, c.analytic_release_velocity)
        );
        out!(
            "total impulse       {:<12.5e} Ns {:<12.5e} Ns {:+.3} %",
            c.total_impulse,
            c.analytic_total_impulse,
            rel(c.total_impulse, c.analytic_total_impulse)
        );
    }
    let mut frames = if s.frames > 0 {
        format!(", {}/fields.pvd ({} frames)", out.display(), s.frames)
    } else {
        String::new()
    };
    if out.join("contact_force.png").exists() {
        frames.push_str(", plots (contact_force, energy, violation .png/.svg)");
    }
    out!(
        "wrote               {}/summary.json, {}/history.csv{frames}",
        out.display(),
        out.display()
    );
}
