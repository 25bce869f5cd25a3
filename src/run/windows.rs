//! An accuracy run advanced window by window ([`accuracy::Controller::window_step`]):
//! checkpoints between windows, progress in thousandths of the span.

use std::time::Instant;

use super::*;

impl RunInProgress {
    /// [`RunInProgress::advance`] of an accuracy run: window by window
    /// ([`accuracy::Controller::window_step`]) until step `until` is passed or the run's
    /// end reached; a checkpoint after a window that passed a multiple of the checkpoint
    /// stride (never inside a window: a resumed run starts its next window where the
    /// uninterrupted one does); progress in thousandths of the span.
    pub(super) fn advance_windows(
        &mut self,
        integ: &mut dyn Integrator,
        until: usize,
        checks: &RunChecks,
        progress: &mut dyn Progress,
    ) -> Result<(), Error> {
        let Some(ctrl) = self.control.as_mut() else {
            return Ok(());
        };
        let t_end = ctrl.spec().t_end;
        let mut reported = ((integ.state().time / t_end) * 1000.0) as usize;
        while integ.state().step < until && !ctrl.done(integ.state().time) {
            let before = integ.state().step;
            let last = &mut self.last;
            let mut keep = |_: &dyn Integrator, st: &crate::integrators::StepStats, _: bool| {
                *last = Some(*st);
                Ok(())
            };
            let (_, st) = ctrl.window_step(integ, checks, &mut [&mut self.obs, &mut keep])?;
            let s = integ.state();
            if let Some((every, abort_after)) =
                self.obs.plan.as_ref().map(|p| (p.every, p.abort_after))
            {
                let done = ctrl.done(s.time);
                if !done && s.step / every > before / every {
                    let t0 = Instant::now();
                    self.obs.checkpoint(integ, Some(ctrl.save()))?;
                    self.obs.writers.seconds += t0.elapsed().as_secs_f64();
                }
                if abort_after.is_some_and(|a| before < a && a <= s.step) {
                    if let Some(h) = self.obs.writers.history.as_mut() {
                        h.sync()?;
                    }
                    std::process::abort();
                }
            }
            let permille = ((s.time / t_end) * 1000.0).clamp(0.0, 1000.0) as usize;
            if permille > reported || ctrl.done(s.time) {
                reported = permille;
                progress.update_with(permille, 1000, s.time, &st);
            }
            if progress.cancelled() {
                return Err(Error::Interrupted {
                    step: s.step,
                    time: s.time,
                });
            }
        }
        Ok(())
    }
}
