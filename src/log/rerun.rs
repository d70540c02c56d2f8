//! Rerun (.rrd) log of a run.
//!
//! Timeline `sim_time` (duration, s). Entities:
//!
//! * `robot/<link>`: per-link world pose (`Transform3D`) at every sim sample;
//!   `robot/<link>/visual_<k>`: static URDF visual (`Boxes3D`, `Cylinders3D`,
//!   `Ellipsoids3D` for spheres, `Capsules3D`) with its origin as a static
//!   `Transform3D`.
//! * `paths/ideal` (green), `paths/sim` (orange) and a recorded run's
//!   `paths/real` (grey, `[compare] reference`): static `LineStrips3D` of
//!   the planar path at z = 0, with a moving `Points3D` marker `paths/<run>/now`;
//!   `paths/goal` (+ `paths/goal/heading` arrow). Only for models with a planar
//!   position. With several robots these are the first robot's; the others'
//!   are `paths/ideal_2`, `paths/sim_2`, `paths/goal_2`, ... (no heading).
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

mod blueprint;

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
use rr::components::{FillMode, Radius, Scalar};
use rr::{EntityPath, EntityPathPart, RecordingStream, TimeColumn};

use crate::log::atomic::write_atomically;
use crate::log::scene::{
    coord_name, goal_points, marker_scale, planar_paths, robot_suffix, segment_name, GOAL_RGBA,
    IDEAL_RGBA, REAL_RGBA, SIM_RGBA,
};
use crate::log::{validate, LogError};
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
    let logged = blueprint::blueprint_msgs(rec)
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
        return Err(incomplete(format!(
            "bad header {}, expected RRF2",
            crate::echo::code(&String::from_utf8_lossy(&head))
        )));
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

    let (scene, robot) = blueprint::scene_extent(rec);
    // Thinner bodies (a 1 cm rod on a 10 m run) would draw below a pixel in
    // the overview: they are drawn at least this thick (the physics uses the
    // URDF's sizes).
    let thick = scene.radius() / 150.0;
    log_robot(stream, rec, thick)?;
    if let Some((link, r)) = blueprint::follow_frame(rec) {
        // A faint ring around the followed link: the follow view frames what
        // it shows, so the ring sets its scale to a few robot sizes (the
        // overview hides it).
        let ring: Vec<[f32; 3]> = (0..=48)
            .map(|k| {
                let a = k as f64 * std::f64::consts::TAU / 48.0;
                [(r * a.cos()) as f32, (r * a.sin()) as f32, 0.0]
            })
            .collect();
        stream.log_static(
            ep(&["robot", &link, blueprint::FOLLOW_RING]),
            &rr::LineStrips3D::new([ring])
                .with_colors([rgba([0.5, 0.5, 0.5, 0.5])])
                .with_radii([Radius::new_ui_points(0.75)]),
        )?;
    }
    log_paths(stream, rec, robot)?;

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
        // The runs in their path colours, a bound in the goal's red.
        let color = match parts.last().copied() {
            Some("ideal") => Some(IDEAL_RGBA),
            Some("sim") => Some(SIM_RGBA),
            Some("bound") => Some(GOAL_RGBA),
            _ => None,
        };
        series_style(stream, &p, &s.name, color, false)?;
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

fn log_robot(stream: &RecordingStream, rec: &RunRecord<'_>, thick: f64) -> Result<(), RrError> {
    let r_min = 0.5 * thick;
    let pose_times: Vec<f64> = rec.sim.link_pose_times().collect();
    for (i, link) in rec.links.iter().enumerate() {
        let link_path = ep(&["robot", &link.name]);
        for (k, v) in link.visuals.iter().enumerate() {
            let vp = ep(&["robot", &link.name, &format!("visual_{k}")]);
            stream.log_static(vp.clone(), &rr_transform(&v.origin))?;
            let c = [rgba(v.rgba)];
            match &v.shape {
                Shape::Mesh { mesh, .. } => stream.log_static(
                    vp,
                    &rr::Mesh3D::new(mesh.vertices.iter().map(|p| f32x3(*p)))
                        .with_triangle_indices(mesh.triangles.iter().copied())
                        .with_vertex_normals(mesh.vertex_normals().into_iter().map(f32x3))
                        .with_albedo_factor(c[0].0),
                )?,
                Shape::Box { size } => stream.log_static(
                    vp,
                    &rr::Boxes3D::from_half_sizes([f32x3(size.map(|s| 0.5 * s.max(thick)))])
                        .with_colors(c)
                        .with_fill_mode(FillMode::Solid),
                )?,
                &Shape::Cylinder { radius, length } => stream.log_static(
                    vp,
                    &rr::Cylinders3D::from_lengths_and_radii(
                        [length as f32],
                        [radius.max(r_min) as f32],
                    )
                    .with_colors(c)
                    .with_fill_mode(FillMode::Solid),
                )?,
                &Shape::Sphere { radius } => stream.log_static(
                    vp,
                    &rr::Ellipsoids3D::from_radii([radius.max(r_min) as f32])
                        .with_colors(c)
                        .with_fill_mode(FillMode::Solid),
                )?,
                // Rerun capsules run from z = 0 to z = length; URDF-style ones are centred.
                &Shape::Capsule { radius, length } => stream.log_static(
                    vp,
                    &rr::Capsules3D::from_lengths_and_radii(
                        [length as f32],
                        [radius.max(r_min) as f32],
                    )
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

/// Overlays, every robot's ideal and simulated path with its moving marker, and the goals
/// (`robot`: the robot's size, m, for the goal posts' height).
fn log_paths(stream: &RecordingStream, rec: &RunRecord<'_>, robot: f64) -> Result<(), RrError> {
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
    let ideal_paths = planar_paths(rec, rec.ideal);
    let Some(first) = ideal_paths.first() else {
        return Ok(());
    };
    let s = marker_scale(first) as f32;
    let several = ideal_paths.len() > 1;
    // The simulated path lies a little above the ideal one and thinner, so
    // where the two coincide (a car 2 mm off its plan) it runs as an orange
    // line inside a green band instead of hiding under it.
    let lift = 0.05 * s;
    let paths = ideal_paths.iter().zip(planar_paths(rec, &rec.sim.traj));
    for (r, (ideal, sim)) in paths.enumerate() {
        let sfx = robot_suffix(r);
        for (run, path, t, color, z, width) in [
            ("ideal", ideal, &rec.ideal.t, IDEAL_RGBA, 0.0, 4.0),
            ("sim", &sim, &rec.sim.traj.t, SIM_RGBA, lift, 1.5),
        ] {
            let name = format!("{run}{sfx}");
            let strip: Vec<[f32; 3]> = path.iter().map(|p| [p[0] as f32, p[1] as f32, z]).collect();
            let label = if several {
                format!("robot {} {run}", r + 1)
            } else {
                run.to_string()
            };
            stream.log_static(
                ep(&["paths", &name]),
                &rr::LineStrips3D::new([strip.clone()])
                    .with_colors([rgba(color)])
                    .with_radii([Radius::new_ui_points(width)])
                    .with_labels([label.as_str()])
                    // In 3D the label sits on the robot; colours and hover name it.
                    .with_show_labels(false),
            )?;
            let now = ep(&["paths", &name, "now"]);
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
        // Which path pair is which robot: a label at each start.
        if several {
            if let Some(p) = ideal.first() {
                stream.log_static(
                    ep(&["paths", &format!("start{sfx}")]),
                    &rr::Points3D::new([[p[0] as f32, p[1] as f32, 0.0]])
                        .with_colors([rgba(IDEAL_RGBA)])
                        .with_radii([Radius::new_scene_units(0.3 * s)])
                        .with_labels([format!("robot {}", r + 1)])
                        .with_show_labels(true),
                )?;
            }
        }
    }
    if let Some(real) = rec.real {
        // The recording above both runs, between their widths.
        let strip: Vec<[f32; 3]> = real
            .pose
            .iter()
            .map(|p| [p[0] as f32, p[1] as f32, 2.0 * lift])
            .collect();
        stream.log_static(
            ep(&["paths", "real"]),
            &rr::LineStrips3D::new([strip.clone()])
                .with_colors([rgba(REAL_RGBA)])
                .with_radii([Radius::new_ui_points(2.5)])
                .with_labels(["real"])
                .with_show_labels(false),
        )?;
        let now = ep(&["paths", "real", "now"]);
        stream.log_static(
            now.clone(),
            &rr::Points3D::update_fields()
                .with_colors([rgba(REAL_RGBA)])
                .with_radii([Radius::new_scene_units(0.4 * s)]),
        )?;
        let cols = rr::Points3D::update_fields()
            .with_positions(strip)
            .columns_of_unit_batches()?;
        stream.send_columns(now, [time_col(&real.t)], cols)?;
    }
    // A post over each goal, taller than the robot, labelled on top: a robot
    // that reaches its goal covers a marker on the ground.
    let post = blueprint::goal_post_height(robot, s as f64) as f32;
    for (r, [gx, gy]) in goal_points(rec).into_iter().enumerate() {
        let at = [gx as f32, gy as f32, 0.0];
        let top = [gx as f32, gy as f32, post];
        let name = format!("goal{}", robot_suffix(r));
        let label = if several {
            format!("goal {}", r + 1)
        } else {
            "goal".to_string()
        };
        stream.log_static(
            ep(&["paths", &name]),
            &rr::Points3D::new([at])
                .with_colors([rgba(GOAL_RGBA)])
                .with_radii([Radius::new_scene_units(0.5 * s)])
                .with_labels([label.as_str()])
                .with_show_labels(false),
        )?;
        stream.log_static(
            ep(&["paths", &name, "post"]),
            &rr::LineStrips3D::new([[at, top]])
                .with_colors([rgba(GOAL_RGBA)])
                .with_radii([Radius::new_ui_points(2.0)]),
        )?;
        stream.log_static(
            ep(&["paths", &name, "label"]),
            &rr::Points3D::new([top])
                .with_colors([rgba(GOAL_RGBA)])
                .with_radii([Radius::new_scene_units(0.3 * s)])
                .with_labels([label.as_str()])
                .with_show_labels(true),
        )?;
        // The goal heading is the first robot's.
        if let Some(h) = rec.goal_heading.filter(|_| r == 0) {
            let len = 3.0 * s;
            stream.log_static(
                ep(&["paths", &name, "heading"]),
                &rr::Arrows3D::from_vectors([[len * h.cos() as f32, len * h.sin() as f32, 0.0]])
                    .with_origins([at])
                    .with_colors([rgba(GOAL_RGBA)]),
            )?;
        }
    }
    Ok(())
}

// ---------------------------------------------------------------- blueprint
