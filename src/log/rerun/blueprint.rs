//! The Rerun blueprint of a run: a 3D overview whose camera frames the whole
//! run, a follow view for runs much larger than the robot, time-series views
//! over the whole run with fitted value ranges, and overlays hidden by default.

use crate::log::rerun::rr;
use rr::blueprint::components::{Corner2D, Eye3DKind, LinkAxis, PanelState};
use rr::blueprint::{
    Blueprint, BlueprintActivation, BlueprintPanel, ContainerLike, Grid, Horizontal,
    SelectionPanel, Spatial3DView, Tabs, TextLogView, TimePanel, TimeSeriesView, Vertical,
};
use rr::external::re_log_types::BlueprintActivationCommand;
use rr::external::re_sdk_types::blueprint::archetypes::{
    EntityBehavior, EyeControls3D, PlotLegend, ScalarAxis, TimeAxis, VisibleTimeRanges,
};
use rr::external::re_sdk_types::datatypes::{
    Range1D, TimeInt, TimeRange, TimeRangeBoundary, VisibleTimeRange,
};
use rr::log::LogMsg;
use rr::AsComponents;

use crate::log::scene::{coord_name, goal_points, marker_scale, planar_paths};
use crate::record::{RunRecord, Shape};

use crate::log::rerun::{ep, RrError, TIMELINE};

/// Axis-aligned box over points, empty until a finite point is added.
#[derive(Clone, Copy)]
pub(super) struct Bounds {
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
    pub(super) fn radius(&self) -> f64 {
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
            let r = match &v.shape {
                Shape::Box { size } => {
                    0.5 * (size[0].powi(2) + size[1].powi(2) + size[2].powi(2)).sqrt()
                }
                Shape::Cylinder { radius, length } | Shape::Capsule { radius, length } => {
                    radius.hypot(0.5 * *length)
                        + if matches!(v.shape, Shape::Capsule { .. }) {
                            *radius
                        } else {
                            0.0
                        }
                }
                Shape::Sphere { radius } => *radius,
                Shape::Mesh { mesh, .. } => mesh.radius(),
            };
            (o[0] * o[0] + o[1] * o[1] + o[2] * o[2]).sqrt() + r
        })
        .fold(0.0, f64::max)
}

/// The run's extent (every link position over the run, both planar paths) and the robot's
/// size (link positions at the first sample plus the reach of their visuals). Overlays are
/// left out: a target line may run far beyond the motion.
pub(super) fn scene_extent(rec: &RunRecord<'_>) -> (Bounds, f64) {
    let mut scene = Bounds::new();
    let poses = &rec.sim.link_poses;
    let stride = (poses.len() / 2000).max(1);
    for row in poses.iter().step_by(stride).chain(poses.last()) {
        for p in row {
            scene.add(p.translation);
        }
    }
    for traj in [rec.ideal, &rec.sim.traj] {
        for path in planar_paths(rec, traj) {
            for p in path.iter().step_by((path.len() / 2000).max(1)) {
                scene.add([p[0], p[1], 0.0]);
            }
        }
    }
    let mut robot = Bounds::new();
    let mut reach: f64 = 0.0;
    let goals = goal_points(rec);
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
    // The goal posts and their labels are in the picture.
    if let Some(first) = planar_paths(rec, rec.ideal).first() {
        let h = goal_post_height(size, marker_scale(first));
        for [x, y] in goals {
            scene.add([x, y, h]);
        }
    }
    if scene.is_empty() {
        scene.add([0.0; 3]);
    }
    (scene, size)
}

/// Entity name of the ring around the followed link (under `robot/<link>/`).
pub(super) const FOLLOW_RING: &str = "follow_ring";

/// The link a follow view tracks and the radius of the ring that frames it:
/// when the run is more than three times the robot's size.
pub(super) fn follow_frame(rec: &RunRecord<'_>) -> Option<(String, f64)> {
    let (scene, robot) = scene_extent(rec);
    let link = rec.links.first()?;
    (!rec.sim.link_poses.is_empty() && scene.radius() > 3.0 * robot)
        .then(|| (link.name.clone(), 1.5 * robot))
}

/// Height of the post over a goal: above the robot (which covers a goal it
/// reaches), and visible at the run's scale (`marker`: the path markers' size).
pub(super) fn goal_post_height(robot: f64, marker: f64) -> f64 {
    (1.5 * robot).max(4.0 * marker)
}

/// Orbit camera looking at `target` from the south-west and above, far enough that a sphere of
/// `radius` around the target fills most of the view.
/// A tracking-error view: title, entity paths, series.
type ErrorGroup<'a> = (&'a str, Vec<String>, Vec<&'a [f64]>);

fn eye(target: [f64; 3], radius: f64, aspect: f64) -> EyeControls3D {
    let dir: [f64; 3] = [-0.45, -0.8, 0.62];
    let n = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt();
    // Vertical field of view of Rerun's default camera is about 55°; a view
    // narrower than tall (width / height = `aspect`) sees less across. 1.1
    // leaves a margin.
    let dist = 1.1 * radius / ((27.5f64).to_radians().tan() * aspect.min(1.0));
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

/// Which robot a coordinate or input belongs to, from the first number in its
/// name (`x2`, `q2_4`, `u1_3`, `omega1`); `None` when the name has no number.
fn robot_of(name: &str) -> Option<usize> {
    let digits: String = name
        .chars()
        .skip_while(|c| !c.is_ascii_digit())
        .take_while(|c| c.is_ascii_digit())
        .collect();
    digits.parse().ok()
}

/// Words of a physics channel's name that say where it is measured (which
/// robot, wheel, side or axis), not what: `slip_rear_left_lon` and
/// `slip_lateral_2` are both `slip`, `grasp1_force` is `grasp_force`.
const WHERE_WORDS: [&str; 13] = [
    "left", "right", "front", "middle", "back", "rear", "lon", "lat", "lateral", "x", "y", "z", "",
];

/// The quantity a physics channel measures, its name without robot numbers
/// and where-words: channels of one quantity share a plot, so one plot has
/// one unit (`grasp1_force` and `grasp1_torque` do not).
pub(super) fn channel_quantity(name: &str) -> String {
    let words: Vec<String> = name
        .split('_')
        .map(|w| w.trim_end_matches(|c: char| c.is_ascii_digit()).to_string())
        .filter(|w| !WHERE_WORDS.contains(&w.as_str()))
        .collect();
    if words.is_empty() {
        name.to_string()
    } else {
        words.join("_")
    }
}

/// Units of the analysis groups whose unit is known (titles name it).
fn analysis_unit(group: &str) -> &'static str {
    match group {
        "grasp_force" => " (N)",
        "grasp_torque" => " (N m)",
        _ => "",
    }
}

/// Most legend rows a plot shows (above the data); more are left to hover.
const MAX_LEGEND: usize = 4;

/// Grid columns for `n` plots: short titles stay readable.
fn columns(n: usize) -> u32 {
    if n <= 4 {
        2
    } else {
        3
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
    .chain(rec.series.iter().filter_map(|s| s.t.last()))
    .fold(0.0f64, |m, t| m.max(*t));
    // A time-series view over the whole run, its value axis fitted to `values`
    // with room above the data for the legend of `legend` entries (none: no legend).
    let mut series = |view: TimeSeriesView,
                      legend: usize,
                      values: &mut dyn Iterator<Item = f64>|
     -> ContainerLike {
        let c: ContainerLike = view.into();
        if let Some(p) = view_path(&c) {
            let (ranges, axis) = whole_run(end);
            props.push((format!("{p}/VisibleTimeRanges"), Box::new(ranges)));
            props.push((format!("{p}/TimeAxis"), Box::new(axis)));
            let [lo, hi] = value_range(values);
            // The legend sits in the top right corner, over this headroom, not on the data.
            let head = if legend > 1 && legend <= MAX_LEGEND {
                (0.1 + 0.15 * legend as f64).min(0.8)
            } else {
                0.0
            };
            let y = ScalarAxis::new().with_range(Range1D([lo, hi + head * (hi - lo)]));
            props.push((format!("{p}/ScalarAxis"), Box::new(y)));
            // More rows than fit above a plot (a car's eight slip channels) would
            // cover the data whatever the headroom: hover names those.
            let lg = PlotLegend::new()
                .with_corner(Corner2D::RightTop)
                .with_visible(legend > 1 && legend <= MAX_LEGEND);
            props.push((format!("{p}/PlotLegend"), Box::new(lg)));
        }
        c
    };
    let (ideal, sim, cmp) = (rec.ideal, &rec.sim.traj, rec.comparison);
    let position_idx = rec.position().map(|p| p.to_vec()).unwrap_or_default();
    let unit_of = |i: usize| {
        if rec.angular.contains(&i) {
            " (rad)"
        } else if position_idx.contains(&i) {
            " (m)"
        } else {
            ""
        }
    };
    let several = rec.robot_positions.len() > 1;

    let mut state_views: Vec<(Option<usize>, ContainerLike)> = Vec::new();
    for i in 0..rec.state_names.len() {
        let name = coord_name(rec.state_names, i);
        let v = series(
            TimeSeriesView::new(format!("{name}{}", unit_of(i))).with_origin(ep(&["state", &name])),
            2,
            &mut ideal.q.iter().chain(&sim.q).map(|q| q[i]),
        );
        state_views.push((robot_of(&name).filter(|_| several), v));
    }

    // Tracking errors by unit: one axis never mixes metres and radians.
    let mut groups: [ErrorGroup<'_>; 3] = [
        ("error, lengths (m)", Vec::new(), Vec::new()),
        ("error, angles (rad)", Vec::new(), Vec::new()),
        ("error, other coordinates", Vec::new(), Vec::new()),
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
    // A feedback policy's sim run reacts to its own state: its distance to the ideal run is
    // not a tracking error (the report shows those metrics as n/a), so no such plots.
    let mut analysis: Vec<ContainerLike> = groups
        .into_iter()
        .filter(|(_, c, _)| rec.tracking_meaningful && !c.is_empty())
        .map(|(name, contents, data)| {
            let n = contents.len();
            series(
                TimeSeriesView::new(name)
                    .with_origin("/errors")
                    .with_contents(contents),
                n,
                &mut data.into_iter().flatten().copied(),
            )
        })
        .collect();
    // The analysis series: one plot per group (the first path component: `V`,
    // `grasp_force`, ...), so a quantity shares its axis with its bound, not
    // with quantities of other units.
    let mut a_groups: Vec<&str> = Vec::new();
    for s in rec.series.iter() {
        let g = s.name.split('/').find(|p| !p.is_empty()).unwrap_or("");
        if !a_groups.contains(&g) {
            a_groups.push(g);
        }
    }
    for g in a_groups {
        let members: Vec<&crate::record::Series> = rec
            .series
            .iter()
            .filter(|s| s.name.split('/').find(|p| !p.is_empty()).unwrap_or("") == g)
            .collect();
        analysis.push(series(
            TimeSeriesView::new(format!("{g}{}", analysis_unit(g)))
                .with_origin(ep(&["analysis", g]).to_string()),
            members.len(),
            &mut members.iter().flat_map(|s| s.values.iter().copied()),
        ));
    }

    // One view per command (inputs may have different units: m/s and rad/s).
    let mut command_views: Vec<(Option<usize>, ContainerLike)> = Vec::new();
    for j in 0..rec.input_names.len() {
        let name = coord_name(rec.input_names, j);
        let v = series(
            TimeSeriesView::new(name.to_string()).with_origin(ep(&["command", &name])),
            1,
            &mut ideal.u.iter().map(|u| u[j]),
        );
        command_views.push((robot_of(&name).filter(|_| several), v));
    }
    // Sim channels grouped by the quantity they measure (every wheel's slip in
    // one plot, each robot's grasp force with the other's, never a force with a
    // torque); slip goes to the analysis tab.
    let mut channel_groups: Vec<(String, Vec<usize>)> = Vec::new();
    for (k, (name, _)) in rec.sim.channels.iter().enumerate() {
        let key = channel_quantity(name);
        match channel_groups.iter_mut().find(|(g, _)| *g == key) {
            Some((_, v)) => v.push(k),
            None => channel_groups.push((key, vec![k])),
        }
    }
    let mut channel_views: Vec<ContainerLike> = Vec::new();
    for (key, idx) in &channel_groups {
        let contents: Vec<String> = idx
            .iter()
            .map(|&k| ep(&["sim", &rec.sim.channels[k].0]).to_string())
            .collect();
        let title = if idx.len() == 1 {
            rec.sim.channels[idx[0]].0.clone()
        } else if idx.len() > MAX_LEGEND {
            format!("{key}: {} channels (hover for names)", idx.len())
        } else {
            key.clone()
        };
        let v = series(
            TimeSeriesView::new(title)
                .with_origin("/sim")
                .with_contents(contents),
            idx.len(),
            &mut idx
                .iter()
                .flat_map(|&k| rec.sim.channels[k].1.iter().copied()),
        );
        if key == "slip" {
            analysis.push(v);
        } else {
            channel_views.push(v);
        }
    }

    // Tabs, the answer first: errors, V, the wrench against its bound, slip;
    // then the states and commands (per robot when there are several), the
    // other channels and the segment log.
    let grid = |name: String, views: Vec<ContainerLike>| -> ContainerLike {
        let n = views.len();
        Grid::new(views)
            .with_name(name)
            .with_grid_columns(columns(n))
            .into()
    };
    let per_robot = |what: &str, views: Vec<(Option<usize>, ContainerLike)>| {
        let mut robots: Vec<Option<usize>> = Vec::new();
        for (r, _) in &views {
            if !robots.contains(r) {
                robots.push(*r);
            }
        }
        robots.sort();
        let mut views: Vec<Option<(Option<usize>, ContainerLike)>> =
            views.into_iter().map(Some).collect();
        robots
            .into_iter()
            .map(|r| {
                let mine: Vec<ContainerLike> = views
                    .iter_mut()
                    .filter(|v| v.as_ref().is_some_and(|(vr, _)| *vr == r))
                    .filter_map(|v| v.take().map(|(_, c)| c))
                    .collect();
                let name = match r {
                    Some(r) => format!("{what}, robot {r}"),
                    None => what.to_string(),
                };
                (name, mine)
            })
            .collect::<Vec<_>>()
    };
    let mut tabs: Vec<ContainerLike> = Vec::new();
    if !analysis.is_empty() {
        tabs.push(grid("analysis".into(), analysis));
    }
    for (name, views) in per_robot("state", state_views) {
        tabs.push(grid(name, views));
    }
    for (name, views) in per_robot("commands", command_views) {
        tabs.push(grid(name, views));
    }
    if !channel_views.is_empty() {
        tabs.push(grid("sim channels".into(), channel_views));
    }
    tabs.push(TextLogView::new("segments").with_origin("/segment").into());

    // 3D: an overview framing the whole run, and a view following the robot when the run
    // is much larger than the robot (the rover: a 0.6 m robot on a 10 m path).
    let (scene, robot) = scene_extent(rec);
    let hidden = hidden_overlays(rec);
    let follow = rec
        .links
        .first()
        .filter(|_| !rec.sim.link_poses.is_empty() && scene.radius() > 3.0 * robot);
    let follows = follow.is_some();
    let overview: ContainerLike = Spatial3DView::new("run overview")
        .with_origin("/")
        .with_contents(["/robot/**", "/paths/**"])
        .into();
    if let Some(p) = view_path(&overview) {
        let radius = scene.radius().max(robot);
        // The left half of a 16:10 window, whole or halved by the follow view.
        let aspect = if follows { 1.6 } else { 0.8 };
        props.push((
            format!("{p}/EyeControls3D"),
            Box::new(eye(scene.center(), radius, aspect)),
        ));
        hide_in_view(&mut props, &p, &hidden);
        if let Some(link) = follow {
            let ring = ep(&["robot", &link.name, FOLLOW_RING]).to_string();
            hide_in_view(&mut props, &p, &[ring]);
        }
    }
    let mut left = vec![overview];
    if let Some(link) = follow {
        // Only the robot and the runs' current positions: the viewer frames a view on what
        // it shows, so the static paths (the whole run) would frame it at run scale.
        let c: ContainerLike = Spatial3DView::new(format!("following {}", link.name))
            .with_origin("/")
            .with_contents(["/robot/**", "/paths/*/now"])
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
    let bp = Blueprint::new(
        Horizontal::new([Vertical::new(left).into(), Tabs::new(tabs).into()])
            .with_column_shares([1.0, 1.0]),
    )
    .with_time_panel(TimePanel::new().with_timeline(TIMELINE))
    .with_blueprint_panel(BlueprintPanel::new().with_state(PanelState::Collapsed))
    .with_selection_panel(SelectionPanel::new().with_state(PanelState::Collapsed));
    (bp, props)
}

/// The blueprint as messages for [`RecordingStream::send_blueprint`]: the SDK's own layout
/// messages (captured from a memory stream) followed by the view properties, in the same
/// blueprint store, activated by the command returned last.
pub(super) fn blueprint_msgs(
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
