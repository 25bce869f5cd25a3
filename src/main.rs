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

mod cli;
use cli::*;

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
        /// `accuracy` only: an accuracy to ask (repeatable; default 1e-1, 1e-2, 1e-3).
        #[arg(long = "tol", allow_hyphen_values = true)]
        tols: Vec<f64>,
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
    // no flush of subnormals while the inputs are read and validated (issue 48: under
    // the flush, `time.t_end = 5e-320` compared as 0 and was refused with a false
    // reason): the runs set the run's mode themselves (`app::run_scene` and friends),
    // the studies and the FCLIB solve once their inputs are checked
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
            tols,
        }) => {
            let dir = out.unwrap_or_else(|| match &scene {
                Some(p) => PathBuf::from(format!(
                    "out/study-{name}-{}",
                    p.file_stem()
                        .map_or("scene".into(), |s| s.to_string_lossy())
                )),
                None => PathBuf::from(format!("out/study-{name}")),
            });
            let _flush = signorini::linalg::FlushGuard::for_run();
            let result = match &scene {
                Some(p) => signorini::study::run_on_scene(&name, p, &set, &schemes, &tols, &dir),
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
            .and_then(|r| {
                if !quiet {
                    print_summary(&r.summary, &dir);
                }
                accuracy_met(&r.summary)
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
