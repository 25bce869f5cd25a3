//! The step `h` as a per-step parameter ([`ThetaCore::set_dt`]).
//!
//! What depends on `h`: the step matrix `M̂(h)` of the scheme
//! ([`crate::integrators::step_matrix::StepForm`]) and everything condensed on its factor
//! (`W = GᵀM̂⁻¹G`, `W_D`, `W_N` under the `M̂⁻¹` metric, the zone's flexibilities), the
//! free step's `q + hθv`, and the clock `t_k`. On a structure whose `M̂` is constant the
//! Delassus data of each `h` (its factor included) are formed through the structure's one
//! call ([`crate::integrators::structure::StructureModel::factor`]) in the build's order
//! ([`ThetaCore::condense_at`]) and kept in a cache of [`STEP_CACHE_ENTRIES`] other steps
//! within [`STEP_CACHE_BYTES`], least recently used dropped first (formed again when
//! asked again); a structure that forms `M̂ⁿ` at every step needs nothing but the new `h`.
//!
//! The clock restarts at each change: `t_k = t_o + (k − k_o)·h` from the step `k_o` and
//! time `t_o` of the change, so a run at one `h` keeps `t_k = k·h` to the bit. A step
//! changed by [`ThetaCore::set_dt`] continues exactly as a run resumed from a checkpoint
//! at the new `h` would (the checkpoint records the `h` it ran at and the clock's
//! origin; `tests/regression_step_size_change.rs`).

use super::*;
use crate::integrators::saved::{Bits, IntegratorState};

/// Other step sizes whose Delassus data a [`ThetaCore`] keeps (the accuracy mode's
/// ladder of steps: one up, one down and the last two).
pub const STEP_CACHE_ENTRIES: usize = 4;

/// Bytes the kept Delassus data of other step sizes may hold in all (factors and
/// condensed blocks, by [`Delassus::bytes`]): 1 GiB. A data set larger than this alone is
/// never kept.
pub const STEP_CACHE_BYTES: u64 = 1 << 30;

/// The Delassus data of other step sizes (module doc), most recently used last.
#[derive(Debug)]
pub(crate) struct StepCache {
    entries: Vec<(u64, Delassus)>,
}

impl StepCache {
    /// An empty cache whose list never grows past its first allocation.
    pub(crate) fn new() -> Self {
        StepCache {
            entries: Vec::with_capacity(STEP_CACHE_ENTRIES + 1),
        }
    }
}

impl StepCache {
    /// Takes the data of step `h` out of the cache, if kept.
    fn take(&mut self, h: f64) -> Option<Delassus> {
        let i = self.entries.iter().position(|(b, _)| *b == h.to_bits())?;
        Some(self.entries.remove(i).1)
    }

    /// Keeps the data of step `h`, dropping the least recently used beyond the entries'
    /// or the bytes' limit.
    fn put(&mut self, h: f64, del: Delassus) {
        if del.bytes() > STEP_CACHE_BYTES {
            return;
        }
        self.entries.push((h.to_bits(), del));
        while self.entries.len() > STEP_CACHE_ENTRIES
            || self.entries.iter().map(|(_, d)| d.bytes()).sum::<u64>() > STEP_CACHE_BYTES
        {
            self.entries.remove(0);
        }
    }
}

impl ThetaCore {
    /// Whether the structure's `M̂` is constant at a given `h`.
    pub fn step_matrix_constant(&self) -> bool {
        self.structure.step_matrix_constant()
    }

    /// Makes `h` the step of the next steps (module doc). On a constant `M̂` the factor
    /// and Delassus data of `h` come from the cache or are formed (counted in the next
    /// step's [`StepStats::factorizations`]); the state, the impulses and the contact data
    /// carry over as through a checkpoint. The same `h` (to the bit) changes nothing.
    pub fn set_dt(&mut self, scheme: &str, h: f64) -> Result<(), Error> {
        if h.to_bits() == self.h.to_bits() {
            return Ok(());
        }
        crate::error::require_positive("dt", h)?;
        let mut saved = std::mem::take(&mut self.carry.snapshot);
        self.save_into(scheme, &mut saved);
        if self.structure.step_matrix_constant() {
            let fresh = match self.step_cache.take(h) {
                Some(d) => {
                    let old = std::mem::replace(&mut self.del, d);
                    self.step_cache.put(self.h, old);
                    None
                }
                None => Some(self.factor_at(h)?),
            };
            if let Some(del) = fresh {
                self.carry.pending_factorizations += 1;
                let old = std::mem::replace(&mut self.del, del);
                let p = self.cfg.built;
                self.condense(&p);
                self.del.start_stepping();
                self.step_cache.put(self.h, old);
            }
        }
        self.h = h;
        let restored = self.restore(scheme, &saved);
        self.carry.snapshot = saved;
        restored
    }

    /// The factor of `M̂(h)` through the structure's one call, in Delassus storage sized
    /// as [`ThetaCore::new`] sizes it, with `G` evaluated at the state (not yet condensed:
    /// [`ThetaCore::condense`]).
    fn factor_at(&mut self, h: f64) -> Result<Delassus, Error> {
        let p = self.cfg.built;
        // a constant `M̂(h)` has one pattern for every h: the structure factors it on
        // the current factor's symbolic analysis, handed over with the matrix formed
        // (a backend without one to share, or another pattern, is analysed afresh)
        let form = self.cfg.step_form;
        let planned = match self.del.factor.analysis() {
            Some(an) if self.structure.step_matrix_constant() => {
                let mut m = crate::integrators::step_matrix::StepMatrix::form(
                    &self.sys,
                    form.coefficients(h),
                );
                m.keep_analysis(Some(an));
                Some(m)
            }
            _ => None,
        };
        let factor = self.structure.factor(
            &self.sys,
            (form, h),
            (&self.state.q, &self.state.v),
            planned,
        )?;
        let jac = ContactJacobian::for_set(self.contacts.as_ref());
        let mut del = Delassus::new(
            factor,
            jac,
            self.cfg.n,
            (p.delassus, p.delassus_pool),
            self.cfg.with_projection,
            p.metric,
            self.cfg.operators_constant,
        )?;
        del.limit_columns(workspace_cap(self.cfg.rows, &p));
        let mut gap = vec![0.0; self.cfg.m];
        self.contacts
            .evaluate(&self.state.q, &mut gap, &mut del.jac);
        Ok(del)
    }

    /// What the build does to the Delassus data of a constant `M̂` once `G` is evaluated
    /// (the zone's condensation, `W` and its companions, the matrix-free threshold's
    /// column limit, the products' flexibilities), on `self.del`; the zone's and the
    /// workspaces' buffers are sized by the first call (the build's) and only read after.
    pub(super) fn condense(&mut self, params: &SchemeParams) {
        if !self.cfg.g_constant && self.contacts.condensed() {
            let zone = self.contacts.zone();
            let fixed = fixed_rows(self.contacts.as_ref());
            self.del
                .condense_zone(&zone, fixed, &self.sys.stiffness, true);
            if self.zone.dofs.is_empty()
                && let Some(dofs) = self.del.flexibility_zone()
            {
                let z = dofs.len();
                self.zone.dofs = dofs.to_vec();
                for buf in [
                    &mut self.zone.velocity_correction,
                    &mut self.zone.position_correction,
                    &mut self.zone.q_iterate,
                    &mut self.zone.q_last,
                    &mut self.zone.q_start,
                ] {
                    *buf = vec![0.0; z];
                }
            }
        }
        self.del.refresh(&self.sys.stiffness);
        let rows_mf = matrix_free_rows(self.ws.cap, self.cfg.g_constant, self.del.is_dense());
        if rows_mf < self.ws.cap {
            self.ws.matrix_free_from(rows_mf, params);
            self.del.limit_columns(rows_mf);
            if let Some(cp) = self.coupled.as_mut() {
                cp.cap = cp.cap.min(rows_mf);
            }
        }
        // a constant G whose problems may go matrix-free: its products through the
        // zone flexibilities F (formed once from the factor) instead of a solve each
        if self.cfg.g_constant && self.ws.matrix_free.capacity() > 0 {
            self.del.condense_products();
        }
    }

    /// The state a checkpoint saves ([`IntegratorState`]), with the step it ran at and the
    /// clock's origin.
    pub fn save(&self, scheme: &str) -> IntegratorState {
        let mut s = IntegratorState::default();
        self.save_into(scheme, &mut s);
        s
    }

    /// [`ThetaCore::save`] into `s`, reusing its buffers (no allocation once `s` holds a
    /// state of this size).
    pub fn save_into(&self, scheme: &str, s: &mut IntegratorState) {
        self.state.save_into(scheme, s);
        s.dt = Some(Bits(self.h));
        s.impulse_dt =
            (self.carry.warm_h.to_bits() != self.h.to_bits()).then_some(Bits(self.carry.warm_h));
        s.origin = (self.carry.origin != (0, 0.0))
            .then_some((self.carry.origin.0, Bits(self.carry.origin.1)));
    }

    /// The clock of a restored state `s`: its origin, or the restored step when it ran at
    /// another `h` than this core's.
    pub(super) fn restore_clock(&mut self, s: &IntegratorState) {
        // the impulse was made over the saving core's step unless it says otherwise
        self.carry.warm_h = s.impulse_dt.or(s.dt).map_or(self.h, |d| d.0);
        self.carry.origin = s.origin.map_or((0, 0.0), |(k, t)| (k, t.0));
        if s.dt.is_some_and(|d| d.0.to_bits() != self.h.to_bits()) {
            self.carry.origin = (s.step, s.time.0);
        }
    }
}

/// Per contact row, whether its block of `G` is constant
/// ([`ContactSet::block_is_linear`]), for the zone condensation.
pub(crate) fn fixed_rows(contacts: &dyn ContactSet) -> Vec<bool> {
    (0..contacts.len())
        .flat_map(|a| std::iter::repeat_n(contacts.block_is_linear(a), contacts.dim(a)))
        .collect()
}
