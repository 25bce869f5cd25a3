//! The end of a run: the writers closed (the history's last rows, the frames'
//! collection), a checkpoint that would only resume a finished run removed, the
//! [`Summary`] formed from the observers' accumulators ([`RunInProgress::finish`]), and
//! `summary.json` and the plots written ([`finish`]).

use std::time::Instant;

use super::*;

impl RunInProgress {
    /// Ends a run advanced to its last step: closes the writers, removes a checkpoint
    /// that would only resume a finished run, and forms the [`Summary`].
    pub fn finish(self, integ: &mut dyn Integrator) -> Result<RunResult, Error> {
        let done = integ.state().step;
        if !self.is_done(integ) {
            return Err(Error::Numerical(format!(
                "the run was finished at step {done} of {} (t = {:e} s)",
                self.steps,
                integ.state().time
            )));
        }
        let RunInProgress {
            obs,
            steps,
            control,
            elements,
            theta,
            reference,
            parameters,
            energy0,
            mut output_seconds,
            stepping_seconds: wall,
            _lock,
            ..
        } = self;
        // an accuracy run's steps are those it took
        let steps = if control.is_some() { done } else { steps };
        let accuracy = control.as_ref().map(|c| c.summary(energy0));
        let t_fin = Instant::now();
        let obs_h = obs.h;
        let RunObserver {
            acc,
            tracker,
            mut writers,
            plan,
            energy,
            probes,
            rotations,
            last_rotation,
            ..
        } = obs;
        let rotation = rotations.as_ref().map(|r| {
            let w = last_rotation.unwrap_or(rotations::Turned {
                body: 0,
                cell: 0,
                angle: 0.0,
            });
            RotationSummary {
                limit: r.limit(),
                final_largest: w.angle,
                body: w.body,
                cell: w.cell,
            }
        });
        let energy_balance = energy.map(|e| EnergyBalance {
            supplied_work: e.audit.work(),
            excess_max: acc.energy_excess,
            scale_floor: e.audit.floor(),
        });
        output_seconds += writers.seconds;
        let history_thread = matches!(writers.history, Some(history_thread::History::Thread(_)));
        if let Some(w) = writers.history.take() {
            w.finish()?;
        }
        let (frame_count, frame_seconds, frame_wait) = match writers.frames.take() {
            Some(f) => {
                let wait = f.waited_seconds();
                let w = f.finish()?;
                (w.frames().len(), w.busy_seconds(), wait)
            }
            None => (0, 0.0, 0.0),
        };
        // the run is complete: its checkpoint would only resume a finished run
        if let Some(p) = plan {
            let path = p.dir.join(checkpoint::FILE);
            if path.exists() {
                std::fs::remove_file(&path).map_err(|e| Error::write(&path, e))?;
            }
        }
        output_seconds += t_fin.elapsed().as_secs_f64();
        let s = integ.state();
        let sys = integ.system();
        let energy1 = sys.total_energy(s.time, &s.q, &s.v);
        let contact = reference.map(|r| contact_summary(&tracker, sys, &s.v, r));
        let summary = Summary {
            scheme: integ.name().to_string(),
            elements,
            dofs: s.q.len(),
            dt: obs_h,
            theta,
            steps,
            t_end: s.time,
            wall_seconds: wall,
            seconds_per_step: wall / steps.max(1) as f64,
            output_seconds,
            frames: frame_count,
            frame_seconds,
            frame_wait_seconds: frame_wait,
            max_violation: acc.violation,
            contact,
            iterations: acc.iterations(steps),
            caps_hit: acc.caps,
            newton_loops: NewtonLoops {
                coupled_solves: acc.loops[0],
                stalls: acc.loops[1],
                steps_with_held_rows: acc.loops[2],
                complementarity_fallbacks: acc.loops[3],
            },
            friction: acc.friction(s.tangent_dim > 0),
            // set by `finish`
            memory_planned_bytes: 0,
            peak_memory_bytes: None,
            matrix_free: (acc.global[0] > 0).then(|| summary::MatrixFreeSummary {
                solves: acc.global[0],
                products: acc.global[1],
                products_per_solve: acc.global[1] as f64 / acc.global[0] as f64,
            }),
            nonlinear: (!integ.step_matrix_constant()).then(|| summary::NonlinearSummary {
                factorizations: acc.factorizations,
                factorizations_per_step: acc.factorizations as f64 / steps.max(1) as f64,
                assembly_seconds: acc.assembly_seconds,
                factorization_seconds: acc.factorization_seconds,
            }),
            max_lcp_residual: acc.lcp_res,
            energy: [energy0, energy1],
            energy_balance,
            rotation,
            probes: probes.summaries(reference.as_ref()),
            // set by the application, which knows the bodies
            bodies: Vec::new(),
            arithmetic: crate::linalg::arithmetic().name().to_string(),
            subnormals: crate::linalg::subnormals::current_thread()
                .name()
                .to_string(),
            history_thread,
            path: integ.path(),
            model_seconds: 0.0,
            integrator_seconds: 0.0,
            parameters,
            accuracy,
        };
        Ok(RunResult {
            summary,
            dt: match (&tracker.trace, tracker.trace_dt) {
                (Some(_), Some(d)) => d,
                _ => Vec::new(),
            },
            force: tracker.trace.unwrap_or_default(),
            state: integ.state().clone(),
        })
    }
}

/// Completes a run: records the set-up times, writes `summary.json` and the plots.
pub fn finish(
    mut r: RunResult,
    setup: [f64; 2],
    planned: u64,
    out: Option<Output>,
) -> Result<RunResult, Error> {
    [r.summary.model_seconds, r.summary.integrator_seconds] = setup;
    r.summary.memory_planned_bytes = planned;
    r.summary.peak_memory_bytes = crate::limits::peak_memory();
    if let Some(o) = out {
        write_summary(&r.summary, o.dir)?;
        if o.options.plots {
            crate::plot::plot_run(o.dir)?;
        }
    }
    Ok(r)
}
