//! Studies of the paper's academic examples (issue 5), each one command
//! (`signorini study NAME --out DIR`) that writes a CSV table, a plot (PNG and SVG) and
//! a verdict line per finding (`verdict.txt`, also returned).
//!
//! The studies run on the bouncing ball of eq. 7 (Ballard's example,
//! [`BouncingBall::ballard`]) and the impacting oscillator of eq. 8
//! ([`Oscillator::example`]) against their closed forms:
//! - `convergence`: errors in position and velocity in the uniform, l1 and l2 norms
//!   against h for Moreau–Jean, Schatzman–Paoli and Algorithm 1 on both examples, with
//!   fitted orders (Fig. 2);
//! - `projection-multiplier`: max |τ| against h for Algorithm 1 on both examples
//!   (Fig. 3, eq. 37: τ = O(h));
//! - `chattering`: Algorithm 1 with the explicit forecast γ = 0, 1, 2 (eq. 61) and the
//!   free forecast (eq. 62), and Algorithm 2, at h = 5e-2: contact switches after the
//!   accumulation, post-accumulation velocity amplitude, time to rest (Fig. 4); and the
//!   rocking block of eq. 9–10 with the paper's parameters under the same five cases:
//!   corner switches after t = 1 and energy at t = 2 (Fig. 9);
//! - `energy`: kinetic, potential and total energy for e = 1/2 and e = 1, without
//!   projection (Moreau–Jean) and with it (Algorithms 1 and 2) (Figs. 6, 7).
//!
//! Moreau–Jean and Algorithm 1 run with [`STUDY_FORECAST`] in the convergence,
//! projection-multiplier and energy studies.
//!
//! `energy` uses the ball.
//!
//! The impacting bar has its own studies in [`bar`]: `speed-accuracy` (error against
//! cost for every scheme, size and Courant number) and `extremes` (stability at the
//! brief's extremes, 10⁶ elements included). The slider–crank of sec. 6.3.1 has
//! `slider-crank` in [`slider_crank`] (Table 3, Figs. 21–24). `extremes` on a scene file
//! (`signorini study extremes SCENE`) is [`extremes`]: every scheme at the scene's
//! step ×1/8 … ×8, e = 0 and 1, θ = 1/2 and 1, stiffness ×1e-3 and ×1e3. `costs`
//! ([`costs`]) measures a step, a set-up and the memory per size (bars of 10³ … 10⁶
//! elements, hex8 cubes of 4³ … 16³ cells), in contact and in flight.

pub mod bar;
pub mod costs;
pub mod extremes;
pub mod slider_crank;
pub mod sweep;

use std::fmt::Write as _;
use std::path::Path;

use crate::analytic::ball::BouncingBall;
use crate::analytic::oscillator::Oscillator;
use crate::contact::block::BlockCorners;
use crate::contact::plane::NodesOnPlane;
use crate::error::Error;
use crate::integrators::{self, Forecast, Integrator, SchemeKind, SchemeParams, StepStats};
use crate::io::write_atomic;
use crate::model::point_mass::{oscillator, point_mass, rigid_block};
use crate::plot::{Curve, lines};

/// The studies `signorini study` knows.
pub const NAMES: [&str; 8] = [
    "convergence",
    "projection-multiplier",
    "chattering",
    "energy",
    "speed-accuracy",
    "extremes",
    "slider-crank",
    "costs",
];

/// A run of the ball: per step the time at the end of the step, height, velocity,
/// impulse and projection multiplier.
#[derive(Clone, Debug, Default)]
pub struct Trajectory {
    /// `t_{k+1}` (s).
    pub t: Vec<f64>,
    /// Height `q` (m).
    pub q: Vec<f64>,
    /// Velocity `v` (m/s).
    pub v: Vec<f64>,
    /// Impulse `P` over the step (N·s).
    pub p: Vec<f64>,
    /// Projection multiplier `τ` (eq. 28).
    pub tau: Vec<f64>,
}

/// An academic example with a closed form.
#[derive(Clone, Copy, Debug)]
pub enum Example {
    /// The bouncing ball (eq. 7).
    Ball(BouncingBall),
    /// The impacting oscillator (eq. 8).
    Oscillator(Oscillator),
}

impl Example {
    /// Short name for tables and messages.
    pub fn name(&self) -> &'static str {
        match self {
            Example::Ball(_) => "ball",
            Example::Oscillator(_) => "oscillator",
        }
    }
    /// The exact state (position, right-limit velocity) at the given times.
    pub fn exact(&self, t: &[f64]) -> Vec<(f64, f64)> {
        match self {
            Example::Ball(b) => t.iter().map(|&t| b.state(t)).collect(),
            Example::Oscillator(o) => {
                let f = o.flights(t.last().copied().unwrap_or(0.0) + 1.0);
                t.iter().map(|&t| f.at(t)).collect()
            }
        }
    }
}

/// Integrates the ball `b` with `params` and step `h` up to `t_end`.
pub fn ball_run(
    b: &BouncingBall,
    params: &SchemeParams,
    h: f64,
    t_end: f64,
) -> Result<Trajectory, Error> {
    example_run(&Example::Ball(*b), params, h, t_end)
}

/// Integrates example `x` with `params` and step `h` up to `t_end`; the gap is the
/// height `q`. The ball's dof is its displacement from `q0` (reference position `q0`);
/// the oscillator's dof is `q` itself, since its spring acts on `q`.
pub fn example_run(
    x: &Example,
    params: &SchemeParams,
    h: f64,
    t_end: f64,
) -> Result<Trajectory, Error> {
    let (sys, reference, u0, v0, e) = match x {
        Example::Ball(b) => (
            point_mass(1, b.mass, &[b.force])?,
            b.q0,
            0.0,
            b.v0,
            b.restitution,
        ),
        Example::Oscillator(o) => (
            oscillator(o.mass, o.damping, o.stiffness, o.force)?,
            0.0,
            o.q0,
            o.v0,
            o.restitution,
        ),
    };
    let contact = NodesOnPlane::new(vec![vec![0]], vec![vec![reference]], vec![1.0], 0.0, e)?;
    let mut integ = integrators::build(params, sys, Box::new(contact), &[u0], &[v0], h)?;
    let steps = crate::limits::step_count(t_end, h, "t_end", "h")?;
    let mut r = Trajectory::default();
    let mut record = |integ: &dyn Integrator, _: &StepStats, _: bool| {
        let s = integ.state();
        r.t.push(s.time);
        r.q.push(reference + s.q[0]);
        r.v.push(s.v[0]);
        r.p.push(s.impulse[0]);
        r.tau.push(s.projection[0]);
        Ok(())
    };
    crate::run::drive(
        integ.as_mut(),
        steps,
        &study_checks(params),
        &mut [&mut record],
        &mut crate::run::Quiet,
    )?;
    Ok(r)
}

/// The run checks of a study's own runs: non-finite states stop them, but caps are
/// counted, not fatal (the studies measure and report them, e.g. the chattering of
/// Algorithm 1 with the explicit forecast).
fn study_checks(params: &SchemeParams) -> crate::run::RunChecks {
    crate::run::RunChecks {
        allow_caps: true,
        ..crate::run::RunChecks::new(params, 0.0)
    }
}

/// Least-squares slope of `log err` against `log h` (zero errors skipped).
pub fn fit_order(h: &[f64], err: &[f64]) -> f64 {
    let pts: Vec<(f64, f64)> = h
        .iter()
        .zip(err)
        .filter(|(_, e)| **e > 0.0)
        .map(|(h, e)| (h.ln(), e.ln()))
        .collect();
    let n = pts.len() as f64;
    let (sx, sy) = pts.iter().fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
    let (mx, my) = (sx / n, sy / n);
    let num: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let den: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    num / den
}

/// Uniform, l1 and l2 norms of `e` sampled every `h`.
fn norms(e: &[f64], h: f64) -> [f64; 3] {
    let max = e.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let l1 = h * e.iter().map(|x| x.abs()).sum::<f64>();
    let l2 = (h * e.iter().map(|x| x * x).sum::<f64>()).sqrt();
    [max, l1, l2]
}

/// The paper's rules ([`SchemeParams::paper_rules`]): these studies reproduce its figures.
fn params(kind: SchemeKind, forecast: Forecast) -> SchemeParams {
    SchemeParams {
        kind,
        forecast,
        ..SchemeParams::default()
    }
    .paper_rules()
}

/// Steps of the convergence study: h₀ = 0.0137 s times 0.7^j, j = 0 … 11 (down to
/// 2.7e-4). h₀ divides no impact time and the ratio is not a power of 2, so the
/// distance from an impact to the grid varies from one h to the next instead of
/// repeating, which keeps the fitted slopes from aliasing.
pub fn convergence_steps() -> Vec<f64> {
    (0..12).map(|j| 0.0137 * 0.7f64.powi(j)).collect()
}

/// The activation rule of the convergence, projection-multiplier and energy studies
/// for Moreau–Jean and Algorithm 1: the explicit forecast with γ = 0 (eq. 61), i.e. a
/// contact is active when its gap at the start of the step is closed, the index set
/// the paper's consistency analysis (Prop. 1–2) assumes. With the free forecast
/// (eq. 62) the ball is caught before it penetrates, τ is zero and no energy is
/// created, so Figs. 3 and 7 would not show (measured: max |τ| = 0 at every h).
pub const STUDY_FORECAST: Forecast = Forecast::Explicit { gamma: 0.0 };

/// Horizon of the convergence study (s): three impacts (t = 1, 2, 2.5), before the
/// accumulation at t = 3.
pub const CONVERGENCE_T: f64 = 2.6;

/// The fitted orders of one scheme: position then velocity, each uniform / l1 / l2.
#[derive(Clone, Copy, Debug)]
pub struct Orders {
    /// Example (`ball` or `oscillator`).
    pub example: &'static str,
    /// Scheme.
    pub kind: SchemeKind,
    /// Position orders (uniform, l1, l2).
    pub q: [f64; 3],
    /// Velocity orders (uniform, l1, l2).
    pub v: [f64; 3],
}

/// One row of the convergence table: example, scheme, h, errors (q uniform, l1, l2,
/// v uniform, l1, l2).
pub type ErrorRow = (&'static str, SchemeKind, f64, [f64; 6]);

/// Runs the convergence study; returns the fitted orders and the table rows
/// (scheme, h, six errors).
pub fn convergence_orders() -> Result<(Vec<Orders>, Vec<ErrorRow>), Error> {
    let hs = convergence_steps();
    let mut rows = Vec::new();
    let mut orders = Vec::new();
    for x in [
        Example::Ball(BouncingBall::ballard()),
        Example::Oscillator(Oscillator::example()),
    ] {
        for kind in [
            SchemeKind::MoreauJean,
            SchemeKind::SchatzmanPaoli,
            SchemeKind::DirectProjection,
        ] {
            let mut errs = Vec::new();
            for &h in &hs {
                let r = example_run(&x, &params(kind, STUDY_FORECAST), h, CONVERGENCE_T)?;
                let exact = x.exact(&r.t);
                let eq: Vec<f64> = (0..r.t.len()).map(|k| r.q[k] - exact[k].0).collect();
                let ev: Vec<f64> = (0..r.t.len()).map(|k| r.v[k] - exact[k].1).collect();
                let (nq, nv) = (norms(&eq, h), norms(&ev, h));
                let e = [nq[0], nq[1], nq[2], nv[0], nv[1], nv[2]];
                rows.push((x.name(), kind, h, e));
                errs.push(e);
            }
            let col = |i: usize| errs.iter().map(|e| e[i]).collect::<Vec<_>>();
            orders.push(Orders {
                example: x.name(),
                kind,
                q: [0, 1, 2].map(|i| fit_order(&hs, &col(i))),
                v: [3, 4, 5].map(|i| fit_order(&hs, &col(i))),
            });
        }
    }
    Ok((orders, rows))
}

fn convergence(dir: &Path) -> Result<Vec<String>, Error> {
    let (orders, rows) = convergence_orders()?;
    let mut csv = String::from("example,scheme,h,q_uniform,q_l1,q_l2,v_uniform,v_l1,v_l2\n");
    for (x, k, h, e) in &rows {
        let _ = writeln!(
            csv,
            "{x},{},{h},{},{},{},{},{},{}",
            k.name(),
            e[0],
            e[1],
            e[2],
            e[3],
            e[4],
            e[5]
        );
    }
    write_atomic(&dir.join("convergence.csv"), csv.as_bytes())?;
    for x in ["ball", "oscillator"] {
        let mut curves = Vec::new();
        for (label, c) in [("q uniform", 0), ("q l1", 1), ("v l1", 4), ("v l2", 5)] {
            for o in orders.iter().filter(|o| o.example == x) {
                curves.push(Curve {
                    name: format!("{} {label}", o.kind.name()),
                    points: rows
                        .iter()
                        .filter(|r| r.0 == x && r.1 == o.kind)
                        .map(|r| (r.2, r.3[c]))
                        .collect(),
                });
            }
        }
        lines(
            &dir.join(format!("convergence-{x}")),
            &format!("{x}: error against h (Fig. 2)"),
            "h (s)",
            "error",
            &curves,
            true,
        )?;
    }
    // expected (theory, Fig. 2): position order 1 in every norm; velocity order 0 in
    // the uniform norm (a jump missed by one step), 1 in l1 and 1/2 in l2
    let want_q = [1.0, 1.0, 1.0];
    let want_v = [0.0, 1.0, 0.5];
    let close = |a: &[f64; 3], b: &[f64; 3]| a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 0.15);
    Ok(orders
        .iter()
        .map(|o| {
            format!(
                "convergence {} {}: position orders {:.2}/{:.2}/{:.2} (uniform/l1/l2; expected 1), \
                 velocity {:.2}/{:.2}/{:.2} (expected 0/1/0.5): {}",
                o.example,
                o.kind.name(),
                o.q[0],
                o.q[1],
                o.q[2],
                o.v[0],
                o.v[1],
                o.v[2],
                if close(&o.q, &want_q) && close(&o.v, &want_v) {
                    "as in Fig. 2"
                } else {
                    "DIFFERS from Fig. 2's orders by more than 0.15"
                }
            )
        })
        .collect())
}

/// One example's projection-multiplier fit: name, points (h, max |τ|), slope.
pub type TauFit = (&'static str, Vec<(f64, f64)>, f64);

/// max |τ| of Algorithm 1 for each h of [`convergence_steps`] (up to t = 2.6) on the
/// ball and on the oscillator: per example, its name, the points (h, max |τ|) and the
/// fitted slope.
pub fn projection_multipliers() -> Result<Vec<TauFit>, Error> {
    let hs = convergence_steps();
    let mut out = Vec::new();
    for x in [
        Example::Ball(BouncingBall::ballard()),
        Example::Oscillator(Oscillator::example()),
    ] {
        let mut pts = Vec::new();
        for &h in &hs {
            let r = example_run(
                &x,
                &params(SchemeKind::DirectProjection, STUDY_FORECAST),
                h,
                CONVERGENCE_T,
            )?;
            pts.push((h, r.tau.iter().fold(0.0f64, |m, x| m.max(x.abs()))));
        }
        let slope = fit_order(&hs, &pts.iter().map(|p| p.1).collect::<Vec<_>>());
        out.push((x.name(), pts, slope));
    }
    Ok(out)
}

fn projection_multiplier(dir: &Path) -> Result<Vec<String>, Error> {
    let res = projection_multipliers()?;
    let mut csv = String::from("example,h,max_abs_tau\n");
    for (x, pts, _) in &res {
        for (h, t) in pts {
            let _ = writeln!(csv, "{x},{h},{t}");
        }
    }
    write_atomic(&dir.join("projection-multiplier.csv"), csv.as_bytes())?;
    let curves: Vec<Curve> = res
        .iter()
        .map(|(x, pts, _)| Curve {
            name: format!("{x}: max |τ|"),
            points: pts.clone(),
        })
        .collect();
    lines(
        &dir.join("projection-multiplier"),
        "Algorithm 1: max |τ| against h (Fig. 3)",
        "h (s)",
        "max |τ| (kg·m, M̂⁻¹ metric)",
        &curves,
        true,
    )?;
    Ok(res
        .iter()
        .map(|(x, _, slope)| {
            format!(
                "projection-multiplier {x}: max |τ| = O(h^{slope:.2}) (expected slope 1, eq. 37): {}",
                if (slope - 1.0).abs() <= 0.15 {
                    "as in Fig. 3"
                } else {
                    "DIFFERS from Fig. 3"
                }
            )
        })
        .collect())
}

/// Chattering measures of one run after `t0`.
#[derive(Clone, Copy, Debug)]
pub struct Chatter {
    /// Contact switches (impulse turning positive or zero) after `t0`.
    pub switches: usize,
    /// max |v| after `t0` (m/s).
    pub amplitude: f64,
    /// First time from which |v| ≤ 1e-10 and no switch follows (s), if any.
    pub rest: Option<f64>,
}

/// Measures chattering on a trajectory after `t0`.
pub fn chatter(r: &Trajectory, t0: f64) -> Chatter {
    let closed: Vec<bool> = r.p.iter().map(|&p| p > 0.0).collect();
    let switches = (1..closed.len())
        .filter(|&k| r.t[k] > t0 && closed[k] != closed[k - 1])
        .count();
    let amplitude = (0..r.t.len())
        .filter(|&k| r.t[k] > t0)
        .fold(0.0f64, |m, k| m.max(r.v[k].abs()));
    // last step that moves or switches; rest starts after it
    let last_bad = (1..r.t.len())
        .rev()
        .find(|&k| r.v[k].abs() > 1e-10 || closed[k] != closed[k - 1]);
    let rest = match last_bad {
        Some(k) if k + 1 < r.t.len() => Some(r.t[k]),
        Some(_) => None,
        None => Some(0.0),
    };
    Chatter {
        switches,
        amplitude,
        rest,
    }
}

/// The cases of the chattering study: label, scheme, forecast.
pub fn chattering_cases() -> Vec<(String, SchemeKind, Forecast)> {
    let mut v: Vec<_> = [0.0, 1.0, 2.0]
        .iter()
        .map(|&g| {
            (
                format!("Algorithm 1, explicit forecast γ = {g}"),
                SchemeKind::DirectProjection,
                Forecast::Explicit { gamma: g },
            )
        })
        .collect();
    v.push((
        "Algorithm 1, free forecast".into(),
        SchemeKind::DirectProjection,
        Forecast::Free,
    ));
    v.push((
        "Algorithm 2".into(),
        SchemeKind::CombinedProjection,
        Forecast::Free,
    ));
    v
}

fn chattering(dir: &Path) -> Result<Vec<String>, Error> {
    let b = BouncingBall::ballard();
    let (h, t_end, t0) = (5e-2, 10.0, 3.5);
    let mut csv = String::from("case,switches_after_3.5,max_abs_v_after_3.5,rest_time\n");
    let mut verdicts = Vec::new();
    let mut curves = Vec::new();
    for (label, kind, forecast) in chattering_cases() {
        let r = ball_run(&b, &params(kind, forecast), h, t_end)?;
        let c = chatter(&r, t0);
        let rest = c.rest.map_or("never".to_string(), |t| format!("{t:.2}"));
        let _ = writeln!(csv, "\"{label}\",{},{},{rest}", c.switches, c.amplitude);
        verdicts.push(format!(
            "chattering {label}: {} contact switches after t = 3.5, max |v| {:.2e} m/s, at rest from t = {rest}{}",
            c.switches,
            c.amplitude,
            if c.switches > 0 {
                " (chatters, as Fig. 4 shows)"
            } else {
                " (no chattering)"
            }
        ));
        curves.push(Curve {
            name: label,
            points: r.t.iter().copied().zip(r.q.iter().copied()).collect(),
        });
    }
    // the rocking block, paper parameters (Fig. 9)
    let mut block_csv = String::from("case,switches_after_1,energy_at_2_J,rest_energy_J\n");
    for (label, kind, forecast) in chattering_cases() {
        let label = format!("block, {label}");
        let b = block_run(&params(kind, forecast))?;
        let _ = writeln!(
            block_csv,
            "\"{label}\",{},{},{}",
            b.switches, b.energy, b.rest_energy
        );
        verdicts.push(format!(
            "chattering {label}: {} corner switches after t = 1, energy at t = 2 {:.4} J (rest {:.4} J){}",
            b.switches,
            b.energy,
            b.rest_energy,
            if b.switches > 0 {
                " (spurious oscillations, as Fig. 9 c)"
            } else if (b.energy / b.rest_energy - 1.0).abs() < 1e-9 {
                " (flat at rest without oscillation, as Fig. 9 d)"
            } else {
                " (no switching, but at rest above the minimum energy)"
            }
        ));
    }
    write_atomic(&dir.join("chattering.csv"), csv.as_bytes())?;
    write_atomic(&dir.join("chattering-block.csv"), block_csv.as_bytes())?;
    lines(
        &dir.join("chattering"),
        "Bouncing ball, h = 5e-2: height (Fig. 4)",
        "time (s)",
        "q (m)",
        &curves,
        false,
    )?;
    Ok(verdicts)
}

/// What the chattering study measures on the rocking block.
#[derive(Clone, Copy, Debug)]
pub struct BlockOutcome {
    /// Corner contact switches after t = 1.
    pub switches: usize,
    /// Energy at t = 2 (J).
    pub energy: f64,
    /// Energy of the block at rest, m g l/2 (J).
    pub rest_energy: f64,
}

/// The rocking block of Fig. 9 (l = 1.5, L = 1, y0 = 1, θ0 = 0.2, ω0 = 0.2, m = 1,
/// e = 0.5, g = 9.81, h = 1e-2, T = 2) with `params`.
pub fn block_run(params: &SchemeParams) -> Result<BlockOutcome, Error> {
    let (m, len, thick, g, h) = (1.0, 1.0, 1.5, 9.81, 1e-2);
    let sys = rigid_block(m, len, thick, g)?;
    let corners = BlockCorners::new(len, thick, 0.5)?;
    let mut integ = integrators::build(
        params,
        sys,
        Box::new(corners),
        &[0.0, 1.0, 0.2],
        &[0.0, 0.0, 0.2],
        h,
    )?;
    let inertia = m * (len * len + thick * thick) / 12.0;
    let mut prev = [false; 2];
    let mut switches = 0;
    let mut count = |integ: &dyn Integrator, _: &StepStats, _: bool| {
        let s = integ.state();
        let closed = [s.impulse[0] > 0.0, s.impulse[1] > 0.0];
        if s.time > 1.0 && closed != prev {
            switches += 1;
        }
        prev = closed;
        Ok(())
    };
    crate::run::drive(
        integ.as_mut(),
        200,
        &study_checks(params),
        &mut [&mut count],
        &mut crate::run::Quiet,
    )?;
    let s = integ.state();
    let energy = 0.5 * m * (s.v[0] * s.v[0] + s.v[1] * s.v[1])
        + 0.5 * inertia * s.v[2] * s.v[2]
        + m * g * s.q[1];
    Ok(BlockOutcome {
        switches,
        energy,
        rest_energy: m * g * 0.5 * thick,
    })
}

/// Energy `½ m v² − f q` along a trajectory.
fn energies(b: &BouncingBall, r: &Trajectory) -> Vec<(f64, f64, f64)> {
    (0..r.t.len())
        .map(|k| {
            let ke = 0.5 * b.mass * r.v[k] * r.v[k];
            (r.t[k], ke, -b.force * r.q[k])
        })
        .collect()
}

fn energy(dir: &Path) -> Result<Vec<String>, Error> {
    let h = 1e-2;
    let mut csv = String::from("restitution,scheme,time,kinetic,potential,total\n");
    let mut verdicts = Vec::new();
    let mut curves = Vec::new();
    for e in [0.5, 1.0] {
        let b = BouncingBall {
            restitution: e,
            ..BouncingBall::ballard()
        };
        let e0 = -b.force * b.q0 + 0.5 * b.mass * b.v0 * b.v0;
        for (kind, forecast) in [
            (SchemeKind::MoreauJean, STUDY_FORECAST),
            (SchemeKind::DirectProjection, STUDY_FORECAST),
            (SchemeKind::CombinedProjection, Forecast::Free),
        ] {
            let r = ball_run(&b, &params(kind, forecast), h, 10.0)?;
            let en = energies(&b, &r);
            for (t, ke, pe) in &en {
                let _ = writeln!(csv, "{e},{},{t},{ke},{pe},{}", kind.name(), ke + pe);
            }
            let max_total = en.iter().fold(f64::MIN, |m, x| m.max(x.1 + x.2));
            verdicts.push(format!(
                "energy e = {e}, {}: largest total {max_total:.5} J against {e0:.5} J at t = 0 ({:+.3} %){}",
                kind.name(),
                100.0 * (max_total / e0 - 1.0),
                if max_total > e0 * (1.0 + 1e-9) {
                    ": energy is created"
                } else {
                    ""
                }
            ));
            curves.push(Curve {
                name: format!("e = {e}, {}", kind.name()),
                points: en.iter().map(|x| (x.0, x.1 + x.2)).collect(),
            });
        }
    }
    write_atomic(&dir.join("energy.csv"), csv.as_bytes())?;
    lines(
        &dir.join("energy"),
        "Bouncing ball, h = 1e-2: total energy (Figs. 6, 7)",
        "time (s)",
        "energy (J)",
        &curves,
        false,
    )?;
    Ok(verdicts)
}

/// Runs study `name` into `dir` and returns its verdict lines (also written to
/// `dir/verdict.txt`).
pub fn run(name: &str, dir: &Path) -> Result<Vec<String>, Error> {
    std::fs::create_dir_all(dir).map_err(|e| Error::write(dir, e))?;
    let verdicts = match name {
        "convergence" => convergence(dir)?,
        "projection-multiplier" => projection_multiplier(dir)?,
        "chattering" => chattering(dir)?,
        "energy" => energy(dir)?,
        "speed-accuracy" => bar::speed_accuracy(dir)?,
        "extremes" => bar::extremes(dir)?,
        "slider-crank" => slider_crank::study(dir)?,
        "costs" => costs::costs(dir)?,
        other => {
            return Err(Error::invalid(
                "study",
                other,
                &format!("unknown study; the studies are {}", NAMES.join(", ")),
            ));
        }
    };
    write_atomic(
        &dir.join("verdict.txt"),
        (verdicts.join("\n") + "\n").as_bytes(),
    )?;
    Ok(verdicts)
}

/// `signorini study extremes SCENE`: [`extremes::scene_extremes`] on a scene file under
/// `schemes` (all when empty), with its verdicts also in `dir/verdict.txt`.
pub fn run_on_scene(
    name: &str,
    scene: &Path,
    overrides: &[String],
    schemes: &[SchemeKind],
    dir: &Path,
) -> Result<Vec<String>, Error> {
    if name != "extremes" {
        return Err(Error::invalid(
            "study",
            name,
            "takes no scene file; only `extremes` runs on a scene (`signorini study extremes \
             SCENE`)",
        ));
    }
    let verdicts = extremes::scene_extremes(scene, overrides, schemes, dir)?;
    write_atomic(
        &dir.join("verdict.txt"),
        (verdicts.join("\n") + "\n").as_bytes(),
    )?;
    Ok(verdicts)
}
