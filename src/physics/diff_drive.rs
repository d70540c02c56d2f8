//! Rigid-body differential drive: two driven wheels on one axle and
//! frictionless casters (`models/diff_drive.urdf`, or a user's URDF with the
//! declared names) on a ground plane.
//!
//! Nothing enforces the unicycle's constraints: the body moves only through
//! wheel–ground friction, so wheel slip (along and across each wheel) is
//! real and measured. Casters are made frictionless, as an ideal ball caster
//! that rolls every way.
//!
//! Geometry comes from the URDF (see [`super::wheeled`]): the wheel radii
//! (their round collisions), the track (the wheel centres' distance across
//! the body) and the model's reference point (the axle midpoint, in the
//! body frame). Actuation: servo drives on both wheel joints at
//! (v ∓ ω b)/r (b = half track), each capped at its joint's
//! `<limit effort>` (`[sim] motor_max_torque` when the URDF gives none).
//! Read-back: the axle midpoint's (x, y) and the body's yaw θ, unwrapped.
//!
//! Channels: per wheel the contact-point velocity along and across the wheel
//! (`slip_left_lon`, `slip_left_lat`, `slip_right_lon`, `slip_right_lat`,
//! m/s) and its rim speed relative to the body (`rim_speed_left`,
//! `rim_speed_right`, m/s).

use super::rapier::prelude::*;
use super::real::{f, vector};
use super::required::Required;
use super::urdf::{Drive, SimWorld};
use super::wheeled::{self, Wheel};
use super::{angles, PhysicsSettings, PhysicsSystem};
use crate::model::{Input, State};
use crate::record::Pose;
use std::path::Path;

/// Default body link name.
pub const BASE: &str = "base_link";
/// Default left wheel joint name.
pub const LEFT_JOINT: &str = "left_wheel_joint";
/// Default right wheel joint name.
pub const RIGHT_JOINT: &str = "right_wheel_joint";
/// Default caster link name.
pub const CASTER: &str = "caster";

/// The links and joints a differential drive looks up in its URDF.
pub const REQUIRED: [Required; 4] = [
    Required::link(
        BASE,
        "the body; its +x axis is the heading θ, the wheels and casters hang from it",
    )
    .renamed_by("base_link"),
    Required::joint(
        LEFT_JOINT,
        "continuous, to the left wheel (a link with a sphere or cylinder collision); axis horizontal, across the body's x axis; driven at (v − ω b)/r",
    )
    .renamed_by("left_wheel_joint"),
    Required::joint(
        RIGHT_JOINT,
        "the same for the right wheel, on the same axle; driven at (v + ω b)/r",
    )
    .renamed_by("right_wheel_joint"),
    Required::link(
        CASTER,
        "a caster: its collisions are made frictionless (a list: every caster link)",
    )
    .renamed_by("caster_links"),
];

/// The URDF names a scenario gives the robot's parts.
#[derive(Debug, Clone)]
pub struct DiffDriveNames {
    /// Body link.
    pub base: String,
    /// Left wheel joint.
    pub left: String,
    /// Right wheel joint.
    pub right: String,
    /// Caster links.
    pub casters: Vec<String>,
}

/// What the kinematics needs from the URDF, in the body frame.
#[derive(Debug, Clone)]
pub struct DiffDriveGeometry {
    /// Left and right wheels.
    pub wheels: [Wheel; 2],
    /// Half the track (wheel centres' distance across the body), m.
    pub half_track: f64,
    /// The axle midpoint (the model's reference point) in the body frame, m.
    pub point: [f64; 2],
    /// Height of the wheels' contact plane in the body frame, m.
    pub ground: f64,
    /// Torque limit of each wheel drive from its joint's `<limit effort>`, N·m.
    pub effort: [Option<f64>; 2],
}

/// The `<limit effort>` of a joint, when the URDF gives one (> 0).
pub fn effort(robot: &urdf_rs::Robot, joint: &str) -> Option<f64> {
    robot
        .joints
        .iter()
        .find(|j| j.name == joint)
        .map(|j| j.limit.effort)
        .filter(|e| e.is_finite() && *e > 0.0)
}

impl DiffDriveGeometry {
    /// Read and check the URDF: errors name the joint or link at fault.
    pub fn read(robot: &urdf_rs::Robot, names: &DiffDriveNames) -> Result<Self, String> {
        let frames = wheeled::link_frames(robot);
        let base = names.base.as_str();
        let mut wheels = Vec::new();
        for j in [&names.left, &names.right] {
            let w = wheeled::wheel(robot, &frames, base, j)?;
            let parent = &wheeled::joint(robot, j)?.parent.link;
            wheeled::rigidly_on(robot, parent, base, &format!("joint `{j}`"))?;
            wheels.push(w);
        }
        let [l, r]: [Wheel; 2] = wheels.try_into().expect("two wheels");
        if !wheeled::same_position(l.center[0], r.center[0]) {
            return Err(format!(
                "URDF joints `{}` and `{}` must put both wheels on one axle: their centres sit at x = {:.4} and {:.4} m in `{base}`",
                l.joint, r.joint, l.center[0], r.center[0]
            ));
        }
        if l.center[1] <= r.center[1] {
            return Err(format!(
                "URDF joint `{}` puts its wheel at y = {:.4} m in `{base}`, not left of `{}`'s ({:.4} m): left and right swapped?",
                l.joint, l.center[1], r.joint, r.center[1]
            ));
        }
        let ground = wheeled::contact_plane(&[&l, &r])?;
        for c in &names.casters {
            caster_on_plane(robot, &frames, base, c, ground)?;
        }
        Ok(DiffDriveGeometry {
            half_track: 0.5 * (l.center[1] - r.center[1]),
            point: [
                0.5 * (l.center[0] + r.center[0]),
                0.5 * (l.center[1] + r.center[1]),
            ],
            ground,
            effort: [effort(robot, &l.joint), effort(robot, &r.joint)],
            wheels: [l, r],
        })
    }
}

/// A caster has collisions, and its spheres (if it moves with the body)
/// reach the wheels' contact plane within 2 mm: a caster above it would tip
/// the robot, one below it lift a wheel.
pub fn caster_on_plane(
    robot: &urdf_rs::Robot,
    frames: &std::collections::HashMap<String, super::rapier::math::Pose>,
    base: &str,
    caster: &str,
    ground: f64,
) -> Result<(), String> {
    let Some(link) = robot.links.iter().find(|l| l.name == caster) else {
        return Err(format!("URDF lacks link `{caster}`"));
    };
    if link.collision.is_empty() {
        return Err(format!(
            "URDF link `{caster}` has no <collision>: a caster must touch the ground"
        ));
    }
    if wheeled::rigidly_on(robot, caster, base, "").is_err() {
        return Ok(());
    }
    let in_base = frames[base].inverse() * frames[caster];
    for c in &link.collision {
        if let urdf_rs::Geometry::Sphere { radius } = c.geometry {
            let o = c.origin.xyz.0;
            let z = f(in_base.transform_point(vector(o[0], o[1], o[2])).z) - radius;
            if (z - ground).abs() > 2e-3 {
                return Err(format!(
                    "URDF link `{caster}`: its sphere's lowest point is {:.4} m {} the wheels' contact plane",
                    (z - ground).abs(),
                    if z > ground { "above" } else { "below" }
                ));
            }
        }
    }
    Ok(())
}

/// The differential drive in Rapier.
pub struct DiffDrivePhysics {
    sim: SimWorld,
    geom: DiffDriveGeometry,
    base: RigidBodyHandle,
    wheels: [RigidBodyHandle; 2],
    drives: [Drive; 2],
    /// Unwrapped heading.
    theta: f64,
    /// Model coordinates read back after the last step.
    q: State,
}

impl DiffDrivePhysics {
    /// Build the robot at `start` = (x, y, θ) on the ground.
    pub fn new(
        robot: &urdf_rs::Robot,
        urdf_dir: &Path,
        names: &DiffDriveNames,
        start: &[f64],
        sim: &PhysicsSettings,
    ) -> Result<Self, String> {
        let geom = DiffDriveGeometry::read(robot, names)?;
        let frames = wheeled::link_frames(robot);
        let root = wheeled::root_pose(
            &frames,
            &names.base,
            geom.point,
            geom.ground,
            start[0],
            start[1],
            start[2],
        );
        let mut sw = SimWorld::on_ground(robot, urdf_dir, sim, root);
        let base = sw.require_link(&names.base)?;
        let wheels = [
            sw.require_link(&geom.wheels[0].link)?,
            sw.require_link(&geom.wheels[1].link)?,
        ];
        let mut drives = Vec::new();
        for (w, e) in geom.wheels.iter().zip(geom.effort) {
            let mut d = sw.drive_for(sw.require_joint(&w.joint)?, JointAxis::AngX, 0.0);
            d.max_torque = e;
            drives.push(d);
        }
        for c in &names.casters {
            let b = sw.require_link(c)?;
            for h in sw.world.bodies[b].colliders().to_vec() {
                if let Some(col) = sw.world.colliders.get_mut(h) {
                    col.set_friction(0.0);
                }
            }
        }
        // Slow robot on a half-space: CCD never acts (see the rover).
        sw.world.integration_parameters.max_ccd_substeps = 0;
        let mut me = DiffDrivePhysics {
            sim: sw,
            base,
            wheels,
            drives: drives.try_into().expect("two drives"),
            theta: start[2],
            q: State::zeros(3),
            geom,
        };
        me.read_back();
        me.apply(&Input::zeros(2));
        Ok(me)
    }

    /// The geometry read from the URDF.
    pub fn geometry(&self) -> &DiffDriveGeometry {
        &self.geom
    }

    fn read_back(&mut self) {
        let b = &self.sim.world.bodies[self.base];
        let p = self.geom.point;
        let c = b.position().transform_point(vector(p[0], p[1], 0.0));
        self.q.copy_from_slice(&[f(c.x), f(c.y), self.theta]);
    }
}

impl PhysicsSystem for DiffDrivePhysics {
    fn state(&self) -> State {
        self.q.clone()
    }

    fn apply(&mut self, u: &Input) {
        let b = self.geom.half_track;
        let speeds = [u[0] - u[1] * b, u[0] + u[1] * b];
        for ((wheel, drive), speed) in self.geom.wheels.iter().zip(&mut self.drives).zip(speeds) {
            self.sim.drive(drive, wheel.rate(speed));
        }
    }

    fn step(&mut self) {
        self.sim.step();
        let yaw = angles::yaw(self.sim.world.bodies[self.base].rotation());
        self.theta = angles::unwrap(self.theta, yaw);
        self.read_back();
    }

    fn link_poses(&self) -> Vec<Pose> {
        self.sim.link_poses()
    }

    fn sim_world(&mut self) -> Option<&mut SimWorld> {
        Some(&mut self.sim)
    }

    fn channel_names(&self) -> Vec<String> {
        [
            "slip_left_lon",
            "slip_left_lat",
            "slip_right_lon",
            "slip_right_lat",
            "rim_speed_left",
            "rim_speed_right",
        ]
        .map(String::from)
        .to_vec()
    }

    fn channels(&self) -> Vec<f64> {
        let bodies = &self.sim.world.bodies;
        let mut out = Vec::with_capacity(6);
        for (h, w) in self.wheels.iter().zip(&self.geom.wheels) {
            let (lon, lat) = wheeled::contact_slip(&bodies[*h], w);
            out.push(lon);
            out.push(lat);
        }
        for (h, w) in self.wheels.iter().zip(&self.geom.wheels) {
            out.push(wheeled::rim_speed(&bodies[self.base], &bodies[*h], w));
        }
        out
    }
}
