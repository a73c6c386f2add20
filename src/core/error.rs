//! One error type for the whole pipeline.
//!
//! Every variant names what the user has to fix: the file and line, the parameter, or the solver
//! that failed to converge (with its iteration count and residual). The CLI prints the message and
//! exits non-zero; no stage writes partial output when it returns an error (see [`crate::core::output`]).

use std::path::PathBuf;

/// Errors raised by any stage of `asperity`.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The operating system refused to read or write a file.
    #[error("{path}: {source}")]
    Io {
        /// The file that could not be read or written.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// A file was read but its content is malformed. `line` is 1-based; 0 means "whole file".
    #[error("{path}{}: {message}", if *.line > 0 { format!(":{}", .line) } else { String::new() })]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line of the problem; 0 for the whole file.
        line: usize,
        /// What is wrong and, where it helps, what was expected.
        message: String,
    },
    /// A parameter (CLI flag, config key, function argument) has an impossible value.
    #[error("invalid parameter `{name}`: {message}")]
    InvalidParameter {
        /// The parameter as the user names it (flag, config key or argument).
        name: String,
        /// Why the value is impossible, with the range expected.
        message: String,
    },
    /// An iterative solver hit its iteration cap before meeting its tolerance.
    #[error("{solver} did not converge: {iterations} iterations, residual {residual:.3e} > tolerance {tolerance:.3e}")]
    NonConvergence {
        /// The solver and its problem (e.g. "normal contact, displacement control (secant)").
        solver: String,
        /// Iterations run.
        iterations: usize,
        /// Residual at the last iteration, in the solver's own (usually relative) measure.
        residual: f64,
        /// Tolerance the residual had to meet, same measure.
        tolerance: f64,
    },
    /// Input data that is well formed but cannot be used (no contact, no complete cycle, ...).
    #[error("{0}")]
    Data(String),
    /// A request that would exceed a documented resource limit (grid size, memory, file size,
    /// number of steps), refused before any allocation (see [`crate::core::limits`]).
    #[error("resource limit `{name}`: {message}")]
    Limit {
        /// The limited quantity or the flag that sets it (e.g. "--grid").
        name: String,
        /// The request, the limit and how to stay within it.
        message: String,
    },
}

/// Result alias used across the crate.
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// Shorthand for [`Error::InvalidParameter`].
    pub fn param(name: impl Into<String>, message: impl Into<String>) -> Self {
        Error::InvalidParameter {
            name: name.into(),
            message: message.into(),
        }
    }

    /// The same error naming parameter `name` instead (the flag of a command, the keyword of a
    /// binding), when it is an [`Error::InvalidParameter`]; any other error unchanged.
    pub fn renamed_param(self, name: &str) -> Self {
        match self {
            Error::InvalidParameter { message, .. } => Error::param(name, message),
            other => other,
        }
    }

    /// Shorthand for [`Error::Parse`].
    pub fn parse(path: impl Into<PathBuf>, line: usize, message: impl Into<String>) -> Self {
        Error::Parse {
            path: path.into(),
            line,
            message: message.into(),
        }
    }

    /// Shorthand for [`Error::Limit`].
    pub fn limit(name: impl Into<String>, message: impl Into<String>) -> Self {
        Error::Limit {
            name: name.into(),
            message: message.into(),
        }
    }

    /// Attach the file an error came from: a [`Error::Data`] message gets the file's name in
    /// front (as `file: message`), an [`Error::InvalidParameter`] raised on the file's content
    /// becomes a [`Error::Parse`] of the file. Errors that already name a file, a flag or a
    /// limit are returned unchanged.
    pub fn in_file(self, path: &std::path::Path) -> Self {
        match self {
            Error::Data(m) => Error::parse(path, 0, m),
            Error::InvalidParameter { name, message } if !name.starts_with('-') => {
                Error::parse(path, 0, format!("{name}: {message}"))
            }
            other => other,
        }
    }

    /// Shorthand for [`Error::Io`].
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}

/// A number for a message: Rust's shortest round-trip form for ordinary magnitudes, scientific
/// notation outside `[1e-4, 1e6)` (so that `1e300` is not printed as 301 digits), `NaN`, `inf`.
pub fn num(value: f64) -> String {
    let a = value.abs();
    if !value.is_finite() || value == 0.0 || (1e-4..1e6).contains(&a) {
        format!("{value}")
    } else {
        format!("{value:e}")
    }
}

/// Check that a parameter is finite and strictly positive.
pub fn require_positive(name: &str, value: f64) -> Result<f64> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(Error::param(
            name,
            format!("must be finite and > 0, got {}", num(value)),
        ))
    }
}

/// Check that a parameter is finite.
pub fn require_finite(name: &str, value: f64) -> Result<f64> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(Error::param(
            name,
            format!("must be finite, got {}", num(value)),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_in_messages_stay_short() {
        assert_eq!(num(1e300), "1e300");
        assert_eq!(num(-2.5e-300), "-2.5e-300");
        assert_eq!(num(0.6), "0.6");
        assert_eq!(num(210e9), "2.1e11");
        assert_eq!(num(f64::NAN), "NaN");
        let e = require_positive("--x", -1e300).unwrap_err().to_string();
        assert!(e.len() < 60, "{e}");
    }
}
