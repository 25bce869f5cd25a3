//! Displacement probes (a scene's `[[probes]]`): the mean displacement of a node set at
//! named times, measured as the run goes and reported in the summary
//! ([`ProbeSummary`]), with the impacting bar's closed form
//! ([`ImpactingBar::displacement`]) beside it on a rod when the scene has that
//! reference.
//!
//! The θ-method's displacement is linear within a step (`q_{k+1} = q_k + h(θ v_{k+1} +
//! (1−θ) v_k)`, eq. 18), so a probe time `t*` in `(t_k, t_{k+1}]` is read by linear
//! interpolation between the states of the two steps. The previous state is kept only
//! for the probes whose next time falls within the coming step, so the per-step cost
//! is one comparison per probe; nothing is allocated after [`ProbeSet::new`].
//! Schatzman–Paoli's positions are its own (eq. 20–22): they are read the same way.

use serde::Serialize;

use crate::analytic::ImpactingBar;
use crate::model::TimeFunction;
use crate::model::geometry::{Geometry, Probe};

/// Where one displacement component of a probe point is read.
#[derive(Clone, Copy, Debug)]
enum Source {
    /// A dof of the integrated system.
    Dof(usize),
    /// Fixed: zero.
    Fixed,
    /// Moved at `w φ(t)`: `u = w ∫₀ᵗ φ`, `φ` the index into [`ProbeSet::functions`].
    Prescribed(f64, usize),
}

/// One probe as the run reads it.
#[derive(Clone, Debug)]
struct Reader {
    probe: Probe,
    /// `point · dim + component` of the probe's points.
    sources: Vec<Source>,
    /// Times recorded so far: `values[dim·k .. dim·(k+1)]` at `probe.times[k]`.
    values: Vec<f64>,
    /// The displacement at `prev_time`, kept when the next time falls in the coming step.
    prev: Vec<f64>,
    prev_time: f64,
    /// Scratch: the current displacement.
    now: Vec<f64>,
    /// Mean reference position of the points (m).
    position: [f64; 3],
}

/// The run's probes.
#[derive(Clone, Debug, Default)]
pub struct ProbeSet {
    readers: Vec<Reader>,
    dim: usize,
    functions: Vec<TimeFunction>,
}

/// A probe's result in `summary.json`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ProbeSummary {
    /// The probe's name.
    pub name: String,
    /// Its body.
    pub body: String,
    /// Its node set.
    pub nodes: String,
    /// Nodes in the set (the displacement is their mean).
    pub node_count: usize,
    /// Mean reference position of the nodes (m).
    pub position: [f64; 3],
    /// The probe's times (s).
    pub times: Vec<f64>,
    /// The mean displacement at each time (m; one component per space dimension).
    pub displacement: Vec<Vec<f64>>,
    /// The impacting bar's closed form at the same times (rods of a scene with that
    /// reference).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub analytic: Option<Vec<Vec<f64>>>,
    /// `max |u − u_analytic| / max |u_analytic|` over the times.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub analytic_error: Option<f64>,
}

impl ProbeSet {
    /// The probes of `probes` read through `geometry`'s dof map (taken before the
    /// geometry goes to the frame writer).
    pub fn new(probes: &[Probe], geometry: &Geometry) -> ProbeSet {
        let dim = geometry.dim.max(1);
        let readers = probes
            .iter()
            .map(|p| {
                let sources = p
                    .points
                    .iter()
                    .flat_map(|&pt| (0..dim).map(move |i| pt * dim + i))
                    .map(|k| match geometry.dof_of.get(k).copied().flatten() {
                        Some(d) => Source::Dof(d),
                        // `prescribed` lists its components in increasing order
                        None => geometry
                            .prescribed
                            .binary_search_by_key(&k, |x| x.0)
                            .map_or(Source::Fixed, |i| {
                                let (_, w, f) = geometry.prescribed[i];
                                Source::Prescribed(w, f)
                            }),
                    })
                    .collect();
                let n = p.points.len().max(1) as f64;
                let mut position = [0.0; 3];
                for x in p.points.iter().filter_map(|&pt| geometry.points.get(pt)) {
                    for i in 0..3 {
                        position[i] += x[i] / n;
                    }
                }
                Reader {
                    probe: p.clone(),
                    sources,
                    values: Vec::with_capacity(p.times.len() * dim),
                    prev: vec![0.0; dim],
                    prev_time: f64::NAN,
                    now: vec![0.0; dim],
                    position,
                }
            })
            .collect();
        ProbeSet {
            readers,
            dim,
            functions: geometry.prescribed_functions.clone(),
        }
    }

    /// Whether there is no probe.
    pub fn is_empty(&self) -> bool {
        self.readers.is_empty()
    }

    /// Starts (or resumes with `saved`, the values of [`ProbeSet::save`]) at the state
    /// `(t, q)`: times at or before `t` not yet recorded are read from it.
    pub fn start(&mut self, t: f64, h: f64, q: &[f64], saved: Option<&[Vec<f64>]>) {
        if let Some(saved) = saved {
            for (r, v) in self.readers.iter_mut().zip(saved) {
                r.values.clear();
                r.values.extend_from_slice(v);
            }
        }
        self.observe(t, h, q, false);
    }

    /// After a step ending at `t` with state `q` (`last`: the run's last step, which
    /// records every time still pending).
    pub fn observe(&mut self, t: f64, h: f64, q: &[f64], last: bool) {
        let (dim, functions) = (self.dim, &self.functions);
        // a time at a step, up to the round-off of the accumulated step times
        let tol = 1e-9 * h;
        for r in &mut self.readers {
            let next = |r: &Reader| r.probe.times.get(r.values.len() / dim).copied();
            let Some(t_next) = next(r) else {
                continue;
            };
            let pending = t_next <= t + tol || last;
            if !pending && t_next > t + h + tol {
                continue;
            }
            mean_displacement(&r.probe, &r.sources, functions, t, q, &mut r.now);
            while let Some(ts) = next(r).filter(|&ts| ts <= t + tol || last) {
                // the step's linear displacement; at the start (no previous state) and
                // at a step time the current state itself
                let s = if r.prev_time.is_nan() || t - r.prev_time <= 0.0 {
                    1.0
                } else {
                    ((ts - r.prev_time) / (t - r.prev_time)).clamp(0.0, 1.0)
                };
                for i in 0..dim {
                    let (a, b) = (r.prev[i], r.now[i]);
                    r.values.push(if s == 1.0 { b } else { a + s * (b - a) });
                }
            }
            if next(r).is_some_and(|ts| ts <= t + h + tol) {
                r.prev.copy_from_slice(&r.now);
                r.prev_time = t;
            }
        }
    }

    /// The values recorded so far, per probe (what a checkpoint keeps).
    pub fn save(&self) -> Vec<Vec<f64>> {
        self.readers.iter().map(|r| r.values.clone()).collect()
    }

    /// The summaries, with the closed form of `reference` beside rods' probes.
    pub fn summaries(&self, reference: Option<&ImpactingBar>) -> Vec<ProbeSummary> {
        self.readers
            .iter()
            .map(|r| {
                let p = &r.probe;
                let dim = self.dim;
                let n = p.points.len().max(1) as f64;
                let displacement: Vec<Vec<f64>> =
                    r.values.chunks(dim).map(<[f64]>::to_vec).collect();
                let analytic = reference.zip(p.rod_abscissa.as_ref()).map(|(b, xs)| {
                    p.times
                        .iter()
                        .map(|&t| vec![xs.iter().map(|&x| b.displacement(x, t)).sum::<f64>() / n])
                        .collect::<Vec<_>>()
                });
                let analytic_error = analytic.as_ref().and_then(|a| {
                    let scale = a.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
                    (scale > 0.0 && displacement.len() == a.len()).then(|| {
                        displacement
                            .iter()
                            .flatten()
                            .zip(a.iter().flatten())
                            .fold(0.0f64, |m, (u, v)| m.max((u - v).abs()))
                            / scale
                    })
                });
                ProbeSummary {
                    name: p.name.clone(),
                    body: p.body.clone(),
                    nodes: p.nodes.clone(),
                    node_count: p.points.len(),
                    position: r.position,
                    times: p.times.clone(),
                    displacement,
                    analytic,
                    analytic_error,
                }
            })
            .collect()
    }
}

/// The mean displacement of `probe`'s points at `(t, q)` into `out`.
fn mean_displacement(
    probe: &Probe,
    sources: &[Source],
    functions: &[TimeFunction],
    t: f64,
    q: &[f64],
    out: &mut [f64],
) {
    let dim = out.len();
    out.iter_mut().for_each(|x| *x = 0.0);
    for (k, s) in sources.iter().enumerate() {
        out[k % dim] += match *s {
            Source::Dof(d) => q[d],
            Source::Fixed => 0.0,
            Source::Prescribed(w, f) => w * functions[f].integral(t),
        };
    }
    let n = probe.points.len().max(1) as f64;
    out.iter_mut().for_each(|x| *x /= n);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A two-point, one-dimensional geometry: point 0 on dof 0, point 1 fixed.
    fn set(times: Vec<f64>) -> ProbeSet {
        let g = Geometry {
            dim: 1,
            points: vec![[0.0; 3], [1.0, 0.0, 0.0]],
            dof_of: vec![Some(0), None],
            ..Geometry::default()
        };
        let probes = [
            Probe {
                name: "a".into(),
                points: vec![0],
                times: times.clone(),
                ..Probe::default()
            },
            Probe {
                name: "mean".into(),
                points: vec![0, 1],
                times,
                ..Probe::default()
            },
        ];
        ProbeSet::new(&probes, &g)
    }

    #[test]
    fn reads_step_times_exactly_and_interpolates_between_steps() {
        // q(t) = 3 t on a grid of h = 0.1: times at 0, between steps, at a step and at
        // the end read 3 t (linear, so the interpolation is exact up to round-off)
        let h = 0.1;
        let times = vec![0.0, 0.25, 0.3, 0.999];
        let mut p = set(times.clone());
        p.start(0.0, h, &[0.0], None);
        for k in 1..=10 {
            let t = k as f64 * h;
            p.observe(t, h, &[3.0 * t], k == 10);
        }
        let s = p.summaries(None);
        for (u, t) in s[0].displacement.iter().zip(&times) {
            assert!((u[0] - 3.0 * t).abs() < 1e-14, "t = {t}: {}", u[0]);
        }
        // the mean over a moving and a fixed point is half
        for (u, t) in s[1].displacement.iter().zip(&times) {
            assert!((u[0] - 1.5 * t).abs() < 1e-14, "t = {t}: {}", u[0]);
        }
        assert_eq!(s[1].position, [0.5, 0.0, 0.0]);
        assert_eq!(s[0].node_count, 1);
    }

    #[test]
    fn a_prescribed_component_reads_its_prescribed_displacement() {
        // point 0 on dof 0, point 1 moved at w φ(t) = 2 m/s (φ = 1): u = 2 t
        let g = Geometry {
            dim: 1,
            points: vec![[0.0; 3], [1.0, 0.0, 0.0]],
            dof_of: vec![Some(0), None],
            prescribed: vec![(1, 2.0, 0)],
            prescribed_functions: vec![TimeFunction::one()],
            ..Geometry::default()
        };
        let probe = Probe {
            name: "driven".into(),
            points: vec![1],
            times: vec![0.3],
            ..Probe::default()
        };
        let mut p = ProbeSet::new(&[probe], &g);
        p.start(0.0, 0.1, &[0.0], None);
        for k in 1..=5 {
            p.observe(k as f64 * 0.1, 0.1, &[0.0], k == 5);
        }
        let u = p.save()[0][0];
        assert!((u - 0.6).abs() < 1e-14, "{u}");
    }

    #[test]
    fn resumes_from_saved_values_to_the_same_result() {
        let h = 0.1;
        let times = vec![0.05, 0.35, 0.65];
        let q = |t: f64| (5.0 * t).sin();
        let mut whole = set(times.clone());
        whole.start(0.0, h, &[q(0.0)], None);
        let mut saved = None;
        for k in 1..=10 {
            let t = k as f64 * h;
            whole.observe(t, h, &[q(t)], k == 10);
            if k == 4 {
                saved = Some(whole.save());
            }
        }
        let mut resumed = set(times);
        resumed.start(0.4, h, &[q(0.4)], saved.as_deref());
        for k in 5..=10 {
            let t = k as f64 * h;
            resumed.observe(t, h, &[q(t)], k == 10);
        }
        assert_eq!(whole.save(), resumed.save());
        assert_eq!(whole.save()[0].len(), 3);
    }
}
