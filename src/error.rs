//! Typed errors. Every error a user can cause names where it happened (file, line,
//! column when known), what was expected, what was found and what to do about it.

use std::fmt;
use std::path::PathBuf;

/// A location in an input file (1-based line and column; column is the field index
/// for delimited files).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Location {
    /// File the problem is in.
    pub file: PathBuf,
    /// 1-based line number, if known.
    pub line: Option<usize>,
    /// 1-based column (field) number, if known.
    pub column: Option<usize>,
}

impl Location {
    /// A whole-file location.
    pub fn file(file: impl Into<PathBuf>) -> Self {
        Location {
            file: file.into(),
            line: None,
            column: None,
        }
    }
    /// A line in a file.
    pub fn line(file: impl Into<PathBuf>, line: usize) -> Self {
        Location {
            file: file.into(),
            line: Some(line),
            column: None,
        }
    }
    /// A field (column) on a line.
    pub fn at(file: impl Into<PathBuf>, line: usize, column: usize) -> Self {
        Location {
            file: file.into(),
            line: Some(line),
            column: Some(column),
        }
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        if let Some(l) = self.line {
            write!(f, ":{l}")?;
            if let Some(c) = self.column {
                write!(f, ":{c}")?;
            }
        }
        Ok(())
    }
}

/// Errors of dea-fit. `Input` and `Settings` are the user's to fix (exit status 2).
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Malformed or physically impossible input data.
    #[error("{loc}: {msg}{}", hint_suffix(.hint))]
    Input {
        /// Where.
        loc: Location,
        /// What was expected and what was found.
        msg: String,
        /// What to do about it.
        hint: Option<String>,
    },
    /// A setting (flag, option) that cannot be used.
    #[error("{msg}{}", hint_suffix(.hint))]
    Settings {
        /// What is wrong.
        msg: String,
        /// What to do about it.
        hint: Option<String>,
    },
    /// An operating-system error on a file.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
}

fn hint_suffix(h: &Option<String>) -> String {
    match h {
        Some(h) => format!("; hint: {h}"),
        None => String::new(),
    }
}

impl Error {
    /// An input error at a location.
    pub fn input(loc: Location, msg: impl Into<String>) -> Self {
        Error::Input {
            loc,
            msg: msg.into(),
            hint: None,
        }
    }
    /// A settings error.
    pub fn settings(msg: impl Into<String>) -> Self {
        Error::Settings {
            msg: msg.into(),
            hint: None,
        }
    }
    /// Attach a hint (what the user can do).
    pub fn with_hint(mut self, h: impl Into<String>) -> Self {
        match &mut self {
            Error::Input { hint, .. } | Error::Settings { hint, .. } => *hint = Some(h.into()),
            Error::Io { .. } => {}
        }
        self
    }
    /// An I/O error on a path.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}

/// Result alias.
pub type Result<T> = std::result::Result<T, Error>;
