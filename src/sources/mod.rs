//! Plan sources: plans that come from outside the harness's planners, for
//! any model. Plan files (CSV, JSON, MCAP, rosbag2) in [`file`](mod@file), feedback
//! laws in another process in [`external`]; [`own_plan`] wraps a robot's
//! system so that its plan comes from one of them.

pub mod external;
pub mod file;
pub mod json_numbers;
pub mod own_plan;
