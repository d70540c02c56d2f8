//! Rigid-body differential drive: two driven wheels on one axle and
//! frictionless casters (`models/diff_drive.urdf`, or a user's URDF with the
//! declared names) on a ground plane.
//!
//! Nothing enforces the unicycle's constraints: the body moves only through
//! wheel–ground friction, so wheel slip (along and across each wheel) is
//! real and measured. Casters are made frictionless, as an ideal ball caster
//! that rolls every way.
//!
//! Geometry comes from the URDF (see [`crate::robots::wheeled`]): the wheel radii
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

use crate::engine::rapier::math::Pose as RPose;
use crate::engine::rapier::prelude::*;
use crate::engine::reading::UrdfReading;
use crate::engine::real::{f, vector};
use crate::engine::required::Required;
use crate::engine::urdf::{Drive, SimWorld};
use crate::engine::world::origin;
use crate::engine::{angles, PhysicsSettings, PhysicsSystem};
use crate::error::SetupError;
use crate::model::{Input, State};
use crate::record::Pose;
use crate::robots::wheeled::{self, Wheel};
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
    /// Left wheel joints (one, or several for a skid steer).
    pub left: Vec<String>,
    /// Right wheel joints.
    pub right: Vec<String>,
    /// Caster links.
    pub casters: Vec<String>,
}

/// What the kinematics needs from the URDF, in the body frame.
#[derive(Debug, Clone)]
pub struct DiffDriveGeometry {
    /// Left wheels, then right wheels.
    pub wheels: Vec<Wheel>,
    /// How many of [`DiffDriveGeometry::wheels`] are on the left.
    pub n_left: usize,
    /// Half the track (the wheel lines' distance across the body), m.
    pub half_track: f64,
    /// The reference point in the body frame, m: the axle midpoint (two
    /// wheels), or the wheel centres' centroid (several per side).
    pub point: [f64; 2],
    /// Height of the wheels' contact plane in the body frame, m.
    pub ground: f64,
    /// Torque limit of each wheel drive from its joint's `<limit effort>`, N·m.
    pub effort: Vec<Option<f64>>,
}

/// The mean of `f` over `wheels`.
fn mean(wheels: &[Wheel], f: impl Fn(&Wheel) -> f64) -> f64 {
    wheels.iter().map(f).sum::<f64>() / wheels.len() as f64
}

impl DiffDriveGeometry {
    /// Read and check the URDF: errors name the joint or link at fault.
    pub fn read(robot: &urdf_rs::Robot, names: &DiffDriveNames) -> Result<Self, SetupError> {
        let frames = wheeled::link_frames(robot);
        let base = names.base.as_str();
        let side = |joints: &[String]| -> Result<Vec<Wheel>, SetupError> {
            let mut out = Vec::new();
            for j in joints {
                let w = wheeled::wheel(robot, &frames, base, j)?;
                let parent = &wheeled::joint(robot, j)?.parent.link;
                wheeled::rigidly_on(robot, parent, base, &format!("joint `{j}`"))?;
                out.push(w);
            }
            Ok(out)
        };
        let (left, right) = (side(&names.left)?, side(&names.right)?);
        let (l, r) = (&left[0], &right[0]);
        if left.len() == 1 && right.len() == 1 && !wheeled::same_position(l.center[0], r.center[0])
        {
            return Err(SetupError::urdf_at("joint", l.joint.to_string(), format!(
                "URDF joints `{}` and `{}` must put both wheels on one axle: their centres sit at x = {:.4} and {:.4} m in `{base}`",
                l.joint, r.joint, l.center[0], r.center[0]
            )));
        }
        for ws in [&left, &right] {
            // A side's wheels roll on one line along the body's x axis.
            if let Some(w) = ws
                .iter()
                .find(|w| !wheeled::same_position(w.center[1], ws[0].center[1]))
            {
                return Err(SetupError::urdf_at("joint", ws[0].joint.to_string(), format!(
                    "URDF joints `{}` and `{}` are on one side but their wheels sit at y = {:.4} and {:.4} m in `{base}`: a side's wheels must share one line",
                    ws[0].joint, w.joint, ws[0].center[1], w.center[1]
                )));
            }
        }
        let (yl, yr) = (left[0].center[1], right[0].center[1]);
        if yl <= yr {
            return Err(SetupError::urdf_at("joint", left[0].joint.to_string(), format!(
                "URDF joint `{}` puts its wheel at y = {yl:.4} m in `{base}`, not left of `{}`'s ({yr:.4} m): left and right swapped?",
                left[0].joint, right[0].joint
            )));
        }
        let wheels: Vec<Wheel> = left.iter().chain(&right).cloned().collect();
        let ground = wheeled::contact_plane(&wheels.iter().collect::<Vec<_>>())?;
        for c in &names.casters {
            caster_on_plane(robot, &frames, base, c, ground)?;
        }
        let (xl, xr) = (mean(&left, |w| w.center[0]), mean(&right, |w| w.center[0]));
        Ok(DiffDriveGeometry {
            half_track: 0.5 * (yl - yr),
            point: [0.5 * (xl + xr), 0.5 * (yl + yr)],
            ground,
            effort: wheels
                .iter()
                .map(|w| crate::engine::urdf::effort(robot, &w.joint))
                .collect(),
            n_left: left.len(),
            wheels,
        })
    }

    /// The ground speed of each wheel for (v, ω), left wheels first.
    pub fn wheel_speeds(&self, v: f64, omega: f64) -> impl Iterator<Item = f64> + '_ {
        let b = self.half_track;
        (0..self.wheels.len()).map(move |i| {
            if i < self.n_left {
                v - omega * b
            } else {
                v + omega * b
            }
        })
    }

    /// What was read, for the user.
    pub fn reading(&self, default_torque: f64) -> UrdfReading {
        let mut out = UrdfReading::default();
        for (w, e) in self.wheels.iter().zip(&self.effort) {
            out.wheels.push(w.reading());
            out.drive(&w.joint, *e, default_torque);
        }
        out.geometry = vec![
            ("track_m".into(), vec![2.0 * self.half_track]),
            ("reference_point_m".into(), self.point.to_vec()),
        ];
        if self.n_left > 1 || self.wheels.len() - self.n_left > 1 {
            let xs = self.wheels.iter().map(|w| w.center[0]);
            let span =
                xs.clone().fold(f64::NEG_INFINITY, f64::max) - xs.fold(f64::INFINITY, f64::min);
            out.geometry.push(("wheelbase_m".into(), vec![span]));
        }
        out
    }
}

/// A caster has collisions, and (if it moves with the body) the lowest
/// point of each reaches the wheels' contact plane within 2 mm: a caster
/// above it would tip the robot, one below it lift a wheel. Any collision
/// shape: its lowest point is the bottom of its bounding box in the body
/// frame, exact for spheres, boxes, cylinders and convex meshes alike.
pub(crate) fn caster_on_plane(
    robot: &urdf_rs::Robot,
    frames: &std::collections::HashMap<String, crate::engine::rapier::math::Pose>,
    base: &str,
    caster: &str,
    ground: f64,
) -> Result<(), SetupError> {
    let Some(link) = robot.links.iter().find(|l| l.name == caster) else {
        return Err(SetupError::urdf(format!("URDF lacks link `{caster}`")));
    };
    if link.collision.is_empty() {
        return Err(SetupError::urdf_at(
            "link",
            caster.to_string(),
            format!("URDF link `{caster}` has no <collision>: a caster must touch the ground"),
        ));
    }
    if wheeled::rigidly_on(robot, caster, base, "").is_err() {
        return Ok(());
    }
    let in_base = frames[base].inverse() * frames[caster];
    for c in &link.collision {
        let Some(z) =
            crate::engine::world::lowest_point(&c.geometry, &(in_base * origin(&c.origin)))
        else {
            continue;
        };
        if (z - ground).abs() > 2e-3 {
            return Err(SetupError::urdf_at("link", caster.to_string(), format!(
                "URDF link `{caster}`: the lowest point of its {} collision is {:.4} m {} the wheels' contact plane",
                crate::engine::urdf::shape_tag(&c.geometry),
                (z - ground).abs(),
                if z > ground { "above" } else { "below" }
            )));
        }
    }
    Ok(())
}

/// The differential drive in Rapier.
pub struct DiffDrivePhysics {
    sim: SimWorld,
    geom: DiffDriveGeometry,
    base: RigidBodyHandle,
    /// The base link's pose in its body (identity unless it was lumped).
    base_offset: RPose,
    wheels: Vec<RigidBodyHandle>,
    drives: Vec<Drive>,
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
    ) -> Result<Self, SetupError> {
        let geom = DiffDriveGeometry::read(robot, names)?;
        let frames = wheeled::link_frames(robot);
        // Worn or mismatched tyres (`wheel_radius_scale`): the simulated
        // wheels get the scaled radius, the model and the drives keep the
        // URDF's; the body starts that much lower, on its wheels.
        let wear = (1.0 - sim.wheel_radius_scale) * geom.wheels[0].radius;
        let root = wheeled::root_pose(
            &frames,
            &names.base,
            geom.point,
            geom.ground + wear,
            start[0],
            start[1],
            start[2],
        );
        let links: Vec<&str> = geom.wheels.iter().map(|w| w.link.as_str()).collect();
        let worn =
            crate::engine::perturb::world::worn_wheels(robot, &links, sim.wheel_radius_scale);
        let mut sw = SimWorld::on_ground(&worn, urdf_dir, sim, root)?;
        let (base, base_offset) = sw.require_frame(&names.base)?;
        let wheels = geom
            .wheels
            .iter()
            .map(|w| sw.require_link(&w.link))
            .collect::<Result<Vec<_>, _>>()?;
        let mut drives = Vec::new();
        for (w, e) in geom.wheels.iter().zip(&geom.effort) {
            let mut d = sw.drive_for(sw.require_joint(&w.joint)?, JointAxis::AngX, 0.0);
            d.max_torque = *e;
            drives.push(d);
        }
        for c in &names.casters {
            for h in sw.colliders_of(c)? {
                if let Some(col) = sw.world.colliders.get_mut(h) {
                    col.set_friction(0.0);
                }
            }
        }
        wheeled::roll_on_balls(&mut sw, &geom.wheels)?;
        // Slow robot on a half-space: CCD never acts (see the rover).
        sw.world.integration_parameters.max_ccd_substeps = 0;
        let mut me = DiffDrivePhysics {
            sim: sw,
            base,
            base_offset,
            wheels,
            drives,
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

    /// The base link's world pose.
    fn base_pose(&self) -> RPose {
        *self.sim.world.bodies[self.base].position() * self.base_offset
    }

    fn read_back(&mut self) {
        let p = self.geom.point;
        let c = self.base_pose().transform_point(vector(p[0], p[1], 0.0));
        self.q.copy_from_slice(&[f(c.x), f(c.y), self.theta]);
    }
}

impl PhysicsSystem for DiffDrivePhysics {
    fn state(&self) -> State {
        self.q.clone()
    }

    fn apply(&mut self, u: &Input) {
        let speeds: Vec<f64> = self.geom.wheel_speeds(u[0], u[1]).collect();
        for ((wheel, drive), speed) in self.geom.wheels.iter().zip(&mut self.drives).zip(speeds) {
            self.sim.drive(drive, wheel.rate(speed));
        }
    }

    fn step(&mut self) {
        self.sim.step();
        let yaw = angles::yaw(&self.base_pose().rotation);
        self.theta = angles::unwrap(self.theta, yaw);
        self.read_back();
    }

    fn link_poses(&self) -> Vec<Pose> {
        self.sim.link_poses()
    }

    fn sim_world(&mut self) -> Option<&mut SimWorld> {
        Some(&mut self.sim)
    }

    fn reading(&self) -> UrdfReading {
        self.geom.reading(self.sim.settings.motor_max_torque)
    }

    fn channel_names(&self) -> Vec<String> {
        let g = &self.geom;
        let names = wheel_names(g);
        let mut out = Vec::new();
        for n in &names {
            out.push(format!("slip_{n}_lon"));
            out.push(format!("slip_{n}_lat"));
        }
        out.extend(names.iter().map(|n| format!("rim_speed_{n}")));
        out
    }

    fn channels(&self) -> Vec<f64> {
        let bodies = &self.sim.world.bodies;
        let mut out = Vec::with_capacity(3 * self.wheels.len());
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

/// Channel names of the wheels: `left`, `right` for two wheels; `left_1`,
/// `left_2`, ... (front to back as the joints are listed) for several.
fn wheel_names(g: &DiffDriveGeometry) -> Vec<String> {
    let n_right = g.wheels.len() - g.n_left;
    let side = |name: &str, n: usize| -> Vec<String> {
        if n == 1 {
            vec![name.to_string()]
        } else {
            (1..=n).map(|k| format!("{name}_{k}")).collect()
        }
    };
    let mut out = side("left", g.n_left);
    out.extend(side("right", n_right));
    out
}
