//! The crate-wide error type: every failure names what is wrong (file, line, variable,
//! allowed range) so that a user can act on it.

use std::path::PathBuf;

/// Errors reported by the library. Each variant carries enough context to name the culprit.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A parameter or input is outside its allowed range or not finite.
    #[error("invalid value {value} for `{name}`: allowed range is {range}")]
    InvalidParameter {
        /// Parameter name as the user knows it (FMI name where there is one).
        name: String,
        /// The rejected value, formatted.
        value: String,
        /// Human-readable allowed range, e.g. `[0, 1]`.
        range: String,
    },
    /// The integrator failed; the model stays at its last good time.
    #[error("numerical failure at t = {time} s: {reason}")]
    Numerical {
        /// Last successful time [s].
        time: f64,
        /// What went wrong.
        reason: String,
    },
    /// A step ended in a state outside the physiological bounds
    /// ([`crate::model::bounds::cavity_bounds`]); the model went back to where the step
    /// started (`time`), as after a rollback.
    #[error("at t = {at} s: {reason}; the model stays at t = {time} s")]
    Unphysiological {
        /// Where the model stays: the start of the step [s].
        time: f64,
        /// The end of the step, where the state left the bounds [s].
        at: f64,
        /// Which volume left its bounds, by how much.
        reason: String,
        /// Whether the solver's stiffness test had fired by the end of the step (the
        /// rollback resets it with the rest of the solver's memory).
        stiffness_detected: bool,
    },
    /// A file could not be parsed; names the file, line and column (1-based).
    #[error("{path}:{line}:{column}: {message}")]
    Parse {
        /// File name.
        path: String,
        /// 1-based line, 0 when not applicable.
        line: usize,
        /// 1-based column, 0 when not applicable.
        column: usize,
        /// What is wrong there.
        message: String,
    },
    /// An I/O error on a named file.
    #[error("{path}: {source}")]
    Io {
        /// The file involved.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// A request the current state cannot honour (e.g. a snapshot of another model).
    #[error("{0}")]
    State(String),
}

/// Result alias used throughout the crate.
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// Shorthand for [`Error::InvalidParameter`].
    pub fn invalid(
        name: impl Into<String>,
        value: impl std::fmt::Display,
        range: impl Into<String>,
    ) -> Self {
        Error::InvalidParameter {
            name: name.into(),
            value: value.to_string(),
            range: range.into(),
        }
    }

    /// Shorthand for [`Error::Parse`]: what is wrong (`message`) at `line` and `column`
    /// (1-based, 0 when not applicable) of the file `path` (its name as the user gave it,
    /// or anything that displays as one, such as `Path::display`).
    pub fn parse(
        path: impl std::fmt::Display,
        line: usize,
        column: usize,
        message: impl Into<String>,
    ) -> Self {
        Error::Parse {
            path: path.to_string(),
            line,
            column,
            message: message.into(),
        }
    }

    /// Shorthand for an I/O error on `path`.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}

/// The message of a caught panic's payload (`&str` or `String`; "panic" for anything else),
/// for the C layers that turn a panic into an error code and a log line.
pub(crate) fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "panic".to_string())
}
