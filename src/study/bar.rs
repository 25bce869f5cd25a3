//! Studies of the impacting bar (sec. 6.2, DESIGN.md §7): what accuracy each scheme buys
//! for its cost, and how each behaves at the extremes of the brief.
//!
//! - `speed-accuracy`: every scheme on the reference bar for `N` ∈ {100, 1000, 4000}
//!   elements and Courant numbers `C = c0 h N / L` ∈ {0.25, 0.5, 1, 2, 4}, run to
//!   `t = 5e-4 s` (the contact lasts `2L/c0 = 3.85e-4 s`). Per run: the errors of the
//!   plateau force, of the contact duration, of the release velocity and of the total
//!   impulse against the closed form, the plateau's standard deviation, the largest
//!   penetration and the wall time of the step loop (median of three runs, no
//!   output). The accuracy of a run is its worst relative error over the force, the
//!   duration and the release velocity; the verdict names, per scheme, the cheapest run
//!   reaching each of [`LEVELS`], and the plot shows each scheme's Pareto front (the
//!   best accuracy reachable within a given wall time).
//! - `extremes`: every scheme on the bar at one element, at 10⁶ elements, at tiny and
//!   huge steps (Courant numbers 5e-8 to 5e3), on soft and stiff materials and with
//!   `e = 1`: the run must end without an iteration cap, with finite forces, without
//!   energy growth beyond 1e-6 (θ = 1/2 conserves the bulk energy, the impact law only
//!   dissipates) and, for the projection schemes, without penetration beyond 1e-14 m.
//!   The small cases are `tests/stability_extremes.rs`; 10⁶ elements (≈ 6 ms per step)
//!   lives here, outside the test suite's budget.

use std::fmt::Write as _;
use std::path::Path;

use crate::app::run_bar;
use crate::error::Error;
use crate::integrators::SchemeKind;
use crate::io::write_atomic;
use crate::plot::{Curve, lines};
use crate::run::{Quiet, Summary};
use crate::scene::bar::BarScene;

/// Element counts of `speed-accuracy`.
pub const SIZES: [usize; 3] = [100, 1000, 4000];
/// Courant numbers `c0 h N / L` of `speed-accuracy`.
pub const COURANT: [f64; 5] = [0.25, 0.5, 1.0, 2.0, 4.0];
/// Accuracy levels of the verdict: worst relative error over plateau force, contact
/// duration and release velocity.
pub const LEVELS: [f64; 2] = [1e-2, 2e-3];

/// One run of `speed-accuracy`.
#[derive(Clone, Debug)]
pub struct Tradeoff {
    /// Scheme.
    pub kind: SchemeKind,
    /// Elements.
    pub elements: usize,
    /// Courant number.
    pub courant: f64,
    /// Time step (s).
    pub dt: f64,
    /// Relative errors: plateau force, duration, release velocity, total impulse.
    pub errors: [f64; 4],
    /// Plateau standard deviation (N).
    pub plateau_std: f64,
    /// Largest penetration (m).
    pub max_violation: f64,
    /// Median wall time of the step loop over three runs (s).
    pub wall: f64,
    /// Steps.
    pub steps: usize,
}

impl Tradeoff {
    /// The worst relative error over plateau force, duration and release velocity.
    pub fn accuracy(&self) -> f64 {
        self.errors[..3].iter().fold(0.0, |a, e| a.max(e.abs()))
    }
}

/// The reference bar with `n` elements, Courant number `c`, scheme `kind`, to 5e-4 s.
pub fn tradeoff_scene(kind: SchemeKind, n: usize, c: f64) -> BarScene {
    let mut s = BarScene {
        elements: n,
        t_end: 5e-4,
        ..BarScene::default()
    };
    let c0 = (s.young / s.density).sqrt();
    s.dt = c * s.length / (n as f64 * c0);
    s.scheme.kind = kind;
    s
}

/// Runs `scene` `repeat` times without output; returns the last summary with the
/// median wall time of the step loop.
fn timed(scene: &BarScene, repeat: usize) -> Result<Summary, Error> {
    let mut walls = Vec::with_capacity(repeat);
    let mut last = None;
    for _ in 0..repeat.max(1) {
        let r = run_bar(scene, None, &mut Quiet)?;
        walls.push(r.summary.wall_seconds);
        last = Some(r.summary);
    }
    walls.sort_by(f64::total_cmp);
    let mut s = last.expect("at least one run");
    s.wall_seconds = walls[walls.len() / 2];
    Ok(s)
}

/// Runs the `speed-accuracy` grid for `kinds`, `sizes` and `courant` numbers, each
/// configuration `repeat` times.
pub fn tradeoffs(
    kinds: &[SchemeKind],
    sizes: &[usize],
    courant: &[f64],
    repeat: usize,
) -> Result<Vec<Tradeoff>, Error> {
    let mut out = Vec::new();
    for &kind in kinds {
        for &n in sizes {
            for &c in courant {
                let scene = tradeoff_scene(kind, n, c);
                let s = timed(&scene, repeat)?;
                let k = s.contact.expect("the bar has an analytic reference");
                let rel = |a: f64, b: f64| a / b - 1.0;
                out.push(Tradeoff {
                    kind,
                    elements: n,
                    courant: c,
                    dt: scene.dt,
                    errors: [
                        rel(k.plateau_force, k.analytic_force),
                        rel(k.duration, k.analytic_duration),
                        rel(k.release_velocity, k.analytic_release_velocity),
                        rel(k.total_impulse, k.analytic_total_impulse),
                    ],
                    plateau_std: k.plateau_std,
                    max_violation: s.max_violation,
                    wall: s.wall_seconds,
                    steps: s.steps,
                });
            }
        }
    }
    Ok(out)
}

/// `signorini study speed-accuracy`: writes `speed-accuracy.csv`, the plots
/// `speed-accuracy-force` and `speed-accuracy-duration` (error against wall time) and
/// returns the verdicts.
pub fn speed_accuracy(dir: &Path) -> Result<Vec<String>, Error> {
    let rows = tradeoffs(&SchemeKind::ALL, &SIZES, &COURANT, 3)?;
    let mut csv = String::from(
        "scheme,elements,courant,dt,steps,force_error,duration_error,release_velocity_error,\
         impulse_error,worst_error,plateau_std,max_violation,wall_seconds,us_per_step\n",
    );
    for r in &rows {
        let _ = writeln!(
            csv,
            "{},{},{},{:e},{},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:.4}",
            r.kind.name(),
            r.elements,
            r.courant,
            r.dt,
            r.steps,
            r.errors[0],
            r.errors[1],
            r.errors[2],
            r.errors[3],
            r.accuracy(),
            r.plateau_std,
            r.max_violation,
            r.wall,
            1e6 * r.wall / r.steps as f64,
        );
    }
    write_atomic(&dir.join("speed-accuracy.csv"), csv.as_bytes())?;
    for (stem, what) in [
        (
            "speed-accuracy",
            "smallest worst error (force, duration, release velocity)",
        ),
        ("speed-accuracy-noise", "lowest plateau force std"),
    ] {
        let curves: Vec<Curve> = SchemeKind::ALL
            .iter()
            .map(|&k| {
                let mut pts: Vec<(f64, f64)> = rows
                    .iter()
                    .filter(|r| r.kind == k)
                    // a log axis cannot show an exact zero: floor at 1e-12
                    .map(|r| {
                        let y = if stem == "speed-accuracy" {
                            r.accuracy()
                        } else {
                            r.plateau_std
                        };
                        (r.wall, y.max(1e-12))
                    })
                    .collect();
                pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                Curve {
                    name: k.name().to_string(),
                    points: pareto(&pts),
                }
            })
            .collect();
        lines(
            &dir.join(stem),
            &format!("impacting bar: {what} reachable within a wall time"),
            "wall time of the step loop (s)",
            if stem == "speed-accuracy" {
                "relative error"
            } else {
                "N"
            },
            &curves,
            true,
        )?;
    }
    Ok(tradeoff_verdicts(&rows))
}

/// The Pareto front of points sorted by cost: each kept point is better than every
/// cheaper one.
fn pareto(sorted: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut best = f64::INFINITY;
    sorted
        .iter()
        .filter(|p| {
            let keep = p.1 < best;
            best = best.min(p.1);
            keep
        })
        .copied()
        .collect()
}

/// Per scheme and accuracy level: the cheapest run that reaches it.
pub fn tradeoff_verdicts(rows: &[Tradeoff]) -> Vec<String> {
    let mut v = Vec::new();
    for k in SchemeKind::ALL {
        let mine: Vec<&Tradeoff> = rows.iter().filter(|r| r.kind == k).collect();
        if mine.is_empty() {
            continue;
        }
        let mut parts = Vec::new();
        for level in LEVELS {
            let best = mine
                .iter()
                .filter(|r| r.accuracy() <= level)
                .min_by(|a, b| a.wall.total_cmp(&b.wall));
            parts.push(match best {
                Some(r) => format!(
                    "{} % at N = {}, C = {} in {:.3} ms (force {:+.4} %, duration {:+.3} %, \
                     release velocity {:+.3} %, plateau std {:.3} N)",
                    100.0 * level,
                    r.elements,
                    r.courant,
                    1e3 * r.wall,
                    100.0 * r.errors[0],
                    100.0 * r.errors[1],
                    100.0 * r.errors[2],
                    r.plateau_std
                ),
                None => format!("{} % not reached", 100.0 * level),
            });
        }
        let finest = mine
            .iter()
            .min_by(|a, b| a.accuracy().total_cmp(&b.accuracy()))
            .expect("non-empty");
        v.push(format!(
            "speed-accuracy {}: {}; best {:.3} % (N = {}, C = {})",
            k.name(),
            parts.join("; "),
            100.0 * finest.accuracy(),
            finest.elements,
            finest.courant
        ));
    }
    v
}

/// One extreme case: name and scene (scheme set by the caller).
pub fn extreme_cases() -> Vec<(&'static str, BarScene)> {
    let base = BarScene::default();
    vec![
        (
            "one element, h = 1e-5",
            BarScene {
                elements: 1,
                dt: 1e-5,
                ..base.clone()
            },
        ),
        (
            "10^6 elements, h = 1e-7 (C = 519)",
            BarScene {
                elements: 1_000_000,
                dt: 1e-7,
                t_end: 2e-5,
                ..base.clone()
            },
        ),
        (
            "tiny step h = 1e-12 (C = 5e-8)",
            BarScene {
                elements: 10,
                dt: 1e-12,
                t_end: 1e-8,
                ..base.clone()
            },
        ),
        (
            "huge step h = 1e-3 (C = 5e3)",
            BarScene {
                elements: 1000,
                dt: 1e-3,
                t_end: 0.1,
                ..base.clone()
            },
        ),
        (
            "elastic impact e = 1",
            BarScene {
                dt: 1e-6,
                restitution: 1.0,
                ..base.clone()
            },
        ),
        (
            "soft material E = 1e3 Pa",
            BarScene {
                elements: 100,
                dt: 1e-2,
                t_end: 10.0,
                young: 1e3,
                ..base.clone()
            },
        ),
        (
            "stiff material E = 1e15 Pa",
            BarScene {
                elements: 100,
                dt: 1e-9,
                t_end: 1e-5,
                young: 1e15,
                ..base
            },
        ),
    ]
}

/// The checks of one extreme run; `None` when it passes, else what failed.
pub fn extreme_failure(kind: SchemeKind, s: &Summary, force: &[f64]) -> Option<String> {
    let [e0, e1] = s.energy;
    let mut bad = Vec::new();
    if s.caps_hit > 0 {
        bad.push(format!("{} iteration caps hit", s.caps_hit));
    }
    if !force.iter().all(|f| f.is_finite()) {
        bad.push("non-finite force".to_string());
    }
    if !(e1.is_finite() && e1 <= e0 * (1.0 + 1e-6)) {
        bad.push(format!("energy {e0:.6e} -> {e1:.6e} J"));
    }
    if kind.capabilities().projection && s.max_violation > 1e-14 {
        bad.push(format!("penetration {:.2e} m", s.max_violation));
    }
    (!bad.is_empty()).then(|| bad.join(", "))
}

/// `signorini study extremes`: writes `extremes.csv` and returns one verdict per case
/// and scheme.
pub fn extremes(dir: &Path) -> Result<Vec<String>, Error> {
    let mut csv = String::from(
        "case,scheme,elements,dt,steps,energy_initial,energy_final,max_violation,caps_hit,\
         newton_max,us_per_step,verdict\n",
    );
    let mut v = Vec::new();
    for (name, base) in extreme_cases() {
        for kind in SchemeKind::ALL {
            let mut s = base.clone();
            s.scheme.kind = kind;
            let r = run_bar(&s, None, &mut Quiet)?;
            let sm = &r.summary;
            let fail = extreme_failure(kind, sm, &r.force);
            let verdict = fail.clone().unwrap_or_else(|| "stable".to_string());
            let _ = writeln!(
                csv,
                "{name},{},{},{:e},{},{:e},{:e},{:e},{},{},{:.3},{verdict}",
                kind.name(),
                s.elements,
                s.dt,
                sm.steps,
                sm.energy[0],
                sm.energy[1],
                sm.max_violation,
                sm.caps_hit,
                sm.iterations.newton.max,
                1e6 * sm.seconds_per_step
            );
            v.push(format!(
                "extremes {name} / {}: {} ({} steps, {:.1} µs/step, energy ratio {:.9}, \
                 max violation {:.1e} m)",
                kind.name(),
                match &fail {
                    None => "stable".to_string(),
                    Some(f) => format!("FAILS: {f}"),
                },
                sm.steps,
                1e6 * sm.seconds_per_step,
                sm.energy[1] / sm.energy[0],
                sm.max_violation
            ));
        }
    }
    write_atomic(&dir.join("extremes.csv"), csv.as_bytes())?;
    Ok(v)
}
