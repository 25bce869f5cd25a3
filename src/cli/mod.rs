//! The command line's rooms (the binary only; the library knows nothing of them):
//! `args` (clap types and their conversions), `commands` (one function per subcommand,
//! calling the library's application layer) and `report` (the printed summary of a run).
//! `main.rs` keeps the top-level parser, the start of MPI for MUMPS, and `main`.

use super::*;

mod args;
mod commands;
mod report;

pub(crate) use {args::*, commands::*, report::*};
