//! Forming the iterate from the impulses (eq. 56a, 58, 60):
//! `v = v_free + M̂⁻¹G P − hθ M̂⁻¹K N G τ`, `q = q_k + h(1−θ)v_k + hθ v + N G τ`, fused into
//! one pass over the state where the operators are constant, or on the contact zone's
//! dofs alone while the loop iterates there.

use super::*;

impl ThetaCore {
    /// `v = v_free + M̂⁻¹G P − hθ M̂⁻¹K N G τ_used`, `q = q_k + h(1−θ)v_k + hθ v + N G τ`.
    pub(crate) fn form(&mut self) {
        let (h, th) = (self.h, self.cfg.theta);
        if self.cfg.operators_constant {
            // called once per step: v_free is not needed afterwards (begin_step
            // rewrites it), so hand its buffer over instead of copying
            std::mem::swap(&mut self.dofs.v_new, &mut self.dofs.v_free);
        } else {
            self.dofs.v_new.copy_from_slice(&self.dofs.v_free);
        }
        // a nonlinear structure has the projection's feedback in F(q_θ) (module doc of
        // `structure`)
        let kfac = if self.cfg.feedback && self.structure.step_matrix_constant() {
            -h * th
        } else {
            0.0
        };
        self.carry.state_finite = None;
        if self.cfg.operators_constant && self.form_fused(kfac) {
            return;
        }
        self.del.add_velocity_correction(
            &self.rs.p,
            kfac,
            &self.rs.tau_used,
            &self.rs.tau,
            &mut self.dofs.v_new,
            &self.sys.stiffness,
        );
        let s = &self.state;
        for (((qn, q), v), vn) in self
            .dofs
            .q_new
            .iter_mut()
            .zip(&s.q)
            .zip(&s.v)
            .zip(&self.dofs.v_new)
        {
            *qn = q + h * ((1.0 - th) * v + th * vn);
        }
        self.del
            .add_position_correction(&self.rs.tau, &mut self.dofs.q_new);
    }

    /// [`ThetaCore::form`] in one pass over the state where the corrections are dense
    /// columns ([`Delassus::dense_columns`]) and at most one row carries each of `P`,
    /// `τ_used` (with feedback) and `τ` (a bar's tip, a few nodes on a plane, one at a
    /// time): per dof the same operations in the same order as the axpys of the general
    /// path, so the same bits, with the next step's `y = q + hθ v` written alongside
    /// (`q_lin`, read by [`ThetaCore::begin_step`]). At 10⁶ dofs the separate passes
    /// read and wrote the state four more times per step than a C loop of it (issue 35).
    /// Returns false (nothing done) where the general path must run.
    pub(super) fn form_fused(&mut self, kfac: f64) -> bool {
        let Some((cg, d)) = self.del.dense_columns() else {
            return false;
        };
        let n = self.cfg.n;
        // the one nonzero row of each vector, if one: (column offset, scale)
        let one = |x: &[f64], s: f64| -> Result<Option<(usize, f64)>, ()> {
            let mut it = x.iter().enumerate().filter(|(_, v)| **v != 0.0);
            match (it.next(), it.next()) {
                (None, _) => Ok(None),
                (Some((a, &v)), None) => Ok(Some((a * n, s * v))),
                _ => Err(()),
            }
        };
        let (Ok(p), Ok(fb), Ok(t)) = (
            one(&self.rs.p, 1.0),
            if kfac != 0.0 {
                one(&self.rs.tau_used, kfac)
            } else {
                Ok(None)
            },
            one(&self.rs.tau, 1.0),
        ) else {
            return false;
        };
        if fb.is_some() && d.len() < cg.len() {
            return false;
        }
        let s = &self.state;
        let cols = [(p, cg), (fb, d), (t, cg)].map(|(c, src)| match c {
            Some((o, k)) => (&src[o..o + n], k),
            None => (&s.q[..], 0.0),
        });
        let out = (
            &mut self.dofs.q_new[..],
            &mut self.dofs.v_new[..],
            &mut self.dofs.q_lin[..],
        );
        let args = (&s.q[..], &s.v[..], out, cols, (self.h, self.cfg.theta));
        let finite = fused_update_with((p.is_some(), fb.is_some(), t.is_some()), args);
        self.carry.state_finite = Some(finite);
        self.carry.y_ready = true;
        true
    }

    /// [`ThetaCore::form`] on the contact zone only (`zq_new`): with `G = S B` the gaps and
    /// `G` depend on the zone's dofs alone, and on a linear structure the zone rows of the
    /// corrections are `F (B p) − hθ F_E (B τ_used)` and `(N G τ)_zone`
    /// ([`Delassus::zone_corrections`]), so a Newton iteration needs no sparse solve;
    /// [`ThetaCore::commit`] forms the whole state once with the converged impulses.
    pub(super) fn form_zone(&mut self) {
        let (h, th) = (self.h, self.cfg.theta);
        let kfac = if self.cfg.feedback { -h * th } else { 0.0 };
        self.del.zone_corrections(
            &self.rs.p,
            kfac,
            &self.rs.tau_used,
            &self.rs.tau,
            &mut self.zone.velocity_correction,
            &mut self.zone.position_correction,
        );
        let s = &self.state;
        for (k, &d) in self.zone.dofs.iter().enumerate() {
            let vn = self.dofs.v_free[d] + self.zone.velocity_correction[k];
            self.zone.q_iterate[k] =
                s.q[d] + h * ((1.0 - th) * s.v[d] + th * vn) + self.zone.position_correction[k];
        }
    }
}

/// The arguments of [`fused_update`]: `q_k`, `v_k`, the outputs (`q_new`, `v_new`
/// holding `v_free` on entry, `y`), the three columns with their scales (the impulse's
/// `Â⁻¹G`, the feedback's `Â⁻¹K N G`, the projection's `Â⁻¹G`; unused ones any slice of
/// length `n`) and `(h, θ)`.
pub(super) type FusedArgs<'a> = (
    &'a [f64],
    &'a [f64],
    (&'a mut [f64], &'a mut [f64], &'a mut [f64]),
    [(&'a [f64], f64); 3],
    (f64, f64),
);

/// [`fused_update`] with the terms `(P, F, T)` given at run time.
pub(super) fn fused_update_with(terms: (bool, bool, bool), args: FusedArgs<'_>) -> bool {
    match terms {
        (false, false, false) => fused_update::<false, false, false>(args),
        (true, false, false) => fused_update::<true, false, false>(args),
        (false, true, false) => fused_update::<false, true, false>(args),
        (true, true, false) => fused_update::<true, true, false>(args),
        (false, false, true) => fused_update::<false, false, true>(args),
        (true, false, true) => fused_update::<true, false, true>(args),
        (false, true, true) => fused_update::<false, true, true>(args),
        (true, true, true) => fused_update::<true, true, true>(args),
    }
}

/// One pass of [`ThetaCore::form_fused`]: `v += k_P c_P + k_F c_F`,
/// `q = q_k + h((1 − θ) v_k + θ v) + k_τ c_τ`, `y = q + hθ v`, each term where its
/// const flag is set, in the order of the general path's axpys. Returns whether every
/// new `q` and `v` is finite (an integer test of the exponent bits, which vectorizes).
#[inline(never)]
pub(super) fn fused_update<const P: bool, const F: bool, const T: bool>(
    args: FusedArgs<'_>,
) -> bool {
    const EXP: u64 = 0x7ff0_0000_0000_0000;
    let (q, v, (qn, vn, y), [(cp, kp), (cf, kf), (ct, kt)], (h, th)) = args;
    let n = q.len();
    assert!(v.len() == n && qn.len() == n && vn.len() == n && y.len() == n);
    assert!(cp.len() == n && cf.len() == n && ct.len() == n);
    let mut bad = 0u64;
    for i in 0..n {
        let mut a = vn[i];
        if P {
            a += kp * cp[i];
        }
        if F {
            a += kf * cf[i];
        }
        let mut b = q[i] + h * ((1.0 - th) * v[i] + th * a);
        if T {
            b += kt * ct[i];
        }
        vn[i] = a;
        qn[i] = b;
        y[i] = b + h * th * a;
        bad |= u64::from(a.to_bits() & EXP == EXP) | u64::from(b.to_bits() & EXP == EXP);
    }
    bad == 0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fused pass gives the bits of the general path's separate passes (the axpys of
    /// `Delassus::add_velocity_correction` and `add_position_correction` around the
    /// update loop) for every combination of terms, and reports a non-finite `q` or `v`
    /// (the run's checks then skip their own scan: it must not miss one).
    #[test]
    fn fused_update_matches_the_separate_passes_and_finds_non_finite_values() {
        let n = 37;
        let wave = |k: f64| -> Vec<f64> { (0..n).map(|i| (k * i as f64).sin() * 1e-3).collect() };
        let (q, v, vf) = (wave(0.3), wave(0.7), wave(1.1));
        let (cp, cf, ct) = (wave(1.7), wave(2.3), wave(2.9));
        let (kp, kf, kt, h, th) = (3.7, -1.3e-7, 0.9, 2e-7, 0.5);
        // the fused pass from q_k = `q`, v_free = `vf`: (q, v, y) and the finiteness
        let fused = |terms: (bool, bool, bool), q: &[f64], vf: &[f64], kt: f64| {
            let (mut q2, mut v2, mut y2) = (vec![0.0; n], vf.to_vec(), vec![0.0; n]);
            let cols = [(&cp[..], kp), (&cf[..], kf), (&ct[..], kt)];
            let args = (
                q,
                &v[..],
                (&mut q2[..], &mut v2[..], &mut y2[..]),
                cols,
                (h, th),
            );
            let finite = fused_update_with(terms, args);
            (q2, v2, y2, finite)
        };
        for mask in 0..8 {
            let (p, f, t) = (mask & 1 != 0, mask & 2 != 0, mask & 4 != 0);
            // the general path
            let mut v1 = vf.clone();
            if p {
                v1.iter_mut().zip(&cp).for_each(|(y, x)| *y += kp * x);
            }
            if f {
                v1.iter_mut().zip(&cf).for_each(|(y, x)| *y += kf * x);
            }
            let mut q1: Vec<f64> = (0..n)
                .map(|i| q[i] + h * ((1.0 - th) * v[i] + th * v1[i]))
                .collect();
            if t {
                q1.iter_mut().zip(&ct).for_each(|(y, x)| *y += kt * x);
            }
            let y1: Vec<f64> = (0..n).map(|i| q1[i] + h * th * v1[i]).collect();
            // the fused pass
            let (q2, v2, y2, finite) = fused((p, f, t), &q, &vf, kt);
            assert!(finite);
            for (a, b) in [(&q1, &q2), (&v1, &v2), (&y1, &y2)] {
                assert!(
                    a.iter()
                        .zip(b.iter())
                        .all(|(x, y)| x.to_bits() == y.to_bits())
                );
            }
        }
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            for at in [0, 17, n - 1] {
                let mut vb = vf.clone();
                vb[at] = bad;
                let (.., finite) = fused((false, false, false), &q, &vb, kt);
                assert!(!finite, "{bad} at {at}");
            }
        }
        // a finite v whose q overflows: reported, or every q finite
        let mut qb = q.clone();
        qb[5] = f64::MAX;
        let (q2, .., finite) = fused((false, false, true), &qb, &vf, 1e300);
        assert!(!finite || q2.iter().all(|x| x.is_finite()));
    }
}
