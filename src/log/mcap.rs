//! MCAP log of a run, for Foxglove.
//!
//! Written with the `foxglove` SDK on a private [`Context`]; every message's
//! log (and publish) time is the **simulation time in nanoseconds** (so runs
//! start at the Unix epoch in Foxglove's timeline). Messages are written in
//! time order; chunks are zstd-compressed.
//!
//! # Topics
//!
//! | topic | encoding / schema | one message per | content |
//! |---|---|---|---|
//! | `/plan/command` | json / jsonschema `anholonomy.Command` | ideal sample | inputs applied from `t` on (right limit at a jump) |
//! | `/sim/command` | json / jsonschema `anholonomy.Command` | sim step with the plan in force, and its end | inputs the physics applied over the step from `t` on; the last message, at the plan's end, holds zeros (settling) |
//! | `/ideal/state` | json / jsonschema `anholonomy.State` | ideal sample | ideal (RK4) state |
//! | `/sim/state` | json / jsonschema `anholonomy.State` | sim sample | state read back from physics |
//! | `/sim/channels` | json / jsonschema `anholonomy.SimChannels` | sim sample | extra physics measurements (slip, momentum, ...), when the system has any |
//! | `/tracking/error` | json / jsonschema `anholonomy.TrackingError` | comparison grid sample | sim − ideal per coordinate, plus `position` |
//! | `/tf` | protobuf `foxglove.FrameTransforms` | sim sample | `world` → each link frame |
//! | `/scene` | protobuf `foxglove.SceneUpdate` | once, t = 0 | URDF visuals, one entity per link, frame-locked to the link frame, lifetime 0 (forever) |
//! | `/scene/paths` | protobuf `foxglove.SceneUpdate` | once, t = 0 | ideal path (green) and simulated path (orange) line strips at z = 0, a recorded run's (`[compare] reference`, grey), goal marker (red sphere, arrow for the goal heading); only when the model has a planar position |
//! | `/analysis/<name>` | json / jsonschema `anholonomy.Series` | series sample | a system's own series (e.g. `V/ideal`, the planner's potential along the ideal run): `values.value` |
//!
//! JSON messages all have the form
//! `{"t": <s>, "segment": "<label name>", "values": {"<name>": <number>, ...}}`:
//! `t` is the sample time in seconds, `segment` the plan label in force
//! (for `/tracking/error`, the ideal run's label at that time), and `values`
//! maps input names (`/plan/command`), state coordinate names (`/ideal/state`,
//! `/sim/state`; angles in radians) or coordinate names plus `position`
//! (`/tracking/error`: angles wrapped, in rad; `position` = ‖p_sim − p_ideal‖
//! in m) to numbers (non-finite values are written as `null`).
//!
//! Link frame ids are the URDF link names (a link called `world` becomes
//! `world_link`); scene entity ids are the link names, plus `ideal_path`,
//! `sim_path`, `real_path` and `goal` on `/scene/paths` (the first robot's; a second
//! robot's are `ideal_path_2`, `sim_path_2`, `goal_2`, and so on).
//!
//! # Metadata
//!
//! * `anholonomy.metrics`: every metric, name → value (decimal string).
//! * `anholonomy.run`: `scenario`, `state_names`, `input_names`, `labels`
//!   (comma-separated), `ideal_samples`, `sim_samples`, `sim_steps`.
//! * `anholonomy.plan`: `command` (`continuous`: samples of an open-loop
//!   u(t); `held`: a feedback command held for `hold_period_s`), `jumps_s`
//!   (JSON list of the instants where u jumps) and `details` (JSON, the
//!   planner's record: enough to recompute u(t), e.g. Legendre coefficients).

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::fs::File;
use std::io::{self, BufWriter, Seek, SeekFrom, Write};
use std::path::Path;
use std::sync::Arc;

use foxglove::messages::{
    line_primitive, ArrowPrimitive, Color, CubePrimitive, CylinderPrimitive, FrameTransforms,
    LinePrimitive, Point3, Pose as FgPose, Quaternion, SceneEntity, SceneUpdate, SpherePrimitive,
    Timestamp, TriangleListPrimitive, Vector3,
};
use foxglove::{Context, FoxgloveError, RawChannel, Schema};

mod events;

use crate::log::atomic::write_atomically;
use crate::log::scene::{
    coord_name, goal_points, link_frame, marker_scale, planar_paths, robot_suffix, GOAL_RGBA,
    IDEAL_RGBA, REAL_RGBA, SIM_RGBA,
};
use crate::log::{validate, LogError};
use crate::record::{Pose, RunRecord, Shape};

/// Root frame of `/tf` and of the path / goal scene entities.
pub const WORLD_FRAME: &str = "world";

/// Write the MCAP log of `rec` to `path` (atomically: via `<path>.tmp` + rename).
pub fn write_mcap(path: &Path, rec: &RunRecord<'_>) -> Result<(), LogError> {
    validate(path, rec)?;
    write_atomically(path, |tmp| write_file(tmp, rec))
}

/// The first I/O error of a [`Latched`] writer, readable after the writer
/// has been handed to (and lost in) a failed MCAP writer.
type FirstError = std::sync::Arc<std::sync::Mutex<Option<io::Error>>>;

/// A writer that remembers the first I/O error: the foxglove sink reports
/// per-message write errors only as log warnings, and after one it fails with
/// "attempted another write after a write method failed", which hides the
/// cause (e.g. "No space left on device").
struct Latched<W> {
    inner: W,
    err: FirstError,
}

impl<W> Latched<W> {
    fn latch<T>(&mut self, r: io::Result<T>) -> io::Result<T> {
        if let Err(e) = &r {
            if let Ok(mut first) = self.err.lock() {
                first.get_or_insert_with(|| io::Error::new(e.kind(), e.to_string()));
            }
        }
        r
    }
}

impl<W: Write> Write for Latched<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let r = self.inner.write(buf);
        self.latch(r)
    }
    fn flush(&mut self) -> io::Result<()> {
        let r = self.inner.flush();
        self.latch(r)
    }
}

impl<W: Seek> Seek for Latched<W> {
    fn seek(&mut self, pos: SeekFrom) -> io::Result<u64> {
        let r = self.inner.seek(pos);
        self.latch(r)
    }
}

fn write_file(tmp: &Path, rec: &RunRecord<'_>) -> Result<(), LogError> {
    let io_err = |op, source| LogError::Io {
        op,
        path: tmp.to_path_buf(),
        source,
    };
    let first: FirstError = Default::default();
    let latched = || first.lock().ok().and_then(|mut e| e.take());
    // An SDK error that follows an I/O error is reported as that I/O error.
    let fg_err = |source: FoxgloveError| match latched() {
        Some(e) => io_err("cannot write", e),
        None => LogError::Mcap {
            path: tmp.to_path_buf(),
            source,
        },
    };
    let file = File::create(tmp).map_err(|e| io_err("cannot create", e))?;
    let writer = Latched {
        inner: BufWriter::with_capacity(1 << 20, file),
        err: first.clone(),
    };

    let ctx = Context::new();
    // zstd level 1: on these logs (repetitive JSON) it writes smaller chunks
    // than the default level 3, and ~25 % faster (rover_paper: 20.8 MB in 0.9 s
    // against 21.9 MB in 1.2 s).
    let options = foxglove::McapWriteOptions::default().compression_level(1);
    let handle = foxglove::McapWriter::with_options(options)
        .context(&ctx)
        .create(writer)
        .map_err(fg_err)?;

    let logged = log_all(&ctx, tmp, rec).and_then(|()| {
        handle
            .write_metadata("anholonomy.metrics", metrics_metadata(rec))
            .map_err(fg_err)?;
        handle
            .write_metadata("anholonomy.run", run_metadata(rec))
            .map_err(fg_err)?;
        handle
            .write_metadata("anholonomy.plan", plan_metadata(rec))
            .map_err(fg_err)
    });
    // Always close (flushes and finishes the file) before reporting errors.
    let closed = handle.close().map_err(fg_err);
    if let Err(e) = logged {
        return Err(latched().map_or(e, |io| io_err("cannot write", io)));
    }
    let writer = closed?;
    if let Some(e) = latched() {
        return Err(io_err("cannot write", e));
    }
    let file = writer
        .inner
        .into_inner()
        .map_err(|e| io_err("cannot write", e.into_error()))?;
    drop(file);
    Ok(())
}

// ---------------------------------------------------------------- JSON topics

/// One JSON message: `{"t": .., "segment": .., "values": {name: value, ..}}`.
struct JsonMsg<'a> {
    t: f64,
    segment: &'a str,
    keys: &'a Keys,
    values: &'a [f64],
}

/// The `values` object's keys of one topic, each escaped once and written
/// as `"name":` (`,"name":` after the first): per message only the numbers
/// and the segment are formatted. The bytes are serde_json's compact output
/// (test `json_messages_are_serde_jsons_bytes`).
struct Keys(Vec<Vec<u8>>);

impl Keys {
    fn new(names: &[Cow<'_, str>]) -> Keys {
        Keys(
            names
                .iter()
                .enumerate()
                .map(|(i, n)| {
                    let mut k = if i == 0 { Vec::new() } else { vec![b','] };
                    serde_json::to_writer(&mut k, n.as_ref()).expect("a string serializes");
                    k.push(b':');
                    k
                })
                .collect(),
        )
    }
}

impl JsonMsg<'_> {
    /// Append the message to `buf`. Numbers are written as serde_json writes
    /// them (shortest round-trip form; NaN and infinities as null).
    fn write(&self, buf: &mut Vec<u8>) -> serde_json::Result<()> {
        buf.extend_from_slice(b"{\"t\":");
        serde_json::to_writer(&mut *buf, &self.t)?;
        buf.extend_from_slice(b",\"segment\":");
        serde_json::to_writer(&mut *buf, self.segment)?;
        buf.extend_from_slice(b",\"values\":{");
        for (k, v) in self.keys.0.iter().zip(self.values) {
            buf.extend_from_slice(k);
            serde_json::to_writer(&mut *buf, v)?;
        }
        buf.extend_from_slice(b"}}");
        Ok(())
    }
}

/// JSON schema of a JSON topic whose `values` has the given keys.
fn json_schema(title: &str, description: &str, names: &[Cow<'_, str>]) -> Vec<u8> {
    let props: serde_json::Map<String, serde_json::Value> = names
        .iter()
        .map(|n| {
            (
                n.to_string(),
                serde_json::json!({ "type": ["number", "null"] }),
            )
        })
        .collect();
    let schema = serde_json::json!({
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": title,
        "description": description,
        "type": "object",
        "properties": {
            "t": { "type": "number", "description": "sample time, s" },
            "segment": { "type": "string", "description": "plan label (segment) in force" },
            "values": {
                "type": "object",
                "properties": props,
                "required": names.iter().map(|n| n.as_ref()).collect::<Vec<_>>(),
            },
        },
        "required": ["t", "segment", "values"],
    });
    serde_json::to_vec(&schema).expect("a JSON value always serializes")
}

fn json_channel(
    ctx: &Arc<Context>,
    topic: &str,
    schema_name: &str,
    description: &str,
    names: &[Cow<'_, str>],
    tmp: &Path,
) -> Result<Arc<RawChannel>, LogError> {
    ctx.channel_builder(topic)
        .message_encoding("json")
        .schema(Schema::new(
            schema_name,
            "jsonschema",
            json_schema(schema_name, description, names),
        ))
        .build_raw()
        .map_err(|source| LogError::Mcap {
            path: tmp.to_path_buf(),
            source,
        })
}

// ------------------------------------------------------------------- logging

fn log_all(ctx: &Arc<Context>, tmp: &Path, rec: &RunRecord<'_>) -> Result<(), LogError> {
    let state_names: Vec<Cow<'_, str>> = (0..rec.state_names.len())
        .map(|i| coord_name(rec.state_names, i))
        .collect();
    let input_names: Vec<Cow<'_, str>> = (0..rec.input_names.len())
        .map(|i| coord_name(rec.input_names, i))
        .collect();
    let mut error_names = state_names.clone();
    if rec.comparison.position_error.is_some() {
        error_names.push(Cow::Borrowed("position"));
    }
    for r in 1..=rec.comparison.robot_position_error.len() {
        error_names.push(Cow::Owned(format!("position_{r}")));
    }

    let ch_cmd = json_channel(
        ctx,
        "/plan/command",
        "anholonomy.Command",
        "Plan inputs applied from t on (ideal run)",
        &input_names,
        tmp,
    )?;
    let ch_sim_cmd = json_channel(
        ctx,
        "/sim/command",
        "anholonomy.Command",
        "Inputs the physics applied from t on (zero from the plan's end: settling)",
        &input_names,
        tmp,
    )?;
    let ch_ideal = json_channel(
        ctx,
        "/ideal/state",
        "anholonomy.State",
        "Model state; angles in rad",
        &state_names,
        tmp,
    )?;
    let ch_sim = json_channel(
        ctx,
        "/sim/state",
        "anholonomy.State",
        "Model state; angles in rad",
        &state_names,
        tmp,
    )?;
    let ch_err = json_channel(
        ctx,
        "/tracking/error",
        "anholonomy.TrackingError",
        "Sim minus ideal per coordinate (angles wrapped, rad); position = |p_sim - p_ideal| in m",
        &error_names,
        tmp,
    )?;
    let channel_names: Vec<Cow<'_, str>> = rec
        .sim
        .channels
        .iter()
        .map(|(n, _)| Cow::Borrowed(n.as_str()))
        .collect();
    let ch_chan = if channel_names.is_empty() {
        None
    } else {
        Some(json_channel(
            ctx,
            "/sim/channels",
            "anholonomy.SimChannels",
            "Extra measurements of the physics run (slip, momentum, ...), one per sim sample",
            &channel_names,
            tmp,
        )?)
    };
    let value_name = [Cow::Borrowed("value")];
    let ch_series = rec
        .series
        .iter()
        .map(|s| {
            json_channel(
                ctx,
                &format!("/analysis/{}", s.name),
                "anholonomy.Series",
                "A series the system computes from the runs (see the system's page in the guide)",
                &value_name,
                tmp,
            )
        })
        .collect::<Result<Vec<_>, _>>()?;
    let ch_tf = ctx
        .channel_builder("/tf")
        .build::<FrameTransforms>()
        .into_inner();
    let ch_scene = ctx.channel_builder("/scene").build::<SceneUpdate>();

    // Static scene at t = 0.
    ch_scene.log_with_time(&robot_scene(rec), 0u64);
    if let Some(paths) = paths_scene(rec) {
        let ch_paths = ctx.channel_builder("/scene/paths").build::<SceneUpdate>();
        ch_paths.log_with_time(&paths, 0u64);
    }

    let topics = events::Topics {
        rec,
        tmp,
        cmd: ch_cmd,
        sim_cmd: ch_sim_cmd,
        ideal: ch_ideal,
        sim: ch_sim,
        err: ch_err,
        series: ch_series,
        tf: ch_tf,
        keys_value: Keys::new(&value_name),
        keys_input: Keys::new(&input_names),
        keys_state: Keys::new(&state_names),
        keys_channel: Keys::new(&channel_names),
        keys_error: Keys::new(&error_names),
        error_len: error_names.len(),
        state_len: state_names.len(),
        frames: rec
            .links
            .iter()
            .map(|l| link_frame(&l.name).into_owned())
            .collect(),
        chan: ch_chan,
    };
    topics.log(&events::events(rec, topics.chan.is_some()))
}

// --------------------------------------------------------------------- scene

fn timestamp(ns: u64) -> Timestamp {
    Timestamp::new((ns / 1_000_000_000) as u32, (ns % 1_000_000_000) as u32)
}

fn vec3(v: [f64; 3]) -> Vector3 {
    Vector3 {
        x: v[0],
        y: v[1],
        z: v[2],
    }
}

fn quat(q: [f64; 4]) -> Quaternion {
    Quaternion {
        x: q[0],
        y: q[1],
        z: q[2],
        w: q[3],
    }
}

fn color(c: [f32; 4]) -> Color {
    Color {
        r: c[0] as f64,
        g: c[1] as f64,
        b: c[2] as f64,
        a: c[3] as f64,
    }
}

fn fg_pose(p: &Pose) -> FgPose {
    FgPose {
        position: Some(vec3(p.translation)),
        orientation: Some(quat(p.rotation)),
    }
}

/// `p` composed with a translation `d` along its local axes.
fn offset(p: &Pose, d: [f64; 3]) -> Pose {
    let [x, y, z, w] = p.rotation;
    // v' = v + 2 w (q × v) + 2 q × (q × v)
    let u = [x, y, z];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let c1 = cross(u, d);
    let c2 = cross(u, c1);
    let r = [0, 1, 2].map(|i| d[i] + 2.0 * w * c1[i] + 2.0 * c2[i]);
    Pose {
        translation: [0, 1, 2].map(|i| p.translation[i] + r[i]),
        rotation: p.rotation,
    }
}

fn sphere(p: &Pose, radius: f64, c: Color) -> SpherePrimitive {
    let d = 2.0 * radius;
    SpherePrimitive {
        pose: Some(fg_pose(p)),
        size: Some(vec3([d, d, d])),
        color: Some(c),
    }
}

fn cylinder(p: &Pose, radius: f64, length: f64, c: Color) -> CylinderPrimitive {
    let d = 2.0 * radius;
    CylinderPrimitive {
        pose: Some(fg_pose(p)),
        size: Some(vec3([d, d, length])),
        bottom_scale: 1.0,
        top_scale: 1.0,
        color: Some(c),
    }
}

/// URDF visuals, one entity per link, frame-locked to the link frame.
fn robot_scene(rec: &RunRecord<'_>) -> SceneUpdate {
    let entities = rec
        .links
        .iter()
        .filter(|l| !l.visuals.is_empty())
        .map(|link| {
            let frame = link_frame(&link.name).into_owned();
            let mut e = SceneEntity {
                timestamp: Some(timestamp(0)),
                frame_id: frame.clone(),
                id: frame,
                lifetime: None,
                frame_locked: true,
                ..Default::default()
            };
            for v in &link.visuals {
                let c = color(v.rgba);
                match &v.shape {
                    Shape::Box { size } => e.cubes.push(CubePrimitive {
                        pose: Some(fg_pose(&v.origin)),
                        size: Some(vec3(*size)),
                        color: Some(c),
                    }),
                    Shape::Cylinder { radius, length } => {
                        e.cylinders.push(cylinder(&v.origin, *radius, *length, c))
                    }
                    Shape::Sphere { radius } => e.spheres.push(sphere(&v.origin, *radius, c)),
                    Shape::Mesh { mesh, .. } => e.triangles.push(TriangleListPrimitive {
                        pose: Some(fg_pose(&v.origin)),
                        // Foxglove draws a list of corners, three per triangle.
                        points: mesh
                            .triangles
                            .iter()
                            .flatten()
                            .map(|&i| {
                                let p = mesh.vertices[i as usize];
                                Point3 {
                                    x: p[0],
                                    y: p[1],
                                    z: p[2],
                                }
                            })
                            .collect(),
                        color: Some(c),
                        colors: vec![],
                        indices: vec![],
                    }),
                    &Shape::Capsule { radius, length } => {
                        // No capsule primitive in Foxglove: cylinder + two end spheres.
                        e.cylinders.push(cylinder(&v.origin, radius, length, c));
                        for s in [-0.5, 0.5] {
                            let end = offset(&v.origin, [0.0, 0.0, s * length]);
                            e.spheres.push(sphere(&end, radius, c));
                        }
                    }
                }
            }
            e
        })
        .collect();
    SceneUpdate {
        deletions: vec![],
        entities,
    }
}

fn line(points: &[[f64; 2]], rgba: [f32; 4]) -> LinePrimitive {
    LinePrimitive {
        r#type: line_primitive::Type::LineStrip as i32,
        pose: Some(fg_pose(&Pose::IDENTITY)),
        thickness: 3.0,
        scale_invariant: true,
        points: points
            .iter()
            .map(|p| Point3 {
                x: p[0],
                y: p[1],
                z: 0.0,
            })
            .collect(),
        color: Some(color(rgba)),
        colors: vec![],
        indices: vec![],
    }
}

/// Ideal / simulated paths and goal marker of every robot (models with a
/// planar position).
fn paths_scene(rec: &RunRecord<'_>) -> Option<SceneUpdate> {
    let ideal_paths = planar_paths(rec, rec.ideal);
    let s = marker_scale(ideal_paths.first()?);
    let entity = |id: &str| SceneEntity {
        timestamp: Some(timestamp(0)),
        frame_id: WORLD_FRAME.to_string(),
        id: id.to_string(),
        lifetime: None,
        frame_locked: true,
        ..Default::default()
    };
    let mut entities = Vec::new();
    let paths = ideal_paths.iter().zip(planar_paths(rec, &rec.sim.traj));
    for (r, (ideal, sim)) in paths.enumerate() {
        let sfx = robot_suffix(r);
        entities.push(SceneEntity {
            lines: vec![line(ideal, IDEAL_RGBA)],
            ..entity(&format!("ideal_path{sfx}"))
        });
        entities.push(SceneEntity {
            lines: vec![line(&sim, SIM_RGBA)],
            ..entity(&format!("sim_path{sfx}"))
        });
    }
    if let Some(real) = rec.real {
        let points: Vec<[f64; 2]> = real.pose.iter().map(|p| [p[0], p[1]]).collect();
        entities.push(SceneEntity {
            lines: vec![line(&points, REAL_RGBA)],
            ..entity("real_path")
        });
    }
    for o in rec.overlays {
        let mut line = line(&[], o.rgba);
        line.points = o
            .points
            .iter()
            .map(|p| Point3 {
                x: p[0],
                y: p[1],
                z: p[2],
            })
            .collect();
        let mut e = SceneEntity {
            lines: vec![line],
            ..entity(&o.name)
        };
        if let Some(link) = &o.link {
            e.frame_id = link_frame(link).into_owned();
        }
        entities.push(e);
    }
    for (r, [gx, gy]) in goal_points(rec).into_iter().enumerate() {
        let at = Pose {
            translation: [gx, gy, 0.0],
            rotation: [0.0, 0.0, 0.0, 1.0],
        };
        let mut goal = entity(&format!("goal{}", robot_suffix(r)));
        goal.spheres.push(sphere(&at, 0.5 * s, color(GOAL_RGBA)));
        // The goal heading is the first robot's.
        if let Some(h) = rec.goal_heading.filter(|_| r == 0) {
            let yaw = Pose {
                translation: at.translation,
                rotation: [0.0, 0.0, (0.5 * h).sin(), (0.5 * h).cos()],
            };
            goal.arrows.push(ArrowPrimitive {
                pose: Some(fg_pose(&yaw)),
                shaft_length: 2.0 * s,
                shaft_diameter: 0.2 * s,
                head_length: 0.8 * s,
                head_diameter: 0.5 * s,
                color: Some(color(GOAL_RGBA)),
            });
        }
        entities.push(goal);
    }
    Some(SceneUpdate {
        deletions: vec![],
        entities,
    })
}

// ------------------------------------------------------------------ metadata

fn metrics_metadata(rec: &RunRecord<'_>) -> BTreeMap<String, String> {
    rec.metrics
        .iter()
        .map(|(k, v)| (k.clone(), v.to_string()))
        .collect()
}

/// How `/plan/command` relates to the plan, and the plan itself (JSON strings).
fn plan_metadata(rec: &RunRecord<'_>) -> BTreeMap<String, String> {
    let c = rec.command;
    let mut m = BTreeMap::new();
    m.insert(
        "command".into(),
        c["kind"].as_str().unwrap_or("continuous").to_string(),
    );
    for key in ["hold_period_s", "jumps_s", "jump_count", "details"] {
        if !c[key].is_null() {
            m.insert(key.into(), c[key].to_string());
        }
    }
    m
}

fn run_metadata(rec: &RunRecord<'_>) -> BTreeMap<String, String> {
    let mut m = BTreeMap::new();
    m.insert("scenario".into(), rec.scenario.to_string());
    m.insert("state_names".into(), rec.state_names.join(","));
    m.insert("input_names".into(), rec.input_names.join(","));
    m.insert("labels".into(), rec.labels.join(","));
    m.insert("ideal_samples".into(), rec.ideal.len().to_string());
    m.insert("sim_samples".into(), rec.sim.traj.len().to_string());
    m.insert("sim_steps".into(), rec.sim.steps.to_string());
    m
}

#[cfg(test)]
mod tests;
