//! What each subcommand does: build and run through the library's application layer
//! (`signorini::app`), with the terminal's progress line and the printed results.

use super::*;

/// Progress on stderr: an indicatif bar with steps/s and ETA on a terminal, a plain line
/// per 10 % otherwise (logs, CI).
pub(crate) enum CliProgress {
    Bar(indicatif::ProgressBar),
    Lines {
        last_decile: usize,
        start: std::time::Instant,
    },
}

impl Progress for CliProgress {
    fn phase(&mut self, what: &str) {
        match self {
            CliProgress::Bar(b) => b.suspend(|| err!("  {what}")),
            CliProgress::Lines { .. } => err!("  {what}"),
        }
    }

    fn start(&mut self, total: usize) {
        match self {
            CliProgress::Bar(b) => {
                b.set_length(total as u64);
                b.reset();
            }
            CliProgress::Lines { start, .. } => *start = std::time::Instant::now(),
        }
    }

    fn update(&mut self, step: usize, total: usize) {
        match self {
            CliProgress::Bar(b) => {
                if b.length() != Some(total as u64) {
                    b.set_length(total as u64);
                }
                b.set_position(step as u64);
                if step == total {
                    b.finish();
                }
            }
            CliProgress::Lines { last_decile, start } => {
                let frac = step as f64 / total as f64;
                let el = start.elapsed().as_secs_f64();
                let eta = if frac > 0.0 { el / frac - el } else { 0.0 };
                let rate = step as f64 / el.max(1e-9);
                let decile = (frac * 10.0).floor() as usize;
                if decile > *last_decile || step == total {
                    *last_decile = decile;
                    err!(
                        "  step {step}/{total} ({:.0} %), {rate:.0} steps/s, ETA {eta:.1} s",
                        100.0 * frac
                    );
                }
            }
        }
    }
}

pub(crate) fn run_bar(args: &BarArgs) -> Result<(), signorini::Error> {
    args.validate_flags()?;
    args.output.validate()?;
    let scene = args.scene();
    scene.validate()?;
    if !args.quiet {
        err!(
            "signorini bar: {} elements, h = {:e} s, T = {:e} s, {} steps, scheme {}, θ = {}",
            scene.elements,
            scene.dt,
            scene.t_end,
            scene.steps(),
            scene.scheme.kind.name(),
            scene.scheme.theta
        );
    }
    let mut options = OutputOptions::default();
    args.output.apply(&mut options);
    let out = run::Output {
        dir: &args.out,
        options: &options,
    };
    let result = app::run_bar(&scene, Some(out), progress_sink(args.quiet).as_mut())?;
    if !args.quiet {
        print_summary(&result.summary, &args.out);
    }
    accuracy_met(&result.summary)
}

/// An accuracy run that did not reach its accuracy fails (exit 1) once its outputs and
/// summary are written.
pub(crate) fn accuracy_met(s: &run::Summary) -> Result<(), signorini::Error> {
    match s.accuracy.as_ref().and_then(|a| a.failure()) {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

pub(crate) fn progress_sink(quiet: bool) -> Box<dyn Progress> {
    if quiet {
        Box::new(run::Quiet)
    } else {
        Box::new(if std::io::stderr().is_terminal() {
            let bar = indicatif::ProgressBar::new(0);
            bar.set_style(
                indicatif::ProgressStyle::with_template(
                    "  {bar:40} {pos}/{len} steps  {per_sec}  ETA {eta}",
                )
                .expect("valid template"),
            );
            CliProgress::Bar(bar)
        } else {
            CliProgress::Lines {
                last_decile: 0,
                start: std::time::Instant::now(),
            }
        })
    }
}

pub(crate) fn scene_out(args: &SceneArgs, scene: &Scene) -> PathBuf {
    args.out
        .clone()
        .or_else(|| scene.output.dir.clone())
        .unwrap_or_else(|| PathBuf::from("out").join(args.scene.file_stem().unwrap_or_default()))
}

pub(crate) fn run_scene(args: &SceneArgs) -> Result<(), signorini::Error> {
    args.output.validate()?;
    let mut set = args.set.clone();
    if let Some(tol) = args.accuracy {
        set.push(format!("time.accuracy={tol:e}"));
    }
    let scene = Scene::from_file_with(&args.scene, &set)?;
    let out = scene_out(args, &scene);
    if !args.quiet {
        err!(
            "signorini run {}: {} steps of {:e} s, scheme {}",
            args.scene.display(),
            scene.steps(),
            scene.time.dt,
            scene.scheme.kind.name()
        );
    }
    let mut options = scene.output.clone();
    args.output.apply(&mut options);
    let o = run::Output {
        dir: &out,
        options: &options,
    };
    let result = app::run_scene(&scene, Some(o), progress_sink(args.quiet).as_mut())
        .map_err(|e| e.in_file(&args.scene))?;
    if !args.quiet {
        print_summary(&result.summary, &out);
    }
    accuracy_met(&result.summary)
}

pub(crate) fn run_example(
    name: &str,
    out: Option<PathBuf>,
    quiet: bool,
) -> Result<(), signorini::Error> {
    let scene = signorini::scene::builtin_scene(name)?;
    let out = out.unwrap_or_else(|| PathBuf::from("out").join(name));
    let o = run::Output {
        dir: &out,
        options: &scene.output,
    };
    let result = app::run_scene(&scene, Some(o), progress_sink(quiet).as_mut())?;
    if !quiet {
        print_summary(&result.summary, &out);
    }
    Ok(())
}

/// `signorini fclib`: reads, solves, prints one line per quantity; `Ok(false)` when the
/// cap was hit above the tolerance.
pub(crate) fn fclib(a: &FclibArgs) -> Result<bool, signorini::Error> {
    use signorini::solvers::friction::FrictionParams;
    let params = FrictionParams {
        solver: a.solver,
        tol: a.tol,
        max_iterations: a.max_iter,
        ..FrictionParams::default()
    };
    params.validate_ranges("--")?;
    if let Some(p) = &a.solution {
        signorini::io::check_output_file("--solution", p, &[&a.file])?;
    }
    let prob = signorini::io::fclib::read(&a.file)?;
    if a.repeat == 0 || a.repeat > 1_000_000 {
        return Err(signorini::Error::invalid(
            "--repeat",
            a.repeat,
            "must be in [1, 1000000]",
        ));
    }
    let measure =
        signorini::solvers::friction::Measure::parse(&a.residual).expect("clap checked the name");
    // the problem is read and checked: now the run's subnormal mode
    let _flush = signorini::linalg::FlushGuard::for_run();
    let sol = signorini::io::fclib::solve_repeated(&prob, &params, measure, a.warm, a.repeat)?;
    out!("problem             {} ({})", a.file.display(), prob.form);
    out!(
        "size                {} contacts in {}-D, {} rows; μ in [{}, {}]; W asymmetry {:.1e}",
        prob.contacts(),
        prob.dim,
        prob.rows(),
        prob.mu.iter().cloned().fold(f64::INFINITY, f64::min),
        prob.mu.iter().cloned().fold(0.0, f64::max),
        prob.asymmetry
    );
    out!(
        "solver              {} (tol {:e} on the {} residual, cap {} sweeps{})",
        sol.solver,
        a.tol,
        sol.measure.name(),
        a.max_iter,
        if a.warm && prob.guess.is_some() {
            ", warm start from /guesses/1"
        } else {
            ""
        }
    );
    out!(
        "result              {} by {}{} after {} iterations{}: residual {:.3e}, {:.3e} s{}",
        if sol.converged {
            "converged"
        } else {
            "NOT converged (cap hit)"
        },
        sol.solved_by,
        if sol.sparse_jacobian {
            " (sparse Jacobian)"
        } else {
            ""
        },
        sol.iterations,
        if sol.prox_iterations > 0 {
            format!(" ({} proximal iterations)", sol.prox_iterations)
        } else {
            String::new()
        },
        sol.residual,
        sol.seconds,
        if a.repeat > 1 {
            format!(" (median of {})", a.repeat)
        } else {
            String::new()
        }
    );
    if let Some(p) = &a.solution {
        let json = serde_json::to_vec_pretty(&sol)
            .map_err(|e| signorini::Error::Numerical(format!("serializing the solution: {e}")))?;
        signorini::io::write_atomic(p, &json)?;
        out!("wrote               {}", p.display());
    }
    Ok(sol.converged)
}

pub(crate) fn check_scene(args: &SceneArgs) -> Result<(), signorini::Error> {
    let scene = Scene::from_file_with(&args.scene, &args.set)?;
    let c = scene.check().map_err(|e| e.in_file(&args.scene))?;
    // printed in full even when the memory does not fit (the error comes last)
    out!("scene               {} (valid)", args.scene.display());
    out!(
        "model               {} bodies, {} cells ({}), {} dofs ({} fixed dofs removed), {} candidate contacts",
        c.bodies,
        c.cells,
        c.cell_kinds
            .iter()
            .map(|(k, n)| format!("{n} {k}"))
            .collect::<Vec<_>>()
            .join(", "),
        c.dofs,
        c.fixed_dofs,
        c.contacts
    );
    let friction = match &c.friction_solver {
        Some(solver) => format!("Coulomb, μ up to {} ({solver})", c.max_friction),
        None => "none (no contact has friction > 0: no friction solver)".to_string(),
    };
    out!(
        "physics             damping {}, gravity {}, friction {}",
        if c.damping { "Rayleigh" } else { "none" },
        if c.gravity { "yes" } else { "none" },
        friction
    );
    for line in &c.interfaces {
        out!("contact entry       {line}");
    }
    for p in &c.probes {
        out!(
            "probe               \"{}\": mean displacement of {} node(s) of {} (set `{}`) at {} time(s) from {:e} to {:e} s",
            p.name,
            p.node_count,
            p.body,
            p.nodes,
            p.times.len(),
            p.times[0],
            p.times[p.times.len() - 1]
        );
    }
    out!(
        "time                {} steps of {:e} s, scheme {}, θ = {}",
        c.steps,
        c.dt,
        c.scheme,
        c.theta
    );
    if let (Some(tol), Some(first), Some(last)) = (c.accuracy, c.ladder.first(), c.ladder.last()) {
        out!(
            "accuracy            {tol:e} asked: the run chooses its steps among {} from {first:e} to {last:e} s (each halving the last), at least {} steps; it estimates the step's error on this mesh, not the mesh's",
            c.ladder.len(),
            c.steps
        );
    }
    out!("newton              {}", c.newton);
    out!("path                {}", c.path);
    out!(
        "memory              {} planned (limit {}): {}",
        signorini::limits::bytes(c.memory_planned),
        signorini::limits::bytes(c.memory_limit),
        c.memory_parts
            .iter()
            .map(|(w, b)| format!("{w} {}", signorini::limits::bytes(*b)))
            .collect::<Vec<_>>()
            .join(", ")
    );
    match c.memory_error {
        Some(e) => Err(e.in_file(&args.scene)),
        None => Ok(()),
    }
}

/// Progress of a sweep: one line per run on stderr.
/// The sweep's line per run; `ranks` under MPI, where every rank prints its own runs
/// (counted within its share) and the lines start with the rank.
pub(crate) struct SweepLines {
    pub(crate) ranks: bool,
}

impl signorini::study::sweep::SweepProgress for SweepLines {
    fn run(&mut self, done: usize, total: usize, r: &signorini::study::sweep::RunRecord, eta: f64) {
        let mut what = if r.point.key.is_empty() {
            "the scene".to_string()
        } else {
            r.point.key.clone()
        };
        if self.ranks {
            what = format!("{what} [rank {}]", r.worker);
        }
        if r.status == "ok" {
            err!(
                "  run {done}/{total} {what}: {:.3e} s ({:.2} µs/step, {} steps, {} dofs), violation {:.1e} m; ETA {eta:.0} s",
                r.wall_seconds,
                1e6 * r.wall_seconds / r.steps.max(1) as f64,
                r.steps,
                r.dofs,
                r.max_violation
            );
        } else {
            err!(
                "  run {done}/{total} {what}: FAILED ({}); ETA {eta:.0} s",
                r.message.as_deref().unwrap_or("")
            );
        }
    }
}

pub(crate) fn sweep(a: &SweepArgs) -> Result<(), signorini::Error> {
    use signorini::study::sweep::{self, Shard, Source, SweepSpec};
    if let Some(SweepCommand::Merge { dir }) = &a.command {
        let v = sweep::merge(dir)?;
        for line in v {
            out!("{line}");
        }
        out!(
            "wrote {}/sweep.csv, sweep-accuracy.png/.svg, verdict.txt",
            dir.display()
        );
        return Ok(());
    }
    let r = &a.run;
    let name = r.scene.clone().expect("clap requires the scene");
    // `bar` is always the built-in bar (a file of that name is `./bar`)
    let source = if name == "bar" {
        Source::Bar
    } else {
        Source::File(PathBuf::from(&name))
    };
    let mut axes = std::collections::BTreeMap::new();
    for x in &r.axis {
        let bad = |why: &str| signorini::Error::invalid("--axis", x, why);
        let (k, v) = x
            .split_once('=')
            .ok_or_else(|| bad("expected KEY=[V1, V2, …]"))?;
        let t: toml::Table = toml::from_str(&format!("v = {}", v.trim()))
            .map_err(|_| bad("the values are not a TOML array (quote strings)"))?;
        let Some(toml::Value::Array(vals)) = t.get("v") else {
            return Err(bad("the values are not a TOML array, e.g. [1e9, 2e9]"));
        };
        if vals.is_empty() {
            return Err(bad("lists no value"));
        }
        // issue 34: a second --axis on a key replaced the first silently
        if axes.insert(k.trim().to_string(), vals.clone()).is_some() {
            return Err(bad(&format!(
                "`{}` has an --axis already: give all its values in one",
                k.trim()
            )));
        }
    }
    let flags = SweepSpec {
        scheme: r.scheme.clone(),
        dt: r.dt.clone(),
        refine: r.refine.clone(),
        theta: r.theta.clone(),
        metric: r.metric.clone(),
        friction_solver: r.friction_solver.clone(),
        friction_tol: r.friction_tol.clone(),
        axes,
        repeat: r.repeat,
        levels: r.levels.clone(),
    };
    // the scene's [sweep] table, under the flags
    let table = source.scene(&r.set, &sweep::points(&SweepSpec::default())[0])?;
    let spec = flags.over(&table.sweep.clone().unwrap_or_default());
    let shard = match &r.shard {
        Some(s) => Some(Shard::parse(s)?),
        None if r.mpi => None,
        None => Shard::from_slurm(|k| std::env::var(k).ok())?,
    };
    let stem = std::path::Path::new(&name)
        .file_stem()
        .map_or("bar".into(), |s| s.to_string_lossy().into_owned());
    let dir = r
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(format!("sweep-{stem}")));
    let points = sweep::points(&spec).len();
    if !r.quiet {
        err!(
            "signorini sweep {}: {points} points{}, {} run(s) each",
            source.name(),
            shard.map_or(String::new(), |s| format!(
                ", shard {}/{} ({} of them)",
                s.index,
                s.count,
                (0..points).filter(|&i| s.owns(i)).count()
            )),
            spec.repeat.unwrap_or(1)
        );
    }
    let jobs = match r.jobs {
        Some(j) if !(1..=sweep::MAX_JOBS).contains(&j) => {
            return Err(signorini::Error::invalid(
                "--jobs",
                j.to_string(),
                &format!("expected 1 to {} points at the same time", sweep::MAX_JOBS),
            ));
        }
        Some(j) => j,
        None if r.mpi => 1,
        None => 0,
    };
    let job = sweep::Sweep {
        source,
        set: r.set.clone(),
        spec,
        dir: dir.clone(),
        resume: r.resume,
        shard,
        jobs,
    };
    let v = if r.mpi {
        #[cfg(feature = "mpi")]
        match job.run_mpi(&mut SweepLines { ranks: true })? {
            Some(v) => v,
            // not rank 0: rank 0 prints the verdicts
            None => return Ok(()),
        }
        #[cfg(not(feature = "mpi"))]
        return Err(signorini::Error::invalid(
            "--mpi",
            "true",
            "this signorini was built without the `mpi` cargo feature \
             (cargo build --release --features mpi, with libopenmpi-dev and libclang-dev)",
        ));
    } else {
        job.run(&mut SweepLines { ranks: false })?
    };
    if !r.quiet {
        for line in v {
            out!("{line}");
        }
        let d = shard.map_or(dir.clone(), |s| s.dir(&dir));
        out!(
            "wrote {}/sweep.csv, sweep-accuracy.png/.svg, verdict.txt, runs/",
            d.display()
        );
    }
    Ok(())
}
