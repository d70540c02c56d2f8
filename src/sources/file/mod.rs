//! `[planner] kind = "file"`: a plan read from a file, for any model.
//!
//! Three formats, chosen by the file's extension:
//!
//! * `.csv`: a header row `t` followed by the model's input names in any
//!   order (and optionally `label`), then one row per sample ([`csv`]);
//! * `.json`: `{"t": [...], "u": {"<input>": [...], ...}}`, optionally
//!   `"label": [...]` ([`json`]);
//! * `.mcap`: the `/plan/command` messages of another run's `run.mcap` (or
//!   another topic of the same form, `topic = "/sim/command"`), so a logged
//!   plan replays on a changed model or settings ([`mcap`]);
//! * a ROS 2 bag (rosbag2, MCAP storage): its directory (with
//!   `metadata.yaml`) or its `.mcap` file; one command topic's CDR messages,
//!   decoded through the definition the bag stores, give the inputs
//!   ([`ros`]).
//!
//! Every sample is checked before anything runs: `t` starts at 0 and
//! increases strictly, every value is finite, every input has a column and
//! no column is unknown; a bad value is reported at its file, row (line) and
//! column. The last sample's `t` is the plan's duration. Between samples u
//! is held (`hold = "zero_order"`, the default: u(t) = u_i on [t_i,
//! t_{i+1}), a jump at every change) or interpolated (`hold = "linear"`).
//! The ideal run integrates the held u exactly (its steps are split at the
//! jumps); the physics applies u at each step's midpoint, so samples on the
//! `sim.dt` grid make both runs apply the same value over every step.

pub mod csv;
pub mod json;
pub mod mcap;
pub mod ros;

use crate::error::SetupError;
use crate::model::Input;
use crate::plan::{ControlLaw, Plan, Segment};
use crate::planner::PlanError;
pub use ros::BagTime;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Largest CSV or JSON plan file read, bytes.
pub const TEXT_MAX_BYTES: u64 = 256 << 20;
/// Largest MCAP file read, bytes (a run's whole log, of which one topic is used).
pub const MCAP_MAX_BYTES: u64 = 4 << 30;
/// The MCAP topic read by default.
pub const DEFAULT_TOPIC: &str = "/plan/command";

/// What happens between two samples.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Hold {
    /// u(t) = u_i on [t_i, t_{i+1}): a digital controller's output.
    #[default]
    ZeroOrder,
    /// u(t) interpolated linearly between samples.
    Linear,
}

impl Hold {
    /// The name as written in scenario files.
    pub fn name(self) -> &'static str {
        match self {
            Hold::ZeroOrder => "zero_order",
            Hold::Linear => "linear",
        }
    }
}

/// A plan read from a file (CSV, JSON, a run's MCAP log or a ROS 2 bag), for
/// any model: open-loop inputs held or interpolated between samples.
#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FilePlanParams {
    /// The plan file, relative to the scenario file: `.csv` (header `t` and the
    /// model's input names), `.json` (`{"t": [...], "u": {"name": [...]}}`), a
    /// run's `run.mcap`, or a ROS 2 bag (its directory with `metadata.yaml`, or
    /// its `.mcap`). `t` starts at 0 and increases strictly; its last value
    /// is the plan's duration.
    pub path: PathBuf,
    /// What the input does between two samples.
    #[serde(default)]
    pub hold: Hold,
    /// MCAP files and ROS 2 bags only: the topic to read. Unset, a run log's
    /// `/plan/command` (the plan; `/sim/command` holds what the physics
    /// applied), or a bag's one topic whose type gives the model's inputs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub topic: Option<String>,
    /// ROS 2 bags only: where `t` comes from, `"log"` (when the recorder
    /// logged each message) or `"header"` (the message's `header.stamp`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time: Option<BagTime>,
    /// ROS 2 bags only: the plan's length, s from the first message (messages
    /// from then on are not used). Unset: one median message period after the
    /// last message.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub duration: Option<f64>,
    /// ROS 2 bags only: the message field each model input is read from, as
    /// `input = "field.path"` (e.g. `v = "twist.linear.x"`, `omega =
    /// "rates[2]"`). Twist and TwistStamped give `v` and `omega`,
    /// AckermannDrive and AckermannDriveStamped `v` and `steer` by default.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub map: BTreeMap<String, String>,
    /// Directory `path` is relative to (the scenario's; set by the scenario layer).
    #[serde(skip)]
    pub base: PathBuf,
}

/// The plan file's format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Comma-separated values with a header.
    Csv,
    /// A JSON object of arrays.
    Json,
    /// A run log or a ROS 2 bag's MCAP file.
    Mcap,
    /// A ROS 2 bag directory (`metadata.yaml` and its files).
    Bag,
    /// One file of a ROS 2 bag in sqlite3 storage (`.db3`).
    Db3,
}

impl FilePlanParams {
    /// The file, resolved against the scenario's directory.
    pub fn file(&self) -> PathBuf {
        self.base.join(&self.path)
    }

    /// The bag directory, when `path` names one (or its `metadata.yaml`).
    pub fn bag_dir(&self) -> Option<PathBuf> {
        let f = self.file();
        if f.is_dir() {
            Some(f)
        } else if f.file_name().is_some_and(|n| n == "metadata.yaml") {
            f.parent().map(Path::to_path_buf)
        } else {
            None
        }
    }

    /// The format from the extension (or a bag directory); errors name the
    /// `planner` key at fault.
    pub fn format(&self) -> Result<Format, SetupError> {
        let ext = self
            .path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        let format = match ext.as_deref() {
            _ if self.bag_dir().is_some() => Format::Bag,
            Some("csv") => Format::Csv,
            Some("json") => Format::Json,
            Some("mcap") => Format::Mcap,
            Some("db3") => Format::Db3,
            Some("bag") => {
                let stem = self
                    .path
                    .file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_else(|| "bag".into());
                return Err(SetupError::key(
                    "planner.path",
                    format!(
                        "{}: a ROS 1 bag, which is not read here: convert it to a ROS 2 bag without ROS, `pip install rosbags` then `rosbags-convert --src {} --dst {stem}_ros2`, and set `path = \"{stem}_ros2\"`",
                        crate::echo::path(&self.path),
                        crate::echo::path(&self.path),
                    ),
                ));
            }
            // A bag directory is named without an extension: one that is
            // not there is a missing file, not an unknown format.
            None if !self.file().exists() => {
                return Err(SetupError::key(
                    "planner.path",
                    format!("file not found: {}", crate::echo::path(&self.file())),
                ))
            }
            other => {
                return Err(SetupError::key(
                    "planner.path",
                    format!(
                        "{}: unknown plan file format{} (use a .csv, .json, .mcap or .db3 file, or a ROS 2 bag's directory)",
                        crate::echo::path(&self.path),
                        other.map(|e| format!(" `.{e}`")).unwrap_or_default()
                    ),
                ))
            }
        };
        let mcap = matches!(format, Format::Mcap | Format::Bag | Format::Db3);
        if self.topic.is_some() && !mcap {
            return Err(SetupError::key(
                "planner.topic",
                "only MCAP plan files and ROS 2 bags have topics (drop it)",
            ));
        }
        if let Some(t) = &self.topic {
            if t.is_empty() {
                return Err(SetupError::key("planner.topic", "must not be empty"));
            }
        }
        let only_bags = |key: &str| {
            SetupError::key(
                key,
                "only ROS 2 bags take it (a CSV's or JSON's times and columns are its own): drop it",
            )
        };
        if !mcap {
            if self.time.is_some() {
                return Err(only_bags("planner.time"));
            }
            if self.duration.is_some() {
                return Err(only_bags("planner.duration"));
            }
            if let Some(k) = self.map.keys().next() {
                return Err(only_bags(&format!("planner.map.{k}")));
            }
        }
        if let Some(d) = self.duration {
            if !(d > 0.0 && d <= crate::plan::MAX_DURATION) {
                return Err(SetupError::key(
                    "planner.duration",
                    format!(
                        "must be in (0, {}] s",
                        crate::numfmt::shortest(crate::plan::MAX_DURATION)
                    ),
                ));
            }
        }
        for (k, v) in &self.map {
            let key = format!("planner.map.{k}");
            ros::msg::FieldPath::parse(v).map_err(|e| SetupError::key(&key, e))?;
        }
        Ok(format)
    }

    /// The bag keys (`topic`, `time`, `map`, `duration`).
    pub fn bag_keys(&self) -> ros::BagKeys<'_> {
        ros::BagKeys {
            topic: self.topic.as_deref(),
            time: self.time.unwrap_or_default(),
            map: &self.map,
            duration: self.duration,
            select: None,
        }
    }

    /// Whether any key only a ROS 2 bag takes is set.
    fn has_bag_keys(&self) -> Option<&'static str> {
        if self.time.is_some() {
            Some("time")
        } else if self.duration.is_some() {
            Some("duration")
        } else if !self.map.is_empty() {
            Some("map")
        } else {
            None
        }
    }

    /// The checks that need no file: format, and that the file exists.
    pub fn check(&self) -> Result<(), SetupError> {
        self.format()?;
        let f = self.file();
        if !f.exists() {
            return Err(SetupError::key(
                "planner.path",
                format!("file not found: {}", crate::echo::path(&f)),
            ));
        }
        Ok(())
    }
}

/// Where a value was read, for messages: the line (CSV row, JSON token) and
/// what names it (`` column `v` ``, `` key `t[3]` ``, `` message 4 ``).
#[derive(Debug, Clone)]
pub struct At {
    /// 1-based line, when the format has lines.
    pub line: Option<usize>,
    /// The column or key.
    pub what: String,
}

/// Samples read from a plan file, before they become a [`Plan`].
#[derive(Debug, Clone, Default)]
pub struct Samples {
    /// Sample times, s.
    pub t: Vec<f64>,
    /// Inputs, row-major: `m` values per sample in the model's input order.
    pub u: Vec<f64>,
    /// Label index per sample (into `labels`).
    pub label: Vec<usize>,
    /// Label names, in order of first use.
    pub labels: Vec<String>,
}

/// Checks and collects samples; every error names the file and where.
pub struct Reader<'a> {
    file: &'a Path,
    input_names: &'a [&'a str],
    out: Samples,
}

impl<'a> Reader<'a> {
    /// A reader for `file`, whose inputs are `input_names`.
    pub fn new(file: &'a Path, input_names: &'a [&'a str]) -> Reader<'a> {
        Reader {
            file,
            input_names,
            out: Samples::default(),
        }
    }

    /// The error for a problem at `at`.
    pub fn error(&self, at: &At, message: impl std::fmt::Display) -> PlanError {
        let message = if at.what.is_empty() {
            message.to_string()
        } else {
            format!("{}: {message}", at.what)
        };
        PlanError::file(self.file.to_path_buf(), at.line, message)
    }

    /// An error about the whole file (no line).
    pub fn file_error(&self, message: impl std::fmt::Display) -> PlanError {
        self.error(
            &At {
                line: None,
                what: String::new(),
            },
            message,
        )
    }

    /// Append one sample: time `t` (read at `t_at`), inputs in model order
    /// (each read at `u_at[i]`), and its label.
    pub fn push(
        &mut self,
        t: f64,
        t_at: &At,
        u: &[f64],
        u_at: &dyn Fn(usize) -> At,
        label: Option<&str>,
    ) -> Result<(), PlanError> {
        use crate::numfmt::shortest;
        if !t.is_finite() {
            return Err(self.error(t_at, format!("{t} is not a finite time")));
        }
        match self.out.t.last() {
            None if t != 0.0 => {
                return Err(self.error(
                    t_at,
                    format!("the first sample must be at t = 0, not {}", shortest(t)),
                ))
            }
            Some(&prev) if t <= prev => {
                return Err(self.error(
                    t_at,
                    format!(
                    "{} does not come after the previous sample's {} (t must increase strictly)",
                    shortest(t),
                    shortest(prev)
                ),
                ))
            }
            _ => {}
        }
        // The last sample's t is the plan's duration: refused here, at its
        // row, rather than as an unreachable goal.
        if t > crate::plan::MAX_DURATION {
            return Err(self.error(
                t_at,
                format!(
                    "{} s is past the longest plan ({} s; this sample's t would be the plan's duration)",
                    shortest(t),
                    shortest(crate::plan::MAX_DURATION)
                ),
            ));
        }
        for (i, v) in u.iter().enumerate() {
            if !v.is_finite() {
                return Err(self.error(&u_at(i), format!("{v} is not a finite number")));
            }
        }
        let name = label.unwrap_or("file");
        let idx = match self.out.labels.iter().position(|l| l == name) {
            Some(i) => i,
            None => {
                self.out.labels.push(name.to_string());
                self.out.labels.len() - 1
            }
        };
        self.out.t.push(t);
        self.out.u.extend_from_slice(u);
        self.out.label.push(idx);
        Ok(())
    }

    /// The samples, once there are at least two (a start and an end).
    pub fn finish(self) -> Result<Samples, PlanError> {
        if self.out.t.len() < 2 {
            return Err(self.file_error(format!(
                "{} sample{}: a plan needs at least two (t = 0 and its end, which is its duration)",
                self.out.t.len(),
                if self.out.t.len() == 1 { "" } else { "s" }
            )));
        }
        Ok(self.out)
    }

    /// The model's input names.
    pub fn input_names(&self) -> &[&str] {
        self.input_names
    }
}

/// A hint for a column (or JSON input) named `name` that is not one of
/// the model's `inputs`: a steering angle for a car steered by rate.
pub(crate) fn unknown_input_hint(name: &str, inputs: &[String]) -> &'static str {
    if name == "steer" && inputs.iter().any(|i| i == "steer_rate") {
        "; `steer` is a steering angle: steer the car by angle with `[model] steering = \"angle\"`"
    } else {
        ""
    }
}

/// Read and check the plan file of `params` for a model with `input_names`.
pub fn read(params: &FilePlanParams, input_names: &[&str]) -> Result<Samples, PlanError> {
    Ok(read_detailed(params, input_names)?.0)
}

/// [`read`], and what a ROS 2 bag's samples were read from.
fn read_detailed(
    params: &FilePlanParams,
    input_names: &[&str],
) -> Result<(Samples, Option<ros::BagInfo>), PlanError> {
    let file = params.file();
    let format = params.format().map_err(|e| PlanError::InvalidParameter {
        name: e
            .key_name()
            .and_then(|k| k.strip_prefix("planner."))
            .unwrap_or("path")
            .into(),
        reason: e.reason().into(),
    })?;
    for k in params.map.keys() {
        if !input_names.contains(&k.as_str()) {
            return Err(PlanError::InvalidParameter {
                name: format!("map.{k}"),
                reason: format!(
                    "`{k}` is not an input of this model (its inputs: {})",
                    input_names.join(", ")
                ),
            });
        }
    }
    let keys = params.bag_keys();
    match format {
        Format::Csv => Ok((csv::read(Reader::new(&file, input_names))?, None)),
        Format::Json => Ok((json::read(Reader::new(&file, input_names))?, None)),
        Format::Mcap => {
            let inv = ros::Inventory::scan(std::slice::from_ref(&file))?;
            let default = inv.has(DEFAULT_TOPIC).then_some(DEFAULT_TOPIC);
            let topic = params.topic.as_deref().or(default);
            let ros = inv.channels.iter().any(|c| c.encoding == "cdr");
            if topic.is_some_and(|t| inv.is_json(t)) || !ros {
                let topic = topic.unwrap_or(DEFAULT_TOPIC);
                if let Some(k) = params.has_bag_keys() {
                    return Err(PlanError::InvalidParameter {
                        name: k.into(),
                        reason: format!(
                            "only ROS 2 bags take it; topic `{topic}` of {} is a run log's (JSON)",
                            crate::echo::path(&params.path)
                        ),
                    });
                }
                let samples = mcap::read(Reader::new(&file, input_names), topic)?;
                return Ok((samples, None));
            }
            let (s, info) = ros::read_with(&file, &inv, input_names, &keys)?;
            Ok((s, Some(info)))
        }
        Format::Bag => {
            let dir = params.bag_dir().unwrap_or(file);
            let (storage, files) = ros::metadata::bag_files(&dir)?;
            let (s, info) = ros::read(&dir, storage, &files, input_names, &keys)?;
            Ok((s, Some(info)))
        }
        Format::Db3 => {
            let files = std::slice::from_ref(&file);
            let (s, info) = ros::read(&file, ros::Storage::Sqlite3, files, input_names, &keys)?;
            Ok((s, Some(info)))
        }
    }
}

/// The plan of `params` for a model with `input_names`.
pub fn plan(params: &FilePlanParams, input_names: &[&str]) -> Result<Plan, PlanError> {
    let (samples, bag) = read_detailed(params, input_names)?;
    let mut details = serde_json::json!({
        "file": params.path,
        "hold": params.hold.name(),
        "samples": samples.t.len(),
    });
    if let Some(t) = &params.topic {
        details["topic"] = serde_json::json!(t);
    }
    if let Some(b) = bag {
        details["topic"] = serde_json::json!(b.topic);
        details["message_type"] = serde_json::json!(b.type_name);
        details["messages"] = serde_json::json!(b.messages);
        details["time"] = serde_json::json!(params.time.unwrap_or_default().name());
        details["fields"] = serde_json::json!(b.paths.into_iter().collect::<BTreeMap<_, _>>());
    }
    Ok(samples.into_plan(input_names.len(), params.hold, details))
}

impl Samples {
    /// The plan: u(t) held or interpolated between the samples, labels held,
    /// one segment per run of equal labels, duration = the last sample's t.
    pub fn into_plan(self, m: usize, hold: Hold, details: serde_json::Value) -> Plan {
        let n = self.t.len();
        let duration = self.t[n - 1];
        let mut segments: Vec<Segment> = Vec::new();
        for (i, &l) in self.label.iter().enumerate().take(n - 1) {
            match segments.last_mut() {
                Some(s) if s.label == l => s.end = self.t[i + 1],
                _ => segments.push(Segment {
                    label: l,
                    start: self.t[i],
                    end: self.t[i + 1],
                }),
            }
        }
        // Jumps of a held u: where a sample differs from the one before,
        // the last one included (the run ends there, so the step before it
        // must read the held value up to its end, not the last sample's).
        let jumps: Arc<[f64]> = (1..n)
            .filter(|&i| self.u[i * m..(i + 1) * m] != self.u[(i - 1) * m..i * m])
            .map(|i| self.t[i])
            .collect();
        let labels = self.labels.clone();
        let s2 = Arc::new(self);
        // The sample in force at t (the first before t = 0).
        let row = |s: &Samples, t: f64| s.t.partition_point(|&ti| ti <= t).saturating_sub(1);
        let law = match hold {
            Hold::ZeroOrder => {
                let f = move |t: f64| {
                    let i = row(&s2, t);
                    (
                        Input::from_column_slice(&s2.u[i * m..(i + 1) * m]),
                        s2.label[i],
                    )
                };
                ControlLaw::Piecewise {
                    u: Arc::new(f),
                    jumps,
                }
            }
            Hold::Linear => {
                let f = move |t: f64| {
                    let i = row(&s2, t);
                    let a = &s2.u[i * m..(i + 1) * m];
                    let u = match s2.t.get(i + 1) {
                        // At a sample itself the sample exactly (w = 0).
                        Some(&t1) if t > s2.t[i] => {
                            let w = (t - s2.t[i]) / (t1 - s2.t[i]);
                            let b = &s2.u[(i + 1) * m..(i + 2) * m];
                            Input::from_iterator(m, a.iter().zip(b).map(|(x, y)| x + (y - x) * w))
                        }
                        _ => Input::from_column_slice(a),
                    };
                    (u, s2.label[i])
                };
                ControlLaw::Piecewise {
                    u: Arc::new(f),
                    jumps: Arc::new([]),
                }
            }
        };
        Plan {
            labels,
            segments,
            duration,
            law,
            details,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn samples(t: &[f64], u: &[f64]) -> Samples {
        Samples {
            t: t.to_vec(),
            u: u.to_vec(),
            label: vec![0; t.len()],
            labels: vec!["file".into()],
        }
    }

    #[test]
    fn zero_order_hold_is_right_continuous_and_jumps_where_u_changes() {
        let p = samples(&[0.0, 0.5, 1.0, 2.0], &[1.0, 1.0, 3.0, 9.0]).into_plan(
            1,
            Hold::ZeroOrder,
            serde_json::Value::Null,
        );
        assert_eq!(p.duration, 2.0);
        // 0.5 repeats the value before: no jump there; the end is one.
        assert_eq!(p.jumps(), vec![1.0, 2.0]);
        let mut c = p.controller();
        let q = crate::model::State::zeros(1);
        let u = |c: &mut Box<dyn crate::plan::Controller>, t: f64| c.command(t, &q).u[0];
        assert_eq!(u(&mut c, 0.0), 1.0);
        assert_eq!(u(&mut c, 0.999), 1.0);
        assert_eq!(u(&mut c, 1.0), 3.0);
        assert_eq!(u(&mut c, 1.999), 3.0);
        assert_eq!(u(&mut c, 2.0), 9.0);
    }

    #[test]
    fn linear_hold_interpolates_and_hits_samples_exactly() {
        let p = samples(&[0.0, 0.1, 0.3], &[0.1, 0.7, -0.2]).into_plan(
            1,
            Hold::Linear,
            serde_json::Value::Null,
        );
        assert!(p.jumps().is_empty());
        let mut c = p.controller();
        let q = crate::model::State::zeros(1);
        for (t, want) in [
            (0.0, 0.1),
            (0.1, 0.7),
            (0.3, -0.2),
            (0.05, 0.4),
            (0.2, 0.25),
        ] {
            let got = c.command(t, &q).u[0];
            assert!((got - want).abs() < 1e-15, "t = {t}: {got} vs {want}");
        }
        assert_eq!(c.command(0.1, &q).u[0].to_bits(), 0.7f64.to_bits());
    }

    #[test]
    fn segments_follow_label_runs() {
        let mut s = samples(&[0.0, 1.0, 2.0, 3.0], &[0.0; 4]);
        s.labels = vec!["a".into(), "b".into()];
        s.label = vec![0, 0, 1, 0];
        let p = s.into_plan(1, Hold::ZeroOrder, serde_json::Value::Null);
        let segs: Vec<(usize, f64, f64)> = p
            .segments
            .iter()
            .map(|s| (s.label, s.start, s.end))
            .collect();
        assert_eq!(segs, vec![(0, 0.0, 2.0), (1, 2.0, 3.0)]);
    }
}
