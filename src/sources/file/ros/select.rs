//! One element of a message's array, chosen by a string field: a tf
//! message (`tf2_msgs/msg/TFMessage`) carries several transforms, and a
//! recorded trajectory is the one whose `child_frame_id` names the robot's
//! frame. Field paths are then written inside that element
//! (`transform.translation.x`); a message without such an element is not
//! a sample of the trajectory.

use crate::sources::file::ros::msg::{FieldPath, FieldPathError, Step};
use re_ros_msg::deserialize::Value;

/// The element of `array` whose string field `key` is `value`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Select<'a> {
    /// The array's field path in the message (`transforms`).
    pub array: &'a str,
    /// The element's string field that names it (`child_frame_id`).
    pub key: &'a str,
    /// The name wanted (`base_link`).
    pub value: &'a str,
}

impl Select<'_> {
    /// The path inside an element as a path in the whole message (element 0
    /// stands for every element: the definition is the same).
    pub fn whole(&self, inside: &FieldPath) -> Result<FieldPath, FieldPathError> {
        FieldPath::parse(&format!("{}[0].{}", self.array, inside.text))
    }

    /// The chosen element of a decoded message, if it has one.
    pub fn element<'v>(&self, message: &'v Value) -> Option<&'v Value> {
        let path = FieldPath::parse(self.array).ok()?;
        let mut v = message;
        for step in &path.steps {
            v = match (step, v) {
                (Step::Field(name), Value::Message(m)) => m.get(name)?,
                (Step::Index(i), Value::Array(a) | Value::Sequence(a)) => a.get(*i)?,
                _ => return None,
            };
        }
        let (Value::Array(items) | Value::Sequence(items)) = v else {
            return None;
        };
        items.iter().find(|e| match e {
            Value::Message(m) => {
                matches!(m.get(self.key), Some(Value::String(s)) if s == self.value)
            }
            _ => false,
        })
    }

    /// What a message must hold, for messages (` with `child_frame_id` = "base_link"`).
    pub fn describe(&self) -> String {
        format!(
            " with an element of `{}` whose `{}` is \"{}\"",
            self.array, self.key, self.value
        )
    }
}
