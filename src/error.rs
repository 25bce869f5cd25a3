//! The crate's error type: every failure names what was wrong (file, field, value).

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
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
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

    /// Wraps an I/O error with the path it concerns.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}

/// Checks that `value` is finite and strictly positive.
pub fn require_positive(field: &str, value: f64) -> Result<f64, Error> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(Error::invalid(field, value, "must be a finite number > 0"))
    }
}

/// Checks that `value` is finite and in `[lo, hi]`.
pub fn require_in(field: &str, value: f64, lo: f64, hi: f64) -> Result<f64, Error> {
    if value.is_finite() && value >= lo && value <= hi {
        Ok(value)
    } else {
        Err(Error::invalid(
            field,
            value,
            &format!("must be a finite number in [{lo}, {hi}]"),
        ))
    }
}

/// Checks that `value` is finite (any sign).
pub fn require_finite(field: &str, value: f64) -> Result<f64, Error> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(Error::invalid(field, value, "must be a finite number"))
    }
}
