//! The line protocol between the harness and an external feedback law.
//!
//! One JSON object per line each way, one exchange per control sample:
//!
//! * harness → law: `{"t":0.0,"q":[...],"names":["x","y",...]}` on the
//!   first sample of a run (`names`: the state coordinates, in the order of
//!   `q`), `{"t":0.02,"q":[...]}` after. Numbers are written in their
//!   shortest form that reads back exactly (non-finite ones as `null`), so
//!   the stream is byte for byte the same on every run of a deterministic
//!   setup.
//! * law → harness: `{"u":[...],"label":"...","done":false}`: `u` (one
//!   number per model input) is required, `label` (default `external`) and
//!   `done` (default false: true ends the run) are optional, other keys are
//!   refused.

use crate::model::Input;
use crate::plan::{Command, LabelTable};
use crate::sources::json_numbers::{walk, Step};
use serde::{Deserialize, Serialize};

/// Label of commands whose answer names none.
pub const DEFAULT_LABEL: &str = "external";
/// Longest label, bytes.
pub const MAX_LABEL_BYTES: usize = 200;
/// Most distinct labels one law may use.
pub const MAX_LABELS: usize = 1000;

#[derive(Serialize)]
struct Request<'a> {
    t: f64,
    q: &'a [f64],
    #[serde(skip_serializing_if = "Option::is_none")]
    names: Option<&'a [&'a str]>,
}

/// Append the request line for sample time `t` and state `q` (with the
/// state `names` on a run's first sample) to `buf`, newline included.
pub(crate) fn write_request(buf: &mut Vec<u8>, t: f64, q: &[f64], names: Option<&[&str]>) {
    // Serializing plain numbers and strings cannot fail.
    let _ = serde_json::to_writer(&mut *buf, &Request { t, q, names });
    buf.push(b'\n');
}

/// A law's answer, checked against the model's inputs.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Answer {
    /// The input vector.
    pub u: Vec<f64>,
    /// The law's name for what it is doing.
    #[serde(default)]
    pub label: Option<String>,
    /// The law considers the task complete.
    #[serde(default)]
    pub done: bool,
}

/// At most this much of a bad answer is quoted in a message.
const QUOTE: usize = 120;

/// `line` shortened for a message.
pub fn quote(line: &str) -> String {
    let line = line.trim_end();
    if line.len() <= QUOTE {
        return format!("`{line}`");
    }
    let mut end = QUOTE;
    while !line.is_char_boundary(end) {
        end -= 1;
    }
    format!("`{}`... ({} bytes)", &line[..end], line.len())
}

/// What is wrong with a law's answer line (for the law's author).
#[derive(Debug, thiserror::Error)]
pub enum AnswerError {
    /// The line is not UTF-8.
    #[error("the answer is not UTF-8")]
    NotUtf8,
    /// The line is empty or blank.
    #[error("the answer is an empty line (expected {{\"u\": [...]}})")]
    Empty,
    /// The line is not the answer's JSON object.
    #[error(
        "the answer is not a JSON object {{\"u\": [...], \"label\": ..., \"done\": ...}}: {error}{hint}: {}",
        quote(text)
    )]
    NotJson {
        /// The JSON parser's error.
        error: serde_json::Error,
        /// A hint for NaN or Infinity, or empty.
        hint: &'static str,
        /// The line.
        text: String,
    },
    /// `u` has another length than the model's inputs.
    #[error(
        "the answer has {got} number{} in `u`, the model has {inputs} input{} ({names})",
        plural(*got),
        plural(*inputs)
    )]
    Count {
        /// Numbers in `u`.
        got: usize,
        /// The model's inputs.
        inputs: usize,
        /// Their names, comma-separated.
        names: String,
    },
    /// The label is over [`MAX_LABEL_BYTES`].
    #[error("the answer's label is {0} bytes long (at most {MAX_LABEL_BYTES})")]
    LabelLong(usize),
    /// The law used more than [`MAX_LABELS`] distinct labels.
    #[error("the law used more than {MAX_LABELS} distinct labels (`{0}` is one too many)")]
    TooManyLabels(String),
}

/// `"s"` unless `n` is 1.
fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}

impl Answer {
    /// Parse one answer line (without its newline) for a model with
    /// `input_names`: the message says what is wrong, for the law's author.
    pub fn parse(line: &[u8], input_names: &[&str]) -> Result<Answer, AnswerError> {
        let text = std::str::from_utf8(line).map_err(|_| AnswerError::NotUtf8)?;
        if text.trim().is_empty() {
            return Err(AnswerError::Empty);
        }
        let mut a: Answer = serde_json::from_str(text).map_err(|error| {
            let hint = if text.contains("NaN") || text.contains("Infinity") {
                " (NaN and Infinity are not JSON: u must be finite)"
            } else {
                ""
            };
            AnswerError::NotJson {
                error,
                hint,
                text: text.to_string(),
            }
        })?;
        // Exact values (serde_json's own can be 1 ulp off).
        let n = a.u.len();
        walk(text, &mut |path, _, v| {
            if let [Step::Key(k), Step::Index(i)] = path {
                if k == "u" && *i < n {
                    a.u[*i] = v;
                }
            }
        });
        let m = input_names.len();
        if a.u.len() != m {
            return Err(AnswerError::Count {
                got: a.u.len(),
                names: input_names.join(", "),
                inputs: m,
            });
        }
        if let Some(l) = &a.label {
            if l.len() > MAX_LABEL_BYTES {
                return Err(AnswerError::LabelLong(l.len()));
            }
        }
        Ok(a)
    }

    /// The command, with the label interned in `labels`.
    pub fn command(&self, labels: &LabelTable) -> Result<Command, AnswerError> {
        let name = self.label.as_deref().unwrap_or(DEFAULT_LABEL);
        let label = labels
            .intern(name, MAX_LABELS)
            .ok_or_else(|| AnswerError::TooManyLabels(name.to_string()))?;
        Ok(Command {
            u: Input::from_column_slice(&self.u),
            label,
            done: self.done,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_are_compact_and_exact() {
        let mut b = Vec::new();
        write_request(&mut b, 0.0, &[0.1, -2.0, f64::NAN], Some(&["x", "y", "th"]));
        write_request(&mut b, 0.02, &[1.0 / 3.0, 1e-300, 2.5e20], None);
        assert_eq!(
            String::from_utf8(b).unwrap(),
            "{\"t\":0.0,\"q\":[0.1,-2.0,null],\"names\":[\"x\",\"y\",\"th\"]}\n\
             {\"t\":0.02,\"q\":[0.3333333333333333,1e-300,2.5e+20]}\n"
        );
    }

    #[test]
    fn answers_are_checked() {
        let names = ["v", "w"];
        let a = Answer::parse(
            br#"{"u": [0.1, 0.30000000000000004], "label": "go", "done": true}"#,
            &names,
        )
        .unwrap();
        assert_eq!(a.u[1].to_bits(), (0.1f64 + 0.2).to_bits());
        assert_eq!((a.label.as_deref(), a.done), (Some("go"), true));
        let d = Answer::parse(br#"{"u":[1,2]}"#, &names).unwrap();
        assert_eq!((d.label, d.done), (None, false));
        let err = |line: &str| {
            Answer::parse(line.as_bytes(), &names)
                .unwrap_err()
                .to_string()
        };
        assert!(err(r#"{"u": [1]}"#).contains("has 1 number in `u`, the model has 2 inputs (v, w)"));
        assert!(err("hello").contains("not a JSON object"));
        assert!(err(r#"{"u": [NaN, 1]}"#).contains("NaN and Infinity are not JSON"));
        assert!(err(r#"{"u": [1, 2], "dome": true}"#).contains("unknown field `dome`"));
        assert!(err(r#"{"u": [1, null]}"#).contains("null"));
        assert!(err("").contains("empty line"));
        let long = format!(r#"{{"u": [1, 2], "label": "{}"}}"#, "x".repeat(300));
        assert!(err(&long).contains("300 bytes long"));
    }

    #[test]
    fn labels_are_interned_and_bounded() {
        let t = LabelTable::default();
        let a = |l: &str| Answer {
            u: vec![0.0],
            label: Some(l.into()),
            done: false,
        };
        assert_eq!(a("b").command(&t).unwrap().label, 0);
        assert_eq!(a("c").command(&t).unwrap().label, 1);
        assert_eq!(a("b").command(&t).unwrap().label, 0);
        for i in 0..MAX_LABELS - 2 {
            a(&format!("l{i}")).command(&t).unwrap();
        }
        assert!(a("one more").command(&t).is_err());
        assert_eq!(t.names()[..2], ["b".to_string(), "c".to_string()]);
    }
}
