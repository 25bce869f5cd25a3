//! A distributed factor of the iteration matrix `M̂` (eq. 47, 48) over the ranks of an MPI
//! job: MUMPS, the multifrontal direct solver, behind [`LinearSolver`] (cargo feature
//! `mumps`; DESIGN.md §10, "beyond one machine").
//!
//! `mpirun -np N signorini run SCENE --mumps` starts N copies of the program. Rank 0 (the
//! *host*) runs the whole driver: it assembles `M̂`, forms the Delassus operator, solves
//! the contact problems and writes every output, exactly as a run on one process. The
//! other ranks (`serve`, within [`start`]) hold no model: they wait for the host's commands and join
//! MUMPS' collective phases: analysis (ordering, symbolic factor), numeric factor and
//! solve, each spread over all N ranks (MUMPS' tree and node parallelism, ScaLAPACK on the
//! root front). The matrix is given centrally on the host (MUMPS' `ICNTL(18) = 0`), which
//! distributes it; right-hand sides and solutions are dense and centralized on the host
//! (`ICNTL(20) = ICNTL(21) = 0`), so the free-velocity solve of eq. 62 and the Delassus
//! columns `M̂⁻¹ G` (§4) take the same arrays as with the serial backends.
//!
//! Which factor MUMPS computes follows [`SolverKind`]: `SYM = 1` (`L D Lᵀ` without
//! pivoting, for the positive definite `M̂` of every linear scene), `SYM = 2` (symmetric
//! indefinite, with pivoting) for [`SolverKind::Ldlt`], `SYM = 0` (LU) for
//! [`SolverKind::Lu`]; a dense system ([`SolverKind::Dense`], a few rigid coordinates)
//! stays on the host. The symmetric kinds pass MUMPS the lower triangle only. The
//! ordering is MUMPS' automatic choice (`ICNTL(7) = 7`: METIS, SCOTCH, PORD or AMD, named
//! in [`LinearSolver::backend_name`] after the analysis). A factor that runs out of its
//! workspace estimate (`INFOG(1) = -8, -9, -14, -15, -17, -20`) is retried with twice the
//! relaxation `ICNTL(14)` up to [`WORKSPACE_RETRIES`] times; any other error is returned
//! with MUMPS' `INFOG(1)`, `INFOG(2)` and their meaning.
//!
//! Results are those of the serial backends to the factor's round-off, not bit for bit:
//! MUMPS' elimination order and the partition of its fronts depend on the rank count
//! (`tests/mpi_mumps.rs` holds them to a stated tolerance on 1, 2 and 4 ranks).
//!
//! Why bindings of our own: the crates on crates.io that wrap MUMPS either build their own
//! sequential MUMPS or pin one release's struct layout; the struct of the C interface
//! (`DMUMPS_STRUC_C`) is generated at build time from the installed `dmumps_c.h`
//! (`build.rs`, bindgen), so it matches the system library (Debian's 5.5.1 on Open MPI).
//! The command protocol to the other ranks is ours: one broadcast of three integers per
//! collective phase. In the step loop a solve costs that broadcast plus MUMPS' own
//! scatter of the right-hand side and gather of the solution; nothing is allocated.
//!
//! The one module of the crate with `unsafe` code (the crate denies it elsewhere): the
//! foreign call `dmumps_c` and the struct it fills. Every pointer handed to MUMPS points
//! into a buffer this module owns for as long as the factor lives.
#![allow(unsafe_code)]

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, AtomicI64, Ordering};

use faer::sparse::SparseColMatRef;
use mpi::topology::{Communicator, SimpleCommunicator};
use mpi::traits::Root;

use super::backend::{LinearSolver, SolverKind};
use crate::error::Error;

#[allow(
    non_camel_case_types,
    non_snake_case,
    non_upper_case_globals,
    dead_code,
    clippy::all
)]
mod ffi {
    include!(concat!(env!("OUT_DIR"), "/dmumps.rs"));
}

/// MUMPS' name for "the Fortran `MPI_COMM_WORLD`" in `comm_fortran`.
const USE_COMM_WORLD: i32 = -987_654;
/// Times a factor that ran out of its workspace estimate is retried, each with twice the
/// relaxation `ICNTL(14)` (percent over the analysis' estimate; MUMPS' default 20 for
/// symmetric positive definite, 35 otherwise in 5.5; our first value is MUMPS' own).
pub const WORKSPACE_RETRIES: usize = 3;

/// Whether [`start`] made this process the host of an MPI job: [`crate::linalg::solver::factor`]
/// then builds [`Mumps`] factors.
static ACTIVE: AtomicBool = AtomicBool::new(false);
/// The next factor's identity, shared with the other ranks in every command.
static NEXT_ID: AtomicI64 = AtomicI64::new(1);

/// Commands the host broadcasts to the other ranks: `[command, factor id, argument]`.
mod cmd {
    pub const QUIT: i64 = 0;
    /// Argument: MUMPS' `SYM`.
    pub const INIT: i64 = 1;
    pub const ANALYSE: i64 = 2;
    pub const FACTOR: i64 = 3;
    pub const SOLVE: i64 = 4;
    pub const END: i64 = 5;
}

/// MUMPS' `JOB` values.
mod job {
    pub const INIT: i32 = -1;
    pub const END: i32 = -2;
    pub const ANALYSE: i32 = 1;
    pub const FACTOR: i32 = 2;
    pub const SOLVE: i32 = 3;
}

/// Whether this process hosts a distributed factor ([`start`] on rank 0).
pub fn active() -> bool {
    ACTIVE.load(Ordering::Acquire)
}

/// What [`start`] made of this process.
pub enum Role {
    /// Rank 0: run the command; the guard tells the other ranks to stop and finalizes MPI
    /// when dropped (also while unwinding), after every factor has been dropped.
    Host(HostGuard),
    /// Another rank: it has served the host until the host's guard was dropped; it ends
    /// without output.
    Worker,
}

/// Keeps MPI initialized on the host; dropping it releases the other ranks ([`Role::Host`]).
pub struct HostGuard {
    universe: Option<mpi::environment::Universe>,
}

impl HostGuard {
    /// Ranks of the job (the host included).
    pub fn ranks(&self) -> usize {
        SimpleCommunicator::world().size() as usize
    }
}

impl Drop for HostGuard {
    fn drop(&mut self) {
        ACTIVE.store(false, Ordering::Release);
        broadcast([cmd::QUIT, 0, 0]);
        drop(self.universe.take());
    }
}

/// Initializes MPI. On rank 0, makes every later sparse factor of `M̂` a [`Mumps`] factor
/// and returns [`Role::Host`]; on the other ranks, serves the host's commands until it
/// quits and returns [`Role::Worker`] (module doc). `flag` names the option in errors.
pub fn start(flag: &str) -> Result<Role, Error> {
    let (universe, _) = mpi::initialize_with_threading(mpi::Threading::Serialized)
        .ok_or_else(|| Error::invalid(flag, "", "MPI was already initialized in this process"))?;
    if universe.world().rank() != 0 {
        serve();
        drop(universe);
        return Ok(Role::Worker);
    }
    ACTIVE.store(true, Ordering::Release);
    Ok(Role::Host(HostGuard {
        universe: Some(universe),
    }))
}

fn broadcast(mut msg: [i64; 3]) -> [i64; 3] {
    let world = SimpleCommunicator::world();
    world.process_at_rank(0).broadcast_into(&mut msg[..]);
    msg
}

/// The other ranks' side: join every collective phase the host asks for, until it quits.
fn serve() {
    let mut factors: BTreeMap<i64, Instance> = BTreeMap::new();
    loop {
        let [c, id, arg] = broadcast([0; 3]);
        match c {
            cmd::QUIT => return,
            cmd::INIT => {
                factors.insert(id, Instance::new(arg as i32));
            }
            cmd::ANALYSE | cmd::FACTOR | cmd::SOLVE => {
                if let Some(f) = factors.get_mut(&id) {
                    if c == cmd::FACTOR {
                        f.s.icntl[13] = arg as i32;
                    }
                    f.call(match c {
                        cmd::ANALYSE => job::ANALYSE,
                        cmd::FACTOR => job::FACTOR,
                        _ => job::SOLVE,
                    });
                }
            }
            cmd::END => {
                factors.remove(&id);
            }
            _ => {}
        }
    }
}

/// One MUMPS instance (`JOB = -1` at creation, `JOB = -2` when dropped: both collective).
struct Instance {
    s: Box<ffi::DMUMPS_STRUC_C>,
}

// The struct's pointers point into buffers the host's `Mumps` owns (or are null on the
// other ranks); MPI is initialized `Serialized`, and a factor is used by one thread at a
// time (`&mut self`).
unsafe impl Send for Instance {}

impl Instance {
    fn new(sym: i32) -> Self {
        // SAFETY: DMUMPS_STRUC_C is plain data (integers, floats, pointers, arrays):
        // all zeros is a valid value, and JOB = -1 initializes it.
        let mut s: Box<ffi::DMUMPS_STRUC_C> = Box::new(unsafe { std::mem::zeroed() });
        s.sym = sym;
        s.par = 1; // the host works too
        s.comm_fortran = USE_COMM_WORLD;
        let mut this = Instance { s };
        this.call(job::INIT);
        // ICNTL(k) is icntl[k - 1]: no messages (errors are returned as data)
        this.s.icntl[0] = -1;
        this.s.icntl[1] = -1;
        this.s.icntl[2] = -1;
        this.s.icntl[3] = 0;
        this.s.icntl[6] = 7; // automatic sequential ordering
        this.s.icntl[17] = 0; // matrix centralized on the host
        this.s.icntl[19] = 0; // dense right-hand sides
        this.s.icntl[20] = 0; // centralized solution
        this
    }

    fn call(&mut self, j: i32) {
        self.s.job = j;
        // SAFETY: the struct was initialized by JOB = -1 (or is being by it); every
        // pointer set in it points into a live buffer of the right length (Mumps).
        unsafe { ffi::dmumps_c(&mut *self.s) }
    }

    fn infog(&self, k: usize) -> i32 {
        self.s.infog[k - 1]
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        self.call(job::END);
    }
}

/// A factor of `M̂` computed and applied by MUMPS over every rank of the job (module doc).
/// Built on the host only, after [`start`].
pub struct Mumps {
    id: i64,
    inst: Instance,
    n: usize,
    kind: SolverKind,
    /// 1-based row and column of each entry given to MUMPS, and its value.
    irn: Vec<i32>,
    jcn: Vec<i32>,
    a: Vec<f64>,
    /// Index into the CSC values of each entry (the lower triangle for symmetric kinds).
    pick: Vec<usize>,
    ranks: usize,
    ordering: &'static str,
    /// MUMPS' memory for the last factor: the largest rank's and all ranks' (MB,
    /// `INFOG(21)`, `INFOG(22)`).
    memory_mb: (i32, i32),
    /// Entries of the last factor over all ranks (`INFOG(29)`; MUMPS gives millions as
    /// a negative value past `i32`): comparable with faer's `nnz(L)`.
    entries: i64,
    /// Relaxation of the workspace estimate for the next factor (`ICNTL(14)`).
    relax: i32,
    /// The first failed solve's message (solves return no error: their output is NaN).
    solve_error: Option<String>,
}

impl std::fmt::Debug for Mumps {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Mumps({}, n = {})", self.backend_name(), self.n)
    }
}

fn meaning(infog1: i32) -> &'static str {
    match infog1 {
        -5 | -7 | -13 => "MUMPS could not allocate its working memory",
        -6 => "the matrix is structurally singular",
        -8 | -9 | -14 | -15 | -17 | -20 => "the factor outgrew its workspace estimate",
        -10 => "the matrix is numerically singular (or not positive definite for SYM = 1)",
        -16 => "the order of the matrix is out of range",
        -19 => "the factor needs more memory than ICNTL(23) allows",
        _ => "see the MUMPS users' guide, section \"error diagnostics\"",
    }
}

impl Mumps {
    /// Analyses and factors `a` over the job's ranks; `what` names the matrix in errors.
    pub fn new(
        a: SparseColMatRef<'_, usize, f64>,
        what: &str,
        kind: SolverKind,
    ) -> Result<Self, Error> {
        if !active() {
            return Err(Error::Numerical(format!(
                "{what}: the MUMPS backend needs an MPI job started by `--mumps` (rank 0)"
            )));
        }
        let n = a.nrows();
        if n != a.ncols() {
            return Err(Error::Numerical(format!(
                "{what}: {} × {} is not square",
                n,
                a.ncols()
            )));
        }
        let too_big = |v: usize| i32::try_from(v).is_err();
        if too_big(n) || too_big(n + 1) {
            return Err(Error::Numerical(format!(
                "{what}: order {n} exceeds the 32-bit indices of this MUMPS build"
            )));
        }
        let sym = match kind {
            SolverKind::Cholesky => 1,
            SolverKind::Ldlt => 2,
            SolverKind::Lu | SolverKind::Dense => 0,
        };
        let symmetric = sym != 0;
        let (cp, ri) = (a.col_ptr(), a.row_idx());
        let mut pick = Vec::new();
        let (mut irn, mut jcn) = (Vec::new(), Vec::new());
        for j in 0..n {
            for (p, &i) in ri.iter().enumerate().take(cp[j + 1]).skip(cp[j]) {
                if !symmetric || i >= j {
                    pick.push(p);
                    irn.push(i as i32 + 1);
                    jcn.push(j as i32 + 1);
                }
            }
        }
        let id = NEXT_ID.fetch_add(1, Ordering::Relaxed);
        broadcast([cmd::INIT, id, sym as i64]);
        let inst = Instance::new(sym);
        let mut this = Mumps {
            id,
            inst,
            n,
            kind,
            a: vec![0.0; pick.len()],
            irn,
            jcn,
            pick,
            ranks: SimpleCommunicator::world().size() as usize,
            ordering: "",
            memory_mb: (0, 0),
            entries: 0,
            relax: 0,
            solve_error: None,
        };
        this.copy_values(a);
        let s = &mut this.inst.s;
        s.n = n as i32;
        s.nnz = this.a.len() as i64;
        s.nz = i32::try_from(this.a.len()).unwrap_or(0);
        s.irn = this.irn.as_mut_ptr();
        s.jcn = this.jcn.as_mut_ptr();
        s.a = this.a.as_mut_ptr();
        this.relax = s.icntl[13];
        broadcast([cmd::ANALYSE, id, 0]);
        this.inst.call(job::ANALYSE);
        this.check(what, "analysis")?;
        this.ordering = match this.inst.infog(7) {
            0 => "AMD",
            2 => "AMF",
            3 => "SCOTCH",
            4 => "PORD",
            5 => "METIS",
            6 => "QAMD",
            _ => "MUMPS' ordering",
        };
        this.factor(what)?;
        Ok(this)
    }

    fn copy_values(&mut self, a: SparseColMatRef<'_, usize, f64>) {
        let v = a.val();
        for (dst, &p) in self.a.iter_mut().zip(&self.pick) {
            *dst = v[p];
        }
    }

    fn check(&self, what: &str, phase: &str) -> Result<(), Error> {
        let (i1, i2) = (self.inst.infog(1), self.inst.infog(2));
        if i1 < 0 {
            return Err(Error::Numerical(format!(
                "{what}: MUMPS {phase} failed on {} rank(s): INFOG(1) = {i1}, INFOG(2) = {i2} ({})",
                self.ranks,
                meaning(i1)
            )));
        }
        Ok(())
    }

    fn factor(&mut self, what: &str) -> Result<(), Error> {
        let mut retries = 0;
        loop {
            self.inst.s.icntl[13] = self.relax;
            broadcast([cmd::FACTOR, self.id, self.relax as i64]);
            self.inst.call(job::FACTOR);
            let i1 = self.inst.infog(1);
            if matches!(i1, -8 | -9 | -14 | -15 | -17 | -20) && retries < WORKSPACE_RETRIES {
                retries += 1;
                self.relax = (self.relax.max(10)).saturating_mul(2);
                continue;
            }
            self.memory_mb = (self.inst.infog(21), self.inst.infog(22));
            let e = self.inst.infog(29);
            self.entries = if e < 0 {
                -(e as i64) * 1_000_000
            } else {
                e as i64
            };
            return self.check(what, "factor");
        }
    }

    /// Ranks the factor is spread over.
    pub fn ranks(&self) -> usize {
        self.ranks
    }

    /// MUMPS' memory for the last factor in MB: on the largest rank and on all ranks
    /// together (`INFOG(21)`, `INFOG(22)`): what spreading the factor buys.
    pub fn memory_mb(&self) -> (i32, i32) {
        self.memory_mb
    }

    /// The first solve that failed since the factor, if any (its output was NaN).
    pub fn solve_error(&self) -> Option<&str> {
        self.solve_error.as_deref()
    }

    /// Solves the `k` columns of `x` in one collective solve phase; `one_by_one` sets
    /// MUMPS' right-hand-side blocking `ICNTL(27)` to 1, so that each column goes
    /// through the single-column arithmetic and its result does not depend on the
    /// others' (the contract of [`LinearSolver::solve_columns_independently`]).
    fn solve(&mut self, x: &mut [f64], k: usize, one_by_one: bool) {
        let n = self.n;
        // MUMPS reads and writes n·k values: never more than `x` holds
        let k = k.min(x.len() / n.max(1));
        if n == 0 || k == 0 {
            return;
        }
        let s = &mut self.inst.s;
        s.rhs = x.as_mut_ptr();
        s.nrhs = k as i32;
        s.lrhs = n as i32;
        let blocking = s.icntl[26];
        if one_by_one {
            s.icntl[26] = 1;
        }
        broadcast([cmd::SOLVE, self.id, 0]);
        self.inst.call(job::SOLVE);
        self.inst.s.rhs = std::ptr::null_mut();
        self.inst.s.icntl[26] = blocking;
        if self.inst.infog(1) < 0 {
            if self.solve_error.is_none() {
                self.solve_error = self.check("M̂", "solve").err().map(|e| e.to_string());
            }
            x[..n * k].fill(f64::NAN);
        }
    }
}

impl LinearSolver for Mumps {
    fn dim(&self) -> usize {
        self.n
    }
    fn backend_name(&self) -> String {
        let what = match self.kind {
            SolverKind::Cholesky => "L D Lᵀ, positive definite",
            SolverKind::Ldlt => "symmetric indefinite",
            _ => "LU",
        };
        // version_number is a NUL-terminated C string set by JOB = -1
        let v: String = self
            .inst
            .s
            .version_number
            .iter()
            .take_while(|&&c| c != 0)
            .map(|&c| c as u8 as char)
            .collect();
        format!(
            "MUMPS {} ({what}, {} ordering, {} factor entries) over {} MPI rank(s), factor \
             {} MB on the largest rank, {} MB in all",
            v.trim(),
            self.ordering,
            self.entries,
            self.ranks,
            self.memory_mb.0,
            self.memory_mb.1
        )
    }
    fn refactor(&mut self, a: SparseColMatRef<'_, usize, f64>, what: &str) -> Result<(), Error> {
        if a.nrows() != self.n
            || a.ncols() != self.n
            || a.val().len() < self.pick.last().map_or(0, |p| p + 1)
        {
            return Err(Error::Numerical(format!(
                "{what}: refactor on a pattern other than the analysed one ({} × {})",
                a.nrows(),
                a.ncols()
            )));
        }
        self.copy_values(a);
        self.solve_error = None;
        self.factor(what)
    }
    fn solve_in_place(&mut self, x: &mut [f64]) {
        self.solve(x, 1, true);
    }
    fn solve_columns_independently(&mut self, x: &mut [f64], k: usize) {
        self.solve(x, k, true);
    }
    fn solve_block_in_place(&mut self, x: &mut [f64], k: usize) {
        self.solve(x, k, false);
    }
}

impl Drop for Mumps {
    fn drop(&mut self) {
        // the others drop their instance on END; ours drops (JOB = -2) after this
        broadcast([cmd::END, self.id, 0]);
    }
}

/// Builds a [`Mumps`] factor when this process hosts an MPI job ([`start`]) and `kind` is
/// sparse; `None` otherwise (the serial backends then factor).
pub(crate) fn factor_if_active(
    a: SparseColMatRef<'_, usize, f64>,
    what: &str,
    kind: SolverKind,
) -> Option<Result<Box<dyn LinearSolver>, Error>> {
    (active() && kind != SolverKind::Dense)
        .then(|| Mumps::new(a, what, kind).map(|m| Box::new(m) as Box<dyn LinearSolver>))
}
