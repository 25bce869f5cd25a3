//! The command line's arguments: clap types of every subcommand and their conversions
//! to the library's parameters.

use super::*;

/// A count flag's value (`--jobs`, `--max-iter`, `--repeat`, …): a whole number ≥ 1.
/// Without it, `--jobs -1` was read as an unknown flag `-1` ("unexpected argument").
fn positive(s: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(n) if n >= 1 => Ok(n),
        _ => Err("must be a positive integer (1, 2, 3, …)".to_string()),
    }
}

/// `--jobs`: a whole number, its range (1 to 1024) checked by the sweep, which names it.
fn jobs(s: &str) -> Result<usize, String> {
    s.trim()
        .parse::<usize>()
        .map_err(|_| "must be a positive integer (1 to 1024)".to_string())
}

/// A count flag that takes 0 where the run says what 0 means (`--checkpoint-every`,
/// `--delassus-pool`, …; a 0 the run cannot use is refused there, with its reason):
/// a whole number ≥ 0.
fn count(s: &str) -> Result<usize, String> {
    s.trim()
        .parse::<usize>()
        .map_err(|_| "must be a whole number (0, 1, 2, …)".to_string())
}

#[derive(Args)]
pub(crate) struct FclibArgs {
    /// The problem file (.hdf5, .h5 or .dat).
    pub(crate) file: PathBuf,
    /// The friction solver.
    #[arg(long, value_enum, default_value = "auto")]
    pub(crate) solver: signorini::solvers::friction::FrictionSolverKind,
    /// Residual to reach (relative; see --residual).
    #[arg(long, default_value_t = signorini::io::fclib::DEFAULT_TOL)]
    pub(crate) tol: f64,
    /// Which residual: `siconos` (Siconos' natural-map error on De Saxcé's velocity,
    /// comparable with Siconos' figures) or `velocity` (Alart–Curnier's map, each contact
    /// scaled to m/s by its W_NN: what the schemes stop on).
    #[arg(long, default_value = "siconos", value_parser = ["siconos", "velocity"])]
    pub(crate) residual: String,
    /// Cap on NSGS sweeps (over all proximal iterations for prox).
    #[arg(long, default_value_t = signorini::io::fclib::DEFAULT_MAX_ITERATIONS, allow_hyphen_values = true, value_parser = positive)]
    pub(crate) max_iter: usize,
    /// Start from the file's /guesses/1/r instead of r = 0.
    #[arg(long)]
    pub(crate) warm: bool,
    /// Solve this many times (from the same start) and report the median time.
    #[arg(long, default_value_t = 1, allow_hyphen_values = true, value_parser = positive)]
    pub(crate) repeat: usize,
    /// Write r, u, residual, iterations and seconds as JSON.
    #[arg(long, value_name = "OUT.json")]
    pub(crate) solution: Option<PathBuf>,
}

#[derive(Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub(crate) struct SweepArgs {
    #[command(subcommand)]
    pub(crate) command: Option<SweepCommand>,
    #[command(flatten)]
    pub(crate) run: SweepRunArgs,
}

#[derive(Subcommand)]
pub(crate) enum SweepCommand {
    /// Join the shards (DIR/shard-i-of-N/, from --shard or a Slurm array) of one sweep
    /// into DIR's table: equal to the unsharded sweep's but for the timings.
    Merge {
        /// The sweep's output directory (the --out of every shard).
        dir: PathBuf,
    },
}

#[derive(Args)]
pub(crate) struct SweepRunArgs {
    /// The scene file, or `bar` for the reference impacting bar (meshes/bar.toml; a
    /// file named `bar` is `./bar`).
    #[arg(required = true)]
    pub(crate) scene: Option<String>,
    /// Override a key of the scene before the grid's (as `run --set`; repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub(crate) set: Vec<String>,
    /// Schemes (comma-separated scheme names).
    #[arg(long, value_delimiter = ',', value_name = "NAMES")]
    pub(crate) scheme: Vec<String>,
    /// Time steps (s, comma-separated).
    #[arg(long, value_delimiter = ',', value_name = "H")]
    pub(crate) dt: Vec<f64>,
    /// Mesh refinement levels: every generated mesh's cell counts times the level.
    #[arg(long, value_delimiter = ',', value_name = "LEVELS", allow_hyphen_values = true, value_parser = positive)]
    pub(crate) refine: Vec<usize>,
    /// θ values.
    #[arg(long, value_delimiter = ',')]
    pub(crate) theta: Vec<f64>,
    /// Projection metrics (mass, euclidean).
    #[arg(long, value_delimiter = ',')]
    pub(crate) metric: Vec<String>,
    /// Friction solvers (auto, nsgs, prox, nsn, …).
    #[arg(long, value_delimiter = ',')]
    pub(crate) friction_solver: Vec<String>,
    /// Friction tolerances.
    #[arg(long, value_delimiter = ',')]
    pub(crate) friction_tol: Vec<f64>,
    /// Any scene key over a list of TOML values: KEY=[V1, V2, …] (repeatable), e.g.
    /// --axis 'bodies[0].material.young=[1e9, 2e9]'.
    #[arg(long, value_name = "KEY=[VALUES]")]
    pub(crate) axis: Vec<String>,
    /// Runs per point; the wall time is their median.
    #[arg(long, allow_hyphen_values = true, value_parser = positive)]
    pub(crate) repeat: Option<usize>,
    /// Accuracy levels of the verdict (relative, comma-separated; default 0.1,0.01,0.001).
    #[arg(long, value_delimiter = ',')]
    pub(crate) levels: Vec<f64>,
    /// Output directory (default out/sweep-<scene stem>).
    #[arg(long)]
    pub(crate) out: Option<PathBuf>,
    /// Keep the runs already recorded in the directory (same grid) and run the rest.
    #[arg(long)]
    pub(crate) resume: bool,
    /// Run only shard i of N (points whose index is i modulo N), into DIR/shard-i-of-N/;
    /// read from SLURM_ARRAY_TASK_ID/COUNT (less SLURM_ARRAY_TASK_MIN) when not given.
    #[arg(long, value_name = "i/N")]
    pub(crate) shard: Option<String>,
    /// Spread the grid over the ranks of an MPI job (`mpirun -np N signorini sweep …
    /// --mpi`; builds with the `mpi` feature): rank 0 gathers the records and writes
    /// the table.
    #[arg(long, conflicts_with = "shard")]
    pub(crate) mpi: bool,
    /// Points run at the same time, each on its share of the cores (default: one per
    /// core; 1 with --repeat > 1, whose timing medians want each point alone, and with
    /// --mpi, whose ranks fill the cores). Every point's record is the same with any
    /// value, times and peak memory aside.
    #[arg(long, value_name = "N", allow_hyphen_values = true, value_parser = jobs)]
    pub(crate) jobs: Option<usize>,
    /// Print only one line per run.
    #[arg(long)]
    pub(crate) quiet: bool,
}

#[derive(Args)]
pub(crate) struct SceneArgs {
    /// The scene file.
    pub(crate) scene: PathBuf,
    /// Override a key of the scene: KEY=VALUE, KEY a dotted path with array indices,
    /// VALUE in TOML (repeatable), e.g. --set scheme.newton.modified=true
    /// --set 'bodies[0].material.model="svk"'.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub(crate) set: Vec<String>,
    /// The accuracy mode: the relative accuracy asked of the run's observables (the
    /// same as --set time.accuracy=TOL); the run chooses its steps (at most time.dt, or
    /// time.dt_max; a pilot pass runs the whole span at it first) and writes the error it
    /// estimates (exit 1 when over TOL): the step's error on this mesh, not the mesh's.
    /// Experimental (issue 50): it meets TOL on the committed scenes but the Hertz ball
    /// (a silent miss) and costs more than the cheapest fixed step that does (`signorini
    /// study accuracy SCENE` measures both).
    #[arg(long, value_name = "TOL", allow_hyphen_values = true)]
    pub(crate) accuracy: Option<f64>,
    /// Output directory (default: the scene's output.dir, else out/<file stem>).
    #[arg(long)]
    pub(crate) out: Option<PathBuf>,
    /// Print nothing but errors.
    #[arg(long)]
    pub(crate) quiet: bool,
    #[command(flatten)]
    pub(crate) output: OutputArgs,
}

/// Output strides and formats (override the scene's `[output]`).
#[derive(Args, Clone)]
pub(crate) struct OutputArgs {
    /// Save a field frame every K steps (default: about 100 frames; frames are also saved
    /// at the start, at contact onset and release and at the last step).
    #[arg(long, value_name = "K", allow_hyphen_values = true, value_parser = count)]
    pub(crate) save_every: Option<usize>,
    /// Write a history row every K steps (default 1).
    #[arg(long, value_name = "K", allow_hyphen_values = true, value_parser = count)]
    pub(crate) history_every: Option<usize>,
    /// Write no field frames (neither .vtu/.pvd nor, with the hdf5 feature, the VTKHDF grid).
    #[arg(long)]
    pub(crate) no_fields: bool,
    /// Write the .vtu arrays as text instead of zlib-compressed binary.
    #[arg(long)]
    pub(crate) ascii: bool,
    /// Draw no plots at the end of the run.
    #[arg(long)]
    pub(crate) no_plots: bool,
    /// Write no HDF5 file (builds with the `hdf5` feature write one by default).
    #[arg(long)]
    pub(crate) no_hdf5: bool,
    /// Write a checkpoint every K steps (`checkpoint.json` in the output directory);
    /// `signorini resume DIR` finishes a killed run from it.
    #[arg(long, value_name = "K", allow_hyphen_values = true, value_parser = count)]
    pub(crate) checkpoint_every: Option<usize>,
}

impl OutputArgs {
    /// Checks the strides whether or not the run writes what they stride.
    pub(crate) fn validate(&self) -> Result<(), signorini::Error> {
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

    pub(crate) fn apply(&self, o: &mut OutputOptions) {
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
pub(crate) enum ForecastArg {
    Explicit,
    Free,
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum LcpArg {
    Auto,
    Lemke,
    BlockPivoting,
    Pgs,
}

#[derive(Args)]
pub(crate) struct BarArgs {
    /// Number of rod elements N.
    #[arg(long, default_value_t = 1000, allow_hyphen_values = true, value_parser = count)]
    pub(crate) elements: usize,
    /// Time step h (s).
    #[arg(long, default_value_t = 2e-7, allow_hyphen_values = true)]
    pub(crate) dt: f64,
    /// End time (s).
    #[arg(long, default_value_t = 1e-3, allow_hyphen_values = true)]
    pub(crate) t_end: f64,
    /// The accuracy mode: the relative accuracy asked of the contact impulse history,
    /// the energy, the impact locations and the displacement field; the run chooses its
    /// steps (at most --dt, at least --dt-min; a pilot pass runs the whole span at --dt
    /// first, so give a --dt well above the step needed) and writes the error it
    /// estimates (exit 1 when over TOL). Experimental (issue 50): it meets TOL on the
    /// bar but costs more than the cheapest fixed step that does (`signorini study
    /// accuracy` measures both).
    #[arg(long, value_name = "TOL", allow_hyphen_values = true)]
    pub(crate) accuracy: Option<f64>,
    /// The accuracy mode's smallest step (s; default dt / 2^10).
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub(crate) dt_min: Option<f64>,
    /// θ of the θ-method, in [1/2, 1].
    #[arg(long, default_value_t = 0.5, allow_hyphen_values = true)]
    pub(crate) theta: f64,
    /// Time-stepping scheme.
    #[arg(long, value_enum, default_value = "combined-projection")]
    pub(crate) scheme: SchemeKind,
    /// Activation forecast for moreau-jean and direct-projection (eq. 61 / 62).
    #[arg(long, value_enum, default_value = "free")]
    pub(crate) forecast: ForecastArg,
    /// γ of the explicit forecast (eq. 61), in [0, 2].
    #[arg(long, default_value_t = 1.0, allow_hyphen_values = true)]
    pub(crate) gamma: f64,
    /// Restitution coefficient e at the tip, in [0, 1].
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub(crate) restitution: f64,
    /// Initial gap between the tip and the wall (m).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub(crate) gap: f64,
    /// Initial velocity of the bar (m/s; negative moves towards the wall).
    #[arg(long, default_value_t = -0.1, allow_hyphen_values = true)]
    pub(crate) velocity: f64,
    /// Length L (m).
    #[arg(long, default_value_t = 1.0, allow_hyphen_values = true)]
    pub(crate) length: f64,
    /// Cross-section S (m²); default π·10⁻⁴.
    #[arg(long, default_value_t = std::f64::consts::PI * 1e-4, allow_hyphen_values = true)]
    pub(crate) area: f64,
    /// Young's modulus E (Pa).
    #[arg(long, default_value_t = 210e9, allow_hyphen_values = true)]
    pub(crate) young: f64,
    /// Density ρ (kg/m³).
    #[arg(long, default_value_t = 7800.0, allow_hyphen_values = true)]
    pub(crate) density: f64,
    /// Mass matrix.
    #[arg(long, value_enum, default_value = "consistent")]
    pub(crate) mass: MassKind,
    /// Position projection metric for the projection schemes (eq. 58 / 60).
    #[arg(long, value_enum, default_value = "mass")]
    pub(crate) metric: Metric,
    /// Moreau–Jean: the forecast's active set alone (eq. 61/62), not closed on the
    /// step's solution.
    #[arg(long)]
    pub(crate) no_activation_closure: bool,
    /// Algorithm 2's position rule on the active set: persistent (g = 0 where P > 0 in
    /// this step and the last, the default), paper (where P > 0, eq. 68),
    /// complementarity (τ ≥ 0 only) or all-active (Siconos' code).
    #[arg(long, value_enum, default_value = "persistent")]
    pub(crate) projection_rule: ProjectionRule,
    /// Newton's law with e on contacts separating at the step's start too (eq. 18d as
    /// written), instead of max(e, (1 − θ)/θ), which keeps impulses from adding energy.
    #[arg(long)]
    pub(crate) newton_restitution: bool,
    /// Projection schemes: update only q with τ (Siconos' practice), not v through the
    /// −hθK N G τ term of eq. 56a.
    #[arg(long)]
    pub(crate) no_projection_feedback: bool,
    /// Stop projecting below this violation (m); 0 projects to machine accuracy.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub(crate) projection_tolerance: f64,
    /// One-step LCP solver: auto (Lemke up to 16 unknowns, block pivoting above), Lemke,
    /// block pivoting (both exact), or projected Gauss–Seidel.
    #[arg(long, value_enum, default_value = "auto")]
    pub(crate) lcp: LcpArg,
    /// PGS tolerance on the complementarity residual, relative to max(1, |q|).
    #[arg(long, default_value_t = 1e-12, allow_hyphen_values = true)]
    pub(crate) lcp_tol: f64,
    /// PGS sweep cap.
    #[arg(long, default_value_t = 10_000, allow_hyphen_values = true, value_parser = count)]
    pub(crate) lcp_max_sweeps: usize,
    /// Delassus storage: dense n×m blocks, per-active-column, or auto (dense up to 64
    /// contacts).
    #[arg(long, value_enum, default_value = "auto")]
    pub(crate) delassus: DelassusKind,
    /// Columns of the per-active-column pool (0: as many as fit in 2 GiB).
    #[arg(long, default_value_t = 0, allow_hyphen_values = true, value_parser = count)]
    pub(crate) delassus_pool: usize,
    /// Newton / fixed-point tolerance (relative).
    #[arg(long, default_value_t = 1e-10, allow_hyphen_values = true)]
    pub(crate) newton_tol: f64,
    /// Newton iteration cap per step.
    #[arg(long, default_value_t = 50, allow_hyphen_values = true, value_parser = positive)]
    pub(crate) newton_max_iterations: usize,
    /// Count iteration caps hit (Newton, projection, LCP) in the summary and go on,
    /// instead of failing the run (exit code 1) at the first one.
    #[arg(long)]
    pub(crate) allow_caps: bool,
    /// Largest energy growth beyond the work supplied, relative to the run's energy
    /// scale, before the run fails (exit code 1); `inf` accepts any.
    #[arg(long, default_value_t = signorini::integrators::DEFAULT_MAX_ENERGY_EXCESS)]
    pub(crate) max_energy_excess: f64,
    /// Output directory.
    #[arg(long, default_value = "out/bar")]
    pub(crate) out: PathBuf,
    /// Print nothing but errors.
    #[arg(long)]
    pub(crate) quiet: bool,
    #[command(flatten)]
    pub(crate) output: OutputArgs,
}

impl BarArgs {
    /// Checks every flag, also those the chosen options do not use (`--lcp-tol -1`
    /// without `--lcp pgs` is as wrong as with it).
    pub(crate) fn validate_flags(&self) -> Result<(), signorini::Error> {
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

    pub(crate) fn scene(&self) -> BarScene {
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
            accuracy: self.accuracy,
            dt_min: self.dt_min,
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
