//! Recorded trajectories of a real robot (or of another engine): the
//! planar pose (x, y, yaw) over time, read from a rosbag2 topic
//! ([`bag`]: `nav_msgs/msg/Odometry`, `geometry_msgs/msg/PoseStamped`,
//! `PoseWithCovarianceStamped`, or one child frame of a tf topic) or from a
//! CSV `t,x,y,theta` ([`csv`]); lined up with a plan's commands in time and
//! with the scenario's start in space ([`align`]); compared with the runs
//! ([`metrics`]: the `real_*` metrics of `[compare] reference`, and the
//! residual `anholonomy fit` minimises).
//!
//! A reference is written `BAG:TOPIC` (a bag directory or its `.mcap`, then
//! the topic), `BAG:/tf:FRAME` for a tf frame, or a path ending in `.csv`.

pub mod align;
pub mod bag;
pub mod clock;
pub mod csv;
pub mod metrics;

use crate::planner::{FileProblem, PlanError};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Why a recording cannot be used.
#[derive(Debug, Error)]
pub enum RecordingError {
    /// The reference as written is not one (no topic, an unknown form).
    #[error("{0}")]
    Spec(String),
    /// The file (a bag, a CSV) is unusable there.
    #[error("{0}")]
    File(Box<FileProblem>),
    /// It cannot be lined up with the plan (no overlap, too few samples).
    #[error("{0}")]
    Alignment(String),
}

impl RecordingError {
    /// A problem in `path` (at `line`).
    pub fn file(path: &Path, line: Option<usize>, message: impl Into<String>) -> RecordingError {
        RecordingError::File(Box::new(FileProblem {
            path: path.to_path_buf(),
            line,
            message: message.into(),
        }))
    }
}

impl From<PlanError> for RecordingError {
    fn from(e: PlanError) -> RecordingError {
        match e {
            PlanError::File(f) => RecordingError::File(f),
            other => RecordingError::Spec(other.to_string()),
        }
    }
}

/// Where a recording is, as a reference names it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Source {
    /// A CSV file with columns `t`, `x`, `y` and `theta` (rad) or `theta_deg`.
    Csv(PathBuf),
    /// A topic of a rosbag2 bag (its directory, or one storage file).
    Bag {
        /// The bag.
        path: PathBuf,
        /// The topic.
        topic: String,
        /// A tf topic's child frame.
        frame: Option<String>,
    },
}

/// How a reference is written, for messages.
pub const FORMS: &str = "`BAG:TOPIC` (a rosbag2 directory or its .mcap, then a pose topic, e.g. `robot_bag:/odom`), `BAG:/tf:FRAME` (a frame of a tf topic) or a `.csv` file with columns t, x, y and theta";

impl Source {
    /// Parse a reference; relative paths are resolved against `base`.
    pub fn parse(text: &str, base: &Path) -> Result<Source, RecordingError> {
        let bad = |why: &str| RecordingError::Spec(format!("`{text}`: {why}; write {FORMS}"));
        if let Some(i) = text.find(":/") {
            let (path, rest) = (&text[..i], &text[i + 1..]);
            if path.is_empty() {
                return Err(bad("no bag before the topic"));
            }
            let (topic, frame) = match rest.split_once(':') {
                Some((t, f)) => (t, Some(f)),
                None => (rest, None),
            };
            if topic.len() < 2 || topic.contains(char::is_whitespace) {
                return Err(bad("not a topic name"));
            }
            if frame.is_some_and(|f| f.is_empty() || f.contains(char::is_whitespace)) {
                return Err(bad("an empty or spaced frame name after the topic"));
            }
            return Ok(Source::Bag {
                path: base.join(path),
                topic: topic.to_string(),
                frame: frame.map(str::to_string),
            });
        }
        let p = Path::new(text);
        if p.extension()
            .is_some_and(|e| e.to_string_lossy().eq_ignore_ascii_case("csv"))
        {
            return Ok(Source::Csv(base.join(p)));
        }
        if text.is_empty() {
            return Err(bad("empty"));
        }
        Err(bad("neither a bag and a topic nor a CSV file"))
    }

    /// The file or directory read.
    pub fn path(&self) -> &Path {
        match self {
            Source::Csv(p) => p,
            Source::Bag { path, .. } => path,
        }
    }

    /// As messages and logs name it.
    pub fn describe(&self) -> String {
        match self {
            Source::Csv(p) => p.display().to_string(),
            Source::Bag { path, topic, frame } => format!(
                "{}:{topic}{}",
                path.display(),
                frame.as_ref().map(|f| format!(":{f}")).unwrap_or_default()
            ),
        }
    }
}

/// A recorded planar trajectory, in its own time and frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    /// What it was read from.
    pub source: String,
    /// Sample times, s, strictly increasing.
    pub t: Vec<f64>,
    /// (x m, y m, yaw rad) per sample.
    pub pose: Vec<[f64; 3]>,
    /// Read from a bag: the bag's storage files and the bag time of t = 0,
    /// ns (a plan read from the same bag lines up on that clock).
    pub bag_clock: Option<(Vec<PathBuf>, i64)>,
}

impl Recording {
    /// Read the recording `source` names; a bag's times come from its log
    /// or header time (`time`).
    pub fn read(
        source: &Source,
        time: crate::sources::file::BagTime,
    ) -> Result<Recording, RecordingError> {
        let rec = match source {
            Source::Csv(p) => csv::read(p)?,
            Source::Bag { path, topic, frame } => bag::read(path, topic, frame.as_deref(), time)?,
        };
        if rec.t.len() < 2 {
            return Err(RecordingError::file(
                source.path(),
                None,
                format!(
                    "{}: {} sample{}: a recording needs at least two",
                    source.describe(),
                    rec.t.len(),
                    if rec.t.len() == 1 { "" } else { "s" }
                ),
            ));
        }
        Ok(rec)
    }
}

/// Yaw of a unit quaternion (x, y, z, w), rad.
pub(crate) fn yaw_of(x: f64, y: f64, z: f64, w: f64) -> f64 {
    (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn references_parse() {
        let b = Path::new("/s");
        assert_eq!(
            Source::parse("bag:/odom", b).unwrap(),
            Source::Bag {
                path: "/s/bag".into(),
                topic: "/odom".into(),
                frame: None
            }
        );
        assert_eq!(
            Source::parse("d/run.mcap:/tf:base_link", b).unwrap(),
            Source::Bag {
                path: "/s/d/run.mcap".into(),
                topic: "/tf".into(),
                frame: Some("base_link".into())
            }
        );
        assert_eq!(
            Source::parse("r.CSV", b).unwrap(),
            Source::Csv("/s/r.CSV".into())
        );
        for bad in ["", "bag", ":/odom", "bag:/", "bag:/tf:", "r.json"] {
            assert!(Source::parse(bad, b).is_err(), "{bad}");
        }
    }

    #[test]
    fn yaw_of_a_rotation_about_z() {
        let a: f64 = 2.0;
        let y = yaw_of(0.0, 0.0, (a / 2.0).sin(), (a / 2.0).cos());
        assert!((y - a).abs() < 1e-12);
    }
}
