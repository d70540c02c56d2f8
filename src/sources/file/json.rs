//! JSON plan files: `{"t": [...], "u": {"<input>": [...], ...}}`, with an
//! optional `"label": [...]` of strings; every array as long as `t`.
//! serde_json checks the structure; the numbers are then read again
//! exactly ([`crate::sources::json_numbers`]).

use crate::planner::PlanError;
use crate::sources::file::{At, Reader, Samples, TEXT_MAX_BYTES};
use crate::sources::json_numbers::{line_at, walk, Step};
use serde::Deserialize;
use std::collections::BTreeMap;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JsonPlan {
    t: Vec<f64>,
    u: BTreeMap<String, Vec<f64>>,
    #[serde(default)]
    label: Option<Vec<String>>,
}

/// The plan file as text (a regular file within the size cap, UTF-8).
pub(super) fn read_text(r: &Reader<'_>) -> Result<String, PlanError> {
    let text =
        crate::input::read_text(r.file, "plan file", TEXT_MAX_BYTES).map_err(|e| match e {
            crate::error::Error::Input {
                key: None,
                path,
                line,
                message,
            } => PlanError::file(path, line, message),
            other => r.file_error(other),
        })?;
    // A UTF-8 byte order mark (spreadsheets write one) is not part of the
    // first column's name: dropped.
    Ok(match text.strip_prefix('\u{feff}') {
        Some(rest) => rest.to_string(),
        None => text,
    })
}

/// Read a JSON plan file.
pub fn read(mut r: Reader<'_>) -> Result<Samples, PlanError> {
    let text = read_text(&r)?;
    if text.trim().is_empty() {
        return Err(
            r.file_error("empty file: expected {\"t\": [...], \"u\": {\"<input>\": [...]}}")
        );
    }
    let mut plan: JsonPlan = serde_json::from_str(&text).map_err(|e| {
        r.error(
            &At {
                line: Some(e.line()),
                what: String::new(),
            },
            e,
        )
    })?;
    let names: Vec<String> = r.input_names().iter().map(|s| s.to_string()).collect();
    for key in plan.u.keys() {
        if !names.contains(key) {
            return Err(r.error(
                &At {
                    line: line_of_key(&text, key),
                    what: format!("key `u.{key}`"),
                },
                format!(
                    "unknown input (the model's inputs: {}){}",
                    names.join(", "),
                    crate::sources::file::unknown_input_hint(key, &names)
                ),
            ));
        }
    }
    let n = plan.t.len();
    for name in &names {
        match plan.u.get(name) {
            None => {
                return Err(r.error(
                    &At {
                        line: line_of_key(&text, "u"),
                        what: "key `u`".into(),
                    },
                    format!(
                        "no input `{name}` (expected every one of {})",
                        names.join(", ")
                    ),
                ))
            }
            Some(v) if v.len() != n => {
                return Err(r.error(
                    &At {
                        line: line_of_key(&text, name),
                        what: format!("key `u.{name}`"),
                    },
                    format!("{} values, `t` has {n}", v.len()),
                ))
            }
            _ => {}
        }
    }
    if let Some(l) = &plan.label {
        if l.len() != n {
            return Err(r.error(
                &At {
                    line: line_of_key(&text, "label"),
                    what: "key `label`".into(),
                },
                format!("{} labels, `t` has {n}", l.len()),
            ));
        }
    }
    // Exact numbers, and the line of every value for messages.
    let mut t_line = vec![None; n];
    let mut u_line: BTreeMap<String, Vec<Option<usize>>> =
        names.iter().map(|k| (k.clone(), vec![None; n])).collect();
    let mut pos = (1, 0);
    walk(&text, &mut |path, offset, v| {
        pos = line_at(&text, pos, offset);
        match path {
            [Step::Key(k), Step::Index(i)] if k == "t" && *i < n => {
                plan.t[*i] = v;
                t_line[*i] = Some(pos.0);
            }
            [Step::Key(k), Step::Key(name), Step::Index(i)] if k == "u" && *i < n => {
                if let (Some(col), Some(lines)) =
                    (plan.u.get_mut(name.as_ref()), u_line.get_mut(name.as_ref()))
                {
                    col[*i] = v;
                    lines[*i] = Some(pos.0);
                }
            }
            _ => {}
        }
    });
    let mut u = vec![0.0; names.len()];
    for k in 0..n {
        for (i, name) in names.iter().enumerate() {
            u[i] = plan.u[name][k];
        }
        let at_u = |i: usize| At {
            line: u_line[&names[i]][k],
            what: format!("key `u.{}[{k}]`", names[i]),
        };
        let at_t = At {
            line: t_line[k],
            what: format!("key `t[{k}]`"),
        };
        let label = plan.label.as_ref().map(|l| l[k].as_str());
        r.push(plan.t[k], &at_t, &u, &at_u, label)?;
    }
    r.finish()
}

/// Line of the first `"key"` in `text` (good enough for a message).
fn line_of_key(text: &str, key: &str) -> Option<usize> {
    let needle = serde_json::to_string(key).ok()?;
    let at = text.find(&needle)?;
    Some(text[..at].matches('\n').count() + 1)
}
