//! The companion run of an accuracy run (the module doc of [`super`]): one step per kept
//! window, of the window's length, from the companion's own state, and its comparison
//! with the run (the global estimates, [`super::CompanionEstimates`]).

use super::*;

impl Controller {
    /// The companion's step over the window just kept (module doc): one step of the
    /// window's length from the companion's own state, then its comparison with the run
    /// (`∫|P − P_c| dt` by the trapezoidal rule over the windows' ends; at the run's end
    /// the energies and `‖q − q_c‖_M`). The run's state `B₂` is restored after it. A
    /// companion step that fails starts the companion again from the run's state
    /// (counted: [`CompanionEstimates::resyncs`]).
    pub(super) fn companion_step(
        &mut self,
        integ: &mut dyn Integrator,
        checks: &RunChecks,
        big: f64,
        last: bool,
    ) -> Result<(), Error> {
        use crate::integrators::saved::Bits;
        // the run's cumulative impulse, this window's included (normal impulses are
        // never negative: the scale's sum of their magnitudes is the sum itself)
        let p_r = self.st.scales[0].0;
        let Some(mut comp) = self.st.companion.take() else {
            return Ok(());
        };
        integ.restore(&comp)?;
        self.st.counts[2] += 1;
        let ok = match integ
            .set_dt(big)
            .and_then(|_| integ.prepare())
            .and_then(|_| integ.step())
        {
            Ok(st) => {
                self.st.counts[4] += st.factorizations;
                checks.check(integ, &st).is_ok()
            }
            Err(_) => false,
        };
        let p_c = if ok {
            integ.save_into(&mut comp);
            let s = integ.state();
            if last {
                self.q_a.copy_from_slice(&s.q);
                self.v_a.copy_from_slice(&s.v);
            }
            self.st.global[2].0 + s.impulse.iter().sum::<f64>()
        } else {
            self.st.resyncs += 1;
            comp.clone_from(&self.b2);
            p_r
        };
        self.st.companion = Some(comp);
        integ.restore(&self.b2)?;
        let g = &mut self.st.global;
        let dp = (p_r - p_c).abs();
        g[0] = Bits(g[0].0 + 0.5 * (g[1].0 + dp) * big);
        g[1] = Bits(dp);
        g[2] = Bits(p_c);
        // (a companion that failed its last step is the run's state: no difference)
        if last && ok {
            let m = self.measure(integ, true, true);
            let g = &mut self.st.global;
            g[3] = Bits((m.total - m.total_a).abs());
            g[4] = Bits(m.difference);
        }
        Ok(())
    }
}
