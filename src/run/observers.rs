//! The run's own observers: the statistics accumulator, the contact measurement
//! ([`ContactTracker`], in [`super::contact`]), the history and frame writers, the energy balance check and
//! the checkpoint writer, all behind one [`RunObserver`] that the driver calls after
//! every step.

use std::path::PathBuf;
use std::time::Instant;

use super::checkpoint::{self, Checkpoint, RunState};
use super::contact::ContactTracker;
use super::driver::Observer;
use super::summary::{FrictionSummary, Iterations, MeanMax};
use crate::error::Error;
use crate::integrators::saved::{Bits, Floats};
use crate::integrators::{Integrator, StepStats};
use crate::io::OutputOptions;
use crate::io::frames::FrameStream;

#[derive(Default)]
pub(super) struct Acc {
    pub(super) sum: [usize; 4],
    pub(super) max: [usize; 4],
    pub(super) caps: usize,
    pub(super) lcp_res: f64,
    pub(super) violation: f64,
    pub(super) fr_solves: usize,
    pub(super) fr_sweeps: usize,
    pub(super) fr_sweeps_max: usize,
    pub(super) fr_res_sum: f64,
    pub(super) fr_res_max: f64,
    pub(super) fr_steps: usize,
    pub(super) fr_caps: usize,
    pub(super) fr_fallbacks: usize,
    /// Matrix-free solves and their products.
    pub(super) global: [usize; 2],
    /// Coupled position solves, stagnated Newton loops, steps with held rows.
    pub(super) loops: [usize; 4],
    /// Largest relative energy excess met ([`EnergyCheck`]).
    pub(super) energy_excess: f64,
    /// Nonlinear structures: factorizations of `M̂ⁿ`, and the seconds spent assembling
    /// and factoring (this session's steps).
    pub(super) factorizations: usize,
    pub(super) assembly_seconds: f64,
    pub(super) factorization_seconds: f64,
}

impl Acc {
    pub(super) fn add(&mut self, s: &StepStats) {
        let v = [
            s.newton_iterations,
            s.projection_iterations,
            s.index_set_iterations,
            s.lcp_iterations,
        ];
        for i in 0..4 {
            self.sum[i] += v[i];
            self.max[i] = self.max[i].max(v[i]);
        }
        self.caps += s.caps_hit;
        self.loops[0] += s.coupled_solves;
        self.loops[1] += s.newton_stalls;
        self.loops[2] += usize::from(s.held_rows > 0);
        self.loops[3] += s.complementarity_fallbacks;
        self.global[0] += s.global_solves;
        self.global[1] += s.global_products;
        if s.friction_solves > 0 {
            self.fr_solves += s.friction_solves;
            self.fr_sweeps += s.friction_iterations;
            self.fr_sweeps_max = self.fr_sweeps_max.max(s.friction_iterations);
            self.fr_res_sum += s.friction_residual;
            self.fr_res_max = self.fr_res_max.max(s.friction_residual);
            self.fr_steps += 1;
            self.fr_caps += s.friction_caps;
            self.fr_fallbacks += s.friction_fallbacks;
        }
        self.lcp_res = self.lcp_res.max(s.lcp_residual);
        self.violation = self.violation.max(s.max_violation);
        self.factorizations += s.factorizations;
        self.assembly_seconds += s.assembly_seconds;
        self.factorization_seconds += s.factorization_seconds;
    }
    pub(super) fn friction(&self, frictional: bool) -> Option<FrictionSummary> {
        frictional.then(|| FrictionSummary {
            solves: self.fr_solves,
            sweeps_mean: self.fr_sweeps as f64 / self.fr_solves.max(1) as f64,
            sweeps_max_per_step: self.fr_sweeps_max,
            residual_mean: self.fr_res_sum / self.fr_steps.max(1) as f64,
            residual_max: self.fr_res_max,
            caps_hit: self.fr_caps,
            fallbacks: self.fr_fallbacks,
        })
    }
    pub(super) fn iterations(&self, steps: usize) -> Iterations {
        let mm = |i: usize| MeanMax {
            mean: self.sum[i] as f64 / steps.max(1) as f64,
            max: self.max[i],
        };
        Iterations {
            newton: mm(0),
            projection: mm(1),
            index_set: mm(2),
            lcp: mm(3),
        }
    }
}

/// Where the run's output goes and what it costs: the history and frame observers.
pub(super) struct Writers {
    pub(super) history: Option<super::history_thread::History>,
    pub(super) frames: Option<FrameStream>,
    pub(super) frame_stride: usize,
    pub(super) history_stride: usize,
    pub(super) closed_before: bool,
    /// Frames pushed (for checkpoints).
    pub(super) frame_count: usize,
    pub(super) seconds: f64,
}

impl Writers {
    pub(super) fn observe(
        &mut self,
        integ: &dyn Integrator,
        st: &StepStats,
        last: bool,
    ) -> Result<(), Error> {
        if self.history.is_none() {
            return Ok(());
        }
        let t0 = Instant::now();
        let s = integ.state();
        let k = s.step;
        if let Some(w) = self
            .history
            .as_mut()
            .filter(|_| k.is_multiple_of(self.history_stride) || last)
        {
            w.row(integ.system(), s, st)?;
        }
        let closed = s.impulse.iter().any(|&p| p > 0.0);
        let switch = closed != self.closed_before;
        self.closed_before = closed;
        if let Some(w) = self
            .frames
            .as_mut()
            .filter(|_| k.is_multiple_of(self.frame_stride) || last || switch)
        {
            if let Some(hw) = self.history.as_mut() {
                hw.flush()?;
            }
            w.push(s, integ.jacobian(), integ.dt())?;
            self.frame_count += 1;
        }
        self.seconds += t0.elapsed().as_secs_f64();
        Ok(())
    }
}

/// When and where a run writes its checkpoints.
pub(super) struct CheckpointPlan {
    pub(super) every: usize,
    pub(super) dir: PathBuf,
    pub(super) source: serde_json::Value,
    pub(super) output: OutputOptions,
    pub(super) steps: usize,
    pub(super) energy0: f64,
    /// The run's input files at its start, and its directory (canonical), for
    /// [`Checkpoint::verify`].
    pub(super) inputs: Vec<checkpoint::InputFile>,
    pub(super) out_dir: PathBuf,
    /// The running SHA-256 of the history up to the last checkpoint.
    pub(super) history_hash: checkpoint::HistoryHash,
    /// Test hook (`SIGNORINI_ABORT_AFTER_STEP`): abort the process right after this
    /// step's checkpoint and output, as a SIGKILL would, to test `resume`.
    pub(super) abort_after: Option<usize>,
}

/// The run's own observer: statistics, energy balance, contact measurement, output,
/// checkpoints.
pub(super) struct RunObserver {
    pub(super) acc: Acc,
    pub(super) tracker: ContactTracker,
    pub(super) writers: Writers,
    pub(super) h: f64,
    pub(super) plan: Option<CheckpointPlan>,
    pub(super) energy: Option<EnergyCheck>,
    pub(super) probes: super::probes::ProbeSet,
    /// The rotation check of linear bodies, at the energy check's stride.
    pub(super) rotations: Option<super::rotations::RotationCheck>,
    /// The cell that turned most at the last check.
    pub(super) last_rotation: Option<super::rotations::Turned>,
    /// An accuracy run: its windows write the checkpoints
    /// ([`super::RunInProgress::advance`]), never a step inside one.
    pub(super) windowed: bool,
}

/// Steps between two checks of the energy balance (each costs the two quadratic forms
/// of the energy; the work is summed every step).
pub const ENERGY_CHECK_STRIDE: usize = 64;

/// The relative excess from which the energy check bounds the energy's rounding
/// ([`crate::model::energy::EnergyAudit::roundoff`], two passes over `M` and `K`): far
/// below every limit, far above what a clean linear run meets (1.6e-13), so the bar's
/// steps pay nothing for it.
const ROUNDOFF_FROM: f64 = 1e-9;

/// The energy-balance check of a θ-method run (module doc of [`crate::model::energy`]).
pub(super) struct EnergyCheck {
    pub(super) audit: crate::model::energy::EnergyAudit,
    pub(super) theta: f64,
    /// `scheme.max_energy_excess`.
    pub(super) max: f64,
    /// `scheme.allow_caps`: capped steps may be what added the energy.
    pub(super) caps_allowed: bool,
}

impl EnergyCheck {
    /// Sums the step's work; every [`ENERGY_CHECK_STRIDE`] steps and at the last one,
    /// checks the balance (the largest relative excess goes to `worst`).
    pub(super) fn observe(
        &mut self,
        integ: &dyn Integrator,
        last: bool,
        worst: &mut f64,
    ) -> Result<(), Error> {
        let (s, sys, h) = (integ.state(), integ.system(), integ.dt());
        self.audit.advance(sys, s.time - h, h, self.theta, &s.q);
        if !(last || s.step.is_multiple_of(ENERGY_CHECK_STRIDE)) {
            return Ok(());
        }
        let x = self.audit.excess(sys, s.time, &s.q, &s.v);
        let (mut rel, abs) = (x.relative, x.joules);
        if rel > ROUNDOFF_FROM {
            // within the energy's own rounding it is no gain (`model::energy`): the
            // scale is floored so that the rounding sits at the limit
            let bound = self.audit.roundoff(sys, &s.q, &s.v);
            rel = abs / x.scale.max(bound / self.max);
        }
        *worst = worst.max(rel);
        if rel > self.max {
            return Err(Error::RunFailed {
                step: s.step,
                time: s.time,
                contact: None,
                detail: format!(
                    "the energy grew by {abs:.3e} J ({:.3e} of the run's energy scale) beyond \
                     the {:.3e} J supplied by loads and prescribed motion, more than \
                     scheme.max_energy_excess = {}: the solution is not the scheme's (lower \
                     the time step or the tolerances{}, or raise scheme.max_energy_excess \
                     to accept it: {})",
                    rel,
                    self.audit.work(),
                    self.max,
                    if self.caps_allowed {
                        ", do not allow caps (capped steps are not the scheme's solution)"
                    } else {
                        ""
                    },
                    super::driver::MAX_ENERGY_EXCESS_SPELLINGS
                ),
            });
        }
        Ok(())
    }
}

impl Observer for RunObserver {
    fn observe(&mut self, integ: &dyn Integrator, st: &StepStats, last: bool) -> Result<(), Error> {
        self.acc.add(st);
        if let Some(e) = self.energy.as_mut() {
            e.observe(integ, last, &mut self.acc.energy_excess)?;
        }
        let s = integ.state();
        if let Some(r) = self.rotations.as_ref()
            && (last || s.step.is_multiple_of(ENERGY_CHECK_STRIDE))
        {
            self.last_rotation = r.check(s.step, s.time, &s.q)?;
        }
        // each step measured over its own h (the accuracy mode varies it)
        let h = integ.dt();
        let f = s.impulse.iter().sum::<f64>() / h;
        let g = s.gap.iter().copied().fold(f64::INFINITY, f64::min);
        self.tracker.push(s.step - 1, f, g, s.time, h);
        self.probes.observe(s.time, h, &s.q, last);
        self.writers.observe(integ, st, last)?;
        if let Some((every, abort_after)) = self
            .plan
            .as_ref()
            .filter(|_| !self.windowed)
            .map(|p| (p.every, p.abort_after))
        {
            if !last && s.step.is_multiple_of(every) {
                let t0 = Instant::now();
                self.checkpoint(integ, None)?;
                self.writers.seconds += t0.elapsed().as_secs_f64();
            }
            if abort_after == Some(s.step) {
                if let Some(h) = self.writers.history.as_mut() {
                    h.sync()?;
                }
                std::process::abort();
            }
        }
        Ok(())
    }
}

impl RunObserver {
    /// Flushes the history, waits for the queued frames and writes the checkpoint.
    pub(super) fn checkpoint(
        &mut self,
        integ: &dyn Integrator,
        accuracy: Option<super::accuracy::ControllerState>,
    ) -> Result<(), Error> {
        let Some(p) = &mut self.plan else {
            return Ok(());
        };
        let (history_bytes, history_rows) = match self.writers.history.as_mut() {
            Some(h) => h.sync()?,
            None => (0, 0),
        };
        let history = crate::io::part_path(&p.dir.join("history.csv"));
        let (kept, hashed) =
            checkpoint::hash_history(&history, std::mem::take(&mut p.history_hash), history_bytes)?;
        p.history_hash = kept;
        let p = &*p;
        if let Some(f) = self.writers.frames.as_mut() {
            f.sync()?;
        }
        let a = &self.acc;
        let t = &self.tracker;
        let run = RunState {
            sum: a.sum,
            max: a.max,
            caps: a.caps,
            lcp_res: Bits(a.lcp_res),
            violation: Bits(a.violation),
            friction_counts: [
                a.fr_solves,
                a.fr_sweeps,
                a.fr_sweeps_max,
                a.fr_steps,
                a.fr_caps,
                a.fr_fallbacks,
            ],
            friction_residual: [Bits(a.fr_res_sum), Bits(a.fr_res_max)],
            newton_loops: a.loops,
            global: a.global,
            factorizations: a.factorizations,
            energy_audit: self
                .energy
                .as_ref()
                .map_or([0.0; 6], |e| e.audit.save())
                .map(Bits),
            energy_excess: Bits(a.energy_excess),
            trace: t.trace.clone().map(Floats),
            trace_dt: t.trace_dt.clone().map(Floats),
            contact_dt: Floats(t.dt.clone()),
            first_contact_start: Bits(t.first_time),
            total_impulse: Bits(t.total_impulse),
            varied: t.varied,
            first_contact: t.first,
            contact_force: Floats(t.force.clone()),
            contact_min_gap: Floats(t.min_gap.clone()),
            contact_done: t.done,
            total_force: Bits(t.total_force),
            energy0: Bits(p.energy0),
            history_bytes,
            history_sha256: hashed.hex(),
            history_rows,
            frames: self.writers.frame_count,
            closed_before: self.writers.closed_before,
            probes: self.probes.save().into_iter().map(Floats).collect(),
            accuracy,
        };
        Checkpoint {
            format: checkpoint::FORMAT.to_string(),
            version: checkpoint::VERSION,
            source: p.source.clone(),
            output: p.output.clone(),
            every: p.every,
            steps: p.steps,
            integrator: integ.save(),
            run,
            build: checkpoint::build_id(),
            out_dir: p.out_dir.clone(),
            inputs: p.inputs.clone(),
            arithmetic: crate::linalg::arithmetic(),
            subnormals: crate::linalg::subnormals::current_thread(),
            digest: String::new(),
        }
        .write(&p.dir)
    }

    /// The accumulators of a checkpoint.
    pub(super) fn restore(&mut self, r: &RunState) {
        let a = &mut self.acc;
        (a.sum, a.max, a.caps) = (r.sum, r.max, r.caps);
        (a.lcp_res, a.violation) = (r.lcp_res.0, r.violation.0);
        [
            a.fr_solves,
            a.fr_sweeps,
            a.fr_sweeps_max,
            a.fr_steps,
            a.fr_caps,
            a.fr_fallbacks,
        ] = r.friction_counts;
        (a.fr_res_sum, a.fr_res_max) = (r.friction_residual[0].0, r.friction_residual[1].0);
        a.loops = r.newton_loops;
        a.global = r.global;
        a.factorizations = r.factorizations;
        a.energy_excess = r.energy_excess.0;
        let t = &mut self.tracker;
        t.trace = r.trace.as_ref().map(|f| f.0.clone());
        t.trace_dt = r.trace_dt.as_ref().map(|f| f.0.clone());
        t.dt = r.contact_dt.0.clone();
        t.first_time = r.first_contact_start.0;
        t.total_impulse = r.total_impulse.0;
        t.varied = r.varied;
        t.first = r.first_contact;
        t.force = r.contact_force.0.clone();
        t.min_gap = r.contact_min_gap.0.clone();
        t.done = r.contact_done;
        t.total_force = r.total_force.0;
        self.writers.closed_before = r.closed_before;
        self.writers.frame_count = r.frames;
    }
}
