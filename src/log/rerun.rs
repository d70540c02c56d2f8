//! Rerun (.rrd) log of a run.
//!
//! Timeline `sim_time` (duration, s). Entities:
//!
//! * `robot/<link>`: per-link world pose (`Transform3D`) at every sim sample;
//!   `robot/<link>/visual_<k>`: static URDF visual (`Boxes3D`, `Cylinders3D`,
//!   `Ellipsoids3D` for spheres, `Capsules3D`) with its origin as a static
//!   `Transform3D`.
//! * `paths/ideal` (green) and `paths/sim` (orange): static `LineStrips3D` of
//!   the planar path at z = 0, with a moving `Points3D` marker `paths/<run>/now`;
//!   `paths/goal` (+ `paths/goal/heading` arrow). Only for models with a planar
//!   position.
//! * `state/<coord>/ideal`, `state/<coord>/sim`, `errors/<coord>`,
//!   `errors/position`, `command/<input>`, `sim/<channel>`: `Scalars` series.
//! * `segment`: `TextLog` entry whenever the plan label changes.
//! * Recording properties: `metrics` (one scalar per metric), `run` (scenario).
//!
//! A blueprint lays out a 3D overview (`/robot/**`, `/paths/**`) whose camera
//! frames the whole run (both paths and every link position, overlays such as
//! target lines excluded), a second 3D view that follows the robot's first
//! link when the run is much larger than the robot, one time-series view per
//! state coordinate (ideal vs sim), tracking errors split by unit (lengths in
//! m, angles in rad, other coordinates), one view per command, sim channels
//! grouped by their leading name token (`slip_*`, ...) and the segment log.
//! Every time-series view shows the whole run (not a trailing window) with a
//! value range fitted to its data. The blueprint and its view properties (camera, time ranges) go
//! into the recording as one blueprint store, activated once complete.

use std::fmt::Display;
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

/// The Rerun SDK as this writer names it: `re_sdk` plus the types the
/// `rerun` facade crate re-exports (the facade is not a dependency: see
/// Cargo.toml).
mod rr {
    pub use re_sdk::log::TimeColumn;
    pub use re_sdk::*;
    pub use re_sdk_types::archetypes::*;
    pub use re_sdk_types::components::Color;
    pub use re_sdk_types::datatypes::Quaternion;
    pub use re_sdk_types::{components, AnyValues};

    pub mod external {
        pub use re_sdk::external::*;
        pub use re_sdk_types;
    }
}
use rr::blueprint::components::{Eye3DKind, LinkAxis, PanelState};
use rr::blueprint::{
    Blueprint, BlueprintActivation, BlueprintPanel, ContainerLike, Grid, Horizontal,
    SelectionPanel, Spatial3DView, Tabs, TextLogView, TimePanel, TimeSeriesView, Vertical,
};
use rr::components::{FillMode, Radius, Scalar};
use rr::external::re_log_types::BlueprintActivationCommand;
use rr::external::re_sdk_types::blueprint::archetypes::{
    EntityBehavior, EyeControls3D, ScalarAxis, TimeAxis, VisibleTimeRanges,
};
use rr::external::re_sdk_types::datatypes::{
    Range1D, TimeInt, TimeRange, TimeRangeBoundary, VisibleTimeRange,
};
use rr::log::LogMsg;
use rr::{AsComponents, EntityPath, EntityPathPart, RecordingStream, TimeColumn};

use super::atomic::write_atomically;
use super::scene::{
    coord_name, goal_pose, marker_scale, planar_path, segment_name, GOAL_RGBA, IDEAL_RGBA, SIM_RGBA,
};
use super::{validate, LogError};
use crate::record::{Pose, RunRecord, Shape};

/// Name of the timeline all temporal data is logged on.
pub const TIMELINE: &str = "sim_time";

/// Write the Rerun recording of `rec` to `path` (atomically: via `<path>.tmp` + rename).
pub fn write_rrd(path: &Path, rec: &RunRecord<'_>) -> Result<(), LogError> {
    validate(path, rec)?;
    write_atomically(path, |tmp| write_file(tmp, rec))
}

/// Errors of the logging calls (SDK errors are rendered to text).
#[derive(Debug)]
struct RrError(String);

impl<E: Display> From<E> for RrError {
    fn from(e: E) -> Self {
        RrError(e.to_string())
    }
}

fn write_file(tmp: &Path, rec: &RunRecord<'_>) -> Result<(), LogError> {
    let rr_err = |message: String| LogError::Rerun {
        path: tmp.to_path_buf(),
        message,
    };
    let stream = rr::RecordingStreamBuilder::new("anholonomy")
        .recording_name(rec.scenario)
        // The caller asked for a file: ignore a `RERUN=off` environment.
        .enabled(true)
        .save(tmp)
        .map_err(|e| rr_err(e.to_string()))?;
    let logged = blueprint_msgs(rec)
        .map(|(msgs, cmd)| stream.send_blueprint(msgs, cmd))
        .and_then(|()| log_all(&stream, rec));
    let flushed = stream.flush_blocking();
    // Dropping the last handle joins the batcher and file-writer threads; the
    // file writer appends the RRD footer when it shuts down.
    drop(stream);
    logged.map_err(|e| rr_err(e.0))?;
    flushed.map_err(|e| rr_err(format!("flush failed: {e}")))?;
    check_complete(tmp)
}

/// The file must start with the RRD stream header and end with the stream footer.
fn check_complete(path: &Path) -> Result<(), LogError> {
    let incomplete = |reason: String| LogError::Incomplete {
        path: path.to_path_buf(),
        reason,
    };
    let io = |e: std::io::Error| LogError::Io {
        op: "cannot read back",
        path: path.to_path_buf(),
        source: e,
    };
    let mut f = std::fs::File::open(path).map_err(io)?;
    let len = f.metadata().map_err(io)?.len();
    if len < 24 {
        return Err(incomplete(format!("only {len} bytes")));
    }
    let mut head = [0u8; 4];
    f.read_exact(&mut head).map_err(io)?;
    // Stream footer: [entries...] "RRF2" "FOOT" <u32 count>.
    let mut tail = [0u8; 12];
    f.seek(SeekFrom::End(-12)).map_err(io)?;
    f.read_exact(&mut tail).map_err(io)?;
    if &head != b"RRF2" {
        return Err(incomplete(format!("bad header {head:?}, expected RRF2")));
    }
    if &tail[..8] != b"RRF2FOOT" {
        return Err(incomplete(
            "no RRD stream footer (writer did not finish)".into(),
        ));
    }
    Ok(())
}

// ------------------------------------------------------------------- paths

fn ep(parts: &[&str]) -> EntityPath {
    EntityPath::new(parts.iter().map(|p| EntityPathPart::new(*p)).collect())
}

fn rgba(c: [f32; 4]) -> rr::Color {
    let b = |x: f32| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
    rr::Color::from_unmultiplied_rgba(b(c[0]), b(c[1]), b(c[2]), b(c[3]))
}

fn f32x3(v: [f64; 3]) -> [f32; 3] {
    v.map(|x| x as f32)
}

fn quat(q: [f64; 4]) -> rr::Quaternion {
    rr::Quaternion::from_xyzw(q.map(|x| x as f32))
}

fn rr_transform(p: &Pose) -> rr::Transform3D {
    rr::Transform3D::from_translation_rotation(f32x3(p.translation), quat(p.rotation))
}

// ------------------------------------------------------------------ logging

fn time_col(t: &[f64]) -> TimeColumn {
    TimeColumn::new_duration_secs(TIMELINE, t.iter().copied())
}

fn send_scalars(
    stream: &RecordingStream,
    path: EntityPath,
    t: &[f64],
    values: impl IntoIterator<Item = f64>,
) -> Result<(), RrError> {
    let cols = rr::Scalars::new(values).columns_of_unit_batches()?;
    stream.send_columns(path, [time_col(t)], cols)?;
    Ok(())
}

fn series_style(
    stream: &RecordingStream,
    path: &EntityPath,
    name: &str,
    color: Option<[f32; 4]>,
    step: bool,
) -> Result<(), RrError> {
    let mut s = rr::SeriesLines::new().with_names([name]);
    if let Some(c) = color {
        s = s.with_colors([rgba(c)]);
    }
    if step {
        s = s.with_interpolation_mode(rr::components::InterpolationMode::StepAfter);
    }
    stream.log_static(path.clone(), &s)?;
    Ok(())
}

fn log_all(stream: &RecordingStream, rec: &RunRecord<'_>) -> Result<(), RrError> {
    stream.log_static(EntityPath::root(), &rr::ViewCoordinates::RIGHT_HAND_Z_UP())?;

    // Properties: scenario and metrics.
    stream.send_property(
        "run",
        &rr::AnyValues::default()
            .with_component::<rr::components::Text>("scenario", [rec.scenario]),
    )?;
    if !rec.metrics.is_empty() {
        let mut m = rr::AnyValues::default();
        for (name, v) in rec.metrics {
            // Empty names are not valid component identifiers; skip them.
            if let Ok(id) = rr::ComponentIdentifier::try_new(name) {
                m = m.with_component::<Scalar>(id, [*v]);
            }
        }
        stream.send_property("metrics", &m)?;
    }

    log_robot(stream, rec)?;
    log_paths(stream, rec)?;

    let ideal = rec.ideal;
    let sim = &rec.sim.traj;
    for i in 0..rec.state_names.len() {
        let name = coord_name(rec.state_names, i);
        let p_ideal = ep(&["state", &name, "ideal"]);
        let p_sim = ep(&["state", &name, "sim"]);
        series_style(
            stream,
            &p_ideal,
            &format!("{name} ideal"),
            Some(IDEAL_RGBA),
            false,
        )?;
        series_style(
            stream,
            &p_sim,
            &format!("{name} sim"),
            Some(SIM_RGBA),
            false,
        )?;
        send_scalars(stream, p_ideal, &ideal.t, ideal.q.iter().map(|q| q[i]))?;
        send_scalars(stream, p_sim, &sim.t, sim.q.iter().map(|q| q[i]))?;
        let p_err = ep(&["errors", &name]);
        series_style(stream, &p_err, &name, None, false)?;
        send_scalars(
            stream,
            p_err,
            &rec.comparison.t,
            rec.comparison.coord_error[i].iter().copied(),
        )?;
    }
    if let Some(pe) = &rec.comparison.position_error {
        let p = ep(&["errors", "position"]);
        series_style(stream, &p, "position", None, false)?;
        send_scalars(stream, p, &rec.comparison.t, pe.iter().copied())?;
    }
    for (r, pe) in rec.comparison.robot_position_error.iter().enumerate() {
        let name = format!("position_{}", r + 1);
        let p = ep(&["errors", &name]);
        series_style(stream, &p, &name, None, false)?;
        send_scalars(stream, p, &rec.comparison.t, pe.iter().copied())?;
    }
    for j in 0..rec.input_names.len() {
        let name = coord_name(rec.input_names, j);
        let p = ep(&["command", &name]);
        series_style(stream, &p, &name, None, true)?;
        send_scalars(stream, p, &ideal.t, ideal.u.iter().map(|u| u[j]))?;
    }
    for (name, values) in &rec.sim.channels {
        let p = ep(&["sim", name]);
        series_style(stream, &p, name, None, false)?;
        send_scalars(stream, p, &sim.t, values.iter().copied())?;
    }
    for s in rec.series {
        let mut parts = vec!["analysis"];
        parts.extend(s.name.split('/').filter(|p| !p.is_empty()));
        let p = ep(&parts);
        series_style(stream, &p, &s.name, None, false)?;
        send_scalars(stream, p, &s.t, s.values.iter().copied())?;
    }

    // Segment label: one text-log entry at every change.
    let mut times = Vec::new();
    let mut texts = Vec::new();
    for (k, &l) in ideal.label.iter().enumerate() {
        if k == 0 || ideal.label[k - 1] != l {
            times.push(ideal.t[k]);
            texts.push(format!("segment {}", segment_name(rec.labels, l)));
        }
    }
    if !times.is_empty() {
        let cols = rr::TextLog::update_fields()
            .with_many_text(texts)
            .columns_of_unit_batches()?;
        stream.send_columns("segment", [time_col(&times)], cols)?;
    }
    Ok(())
}

fn log_robot(stream: &RecordingStream, rec: &RunRecord<'_>) -> Result<(), RrError> {
    let pose_times: Vec<f64> = rec.sim.link_pose_times().collect();
    for (i, link) in rec.links.iter().enumerate() {
        let link_path = ep(&["robot", &link.name]);
        for (k, v) in link.visuals.iter().enumerate() {
            let vp = ep(&["robot", &link.name, &format!("visual_{k}")]);
            stream.log_static(vp.clone(), &rr_transform(&v.origin))?;
            let c = [rgba(v.rgba)];
            match v.shape {
                Shape::Box { size } => stream.log_static(
                    vp,
                    &rr::Boxes3D::from_half_sizes([f32x3(size.map(|s| 0.5 * s))])
                        .with_colors(c)
                        .with_fill_mode(FillMode::Solid),
                )?,
                Shape::Cylinder { radius, length } => stream.log_static(
                    vp,
                    &rr::Cylinders3D::from_lengths_and_radii([length as f32], [radius as f32])
                        .with_colors(c)
                        .with_fill_mode(FillMode::Solid),
                )?,
                Shape::Sphere { radius } => stream.log_static(
                    vp,
                    &rr::Ellipsoids3D::from_radii([radius as f32])
                        .with_colors(c)
                        .with_fill_mode(FillMode::Solid),
                )?,
                // Rerun capsules run from z = 0 to z = length; URDF-style ones are centred.
                Shape::Capsule { radius, length } => stream.log_static(
                    vp,
                    &rr::Capsules3D::from_lengths_and_radii([length as f32], [radius as f32])
                        .with_translations([[0.0, 0.0, -0.5 * length as f32]])
                        .with_colors(c)
                        .with_fill_mode(FillMode::Solid),
                )?,
            }
        }
        if rec.sim.link_poses.is_empty() {
            continue;
        }
        let poses = rec.sim.link_poses.iter().map(|row| &row[i]);
        let cols = rr::Transform3D::update_fields()
            .with_many_translation(poses.clone().map(|p| f32x3(p.translation)))
            .with_many_quaternion(poses.map(|p| quat(p.rotation)))
            .columns_of_unit_batches()?;
        stream.send_columns(link_path, [time_col(&pose_times)], cols)?;
    }
    Ok(())
}

fn log_paths(stream: &RecordingStream, rec: &RunRecord<'_>) -> Result<(), RrError> {
    for o in rec.overlays {
        let strip: Vec<[f32; 3]> = o
            .points
            .iter()
            .map(|p| [p[0] as f32, p[1] as f32, p[2] as f32])
            .collect();
        let path = match &o.link {
            Some(link) => ep(&["robot", link, &o.name]),
            None => ep(&["paths", &o.name]),
        };
        stream.log_static(
            path,
            &rr::LineStrips3D::new([strip])
                .with_colors([rgba(o.rgba)])
                .with_radii([Radius::new_ui_points(1.0)])
                .with_labels([o.name.as_str()])
                // Obstacles and ellipsoid covers can number dozens: their labels
                // would bury the robot. Names stay on hover and in the entity tree.
                .with_show_labels(false),
        )?;
    }
    let (Some(ideal), Some(sim)) = (planar_path(rec, rec.ideal), planar_path(rec, &rec.sim.traj))
    else {
        return Ok(());
    };
    let s = marker_scale(&ideal) as f32;
    let xyz = |p: &[f64; 2]| [p[0] as f32, p[1] as f32, 0.0];
    for (name, path, t, color) in [
        ("ideal", &ideal, &rec.ideal.t, IDEAL_RGBA),
        ("sim", &sim, &rec.sim.traj.t, SIM_RGBA),
    ] {
        let strip: Vec<[f32; 3]> = path.iter().map(xyz).collect();
        stream.log_static(
            ep(&["paths", name]),
            &rr::LineStrips3D::new([strip.clone()])
                .with_colors([rgba(color)])
                .with_radii([Radius::new_ui_points(1.5)])
                .with_labels([name])
                // In 3D the label sits on the robot; colours and hover name it.
                .with_show_labels(false),
        )?;
        let now = ep(&["paths", name, "now"]);
        stream.log_static(
            now.clone(),
            &rr::Points3D::update_fields()
                .with_colors([rgba(color)])
                .with_radii([Radius::new_scene_units(0.4 * s)]),
        )?;
        let cols = rr::Points3D::update_fields()
            .with_positions(strip)
            .columns_of_unit_batches()?;
        stream.send_columns(now, [time_col(t)], cols)?;
    }
    if let Some(([gx, gy], heading)) = goal_pose(rec) {
        let at = [gx as f32, gy as f32, 0.0];
        stream.log_static(
            ep(&["paths", "goal"]),
            &rr::Points3D::new([at])
                .with_colors([rgba(GOAL_RGBA)])
                .with_radii([Radius::new_scene_units(0.5 * s)])
                .with_labels(["goal"])
                .with_show_labels(false),
        )?;
        if let Some(h) = heading {
            let len = 3.0 * s;
            stream.log_static(
                ep(&["paths", "goal", "heading"]),
                &rr::Arrows3D::from_vectors([[len * h.cos() as f32, len * h.sin() as f32, 0.0]])
                    .with_origins([at])
                    .with_colors([rgba(GOAL_RGBA)]),
            )?;
        }
    }
    Ok(())
}

// ---------------------------------------------------------------- blueprint

/// Axis-aligned box over points, empty until a finite point is added.
#[derive(Clone, Copy)]
struct Bounds {
    lo: [f64; 3],
    hi: [f64; 3],
}

impl Bounds {
    fn new() -> Self {
        Bounds {
            lo: [f64::INFINITY; 3],
            hi: [f64::NEG_INFINITY; 3],
        }
    }
    fn add(&mut self, p: [f64; 3]) {
        if p.iter().all(|x| x.is_finite()) {
            for ((lo, hi), x) in self.lo.iter_mut().zip(&mut self.hi).zip(p) {
                *lo = lo.min(x);
                *hi = hi.max(x);
            }
        }
    }
    fn is_empty(&self) -> bool {
        self.lo[0] > self.hi[0]
    }
    fn center(&self) -> [f64; 3] {
        [0, 1, 2].map(|i| 0.5 * (self.lo[i] + self.hi[i]))
    }
    /// Half the diagonal.
    fn radius(&self) -> f64 {
        0.5 * (0..3)
            .map(|i| (self.hi[i] - self.lo[i]).powi(2))
            .sum::<f64>()
            .sqrt()
    }
}

/// Largest distance of a visual from its link frame origin (a crude robot size per link).
fn link_reach(link: &crate::record::LinkVisual) -> f64 {
    link.visuals
        .iter()
        .map(|v| {
            let o = v.origin.translation;
            let r = match v.shape {
                Shape::Box { size } => {
                    0.5 * (size[0].powi(2) + size[1].powi(2) + size[2].powi(2)).sqrt()
                }
                Shape::Cylinder { radius, length } | Shape::Capsule { radius, length } => {
                    radius.hypot(0.5 * length)
                        + if matches!(v.shape, Shape::Capsule { .. }) {
                            radius
                        } else {
                            0.0
                        }
                }
                Shape::Sphere { radius } => radius,
            };
            (o[0] * o[0] + o[1] * o[1] + o[2] * o[2]).sqrt() + r
        })
        .fold(0.0, f64::max)
}

/// The run's extent (every link position over the run, both planar paths) and the robot's
/// size (link positions at the first sample plus the reach of their visuals). Overlays are
/// left out: a target line may run far beyond the motion.
fn scene_extent(rec: &RunRecord<'_>) -> (Bounds, f64) {
    let mut scene = Bounds::new();
    let poses = &rec.sim.link_poses;
    let stride = (poses.len() / 2000).max(1);
    for row in poses.iter().step_by(stride).chain(poses.last()) {
        for p in row {
            scene.add(p.translation);
        }
    }
    for traj in [rec.ideal, &rec.sim.traj] {
        if let Some(path) = planar_path(rec, traj) {
            for p in path.iter().step_by((path.len() / 2000).max(1)) {
                scene.add([p[0], p[1], 0.0]);
            }
        }
    }
    let mut robot = Bounds::new();
    let mut reach: f64 = 0.0;
    if let Some(first) = poses.first() {
        for (p, link) in first.iter().zip(rec.links) {
            robot.add(p.translation);
            reach = reach.max(link_reach(link));
        }
    }
    let size = if robot.is_empty() {
        0.5
    } else {
        (robot.radius() + reach).max(0.05)
    };
    if scene.is_empty() {
        scene.add([0.0; 3]);
    }
    (scene, size)
}

/// Orbit camera looking at `target` from the south-west and above, far enough that a sphere of
/// `radius` around the target fills most of the view.
/// A tracking-error view: title, entity paths, series.
type ErrorGroup<'a> = (&'a str, Vec<String>, Vec<&'a [f64]>);

fn eye(target: [f64; 3], radius: f64) -> EyeControls3D {
    let dir: [f64; 3] = [-0.45, -0.8, 0.62];
    let n = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt();
    // Vertical field of view of Rerun's default camera is about 55°; 1.1 leaves a margin.
    let dist = 1.1 * radius / (27.5f64).to_radians().tan();
    let pos = [0, 1, 2].map(|i| (target[i] + dist * dir[i] / n) as f32);
    EyeControls3D::new()
        .with_kind(Eye3DKind::Orbital)
        .with_position(pos)
        .with_look_target(target.map(|x| x as f32))
        .with_eye_up([0.0f32, 0.0, 1.0])
}

/// The whole run on the `sim_time` axis (not a trailing window), s → ns.
fn whole_run(end_s: f64) -> (VisibleTimeRanges, TimeAxis) {
    let end = (end_s.max(0.0) * 1e9).ceil() as i64;
    let all = VisibleTimeRange {
        timeline: TIMELINE.into(),
        range: TimeRange {
            start: TimeRangeBoundary::Infinite,
            end: TimeRangeBoundary::Infinite,
        },
    };
    let axis = TimeAxis::new()
        .with_link(LinkAxis::Independent)
        .with_view_range(TimeRange {
            start: TimeRangeBoundary::Absolute(TimeInt(0)),
            end: TimeRangeBoundary::Absolute(TimeInt(end)),
        });
    (VisibleTimeRanges::new([all]), axis)
}

/// A view property to log into the blueprint store: `view/<id>/<archetype name>`.
type Property = (String, Box<dyn AsComponents>);

fn view_path(v: &ContainerLike) -> Option<String> {
    match v {
        ContainerLike::View(v) => Some(v.blueprint_path().to_string()),
        _ => None,
    }
}

/// Value range of a plot: the finite extremes, padded; a flat series gets a small band.
fn value_range(values: impl Iterator<Item = f64>) -> [f64; 2] {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if lo > hi {
        return [-1.0, 1.0];
    }
    let pad = if hi - lo > 1e-12 * hi.abs().max(lo.abs()) {
        0.05 * (hi - lo)
    } else {
        (0.1 * hi.abs()).max(1e-9)
    };
    [lo - pad, hi + pad]
}

/// Overlays logged but hidden in the 3D views until the user switches them on: the
/// robot's ellipsoid cover (dilf, `ellipsoid_*` on the links) wraps the arms and hides them.
fn hidden_overlays(rec: &RunRecord<'_>) -> Vec<String> {
    rec.overlays
        .iter()
        .filter_map(|o| match &o.link {
            Some(link) if o.name.starts_with("ellipsoid_") => {
                Some(ep(&["robot", link, &o.name]).to_string())
            }
            _ => None,
        })
        .collect()
}

/// Per-entity `visible = false` in a view, where the viewer (and the Python SDK's
/// `overrides=`) keeps entity behaviour: `<view>/ViewContents/overrides/<entity>/visualizers`.
fn hide_in_view(props: &mut Vec<Property>, view: &str, entities: &[String]) {
    for e in entities {
        let e = e.trim_start_matches('/');
        props.push((
            format!("{view}/ViewContents/overrides/{e}/visualizers"),
            Box::new(EntityBehavior::new().with_visible(false)),
        ));
    }
}

/// The layout, plus the view properties the SDK's builders cannot set.
fn blueprint(rec: &RunRecord<'_>) -> (Blueprint, Vec<Property>) {
    let mut props: Vec<Property> = Vec::new();
    let end = [
        rec.ideal.t.last(),
        rec.sim.traj.t.last(),
        rec.comparison.t.last(),
    ]
    .into_iter()
    .flatten()
    .fold(0.0f64, |m, t| m.max(*t));
    // A time-series view over the whole run, its value axis fitted to `values`.
    let mut series =
        |view: TimeSeriesView, values: &mut dyn Iterator<Item = f64>| -> ContainerLike {
            let c: ContainerLike = view.into();
            if let Some(p) = view_path(&c) {
                let (ranges, axis) = whole_run(end);
                props.push((format!("{p}/VisibleTimeRanges"), Box::new(ranges)));
                props.push((format!("{p}/TimeAxis"), Box::new(axis)));
                let y = ScalarAxis::new().with_range(Range1D(value_range(values)));
                props.push((format!("{p}/ScalarAxis"), Box::new(y)));
            }
            c
        };
    let (ideal, sim, cmp) = (rec.ideal, &rec.sim.traj, rec.comparison);

    let state_views: Vec<ContainerLike> = (0..rec.state_names.len())
        .map(|i| {
            let name = coord_name(rec.state_names, i);
            series(
                TimeSeriesView::new(format!("{name}: ideal vs sim"))
                    .with_origin(ep(&["state", &name])),
                &mut ideal.q.iter().chain(&sim.q).map(|q| q[i]),
            )
        })
        .collect();

    // Tracking errors by unit: one axis never mixes metres and radians.
    let position_idx = rec.position.map(|p| p.to_vec()).unwrap_or_default();
    let mut groups: [ErrorGroup<'_>; 3] = [
        ("tracking error, lengths (m)", Vec::new(), Vec::new()),
        ("tracking error, angles (rad)", Vec::new(), Vec::new()),
        ("tracking error, other coordinates", Vec::new(), Vec::new()),
    ];
    if let Some(p) = &cmp.position_error {
        groups[0].1.push("/errors/position".into());
        groups[0].2.push(p);
    }
    for (r, p) in cmp.robot_position_error.iter().enumerate() {
        groups[0].1.push(format!("/errors/position_{}", r + 1));
        groups[0].2.push(p);
    }
    for i in 0..rec.state_names.len() {
        let path = ep(&["errors", &coord_name(rec.state_names, i)]).to_string();
        let g = if rec.angular.contains(&i) {
            1
        } else if position_idx.contains(&i) {
            0
        } else {
            2
        };
        groups[g].1.push(path);
        groups[g].2.push(&cmp.coord_error[i]);
    }
    let error_views: Vec<ContainerLike> = groups
        .into_iter()
        .filter(|(_, c, _)| rec.tracking_meaningful && !c.is_empty())
        .map(|(name, contents, data)| {
            series(
                TimeSeriesView::new(name)
                    .with_origin("/errors")
                    .with_contents(contents),
                &mut data.into_iter().flatten().copied(),
            )
        })
        .collect();
    // One view per command (inputs may have different units: m/s and rad/s).
    let command_views: Vec<ContainerLike> = (0..rec.input_names.len())
        .map(|j| {
            let name = coord_name(rec.input_names, j);
            series(
                TimeSeriesView::new(format!("command {name}")).with_origin(ep(&["command", &name])),
                &mut ideal.u.iter().map(|u| u[j]),
            )
        })
        .collect();
    // Sim channels grouped by their leading name token (slip_*, angular_momentum_*, ...).
    let mut channel_groups: Vec<(String, Vec<usize>)> = Vec::new();
    for (k, (name, _)) in rec.sim.channels.iter().enumerate() {
        let key = name.split('_').next().unwrap_or(name).to_string();
        match channel_groups.iter_mut().find(|(g, _)| *g == key) {
            Some((_, v)) => v.push(k),
            None => channel_groups.push((key, vec![k])),
        }
    }
    let channel_views: Vec<ContainerLike> = channel_groups
        .iter()
        .map(|(key, idx)| {
            let contents: Vec<String> = idx
                .iter()
                .map(|&k| ep(&["sim", &rec.sim.channels[k].0]).to_string())
                .collect();
            let title = if idx.len() == 1 {
                rec.sim.channels[idx[0]].0.clone()
            } else {
                format!("{key}_*")
            };
            series(
                TimeSeriesView::new(title)
                    .with_origin("/sim")
                    .with_contents(contents),
                &mut idx
                    .iter()
                    .flat_map(|&k| rec.sim.channels[k].1.iter().copied()),
            )
        })
        .collect();
    // A feedback policy's sim run reacts to its own state: its distance to the ideal run is
    // not a tracking error (the report shows those metrics as n/a), so no such plots.
    let mut lower: Vec<ContainerLike> = Vec::new();
    if !error_views.is_empty() {
        lower.push(Grid::new(error_views).with_name("tracking errors").into());
    }
    lower.push(Grid::new(command_views).with_name("commands").into());
    if !channel_views.is_empty() {
        lower.push(Grid::new(channel_views).with_name("sim channels").into());
    }
    if !rec.series.is_empty() {
        // One plot per group (the first path component: `V`, `grasp_force`,
        // ...), so a quantity shares its axis with its bound, not with
        // quantities of other units.
        let mut groups: Vec<&str> = Vec::new();
        for s in rec.series.iter() {
            let g = s.name.split('/').find(|p| !p.is_empty()).unwrap_or("");
            if !groups.contains(&g) {
                groups.push(g);
            }
        }
        let views: Vec<ContainerLike> = groups
            .iter()
            .map(|g| {
                TimeSeriesView::new(*g)
                    .with_origin(ep(&["analysis", g]).to_string())
                    .into()
            })
            .collect();
        lower.push(Grid::new(views).with_name("analysis").into());
    }
    lower.push(TextLogView::new("segments").with_origin("/segment").into());

    // 3D: an overview framing the whole run, and a view following the robot when the run
    // is much larger than the robot (the rover: a 0.6 m robot on a 10 m path).
    let (scene, robot) = scene_extent(rec);
    let hidden = hidden_overlays(rec);
    let overview: ContainerLike = Spatial3DView::new("run overview")
        .with_origin("/")
        .with_contents(["/robot/**", "/paths/**"])
        .into();
    if let Some(p) = view_path(&overview) {
        let radius = scene.radius().max(robot);
        props.push((
            format!("{p}/EyeControls3D"),
            Box::new(eye(scene.center(), radius)),
        ));
        hide_in_view(&mut props, &p, &hidden);
    }
    let mut left = vec![overview];
    let follow = rec
        .links
        .first()
        .filter(|_| !rec.sim.link_poses.is_empty() && scene.radius() > 3.0 * robot);
    if let Some(link) = follow {
        let c: ContainerLike = Spatial3DView::new(format!("following {}", link.name))
            .with_origin("/")
            .with_contents(["/robot/**", "/paths/**"])
            .into();
        if let Some(p) = view_path(&c) {
            // Only the tracked entity: a fixed eye position in the blueprint would pin the
            // camera and override the tracking.
            let target =
                rr::components::EntityPath::from(ep(&["robot", &link.name]).to_string().as_str());
            let follow = EyeControls3D::new()
                .with_kind(Eye3DKind::Orbital)
                .with_eye_up([0.0f32, 0.0, 1.0])
                .with_tracking_entity(target);
            props.push((format!("{p}/EyeControls3D"), Box::new(follow)));
            hide_in_view(&mut props, &p, &hidden);
        }
        left.push(c);
    }
    let right = Vertical::new([
        Grid::new(state_views).with_name("state").into(),
        Tabs::new(lower).into(),
    ]);
    let bp = Blueprint::new(Horizontal::new([Vertical::new(left).into(), right.into()]))
        .with_time_panel(TimePanel::new().with_timeline(TIMELINE))
        .with_blueprint_panel(BlueprintPanel::new().with_state(PanelState::Collapsed))
        .with_selection_panel(SelectionPanel::new().with_state(PanelState::Collapsed));
    (bp, props)
}

/// The blueprint as messages for [`RecordingStream::send_blueprint`]: the SDK's own layout
/// messages (captured from a memory stream) followed by the view properties, in the same
/// blueprint store, activated by the command returned last.
fn blueprint_msgs(
    rec: &RunRecord<'_>,
) -> Result<(Vec<LogMsg>, BlueprintActivationCommand), RrError> {
    let (bp, props) = blueprint(rec);
    let (mem, storage) = rr::RecordingStreamBuilder::new("anholonomy").memory()?;
    bp.send(
        &mem,
        BlueprintActivation {
            make_active: true,
            make_default: true,
        },
    )?;
    mem.flush_blocking()?;
    let mut cmd = None;
    let mut msgs = Vec::new();
    for m in storage.take() {
        match m {
            LogMsg::BlueprintActivationCommand(c) => cmd = Some(c),
            other => msgs.push(other),
        }
    }
    drop(mem);
    let cmd = cmd.ok_or_else(|| RrError("blueprint without activation command".into()))?;
    msgs.retain(|m| *m.store_id() == cmd.blueprint_id);
    let (bp_rec, bp_storage) = rr::RecordingStreamBuilder::new("anholonomy")
        .recording_id(cmd.blueprint_id.recording_id().clone())
        .blueprint()
        .memory()?;
    bp_rec.set_time_sequence("blueprint", 0);
    for (path, arch) in &props {
        bp_rec.log(path.as_str(), arch.as_ref())?;
    }
    bp_rec.flush_blocking()?;
    msgs.extend(
        bp_storage
            .take()
            .into_iter()
            .filter(|m| !matches!(m, LogMsg::SetStoreInfo(_))),
    );
    Ok((msgs, cmd))
}
