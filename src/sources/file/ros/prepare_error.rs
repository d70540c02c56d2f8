//! Why a topic's messages cannot be read for the model: its stored
//! definition, or the inputs' field paths in it. Kept apart from the
//! decoder's own errors ([`crate::sources::file::ros::error`]), which
//! [`crate::sources::file::ros::msg`] uses, as these wrap its field path
//! errors.

use crate::sources::file::ros::error::{DefinitionError, FieldError};
use crate::sources::file::ros::msg::FieldPathError;

/// A model input that neither the scenario's `[planner.map]` nor the
/// message type's defaults give a field for.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Unmapped {
    /// The message type.
    pub ty: String,
    /// The input.
    pub input: String,
    /// The model's inputs.
    pub inputs: Vec<String>,
    /// The inputs the type gives by default, if it has defaults.
    pub defaults: Option<Vec<&'static str>>,
}

impl std::fmt::Display for Unmapped {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let Unmapped {
            ty,
            input,
            inputs,
            defaults,
        } = self;
        write!(
            f,
            "no field gives the input `{input}` (the model's inputs: {}): map it in the scenario, `[planner.map] {input} = \"field.path\"`",
            inputs.join(", ")
        )?;
        if let Some(names) = defaults {
            write!(f, "; {ty} gives {} by default", names.join(" and "))?;
            if names.contains(&"steer") && input == "steer_rate" {
                f.write_str(
                    " (a steering angle: steer the car by angle with `[model] steering = \"angle\"`)",
                )?;
            }
        }
        Ok(())
    }
}

impl std::error::Error for Unmapped {}

/// Why a topic's messages cannot be read for the model: its stored
/// definition, or the inputs' field paths in it.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub(crate) enum PrepareError {
    /// The channel has no schema.
    #[error("the bag stores no message definition for this topic (its channel has no schema): it cannot be decoded; record it again where the message package is installed")]
    NoSchema,
    /// The schema is empty.
    #[error("the bag stores no definition of {ty} (an empty schema: the recorder did not have the message package); record it again where the package is installed")]
    EmptySchema {
        /// The message type.
        ty: String,
    },
    /// The schema is not a `.msg` text.
    #[error("the definition of {ty} is stored as `{encoding}`; only `ros2msg` (.msg) definitions are read")]
    Encoding {
        /// The message type.
        ty: String,
        /// The schema's encoding.
        encoding: String,
    },
    /// The schema's bytes are not text.
    #[error("the definition of {ty} is not UTF-8 text")]
    NotUtf8 {
        /// The message type.
        ty: String,
    },
    /// The definition does not parse or check.
    #[error("the bag's definition of {ty} is not usable: {source}")]
    Definition {
        /// The message type.
        ty: String,
        /// What is wrong with it.
        #[source]
        source: DefinitionError,
    },
    /// An input has no field.
    #[error("{0}")]
    Unmapped(#[from] Unmapped),
    /// An input's field path is not a path.
    #[error("input `{input}`: {source}")]
    Path {
        /// The input.
        input: String,
        /// What is wrong with the path.
        #[source]
        source: FieldPathError,
    },
    /// A path inside the selected element is not a path in the message.
    #[error("{0}")]
    Select(#[source] FieldPathError),
    /// An input's field path names no number in the type.
    #[error("input `{input}` = `{text}` ({from}): {source}")]
    Resolve {
        /// The input.
        input: String,
        /// Its field path as written.
        text: String,
        /// Where the path comes from (`planner.map.v`, `the default for ...`).
        from: String,
        /// What the path names instead (boxed: it is the largest variant).
        #[source]
        source: Box<FieldError>,
    },
    /// `time = "header"` for a type without `header.stamp`.
    #[error("time = \"header\", but {ty} has no `header.stamp` (not a stamped type): drop `time` to use the log time")]
    NoStamp {
        /// The message type.
        ty: String,
    },
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sources::file::ros::error::tests::{stamped, SEP};
    use crate::sources::file::ros::{prepare, BagKeys, BagTime};
    use std::collections::BTreeMap;

    #[test]
    fn prepare_errors() {
        let map = BTreeMap::new();
        let keys = BagKeys {
            topic: None,
            time: BagTime::Log,
            map: &map,
            duration: None,
            select: None,
        };
        let twist = "geometry_msgs/msg/Twist";
        let text = format!("Vector3 linear\nVector3 angular\n{SEP}\nMSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n");
        let err = |schema, inputs: &[&str], keys: &BagKeys<'_>| {
            prepare(schema, inputs, keys).err().unwrap().to_string()
        };
        let vw = &["v", "omega"][..];
        assert_eq!(err(None, vw, &keys), "the bag stores no message definition for this topic (its channel has no schema): it cannot be decoded; record it again where the message package is installed");
        assert_eq!(err(Some((twist, "ros2msg", b"")), vw, &keys), "the bag stores no definition of geometry_msgs/msg/Twist (an empty schema: the recorder did not have the message package); record it again where the package is installed");
        assert_eq!(err(Some((twist, "ros2idl", text.as_bytes())), vw, &keys), "the definition of geometry_msgs/msg/Twist is stored as `ros2idl`; only `ros2msg` (.msg) definitions are read");
        assert_eq!(
            err(Some((twist, "ros2msg", b"\xff\xfe")), vw, &keys),
            "the definition of geometry_msgs/msg/Twist is not UTF-8 text"
        );
        assert_eq!(err(Some((twist, "ros2msg", b"p/B b\n")), vw, &keys), "the bag's definition of geometry_msgs/msg/Twist is not usable: field `b` of geometry_msgs/msg/Twist is of type p/B, which the bag's definition does not include");
        let ok = Some((twist, "ros2msg", text.as_bytes()));
        assert!(prepare(ok, vw, &keys).is_ok());
        assert_eq!(err(ok, &["v", "a"], &keys), "no field gives the input `a` (the model's inputs: v, a): map it in the scenario, `[planner.map] a = \"field.path\"`; geometry_msgs/msg/Twist gives v and omega by default");
        let ack = "ackermann_msgs/msg/AckermannDrive";
        let e = err(
            Some((ack, "ros2msg", b"float32 speed\n")),
            &["v", "steer_rate"],
            &keys,
        );
        assert_eq!(e, "no field gives the input `steer_rate` (the model's inputs: v, steer_rate): map it in the scenario, `[planner.map] steer_rate = \"field.path\"`; ackermann_msgs/msg/AckermannDrive gives v and steer by default (a steering angle: steer the car by angle with `[model] steering = \"angle\"`)");
        assert_eq!(err(Some(("p/msg/A", "ros2msg", b"float32 speed\n")), &["v"], &keys), "no field gives the input `v` (the model's inputs: v): map it in the scenario, `[planner.map] v = \"field.path\"`");
        let bad_map: BTreeMap<String, String> = [
            ("omega".to_string(), "angular.q".to_string()),
            ("v".to_string(), "linear..x".to_string()),
        ]
        .into();
        let mapped = BagKeys {
            map: &bad_map,
            ..keys
        };
        assert_eq!(err(ok, &["omega"], &mapped), "input `omega` = `angular.q` (planner.map.omega): no field `q` in `angular` (geometry_msgs/Vector3: fields x, y, z)");
        assert_eq!(err(ok, &["v"], &mapped), "input `v`: `linear..x` is not a field path (names of letters, digits and `_`, joined by `.`, each optionally followed by `[index]`)");
        let header = BagKeys {
            time: BagTime::Header,
            ..keys
        };
        assert_eq!(err(ok, vw, &header), "time = \"header\", but geometry_msgs/msg/Twist has no `header.stamp` (not a stamped type): drop `time` to use the log time");
        // A select's array is checked when the scenario is read; one that is
        // no path still says so here.
        let sel = BagKeys {
            select: Some(crate::sources::file::ros::select::Select {
                array: "trans forms",
                key: "child_frame_id",
                value: "base_link",
            }),
            ..keys
        };
        let e = prepare(ok, &["v"], &sel).err().unwrap();
        assert!(matches!(e, PrepareError::Select(_)), "{e:?}");
        assert_eq!(e.to_string(), "`trans forms[0].linear.x` is not a field path (names of letters, digits and `_`, joined by `.`, each optionally followed by `[index]`)");
        let stamped = stamped();
        let s = Some((
            "geometry_msgs/msg/TwistStamped",
            "ros2msg",
            stamped.as_bytes(),
        ));
        assert!(prepare(s, vw, &header).is_ok());
        let e = prepare(ok, &["omega"], &mapped).err().unwrap();
        let PrepareError::Resolve { source, .. } = &e else {
            panic!("{e:?}")
        };
        assert!(matches!(**source, FieldError::NoField { .. }), "{e:?}");
    }
}
