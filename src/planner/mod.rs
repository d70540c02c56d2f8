//! Planners: one module per planner. Each turns (start, goal, model
//! parameters, planner parameters) into a [`crate::plan::Plan`].

pub mod dilf;
pub mod endogenous;
pub mod rover_primitives;
pub mod sphere_geometric;
pub mod sphere_triangle;
pub mod stokes_disk;
pub mod stokes_space;

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
    /// An iterative planner stopped without converging.
    #[error("planner did not converge: {0}")]
    NoConvergence(String),
}

/// `Ok` when `ok`, else [`PlanError::InvalidParameter`] naming the parameter.
pub fn check_param(name: &str, ok: bool, reason: &str) -> Result<(), PlanError> {
    if ok {
        Ok(())
    } else {
        Err(PlanError::InvalidParameter {
            name: name.into(),
            reason: reason.into(),
        })
    }
}
