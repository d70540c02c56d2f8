//! anholonomy: validation harness for nonholonomic motion planners.
//!
//! Pipeline: [`scenario`] → [`planner`] → [`plan`] → ideal run
//! ([`integrate`], RK4 on a [`model`]) → physics replay ([`physics`], Rapier
//! with a URDF) → [`compare`] → logs ([`log`]: MCAP, Rerun, summary.json).
//! [`runner`] strings the stages together for one scenario.

pub mod compare;
pub mod error;
pub mod integrate;
pub mod log;
pub mod model;
pub mod physics;
pub mod plan;
pub mod planner;
pub mod progress;
pub mod record;
pub mod runner;
pub mod scenario;
pub mod suite;
pub mod sweep;
pub mod systems;

pub use error::Error;
