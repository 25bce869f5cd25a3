//! `chattering` (Figs. 4 and 9): the forecasts of eq. 61–62 and Algorithm 2 after an
//! accumulation of impacts, on the bouncing ball and the rocking block of eq. 9–10.

use super::*;

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

pub(super) fn chattering(dir: &Path) -> Result<Vec<String>, Error> {
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
