//! rosbag2's sqlite3 storage (`.db3`, the default of ROS 2 Humble and
//! older): a `topics` table (id, name, type, serialization format), a
//! `messages` table (topic id, receive time in ns, CDR bytes) and, from ROS
//! 2 Iron on, a `message_definitions` table with each type's `.msg` text.
//! Read through SQLite itself (rusqlite, bundled); the messages then go
//! through the same decoding as an MCAP bag's ([`crate::sources::file::ros::Decoder`]).
//!
//! A Humble bag stores no definitions: the common command types are built
//! in ([`BUILT_IN`], the definitions rosbag2 writes for them).

use crate::planner::PlanError;
use crate::sources::file::ros::{ChannelInfo, Decoder, Inventory, Storage};
use rusqlite::{Connection, OpenFlags};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// `ros2msg` definitions of the types [`crate::sources::file::ros::DEFAULT_MAPS`] reads, for
/// bags that store none: (type, definition), as rosbag2 writes them.
pub const BUILT_IN: &[(&str, &str)] = &[
    ("geometry_msgs/msg/Twist", TWIST),
    ("geometry_msgs/msg/TwistStamped", TWIST_STAMPED),
    ("ackermann_msgs/msg/AckermannDrive", ACKERMANN),
    (
        "ackermann_msgs/msg/AckermannDriveStamped",
        ACKERMANN_STAMPED,
    ),
];

const TWIST: &str = "geometry_msgs/Vector3 linear\ngeometry_msgs/Vector3 angular\n================================================================================\nMSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n";

const TWIST_STAMPED: &str = "std_msgs/Header header\ngeometry_msgs/Twist twist\n================================================================================\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n================================================================================\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n================================================================================\nMSG: geometry_msgs/Twist\ngeometry_msgs/Vector3 linear\ngeometry_msgs/Vector3 angular\n================================================================================\nMSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n";

const ACKERMANN: &str = "float32 steering_angle\nfloat32 steering_angle_velocity\nfloat32 speed\nfloat32 acceleration\nfloat32 jerk\n";

const ACKERMANN_STAMPED: &str = "std_msgs/Header header\nackermann_msgs/AckermannDrive drive\n================================================================================\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n================================================================================\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n================================================================================\nMSG: ackermann_msgs/AckermannDrive\nfloat32 steering_angle\nfloat32 steering_angle_velocity\nfloat32 speed\nfloat32 acceleration\nfloat32 jerk\n";

/// The built-in definition of `ty`, if it has one.
pub(crate) fn built_in(ty: &str) -> Option<&'static str> {
    let ty = crate::sources::file::ros::msg::normalize(ty);
    BUILT_IN
        .iter()
        .find(|(t, _)| crate::sources::file::ros::msg::normalize(t) == ty)
        .map(|(_, d)| *d)
}

/// An error about `file`.
fn err(file: &Path, m: impl std::fmt::Display) -> PlanError {
    PlanError::file(file.to_path_buf(), None, m.to_string())
}

/// `file`, opened read-only, checked to be a rosbag2 sqlite3 database.
fn open(file: &Path) -> Result<Connection, PlanError> {
    crate::input::check_regular(file, "plan file", crate::sources::file::ros::MCAP_MAX_BYTES)
        .map_err(|m| err(file, m))?;
    let bad = |e: rusqlite::Error| err(file, format!("not a readable sqlite3 bag file: {e}"));
    let conn = Connection::open_with_flags(
        file,
        OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX,
    )
    .map_err(bad)?;
    let tables = table_names(&conn).map_err(bad)?;
    for t in ["topics", "messages"] {
        if !tables.iter().any(|n| n == t) {
            return Err(err(
                file,
                format!("not a rosbag2 sqlite3 file: it has no `{t}` table"),
            ));
        }
    }
    Ok(conn)
}

fn table_names(conn: &Connection) -> rusqlite::Result<Vec<String>> {
    let mut st = conn.prepare("SELECT name FROM sqlite_master WHERE type = 'table'")?;
    let names = st.query_map([], |r| r.get::<_, String>(0))?;
    names.collect()
}

/// Scan the sqlite3 `files` for their topics and message counts.
pub fn scan(files: &[PathBuf]) -> Result<Inventory, PlanError> {
    let mut out = Inventory {
        storage: Storage::Sqlite3,
        files: files.to_vec(),
        channels: Vec::new(),
    };
    for (fi, file) in files.iter().enumerate() {
        let conn = open(file)?;
        let bad = |e: rusqlite::Error| err(file, format!("not a readable sqlite3 bag file: {e}"));
        let mut counts: HashMap<i64, usize> = HashMap::new();
        {
            let mut st = conn
                .prepare("SELECT topic_id, count(*) FROM messages GROUP BY topic_id")
                .map_err(bad)?;
            let rows = st
                .query_map([], |r| Ok((r.get::<_, i64>(0)?, r.get::<_, i64>(1)?)))
                .map_err(bad)?;
            for row in rows {
                let (id, n) = row.map_err(bad)?;
                counts.insert(id, usize::try_from(n).unwrap_or(0));
            }
        }
        let mut st = conn
            .prepare("SELECT id, name, type, serialization_format FROM topics ORDER BY id")
            .map_err(bad)?;
        let rows = st
            .query_map([], |r| {
                Ok((
                    r.get::<_, i64>(0)?,
                    r.get::<_, String>(1)?,
                    r.get::<_, String>(2)?,
                    r.get::<_, String>(3)?,
                ))
            })
            .map_err(bad)?;
        for row in rows {
            let (id, topic, ty, format) = row.map_err(bad)?;
            let Ok(small) = u16::try_from(id) else {
                return Err(err(
                    file,
                    format!("topic `{topic}` has the id {id}, beyond the 65 535 topics read"),
                ));
            };
            out.channels.push(ChannelInfo {
                file: fi,
                id: small,
                topic,
                encoding: format,
                type_name: Some(ty),
                count: counts.get(&id).copied().unwrap_or(0),
            });
        }
    }
    Ok(out)
}

/// The stored definitions of `file` by type (none before ROS 2 Iron).
fn definitions(
    conn: &Connection,
    file: &Path,
) -> Result<HashMap<String, (String, Vec<u8>)>, PlanError> {
    let bad = |e: rusqlite::Error| err(file, format!("not a readable sqlite3 bag file: {e}"));
    let mut out = HashMap::new();
    if !table_names(conn)
        .map_err(bad)?
        .iter()
        .any(|t| t == "message_definitions")
    {
        return Ok(out);
    }
    let mut st = conn
        .prepare("SELECT topic_type, encoding, encoded_message_definition FROM message_definitions")
        .map_err(bad)?;
    let rows = st
        .query_map([], |r| {
            Ok((
                r.get::<_, String>(0)?,
                r.get::<_, String>(1)?,
                r.get::<_, String>(2)?,
            ))
        })
        .map_err(bad)?;
    for row in rows {
        let (ty, encoding, text) = row.map_err(bad)?;
        out.insert(ty, (encoding, text.into_bytes()));
    }
    Ok(out)
}

/// The messages of the decoder's topic in `file` (index `fi`), on the
/// topic ids `ids`, in receive-time order (ties in recording order).
pub fn messages(
    file: &Path,
    fi: usize,
    ids: &[u16],
    dec: &mut Decoder<'_>,
) -> Result<(), PlanError> {
    let conn = open(file)?;
    let bad = |e: rusqlite::Error| err(file, format!("not a readable sqlite3 bag file: {e}"));
    let defs = definitions(&conn, file)?;
    let mut types: HashMap<u16, String> = HashMap::new();
    {
        let mut st = conn.prepare("SELECT id, type FROM topics").map_err(bad)?;
        let rows = st
            .query_map([], |r| Ok((r.get::<_, i64>(0)?, r.get::<_, String>(1)?)))
            .map_err(bad)?;
        for row in rows {
            let (id, ty) = row.map_err(bad)?;
            if let Ok(id) = u16::try_from(id) {
                types.insert(id, ty);
            }
        }
    }
    let list: Vec<String> = ids.iter().map(u16::to_string).collect();
    // The ids are this bag's own integers: formatted, not user text.
    let sql = format!(
        "SELECT topic_id, timestamp, data FROM messages WHERE topic_id IN ({}) ORDER BY timestamp, id",
        list.join(", ")
    );
    let mut st = conn.prepare(&sql).map_err(bad)?;
    let mut rows = st.query([]).map_err(bad)?;
    while let Some(row) = rows.next().map_err(bad)? {
        let id: i64 = row.get(0).map_err(bad)?;
        let ns: i64 = row.get(1).map_err(bad)?;
        let data = row.get_ref(2).map_err(bad)?;
        let data = data.as_blob().map_err(|_| {
            err(
                file,
                format!("topic `{}`: a message that is not bytes", dec.topic()),
            )
        })?;
        let channel = u16::try_from(id).unwrap_or(u16::MAX);
        let log_time = u64::try_from(ns).map_err(|_| {
            err(
                file,
                format!(
                    "topic `{}`: a message logged at {ns} ns, before 1970",
                    dec.topic()
                ),
            )
        })?;
        let ty = types.get(&channel).cloned().unwrap_or_default();
        let schema = || -> Option<crate::sources::file::ros::SchemaRef<'_>> {
            match defs.get(&ty) {
                Some((encoding, text)) if !text.is_empty() => {
                    Some((ty.as_str(), encoding.as_str(), text.as_slice()))
                }
                _ => built_in(&ty).map(|d| (ty.as_str(), "ros2msg", d.as_bytes())),
            }
        };
        dec.message(file, fi, channel, schema, log_time, data)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn built_in_definitions_parse_and_resolve_the_default_fields() {
        for (ty, text) in BUILT_IN {
            let def = crate::sources::file::ros::msg::Definition::parse(ty, text)
                .unwrap_or_else(|e| panic!("{ty}: {e}"));
            let (_, fields) = crate::sources::file::ros::DEFAULT_MAPS
                .iter()
                .find(|(t, _)| t == ty)
                .expect("a default map");
            for (_, path) in *fields {
                let p = crate::sources::file::ros::msg::FieldPath::parse(path).unwrap();
                def.resolve_number(&p)
                    .unwrap_or_else(|e| panic!("{ty} {path}: {e}"));
            }
        }
        assert!(built_in("geometry_msgs/Twist").is_some());
        assert!(built_in("std_msgs/msg/Float64").is_none());
    }
}
