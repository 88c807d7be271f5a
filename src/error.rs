//! One error type for the whole crate.
//!
//! Every failure a user can cause is a value of [`Error`], never a panic.
//! Messages are one line and name the file, line and column where there is one.

use std::path::PathBuf;

/// The crate's error. New variants may be added: match with a `_` arm.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A problem at a definite place in a CSV file.
    /// `line` is 1-based and counts the header as line 1.
    #[error("{file}:{line}{}: {message}", column.as_ref().map(|c| format!(": column '{c}'")).unwrap_or_default())]
    Csv {
        file: String,
        line: u64,
        column: Option<String>,
        message: String,
    },

    /// A problem with a whole input (file or in-memory data), not one cell.
    #[error("{source_name}: {message}")]
    Input {
        source_name: String,
        message: String,
    },

    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },

    /// JSON (de)serialisation failed.
    #[error("{context}: {source}")]
    Json {
        context: String,
        #[source]
        source: serde_json::Error,
    },

    /// A parameter or option is out of its valid range.
    #[error("invalid parameter: {0}")]
    InvalidParameter(String),

    /// A joint vector has the wrong length for the robot or model.
    #[error("a joint vector has {got} values but the robot or model has {expected} joints")]
    JointCount { expected: usize, got: usize },

    /// A robot that is neither a preset nor a robot file.
    #[error(
        "unknown robot '{name}': neither a preset ({known}) nor a robot file (TOML or JSON, see `robokrige robot --help`)"
    )]
    UnknownRobot { name: String, known: String },

    /// Numerical inverse kinematics did not reach the target.
    #[error(
        "inverse kinematics did not converge after {iterations} iterations \
         (position residual {position_mm:.3e} mm, orientation residual {orientation_rad:.3e} rad)"
    )]
    IkNotConverged {
        iterations: usize,
        position_mm: f64,
        orientation_rad: f64,
    },

    /// Trajectory points that inverse kinematics could not reach (0-based
    /// indices, in order) and the first failure's message.
    #[error(
        "{} trajectory point(s) unreachable (0-based indices {}): first failure: {first}",
        indices.len(),
        indices.iter().take(20).map(|i| i.to_string()).collect::<Vec<_>>().join(", ")
            + if indices.len() > 20 { ", …" } else { "" }
    )]
    Unreachable { indices: Vec<usize>, first: String },

    /// Drawing a plot failed.
    #[error("{}: plot: {message}", path.display())]
    Plot { path: PathBuf, message: String },

    /// A command would allocate more memory than the limit allows
    /// ([`crate::memory`]).
    #[error("{what} needs about {needed} of memory, over the limit of {limit}: {hint}")]
    Memory {
        what: String,
        needed: String,
        limit: String,
        hint: String,
    },

    /// A linear-algebra step failed (e.g. a matrix that stays singular).
    #[error("numerical failure: {0}")]
    Numerical(String),
}

/// Crate-wide result alias.
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// Wrap an I/O error with the path it concerns.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}
