//! `energy` (Figs. 6, 7): kinetic, potential and total energy of the bouncing ball for
//! e = 1/2 and e = 1, without projection and with it.

use super::*;

/// Energy `½ m v² − f q` along a trajectory.
pub(super) fn energies(b: &BouncingBall, r: &Trajectory) -> Vec<(f64, f64, f64)> {
    (0..r.t.len())
        .map(|k| {
            let ke = 0.5 * b.mass * r.v[k] * r.v[k];
            (r.t[k], ke, -b.force * r.q[k])
        })
        .collect()
}

pub(super) fn energy(dir: &Path) -> Result<Vec<String>, Error> {
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
