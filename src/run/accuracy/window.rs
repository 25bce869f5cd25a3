//! One window's comparison of `A` with `B` (the module doc of [`super`]): what is read
//! of a state ([`Measures`]: energies and mass norms, in one walk over `M` and `K` for a
//! linear structure), the window's estimates and their ratios to the allowances
//! ([`Window`]), and what an accepted window adds to the sums and scales.

use super::*;

/// What [`Controller::measure`] reads of a state.
pub(super) struct Measures {
    /// Its total energy (J).
    pub(super) total: f64,
    /// The total energy of the comparison step `A` (J; NaN when not asked).
    pub(super) total_a: f64,
    /// `‖q − q₀‖_M`.
    pub(super) displacement: f64,
    /// `‖q_A − q‖_M` (NaN when not asked).
    pub(super) difference: f64,
}

/// One window's comparison ([`Controller::compare`]).
pub(super) struct Window {
    /// Ratios of the estimates to their allowances, in [`OBSERVABLES`] order.
    pub(super) ratios: [f64; 4],
    /// The estimates of `B`'s error, in the same order.
    pub(super) d: [f64; 4],
    /// No contact opened or closed in it.
    pub(super) smooth: bool,
    /// `|P_B|`, `|E_B|`, the largest gap change, `‖q_B − q₀‖_M`: the scales' new values.
    pub(super) values: [f64; 4],
    /// `E_B`, where the next window starts.
    pub(super) energy: f64,
}

impl Controller {
    /// The state's displacement norm and, with `energies`, its energies; with
    /// `against_a` the same of the comparison step `A` (its `q`, `v` in `q_a`, `v_a`)
    /// and `‖q_A − q‖_M`. A linear structure reads `M` and `K` once each; any other goes
    /// through the system's energies. Energies not asked are NaN.
    pub(super) fn measure(
        &mut self,
        integ: &dyn Integrator,
        against_a: bool,
        energies: bool,
    ) -> Measures {
        let (s, sys) = (integ.state(), integ.system());
        for (d, (a, b)) in self.disp.iter_mut().zip(self.st.q0.0.iter().zip(&s.q)) {
            *d = b - a;
        }
        if against_a {
            for (d, (a, b)) in self.diff.iter_mut().zip(self.q_a.iter().zip(&s.q)) {
                *d = a - b;
            }
        }
        if !energies {
            let nan = f64::NAN;
            let (u, d) = if against_a {
                let [u, d] = crate::linalg::bilinear_forms(
                    sys.mass.as_ref(),
                    [(&self.disp, &self.disp), (&self.diff, &self.diff)],
                );
                (u, d)
            } else {
                (self.forms.mass_form(sys, &self.disp), nan)
            };
            return Measures {
                total: nan,
                total_a: nan,
                displacement: u.max(0.0).sqrt(),
                difference: d.max(0.0).sqrt(),
            };
        }
        if self.fused {
            let (m, k) = (sys.mass.as_ref(), sys.stiffness.as_ref());
            let [vmv, umu, ama, dmd] = if against_a {
                crate::linalg::bilinear_forms(
                    m,
                    [
                        (&s.v, &s.v),
                        (&self.disp, &self.disp),
                        (&self.v_a, &self.v_a),
                        (&self.diff, &self.diff),
                    ],
                )
            } else {
                let [a, b] =
                    crate::linalg::bilinear_forms(m, [(&s.v, &s.v), (&self.disp, &self.disp)]);
                [a, b, f64::NAN, f64::NAN]
            };
            let [qkq, aka] = if against_a {
                crate::linalg::bilinear_forms(k, [(&s.q, &s.q), (&self.q_a, &self.q_a)])
            } else {
                [
                    crate::linalg::bilinear_forms(k, [(&s.q, &s.q)])[0],
                    f64::NAN,
                ]
            };
            let work = |q: &[f64]| crate::linalg::dot(&sys.force, q);
            return Measures {
                total: 0.5 * vmv + 0.5 * qkq - work(&s.q),
                total_a: if against_a {
                    0.5 * ama + 0.5 * aka - work(&self.q_a)
                } else {
                    f64::NAN
                },
                displacement: umu.max(0.0).sqrt(),
                difference: dmd.max(0.0).sqrt(),
            };
        }
        let (kinetic, v) = sys.energies_with(&self.forms, s.time, &s.q, &s.v, &mut self.scratch);
        let displacement = self.forms.mass_form(sys, &self.disp).max(0.0).sqrt();
        let (total_a, difference) = if against_a {
            let (ka, va) =
                sys.energies_with(&self.forms, s.time, &self.q_a, &self.v_a, &mut self.scratch);
            (
                ka + va,
                self.forms.mass_form(sys, &self.diff).max(0.0).sqrt(),
            )
        } else {
            (f64::NAN, f64::NAN)
        };
        Measures {
            total: kinetic + v,
            total_a,
            displacement,
            difference,
        }
    }

    /// The scales the allowances are relative to, from the maxima met so far (`sc`,
    /// the window's included): the cumulative impulse, the largest gap change and the
    /// largest displacement `‖q − q₀‖_M`, each floored. Running maxima: a window is
    /// never allowed more than the run's own scale at its end would allow (early
    /// windows, whose scale is still small, are held to more).
    pub(super) fn scales(&self, sc: [f64; 4]) -> [f64; 3] {
        let p = self.st.pilot.map(|b| b.0);
        [
            sc[0].max(p[0]),
            sc[2].max(p[1]).max(self.floors[1]),
            sc[3].max(p[2]).max(self.floors[2]),
        ]
    }

    /// Whether no contact opened or closed in the window (impulse signs of `S₀`, `A`,
    /// `B₁`, `B₂` alike).
    pub(super) fn smooth(&self, b2: &crate::integrators::State) -> bool {
        let signs = self.signs();
        (0..b2.impulse.len()).all(|c| !Self::switched(signs, &self.impulse_a, b2, c))
    }

    /// The impulses of `S₀` and `B₁` (`None` before the first window).
    pub(super) fn signs(&self) -> Option<(&[f64], &[f64])> {
        Some((
            &self.s0.vectors.get("impulse")?.0,
            &self.b1.vectors.get("impulse")?.0,
        ))
    }

    /// Whether contact `c` opened or closed in the window (the signs of its impulse at
    /// `S₀`, `A`, `B₁`, `B₂` differ).
    pub(super) fn switched(
        signs: Option<(&[f64], &[f64])>,
        impulse_a: &[f64],
        b2: &crate::integrators::State,
        c: usize,
    ) -> bool {
        let Some((p0, p1)) = signs else {
            return true;
        };
        let on = b2.impulse[c] > 0.0;
        (p0[c] > 0.0) != on || (p1[c] > 0.0) != on || (impulse_a[c] > 0.0) != on
    }

    /// The window's window impulse of `B` (`Σ P` of both steps).
    pub(super) fn impulse_b(&self, b2: &crate::integrators::State) -> f64 {
        let p1: f64 = self
            .b1
            .vectors
            .get("impulse")
            .map_or(0.0, |f| f.0.iter().sum());
        p1 + b2.impulse.iter().sum::<f64>()
    }

    /// The largest change of a gap from the start, and the gaps' difference `|g_A − g_B|`.
    pub(super) fn gaps(&self, b2: &crate::integrators::State) -> (f64, f64) {
        let mut change = 0.0f64;
        let mut diff = 0.0f64;
        let signs = self.signs();
        for c in 0..b2.gap.len() {
            change = change.max((b2.gap[c] - self.st.gap0.0[c]).abs());
            // event location: the gaps of the contacts that opened or closed with an open
            // gap at either end (an impact or a release; module doc)
            let open = [self.gap_s0[c], self.gap_a[c], b2.gap[c]]
                .iter()
                .any(|&g| g > self.floors[1]);
            if open && Self::switched(signs, &self.impulse_a, b2, c) {
                diff = diff.max((b2.gap[c] - self.gap_a[c]).abs());
            }
        }
        (change, diff)
    }

    /// The window's differences `|A − B|` (the estimates of `B`'s error, undivided:
    /// module doc) and their ratios to the allowances.
    pub(super) fn compare(
        &mut self,
        integ: &dyn Integrator,
        big: f64,
        p_a: f64,
        e0: f64,
    ) -> Window {
        let tol = self.spec.tol;
        let span = self.spec.t_end;
        let share = big / span;
        let s = integ.state();
        // the part of the span the window ends at: the budgets are spent in proportion
        let elapsed = (s.time / span).min(1.0);
        let smooth = self.smooth(s);
        let p_b = self.impulse_b(s);
        // a conservative structure's smooth windows keep the energy in both A and B
        // (the trapezoidal rule conserves it exactly): nothing to compare there
        let m = self.measure(integ, true, !(smooth && self.conservative));
        let (e_b, e_a, d_x, u) = if m.total.is_nan() {
            (e0, e0, m.difference, m.displacement)
        } else {
            (m.total, m.total_a, m.difference, m.displacement)
        };
        let s = integ.state();
        let (change, d_g) = self.gaps(s);
        let d = [(p_a - p_b).abs(), (e_a - e_b).abs(), d_g, d_x];
        let ratio = |d: f64, allow: f64| {
            if d == 0.0 {
                0.0
            } else if allow > 0.0 {
                d / allow
            } else {
                f64::INFINITY
            }
        };
        let values = [p_b.abs(), e_b.abs(), change, u];
        let sc = self.st.scales.map(|b| b.0);
        let [impulse, ell, u_scale] =
            self.scales([sc[0] + values[0], 0.0, sc[2].max(change), sc[3].max(u)]);
        let e_scale = sc[1].max(e0.abs()).max(e_b.abs()).max(self.floors[0]);
        // a budget: what the span so far allows less what the kept windows spent, and
        // never below a quarter of the window's own share (a run that overspent at
        // its floor goes on at sane steps; its estimate then says it missed)
        let spent = self.st.sums.map(|b| b.0);
        let budget = |total: f64, spent: f64| (total * elapsed - spent).max(0.25 * total * share);
        Window {
            ratios: [
                ratio(d[0], budget(tol * impulse, spent[0])),
                ratio(d[1], budget(tol * e_scale, spent[1])),
                ratio(d[2], tol * ell),
                ratio(
                    d[3],
                    if smooth {
                        tol * u_scale * share
                    } else {
                        budget(tol * u_scale, spent[4])
                    },
                ),
            ],
            d,
            smooth,
            values,
            energy: e_b,
        }
    }

    /// Adds an accepted window's differences to the sums and its values to the scales.
    pub(super) fn accept(&mut self, w: &Window) {
        use crate::integrators::saved::Bits;
        self.e_next = Some(w.energy);
        let sums = &mut self.st.sums;
        sums[0] = Bits(sums[0].0 + w.d[0]);
        sums[1] = Bits(sums[1].0 + w.d[1]);
        // only a window where a contact opens or closes has a gap difference
        // ([`Controller::gaps`]): the event-location estimate is their largest
        sums[3] = Bits(sums[3].0.max(w.d[2]));
        sums[4] = Bits(sums[4].0 + w.d[3]);
        let sc = &mut self.st.scales;
        sc[0] = Bits(sc[0].0 + w.values[0]);
        sc[1] = Bits(sc[1].0.max(w.values[1]));
        for i in 2..4 {
            sc[i] = Bits(sc[i].0.max(w.values[i]));
        }
    }

    /// The scales of a window accepted at the floor without its comparison (the step
    /// `A` failed): its own values, no difference.
    pub(super) fn accept_scales(&mut self, integ: &dyn Integrator) {
        use crate::integrators::saved::Bits;
        let s = integ.state();
        let p_b = self.impulse_b(s);
        let m = self.measure(integ, false, true);
        let (e_b, u) = (m.total, m.displacement);
        self.e_next = Some(e_b);
        let s = integ.state();
        let (change, _) = self.gaps(s);
        let sc = &mut self.st.scales;
        sc[0] = Bits(sc[0].0 + p_b.abs());
        for (i, x) in [(1, e_b.abs()), (2, change), (3, u)] {
            sc[i] = Bits(sc[i].0.max(x));
        }
    }
}
