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
        /// The file's name as given by the caller (a path or a label).
        file: String,
        /// 1-based line number; the header is line 1.
        line: u64,
        /// The column's header name, when the problem is in one cell.
        column: Option<String>,
        /// What is wrong, one line.
        message: String,
    },

    /// A problem with a whole input (file or in-memory data), not one cell.
    #[error("{source_name}: {message}")]
    Input {
        /// The input's name: a file path, a folder, or a label for in-memory data.
        source_name: String,
        /// What is wrong, one line.
        message: String,
    },

    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or folder being read or written.
        path: PathBuf,
        /// The underlying I/O error.
        #[source]
        source: std::io::Error,
    },

    /// JSON (de)serialisation failed.
    #[error("{context}: {source}")]
    Json {
        /// What was being (de)serialised, e.g. `"model"` or the source file's name.
        context: String,
        /// The underlying serde_json error.
        #[source]
        source: serde_json::Error,
    },

    /// A parameter or option is out of its valid range.
    #[error("invalid parameter: {0}")]
    InvalidParameter(String),

    /// A joint vector has the wrong length for the robot or model.
    #[error("a joint vector has {got} values but the robot or model has {expected} joints")]
    JointCount {
        /// Joints of the robot or model.
        expected: usize,
        /// Values in the joint vector given.
        got: usize,
    },

    /// A robot that is neither a preset nor a robot file.
    #[error(
        "unknown robot '{name}': neither a preset ({known}) nor a robot file (TOML or JSON, see `robokrige robot --help`)"
    )]
    UnknownRobot {
        /// The name or path given.
        name: String,
        /// The preset names, comma-separated.
        known: String,
    },

    /// Numerical inverse kinematics did not reach the target.
    #[error(
        "inverse kinematics did not converge after {iterations} iterations \
         (position residual {position_mm:.3e} mm, orientation residual {orientation_rad:.3e} rad)"
    )]
    IkNotConverged {
        /// Iterations run (at most `IkOptions::max_iter`; fewer when the
        /// damping μ grew past its cap).
        iterations: usize,
        /// Remaining position error `‖p* − p‖`, mm.
        position_mm: f64,
        /// Remaining orientation error `‖log(R* Rᵀ)‖`, radians (0 for a
        /// position-only target).
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
    Unreachable {
        /// 0-based indices of the unreachable points, ascending.
        indices: Vec<usize>,
        /// The first failure's message (usually an [`Error::IkNotConverged`]).
        first: String,
    },

    /// Drawing a plot failed.
    #[error("{}: plot: {message}", path.display())]
    Plot {
        /// The chart file being drawn.
        path: PathBuf,
        /// The plotting backend's message.
        message: String,
    },

    /// A command would allocate more memory than the limit allows
    /// ([`crate::memory`]).
    #[error("{what} needs about {needed} of memory, over the limit of {limit}: {hint}")]
    Memory {
        /// What would allocate, in words (e.g. "a fit of 20000 rows").
        what: String,
        /// Estimated need, human-readable (e.g. `"3.2 GB"`, see
        /// [`crate::memory::human`]).
        needed: String,
        /// The limit, human-readable, with its source (`ROBOKRIGE_MEMORY_LIMIT`
        /// or available memory).
        limit: String,
        /// What to do instead, e.g. an option with fewer rows.
        hint: String,
    },

    /// A linear-algebra step failed (e.g. a matrix that stays singular).
    #[error("numerical failure: {0}")]
    Numerical(String),

    /// The caller cancelled the work through its cancellation token (the
    /// `cancel` module; e.g. Ctrl-C in Python); nothing was produced.
    #[error("interrupted: the work was cancelled before it finished")]
    Interrupted,

    /// A failure in one output axis of a model (fit or refit); the cause
    /// keeps its own variant.
    #[error("output {axis}: {source}")]
    Axis {
        /// The axis: `ex`, `ey` or `ez`.
        axis: &'static str,
        /// What went wrong there.
        #[source]
        source: Box<Error>,
    },
}

/// Crate-wide result alias.
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// Whether this is [`Error::Interrupted`], also inside an
    /// [`Error::Axis`].
    pub fn is_interrupted(&self) -> bool {
        match self {
            Error::Interrupted => true,
            Error::Axis { source, .. } => source.is_interrupted(),
            _ => false,
        }
    }

    /// Wrap an I/O error with the path it concerns.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}
