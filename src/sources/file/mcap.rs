//! MCAP plan files: the messages of one JSON topic of a run log, by default
//! `/plan/command` (the ideal run's commands, one per ideal sample) or
//! `/sim/command` (what the physics applied, one per step while the plan
//! was in force, then a zero at its end). Each message is
//! `{"t": <s>, "segment": "<label>", "values": {"<input>": <number>, ...}}`;
//! the segment becomes the sample's label.

use crate::planner::PlanError;
use crate::sources::file::{At, Reader, Samples};
use crate::sources::json_numbers::{walk, Step};
use serde::Deserialize;
use std::collections::BTreeMap;

#[derive(Deserialize)]
struct Message {
    t: f64,
    #[serde(default)]
    segment: Option<String>,
    values: BTreeMap<String, Option<f64>>,
}

/// Read the messages of `topic` in a run log.
pub fn read(mut r: Reader<'_>, topic: &str) -> Result<Samples, PlanError> {
    let bytes = crate::sources::file::ros::read_bytes(r.file)?;
    let stream = mcap::MessageStream::new(&bytes)
        .map_err(|e| r.file_error(format!("not a readable MCAP file: {e}")))?;
    let names: Vec<String> = r.input_names().iter().map(|s| s.to_string()).collect();
    let mut topics: Vec<String> = Vec::new();
    let mut u = vec![0.0; names.len()];
    let mut k = 0usize;
    for msg in stream {
        let msg = msg.map_err(|e| r.file_error(format!("not a readable MCAP file: {e}")))?;
        if msg.channel.topic != topic {
            if !topics.contains(&msg.channel.topic) {
                topics.push(msg.channel.topic.clone());
            }
            continue;
        }
        let at = |what: String| At { line: None, what };
        let here = format!("topic `{topic}` message {k}");
        let text = std::str::from_utf8(&msg.data)
            .map_err(|_| r.error(&at(here.clone()), "not UTF-8 JSON"))?;
        let mut m: Message = serde_json::from_str(text)
            .map_err(|e| r.error(&at(here.clone()), format!("not a command message: {e}")))?;
        walk(text, &mut |path, _, v| match path {
            [Step::Key(key)] if key == "t" => m.t = v,
            [Step::Key(key), Step::Key(name)] if key == "values" => {
                if let Some(slot) = m.values.get_mut(name.as_ref()) {
                    *slot = Some(v);
                }
            }
            _ => {}
        });
        for key in m.values.keys() {
            if !names.contains(key) {
                return Err(r.error(
                    &at(format!("{here}, value `{key}`")),
                    format!(
                        "not an input of this model (its inputs: {}); was the log written for another model?",
                        names.join(", ")
                    ),
                ));
            }
        }
        for (i, name) in names.iter().enumerate() {
            u[i] = match m.values.get(name) {
                Some(Some(v)) => *v,
                // Logs write non-finite numbers as null.
                Some(None) => f64::NAN,
                None => {
                    return Err(r.error(
                        &at(here.clone()),
                        format!(
                            "no value `{name}` (the model's inputs: {})",
                            names.join(", ")
                        ),
                    ))
                }
            };
        }
        let t_at = at(format!("{here}, `t`"));
        let u_at = |i: usize| at(format!("{here}, value `{}`", names[i]));
        r.push(m.t, &t_at, &u, &u_at, m.segment.as_deref())?;
        k += 1;
    }
    if k == 0 {
        return Err(r.file_error(format!(
            "no messages on topic `{topic}` (topics: {})",
            if topics.is_empty() {
                "none".to_string()
            } else {
                topics.join(", ")
            }
        )));
    }
    r.finish()
}
