//! Rigid-body mobile manipulator (seed 004): `models/mobile_manipulator.urdf`
//! on a ground plane among fixed obstacles.
//!
//! The platform is a differential drive: two driven wheels on the axle
//! through the model's reference point, two frictionless ball casters. The
//! unicycle constraint of Eq. 1 holds only as well as wheel friction allows.
//! The PUMA 560 arm's six joints and both wheels carry velocity motors:
//! wheel rates (v ∓ ω b)/r for the inputs (v, ω), joint rates u_a.
//!
//! Obstacles are fixed colliders: the convex hull of each generalized
//! ellipsoid's surface mesh (inscribed, so slightly smaller than the shape the
//! planner avoids). Robot colliders meet the ground, the obstacles and the
//! other robot's colliders, never their own robot's.
//!
//! Two robots may carry a beam ([`CarriedBeam`], see `carried`): a
//! [`PhysicsBeam`](crate::robots::mobile_manipulator::beam::physics::PhysicsBeam) fixed to both tools at the planner's grasp offsets. The
//! beam meets the ground, the obstacles and both platforms (the platform
//! boxes); arms, columns and grippers pass it (the planner's
//! `Carried::held` pairs, and the gripper holds it).
//!
//! Read-back: (x, y, θ) of `base_link` (θ unwrapped), each joint angle from
//! the relative rotation of its two links. Channels: `min_clearance` (least
//! distance, m, between any robot collider and any obstacle collider, parry
//! distance queries), `obstacle_contacts` (robot–obstacle collider pairs in
//! contact), `slip_left`/`slip_right` (wheel contact-point speed along the
//! heading, m/s), `slip_lateral` (axle-centre speed across the heading: the
//! violated nonholonomic constraint, m/s), `speed_error`, `turn_rate_error`
//! (measured − commanded platform v, ω) and `joint_rate_error` (largest
//! |measured − commanded| joint rate, rad/s). With two robots, the channels
//! of `carried::PAIR_CHANNELS` follow.

#[cfg(test)]
mod armature_tests;
mod carried;
mod clearance;
mod gripper_balance;
mod joints;
mod setup;
mod urdf;
#[cfg(test)]
mod wrist_tests;

use setup::{check_urdf, is_platform, place_robot};

pub use carried::{link_visuals, robot_link_name, CarriedBeam};
pub use joints::WRIST_CHANNELS;
pub use urdf::urdf;

use crate::error::SetupError;
use joints::{add_armature, compliant_wrist_joint, grasp_frame, settle_wrists};

use crate::engine::rapier::parry::bounding_volume::Aabb;
use crate::engine::rapier::prelude::*;
use crate::engine::real::{self as rl, f, vector};
use crate::engine::required::Required;
use crate::engine::settings::PhysicsSettings;
use crate::engine::urdf::{RobotHandles, SimWorld};
use crate::engine::{angles, PhysicsSystem};
use crate::model::{Input, State};
use crate::record::Pose;
use crate::robots::mobile_manipulator::ellipsoid::Superellipsoid;
use crate::robots::mobile_manipulator::kinematics::{
    self as mm, CompliantWrist, Link, Wrist, DOF, GRASP_OFFSET, HALF_TRACK, INPUTS, MOUNT,
    WHEEL_RADIUS,
};
use crate::robots::mobile_manipulator::puma560;
use std::path::Path;

/// Collision groups of robot 1's and robot 2's colliders.
const ROBOT: [Group; 2] = [Group::GROUP_1, Group::GROUP_4];
/// Collision group of the ground.
const GROUND: Group = Group::GROUP_2;
/// Collision group of obstacles.
const OBSTACLE: Group = Group::GROUP_3;
/// Collision group of the beam's segments.
const BEAM: Group = Group::GROUP_5;
/// Collision group of the platform boxes (which meet the beam).
const PLATFORM: Group = Group::GROUP_6;

/// The clearance channel is recomputed every this many steps (held between:
/// the distance queries cost more than a physics step).
const CLEARANCE_EVERY: usize = 5;

/// Time constant of the joint servos' pull towards their references, s.
const SERVO_TIME: f64 = 0.05;

/// Mass of the platform body, kg (a choice: a PUMA-carrying base).
pub(crate) const PLATFORM_MASS: f64 = 120.0;
/// Wheel mass, kg.
pub(crate) const WHEEL_MASS: f64 = 2.0;
/// Gripper mass, kg.
pub(crate) const TOOL_MASS: f64 = 0.5;

/// URDF joint names of the arm, in order.
pub const ARM_JOINTS: [&str; 6] = ["joint1", "joint2", "joint3", "joint4", "joint5", "joint6"];

/// Drive wheel links (left, right) and their joints.
const WHEELS: [&str; 2] = ["left_wheel", "right_wheel"];
const WHEEL_JOINTS: [&str; 2] = ["left_wheel_joint", "right_wheel_joint"];
/// Caster links (frictionless).
const CASTERS: [&str; 2] = ["caster_front", "caster_rear"];

/// The links and joints each mobile manipulator looks up in its URDF.
pub const REQUIRED: [Required; 23] = [
    Required::link(
        "base_link",
        "the platform (root link); origin at the drive-axle midpoint on the ground",
    ),
    Required::link(WHEELS[0], "driven wheel, left"),
    Required::link(WHEELS[1], "driven wheel, right"),
    Required::link(
        CASTERS[0],
        "front caster (its collisions are made frictionless)",
    ),
    Required::link(
        CASTERS[1],
        "rear caster (its collisions are made frictionless)",
    ),
    Required::link("link1", "PUMA 560 link 1"),
    Required::link("link2", "PUMA 560 link 2"),
    Required::link("link3", "PUMA 560 link 3"),
    Required::link("link4", "PUMA 560 link 4"),
    Required::link("link5", "PUMA 560 link 5"),
    Required::link("link6", "PUMA 560 link 6"),
    Required::link("tool", "the gripper"),
    Required::joint(
        WHEEL_JOINTS[0],
        "base_link to left_wheel: driven at (v − ω b)/r",
    ),
    Required::joint(
        WHEEL_JOINTS[1],
        "base_link to right_wheel: driven at (v + ω b)/r",
    ),
    Required::joint(ARM_JOINTS[0], "arm joint 1 (PUMA 560 DH table, axis z)"),
    Required::joint(ARM_JOINTS[1], "arm joint 2 (PUMA 560 DH table, axis z)"),
    Required::joint(ARM_JOINTS[2], "arm joint 3 (PUMA 560 DH table, axis z)"),
    Required::joint(ARM_JOINTS[3], "arm joint 4 (PUMA 560 DH table, axis z)"),
    Required::joint(ARM_JOINTS[4], "arm joint 5 (PUMA 560 DH table, axis z)"),
    Required::joint(ARM_JOINTS[5], "arm joint 6 (PUMA 560 DH table, axis z)"),
    Required::joint(
        KEPT_FIXED[0],
        "link6 to tool, fixed: kept as a joint (not lumped), it is the compliant wrist",
    ),
    Required::joint(
        KEPT_FIXED[1],
        "base_link to caster_front, fixed: kept as a joint (the platform's bodies as tuned)",
    ),
    Required::joint(
        KEPT_FIXED[2],
        "base_link to caster_rear, fixed: kept as a joint (the platform's bodies as tuned)",
    ),
];

/// The fixed joints the physics keeps as joints: the wrist (made compliant,
/// see `joints`) and the casters, whose bodies the seed-004 gains were
/// tuned with.
const KEPT_FIXED: [&str; 3] = ["tool_joint", "caster_front_joint", "caster_rear_joint"];

/// An obstacle for the physics: a fixed convex collider.
#[derive(Debug, Clone)]
pub struct ObstacleShape {
    /// Name.
    pub name: String,
    /// Shape (world frame).
    pub shape: Superellipsoid,
}

/// Handles of one robot in the world.
struct RobotBodies {
    base: RigidBodyHandle,
    wheels: [RigidBodyHandle; 2],
    wheel_joints: [ImpulseJointHandle; 2],
    arm: [RigidBodyHandle; 6],
    arm_joints: [ImpulseJointHandle; 6],
    tool: RigidBodyHandle,
    /// The joint between the flange (link 6) and the gripper.
    tool_joint: ImpulseJointHandle,
    /// Every collider of the robot, and those that roll on the ground
    /// (wheels and casters: their ground contacts are not collisions).
    colliders: Vec<ColliderHandle>,
    rolling: Vec<ColliderHandle>,
    /// Link bodies in URDF order (for the logs).
    links: Vec<RigidBodyHandle>,
    /// Unwrapped heading and joint angles.
    theta: f64,
    q: [f64; 6],
    /// Joint references: the integral of the commanded joint rates.
    q_ref: [f64; 6],
}

/// The mobile manipulator(s) in Rapier.
pub struct MobileManipulatorPhysics {
    sim: SimWorld,
    robots: Vec<RobotBodies>,
    obstacles: Vec<ColliderHandle>,
    /// World AABBs of the (fixed) obstacles.
    obstacle_aabbs: Vec<Aabb>,
    /// The carried beam, if any.
    beam: Option<carried::Held>,
    /// The clearance channels (to obstacles, robot to robot), refreshed
    /// every [`CLEARANCE_EVERY`] steps.
    clearance: f64,
    robot_clearance: f64,
    steps: usize,
    gain: f64,
    max_torque: f64,
    dt: f64,
    last_u: Input,
    arm_servo: ArmServo,
    /// Per-joint torque limits of the arm servos, N m.
    arm_max_torque: [f64; 6],
    wrist: Wrist,
}

/// How the arm joints execute their rate commands.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum ArmServo {
    /// Stiff position servos: the commanded rate plus a pull with time
    /// constant `SERVO_TIME` towards the integral of the commanded rates,
    /// torque-limited at `[sim] motor_max_torque` (default).
    #[default]
    Stiff,
    /// Joint-space impedance with gravity compensation, as cooperative
    /// manipulators holding one object are run: τ = g(q) + K (q_ref − q) +
    /// D (u − q̇), g(q) the arm's own gravity load (the carried object's
    /// is not compensated). A kinematic inconsistency between the robots then
    /// bends the arms by ~force/K instead of loading the object.
    Impedance {
        /// K per joint, N m/rad.
        stiffness: [f64; 6],
        /// D per joint, N m s/rad.
        damping: [f64; 6],
    },
}

/// What the world holds besides the ground.
#[derive(Debug, Clone, Copy)]
pub struct Setup<'a> {
    /// Start configuration, 9 coordinates per robot.
    pub start: &'a [f64],
    /// Obstacles.
    pub obstacles: &'a [ObstacleShape],
    /// The beam two robots carry.
    pub beam: Option<&'a CarriedBeam>,
    /// The arms' joint servos.
    pub arm: ArmServo,
    /// Per-joint torque limits of the arms' servos, N m (`None`: the
    /// settings' `motor_max_torque` for every joint).
    pub arm_max_torque: Option<[f64; 6]>,
    /// Per-joint armature of the arms, kg m² (the rotor's reflected
    /// inertia, added to each joint's child link about the joint axis).
    pub arm_armature: [f64; 6],
    /// The wrists between flanges and grippers.
    pub wrist: Wrist,
}

impl MobileManipulatorPhysics {
    /// Build the world: one robot per 9 start coordinates (one or two), the
    /// obstacles, and the beam when two robots carry one.
    pub fn new(
        robot: &urdf_rs::Robot,
        urdf_dir: &Path,
        sim: &PhysicsSettings,
        setup: &Setup,
    ) -> Result<Self, SetupError> {
        check_urdf(robot)?;
        let start = setup.start;
        let k = start.len() / DOF;
        if !(1..=2).contains(&k) || start.len() != k * DOF {
            return Err(SetupError::other(format!(
                "mobile manipulator physics: {} start coordinates (9 per robot, one or two robots)",
                start.len()
            )));
        }
        if setup.beam.is_some() != (k == 2) {
            return Err(SetupError::other(
                "mobile manipulator physics: a beam needs exactly two robots".to_string(),
            ));
        }
        let root =
            |r: usize| rl::from_spatial(&mm::frames::<f64>(&start[DOF * r..DOF * (r + 1)]).base);
        // Worn tyres (`wheel_radius_scale`): the drive wheels lose (1 − s)·r of
        // radius, the casters as much, and the robot starts that much lower, level
        // on the ground. The wheel rates still use the model's radius.
        let wear = (1.0 - sim.wheel_radius_scale) * WHEEL_RADIUS;
        let worn = (wear != 0.0).then(|| {
            let tyres = ["left_wheel", "right_wheel", "caster_front", "caster_rear"];
            crate::engine::perturb::world::shrink_round_collisions(robot, &tyres, 1.0, Some(wear))
        });
        let robot = worn.as_ref().unwrap_or(robot);
        let mut sw = SimWorld::new(
            robot,
            urdf_dir,
            &crate::engine::world::WorldOptions {
                settings: sim,
                root_pose: root(0),
                ground: true,
                keep_fixed: &KEPT_FIXED,
            },
        )?;
        let mut handles = vec![sw.robot.clone()];
        if k == 2 {
            handles.push(sw.add_robot(robot, urdf_dir, root(1))?);
        }
        let mut robots = Vec::with_capacity(k);
        for (r, h) in handles.iter().enumerate() {
            robots.push(place_robot(&mut sw, h, &start[DOF * r..DOF * (r + 1)])?);
            if wear != 0.0 {
                for b in &h.links {
                    let body = &mut sw.world.bodies[*b];
                    let mut p = *body.position();
                    p.translation -= vector(0.0, 0.0, wear);
                    body.set_position(p, true);
                }
            }
        }
        for rb in &robots {
            add_armature(&mut sw.world, rb, &setup.arm_armature)?;
        }
        if let Wrist::Compliant(w) = setup.wrist {
            for rb in &robots {
                let j = sw
                    .world
                    .impulse_joints
                    .get_mut(rb.tool_joint, true)
                    .ok_or("mobile manipulator physics: tool_joint missing")?;
                j.data = compliant_wrist_joint(&w);
            }
            if let Some(spec) = setup.beam {
                // The URDF's gripper inertial (Rapier's body mass is only
                // known after a step).
                let tool = robot
                    .links
                    .iter()
                    .find(|l| l.name == "tool")
                    .ok_or("URDF has no link `tool`")?;
                let i = &tool.inertial;
                let gripper = (i.mass.value, i.origin.xyz.0);
                settle_wrists(&mut sw.world, &robots, &w, spec, gripper)?;
            }
        }
        // Collision groups: each robot against the ground, the obstacles and
        // the other robot; the platform boxes also against the beam.
        for (r, rb) in robots.iter().enumerate() {
            let other = if r == 0 { ROBOT[1] } else { ROBOT[0] };
            let filter = GROUND | OBSTACLE | other;
            for c in &rb.colliders {
                let platform = is_platform(&sw, rb.base, *c);
                let groups = if platform {
                    InteractionGroups::new(
                        ROBOT[r] | PLATFORM,
                        filter | BEAM,
                        InteractionTestMode::And,
                    )
                } else {
                    InteractionGroups::new(ROBOT[r], filter, InteractionTestMode::And)
                };
                sw.set_collision_groups(&[*c], groups);
            }
        }
        let ground_colliders: Vec<ColliderHandle> = sw.ground_collider.into_iter().collect();
        sw.set_collision_groups(
            &ground_colliders,
            InteractionGroups::new(GROUND, ROBOT[0] | ROBOT[1] | BEAM, InteractionTestMode::And),
        );
        let mut obstacle_handles = Vec::new();
        for o in setup.obstacles {
            let (v, _) = o.shape.mesh(16, 32);
            let pts: Vec<Vector> = v.iter().map(|p| vector(p[0], p[1], p[2])).collect();
            let builder = ColliderBuilder::convex_hull(&pts)
                .ok_or_else(|| SetupError::other(format!("obstacle `{}`: no convex hull", o.name)))?
                .collision_groups(InteractionGroups::new(
                    OBSTACLE,
                    ROBOT[0] | ROBOT[1] | BEAM,
                    InteractionTestMode::And,
                ))
                .friction(rl::r(sim.friction));
            let ground = sw.ground;
            obstacle_handles.push(sw.world.insert_collider(builder, Some(ground)));
        }
        let beam = match setup.beam {
            Some(spec) => Some(carried::Held::insert(
                &mut sw.world,
                spec,
                [robots[0].tool, robots[1].tool],
                match &setup.wrist {
                    Wrist::Compliant(_) => Some((
                        [robots[0].arm[5], robots[1].arm[5]],
                        [robots[0].tool_joint, robots[1].tool_joint],
                    )),
                    Wrist::Rigid => None,
                },
                InteractionGroups::new(
                    BEAM,
                    GROUND | OBSTACLE | PLATFORM,
                    InteractionTestMode::And,
                ),
            )?),
            None => None,
        };
        let mut me = MobileManipulatorPhysics {
            robots,
            obstacle_aabbs: obstacle_handles
                .iter()
                .map(|h| sw.world.colliders[*h].compute_aabb())
                .collect(),
            beam,
            clearance: f64::INFINITY,
            robot_clearance: f64::INFINITY,
            steps: 0,
            sim: sw,
            obstacles: obstacle_handles,
            gain: sim.motor_gain,
            max_torque: sim.motor_max_torque * sim.torque_scale,
            dt: sim.dt,
            last_u: Input::zeros(INPUTS * k),
            arm_servo: setup.arm,
            arm_max_torque: setup
                .arm_max_torque
                .unwrap_or([sim.motor_max_torque; 6])
                .map(|t| t * sim.torque_scale),
            wrist: setup.wrist,
        };
        if let ArmServo::Impedance { .. } = setup.arm {
            for r in 0..me.robots.len() {
                for a in 0..6 {
                    if let Some(jt) = me
                        .sim
                        .world
                        .impulse_joints
                        .get_mut(me.robots[r].arm_joints[a], false)
                    {
                        jt.data
                            .set_motor_model(JointAxis::AngX, MotorModel::ForceBased);
                    }
                }
            }
        }
        me.apply(&Input::zeros(INPUTS * k));
        me.refresh_clearances();
        Ok(me)
    }

    /// Joint i's angle from its two links (parent frame · joint origin vs child).
    fn joint_angle(&self, r: &RobotBodies, i: usize) -> f64 {
        let b = &self.sim.world.bodies;
        let parent = if i == 0 { r.base } else { r.arm[i - 1] };
        let origin_rot = if i == 0 {
            Rotation::IDENTITY
        } else {
            Rotation::from_rotation_x(rl::r(puma560::DH[i - 1].alpha))
        };
        let rel = (*b[parent].rotation() * origin_rot).inverse() * *b[r.arm[i]].rotation();
        angles::about_axis(&rel, 2)
    }

    /// Joint rate of joint i: relative angular velocity about the joint axis.
    fn joint_rate(&self, r: &RobotBodies, i: usize) -> f64 {
        let b = &self.sim.world.bodies;
        let parent = if i == 0 { r.base } else { r.arm[i - 1] };
        let child = &b[r.arm[i]];
        let axis = *child.rotation() * Vector::Z;
        f((child.angvel() - b[parent].angvel()).dot(axis))
    }
}

fn norm3(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

impl PhysicsSystem for MobileManipulatorPhysics {
    fn state(&self) -> State {
        let mut out = Vec::with_capacity(DOF * self.robots.len());
        for r in &self.robots {
            let t = self.sim.world.bodies[r.base].translation();
            out.extend([f(t.x), f(t.y), r.theta]);
            out.extend(r.q);
        }
        State::from_vec(out)
    }

    fn apply(&mut self, u: &Input) {
        let (gain, tmax) = (self.gain, self.max_torque);
        for (k, r) in self.robots.iter().enumerate() {
            let j = INPUTS * k;
            let (v, w) = (u[j], u[j + 1]);
            let left = (v - w * HALF_TRACK) / WHEEL_RADIUS;
            let right = (v + w * HALF_TRACK) / WHEEL_RADIUS;
            self.sim.drive_joint(r.wheel_joints[0], left, gain, tmax);
            self.sim.drive_joint(r.wheel_joints[1], right, gain, tmax);
            for a in 0..6 {
                // A joint servo: the commanded rate plus a pull towards the
                // integral of the commanded rates (the reference at the end of this
                // step), as a real arm's position servos execute velocity commands.
                // A bare velocity motor lets the arm sag under gravity (joint 3
                // drifts 0.05 rad/s at 8 solver iterations), which the feedback law,
                // whose gains vanish at the goal, cannot undo.
                let rate = u[j + 2 + a];
                let target = angles::wrap(r.q_ref[a] + rate * self.dt);
                let (stiff, damp) = match self.arm_servo {
                    ArmServo::Stiff => (gain / SERVO_TIME, gain),
                    ArmServo::Impedance { stiffness, damping } => (stiffness[a], damping[a]),
                };
                if let Some(jt) = self
                    .sim
                    .world
                    .impulse_joints
                    .get_mut(r.arm_joints[a], false)
                {
                    jt.data
                        .set_motor(
                            JointAxis::AngX,
                            rl::r(target),
                            rl::r(rate),
                            rl::r(stiff),
                            rl::r(damp),
                        )
                        .set_motor_max_force(JointAxis::AngX, rl::r(self.arm_max_torque[a]));
                }
            }
        }
        self.last_u = u.clone();
        if let ArmServo::Impedance { .. } = self.arm_servo {
            self.compensate_gravity();
        }
    }

    fn step(&mut self) {
        self.sim.world.step();
        self.steps += 1;
        if let Some(b) = &mut self.beam {
            b.after_step(&self.sim.world);
        }
        if self.steps.is_multiple_of(CLEARANCE_EVERY) {
            self.refresh_clearances();
        }
        for k in 0..self.robots.len() {
            let yaw = angles::yaw(self.sim.world.bodies[self.robots[k].base].rotation());
            let q: [f64; 6] = std::array::from_fn(|i| self.joint_angle(&self.robots[k], i));
            let u = &self.last_u;
            let dt = self.dt;
            let r = &mut self.robots[k];
            for a in 0..6 {
                r.q_ref[a] += u[INPUTS * k + 2 + a] * dt;
            }
            r.theta = angles::unwrap(r.theta, yaw);
            for (qi, now) in r.q.iter_mut().zip(q) {
                *qi = angles::unwrap(*qi, now);
            }
        }
    }

    /// Every robot's links in URDF order, then the beam's segments (the
    /// order of [`link_visuals`]).
    fn link_poses(&self) -> Vec<Pose> {
        let bodies = &self.sim.world.bodies;
        let mut out: Vec<Pose> = self
            .robots
            .iter()
            .flat_map(|r| r.links.iter().map(|h| rl::to_pose(bodies[*h].position())))
            .collect();
        if let Some(b) = &self.beam {
            out.extend(b.segment_poses(&self.sim.world));
        }
        out
    }

    fn channel_names(&self) -> Vec<String> {
        [
            "min_clearance",
            "obstacle_contacts",
            "slip_left",
            "slip_right",
            "slip_lateral",
            "speed_error",
            "turn_rate_error",
            "joint_rate_error",
            "tilt_deg",
        ]
        .map(String::from)
        .into_iter()
        .chain(
            (self.robots.len() == 2)
                .then_some(carried::PAIR_CHANNELS)
                .into_iter()
                .flatten()
                .map(String::from),
        )
        .chain(
            matches!(self.wrist, Wrist::Compliant(_))
                .then_some(WRIST_CHANNELS)
                .into_iter()
                .flatten()
                .map(String::from),
        )
        .collect()
    }

    /// Each flange's world pose (link 6, the frame the wrist hangs from):
    /// position then rotation matrix row by row
    /// ([`mm::flange_from_measurement`] reads it back).
    fn measurement(&self) -> Option<Vec<f64>> {
        let b = &self.sim.world.bodies;
        let mut out = Vec::with_capacity(mm::FLANGE_MEASUREMENT * self.robots.len());
        for r in &self.robots {
            let p = rl::to_spatial(b[r.arm[5]].position());
            out.extend(p.p);
            out.extend(p.r.iter().flatten());
        }
        Some(out)
    }

    fn channels(&self) -> Vec<f64> {
        let r = &self.robots[0];
        let m = self.platform_motion(0);
        let mut out = vec![
            self.clearance,
            self.obstacle_contacts() as f64,
            m.slip[0],
            m.slip[1],
            m.lateral,
            m.speed - self.last_u[0],
            m.turn_rate - self.last_u[1],
            self.joint_rate_error(r, 0),
            m.tilt_deg,
        ];
        if self.robots.len() == 2 {
            let m2 = self.platform_motion(1);
            out.extend([
                self.robot_clearance,
                self.body_contacts() as f64,
                m2.lateral,
                self.joint_rate_error(&self.robots[1], 1),
                m2.tilt_deg,
            ]);
            if let Some(b) = &self.beam {
                out.extend(b.channels(&self.sim.world));
            }
        }
        if let Wrist::Compliant(w) = self.wrist {
            for r in &self.robots {
                out.extend(self.wrist_deflection(r, &w));
            }
        }
        out
    }
}

/// One platform's measured motion.
struct PlatformMotion {
    /// Wheel contact-point speeds along the heading (left, right), m/s.
    slip: [f64; 2],
    /// Axle-centre speed across the heading, m/s.
    lateral: f64,
    /// Axle-centre speed along the heading, m/s, and yaw rate, rad/s.
    speed: f64,
    turn_rate: f64,
    /// Angle between the platform's up axis and the world's, deg: the
    /// planner's planar state (x, y, θ) cannot see a platform tipping.
    tilt_deg: f64,
}

impl MobileManipulatorPhysics {
    fn platform_motion(&self, k: usize) -> PlatformMotion {
        let b = &self.sim.world.bodies;
        let r = &self.robots[k];
        let base = &b[r.base];
        let heading = *base.rotation() * Vector::X;
        let side = *base.rotation() * Vector::Y;
        let v_axle = base.velocity_at_point(base.translation());
        let slip = |w: RigidBodyHandle| {
            let wb = &b[w];
            let contact = wb.translation() - vector(0.0, 0.0, WHEEL_RADIUS);
            f(wb.velocity_at_point(contact).dot(heading))
        };
        PlatformMotion {
            slip: [slip(r.wheels[0]), slip(r.wheels[1])],
            lateral: f(v_axle.dot(side)),
            speed: f(v_axle.dot(heading)),
            turn_rate: f(base.angvel().z),
            tilt_deg: f((*base.rotation() * Vector::Z).z.clamp(-1.0, 1.0).acos()).to_degrees(),
        }
    }

    /// Gravity compensation of the impedance servos: each arm joint gets
    /// the torque that holds the links beyond it against gravity, applied as
    /// an equal and opposite pair on its two bodies (set anew every step:
    /// Rapier keeps user torques until reset).
    fn compensate_gravity(&mut self) {
        let g = self.sim.world.gravity;
        let bodies = &mut self.sim.world.bodies;
        for r in &self.robots {
            // Mass and first moment of the links beyond each joint, tool first.
            let tool = &bodies[r.tool];
            let (mut m, mut mc) = (tool.mass(), tool.center_of_mass() * tool.mass());
            let mut torque = [Vector::ZERO; 6];
            for k in (0..6).rev() {
                let b = &bodies[r.arm[k]];
                m += b.mass();
                mc += b.center_of_mass() * b.mass();
                let (p, z) = (b.translation(), *b.rotation() * Vector::Z);
                // Gravity's moment about the joint axis, negated.
                let about = (mc - p * m).cross(g);
                torque[k] = -z * about.dot(z);
            }
            bodies[r.base].reset_torques(false);
            for &link in &r.arm {
                bodies[link].reset_torques(false);
            }
            for k in 0..6 {
                let parent = if k == 0 { r.base } else { r.arm[k - 1] };
                bodies[r.arm[k]].add_torque(torque[k], true);
                bodies[parent].add_torque(-torque[k], true);
            }
        }
    }

    /// A compliant wrist's deflection: |translation| (m) and rotation angle
    /// (rad) of the gripper's grasp frame in the flange's, and the largest
    /// |deflection| / travel over the six axes.
    fn wrist_deflection(&self, r: &RobotBodies, w: &CompliantWrist) -> [f64; 3] {
        let b = &self.sim.world.bodies;
        let g = grasp_frame();
        let rel = (*b[r.arm[5]].position() * g).inverse() * (*b[r.tool].position() * g);
        let t = rel.translation;
        let rot = rel.rotation.to_scaled_axis();
        let axes = [t.x, t.y, t.z, rot.x, rot.y, rot.z].map(f);
        let used = (0..6)
            .map(|i| axes[i].abs() / w.travel[i])
            .fold(0.0, f64::max);
        [norm3(&axes[..3]), norm3(&axes[3..]), used]
    }

    /// Largest |measured − commanded| joint rate of robot `k`, rad/s.
    fn joint_rate_error(&self, r: &RobotBodies, k: usize) -> f64 {
        (0..6)
            .map(|i| (self.joint_rate(r, i) - self.last_u[INPUTS * k + 2 + i]).abs())
            .fold(0.0, f64::max)
    }
}
