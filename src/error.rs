//! The crate's error type: every failure names what was wrong (file, field or line,
//! value, expectation), and says which exit code it maps to (DESIGN.md §9):
//! 2 for bad input ([`Error::InvalidParameter`], [`Error::BadFile`], [`Error::Io`] on
//! reading), 1 for a run that fails ([`Error::RunFailed`], [`Error::NotConverged`],
//! [`Error::Numerical`], [`Error::Write`]).

use std::path::PathBuf;

/// Errors returned by model building, solving and output.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A parameter is out of its valid range (negative, NaN, unknown name, ...).
    #[error("invalid value for `{field}`: {value} ({reason})")]
    InvalidParameter {
        /// Name of the parameter as the user wrote it (CLI flag or scene key).
        field: String,
        /// The offending value, printed.
        value: String,
        /// What is expected instead.
        reason: String,
    },
    /// A factorization or linear solve failed.
    #[error("numerical failure: {0}")]
    Numerical(String),
    /// A one-step nonsmooth solver or the Newton loop did not converge.
    #[error("{solver} did not converge at step {step} (t = {time:e} s): {detail}")]
    NotConverged {
        /// Which solver.
        solver: String,
        /// Step index.
        step: usize,
        /// Time at the start of the step.
        time: f64,
        /// Residual, iteration count, cap.
        detail: String,
    },
    /// A malformed input file (mesh, scene, FCLIB problem, checkpoint, history): the
    /// file, where in it (`line 12`, `byte 4096`, a key path), and what is wrong.
    #[error("{}{}: {detail}", file.display(), if where_.is_empty() { String::new() } else { format!(":{where_}") })]
    BadFile {
        /// The file.
        file: PathBuf,
        /// Where in it: `line L`, `line L, column C`, `byte B`, a key path; may be empty.
        where_: String,
        /// What is wrong and what was expected.
        detail: String,
    },
    /// A run stopped because its state can no longer be trusted (a non-finite value, a
    /// violation that exploded, an iteration cap hit that the scene does not allow).
    #[error("run failed at step {step} (t = {time:e} s){}: {detail}", contact.map(|c| format!(", contact {c}")).unwrap_or_default())]
    RunFailed {
        /// Step being taken (1-based: the state after it is the bad one).
        step: usize,
        /// Time at the end of that step (s).
        time: f64,
        /// The contact concerned, when one is.
        contact: Option<usize>,
        /// What went wrong, with the value and the limit.
        detail: String,
    },
    /// The caller asked the run to stop ([`crate::run::Progress::cancelled`]: Ctrl-C in
    /// the Python package): the history and the frames written so far are finished and
    /// readable; no summary is written (exit 1: the run did not complete).
    #[error(
        "run interrupted after step {step} (t = {time:e} s): the outputs hold the steps up to it"
    )]
    Interrupted {
        /// The last completed step.
        step: usize,
        /// Its time (s).
        time: f64,
    },
    /// A run in the accuracy mode (`time.accuracy`) could not reach the accuracy asked:
    /// windows at the smallest step still missed it, or the estimated errors summed over
    /// the run exceed it. Its outputs and summary are written (exit 1).
    #[error("the run did not reach time.accuracy = {target:e}: {detail}")]
    AccuracyNotMet {
        /// The requested accuracy.
        target: f64,
        /// What was missed, with the estimates and the remedy.
        detail: String,
    },
    /// Writing an output file failed (disk full, permissions): the run fails (exit 1).
    #[error("cannot write {path}: {}", os_reason(source))]
    Write {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// Reading an input file failed (missing, unreadable).
    #[error("cannot read {path}: {}", os_reason(source))]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
}

impl Error {
    /// Shorthand for [`Error::InvalidParameter`].
    pub fn invalid(field: &str, value: impl std::fmt::Display, reason: &str) -> Self {
        Error::InvalidParameter {
            field: field.to_string(),
            value: value.to_string(),
            reason: reason.to_string(),
        }
    }

    /// Shorthand for [`Error::BadFile`].
    pub fn bad_file(
        file: impl Into<PathBuf>,
        where_: impl std::fmt::Display,
        detail: impl std::fmt::Display,
    ) -> Self {
        Error::BadFile {
            file: file.into(),
            where_: where_.to_string(),
            detail: detail.to_string(),
        }
    }

    /// Wraps an output error with the path it concerns (exit code 1).
    pub fn write(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Write {
            path: path.into(),
            source,
        }
    }

    /// The process exit code this error maps to: 2 for bad input, 1 for a run that
    /// failed (DESIGN.md §9).
    pub fn exit_code(&self) -> u8 {
        match self {
            Error::InvalidParameter { .. } | Error::BadFile { .. } | Error::Io { .. } => 2,
            Error::Numerical(_)
            | Error::NotConverged { .. }
            | Error::RunFailed { .. }
            | Error::Interrupted { .. }
            | Error::AccuracyNotMet { .. }
            | Error::Write { .. } => 1,
        }
    }

    /// Prefixes the field or location of an input error with `context` (a scene file's
    /// path, a key path such as `bodies[2].`): errors raised while building a model then
    /// name the scene file that asked for it.
    pub fn in_file(self, file: &std::path::Path) -> Self {
        match self {
            Error::InvalidParameter {
                field,
                value,
                reason,
            } => Error::BadFile {
                file: file.to_path_buf(),
                where_: if field.starts_with("line ") {
                    field
                } else {
                    format!("`{field}`")
                },
                detail: if value.starts_with('(') || value.is_empty() {
                    reason
                } else {
                    format!("value {value}: {reason}")
                },
            },
            Error::BadFile {
                file: f,
                where_,
                detail,
            } if f != file => Error::BadFile {
                file: f,
                where_,
                detail: format!("{detail} (read for {})", file.display()),
            },
            Error::Io { path, source } if path != file => Error::BadFile {
                file: path,
                where_: String::new(),
                detail: format!(
                    "cannot read it: {} (read for {})",
                    os_reason(&source),
                    file.display()
                ),
            },
            other => other,
        }
    }

    /// Appends where an input error arose (`sweep point 3 (dt=1e-6)`) to its
    /// explanation; other errors pass unchanged.
    pub fn context(self, what: &str) -> Self {
        match self {
            Error::InvalidParameter {
                field,
                value,
                reason,
            } => Error::InvalidParameter {
                field,
                value,
                reason: format!("{reason} (in {what})"),
            },
            Error::BadFile {
                file,
                where_,
                detail,
            } => Error::BadFile {
                file,
                where_,
                detail: format!("{detail} (in {what})"),
            },
            other => other,
        }
    }

    /// Wraps an I/O error with the path it concerns (reading an input: exit code 2).
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}

/// An operating-system error in words, without the bare `(os error N)` code: what a
/// user can act on (`No such file or directory (os error 2)` reads "no such file or
/// directory").
pub fn os_reason(e: &std::io::Error) -> String {
    use std::io::ErrorKind as K;
    match e.kind() {
        K::NotFound => "no such file or directory".into(),
        K::PermissionDenied => {
            "permission denied (check the file's and its directory's rights)".into()
        }
        K::AlreadyExists => "it already exists (remove it or choose another path)".into(),
        K::StorageFull => "the disk is full".into(),
        K::ReadOnlyFilesystem => "the file system is read-only".into(),
        K::IsADirectory => "it is a directory, not a file".into(),
        K::NotADirectory => "a component of the path is not a directory".into(),
        _ => {
            let text = e.to_string();
            match text.find(" (os error") {
                Some(i) => text[..i].to_string(),
                None => text,
            }
        }
    }
}

/// Most characters of an input quoted in a message ([`excerpt`]).
pub const EXCERPT_CHARS: usize = 80;

/// A piece of the user's input as a message quotes it: its first line, at most
/// [`EXCERPT_CHARS`] characters as printed, control characters escaped (`\0`, `\u{1b}`), and
/// `… (N bytes)` when it was cut, so a file of NUL bytes or one endless token is
/// echoed as one short line, never whole.
pub fn excerpt(s: &str) -> String {
    let line = s.lines().next().unwrap_or("");
    let mut out = String::new();
    let mut shown = 0;
    let mut cut = line.len() < s.trim_end_matches(['\n', '\r']).len();
    for c in line.chars() {
        let piece: String = if c.is_control() {
            c.escape_default().collect()
        } else {
            c.to_string()
        };
        shown += piece.chars().count();
        if shown > EXCERPT_CHARS {
            cut = true;
            break;
        }
        out.push_str(&piece);
    }
    if cut {
        out.push_str(&format!("… ({} bytes)", s.len()));
    }
    out
}

/// A number as a person reads it: plain for moderate magnitudes, `1e-300` rather than
/// 300 zeros, `inf` for the unbounded end of a range (`f64::MAX` and above).
pub fn num(x: f64) -> String {
    if x.is_nan() {
        "NaN".into()
    } else if x.is_infinite() || x.abs() >= f64::MAX / 2.0 || x.abs() >= 1e300 {
        if x > 0.0 { "inf".into() } else { "-inf".into() }
    } else if (x.to_bits() << 1) == 0 || (1e-4..1e7).contains(&x.abs()) {
        // zero by its bits: under a flush of subnormal operands (DAZ), 5e-320 == 0.0
        // holds, and `{x}` then printed 320 digits
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// A closed range `[lo, hi]`, or `[lo, inf)` when `hi` is unbounded.
pub fn range(lo: f64, hi: f64) -> String {
    if num(hi) == "inf" {
        format!("[{}, inf)", num(lo))
    } else {
        format!("[{}, {}]", num(lo), num(hi))
    }
}

/// Checks that `value` is finite and strictly positive.
pub fn require_positive(field: &str, value: f64) -> Result<f64, Error> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(Error::invalid(
            field,
            num(value),
            "must be a finite number > 0",
        ))
    }
}

/// Checks that `value` is finite and in `[lo, hi]` (`hi` may be `f64::MAX` for "no upper
/// bound", printed `inf`).
pub fn require_in(field: &str, value: f64, lo: f64, hi: f64) -> Result<f64, Error> {
    if value.is_finite() && value >= lo && value <= hi {
        Ok(value)
    } else {
        Err(Error::invalid(
            field,
            num(value),
            &format!("must be a finite number in {}", range(lo, hi)),
        ))
    }
}

/// Checks that `value` is finite (any sign).
pub fn require_finite(field: &str, value: f64) -> Result<f64, Error> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(Error::invalid(field, num(value), "must be a finite number"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_and_ranges_print_short() {
        assert_eq!(num(1e-300), "1e-300");
        assert_eq!(num(0.5), "0.5");
        assert_eq!(num(f64::MAX), "inf");
        assert_eq!(range(0.0, 1e300), "[0, inf)");
        assert_eq!(range(0.5, 1.0), "[0.5, 1]");
        let e = require_in("gap", -1.0, 0.0, f64::MAX)
            .unwrap_err()
            .to_string();
        assert!(e.contains("[0, inf)") && e.len() < 120, "{e}");
    }
}
