//! Errors of the harness, split by what the user must do about them.

use std::path::PathBuf;
use thiserror::Error;

/// What the user must do about an [`Error`](enum@Error).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum ErrorKind {
    /// Fix the input (a scenario, a file it names, a flag).
    BadInput,
    /// Something failed while running (physics, a feedback law, logs).
    Runtime,
}

/// Top-level error. [`Error::kind`] says whether the user must fix the input.
#[derive(Debug, Error)]
pub enum Error {
    /// The scenario (or a file it names) is unusable: the user must fix the input.
    #[error("{}{}: {message}", crate::echo::path(.path), .line.map(|l| format!(":{l}")).unwrap_or_default())]
    Input {
        /// File at fault.
        path: PathBuf,
        /// 1-based line, when known.
        line: Option<usize>,
        /// The scenario key at fault, when the error is about one (the
        /// message names it too).
        key: Option<String>,
        /// One-line description naming the key.
        message: String,
    },
    /// The planner refused the task (bad input: exit 2), or did not
    /// converge (exit 3).
    #[error("{}{}: key `{}`: planner: {source}", crate::echo::path(.path), .line.map(|l| format!(":{l}")).unwrap_or_default(), crate::echo::bare(.key))]
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
    #[error("{}: physics: {message}", crate::echo::path(.path))]
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
    #[error("{}: feedback law ({run} run): {message}", crate::echo::path(.path))]
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
    #[error("{}: writing logs: {message}", crate::echo::path(.path))]
    Log {
        /// Scenario file.
        path: PathBuf,
        /// Reason.
        message: String,
    },
    /// A command that writes files (`init`, `models export`) could not
    /// write one.
    #[error("{}: {command}: {message}", crate::echo::path(.path))]
    Write {
        /// The file (or directory) it could not write.
        path: PathBuf,
        /// The command, as typed (`init`).
        command: &'static str,
        /// Reason.
        message: String,
    },
}

/// What a refusal during setup (a system's parameters, its physics built
/// from a URDF) is about, so the scenario layer can point at the line
/// without reading the message.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum About {
    /// A scenario key (`model.radius`, `start`, `sim.perturb.command_latency`).
    Key(String),
    /// A URDF element (`link` or `joint`, by name), or the URDF as a whole.
    Urdf(Option<(&'static str, String)>),
    /// Neither.
    Nothing,
}

/// A refusal during setup: one line, and what it is about.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SetupError {
    /// What the refusal points at.
    pub about: About,
    /// The message (without the `` key `k`: `` a key's refusal is shown with).
    detail: String,
}

impl std::fmt::Display for SetupError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.about {
            About::Key(k) => write!(f, "key `{}`: {}", crate::echo::bare(k), self.detail),
            _ => f.write_str(&self.detail),
        }
    }
}

impl std::error::Error for SetupError {}

/// Messages of lower layers (a model's own checks) are about nothing in particular.
impl From<String> for SetupError {
    fn from(message: String) -> SetupError {
        SetupError::other(message)
    }
}

impl From<&str> for SetupError {
    fn from(message: &str) -> SetupError {
        SetupError::other(message)
    }
}

impl SetupError {
    /// A refusal about scenario key `key`: shown as "key `key`: message".
    pub fn key(key: impl Into<String>, message: impl std::fmt::Display) -> SetupError {
        SetupError {
            about: About::Key(key.into()),
            detail: message.to_string(),
        }
    }

    /// A refusal about the URDF as a whole; the message starts with `URDF`.
    pub fn urdf(message: impl Into<String>) -> SetupError {
        SetupError {
            about: About::Urdf(None),
            detail: message.into(),
        }
    }

    /// A refusal about URDF element `elem` (`link`, `joint`) named `name`.
    pub fn urdf_at(
        elem: &'static str,
        name: impl Into<String>,
        message: impl Into<String>,
    ) -> SetupError {
        SetupError {
            about: About::Urdf(Some((elem, name.into()))),
            detail: message.into(),
        }
    }

    /// A refusal about nothing in particular.
    pub fn other(message: impl Into<String>) -> SetupError {
        SetupError {
            about: About::Nothing,
            detail: message.into(),
        }
    }

    /// The same refusal about `key` instead (a URDF problem a scenario key
    /// is responsible for: the key gains the line, the message is kept).
    pub fn under_key(self, key: impl Into<String>) -> SetupError {
        SetupError::key(key, self.to_string())
    }

    /// The message without the key (a key's refusal: what is wrong with it).
    pub fn reason(&self) -> &str {
        &self.detail
    }

    /// The key the refusal is about, if it is about one.
    pub fn key_name(&self) -> Option<&str> {
        match &self.about {
            About::Key(k) => Some(k),
            _ => None,
        }
    }
}

impl Error {
    /// Shorthand for an input error without a line.
    pub fn input(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        Error::Input {
            key: None,
            path: path.into(),
            line: None,
            message: message.into(),
        }
    }

    /// An input error about key `key`: "key `key`: message".
    pub fn keyed(
        path: impl Into<PathBuf>,
        line: Option<usize>,
        key: &str,
        message: impl std::fmt::Display,
    ) -> Self {
        Error::Input {
            path: path.into(),
            line,
            key: Some(key.to_string()),
            message: format!("key `{}`: {message}", crate::echo::bare(key)),
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

    /// Bad input (planner refusals included) or a failure at run time; of
    /// several errors, a runtime one if any.
    pub fn kind(&self) -> ErrorKind {
        match self {
            // The planner ran and did not reach the goal: not bad input.
            Error::Plan {
                source: crate::planner::PlanError::NoConvergence(_),
                ..
            } => ErrorKind::Runtime,
            Error::Input { .. } | Error::Plan { .. } => ErrorKind::BadInput,
            Error::Several(v) => v
                .iter()
                .map(Error::kind)
                .max()
                .unwrap_or(ErrorKind::BadInput),
            Error::Physics { .. } | Error::Law { .. } | Error::Log { .. } | Error::Write { .. } => {
                ErrorKind::Runtime
            }
        }
    }
}
