//! Errors of the harness, split by what the user must do about them.

use std::path::PathBuf;
use thiserror::Error;

/// Top-level error. [`Error::exit_code`] maps it to the CLI's exit status.
#[derive(Debug, Error)]
pub enum Error {
    /// The scenario (or a file it names) is unusable: the user must fix the input.
    #[error("{path}{}: {message}", .line.map(|l| format!(":{l}")).unwrap_or_default())]
    Input {
        /// File at fault.
        path: PathBuf,
        /// 1-based line, when known.
        line: Option<usize>,
        /// One-line description naming the key.
        message: String,
    },
    /// The planner refused the task (bad input: exit 2).
    #[error("{path}{}: key `{key}`: planner: {source}", .line.map(|l| format!(":{l}")).unwrap_or_default())]
    Plan {
        /// Scenario file.
        path: PathBuf,
        /// 1-based line of `key`, when it is written in the file.
        line: Option<usize>,
        /// The scenario key the refusal is about (`planner.<parameter>`, `goal`, `planner`).
        key: String,
        /// Reason.
        source: crate::planner::PlanError,
    },
    /// Physics setup or stepping failed.
    #[error("{path}: physics: {message}")]
    Physics {
        /// Scenario file.
        path: PathBuf,
        /// Reason.
        message: String,
    },
    /// A feedback law stopped working during a run: an external law's
    /// process could not start, died, answered garbage or too late (a
    /// runtime failure: exit 3). `message` is one line, then the tail of the
    /// process's stderr when it wrote any (lines starting with `  | `).
    #[error("{path}: feedback law ({run} run): {message}")]
    Law {
        /// Scenario file.
        path: PathBuf,
        /// `ideal` or `physics`.
        run: &'static str,
        /// What went wrong.
        message: String,
    },
    /// Writing logs failed.
    #[error("{path}: writing logs: {message}")]
    Log {
        /// Scenario file.
        path: PathBuf,
        /// Reason.
        message: String,
    },
}

impl Error {
    /// Shorthand for an input error without a line.
    pub fn input(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        Error::Input {
            path: path.into(),
            line: None,
            message: message.into(),
        }
    }

    /// Exit status: 2 for bad input (including planner refusals), 3 for runtime failures.
    pub fn exit_code(&self) -> i32 {
        match self {
            Error::Input { .. } | Error::Plan { .. } => 2,
            Error::Physics { .. } | Error::Law { .. } | Error::Log { .. } => 3,
        }
    }
}
