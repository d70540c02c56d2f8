//! The Rapier counterpart of a declared model (`[model] kind =
//! "declared"`): the user's URDF, joints driven by the declared
//! expressions, the state read back from links and joints by name.
//!
//! * **Drives** (`[model.drive]`): a velocity servo on each named joint at
//!   the expression's value (rad/s or m/s), capped at the joint's
//!   `<limit effort>` (`[sim] motor_max_torque` when the URDF gives none),
//!   as the built-in wheeled models drive their wheels.
//!   `[model.drive_position]`: a position servo at the value (rad or m),
//!   within the joint's limits (steering).
//! * **Read-back** (`[model.read]`): `LINK.x|y|z|roll|pitch|yaw` (the link
//!   frame's origin and orientation in the world), `LINK.vx|vy|vz|wx|wy|wz`
//!   (its velocity in its own axes, [`crate::robots::declared::rates`]),
//!   `JOINT.position` or `JOINT.velocity`. The drive expressions see this
//!   read-back state, after the last step.
//!   Angles are unwrapped continuously.
//! * **Start**: the state's reads on the root body (x, y, yaw of links fixed
//!   to the root) place the robot, its lowest collision on the ground; a
//!   state read as a link's yaw one joint below, or as a joint's position,
//!   turns that joint.
//! * Links in `frictionless` have frictionless collisions (ideal casters);
//!   cylinder collisions of the children of continuous joints (wheels) touch
//!   the ground through a ball of their radius, as the built-in wheeled
//!   models' do ([`crate::robots::wheeled::roll_on_balls`]).

use crate::engine::angles;
use crate::engine::rapier::math::Pose as RPose;
use crate::engine::rapier::prelude::*;
use crate::engine::reading::UrdfReading;
use crate::engine::real::{f, r, vector};
use crate::engine::urdf::{Drive, SimWorld};
use crate::engine::urdf_text;
use crate::engine::{Fault, PhysicsSettings, PhysicsSystem};
use crate::error::SetupError;
use crate::model::{Input, KinematicModel, State};
use crate::record::Pose;
use crate::robots::declared::kinematics::{Declared, Expr};
use std::path::Path;
use urdf_rs::{JointType, Robot};

/// What a state is read from.
#[derive(Debug, Clone, PartialEq)]
pub enum Read {
    /// A link frame's coordinate: `x`, `y`, `z`, `roll`, `pitch` or `yaw`.
    Link(String, LinkCoord),
    /// A joint's position (`JOINT.position`).
    Joint(String),
    /// A link frame's velocity in its own axes: `vx`, `vy`, `vz` (m/s, of
    /// the frame's origin) or `wx`, `wy`, `wz` (rad/s); index 0 to 5.
    LinkVelocity(String, usize),
    /// A joint's velocity (`JOINT.velocity`, rad/s or m/s).
    JointVelocity(String),
}

/// The velocity components of a link read, in order.
const LINK_VELOCITIES: [&str; 6] = ["vx", "vy", "vz", "wx", "wy", "wz"];

/// A coordinate of a link frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LinkCoord {
    /// World x, m.
    X,
    /// World y, m.
    Y,
    /// World z, m.
    Z,
    /// Roll (about x, ZYX Euler angles), rad.
    Roll,
    /// Pitch, rad.
    Pitch,
    /// Yaw (heading about world z), rad.
    Yaw,
}

impl Read {
    /// `LINK.x|y|z|roll|pitch|yaw|vx|vy|vz|wx|wy|wz` or
    /// `JOINT.position|velocity`.
    pub fn parse(s: &str) -> Result<Read, SetupError> {
        let shown = crate::echo::code(s);
        let (name, what) = s.rsplit_once('.').ok_or_else(|| {
            format!("{shown}: expected LINK.x|y|z|roll|pitch|yaw|vx|vy|vz|wx|wy|wz or JOINT.position|velocity")
        })?;
        if name.is_empty() {
            return Err(SetupError::other(format!(
                "{shown}: no link or joint name before `.{}`",
                crate::echo::bare(what)
            )));
        }
        let coord = match what {
            "x" => LinkCoord::X,
            "y" => LinkCoord::Y,
            "z" => LinkCoord::Z,
            "roll" => LinkCoord::Roll,
            "pitch" => LinkCoord::Pitch,
            "yaw" => LinkCoord::Yaw,
            "position" => return Ok(Read::Joint(name.to_string())),
            "velocity" => return Ok(Read::JointVelocity(name.to_string())),
            v if LINK_VELOCITIES.contains(&v) => {
                let k = LINK_VELOCITIES.iter().position(|x| *x == v).unwrap_or(0);
                return Ok(Read::LinkVelocity(name.to_string(), k));
            }
            _ => {
                return Err(SetupError::other(format!(
                "{shown}: `.{}` is not a coordinate (LINK.x|y|z|roll|pitch|yaw|vx|vy|vz|wx|wy|wz or JOINT.position|velocity)",
                crate::echo::bare(what)
            )))
            }
        };
        Ok(Read::Link(name.to_string(), coord))
    }

    /// Whether the value is an angle (unwrapped across steps).
    fn angular(&self, robot: &Robot) -> bool {
        match self {
            Read::Link(_, c) => matches!(c, LinkCoord::Roll | LinkCoord::Pitch | LinkCoord::Yaw),
            Read::Joint(j) => robot
                .joints
                .iter()
                .any(|x| x.name == *j && x.joint_type != JointType::Prismatic),
            // A rate is not wrapped.
            Read::LinkVelocity(..) | Read::JointVelocity(_) => false,
        }
    }
}

/// A declared model's physics, as the system hands it over.
#[derive(Debug, Clone)]
pub struct Rig {
    /// State names (for the keys in messages).
    pub states: Vec<String>,
    /// One read per state.
    pub reads: Vec<Read>,
    /// Velocity-driven joints and their rate expressions.
    pub drives: Vec<(String, Expr)>,
    /// Position-driven joints and their angle expressions.
    pub positions: Vec<(String, Expr)>,
    /// Links whose collisions carry no friction.
    pub frictionless: Vec<String>,
    /// `[model] wheels`: the driven joints whose links wear (None: found).
    pub wheels: Option<Vec<String>>,
}

/// One read-back, resolved in the world.
#[derive(Debug, Clone)]
enum Source {
    Link(RigidBodyHandle, RPose, LinkCoord),
    Joint(ImpulseJointHandle),
    LinkVelocity(RigidBodyHandle, RPose, usize),
    JointVelocity(ImpulseJointHandle),
}

/// The declared model in Rapier.
pub struct DeclaredPhysics {
    sim: SimWorld,
    model: Declared,
    sources: Vec<Source>,
    angular: Vec<bool>,
    drives: Vec<(Drive, Expr)>,
    positions: Vec<(Drive, Expr)>,
    q: State,
    /// Slot values of the last command (states, inputs, parameters).
    values: Vec<f64>,
    reading: UrdfReading,
    /// The joints of `drives` and `positions`, for messages.
    drive_names: Vec<String>,
    position_names: Vec<String>,
    /// The first drive that was not finite ([`PhysicsSystem::fault`]).
    fault: Option<Fault>,
}

fn joint<'r>(robot: &'r Robot, name: &str) -> Option<&'r urdf_rs::Joint> {
    robot.joints.iter().find(|j| j.name == name)
}

/// The joint's driven axis.
fn axis_of(j: &urdf_rs::Joint) -> JointAxis {
    if j.joint_type == JointType::Prismatic {
        JointAxis::LinX
    } else {
        JointAxis::AngX
    }
}

impl DeclaredPhysics {
    /// Build the robot at `start`; errors name the `[model]` key at fault.
    pub fn new(
        robot: &Robot,
        urdf_dir: &Path,
        rig: &Rig,
        model: &Declared,
        start: &[f64],
        sim: &PhysicsSettings,
    ) -> Result<Self, SetupError> {
        // Every name against the URDF first, each error with its key.
        for (s, rd) in rig.states.iter().zip(&rig.reads) {
            let key = format!("model.read.{s}");
            match rd {
                Read::Link(l, _) | Read::LinkVelocity(l, _)
                    if !robot.links.iter().any(|x| x.name == *l) =>
                {
                    return Err(SetupError::key(
                        &key,
                        format!("URDF has no link {}", crate::echo::code(l)),
                    ))
                }
                Read::Joint(j) | Read::JointVelocity(j) => match joint(robot, j) {
                    None => {
                        return Err(SetupError::key(
                            &key,
                            format!("URDF has no joint {}", crate::echo::code(j)),
                        ))
                    }
                    Some(x) if matches!(x.joint_type, JointType::Fixed | JointType::Floating | JointType::Planar | JointType::Spherical) => {
                        return Err(SetupError::key(&key, format!("joint `{j}` is {}: only revolute, continuous and prismatic joints have one position",
                            urdf_text::joint_type(&x.joint_type)
                        )))
                    }
                    _ => {}
                },
                _ => {}
            }
        }
        for (table, list) in [("drive", &rig.drives), ("drive_position", &rig.positions)] {
            for (j, _) in list {
                let key = format!("model.{table}.{j}");
                match joint(robot, j) {
                    None => {
                        return Err(SetupError::key(
                            &key,
                            format!("URDF has no joint {}", crate::echo::code(j)),
                        ))
                    }
                    Some(x) if !matches!(x.joint_type, JointType::Revolute | JointType::Continuous | JointType::Prismatic) => {
                        return Err(SetupError::key(&key, format!("joint `{j}` is {}: a drive needs a revolute, continuous or prismatic joint",
                            urdf_text::joint_type(&x.joint_type)
                        )))
                    }
                    _ => {}
                }
            }
        }
        for l in &rig.frictionless {
            if !robot.links.iter().any(|x| x.name == *l) {
                return Err(SetupError::key(
                    "model.frictionless",
                    format!("URDF has no link {}", crate::echo::code(l)),
                ));
            }
        }
        // Rolling links: the children of continuous joints with round collisions.
        let wheels: Vec<&str> = robot
            .joints
            .iter()
            .filter(|j| j.joint_type == JointType::Continuous)
            .map(|j| j.child.link.as_str())
            .filter(|l| crate::engine::urdf::collision_radius(robot, l).is_some())
            .collect();
        // Worn or mismatched tyres (`wheel_radius_scale`): the wheels'
        // collisions get the scaled radius, and the robot, placed on its
        // nominal wheels, starts lower by the wear, on its worn ones (the
        // wheel that wears least touches, none is below the ground).
        // The model and the drives keep the nominal radius.
        let mut root = place_root(robot, rig, start)?;
        let s = sim.wheel_radius_scale;
        let worn_links = if s == 1.0 {
            Vec::new()
        } else {
            wearing_wheels(robot, rig, &root)?
        };
        let root_nominal = root;
        let wear = worn_links
            .iter()
            .map(|(_, radius)| (1.0 - s) * radius)
            .min_by(f64::total_cmp);
        if let Some(wear) = wear {
            root.translation.z -= r(wear);
        }
        let names: Vec<&str> = worn_links.iter().map(|(l, _)| l.as_str()).collect();
        let mut worn = crate::engine::perturb::world::worn_wheels(robot, &names, s);
        // Everything else round on the ground (casters, a trailer's
        // wheels) loses as much, so the robot stays level: a pitch-rigid
        // chain would otherwise rest on them with its drive wheels in the air.
        if let Some(wear) = wear {
            let others: Vec<&str> = touching_round_links(robot, &root_nominal)
                .into_iter()
                .filter(|l| !names.contains(l))
                .collect();
            if !others.is_empty() {
                worn = std::borrow::Cow::Owned(
                    crate::engine::perturb::world::shrink_round_collisions(
                        &worn,
                        &others,
                        1.0,
                        Some(wear),
                    ),
                );
            }
        }
        let robot: &urdf_rs::Robot = &worn;
        let mut sw = SimWorld::on_ground(robot, urdf_dir, sim, root)?;
        crate::robots::wheeled::roll_links_on_balls(&mut sw, &wheels)?;
        for l in &rig.frictionless {
            for h in sw.colliders_of(l)? {
                if let Some(c) = sw.world.colliders.get_mut(h) {
                    c.set_friction(0.0);
                }
            }
        }
        // States read through joints: turn them to the start.
        let root_body = sw.robot.link(root_link(robot));
        let mut sources = Vec::new();
        for ((s, rd), &v) in rig.states.iter().zip(&rig.reads).zip(start) {
            let key = format!("model.read.{s}");
            sources.push(match rd {
                Read::Link(l, c) => {
                    let (body, off) = sw.require_frame(l).map_err(|e| e.under_key(&key))?;
                    if *c == LinkCoord::Yaw && root_body != Some(body) {
                        let j = joint_above(robot, l).ok_or_else(|| {
                            SetupError::key(&key, format!("link `{l}` is not on the root body, nor one joint below it: the start cannot place it"))
                        })?;
                        let h = sw.require_joint(&j).map_err(|e| e.under_key(&key))?;
                        // Yaw now (joint at zero) → the joint angle that gives `v`.
                        let now = link_yaw(&sw, body, off);
                        let at = sw.joint_position(h).unwrap_or(0.0);
                        let sign = joint_yaw_sign(&sw, h);
                        if sign == 0.0 {
                            return Err(SetupError::key(&key, format!("joint `{j}` above link `{l}` is not vertical: the start cannot set its yaw"
                            )));
                        }
                        sw.set_joint_position(h, at + sign * angles::wrap(v - now))?;
                    }
                    Source::Link(body, off, *c)
                }
                Read::Joint(j) => {
                    let h = sw.require_joint(j).map_err(|e| e.under_key(&key))?;
                    sw.set_joint_position(h, v)?;
                    Source::Joint(h)
                }
                // The robot starts at rest: a rate's start is what it reads.
                Read::LinkVelocity(l, k) => {
                    let (body, off) = sw.require_frame(l).map_err(|e| e.under_key(&key))?;
                    Source::LinkVelocity(body, off, *k)
                }
                Read::JointVelocity(j) => {
                    Source::JointVelocity(sw.require_joint(j).map_err(|e| e.under_key(&key))?)
                }
            });
        }
        let mut reading = UrdfReading::default();
        let mut drives = Vec::new();
        for (j, e) in &rig.drives {
            let uj = joint(robot, j).expect("checked");
            let h = sw.require_joint(j)?;
            let mut d = sw.drive_for(h, axis_of(uj), sw.joint_position(h).unwrap_or(0.0));
            d.max_torque = crate::engine::urdf::effort(robot, j);
            reading.drive(j, d.max_torque, sim.motor_max_torque);
            drives.push((d, e.clone()));
        }
        let mut positions = Vec::new();
        for (j, e) in &rig.positions {
            let uj = joint(robot, j).expect("checked");
            let h = sw.require_joint(j)?;
            let mut d = sw.drive_for(h, axis_of(uj), sw.joint_position(h).unwrap_or(0.0));
            d.max_torque = crate::engine::urdf::effort(robot, j);
            reading.drive(j, d.max_torque, sim.motor_max_torque);
            positions.push((d, e.clone()));
        }
        // Slow robots on a half-space: CCD never acts (see the rover).
        sw.world.integration_parameters.max_ccd_substeps = 0;
        let angular = rig.reads.iter().map(|rd| rd.angular(robot)).collect();
        let mut me = DeclaredPhysics {
            sim: sw,
            model: model.clone(),
            sources,
            angular,
            drives,
            positions,
            q: State::from_column_slice(start),
            values: Vec::new(),
            reading,
            drive_names: rig.drives.iter().map(|(j, _)| j.clone()).collect(),
            position_names: rig.positions.iter().map(|(j, _)| j.clone()).collect(),
            fault: None,
        };
        me.read_back();
        // The start as given (read-back only adds rounding): the unwrapping
        // continues from the scenario's angles.
        for (i, a) in me.angular.iter().enumerate() {
            if *a {
                me.q[i] = angles::unwrap(start[i], me.q[i]);
            }
        }
        me.apply(&Input::zeros(model.input_names().len()));
        Ok(me)
    }

    fn raw(&self, s: &Source) -> f64 {
        match s {
            Source::Link(b, off, c) => {
                let p = *self.sim.world.bodies[*b].position() * *off;
                match c {
                    LinkCoord::X => f(p.translation.x),
                    LinkCoord::Y => f(p.translation.y),
                    LinkCoord::Z => f(p.translation.z),
                    LinkCoord::Yaw => angles::yaw(&p.rotation),
                    LinkCoord::Roll | LinkCoord::Pitch => {
                        let [x, y, z, w] = crate::engine::real::quat(&p.rotation);
                        if *c == LinkCoord::Roll {
                            (2.0 * (w * x + y * z)).atan2(1.0 - 2.0 * (x * x + y * y))
                        } else {
                            (2.0 * (w * y - z * x)).clamp(-1.0, 1.0).asin()
                        }
                    }
                }
            }
            Source::Joint(h) => self.sim.joint_position(*h).unwrap_or(f64::NAN),
            Source::LinkVelocity(b, off, k) => {
                crate::robots::declared::rates::link_velocity(&self.sim, *b, off, *k)
            }
            Source::JointVelocity(h) => {
                crate::robots::declared::rates::joint_velocity(&self.sim, *h).unwrap_or(f64::NAN)
            }
        }
    }

    fn read_back(&mut self) {
        for i in 0..self.sources.len() {
            let v = self.raw(&self.sources[i]);
            self.q[i] = if self.angular[i] {
                angles::unwrap(self.q[i], v)
            } else {
                v
            };
        }
    }
}

/// Height above the ground within which a wheel's lowest point touches it
/// at the start, m (the placement's rounding is far below).
const TOUCHING: f64 = 1e-4;

/// The links that wear with `wheel_radius_scale`, with their radius: the
/// child links of `[model] wheels`, else of the velocity-driven joints whose
/// round collision touches the ground with the root at `root`.
fn wearing_wheels(
    robot: &Robot,
    rig: &Rig,
    root: &RPose,
) -> Result<Vec<(String, f64)>, SetupError> {
    let frames = crate::robots::wheeled::link_frames(robot);
    let mut out = Vec::new();
    let given = rig.wheels.is_some();
    let joints: Vec<&String> = match &rig.wheels {
        Some(w) => w.iter().collect(),
        None => rig.drives.iter().map(|(j, _)| j).collect(),
    };
    for j in joints {
        let Some(uj) = joint(robot, j) else { continue };
        let link = &uj.child.link;
        let Some(radius) = crate::engine::urdf::collision_radius(robot, link) else {
            if given {
                return Err(SetupError::key(
                    "model.wheels",
                    format!(
                        "joint `{j}` turns link `{link}`, which has no sphere or cylinder collision: it cannot wear"
                    ),
                ));
            }
            continue;
        };
        if given || lowest(robot, &frames, root, link) < TOUCHING {
            out.push((link.clone(), radius));
        }
    }
    Ok(out)
}

/// The lowest point of `link`'s collisions with the root at `root`, m
/// (∞ when it has none).
fn lowest(
    robot: &Robot,
    frames: &std::collections::HashMap<String, RPose>,
    root: &RPose,
    link: &str,
) -> f64 {
    robot
        .links
        .iter()
        .filter(|l| l.name == link)
        .flat_map(|l| &l.collision)
        .filter_map(|c| {
            let at = *root * frames[link] * crate::engine::world::origin(&c.origin);
            crate::engine::world::lowest_point(&c.geometry, &at)
        })
        .fold(f64::INFINITY, f64::min)
}

/// The links with a round (sphere or cylinder) collision that touch the
/// ground with the root at `root`.
fn touching_round_links<'r>(robot: &'r Robot, root: &RPose) -> Vec<&'r str> {
    let frames = crate::robots::wheeled::link_frames(robot);
    robot
        .links
        .iter()
        .map(|l| l.name.as_str())
        .filter(|l| crate::engine::urdf::collision_radius(robot, l).is_some())
        .filter(|l| lowest(robot, &frames, root, l) < TOUCHING)
        .collect()
}

/// The root link: the one no joint points at.
fn root_link(robot: &Robot) -> &str {
    robot
        .links
        .iter()
        .map(|l| l.name.as_str())
        .find(|n| !robot.joints.iter().any(|j| j.child.link == *n))
        .unwrap_or("")
}

/// The one non-fixed joint directly above `link` through fixed joints.
fn joint_above(robot: &Robot, link: &str) -> Option<String> {
    let mut at = link;
    for _ in 0..=robot.joints.len() {
        let j = robot.joints.iter().find(|j| j.child.link == at)?;
        if j.joint_type == JointType::Fixed {
            at = &j.parent.link;
            continue;
        }
        return Some(j.name.clone());
    }
    None
}

/// World yaw of a link frame.
fn link_yaw(sw: &SimWorld, body: RigidBodyHandle, off: RPose) -> f64 {
    angles::yaw(&(*sw.world.bodies[body].position() * off).rotation)
}

/// +1 when the joint's axis points up in the world, −1 down, 0 when it is
/// not vertical (then turning it does not set a yaw).
fn joint_yaw_sign(sw: &SimWorld, h: ImpulseJointHandle) -> f64 {
    let Some(j) = sw.world.impulse_joints.get(h) else {
        return 0.0;
    };
    let frame = *sw.world.bodies[j.body1()].position() * j.data.local_frame1;
    let a = frame.rotation * Vector::X;
    let z = f(a.z);
    if z > 1.0 - 1e-6 {
        1.0
    } else if z < -(1.0 - 1e-6) {
        -1.0
    } else {
        0.0
    }
}

/// The root link's world pose that puts the root body's read links at the
/// start's x, y and yaw, and the lowest collision of the robot (all joints
/// at zero) on the ground.
fn place_root(robot: &Robot, rig: &Rig, start: &[f64]) -> Result<RPose, SetupError> {
    let frames = crate::robots::wheeled::link_frames(robot);
    let root = root_link(robot);
    let on_root = |l: &str| crate::robots::wheeled::rigidly_on(robot, l, root, "").is_ok();
    let mut yaw = None;
    for (rd, &v) in rig.reads.iter().zip(start) {
        if let Read::Link(l, LinkCoord::Yaw) = rd {
            if on_root(l) {
                yaw = Some(v - angles::yaw(&frames[l].rotation));
            }
        }
    }
    let rot = Rotation::from_rotation_z(r(yaw.unwrap_or(0.0)));
    let mut p = [0.0, 0.0];
    for (rd, &v) in rig.reads.iter().zip(start) {
        if let Read::Link(l, c @ (LinkCoord::X | LinkCoord::Y)) = rd {
            if on_root(l) {
                let k = usize::from(*c == LinkCoord::Y);
                let off = rot * frames[l].translation;
                p[k] = v - f(if k == 0 { off.x } else { off.y });
            }
        }
    }
    // The lowest collision point with the root turned to `yaw`.
    let turned = RPose::from_rotation(rot);
    let mut low = f64::INFINITY;
    for l in &robot.links {
        for c in &l.collision {
            let at = turned * frames[&l.name] * crate::engine::world::origin(&c.origin);
            if let Some(z) = crate::engine::world::lowest_point(&c.geometry, &at) {
                low = low.min(z);
            }
        }
    }
    if !low.is_finite() {
        low = 0.0;
    }
    Ok(RPose::from_parts(vector(p[0], p[1], -low), rot))
}

impl PhysicsSystem for DeclaredPhysics {
    fn state(&self) -> State {
        self.q.clone()
    }

    /// A drive that is not finite is not applied (its joint keeps its last
    /// target) and is the system's [`PhysicsSystem::fault`]: the replay
    /// stops there.
    fn apply(&mut self, u: &Input) {
        let mut values = std::mem::take(&mut self.values);
        self.model
            .values(self.q.as_slice(), u.as_slice(), &mut values);
        let mut fault = None;
        for (table, list) in [
            ("drive", &mut self.drives),
            ("drive_position", &mut self.positions),
        ] {
            for (j, (d, e)) in list.iter_mut().enumerate() {
                let v = e.eval(&values);
                if !v.is_finite() {
                    fault.get_or_insert((table, j, v));
                    continue;
                }
                if table == "drive" {
                    self.sim.drive(d, v);
                } else {
                    d.angle = v;
                    self.sim.drive(d, 0.0);
                }
            }
        }
        if let (None, Some((table, j, v))) = (&self.fault, fault) {
            let (name, e) = if table == "drive" {
                (&self.drive_names[j], &self.drives[j].1)
            } else {
                (&self.position_names[j], &self.positions[j].1)
            };
            self.fault = Some(Fault {
                what: format!(
                    "key `model.{table}.{}` ({}) gives {v}",
                    crate::echo::bare(name),
                    crate::echo::code(e.text())
                ),
                from: crate::model::point_text(&self.model, self.q.as_slice(), u.as_slice()),
            });
        }
        self.values = values;
    }

    fn fault(&self) -> Option<Fault> {
        self.fault.clone()
    }

    fn step(&mut self) {
        self.sim.step();
        self.read_back();
    }

    fn link_poses(&self) -> Vec<Pose> {
        self.sim.link_poses()
    }

    fn sim_world(&mut self) -> Option<&mut SimWorld> {
        Some(&mut self.sim)
    }

    fn reading(&self) -> UrdfReading {
        self.reading.clone()
    }
}
