//! Planners: one module per planner. Each turns (start, goal, model
//! parameters, planner parameters) into a [`crate::plan::Plan`].

pub mod endogenous;

use thiserror::Error;

/// Why a planner could not produce a plan. Always a clear, user-facing reason.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum PlanError {
    /// A parameter is outside its valid range.
    #[error("invalid planner parameter `{name}`: {reason}")]
    InvalidParameter {
        /// Parameter name as written in the scenario file.
        name: String,
        /// What is wrong with it.
        reason: String,
    },
    /// The goal cannot be reached under the planner's constraints.
    #[error("goal unreachable: {0}")]
    Unreachable(String),
    /// An iterative planner stopped without converging (a runtime
    /// failure: exit 3).
    #[error("planner did not converge: {0}")]
    NoConvergence(String),
    /// The model's equations cannot be planned with where the planner
    /// starts (a declared expression that is not differentiable there);
    /// `key` is the scenario key of the equation.
    #[error("{reason}")]
    Model {
        /// The equation's scenario key (`model.kinematics.theta1`).
        key: String,
        /// What is wrong, naming the expression.
        reason: String,
    },
    /// A file the planner reads (a plan file) is unusable: bad input in
    /// that file, reported against it (`FILE:LINE: message`), not against
    /// the scenario.
    #[error("{0}")]
    File(Box<FileProblem>),
}

/// What is wrong where in a file a planner reads.
#[derive(Debug, Error, Clone, PartialEq)]
#[error("{}{}: {message}", crate::echo::path(.path), .line.map(|l| format!(":{l}")).unwrap_or_default())]
pub struct FileProblem {
    /// The file at fault.
    pub path: std::path::PathBuf,
    /// 1-based line (a CSV row, a JSON value), when known.
    pub line: Option<usize>,
    /// One line naming the column or key.
    pub message: String,
}

impl PlanError {
    /// A [`PlanError::File`].
    pub fn file(path: std::path::PathBuf, line: Option<usize>, message: String) -> PlanError {
        PlanError::File(Box::new(FileProblem {
            path,
            line,
            message,
        }))
    }
}

/// `Ok` when `ok`, else [`PlanError::InvalidParameter`] naming the parameter.
pub(crate) fn check_param(name: &str, ok: bool, reason: &str) -> Result<(), PlanError> {
    if ok {
        Ok(())
    } else {
        Err(PlanError::InvalidParameter {
            name: name.into(),
            reason: reason.into(),
        })
    }
}
