//! ROS 2 bags (rosbag2, MCAP or sqlite3 storage) as plan files: one
//! command topic's messages, decoded through the definition the bag stores
//! with the topic ([`msg`]; a sqlite3 bag of ROS 2 Humble or older stores
//! none, and the common command types are built in, [`sqlite`]), become
//! samples: `t` from the log time (or the header stamp),
//! starting at 0 at the first message; the inputs from message fields,
//! by default for the common command types ([`DEFAULT_MAPS`]) or as the
//! scenario's `[planner.map]` says. The plan ends one median message period
//! after the last message (or at `duration`), where the robot is stopped.
//!
//! Every problem names the file, the topic and the message's index on that
//! topic (0 for the first).

pub mod error;
pub mod metadata;
pub mod msg;
mod prepare_error;
pub mod select;
pub mod sqlite;

use crate::planner::PlanError;
use crate::sources::file::{At, Reader, Samples, MCAP_MAX_BYTES};
use msg::{Definition, FieldPath};
use prepare_error::{PrepareError, Unmapped};
use std::collections::{BTreeMap, HashMap};
use std::io::Read;
use std::path::{Path, PathBuf};
use std::rc::Rc;

/// Where `t` comes from.
#[derive(
    Debug,
    Clone,
    Copy,
    Default,
    PartialEq,
    Eq,
    serde::Deserialize,
    serde::Serialize,
    schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum BagTime {
    /// The time the recorder logged each message (`ros2 bag record`'s receive time).
    #[default]
    Log,
    /// The message's own `header.stamp` (stamped types only).
    Header,
}

impl BagTime {
    /// The name as written in scenario files.
    pub fn name(self) -> &'static str {
        match self {
            BagTime::Log => "log",
            BagTime::Header => "header",
        }
    }
}

/// The model inputs the common command types give without a `[planner.map]`:
/// (type, [(input, field path)]).
pub const DEFAULT_MAPS: &[(&str, &[(&str, &str)])] = &[
    (
        "geometry_msgs/msg/Twist",
        &[("v", "linear.x"), ("omega", "angular.z")],
    ),
    (
        "geometry_msgs/msg/TwistStamped",
        &[("v", "twist.linear.x"), ("omega", "twist.angular.z")],
    ),
    (
        "ackermann_msgs/msg/AckermannDrive",
        &[("v", "speed"), ("steer", "steering_angle")],
    ),
    (
        "ackermann_msgs/msg/AckermannDriveStamped",
        &[("v", "drive.speed"), ("steer", "drive.steering_angle")],
    ),
];

/// The scenario's bag keys.
#[derive(Debug, Clone, Copy)]
pub struct BagKeys<'a> {
    /// `topic`, if set.
    pub topic: Option<&'a str>,
    /// `time`.
    pub time: BagTime,
    /// `[planner.map]`.
    pub map: &'a BTreeMap<String, String>,
    /// `duration`, if set.
    pub duration: Option<f64>,
    /// Numbers read in one element of an array (a tf message's transform),
    /// not the message itself; `None` for commands.
    pub select: Option<select::Select<'a>>,
}

/// A channel of one of the bag's files.
#[derive(Debug, Clone)]
pub struct ChannelInfo {
    /// Index of its file.
    pub file: usize,
    /// Its id in that file.
    pub id: u16,
    /// Topic.
    pub topic: String,
    /// `cdr`, `json`, ...
    pub encoding: String,
    /// Its schema's name (the message type), if it has one.
    pub type_name: Option<String>,
    /// Messages on it.
    pub count: usize,
}

/// How a bag's files store their messages.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Storage {
    /// MCAP files (`.mcap`), each channel with its schema.
    #[default]
    Mcap,
    /// SQLite databases (`.db3`): `topics`, `messages` and, from ROS 2 Iron
    /// on, `message_definitions` tables.
    Sqlite3,
}

/// The channels of a bag's files.
#[derive(Debug, Clone, Default)]
pub struct Inventory {
    /// How the files store messages.
    pub storage: Storage,
    /// The files, in order.
    pub files: Vec<PathBuf>,
    /// Every channel of every file.
    pub channels: Vec<ChannelInfo>,
}

/// A file's bytes (a regular file within the MCAP cap).
pub(crate) fn read_bytes(file: &Path) -> Result<Vec<u8>, PlanError> {
    let err = |m: String| PlanError::file(file.to_path_buf(), None, m);
    crate::input::check_regular(file, "plan file", MCAP_MAX_BYTES)
        .map_err(|e| err(e.to_string()))?;
    let mut bytes = Vec::new();
    std::fs::File::open(file)
        .and_then(|f| f.take(MCAP_MAX_BYTES + 1).read_to_end(&mut bytes))
        .map_err(|e| err(format!("cannot read plan file: {e}")))?;
    if bytes.is_empty() {
        return Err(err("empty file: expected an MCAP file".into()));
    }
    Ok(bytes)
}

impl Inventory {
    /// Scan `files` for their channels and message counts.
    pub fn scan(files: &[PathBuf]) -> Result<Inventory, PlanError> {
        use mcap::records::Record;
        let mut out = Inventory {
            storage: Storage::Mcap,
            files: files.to_vec(),
            channels: Vec::new(),
        };
        for (fi, file) in files.iter().enumerate() {
            let bytes = read_bytes(file)?;
            let bad = |e: mcap::McapError| {
                PlanError::file(file.clone(), None, format!("not a readable MCAP file: {e}"))
            };
            let mut schemas: HashMap<u16, String> = HashMap::new();
            let mut index: HashMap<u16, usize> = HashMap::new();
            for rec in mcap::read::ChunkFlattener::new(&bytes).map_err(bad)? {
                match rec.map_err(bad)? {
                    Record::Schema { header, .. } => {
                        schemas.insert(header.id, header.name);
                    }
                    Record::Channel(c) => {
                        if index.contains_key(&c.id) {
                            continue;
                        }
                        index.insert(c.id, out.channels.len());
                        out.channels.push(ChannelInfo {
                            file: fi,
                            id: c.id,
                            topic: c.topic,
                            encoding: c.message_encoding,
                            type_name: schemas.get(&c.schema_id).cloned(),
                            count: 0,
                        });
                    }
                    Record::Message { header, .. } => {
                        if let Some(&i) = index.get(&header.channel_id) {
                            out.channels[i].count += 1;
                        }
                    }
                    _ => {}
                }
            }
        }
        Ok(out)
    }

    /// Whether some channel has `topic`.
    pub fn has(&self, topic: &str) -> bool {
        self.channels.iter().any(|c| c.topic == topic)
    }

    /// Whether every channel of `topic` (at least one) holds JSON (a run log).
    pub fn is_json(&self, topic: &str) -> bool {
        let mut chans = self.channels.iter().filter(|c| c.topic == topic).peekable();
        chans.peek().is_some() && chans.all(|c| c.encoding == "json")
    }

    /// `topic (type), ...` of every topic, for messages.
    pub fn topics(&self) -> String {
        let mut seen: Vec<String> = Vec::new();
        for c in &self.channels {
            let t = match &c.type_name {
                Some(ty) if !ty.is_empty() => format!("{} ({ty})", c.topic),
                _ => c.topic.clone(),
            };
            if !seen.contains(&t) {
                seen.push(t);
            }
        }
        if seen.is_empty() {
            "none".into()
        } else {
            seen.join(", ")
        }
    }
}

/// The field path of each input for messages of type `ty` (the scenario's
/// map first, then the type's defaults); `Err` names an input neither gives.
fn paths_for<'a>(
    ty: &str,
    inputs: &[&'a str],
    map: &BTreeMap<String, String>,
) -> Result<Vec<String>, &'a str> {
    let defaults = DEFAULT_MAPS
        .iter()
        .find(|(t, _)| msg::normalize(t) == msg::normalize(ty))
        .map(|(_, m)| *m)
        .unwrap_or(&[]);
    inputs
        .iter()
        .map(|&i| {
            map.get(i)
                .cloned()
                .or_else(|| {
                    defaults
                        .iter()
                        .find(|(n, _)| *n == i)
                        .map(|(_, p)| p.to_string())
                })
                .ok_or(i)
        })
        .collect()
}

/// Why an input has no field: with the inputs the type gives by default.
fn unmapped(ty: &str, input: &str, inputs: &[&str]) -> Unmapped {
    let defaults = DEFAULT_MAPS
        .iter()
        .find(|(t, _)| msg::normalize(t) == msg::normalize(ty))
        .map(|(_, d)| d.iter().map(|(n, _)| *n).collect());
    Unmapped {
        ty: ty.to_string(),
        input: input.to_string(),
        inputs: inputs.iter().map(|i| i.to_string()).collect(),
        defaults,
    }
}

/// The topic to read: the scenario's, or the one topic whose type maps to
/// every input of the model.
fn choose_topic(
    inv: &Inventory,
    keys: &BagKeys<'_>,
    inputs: &[&str],
    bag: &Path,
) -> Result<String, PlanError> {
    let err = |m: String| PlanError::file(bag.to_path_buf(), None, m);
    if let Some(t) = keys.topic {
        if !inv.has(t) {
            return Err(err(format!(
                "no topic `{t}` in the bag (topics: {})",
                inv.topics()
            )));
        }
        return Ok(t.to_string());
    }
    let mut fits: Vec<&ChannelInfo> = Vec::new();
    for c in &inv.channels {
        let Some(ty) = &c.type_name else { continue };
        if c.encoding == "cdr"
            && paths_for(ty, inputs, keys.map).is_ok()
            && !fits.iter().any(|f| f.topic == c.topic)
        {
            fits.push(c);
        }
    }
    match fits.as_slice() {
        [one] => Ok(one.topic.clone()),
        [] => Err(err(format!(
            "no topic whose messages give this model's inputs ({}) by default (topics: {}): choose one with `topic = \"...\"` and map its fields with `[planner.map]`",
            inputs.join(", "),
            inv.topics()
        ))),
        many => Err(err(format!(
            "several topics could be the commands ({}): choose one with `topic = \"...\"`",
            many.iter()
                .map(|c| c.topic.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ))),
    }
}

/// What a topic's messages are read with: the definition and the inputs' paths.
struct Prepared {
    def: Definition,
    paths: Vec<FieldPath>,
    stamp: Option<[FieldPath; 2]>,
}

/// What was read, for the plan's details.
#[derive(Debug, Clone)]
pub struct BagInfo {
    /// The topic read.
    pub topic: String,
    /// Its message type.
    pub type_name: String,
    /// Messages read.
    pub messages: usize,
    /// Each input's field path.
    pub paths: Vec<(String, String)>,
    /// The bag time of t = 0 (the first message's log or header time), ns:
    /// how two topics of one bag line up.
    pub first_ns: i64,
}

/// Read the command topic of the bag made of `files` in `storage` (`bag`:
/// the path the scenario gave, for bag-wide messages) for a model with
/// `inputs`.
pub fn read(
    bag: &Path,
    storage: Storage,
    files: &[PathBuf],
    inputs: &[&str],
    keys: &BagKeys<'_>,
) -> Result<(Samples, BagInfo), PlanError> {
    let inv = match storage {
        Storage::Mcap => Inventory::scan(files)?,
        Storage::Sqlite3 => sqlite::scan(files)?,
    };
    read_with(bag, &inv, inputs, keys)
}

/// [`read`] with the bag's channels already scanned.
pub(crate) fn read_with(
    bag: &Path,
    inv: &Inventory,
    inputs: &[&str],
    keys: &BagKeys<'_>,
) -> Result<(Samples, BagInfo), PlanError> {
    let topic = choose_topic(inv, keys, inputs, bag)?;
    let chans: Vec<&ChannelInfo> = inv.channels.iter().filter(|c| c.topic == topic).collect();
    let total: usize = chans.iter().map(|c| c.count).sum();
    let type_of = |c: &ChannelInfo| c.type_name.clone().unwrap_or_default();
    if total == 0 {
        let ty = chans.first().map(|c| type_of(c)).unwrap_or_default();
        return Err(PlanError::file(
            bag.to_path_buf(),
            None,
            format!(
                "topic `{topic}`{}: no messages (an empty topic: nothing was published on it while recording)",
                if ty.is_empty() { String::new() } else { format!(" ({ty})") }
            ),
        ));
    }
    for c in &chans {
        if c.encoding != "cdr" {
            return Err(PlanError::file(
                inv.files[c.file].clone(),
                None,
                format!(
                    "topic `{topic}`: messages encoded as `{}`, not CDR (ROS 2) nor a run log's JSON",
                    c.encoding
                ),
            ));
        }
    }
    // Samples on the topic's first file, whose errors name that file.
    let first_file = inv.files[chans[0].file].clone();
    let mut dec = Decoder {
        topic: &topic,
        inputs,
        keys,
        prepared: HashMap::new(),
        raw: Vec::new(),
        k: 0,
        type_name: String::new(),
        paths_used: Vec::new(),
    };
    for (fi, file) in inv.files.iter().enumerate() {
        let ids: Vec<u16> = chans
            .iter()
            .filter(|c| c.file == fi)
            .map(|c| c.id)
            .collect();
        if ids.is_empty() {
            continue;
        }
        match inv.storage {
            Storage::Mcap => mcap_messages(file, fi, &mut dec)?,
            Storage::Sqlite3 => sqlite::messages(file, fi, &ids, &mut dec)?,
        }
    }
    dec.finish(&first_file)
}

/// The stored definition of a channel's messages: type name, encoding
/// (`ros2msg`) and text.
pub type SchemaRef<'a> = (&'a str, &'a str, &'a [u8]);

/// Decodes the chosen topic's messages, from whichever storage, into
/// samples: the same types, field paths and timing for every storage.
pub struct Decoder<'a> {
    topic: &'a str,
    inputs: &'a [&'a str],
    keys: &'a BagKeys<'a>,
    prepared: HashMap<(usize, u16), Rc<Prepared>>,
    /// (ns, values, message index)
    raw: Vec<(i64, Vec<f64>, usize)>,
    k: usize,
    type_name: String,
    paths_used: Vec<(String, String)>,
}

impl Decoder<'_> {
    /// The topic being read.
    pub fn topic(&self) -> &str {
        self.topic
    }

    /// One message of the topic from `file` (index `fi`), on its channel
    /// `channel`, whose stored definition `schema` gives (asked once per
    /// channel), logged at `log_time` ns.
    pub fn message<'s>(
        &mut self,
        file: &Path,
        fi: usize,
        channel: u16,
        schema: impl FnOnce() -> Option<SchemaRef<'s>>,
        log_time: u64,
        data: &[u8],
    ) -> Result<(), PlanError> {
        let topic = self.topic;
        let k = self.k;
        let at_msg = |m: String| {
            PlanError::file(
                file.to_path_buf(),
                None,
                format!("topic `{topic}` message {k}: {m}"),
            )
        };
        let key = (fi, channel);
        let p = match self.prepared.get(&key) {
            Some(p) => p.clone(),
            None => {
                let p = Rc::new(
                    prepare(schema(), self.inputs, self.keys).map_err(|e| at_msg(e.to_string()))?,
                );
                if self.type_name.is_empty() {
                    self.type_name = p.def.name().to_string();
                    self.paths_used = self
                        .inputs
                        .iter()
                        .zip(&p.paths)
                        .map(|(i, p)| (i.to_string(), p.text.clone()))
                        .collect();
                }
                self.prepared.insert(key, p.clone());
                p
            }
        };
        let inputs = self.inputs;
        let decoded = p.def.decode(data).map_err(|e| at_msg(e.to_string()))?;
        let v = match &self.keys.select {
            None => &decoded,
            Some(s) => match s.element(&decoded) {
                Some(e) => e,
                // Another frame's message: not this topic's samples.
                None => {
                    self.k += 1;
                    return Ok(());
                }
            },
        };
        let mut u = Vec::with_capacity(inputs.len());
        for (i, path) in p.paths.iter().enumerate() {
            let x = msg::number_at(v, path)
                .map_err(|e| at_msg(format!("input `{}` = `{}`: {e}", inputs[i], path.text)))?;
            if !x.is_finite() {
                return Err(at_msg(format!(
                    "field `{}` (input `{}`): {x} is not a finite number",
                    path.text, inputs[i]
                )));
            }
            u.push(x);
        }
        let ns = match &p.stamp {
            None => i64::try_from(log_time)
                .map_err(|_| at_msg(format!("log time {log_time} ns is out of range")))?,
            Some([sec, nsec]) => {
                let s = msg::integer_at(v, sec);
                let n = msg::integer_at(v, nsec);
                match (s, n) {
                    (Some(s), Some(n)) => s * 1_000_000_000 + n,
                    _ => {
                        return Err(at_msg(
                            "no integer `header.stamp.sec` and `header.stamp.nanosec`".into(),
                        ))
                    }
                }
            }
        };
        let raw = &mut self.raw;
        if let Some(&(prev, ..)) = raw.last() {
            if ns < prev {
                let t0 = raw[0].0;
                let secs = |x: i64| crate::numfmt::readable((x - t0) as f64 * 1e-9);
                return Err(at_msg(format!(
                    "time goes backwards: its {} time is {} s after the first message, before the previous message's {} s",
                    self.keys.time.name(),
                    secs(ns),
                    secs(prev)
                )));
            }
            if ns == prev {
                // Two commands at one instant: the later one is in force.
                let last = raw.last_mut().expect("a previous message");
                *last = (ns, u, k);
                self.k += 1;
                return Ok(());
            }
        }
        raw.push((ns, u, k));
        self.k += 1;
        Ok(())
    }

    /// The samples (errors about the whole topic name `first_file`).
    fn finish(self, first_file: &Path) -> Result<(Samples, BagInfo), PlanError> {
        let Decoder {
            topic,
            inputs,
            keys,
            mut raw,
            k,
            type_name,
            paths_used,
            ..
        } = self;
        let Some(&(t0, ..)) = raw.first() else {
            let what = keys.select.map(|s| s.describe()).unwrap_or_default();
            return Err(PlanError::file(
                first_file.to_path_buf(),
                None,
                format!("topic `{topic}`: no message{what}"),
            ));
        };
        let secs = |ns: i64| (ns - t0) as f64 / 1e9;
        let end = match keys.duration {
            Some(d) => {
                raw.retain(|s| secs(s.0) < d);
                d
            }
            None if raw.len() < 2 => {
                return Err(PlanError::file(
                    first_file.to_path_buf(),
                    None,
                    format!(
                        "topic `{topic}`: {} distinct message time{}: no period to end the plan on; set the plan's length with `duration`",
                        raw.len(),
                        if raw.len() == 1 { "" } else { "s" }
                    ),
                ))
            }
            None => {
                let mut gaps: Vec<i64> = raw.windows(2).map(|w| w[1].0 - w[0].0).collect();
                gaps.sort_unstable();
                let n = gaps.len();
                let median = if n % 2 == 1 {
                    gaps[n / 2]
                } else {
                    gaps[n / 2 - 1] + (gaps[n / 2] - gaps[n / 2 - 1]) / 2
                };
                secs(raw[raw.len() - 1].0 + median)
            }
        };
        let mut r = Reader::new(first_file, inputs);
        for (ns, u, k) in &raw {
            let at = At {
                line: None,
                what: format!("topic `{topic}` message {k}"),
            };
            r.push(secs(*ns), &at, u, &|_| at.clone(), Some(topic))?;
        }
        let at = At {
            line: None,
            what: format!("topic `{topic}`, the plan's end"),
        };
        r.push(
            end,
            &at,
            &vec![0.0; inputs.len()],
            &|_| at.clone(),
            Some(topic),
        )?;
        Ok((
            r.finish()?,
            BagInfo {
                topic: topic.to_string(),
                type_name,
                messages: k,
                paths: paths_used,
                first_ns: t0,
            },
        ))
    }
}

/// The messages of the decoder's topic in the MCAP file `file` (index `fi`).
fn mcap_messages(file: &Path, fi: usize, dec: &mut Decoder<'_>) -> Result<(), PlanError> {
    let bytes = read_bytes(file)?;
    let bad = |e: mcap::McapError| {
        PlanError::file(
            file.to_path_buf(),
            None,
            format!("not a readable MCAP file: {e}"),
        )
    };
    for m in mcap::MessageStream::new(&bytes).map_err(bad)? {
        let m = m.map_err(bad)?;
        if m.channel.topic != dec.topic() {
            continue;
        }
        let schema = m.channel.schema.as_ref();
        dec.message(
            file,
            fi,
            m.channel.id,
            || schema.map(|s| (s.name.as_str(), s.encoding.as_str(), &s.data[..])),
            m.log_time,
            &m.data,
        )?;
    }
    Ok(())
}

/// The definition and paths for messages whose stored definition is
/// `schema` (type name, encoding, text).
fn prepare(
    schema: Option<SchemaRef<'_>>,
    inputs: &[&str],
    keys: &BagKeys<'_>,
) -> Result<Prepared, PrepareError> {
    let Some((name, encoding, data)) = schema else {
        return Err(PrepareError::NoSchema);
    };
    let ty = name.to_string();
    if data.is_empty() {
        return Err(PrepareError::EmptySchema { ty });
    }
    if encoding != "ros2msg" {
        return Err(PrepareError::Encoding {
            ty,
            encoding: encoding.to_string(),
        });
    }
    let Ok(text) = std::str::from_utf8(data) else {
        return Err(PrepareError::NotUtf8 { ty });
    };
    let def = Definition::parse(&ty, text).map_err(|source| PrepareError::Definition {
        ty: ty.clone(),
        source,
    })?;
    let texts = paths_for(&ty, inputs, keys.map).map_err(|i| unmapped(&ty, i, inputs))?;
    let mut paths = Vec::new();
    for (input, text) in inputs.iter().zip(texts) {
        let p = FieldPath::parse(&text).map_err(|source| PrepareError::Path {
            input: input.to_string(),
            source,
        })?;
        let from = if keys.map.contains_key(*input) {
            format!("planner.map.{input}")
        } else {
            format!("the default for {ty}")
        };
        let whole = match &keys.select {
            Some(s) => s.whole(&p).map_err(PrepareError::Select)?,
            None => p.clone(),
        };
        def.resolve_number(&whole)
            .map_err(|source| PrepareError::Resolve {
                input: input.to_string(),
                text,
                from,
                source: Box::new(source),
            })?;
        paths.push(p);
    }
    let stamp = match keys.time {
        BagTime::Log => None,
        BagTime::Header => {
            let sec = FieldPath::parse("header.stamp.sec").expect("a path");
            let nsec = FieldPath::parse("header.stamp.nanosec").expect("a path");
            let whole = |p: &FieldPath| match &keys.select {
                Some(s) => s.whole(p).map_err(PrepareError::Select),
                None => Ok(p.clone()),
            };
            if def.resolve_number(&whole(&sec)?).is_err()
                || def.resolve_number(&whole(&nsec)?).is_err()
            {
                return Err(PrepareError::NoStamp { ty });
            }
            Some([sec, nsec])
        }
    };
    Ok(Prepared { def, paths, stamp })
}
