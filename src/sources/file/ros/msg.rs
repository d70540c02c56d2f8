//! ROS 2 messages through the definition a bag stores with each channel
//! (the `ros2msg` schema: the type's `.msg` text followed by those of the
//! types it uses): parsed by `re_ros_msg`, CDR decoded by it with
//! `re_cdr`, numbers picked by field paths (`twist.linear.x`,
//! `wheel_speeds[1]`) resolved against the definition before any message
//! is read. No type is built in: any message of numbers, nested messages,
//! arrays and strings decodes.

use re_ros_msg::deserialize::{decode_message, TypeResolver, Value};
use re_ros_msg::message_spec::{ArraySize, BuiltInType, ComplexType, MessageSpecification, Type};
use re_ros_msg::MessageSchema;
use std::collections::HashMap;

pub use crate::sources::file::ros::error::{DecodeError, DefinitionError, FieldError};
use crate::sources::file::ros::error::{ValueError, MAX_FIXED};

/// `pkg/msg/Type` and `pkg/Type` name the same type.
pub(crate) fn normalize(name: &str) -> String {
    match name.split('/').collect::<Vec<_>>().as_slice() {
        [pkg, "msg", ty] => format!("{pkg}/{ty}"),
        _ => name.to_string(),
    }
}

/// One step of a field path.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Step {
    /// A field of a message.
    Field(String),
    /// An element of an array or sequence.
    Index(usize),
}

/// A field path: `a.b[2].c`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FieldPath {
    /// As written.
    pub text: String,
    /// Its steps.
    pub steps: Vec<Step>,
}

/// What is wrong with a written field path.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum FieldPathError {
    /// Nothing (or only blanks) was written.
    #[error("an empty field path (write e.g. `twist.linear.x`)")]
    Empty,
    /// A name is empty or holds other characters than letters, digits and `_`.
    #[error(
        "`{0}` is not a field path (names of letters, digits and `_`, joined by `.`, each optionally followed by `[index]`)"
    )]
    NotPath(String),
    /// An index without its brackets.
    #[error("`{0}`: an index is written `[2]`")]
    Bracket(String),
    /// Brackets around something other than a whole number.
    #[error("`{text}`: `{index}` is not an index")]
    NotIndex {
        /// The path as written.
        text: String,
        /// What the brackets hold.
        index: String,
    },
}

impl FieldPath {
    /// Parse `a.b[2].c`; the error says what is wrong with it.
    pub fn parse(text: &str) -> Result<FieldPath, FieldPathError> {
        let mut steps = Vec::new();
        if text.trim().is_empty() {
            return Err(FieldPathError::Empty);
        }
        for part in text.split('.') {
            let (name, mut rest) = match part.find('[') {
                Some(i) => (&part[..i], &part[i..]),
                None => (part, ""),
            };
            let ok = |c: char| c.is_ascii_alphanumeric() || c == '_';
            if name.is_empty() || !name.chars().all(ok) {
                return Err(FieldPathError::NotPath(text.to_string()));
            }
            steps.push(Step::Field(name.to_string()));
            while !rest.is_empty() {
                let close = rest.find(']').filter(|_| rest.starts_with('['));
                let Some(close) = close else {
                    return Err(FieldPathError::Bracket(text.to_string()));
                };
                let i: usize = rest[1..close]
                    .parse()
                    .map_err(|_| FieldPathError::NotIndex {
                        text: text.to_string(),
                        index: rest[1..close].to_string(),
                    })?;
                steps.push(Step::Index(i));
                rest = &rest[close + 1..];
            }
        }
        Ok(FieldPath {
            text: text.to_string(),
            steps,
        })
    }
}

/// A message type's definition as a bag stores it, checked: every type it
/// uses is defined, none contains itself, fixed arrays are of sane size.
pub struct Definition {
    schema: MessageSchema,
    /// Normalized name → index into `schema.dependencies`.
    names: HashMap<String, usize>,
}

/// Resolves the types a definition uses, by either spelling of their names.
struct Resolver<'a>(&'a Definition);

impl TypeResolver for Resolver<'_> {
    fn resolve(
        &self,
        scope: &MessageSpecification,
        ty: &ComplexType,
    ) -> Option<&MessageSpecification> {
        self.0.resolve(scope, ty)
    }
}

fn type_name(scope: &MessageSpecification, ty: &ComplexType) -> String {
    match ty {
        ComplexType::Absolute { package, name } => normalize(&format!("{package}/{name}")),
        ComplexType::Relative { name } => match scope.name.split_once('/') {
            Some((pkg, _)) => format!("{pkg}/{name}"),
            None => name.clone(),
        },
    }
}

fn builtin_name(b: &BuiltInType) -> &'static str {
    match b {
        BuiltInType::Bool => "bool",
        BuiltInType::Byte => "byte",
        BuiltInType::Char => "char",
        BuiltInType::Float32 => "float32",
        BuiltInType::Float64 => "float64",
        BuiltInType::Int8 => "int8",
        BuiltInType::Int16 => "int16",
        BuiltInType::Int32 => "int32",
        BuiltInType::Int64 => "int64",
        BuiltInType::UInt8 => "uint8",
        BuiltInType::UInt16 => "uint16",
        BuiltInType::UInt32 => "uint32",
        BuiltInType::UInt64 => "uint64",
        BuiltInType::String(_) => "string",
        BuiltInType::WString(_) => "wstring",
    }
}

fn is_number(b: &BuiltInType) -> bool {
    !matches!(
        b,
        BuiltInType::Bool | BuiltInType::String(_) | BuiltInType::WString(_)
    )
}

/// What a field path ends on, for messages.
enum Leaf<'a> {
    Scalar(&'a BuiltInType),
    Message(&'a MessageSpecification),
    /// The element type, and the size when fixed.
    Array(&'a Type, Option<usize>),
}

impl Definition {
    /// Parse and check the definition of type `name` (`pkg/msg/Type`).
    pub fn parse(name: &str, text: &str) -> Result<Definition, DefinitionError> {
        // The parser's error is anyhow's: kept as it prints, with its causes.
        let schema = MessageSchema::parse(name, text)
            .map_err(|e| DefinitionError::Syntax(format!("{e:#}")))?;
        let names = schema
            .dependencies
            .iter()
            .enumerate()
            .map(|(i, d)| (normalize(&d.name), i))
            .collect();
        let def = Definition { schema, names };
        def.check(&def.schema.spec, &mut Vec::new())?;
        Ok(def)
    }

    /// The type's name as the bag gives it.
    pub fn name(&self) -> &str {
        &self.schema.spec.name
    }

    fn resolve(
        &self,
        scope: &MessageSpecification,
        ty: &ComplexType,
    ) -> Option<&MessageSpecification> {
        let full = type_name(scope, ty);
        self.names
            .get(&full)
            .map(|&i| &self.schema.dependencies[i])
            .or_else(|| (normalize(&self.schema.spec.name) == full).then_some(&self.schema.spec))
    }

    /// Every type `spec` uses is defined and none contains itself.
    fn check(
        &self,
        spec: &MessageSpecification,
        stack: &mut Vec<String>,
    ) -> Result<(), DefinitionError> {
        let me = normalize(&spec.name);
        if stack.contains(&me) {
            return Err(DefinitionError::Recursive {
                chain: stack.clone(),
                again: me,
            });
        }
        stack.push(me);
        for f in &spec.fields {
            let mut ty = &f.ty;
            while let Type::Array { ty: inner, size } = ty {
                if let ArraySize::Fixed(n) = size {
                    if *n > MAX_FIXED {
                        return Err(DefinitionError::FixedTooLong {
                            field: f.name.clone(),
                            message: spec.name.clone(),
                            len: *n,
                        });
                    }
                }
                ty = inner;
            }
            if let Type::Complex(c) = ty {
                let Some(inner) = self.resolve(spec, c) else {
                    return Err(DefinitionError::Undefined {
                        field: f.name.clone(),
                        message: spec.name.clone(),
                        type_name: type_name(spec, c),
                    });
                };
                self.check(inner, stack)?;
            }
        }
        stack.pop();
        Ok(())
    }

    fn leaf<'a>(&'a self, scope: &'a MessageSpecification, ty: &'a Type) -> Leaf<'a> {
        match ty {
            Type::BuiltIn(b) => Leaf::Scalar(b),
            Type::Array { ty, size } => Leaf::Array(
                ty,
                match size {
                    ArraySize::Fixed(n) => Some(*n),
                    _ => None,
                },
            ),
            Type::Complex(c) => {
                let spec = self.resolve(scope, c).expect("checked");
                match spec.underlying_type_if_enum_like() {
                    Ok(Some(b)) => Leaf::Scalar(b),
                    _ => Leaf::Message(spec),
                }
            }
        }
    }

    /// Check that `path` names a number in every message of this type;
    /// the error says what is there instead.
    pub fn resolve_number(&self, path: &FieldPath) -> Result<(), FieldError> {
        let mut scope = &self.schema.spec;
        let mut leaf = Leaf::Message(scope);
        let mut at = String::new();
        for step in &path.steps {
            leaf = match (step, leaf) {
                (Step::Field(name), Leaf::Message(spec)) => {
                    let Some(f) = spec.fields.iter().find(|f| &f.name == name) else {
                        // The placeholder member of an empty IDL struct is no field to offer.
                        let fields = spec
                            .fields
                            .iter()
                            .map(|f| f.name.clone())
                            .filter(|n| n != "structure_needs_at_least_one_member")
                            .collect();
                        return Err(FieldError::NoField {
                            name: name.clone(),
                            at,
                            message: spec.name.clone(),
                            fields,
                        });
                    };
                    scope = spec;
                    self.leaf(scope, &f.ty)
                }
                (Step::Index(i), Leaf::Array(elem, fixed)) => {
                    if let Some(n) = fixed {
                        if *i >= n {
                            return Err(FieldError::PastEnd {
                                index: *i,
                                at,
                                len: n,
                            });
                        }
                    }
                    self.leaf(scope, elem)
                }
                (Step::Field(name), Leaf::Scalar(b)) => {
                    return Err(FieldError::ScalarHasNoField {
                        at,
                        scalar: builtin_name(b),
                        name: name.clone(),
                    })
                }
                (Step::Field(name), Leaf::Array(..)) => {
                    return Err(FieldError::ArrayNeedsIndex {
                        at,
                        name: name.clone(),
                    })
                }
                (Step::Index(i), _) => return Err(FieldError::NotArray { at, index: *i }),
            };
            match step {
                Step::Field(n) if at.is_empty() => at = n.clone(),
                Step::Field(n) => at = format!("{at}.{n}"),
                Step::Index(i) => at = format!("{at}[{i}]"),
            }
        }
        match leaf {
            Leaf::Scalar(b) if is_number(b) => Ok(()),
            Leaf::Scalar(b) => Err(FieldError::NotNumber {
                at,
                scalar: builtin_name(b),
            }),
            Leaf::Message(spec) => Err(FieldError::Message {
                at,
                message: spec.name.clone(),
                fields: spec.fields.iter().map(|f| f.name.clone()).collect(),
            }),
            Leaf::Array(..) => Err(FieldError::Array { at }),
        }
    }

    /// Decode one CDR message (with its 4-byte encapsulation header).
    pub fn decode(&self, data: &[u8]) -> Result<Value, DecodeError> {
        if data.len() < 4 {
            return Err(DecodeError::TooShort { len: data.len() });
        }
        let resolver = Resolver(self);
        let body = &data[4..];
        let spec = &self.schema.spec;
        let out = match [data[0], data[1]] {
            [0, 0] => decode_message(
                &mut re_cdr::CdrReader::<re_cdr::BigEndian>::new(body),
                spec,
                &resolver,
            ),
            [0, 1] => decode_message(
                &mut re_cdr::CdrReader::<re_cdr::LittleEndian>::new(body),
                spec,
                &resolver,
            ),
            [a, b] => {
                return Err(DecodeError::Representation {
                    code: u16::from_be_bytes([a, b]),
                })
            }
        };
        out.map_err(|e| match e {
            re_cdr::Error::UnexpectedEof => DecodeError::Truncated {
                len: data.len(),
                message: spec.name.clone(),
            },
            source => DecodeError::Cdr {
                message: spec.name.clone(),
                source,
            },
        })
    }
}

/// The number at `path` in a decoded message (checked with
/// [`Definition::resolve_number`], so only a sequence's length can make it
/// missing).
pub(crate) fn number_at(v: &Value, path: &FieldPath) -> Result<f64, ValueError> {
    use re_ros_msg::deserialize::primitive_array::PrimitiveArray as P;
    let missing = || ValueError::Missing {
        path: path.text.clone(),
    };
    let not_number = || ValueError::NotNumber {
        path: path.text.clone(),
    };
    let mut v = v;
    let mut at = String::new();
    let mut element: Option<f64> = None;
    for step in &path.steps {
        let next = match (step, v) {
            (Step::Field(name), Value::Message(m)) => m.get(name),
            (Step::Index(i), Value::Array(a) | Value::Sequence(a)) => {
                let got = a.get(*i);
                if got.is_none() {
                    return Err(ValueError::TooFew {
                        at,
                        len: a.len(),
                        index: *i,
                    });
                }
                got
            }
            (Step::Index(i), Value::PrimitiveArray(p) | Value::PrimitiveSeq(p)) => {
                let x = match p {
                    P::I8(x) => x.get(*i).map(|&x| x as f64),
                    P::U8(x) => x.get(*i).map(|&x| x as f64),
                    P::I16(x) => x.get(*i).map(|&x| x as f64),
                    P::U16(x) => x.get(*i).map(|&x| x as f64),
                    P::I32(x) => x.get(*i).map(|&x| x as f64),
                    P::U32(x) => x.get(*i).map(|&x| x as f64),
                    P::I64(x) => x.get(*i).map(|&x| x as f64),
                    P::U64(x) => x.get(*i).map(|&x| x as f64),
                    P::F32(x) => x.get(*i).map(|&x| x as f64),
                    P::F64(x) => x.get(*i).copied(),
                    P::Bool(_) | P::String(_) => None,
                };
                let len = match p {
                    P::Bool(x) => x.len(),
                    P::I8(x) => x.len(),
                    P::U8(x) => x.len(),
                    P::I16(x) => x.len(),
                    P::U16(x) => x.len(),
                    P::I32(x) => x.len(),
                    P::U32(x) => x.len(),
                    P::I64(x) => x.len(),
                    P::U64(x) => x.len(),
                    P::F32(x) => x.len(),
                    P::F64(x) => x.len(),
                    P::String(x) => x.len(),
                };
                match x {
                    Some(x) => {
                        element = Some(x);
                        None
                    }
                    None if *i >= len => return Err(ValueError::TooFew { at, len, index: *i }),
                    None => return Err(not_number()),
                }
            }
            _ => return Err(missing()),
        };
        match step {
            Step::Field(n) if at.is_empty() => at = n.clone(),
            Step::Field(n) => at = format!("{at}.{n}"),
            Step::Index(i) => at = format!("{at}[{i}]"),
        }
        if let Some(x) = element {
            return Ok(x);
        }
        v = next.ok_or_else(missing)?;
    }
    Ok(match v {
        Value::I8(x) => *x as f64,
        Value::U8(x) => *x as f64,
        Value::I16(x) => *x as f64,
        Value::U16(x) => *x as f64,
        Value::I32(x) => *x as f64,
        Value::U32(x) => *x as f64,
        Value::I64(x) => *x as f64,
        Value::U64(x) => *x as f64,
        Value::F32(x) => *x as f64,
        Value::F64(x) => *x,
        _ => return Err(not_number()),
    })
}

/// The integer at `path` (a header stamp's `sec` or `nanosec`), exactly.
pub(crate) fn integer_at(v: &Value, path: &FieldPath) -> Option<i64> {
    let mut v = v;
    for step in &path.steps {
        v = match (step, v) {
            (Step::Field(name), Value::Message(m)) => m.get(name)?,
            _ => return None,
        };
    }
    match v {
        Value::I32(x) => Some(*x as i64),
        Value::U32(x) => Some(*x as i64),
        Value::I64(x) => Some(*x),
        Value::U64(x) => i64::try_from(*x).ok(),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TWIST_STAMPED: &str = "std_msgs/Header header\ngeometry_msgs/Twist twist\n================================================================================\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n================================================================================\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n================================================================================\nMSG: geometry_msgs/Twist\nVector3 linear\nVector3 angular\n================================================================================\nMSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n";

    #[test]
    fn field_paths_parse() {
        let p = FieldPath::parse("a.b[2][3].c_1").unwrap();
        assert_eq!(
            p.steps,
            vec![
                Step::Field("a".into()),
                Step::Field("b".into()),
                Step::Index(2),
                Step::Index(3),
                Step::Field("c_1".into())
            ]
        );
        for bad in ["", "a..b", "a.", "a[", "a[x]", "a]", "a b", "[1]"] {
            assert!(FieldPath::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn paths_resolve_against_the_definition() {
        let d = Definition::parse("geometry_msgs/msg/TwistStamped", TWIST_STAMPED).unwrap();
        let ok = |p: &str| d.resolve_number(&FieldPath::parse(p).unwrap());
        assert!(ok("twist.linear.x").is_ok());
        assert!(ok("header.stamp.nanosec").is_ok());
        let e = ok("twist.linear.w").unwrap_err().to_string();
        assert!(
            e.contains("no field `w` in `twist.linear`") && e.contains("x, y, z"),
            "{e}"
        );
        let e = ok("header.frame_id").unwrap_err().to_string();
        assert!(e.contains("is a string, not a number"), "{e}");
        let e = ok("twist.linear").unwrap_err().to_string();
        assert!(e.contains("is a message"), "{e}");
        let e = ok("twist[0]").unwrap_err().to_string();
        assert!(e.contains("not an array"), "{e}");
    }

    #[test]
    fn a_definition_that_lacks_a_type_or_contains_itself_is_refused() {
        let e = Definition::parse("p/msg/A", "p/B b\n").err().unwrap();
        assert!(matches!(e, DefinitionError::Undefined { .. }), "{e:?}");
        let e = e.to_string();
        assert!(
            e.contains("p/B, which the bag's definition does not include"),
            "{e}"
        );
        let e = Definition::parse(
            "p/msg/A",
            "B b\n================================================================================\nMSG: p/B\np/A a\n",
        )
        .err()
        .unwrap();
        assert!(matches!(e, DefinitionError::Recursive { .. }), "{e:?}");
        assert!(e.to_string().contains("contains itself"), "{e}");
    }

    #[test]
    fn normalized_names() {
        assert_eq!(normalize("std_msgs/msg/Header"), "std_msgs/Header");
        assert_eq!(normalize("std_msgs/Header"), "std_msgs/Header");
    }
}
