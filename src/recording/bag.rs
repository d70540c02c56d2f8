//! A recorded pose topic of a rosbag2 bag, read by the bag reader that
//! reads plans from bags ([`crate::sources::file::ros`]: the same storage
//! files, the definitions the bag stores, the same log or header time), so
//! every storage it reads serves recordings too.
//!
//! The pose is taken from the message's position and orientation:
//! `nav_msgs/msg/Odometry` and `geometry_msgs/msg/PoseWithCovarianceStamped`
//! at `pose.pose`, `geometry_msgs/msg/PoseStamped` at `pose`, and a
//! `tf2_msgs/msg/TFMessage` topic's transform whose `child_frame_id` is the
//! frame asked for (in its parent's frame; tf chains are not composed).

use crate::recording::{Recording, RecordingError};
use crate::sources::file::ros::{self, msg::normalize, select::Select, BagKeys};
use crate::sources::file::BagTime;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The pose types read, with the path of the pose in each.
const POSES: &[(&str, &str)] = &[
    ("nav_msgs/msg/Odometry", "pose.pose"),
    ("geometry_msgs/msg/PoseWithCovarianceStamped", "pose.pose"),
    ("geometry_msgs/msg/PoseStamped", "pose"),
];

/// The tf message type.
const TF: &str = "tf2_msgs/msg/TFMessage";

/// The numbers read from each message.
const FIELDS: [&str; 6] = ["x", "y", "qx", "qy", "qz", "qw"];

/// The storage and files of the bag at `path`: a bag directory's (its
/// `metadata.yaml` names them) or the one file named (`.db3`: sqlite3).
pub(crate) fn storage_files(path: &Path) -> Result<(ros::Storage, Vec<PathBuf>), RecordingError> {
    if path.is_dir() {
        return Ok(ros::metadata::bag_files(path)?);
    }
    if !path.exists() {
        return Err(RecordingError::file(
            path,
            None,
            "no such file or directory",
        ));
    }
    if path.file_name().is_some_and(|n| n == "metadata.yaml") {
        let dir = path.parent().unwrap_or(Path::new("."));
        return Ok(ros::metadata::bag_files(dir)?);
    }
    let storage = if path.extension().is_some_and(|e| e == "db3") {
        ros::Storage::Sqlite3
    } else {
        ros::Storage::Mcap
    };
    Ok((storage, vec![path.to_path_buf()]))
}

/// What the bag at `path` holds: its channels, in whichever storage.
fn inventory(path: &Path) -> Result<(Vec<PathBuf>, ros::Inventory), RecordingError> {
    let (storage, files) = storage_files(path)?;
    let inv = match storage {
        ros::Storage::Mcap => ros::Inventory::scan(&files)?,
        ros::Storage::Sqlite3 => ros::sqlite::scan(&files)?,
    };
    Ok((files, inv))
}

/// Read the pose on `topic` (a tf topic: of child frame `frame`).
pub fn read(
    path: &Path,
    topic: &str,
    frame: Option<&str>,
    time: BagTime,
) -> Result<Recording, RecordingError> {
    let (files, inv) = inventory(path)?;
    let err = |m: String| RecordingError::file(path, None, m);
    let Some(ty) = inv
        .channels
        .iter()
        .find(|c| c.topic == topic)
        .map(|c| c.type_name.clone().unwrap_or_default())
    else {
        return Err(err(format!(
            "no topic `{topic}` in the bag (topics: {})",
            inv.topics()
        )));
    };
    let known = || {
        POSES
            .iter()
            .map(|(t, _)| *t)
            .chain([TF])
            .collect::<Vec<_>>()
            .join(", ")
    };
    let is = |t: &str| normalize(&ty) == normalize(t);
    let (prefix, select) = if is(TF) {
        let Some(frame) = frame else {
            return Err(err(format!(
                "topic `{topic}` is a tf topic ({ty}): name the robot's frame, `{}:{topic}:FRAME` (e.g. `:base_link`)",
                path.display()
            )));
        };
        let s = Select {
            array: "transforms",
            key: "child_frame_id",
            value: frame,
        };
        (("transform.translation", "transform.rotation"), Some(s))
    } else {
        let Some((_, at)) = POSES.iter().find(|(t, _)| is(t)) else {
            return Err(err(format!(
                "topic `{topic}` holds {}, not a pose (read: {})",
                if ty.is_empty() {
                    "messages of no stored type".to_string()
                } else {
                    ty.clone()
                },
                known()
            )));
        };
        if let Some(f) = frame {
            return Err(err(format!(
                "topic `{topic}` is not a tf topic ({ty}): drop the frame `:{f}`"
            )));
        }
        let (p, o): (&'static str, &'static str) = match *at {
            "pose" => ("pose.position", "pose.orientation"),
            _ => ("pose.pose.position", "pose.pose.orientation"),
        };
        ((p, o), None)
    };
    let (pos, rot) = prefix;
    let map: BTreeMap<String, String> = FIELDS
        .iter()
        .map(|f| {
            let path = match *f {
                "x" | "y" => format!("{pos}.{f}"),
                q => format!("{rot}.{}", &q[1..]),
            };
            (f.to_string(), path)
        })
        .collect();
    let keys = BagKeys {
        topic: Some(topic),
        time,
        map: &map,
        // The whole topic: the reader ends a plan at `duration`, and the
        // sample it adds there is dropped below.
        duration: Some(crate::plan::MAX_DURATION),
        select,
    };
    let (samples, info) = ros::read_with(path, &inv, &FIELDS, &keys)?;
    let n = samples.t.len() - 1;
    let pose = samples
        .u
        .chunks(FIELDS.len())
        .take(n)
        .map(|v| [v[0], v[1], crate::recording::yaw_of(v[2], v[3], v[4], v[5])])
        .collect();
    Ok(Recording {
        source: format!(
            "{}:{topic}{}",
            path.display(),
            frame.map(|f| format!(":{f}")).unwrap_or_default()
        ),
        t: samples.t[..n].to_vec(),
        pose,
        bag_clock: Some((files, info.first_ns)),
    })
}

/// The bag time (ns) of a bag plan's t = 0: the first command on its topic.
pub(crate) fn commands_start(
    path: &Path,
    inputs: &[&str],
    keys: &BagKeys<'_>,
) -> Result<(Vec<PathBuf>, i64), RecordingError> {
    let (files, inv) = inventory(path)?;
    let (_, info) = ros::read_with(path, &inv, inputs, keys)?;
    Ok((files, info.first_ns))
}
