//! One error type for the whole core. Every message is meant to be shown to a
//! person as is: it names the problem and, where there is one, the place
//! (file, pixel size, line and column, limit, request field).
//!
//! Errors cross the wasm boundary as [`ErrorInfo`], a plain object
//! `{kind, message, line?, column?, field?}`: `line` and `column`
//! whenever the error has a place, so a page never reads them from the text (see `www/app/protocol.js`).
use serde::Serialize;
use std::fmt;

/// Result alias used throughout the crate.
pub type Result<T> = std::result::Result<T, Error>;

/// Everything that can go wrong in the core, with a message a person can act on.
#[derive(Debug, Clone, PartialEq)]
pub enum Error {
    /// The input bytes or values are not acceptable; the message says why.
    InvalidInput(String),
    /// The request itself could not be read into its type (a missing or
    /// mistyped field, an unknown option): the caller's fault, not the
    /// user's input. Built by `api::request`.
    BadRequest(String),
    /// An explicit limit was exceeded (image size, shape count, operations ...).
    Limit(String),
    /// The input is valid, but this way of computing it cannot take it
    /// (e.g. a number beyond the GPU's 32-bit floats); another way (the
    /// CPU) can, and the message says which.
    Unsupported(String),
    /// A text input (script, grammar, JSON) failed to parse at a place.
    Syntax {
        line: usize,
        column: usize,
        message: String,
    },
    /// `error` (a limit or a rule, not a parse failure) was met at a place
    /// in a text input: a program's statement, a grammar's rule. Its kind
    /// stays `error`'s; the place travels as `line` and `column` beside
    /// the message, as a syntax error's does. Built with [`Error::placed`].
    Placed {
        line: usize,
        column: usize,
        error: Box<Error>,
    },
    /// The job was cancelled through its cancel flag.
    Cancelled,
    /// `error` is about one field of a request: `field` is its dotted path
    /// (e.g. `tolerance`, `params.d_max`, `program`). Built with [`Error::at`].
    Field { field: String, error: Box<Error> },
}

/// An [`Error`] as plain data: what the worker posts and the page's
/// `JobError` carries. `message` is the whole human-readable text (for a
/// syntax error it includes "line L, column C").
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ErrorInfo {
    pub kind: &'static str,
    pub message: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub line: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub column: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub field: Option<String>,
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
    /// This error is about request field `field` (a dotted path). An error
    /// already tied to a field keeps the innermost (most precise) one.
    pub fn at(self, field: impl Into<String>) -> Self {
        match self {
            Error::Field { .. } | Error::Cancelled => self,
            e => Error::Field {
                field: field.into(),
                error: Box::new(e),
            },
        }
    }
    /// This error was met at `line`, `column` (1-based) of a text input.
    /// A syntax error keeps its own place.
    pub fn placed(self, line: usize, column: usize) -> Self {
        match self {
            Error::Syntax { .. } | Error::Placed { .. } | Error::Cancelled => self,
            Error::Field { field, error } => Error::Field {
                field,
                error: Box::new(error.placed(line, column)),
            },
            e => Error::Placed {
                line,
                column,
                error: Box::new(e),
            },
        }
    }
    /// The error without its field and place, if any.
    pub fn inner(&self) -> &Error {
        match self {
            Error::Field { error, .. } | Error::Placed { error, .. } => error.inner(),
            e => e,
        }
    }
    /// A short machine-readable category, used by the worker protocol:
    /// `invalid-input`, `bad-request`, `limit`, `unsupported`, `syntax` or
    /// `cancelled`.
    pub fn kind(&self) -> &'static str {
        match self.inner() {
            Error::InvalidInput(_) => "invalid-input",
            Error::BadRequest(_) => "bad-request",
            Error::Limit(_) => "limit",
            Error::Unsupported(_) => "unsupported",
            Error::Syntax { .. } => "syntax",
            Error::Cancelled => "cancelled",
            Error::Field { .. } | Error::Placed { .. } => {
                unreachable!("inner() unwraps fields and places")
            }
        }
    }
    /// The dotted request field at fault, if known.
    pub fn field(&self) -> Option<&str> {
        match self {
            Error::Field { field, .. } => Some(field),
            _ => None,
        }
    }
    /// Line and column (1-based) of a syntax error or a placed one.
    pub fn position(&self) -> Option<(usize, usize)> {
        match self {
            Error::Syntax { line, column, .. } | Error::Placed { line, column, .. } => {
                Some((*line, *column))
            }
            Error::Field { error, .. } => error.position(),
            _ => None,
        }
    }
    /// The error as plain data for the worker protocol.
    pub fn info(&self) -> ErrorInfo {
        let pos = self.position();
        ErrorInfo {
            kind: self.kind(),
            message: self.to_string(),
            line: pos.map(|p| p.0),
            column: pos.map(|p| p.1),
            field: self.field().map(str::to_string),
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::InvalidInput(m)
            | Error::BadRequest(m)
            | Error::Limit(m)
            | Error::Unsupported(m) => f.write_str(m),
            Error::Syntax {
                line,
                column,
                message,
            } => {
                write!(f, "line {line}, column {column}: {message}")
            }
            Error::Placed {
                line,
                column,
                error,
            } => write!(f, "line {line}, column {column}: {error}"),
            Error::Cancelled => f.write_str("cancelled"),
            Error::Field { error, .. } => error.fmt(f),
        }
    }
}

impl std::error::Error for Error {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_field_keeps_kind_position_and_message() {
        let e = Error::Syntax {
            line: 3,
            column: 7,
            message: "expected ')'".into(),
        }
        .at("program")
        .at("outer");
        assert_eq!(
            e.info(),
            ErrorInfo {
                kind: "syntax",
                message: "line 3, column 7: expected ')'".into(),
                line: Some(3),
                column: Some(7),
                field: Some("program".into()),
            }
        );
        // A limit met at a place keeps its kind, and its place is data.
        let p = Error::limit("more than 9 shapes")
            .placed(4, 2)
            .at("program");
        assert_eq!(
            p.info(),
            ErrorInfo {
                kind: "limit",
                message: "line 4, column 2: more than 9 shapes".into(),
                line: Some(4),
                column: Some(2),
                field: Some("program".into()),
            }
        );
        let l = Error::limit("too big").at("size");
        assert_eq!((l.kind(), l.field()), ("limit", Some("size")));
        assert_eq!(Error::Cancelled.at("x").field(), None);
    }
}
