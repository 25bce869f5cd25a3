//! `signorini`: command-line front end. Parses flags, prints progress and results;
//! all the work is in the library.

#![deny(unsafe_code)]

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand, ValueEnum};
use signorini::app;
use signorini::delassus::DelassusKind;
use signorini::integrators::{Forecast, Metric, ProjectionRule, SchemeKind};
use signorini::io::OutputOptions;
use signorini::io::frames::Encoding;
use signorini::model::MassKind;
use signorini::run::{self, Progress};
use signorini::scene::bar::BarScene;
use signorini::scene::file::Scene;
use signorini::solvers::LcpKind;

/// `println!` that ignores write errors: a closed pipe (`signorini check S | head -1`)
/// must neither panic nor stop a run whose files are still being written.
macro_rules! out {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($t)*);
    }};
}

/// `eprintln!` that ignores write errors (see [`out!`]).
macro_rules! err {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($t)*);
    }};
}

#[derive(Parser)]
#[command(
    name = "signorini",
    version,
    about = "Finite-element impact and contact solver (Acary 2013 projected schemes)",
    long_about = "Finite-element impact and contact solver implementing the event-capturing \
                  schemes of Acary (CMAME 2013). Without a subcommand, runs the reference \
                  impacting bar with Algorithm 2 (same as `signorini bar`)."
)]
#[command(args_conflicts_with_subcommands = true)]
#[command(
    after_help = "Exit codes: 0 success; 1 a run that failed (an iteration cap hit that the \
scene does not allow, a state that turned non-finite, a violation that exploded, an output \
that could not be written; the message names the step, time and contact); 2 bad input (the \
message names the file, the key path or line, the value and what was expected).\n\
Environment: SIGNORINI_MEMORY_LIMIT (bytes, or with K/M/G) holds runs to less memory than \
the machine's."
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// The bar flags, accepted without the subcommand too.
    #[command(flatten)]
    bar: BarArgs,
    /// Separate multiply and add in the chain solves even where the CPU has fused
    /// multiply-add: the same bits on every CPU (the golden histories' arithmetic), at
    /// about 1.8× the cost of the bar's tridiagonal solve.
    #[arg(long, global = true)]
    portable_arithmetic: bool,
    /// Keep IEEE gradual underflow (subnormal numbers) instead of flushing them to zero
    /// on every computing thread: for a bitwise comparison with a build or peer that
    /// keeps them, at up to several times the cost of a step on CPUs that stall on them.
    #[arg(long, global = true)]
    ieee_subnormals: bool,
    /// Factor and solve M̂ with MUMPS over the ranks of an MPI job (`mpirun -np N
    /// signorini run SCENE --mumps`; cargo feature `mumps`): rank 0 runs the command and
    /// the contact problems, the other ranks join MUMPS' factor and solves.
    #[arg(long, global = true)]
    mumps: bool,
}

#[derive(Subcommand)]
enum Command {
    /// The impacting elastic bar (sec. 6.2): N rod elements hitting a rigid wall.
    Bar(BarArgs),
    /// Run a scene file (TOML).
    Run(SceneArgs),
    /// Validate a scene file and print what the model includes and which paths the run takes.
    Check(SceneArgs),
    /// Run one of the paper's academic examples built in (bouncing-ball, oscillator,
    /// rocking-block, slider-crank), as its scene file in meshes/ would.
    Example {
        /// The example.
        name: String,
        /// Output directory (default out/NAME).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Print nothing but errors.
        #[arg(long)]
        quiet: bool,
    },
    /// Run a study: the paper's, on its academic examples (convergence,
    /// projection-multiplier, chattering, energy), the impacting bar's (speed-accuracy,
    /// extremes), the slider–crank's, or the costs per size (costs). Writes CSV, plots
    /// and verdict lines.
    Study {
        /// The study.
        name: String,
        /// `extremes` only: a scene file to run at the extremes (every scheme at its step
        /// ×1/8 … ×8, e = 0 and 1, θ = 1/2 and 1, stiffness ×1e-3 and ×1e3) instead of
        /// the bar's cases.
        scene: Option<PathBuf>,
        /// Output directory (default out/study-NAME, or out/study-NAME-SCENE).
        #[arg(long)]
        out: Option<PathBuf>,
        /// With a scene: set KEY=VALUE in it first (as `run --set`); repeatable.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// With a scene: only this scheme (repeatable; default every scheme).
        #[arg(long = "scheme", value_enum)]
        schemes: Vec<SchemeKind>,
    },
    /// Measure the speed–accuracy trade of a scene (a file, or `bar` for the reference
    /// bar) over a grid of schemes, time steps, mesh refinements, θ, metrics, friction
    /// solvers and any scene key; `sweep merge DIR` joins the shards of a sharded sweep.
    /// Writes sweep.csv, the Pareto plot and verdict lines.
    Sweep(SweepArgs),
    /// Finish a killed run from the checkpoint in its directory (written by
    /// `--checkpoint-every K`): the directory then holds what an uninterrupted run writes.
    Resume {
        /// The run's output directory.
        dir: PathBuf,
        /// Print nothing but errors.
        #[arg(long)]
        quiet: bool,
    },
    /// Redraw the plots (contact force, energy, violation; PNG and SVG) of a run directory
    /// from its history.csv and summary.json.
    Plot {
        /// The run's output directory.
        dir: PathBuf,
    },
    /// Solve a one-step frictional contact problem read from a file: FCLIB HDF5 (local or
    /// global, with the `hdf5` feature) or Siconos' .dat text format (2-D and 3-D).
    /// Exit code 1 when the solver stops at its cap above the tolerance.
    Fclib(FclibArgs),
}

#[derive(Args)]
struct FclibArgs {
    /// The problem file (.hdf5, .h5 or .dat).
    file: PathBuf,
    /// The friction solver.
    #[arg(long, value_enum, default_value = "auto")]
    solver: signorini::solvers::friction::FrictionSolverKind,
    /// Residual to reach (relative; see --residual).
    #[arg(long, default_value_t = signorini::io::fclib::DEFAULT_TOL)]
    tol: f64,
    /// Which residual: `siconos` (Siconos' natural-map error on De Saxcé's velocity,
    /// comparable with Siconos' figures) or `velocity` (Alart–Curnier's map, each contact
    /// scaled to m/s by its W_NN: what the schemes stop on).
    #[arg(long, default_value = "siconos", value_parser = ["siconos", "velocity"])]
    residual: String,
    /// Cap on NSGS sweeps (over all proximal iterations for prox).
    #[arg(long, default_value_t = signorini::io::fclib::DEFAULT_MAX_ITERATIONS)]
    max_iter: usize,
    /// Start from the file's /guesses/1/r instead of r = 0.
    #[arg(long)]
    warm: bool,
    /// Solve this many times (from the same start) and report the median time.
    #[arg(long, default_value_t = 1)]
    repeat: usize,
    /// Write r, u, residual, iterations and seconds as JSON.
    #[arg(long, value_name = "OUT.json")]
    solution: Option<PathBuf>,
}

#[derive(Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
struct SweepArgs {
    #[command(subcommand)]
    command: Option<SweepCommand>,
    #[command(flatten)]
    run: SweepRunArgs,
}

#[derive(Subcommand)]
enum SweepCommand {
    /// Join the shards (DIR/shard-i-of-N/, from --shard or a Slurm array) of one sweep
    /// into DIR's table: equal to the unsharded sweep's but for the timings.
    Merge {
        /// The sweep's output directory (the --out of every shard).
        dir: PathBuf,
    },
}

#[derive(Args)]
struct SweepRunArgs {
    /// The scene file, or `bar` for the reference impacting bar (meshes/bar.toml; a
    /// file named `bar` is `./bar`).
    #[arg(required = true)]
    scene: Option<String>,
    /// Override a key of the scene before the grid's (as `run --set`; repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Schemes (comma-separated scheme names).
    #[arg(long, value_delimiter = ',', value_name = "NAMES")]
    scheme: Vec<String>,
    /// Time steps (s, comma-separated).
    #[arg(long, value_delimiter = ',', value_name = "H")]
    dt: Vec<f64>,
    /// Mesh refinement levels: every generated mesh's cell counts times the level.
    #[arg(long, value_delimiter = ',', value_name = "LEVELS")]
    refine: Vec<usize>,
    /// θ values.
    #[arg(long, value_delimiter = ',')]
    theta: Vec<f64>,
    /// Projection metrics (mass, euclidean).
    #[arg(long, value_delimiter = ',')]
    metric: Vec<String>,
    /// Friction solvers (auto, nsgs, prox, nsn, …).
    #[arg(long, value_delimiter = ',')]
    friction_solver: Vec<String>,
    /// Friction tolerances.
    #[arg(long, value_delimiter = ',')]
    friction_tol: Vec<f64>,
    /// Any scene key over a list of TOML values: KEY=[V1, V2, …] (repeatable), e.g.
    /// --axis 'bodies[0].material.young=[1e9, 2e9]'.
    #[arg(long, value_name = "KEY=[VALUES]")]
    axis: Vec<String>,
    /// Runs per point; the wall time is their median.
    #[arg(long)]
    repeat: Option<usize>,
    /// Accuracy levels of the verdict (relative, comma-separated; default 0.1,0.01,0.001).
    #[arg(long, value_delimiter = ',')]
    levels: Vec<f64>,
    /// Output directory (default out/sweep-<scene stem>).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Keep the runs already recorded in the directory (same grid) and run the rest.
    #[arg(long)]
    resume: bool,
    /// Run only shard i of N (points whose index is i modulo N), into DIR/shard-i-of-N/;
    /// read from SLURM_ARRAY_TASK_ID/COUNT (less SLURM_ARRAY_TASK_MIN) when not given.
    #[arg(long, value_name = "i/N")]
    shard: Option<String>,
    /// Spread the grid over the ranks of an MPI job (`mpirun -np N signorini sweep …
    /// --mpi`; builds with the `mpi` feature): rank 0 gathers the records and writes
    /// the table.
    #[arg(long, conflicts_with = "shard")]
    mpi: bool,
    /// Points run at the same time, each on its share of the cores (default: one per
    /// core; 1 with --repeat > 1, whose timing medians want each point alone, and with
    /// --mpi, whose ranks fill the cores). Every point's record is the same with any
    /// value, times and peak memory aside.
    #[arg(long, value_name = "N")]
    jobs: Option<usize>,
    /// Print only one line per run.
    #[arg(long)]
    quiet: bool,
}

#[derive(Args)]
struct SceneArgs {
    /// The scene file.
    scene: PathBuf,
    /// Override a key of the scene: KEY=VALUE, KEY a dotted path with array indices,
    /// VALUE in TOML (repeatable), e.g. --set scheme.newton.modified=true
    /// --set 'bodies[0].material.model="svk"'.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Output directory (default: the scene's output.dir, else out/<file stem>).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Print nothing but errors.
    #[arg(long)]
    quiet: bool,
    #[command(flatten)]
    output: OutputArgs,
}

/// Output strides and formats (override the scene's `[output]`).
#[derive(Args, Clone)]
struct OutputArgs {
    /// Save a field frame every K steps (default: about 100 frames; frames are also saved
    /// at the start, at contact onset and release and at the last step).
    #[arg(long, value_name = "K")]
    save_every: Option<usize>,
    /// Write a history row every K steps (default 1).
    #[arg(long, value_name = "K")]
    history_every: Option<usize>,
    /// Write no field frames (neither .vtu/.pvd nor, with the hdf5 feature, the VTKHDF grid).
    #[arg(long)]
    no_fields: bool,
    /// Write the .vtu arrays as text instead of zlib-compressed binary.
    #[arg(long)]
    ascii: bool,
    /// Draw no plots at the end of the run.
    #[arg(long)]
    no_plots: bool,
    /// Write no HDF5 file (builds with the `hdf5` feature write one by default).
    #[arg(long)]
    no_hdf5: bool,
    /// Write a checkpoint every K steps (`checkpoint.json` in the output directory);
    /// `signorini resume DIR` finishes a killed run from it.
    #[arg(long, value_name = "K")]
    checkpoint_every: Option<usize>,
}

impl OutputArgs {
    /// Checks the strides whether or not the run writes what they stride.
    fn validate(&self) -> Result<(), signorini::Error> {
        for (flag, v) in [
            ("--save-every", self.save_every),
            ("--history-every", self.history_every),
        ] {
            if v == Some(0) {
                return Err(signorini::Error::invalid(flag, 0, "must be at least 1"));
            }
        }
        Ok(())
    }

    fn apply(&self, o: &mut OutputOptions) {
        if let Some(k) = self.save_every {
            o.stride = k;
        }
        if let Some(k) = self.history_every {
            o.history_stride = k;
        }
        if self.no_fields {
            o.fields = false;
        }
        if self.ascii {
            o.encoding = Encoding::Ascii;
        }
        if self.no_plots {
            o.plots = false;
        }
        if self.no_hdf5 {
            o.hdf5 = Some(false);
        }
        if let Some(k) = self.checkpoint_every {
            o.checkpoint_every = k;
        }
    }
}

/// The CLI's forecast and LCP choices: the library's `Forecast` and `LcpKind` carry their
/// parameters (γ; PGS tolerance and sweeps), which come from their own flags here.
#[derive(Clone, Copy, ValueEnum)]
enum ForecastArg {
    Explicit,
    Free,
}

#[derive(Clone, Copy, ValueEnum)]
enum LcpArg {
    Auto,
    Lemke,
    BlockPivoting,
    Pgs,
}

#[derive(Args)]
struct BarArgs {
    /// Number of rod elements N.
    #[arg(long, default_value_t = 1000)]
    elements: usize,
    /// Time step h (s).
    #[arg(long, default_value_t = 2e-7, allow_hyphen_values = true)]
    dt: f64,
    /// End time (s).
    #[arg(long, default_value_t = 1e-3, allow_hyphen_values = true)]
    t_end: f64,
    /// θ of the θ-method, in [1/2, 1].
    #[arg(long, default_value_t = 0.5, allow_hyphen_values = true)]
    theta: f64,
    /// Time-stepping scheme.
    #[arg(long, value_enum, default_value = "combined-projection")]
    scheme: SchemeKind,
    /// Activation forecast for moreau-jean and direct-projection (eq. 61 / 62).
    #[arg(long, value_enum, default_value = "free")]
    forecast: ForecastArg,
    /// γ of the explicit forecast (eq. 61), in [0, 2].
    #[arg(long, default_value_t = 1.0, allow_hyphen_values = true)]
    gamma: f64,
    /// Restitution coefficient e at the tip, in [0, 1].
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    restitution: f64,
    /// Initial gap between the tip and the wall (m).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    gap: f64,
    /// Initial velocity of the bar (m/s; negative moves towards the wall).
    #[arg(long, default_value_t = -0.1, allow_hyphen_values = true)]
    velocity: f64,
    /// Length L (m).
    #[arg(long, default_value_t = 1.0, allow_hyphen_values = true)]
    length: f64,
    /// Cross-section S (m²); default π·10⁻⁴.
    #[arg(long, default_value_t = std::f64::consts::PI * 1e-4, allow_hyphen_values = true)]
    area: f64,
    /// Young's modulus E (Pa).
    #[arg(long, default_value_t = 210e9, allow_hyphen_values = true)]
    young: f64,
    /// Density ρ (kg/m³).
    #[arg(long, default_value_t = 7800.0, allow_hyphen_values = true)]
    density: f64,
    /// Mass matrix.
    #[arg(long, value_enum, default_value = "consistent")]
    mass: MassKind,
    /// Position projection metric for the projection schemes (eq. 58 / 60).
    #[arg(long, value_enum, default_value = "mass")]
    metric: Metric,
    /// Moreau–Jean: the forecast's active set alone (eq. 61/62), not closed on the
    /// step's solution.
    #[arg(long)]
    no_activation_closure: bool,
    /// Algorithm 2's position rule on the active set: persistent (g = 0 where P > 0 in
    /// this step and the last, the default), paper (where P > 0, eq. 68),
    /// complementarity (τ ≥ 0 only) or all-active (Siconos' code).
    #[arg(long, value_enum, default_value = "persistent")]
    projection_rule: ProjectionRule,
    /// Newton's law with e on contacts separating at the step's start too (eq. 18d as
    /// written), instead of max(e, (1 − θ)/θ), which keeps impulses from adding energy.
    #[arg(long)]
    newton_restitution: bool,
    /// Projection schemes: update only q with τ (Siconos' practice), not v through the
    /// −hθK N G τ term of eq. 56a.
    #[arg(long)]
    no_projection_feedback: bool,
    /// Stop projecting below this violation (m); 0 projects to machine accuracy.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    projection_tolerance: f64,
    /// One-step LCP solver: auto (Lemke up to 16 unknowns, block pivoting above), Lemke,
    /// block pivoting (both exact), or projected Gauss–Seidel.
    #[arg(long, value_enum, default_value = "auto")]
    lcp: LcpArg,
    /// PGS tolerance on the complementarity residual, relative to max(1, |q|).
    #[arg(long, default_value_t = 1e-12, allow_hyphen_values = true)]
    lcp_tol: f64,
    /// PGS sweep cap.
    #[arg(long, default_value_t = 10_000)]
    lcp_max_sweeps: usize,
    /// Delassus storage: dense n×m blocks, per-active-column, or auto (dense up to 64
    /// contacts).
    #[arg(long, value_enum, default_value = "auto")]
    delassus: DelassusKind,
    /// Columns of the per-active-column pool (0: as many as fit in 2 GiB).
    #[arg(long, default_value_t = 0)]
    delassus_pool: usize,
    /// Newton / fixed-point tolerance (relative).
    #[arg(long, default_value_t = 1e-10, allow_hyphen_values = true)]
    newton_tol: f64,
    /// Newton iteration cap per step.
    #[arg(long, default_value_t = 50)]
    newton_max_iterations: usize,
    /// Count iteration caps hit (Newton, projection, LCP) in the summary and go on,
    /// instead of failing the run (exit code 1) at the first one.
    #[arg(long)]
    allow_caps: bool,
    /// Largest energy growth beyond the work supplied, relative to the run's energy
    /// scale, before the run fails (exit code 1); `inf` accepts any.
    #[arg(long, default_value_t = signorini::integrators::DEFAULT_MAX_ENERGY_EXCESS)]
    max_energy_excess: f64,
    /// Output directory.
    #[arg(long, default_value = "out/bar")]
    out: PathBuf,
    /// Print nothing but errors.
    #[arg(long)]
    quiet: bool,
    #[command(flatten)]
    output: OutputArgs,
}

impl BarArgs {
    /// Checks every flag, also those the chosen options do not use (`--lcp-tol -1`
    /// without `--lcp pgs` is as wrong as with it).
    fn validate_flags(&self) -> Result<(), signorini::Error> {
        use signorini::error::{require_in, require_positive};
        require_in("--gamma", self.gamma, 0.0, 2.0)?;
        require_positive("--lcp-tol", self.lcp_tol)?;
        if self.lcp_max_sweeps == 0 {
            return Err(signorini::Error::invalid(
                "--lcp-max-sweeps",
                0,
                "must be at least 1",
            ));
        }
        Ok(())
    }

    fn scene(&self) -> BarScene {
        let mut s = BarScene {
            elements: self.elements,
            dt: self.dt,
            t_end: self.t_end,
            length: self.length,
            area: self.area,
            young: self.young,
            density: self.density,
            velocity: self.velocity,
            gap: self.gap,
            restitution: self.restitution,
            mass: self.mass,
            ..BarScene::default()
        };
        let p = &mut s.scheme;
        p.kind = self.scheme;
        p.theta = self.theta;
        p.forecast = match self.forecast {
            ForecastArg::Explicit => Forecast::Explicit { gamma: self.gamma },
            ForecastArg::Free => Forecast::Free,
        };
        p.metric = self.metric;
        p.projection_rule = self.projection_rule;
        p.activation_closure = !self.no_activation_closure;
        p.energy_consistent_restitution = !self.newton_restitution;
        p.projection_feedback = !self.no_projection_feedback;
        p.projection_tolerance = self.projection_tolerance;
        p.lcp = match self.lcp {
            LcpArg::Auto => LcpKind::Auto,
            LcpArg::Lemke => LcpKind::Lemke,
            LcpArg::BlockPivoting => LcpKind::BlockPivoting,
            LcpArg::Pgs => LcpKind::Pgs {
                tol: self.lcp_tol,
                max_sweeps: self.lcp_max_sweeps,
            },
        };
        p.delassus = self.delassus;
        p.delassus_pool = self.delassus_pool;
        p.newton.tol = self.newton_tol;
        p.newton.max_iterations = self.newton_max_iterations;
        p.allow_caps = self.allow_caps;
        p.max_energy_excess = Some(self.max_energy_excess);
        s
    }
}

/// Progress on stderr: an indicatif bar with steps/s and ETA on a terminal, a plain line
/// per 10 % otherwise (logs, CI).
enum CliProgress {
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

fn run_bar(args: &BarArgs) -> Result<(), signorini::Error> {
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
    Ok(())
}

fn progress_sink(quiet: bool) -> Box<dyn Progress> {
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

fn scene_out(args: &SceneArgs, scene: &Scene) -> PathBuf {
    args.out
        .clone()
        .or_else(|| scene.output.dir.clone())
        .unwrap_or_else(|| PathBuf::from("out").join(args.scene.file_stem().unwrap_or_default()))
}

fn run_scene(args: &SceneArgs) -> Result<(), signorini::Error> {
    args.output.validate()?;
    let scene = Scene::from_file_with(&args.scene, &args.set)?;
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
    Ok(())
}

fn run_example(name: &str, out: Option<PathBuf>, quiet: bool) -> Result<(), signorini::Error> {
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
fn fclib(a: &FclibArgs) -> Result<bool, signorini::Error> {
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

fn check_scene(args: &SceneArgs) -> Result<(), signorini::Error> {
    let scene = Scene::from_file_with(&args.scene, &args.set)?;
    let c = scene.check().map_err(|e| e.in_file(&args.scene))?;
    // printed in full even when the memory does not fit (the error comes last)
    out!("scene               {} (valid)", args.scene.display());
    out!(
        "model               {} bodies, {} cells, {} dofs ({} fixed dofs removed), {} candidate contacts",
        c.bodies,
        c.cells,
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
        out!("interface           {line}");
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
struct SweepLines {
    ranks: bool,
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

fn sweep(a: &SweepArgs) -> Result<(), signorini::Error> {
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

fn print_summary(s: &run::Summary, out: &std::path::Path) {
    out!("scheme              {}", s.scheme);
    out!("path                {}", s.path);
    out!(
        "steps               {} in {:.3} s ({:.3} µs/step, {:.2} ns/dof/step; output {:.0} % of it)",
        s.steps,
        s.wall_seconds,
        1e6 * s.seconds_per_step,
        1e9 * s.seconds_per_step / s.dofs as f64,
        100.0 * s.output_seconds / s.wall_seconds.max(1e-12)
    );
    if s.frames > 0 {
        out!(
            "frames              {} written in {:.3} s on the writer thread, alongside the steps (the loop waited {:.3} s for it)",
            s.frames,
            s.frame_seconds,
            s.frame_wait_seconds
        );
    }
    out!("max violation       {:.3e} m", s.max_violation);
    out!(
        "iterations          newton {:.3}/{}  projection {:.3}/{}  index-set {:.3}/{}  lcp {:.3}/{} (mean/max); caps hit {}",
        s.iterations.newton.mean,
        s.iterations.newton.max,
        s.iterations.projection.mean,
        s.iterations.projection.max,
        s.iterations.index_set.mean,
        s.iterations.index_set.max,
        s.iterations.lcp.mean,
        s.iterations.lcp.max,
        s.caps_hit
    );
    let l = &s.newton_loops;
    if l.coupled_solves + l.stalls + l.steps_with_held_rows + l.complementarity_fallbacks > 0 {
        out!(
            "newton loops        {} coupled position solves, {} stalls within √tol, {} steps with held rows, {} rounds redone with complementarity",
            l.coupled_solves,
            l.stalls,
            l.steps_with_held_rows,
            l.complementarity_fallbacks
        );
    }
    if let Some(n) = &s.nonlinear {
        out!(
            "nonlinear           {} factorizations of M̂ⁿ ({:.2} per step); {:.3} s assembling F and Kⁿ, {:.3} s factoring, of {:.3} s of steps",
            n.factorizations,
            n.factorizations_per_step,
            n.assembly_seconds,
            n.factorization_seconds,
            s.wall_seconds
        );
    }
    if let Some(f) = &s.friction {
        out!(
            "friction            {} solves ({} past NSGS), {:.2} sweeps each (max {} in a step), residual mean {:.2e} max {:.2e}; caps hit {}",
            f.solves,
            f.fallbacks,
            f.sweeps_mean,
            f.sweeps_max_per_step,
            f.residual_mean,
            f.residual_max,
            f.caps_hit
        );
    }
    if let Some(peak) = s.peak_memory_bytes {
        out!(
            "memory              {} peak resident, {} planned",
            signorini::limits::bytes(peak),
            signorini::limits::bytes(s.memory_planned_bytes)
        );
    }
    if let Some(g) = &s.matrix_free {
        out!(
            "matrix-free         {} one-step problems past the dense workspaces, {:.1} products with W each",
            g.solves,
            g.products_per_solve
        );
    }
    if let Some(c) = &s.contact {
        let rel = |a: f64, b: f64| 100.0 * (a / b - 1.0);
        out!("                    measured        analytic        difference");
        out!(
            "contact force       {:<12.3} N  {:<12.3} N  {:+.3} % (plateau std {:.2} N)",
            c.plateau_force,
            c.analytic_force,
            rel(c.plateau_force, c.analytic_force),
            c.plateau_std
        );
        out!(
            "contact duration    {:<12.4e} s  {:<12.4e} s  {:+.3} %",
            c.duration,
            c.analytic_duration,
            rel(c.duration, c.analytic_duration)
        );
        out!(
            "release velocity    {:<12.5} m/s {:<12.5} m/s {:+.3} %",
            c.release_velocity,
            c.analytic_release_velocity,
            rel(c.release_velocity, c.analytic_release_velocity)
        );
        out!(
            "total impulse       {:<12.5e} Ns {:<12.5e} Ns {:+.3} %",
            c.total_impulse,
            c.analytic_total_impulse,
            rel(c.total_impulse, c.analytic_total_impulse)
        );
    }
    let mut frames = if s.frames > 0 {
        format!(", {}/fields.pvd ({} frames)", out.display(), s.frames)
    } else {
        String::new()
    };
    if out.join("contact_force.png").exists() {
        frames.push_str(", plots (contact_force, energy, violation .png/.svg)");
    }
    out!(
        "wrote               {}/summary.json, {}/history.csv{frames}",
        out.display(),
        out.display()
    );
}

/// `--mumps`: MPI and the host's guard on rank 0 (`Some`), `None` on the other ranks
/// once the host is done with them, or when the flag is off.
#[cfg(feature = "mumps")]
fn start_mumps(cli: &Cli) -> Result<Option<signorini::linalg::mumps::HostGuard>, signorini::Error> {
    use signorini::linalg::mumps::{Role, start};
    if !cli.mumps {
        return Ok(None);
    }
    if matches!(&cli.command, Some(Command::Sweep(a)) if a.run.mpi) {
        return Err(signorini::Error::invalid(
            "--mumps",
            "true",
            "not with `sweep --mpi`: there the ranks run the sweep's points, each with its \
             own serial factor",
        ));
    }
    Ok(match start("--mumps")? {
        Role::Host(g) => Some(g),
        Role::Worker => None,
    })
}

#[cfg(not(feature = "mumps"))]
fn start_mumps(cli: &Cli) -> Result<Option<()>, signorini::Error> {
    if cli.mumps {
        return Err(signorini::Error::invalid(
            "--mumps",
            "true",
            "this signorini was built without the `mumps` cargo feature (cargo build \
             --release --features mumps, with libmumps-dev, libopenmpi-dev and libclang-dev)",
        ));
    }
    Ok(None)
}

/// The global flags written before a subcommand (`signorini --mumps run SCENE`) moved
/// after it: the bar's flags are accepted without a subcommand, so clap refuses any
/// flag before one ("the subcommand 'run' cannot be used with '--mumps'", issue 34).
fn globals_after_subcommand(mut args: Vec<std::ffi::OsString>) -> Vec<std::ffi::OsString> {
    const GLOBALS: [&str; 3] = ["--mumps", "--portable-arithmetic", "--ieee-subnormals"];
    const SUBCOMMANDS: [&str; 10] = [
        "bar", "run", "check", "example", "study", "sweep", "resume", "plot", "fclib", "help",
    ];
    let lead = args
        .iter()
        .skip(1)
        .take_while(|a| a.to_str().is_some_and(|a| GLOBALS.contains(&a)))
        .count();
    let next = args.get(1 + lead).and_then(|a| a.to_str());
    if lead > 0 && next.is_some_and(|n| SUBCOMMANDS.contains(&n)) {
        let flags: Vec<_> = args.drain(1..1 + lead).collect();
        args.splice(2..2, flags);
    }
    args
}

fn main() -> ExitCode {
    let cli = Cli::parse_from(globals_after_subcommand(std::env::args_os().collect()));
    signorini::linalg::set_portable_arithmetic(cli.portable_arithmetic);
    signorini::linalg::set_ieee_subnormals(cli.ieee_subnormals);
    // every command's threads (this one and rayon's) in the run's subnormal mode; runs
    // set it again for library callers (`app::run_scene` and friends)
    let _flush = signorini::linalg::FlushGuard::for_run();
    // every command refuses a limit it cannot read (issue 34: ignored silently before)
    if let Err(e) = signorini::limits::memory_limit_setting() {
        err!("error: {e}");
        return ExitCode::from(e.exit_code());
    }
    // kept to the end of main: dropping it releases the other ranks and finalizes MPI
    let _mumps_host = match start_mumps(&cli) {
        Ok(Some(host)) => Some(host),
        Ok(None) if cli.mumps => return ExitCode::SUCCESS, // another rank: served, done
        Ok(None) => None,
        Err(e) => {
            err!("error: {e}");
            return ExitCode::from(e.exit_code());
        }
    };
    let result = match cli.command {
        Some(Command::Bar(a)) => run_bar(&a),
        Some(Command::Run(a)) => run_scene(&a),
        Some(Command::Check(a)) => check_scene(&a),
        Some(Command::Example { name, out, quiet }) => run_example(&name, out, quiet),
        Some(Command::Study {
            name,
            scene,
            out,
            set,
            schemes,
        }) => {
            let dir = out.unwrap_or_else(|| match &scene {
                Some(p) => PathBuf::from(format!(
                    "out/study-{name}-{}",
                    p.file_stem()
                        .map_or("scene".into(), |s| s.to_string_lossy())
                )),
                None => PathBuf::from(format!("out/study-{name}")),
            });
            let result = match &scene {
                Some(p) => signorini::study::run_on_scene(&name, p, &set, &schemes, &dir),
                None if !schemes.is_empty() => Err(signorini::Error::invalid(
                    "--scheme",
                    schemes[0].name(),
                    "needs a scene file (`signorini study extremes SCENE --scheme NAME`)",
                )),
                None if !set.is_empty() => Err(signorini::Error::invalid(
                    "--set",
                    &set[0],
                    "needs a scene file (`signorini study extremes SCENE --set KEY=VALUE`)",
                )),
                None => signorini::study::run(&name, &dir),
            };
            result.map(|v| {
                for line in v {
                    out!("{line}");
                }
                let mut files: Vec<String> = std::fs::read_dir(&dir)
                    .map(|d| {
                        d.filter_map(|e| e.ok())
                            .map(|e| e.file_name().to_string_lossy().into_owned())
                            .collect()
                    })
                    .unwrap_or_default();
                files.sort();
                out!("wrote {}/ {{{}}}", dir.display(), files.join(", "));
            })
        }
        Some(Command::Sweep(a)) => sweep(&a),
        Some(Command::Resume { dir, quiet }) => app::resume(&dir, progress_sink(quiet).as_mut())
            .map(|r| {
                if !quiet {
                    print_summary(&r.summary, &dir);
                }
            }),
        Some(Command::Plot { dir }) => signorini::plot::plot_run(&dir).map(|files| {
            for f in files {
                out!("wrote {}", f.display());
            }
        }),
        Some(Command::Fclib(a)) => match fclib(&a) {
            Ok(true) => Ok(()),
            Ok(false) => return ExitCode::from(1),
            Err(e) => Err(e),
        },
        None => run_bar(&cli.bar),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            err!("error: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}
