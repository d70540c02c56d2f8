//! What goes wrong decoding a bag's messages: a stored definition that
//! cannot be used ([`DefinitionError`]), a field path that names no number
//! in it ([`FieldError`]), a message that does not decode ([`DecodeError`])
//! or lacks an element (`ValueError`). The texts name the type, field and
//! path, and say how to fix them; the caller adds file, topic and message.

/// Largest fixed array a definition may declare, elements (a covariance is 36).
pub(crate) const MAX_FIXED: usize = 1 << 20;

/// Where along a field path something is, for messages: "the message"
/// before the first step, else the path so far in backquotes.
fn here(at: &str) -> String {
    if at.is_empty() {
        "the message".to_string()
    } else {
        format!("`{at}`")
    }
}

/// Why a bag's stored message definition cannot be used.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DefinitionError {
    /// `re_ros_msg` could not parse the `.msg` text; its error (with its
    /// causes) as it prints, since that error type is not kept.
    #[error("{0}")]
    Syntax(String),
    /// A type contains itself, directly or through others.
    #[error("the definition of {} contains itself ({} → {again})", .chain[0], .chain.join(" → "))]
    Recursive {
        /// The types from the outermost to the one that uses `again` (normalized names).
        chain: Vec<String>,
        /// The type met a second time.
        again: String,
    },
    /// A fixed array larger than is read.
    #[error("field `{field}` of {message} is a fixed array of {len} elements (at most {max} are read)", max = MAX_FIXED)]
    FixedTooLong {
        /// The field's name.
        field: String,
        /// The type it is a field of.
        message: String,
        /// The declared number of elements.
        len: usize,
    },
    /// A field's type is not among the definition's types.
    #[error("field `{field}` of {message} is of type {type_name}, which the bag's definition does not include")]
    Undefined {
        /// The field's name.
        field: String,
        /// The type it is a field of.
        message: String,
        /// The missing type's full name.
        type_name: String,
    },
}

/// Why a field path does not name a number in every message of a type.
/// `at` is the path up to (not including) the step that fails, or the
/// whole path when it ends on something else than a number.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum FieldError {
    /// A message has no field of that name.
    #[error("no field `{name}` in {} ({message}: fields {})", here(at), if fields.is_empty() { "none".to_string() } else { fields.join(", ") })]
    NoField {
        /// The name written.
        name: String,
        /// The path to the message (empty: the whole message).
        at: String,
        /// The message's type.
        message: String,
        /// Its fields.
        fields: Vec<String>,
    },
    /// An index past the end of a fixed array.
    #[error(
        "index {index} is past the end of {} (a fixed array of {len})",
        here(at)
    )]
    PastEnd {
        /// The index written.
        index: usize,
        /// The path to the array.
        at: String,
        /// The array's size.
        len: usize,
    },
    /// A field of a number, string or bool.
    #[error("{} is a {scalar}, it has no field `{name}`", here(at))]
    ScalarHasNoField {
        /// The path to the scalar.
        at: String,
        /// Its type (`float64`, `string`, ...).
        scalar: &'static str,
        /// The field written.
        name: String,
    },
    /// A field of an array, without an index first.
    #[error(
        "{} is an array: pick an element before `.{name}` (e.g. `{at}[0].{name}`)",
        here(at)
    )]
    ArrayNeedsIndex {
        /// The path to the array.
        at: String,
        /// The field written.
        name: String,
    },
    /// An index into something that is not an array.
    #[error("{} is not an array, `[{index}]` does not apply", here(at))]
    NotArray {
        /// The path to it.
        at: String,
        /// The index written.
        index: usize,
    },
    /// The path ends on a string or bool.
    #[error("`{at}` is a {scalar}, not a number")]
    NotNumber {
        /// The path.
        at: String,
        /// Its type (`string`, `bool`, ...).
        scalar: &'static str,
    },
    /// The path ends on a message.
    #[error("`{at}` is a message ({message}), not a number: pick one of its fields ({})", fields.join(", "))]
    Message {
        /// The path.
        at: String,
        /// The message's type.
        message: String,
        /// Its fields.
        fields: Vec<String>,
    },
    /// The path ends on an array.
    #[error("`{at}` is an array, not a number: pick an element (e.g. `{at}[0]`)")]
    Array {
        /// The path.
        at: String,
    },
}

/// Why a message's bytes do not decode.
#[derive(Debug, thiserror::Error)]
pub enum DecodeError {
    /// Shorter than the encapsulation header.
    #[error("{len} bytes: too short for CDR (a 4-byte encapsulation header comes first)")]
    TooShort {
        /// The message's length, bytes.
        len: usize,
    },
    /// An encapsulation other than plain CDR.
    #[error("CDR representation 0x{code:04x} is not read (plain CDR is: 0x0000, 0x0001, what ROS 2 writes)")]
    Representation {
        /// The header's first two bytes, big-endian.
        code: u16,
    },
    /// The bytes end inside the message.
    #[error(
        "its {len} bytes end before the message does: a truncated message, or not a {message}"
    )]
    Truncated {
        /// The message's length, bytes.
        len: usize,
        /// Its type.
        message: String,
    },
    /// Any other CDR error (a bad bool, char or string).
    #[error("not a CDR {message}: {source}")]
    Cdr {
        /// The message's type.
        message: String,
        /// What the CDR reader found.
        #[source]
        source: re_cdr::Error,
    },
}

/// Why a decoded message has no number at a (resolved) field path.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub(crate) enum ValueError {
    /// A sequence shorter than the index.
    #[error("`{at}` has {len} elements in this message, no [{index}]")]
    TooFew {
        /// The path to the sequence.
        at: String,
        /// Its length in this message.
        len: usize,
        /// The index written.
        index: usize,
    },
    /// Something else than a number there.
    #[error("`{path}` is not a number")]
    NotNumber {
        /// The whole path as written.
        path: String,
    },
    /// Nothing there.
    #[error("`{path}` is not in this message")]
    Missing {
        /// The whole path as written.
        path: String,
    },
}

#[cfg(test)]
pub(crate) mod tests {
    //! Every error's text, exactly as users read it (the bag tests and the
    //! bad-input corpus match parts of these).
    use super::*;
    use crate::sources::file::ros::msg::{number_at, Definition, FieldPath};

    pub(crate) const SEP: &str =
        "================================================================================";

    pub(crate) fn stamped() -> String {
        format!(
            "std_msgs/Header header\ngeometry_msgs/Twist twist\n{SEP}\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n{SEP}\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n{SEP}\nMSG: geometry_msgs/Twist\nVector3 linear\nVector3 angular\n{SEP}\nMSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n"
        )
    }

    #[test]
    fn definition_errors() {
        let e = Definition::parse("p/msg/A", &format!("B b\n{SEP}\nMSG: p/B\np/A a\n"))
            .err()
            .unwrap();
        assert!(matches!(e, DefinitionError::Recursive { .. }), "{e:?}");
        assert_eq!(
            e.to_string(),
            "the definition of p/A contains itself (p/A → p/B → p/A)"
        );
        let e = Definition::parse("p/msg/A", "float64[2000000] x\n")
            .err()
            .unwrap();
        assert_eq!(
            e.to_string(),
            "field `x` of p/msg/A is a fixed array of 2000000 elements (at most 1048576 are read)"
        );
        let e = Definition::parse("p/msg/A", "p/B b\n").err().unwrap();
        assert_eq!(
            e.to_string(),
            "field `b` of p/msg/A is of type p/B, which the bag's definition does not include"
        );
        let bad = "float64 x y z\n";
        let e = Definition::parse("p/msg/A", bad).err().unwrap();
        let DefinitionError::Syntax(text) = &e else {
            panic!("{e:?}")
        };
        let want = format!(
            "{:#}",
            re_ros_msg::MessageSchema::parse("p/msg/A", bad).unwrap_err()
        );
        assert_eq!(text, &want);
        assert_eq!(e.to_string(), want);
    }

    #[test]
    fn field_errors() {
        let d = Definition::parse("geometry_msgs/msg/TwistStamped", &stamped()).unwrap();
        let arrays = Definition::parse(
            "p/msg/A",
            &format!("float64[3] a\nB[] b\n{SEP}\nMSG: p/B\nfloat64 c\n"),
        )
        .unwrap();
        let empty =
            Definition::parse("p/msg/E", "uint8 structure_needs_at_least_one_member\n").unwrap();
        let cases: [(&Definition, &str, &str); 10] = [
            (&d, "q", "no field `q` in the message (geometry_msgs/msg/TwistStamped: fields header, twist)"),
            (&d, "twist.linear.w", "no field `w` in `twist.linear` (geometry_msgs/Vector3: fields x, y, z)"),
            (&empty, "x", "no field `x` in the message (p/msg/E: fields none)"),
            (&arrays, "a[5]", "index 5 is past the end of `a` (a fixed array of 3)"),
            (&d, "twist.linear.x.y", "`twist.linear.x` is a float64, it has no field `y`"),
            (&arrays, "b.c", "`b` is an array: pick an element before `.c` (e.g. `b[0].c`)"),
            (&d, "twist[0]", "`twist` is not an array, `[0]` does not apply"),
            (&d, "header.frame_id", "`header.frame_id` is a string, not a number"),
            (&d, "twist.linear", "`twist.linear` is a message (geometry_msgs/Vector3), not a number: pick one of its fields (x, y, z)"),
            (&arrays, "a", "`a` is an array, not a number: pick an element (e.g. `a[0]`)"),
        ];
        for (def, path, want) in cases {
            let e = def
                .resolve_number(&FieldPath::parse(path).unwrap())
                .unwrap_err();
            assert_eq!(e.to_string(), want, "{path}");
        }
        assert!(arrays
            .resolve_number(&FieldPath::parse("b[7].c").unwrap())
            .is_ok());
    }

    #[test]
    fn decode_errors() {
        let d = Definition::parse("p/msg/A", "float64 x\nbool b\n").unwrap();
        let cases: [(&[u8], &str); 4] = [
            (&[0, 1], "2 bytes: too short for CDR (a 4-byte encapsulation header comes first)"),
            (&[0x12, 0x34, 0, 0, 1], "CDR representation 0x1234 is not read (plain CDR is: 0x0000, 0x0001, what ROS 2 writes)"),
            (&[0, 1, 0, 0, 0, 0, 0, 0], "its 8 bytes end before the message does: a truncated message, or not a p/msg/A"),
            (&[0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 2], "not a CDR p/msg/A: invalid boolean value: 2"),
        ];
        for (data, want) in cases {
            let e = d.decode(data).unwrap_err();
            assert_eq!(e.to_string(), want, "{data:?}");
        }
        assert!(d.decode(&[0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1]).is_ok());
    }

    #[test]
    fn value_errors() {
        let d = Definition::parse(
            "p/msg/A",
            &format!("float64[] s\nbool[] f\nB[] m\n{SEP}\nMSG: p/B\nfloat64 c\n"),
        )
        .unwrap();
        // s = [1.5], f = [true], m = [].
        let mut data = vec![0, 1, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0];
        data.extend(1.5f64.to_le_bytes());
        data.extend([1, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0]);
        let v = d.decode(&data).unwrap();
        let at = |p: &str| number_at(&v, &FieldPath::parse(p).unwrap());
        assert_eq!(at("s[0]"), Ok(1.5));
        let cases = [
            ("s[3]", "`s` has 1 elements in this message, no [3]"),
            ("m[0].c", "`m` has 0 elements in this message, no [0]"),
            ("f[0]", "`f[0]` is not a number"),
            ("s.x", "`s.x` is not in this message"),
        ];
        for (path, want) in cases {
            assert_eq!(at(path).unwrap_err().to_string(), want, "{path}");
        }
    }
}
