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
    /// Several problems of one input (every problem of a URDF at once), each
    /// an error of its own; printed one per line.
    #[error("{}", .0.iter().map(|e| e.to_string()).collect::<Vec<_>>().join("\nerror: "))]
    Several(Vec<Error>),
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

    /// Several errors as one (a single one as itself).
    pub fn several(mut errors: Vec<Error>) -> Error {
        if errors.len() == 1 {
            errors.remove(0)
        } else {
            Error::Several(errors)
        }
    }

    /// The errors this one holds, one per problem.
    pub fn into_list(self) -> Vec<Error> {
        match self {
            Error::Several(v) => v.into_iter().flat_map(Error::into_list).collect(),
            e => vec![e],
        }
    }

    /// Exit status: 2 for bad input (including planner refusals), 3 for runtime failures.
    pub fn exit_code(&self) -> i32 {
        match self {
            Error::Input { .. } | Error::Plan { .. } => 2,
            Error::Several(v) => v.iter().map(Error::exit_code).max().unwrap_or(2),
            Error::Physics { .. } | Error::Law { .. } | Error::Log { .. } => 3,
        }
    }
}
