#![warn(missing_docs)]
//! anholonomy: validation harness for nonholonomic motion planners.
//!
//! Pipeline: [`scenario`] (TOML → typed configuration) → [`validate`] (every
//! scenario of a call checked, planned and its physics built before anything
//! runs) → [`runner`]: ideal run ([`integrate`], RK4 on a [`model`]) →
//! physics replay ([`engine`], Rapier with a URDF) → [`compare`] → logs
//! ([`log`]: MCAP, Rerun, summary.json, written as one unit); [`sweep`] runs
//! Monte Carlo variants. Configuration flows one way: [`robots`],
//! [`planner`], [`model`] and [`engine`] define their own plain parameter
//! types and never import [`scenario`].

//!
//! The public API is what the binary's commands and the Python package
//! use: prepare scenarios (validated, planned, physics built), run them,
//! read the outcome.
//!
//! ```
//! use anholonomy::runner::{run, RunOptions};
//! use anholonomy::validate::{prepare_all, Call};
//! use std::path::PathBuf;
//!
//! let file = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/disk_paper.toml"));
//! // No logs: nothing is written.
//! let call = Call { log_root: None, sharded: false, max_steps: None };
//! let preps = prepare_all(&[file], &call).expect("a valid scenario");
//! let outcome = run(&preps[0], &RunOptions::default())?;
//! assert!(outcome.passed, "{:?}", outcome.failures);
//! // The physics replay ends within its gate of the ideal run's goal.
//! let miss = outcome.metric("sim_goal_position").unwrap();
//! assert!(miss < 0.05, "{miss}");
//! # Ok::<(), anholonomy::Error>(())
//! ```

pub mod baseline;
pub mod cancel;
pub mod compare;
pub mod echo;
pub mod engine;
pub mod error;
pub mod fit;
pub mod gate;
pub mod init;
pub mod input;
pub mod integrate;
pub mod junit;
pub mod log;
pub mod margin;
pub mod metric;
pub mod model;
pub mod numfmt;
pub mod paper;
pub mod plan;
pub mod planner;
pub mod progress;
#[cfg(test)]
mod prop_config;
pub mod record;
pub mod recording;
pub mod reference;
pub mod report;
pub mod robots;
pub mod runner;
pub mod scenario;
pub mod sources;
pub mod suite;
pub mod sweep;
pub mod validate;
pub mod verdict;

pub use error::Error;
