//! One error type for the whole core. Every message is meant to be shown to a
//! person as is: it names the problem and, where there is one, the place
//! (file, pixel size, line and column, limit).
use std::fmt;

/// Result alias used throughout the crate.
pub type Result<T> = std::result::Result<T, Error>;

/// Everything that can go wrong in the core, with a message a person can act on.
#[derive(Debug, Clone, PartialEq)]
pub enum Error {
    /// The input bytes or values are not acceptable; the message says why.
    InvalidInput(String),
    /// An explicit limit was exceeded (image size, shape count, operations ...).
    Limit(String),
    /// A text input (script, grammar, JSON) failed to parse at a place.
    Syntax {
        line: usize,
        column: usize,
        message: String,
    },
    /// The job was cancelled through its cancel flag.
    Cancelled,
}

impl Error {
    /// Shorthand for [`Error::InvalidInput`].
    pub fn input(msg: impl Into<String>) -> Self {
        Error::InvalidInput(msg.into())
    }
    /// Shorthand for [`Error::Limit`].
    pub fn limit(msg: impl Into<String>) -> Self {
        Error::Limit(msg.into())
    }
    /// A short machine-readable category, used by the worker protocol.
    pub fn kind(&self) -> &'static str {
        match self {
            Error::InvalidInput(_) => "invalid-input",
            Error::Limit(_) => "limit",
            Error::Syntax { .. } => "syntax",
            Error::Cancelled => "cancelled",
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::InvalidInput(m) | Error::Limit(m) => f.write_str(m),
            Error::Syntax {
                line,
                column,
                message,
            } => {
                write!(f, "line {line}, column {column}: {message}")
            }
            Error::Cancelled => f.write_str("cancelled"),
        }
    }
}

impl std::error::Error for Error {}
