//! `[compare]`: a recording of the robot on this plan, the third run of
//! `run` and `check` (see [`crate::recording`]).

use crate::recording::align::Frame;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// `[compare]`: a recorded run beside the ideal and physics runs.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CompareConfig {
    /// The recording, relative to the scenario file: `BAG:TOPIC` (a rosbag2
    /// directory or its `.mcap`, then a `nav_msgs/msg/Odometry`,
    /// `geometry_msgs/msg/PoseStamped` or `PoseWithCovarianceStamped`
    /// topic), `BAG:/tf:FRAME` (a tf child frame), or a CSV with columns
    /// `t`, `x`, `y` and `theta` (rad) or `theta_deg`. Adds the `real_*`
    /// metrics.
    pub reference: String,
    /// The recording's time at which the plan's commands start, s. A
    /// recording in the bag the plan is read from is on the bag's clock
    /// (plan time 0 is the first command) and this shifts it further.
    #[serde(default)]
    pub time_offset: f64,
    /// How the recording's coordinates are laid over the scenario's.
    #[serde(default)]
    pub frame: Frame,
}
