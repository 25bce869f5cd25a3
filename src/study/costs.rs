//! `signorini study costs`: what a step, a set-up and the memory cost per size, in one
//! command (issue 35 §5), so a user sees where their scene sits.
//!
//! Two series, each run in contact and in flight, each a whole run through
//! [`run_bar`] / [`run_scene`] without output files:
//! - the impacting bar (rod P1, tridiagonal factor, one contact) at N = 10³ … 10⁶
//!   elements, h = 2e-7 s, min(1800, max(40, 4·10⁷/N)) steps (the series of
//!   `benches/c_loop.sh`), under Moreau–Jean and Algorithm 2: in contact the reference
//!   bar (the tip on the wall at every step), in flight the same bar 1 mm away;
//! - a hex8 steel cube of k³ cells, k = 4, 8, 16 (375 to 14 739 dofs, 25 to 289 contact
//!   nodes), on a rigid floor under Algorithm 2, h = 1e-6 s, 20 steps: in contact the cube
//!   resting on the floor as it moves down at 0.1 m/s, in flight the floor 1 m below.
//!
//! Per run: µs per step and ns per dof per step (the step loop), set-up seconds (model
//! and integrator: assembly, factorization, Delassus data), the memory the plan
//! estimated before anything was allocated and the peak resident memory the process
//! measured during the run (its high-water mark reset before each run; memory freed by
//! an earlier run and kept by the allocator counts), and the mean summed contact force
//! over the run (zero in flight; the bar's in contact is its plateau E·S·|v0|/c0).
//! Written: `costs.csv` and one line per run.

use std::fmt::Write as _;
use std::path::Path;

use crate::app::{run_bar, run_scene};
use crate::error::Error;
use crate::integrators::SchemeKind;
use crate::io::write_atomic;
use crate::run::{Quiet, RunResult};
use crate::scene::bar::BarScene;
use crate::scene::file::Scene;

/// The bar sizes of the series (elements).
pub const BAR_SIZES: [usize; 4] = [1_000, 10_000, 100_000, 1_000_000];

/// The cube sizes of the series (cells per side).
pub const CUBE_SIZES: [usize; 3] = [4, 8, 16];

/// The bar's steps at `n` elements: the series of `benches/c_loop.sh`.
pub fn bar_steps(n: usize) -> usize {
    (4e7 / n as f64).round().clamp(40.0, 1800.0) as usize
}

/// The cube of `k³` hex8 cells on a floor `gap` below it, under Algorithm 2.
pub fn cube_scene(k: usize, gap: f64) -> Result<Scene, Error> {
    Scene::from_toml(&format!(
        r#"[time]
dt = 1e-6
t_end = 2e-5
[scheme]
kind = "combined-projection"
[[bodies]]
name = "cube"
mesh = {{ generator = "box", cell = "hex8", cells = [{k}, {k}, {k}], size = [0.1, 0.1, 0.1] }}
material = {{ young = 210e9, poisson = 0.3, density = 7800.0 }}
velocity = [0.0, 0.0, -0.1]
[[obstacles]]
name = "floor"
type = "plane"
point = [0.0, 0.0, {z}]
normal = [0.0, 0.0, 1.0]
[[contacts]]
body = "cube"
nodes = "z0"
obstacle = "floor"
[output]
fields = false
plots = false
"#,
        z = -gap
    ))
}

/// One row of the table: what a run cost.
struct Cost {
    series: &'static str,
    size: usize,
    phase: &'static str,
    scheme: &'static str,
}

/// Runs both series at their sizes ([`BAR_SIZES`], [`CUBE_SIZES`]) and writes
/// `dir/costs.csv`; returns one line per run.
pub fn costs(dir: &Path) -> Result<Vec<String>, Error> {
    costs_at(dir, &BAR_SIZES, &CUBE_SIZES)
}

/// [`costs`] at the given sizes, smallest first and the cubes before the bars (whose
/// largest leaves the most memory with the allocator).
pub fn costs_at(dir: &Path, bars: &[usize], cubes: &[usize]) -> Result<Vec<String>, Error> {
    let mut csv = String::from(
        "series,size,dofs,contacts,phase,scheme,steps,us_per_step,ns_per_dof_step,\
         setup_seconds,memory_planned_bytes,peak_memory_bytes,mean_contact_force_n\n",
    );
    let mut lines = Vec::new();
    let mut record = |c: Cost, contacts: usize, r: &RunResult| {
        let s = &r.summary;
        let us = 1e6 * s.seconds_per_step;
        let setup = s.model_seconds + s.integrator_seconds;
        let peak = s.peak_memory_bytes.unwrap_or(0);
        // the mean over the run of the summed contact force: what tells the phases apart
        let force = r.force.iter().sum::<f64>() / r.force.len().max(1) as f64;
        let _ = writeln!(
            csv,
            "{},{},{},{contacts},{},{},{},{us:.4},{:.4},{setup:.4},{},{peak},{force:e}",
            c.series,
            c.size,
            s.dofs,
            c.phase,
            c.scheme,
            s.steps,
            1e3 * us / s.dofs.max(1) as f64,
            s.memory_planned_bytes
        );
        lines.push(format!(
            "costs {} {} ({} dofs) {} {}: {us:.4} µs/step ({:.2} ns/dof), set-up {setup:.3} s, \
             memory planned {} / peak {}",
            c.series,
            c.size,
            s.dofs,
            c.phase,
            c.scheme,
            1e3 * us / s.dofs.max(1) as f64,
            crate::limits::bytes(s.memory_planned_bytes),
            crate::limits::bytes(peak),
        ));
    };
    for &k in cubes {
        for (phase, gap) in [("contact", 0.0), ("flight", 1.0)] {
            let scene = cube_scene(k, gap)?;
            crate::limits::reset_peak_memory();
            let r = run_scene(&scene, None, &mut Quiet)?;
            let c = Cost {
                series: "cube",
                size: k,
                phase,
                scheme: SchemeKind::CombinedProjection.name(),
            };
            record(c, (k + 1) * (k + 1), &r);
        }
    }
    for &n in bars {
        for (phase, gap) in [("contact", 0.0), ("flight", 1e-3)] {
            for kind in [SchemeKind::MoreauJean, SchemeKind::CombinedProjection] {
                let mut b = BarScene {
                    elements: n,
                    dt: 2e-7,
                    gap,
                    ..BarScene::default()
                };
                b.t_end = bar_steps(n) as f64 * b.dt;
                b.scheme.kind = kind;
                crate::limits::reset_peak_memory();
                let r = run_bar(&b, None, &mut Quiet)?;
                let c = Cost {
                    series: "bar",
                    size: n,
                    phase,
                    scheme: kind.name(),
                };
                record(c, 1, &r);
            }
        }
    }
    write_atomic(&dir.join("costs.csv"), csv.as_bytes())?;
    Ok(lines)
}
