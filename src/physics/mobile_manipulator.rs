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
//! planner avoids). Robot colliders meet the ground and the obstacles, never
//! each other.
//!
//! Read-back: (x, y, θ) of `base_link` (θ unwrapped), each joint angle from
//! the relative rotation of its two links. Channels: `min_clearance` (least
//! distance, m, between any robot collider and any obstacle collider, parry
//! distance queries), `obstacle_contacts` (robot–obstacle collider pairs in
//! contact), `slip_left`/`slip_right` (wheel contact-point speed along the
//! heading, m/s), `slip_lateral` (axle-centre speed across the heading: the
//! violated nonholonomic constraint, m/s), `speed_error`, `turn_rate_error`
//! (measured − commanded platform v, ω) and `joint_rate_error` (largest
//! |measured − commanded| joint rate, rad/s).

use super::rapier::parry::bounding_volume::Aabb;
use super::rapier::prelude::*;
use super::real::{self as rl, f, rotation, vector};
use super::settings::PhysicsSettings;
use super::urdf::SimWorld;
use super::{angles, PhysicsSystem};
use crate::model::ellipsoid::Superellipsoid;
use crate::model::mobile_manipulator::{
    self as mm, CollisionShape, Link, DOF, HALF_TRACK, INPUTS, MOUNT, WHEEL_RADIUS,
};
use crate::model::puma560;
use crate::model::spatial::Pose as SPose;
use crate::model::{Input, State};
use crate::record::Pose;
use std::fmt::Write as _;
use std::path::Path;

/// Collision group of robot colliders.
const ROBOT: Group = Group::GROUP_1;
/// Collision group of the ground.
const GROUND: Group = Group::GROUP_2;
/// Collision group of obstacles.
const OBSTACLE: Group = Group::GROUP_3;

/// The clearance channel is recomputed every this many steps (held between:
/// the distance queries cost more than a physics step).
const CLEARANCE_EVERY: usize = 5;

/// Time constant of the joint servos' pull towards their references, s.
const SERVO_TIME: f64 = 0.05;

/// Mass of the platform body, kg (a choice: a PUMA-carrying base).
const PLATFORM_MASS: f64 = 120.0;
/// Wheel mass, kg.
const WHEEL_MASS: f64 = 2.0;
/// Gripper mass, kg.
const TOOL_MASS: f64 = 0.5;

fn fmt3(v: [f64; 3]) -> String {
    format!("{} {} {}", v[0], v[1], v[2])
}

/// URDF `<origin>` orienting the z axis of a cylinder along `axis`.
fn cylinder_rpy(axis: [f64; 3]) -> [f64; 3] {
    if axis[0].abs() > 0.5 {
        [0.0, std::f64::consts::FRAC_PI_2, 0.0]
    } else if axis[1].abs() > 0.5 {
        [std::f64::consts::FRAC_PI_2, 0.0, 0.0]
    } else {
        [0.0; 3]
    }
}

fn geometry(shape: &CollisionShape, center_shift: [f64; 3]) -> (String, [f64; 3], [f64; 3]) {
    let sub = |c: [f64; 3]| {
        [
            c[0] - center_shift[0],
            c[1] - center_shift[1],
            c[2] - center_shift[2],
        ]
    };
    match *shape {
        CollisionShape::Cuboid { center, half } => (
            format!("<box size=\"{}\"/>", fmt3(half.map(|h| 2.0 * h))),
            sub(center),
            [0.0; 3],
        ),
        CollisionShape::Cylinder {
            center,
            axis,
            radius,
            half_length,
        } => (
            format!(
                "<cylinder radius=\"{radius}\" length=\"{}\"/>",
                2.0 * half_length
            ),
            sub(center),
            cylinder_rpy(axis),
        ),
        CollisionShape::Sphere { center, radius } => (
            format!("<sphere radius=\"{radius}\"/>"),
            sub(center),
            [0.0; 3],
        ),
    }
}

fn inertial(out: &mut String, mass: f64, com: [f64; 3], rpy: [f64; 3], i: [f64; 3]) {
    let _ = write!(
        out,
        "    <inertial>\n      <origin xyz=\"{}\" rpy=\"{}\"/>\n      <mass value=\"{mass}\"/>\n      \
         <inertia ixx=\"{}\" ixy=\"0\" ixz=\"0\" iyy=\"{}\" iyz=\"0\" izz=\"{}\"/>\n    </inertial>\n",
        fmt3(com),
        fmt3(rpy),
        i[0],
        i[1],
        i[2]
    );
}

fn shape_elements(out: &mut String, shape: &CollisionShape, shift: [f64; 3], material: &str) {
    let (geom, xyz, rpy) = geometry(shape, shift);
    for tag in ["visual", "collision"] {
        let mat = if tag == "visual" {
            format!("\n      <material name=\"{material}\"/>")
        } else {
            String::new()
        };
        let _ = write!(
            out,
            "    <{tag}>\n      <origin xyz=\"{}\" rpy=\"{}\"/>\n      <geometry>{geom}</geometry>{mat}\n    </{tag}>\n",
            fmt3(xyz),
            fmt3(rpy)
        );
    }
}

fn box_inertia(m: f64, half: [f64; 3]) -> [f64; 3] {
    let [a, b, c] = half.map(|h| 2.0 * h);
    [
        m * (b * b + c * c) / 12.0,
        m * (a * a + c * c) / 12.0,
        m * (a * a + b * b) / 12.0,
    ]
}

/// The URDF text of one mobile manipulator, generated from the model's
/// numbers ([`mm`], [`puma560`]); `models/mobile_manipulator.urdf` must equal
/// it (a test checks), so the URDF and the kinematic model cannot drift apart.
pub fn urdf() -> String {
    let shapes = mm::collision_shapes();
    let mut s = String::new();
    s.push_str(
        "<?xml version=\"1.0\"?>\n<!--\n  Mobile manipulator of seed 004 (Tanner, Loizou & Kyriakopoulos): a\n  \
         differential-drive platform carrying a PUMA 560 arm (standard DH and\n  inertial parameters \
         from Corke's mdl_puma560 / Armstrong et al. 1986; link 1\n  mass 10 kg is ours). \
         GENERATED by anholonomy::physics::mobile_manipulator::urdf()\n  from the kinematic model: \
         edit the model, then run its test urdf_matches_the_model\n  with UPDATE_URDF=1 set.\n\n  \
         base_link origin: the drive-axle midpoint on the ground (the model's (x, y)),\n  \
         +x forward. Wheels: radius 0.1 m at y = +-0.32 m, sphere collisions (point\n  \
         contacts). Casters: frictionless balls (anholonomy sets their friction to 0).\n  \
         Arm: URDF link<i> = DH frame i-1 turned by q_i; every arm joint turns about z.\n-->\n\
         <robot name=\"mobile_manipulator\">\n  <material name=\"body\"><color rgba=\"0.25 0.45 0.75 1\"/></material>\n  \
         <material name=\"arm\"><color rgba=\"0.85 0.85 0.82 1\"/></material>\n  \
         <material name=\"tyre\"><color rgba=\"0.12 0.12 0.14 1\"/></material>\n  \
         <material name=\"tool\"><color rgba=\"0.9 0.5 0.1 1\"/></material>\n\n",
    );
    // base_link: platform box and pedestal.
    s.push_str("  <link name=\"base_link\">\n");
    let CollisionShape::Cuboid { center, half } = shapes[0].1 else {
        unreachable!("the first collision shape is the platform box")
    };
    inertial(
        &mut s,
        PLATFORM_MASS,
        center,
        [0.0; 3],
        box_inertia(PLATFORM_MASS, half),
    );
    for (link, shape) in &shapes {
        if *link == Link::Base {
            if let CollisionShape::Sphere { .. } = shape {
                continue;
            }
            shape_elements(&mut s, shape, [0.0; 3], "body");
        }
    }
    s.push_str("  </link>\n\n");
    // Casters and wheels: the sphere shapes of the base.
    let spheres: Vec<[f64; 3]> = shapes
        .iter()
        .filter_map(|(l, sh)| match (l, sh) {
            (Link::Base, CollisionShape::Sphere { center, .. }) => Some(*center),
            _ => None,
        })
        .collect();
    for (name, c) in ["caster_front", "caster_rear"].iter().zip(&spheres[..2]) {
        let _ = writeln!(s, "  <link name=\"{name}\">");
        inertial(&mut s, 0.2, [0.0; 3], [0.0; 3], [2e-4; 3]);
        let r = 0.05;
        shape_elements(
            &mut s,
            &CollisionShape::Sphere {
                center: [0.0; 3],
                radius: r,
            },
            [0.0; 3],
            "tyre",
        );
        s.push_str("  </link>\n");
        let _ = writeln!(
            s,
            "  <joint name=\"{name}_joint\" type=\"fixed\">\n    <parent link=\"base_link\"/>\n    \
             <child link=\"{name}\"/>\n    <origin xyz=\"{}\"/>\n  </joint>\n",
            fmt3(*c)
        );
    }
    for (name, side) in [("left_wheel", 1.0), ("right_wheel", -1.0)] {
        let _ = writeln!(s, "  <link name=\"{name}\">");
        let (r, w) = (WHEEL_RADIUS, 0.05);
        let side_i = WHEEL_MASS * (3.0 * r * r + w * w) / 12.0;
        inertial(
            &mut s,
            WHEEL_MASS,
            [0.0; 3],
            [0.0; 3],
            [side_i, WHEEL_MASS * r * r / 2.0, side_i],
        );
        let _ = write!(
            s,
            "    <visual>\n      <origin xyz=\"0 0 0\" rpy=\"{} 0 0\"/>\n      \
             <geometry><cylinder radius=\"{r}\" length=\"{w}\"/></geometry>\n      <material name=\"tyre\"/>\n    </visual>\n    \
             <collision>\n      <origin xyz=\"0 0 0\"/>\n      <geometry><sphere radius=\"{r}\"/></geometry>\n    </collision>\n",
            std::f64::consts::FRAC_PI_2
        );
        s.push_str("  </link>\n");
        let _ = writeln!(
            s,
            "  <joint name=\"{name}_joint\" type=\"continuous\">\n    <parent link=\"base_link\"/>\n    \
             <child link=\"{name}\"/>\n    <origin xyz=\"0 {} {r}\"/>\n    <axis xyz=\"0 1 0\"/>\n  </joint>\n",
            side * HALF_TRACK
        );
    }
    // Arm links.
    for i in 0..6 {
        let link = Link::Arm(i as u8 + 1);
        let _ = writeln!(s, "  <link name=\"{}\">", link.urdf_name());
        let p = puma560::INERTIA[i];
        let off = puma560::row_offset::<f64>(i);
        inertial(
            &mut s,
            p.mass,
            off.apply(p.com),
            [puma560::DH[i].alpha, 0.0, 0.0],
            p.inertia,
        );
        for (l, shape) in &shapes {
            if *l == link {
                shape_elements(&mut s, shape, [0.0; 3], "arm");
            }
        }
        s.push_str("  </link>\n");
        let (parent, origin, rpy) = if i == 0 {
            ("base_link".to_string(), MOUNT, [0.0; 3])
        } else {
            let r = puma560::DH[i - 1];
            (
                Link::Arm(i as u8).urdf_name().to_string(),
                [r.a, 0.0, r.d],
                [r.alpha, 0.0, 0.0],
            )
        };
        let _ = writeln!(
            s,
            "  <joint name=\"joint{}\" type=\"continuous\">\n    <parent link=\"{parent}\"/>\n    \
             <child link=\"{}\"/>\n    <origin xyz=\"{}\" rpy=\"{}\"/>\n    <axis xyz=\"0 0 1\"/>\n  </joint>\n",
            i + 1,
            link.urdf_name(),
            fmt3(origin),
            fmt3(rpy)
        );
    }
    // The tool, fixed at the flange (DH frame 6 = link6's frame: row 6 is the identity).
    s.push_str("  <link name=\"tool\">\n");
    inertial(
        &mut s,
        TOOL_MASS,
        [0.0, 0.0, 0.1],
        [0.0; 3],
        [6e-4, 6e-4, 3e-4],
    );
    for (l, shape) in &shapes {
        if *l == Link::Tool {
            shape_elements(&mut s, shape, [0.0; 3], "tool");
        }
    }
    s.push_str("  </link>\n");
    let r6 = puma560::DH[5];
    let _ = writeln!(
        s,
        "  <joint name=\"tool_joint\" type=\"fixed\">\n    <parent link=\"link6\"/>\n    <child link=\"tool\"/>\n    \
         <origin xyz=\"{}\" rpy=\"{} 0 0\"/>\n  </joint>\n</robot>",
        fmt3([r6.a, 0.0, r6.d]),
        r6.alpha
    );
    s
}

/// URDF joint names of the arm, in order.
pub const ARM_JOINTS: [&str; 6] = ["joint1", "joint2", "joint3", "joint4", "joint5", "joint6"];

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
    colliders: Vec<ColliderHandle>,
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
    /// The clearance channel, refreshed every [`CLEARANCE_EVERY`] steps.
    clearance: f64,
    steps: usize,
    gain: f64,
    max_torque: f64,
    dt: f64,
    last_u: Input,
}

fn to_rapier(p: &SPose<f64>) -> super::rapier::math::Pose {
    let q = p.quaternion();
    super::rapier::math::Pose::from_parts(
        vector(p.p[0], p.p[1], p.p[2]),
        rotation(q[0], q[1], q[2], q[3]),
    )
}

/// Check the URDF's arm joints against the DH table the planner uses.
fn check_urdf(robot: &urdf_rs::Robot) -> Result<(), String> {
    for (i, name) in ARM_JOINTS.iter().enumerate() {
        let j = robot
            .joints
            .iter()
            .find(|j| j.name == *name)
            .ok_or_else(|| format!("URDF has no joint `{name}`"))?;
        let (xyz, rpy) = if i == 0 {
            (MOUNT, [0.0; 3])
        } else {
            let r = puma560::DH[i - 1];
            ([r.a, 0.0, r.d], [r.alpha, 0.0, 0.0])
        };
        let bad = (0..3).any(|k| {
            (j.origin.xyz[k] - xyz[k]).abs() > 1e-9 || (j.origin.rpy[k] - rpy[k]).abs() > 1e-9
        }) || j.axis.xyz.0 != [0.0, 0.0, 1.0];
        if bad {
            return Err(format!(
                "URDF joint `{name}` differs from the PUMA 560 model (origin {xyz:?} rpy {rpy:?}, axis z expected)"
            ));
        }
    }
    Ok(())
}

impl MobileManipulatorPhysics {
    /// Build the world with one robot at `start` (9 coordinates) and the obstacles.
    pub fn new(
        robot: &urdf_rs::Robot,
        urdf_dir: &Path,
        start: &[f64],
        sim: &PhysicsSettings,
        obstacles: &[ObstacleShape],
    ) -> Result<Self, String> {
        check_urdf(robot)?;
        let frames = mm::frames::<f64>(&start[..DOF]);
        let mut sw = SimWorld::on_ground(robot, urdf_dir, sim, to_rapier(&frames.base));
        let link = |sw: &SimWorld, n: &str| sw.require_link(n);
        let base = link(&sw, "base_link")?;
        let wheels = [link(&sw, "left_wheel")?, link(&sw, "right_wheel")?];
        let wheel_joints = [
            sw.require_joint("left_wheel_joint")?,
            sw.require_joint("right_wheel_joint")?,
        ];
        let mut arm = [base; 6];
        let mut arm_joints = [wheel_joints[0]; 6];
        for i in 0..6 {
            arm[i] = link(&sw, Link::Arm(i as u8 + 1).urdf_name())?;
            arm_joints[i] = sw.require_joint(ARM_JOINTS[i])?;
        }
        // Put the arm at the start angles (the URDF loads at q = 0).
        for (body, pose) in arm.iter().zip(&frames.arm) {
            sw.world.bodies[*body].set_position(to_rapier(pose), true);
        }
        let tool = link(&sw, "tool")?;
        sw.world.bodies[tool].set_position(to_rapier(&frames.tool), true);
        // Casters roll freely: no friction.
        for name in ["caster_front", "caster_rear"] {
            let h = link(&sw, name)?;
            for c in sw.world.bodies[h].colliders().to_vec() {
                if let Some(col) = sw.world.colliders.get_mut(c) {
                    col.set_friction(0.0);
                }
            }
        }
        // Collision groups: robot vs ground and obstacles, never robot vs robot.
        let robot_colliders = sw.robot.colliders.clone();
        sw.set_collision_groups(
            &robot_colliders,
            InteractionGroups::new(ROBOT, GROUND | OBSTACLE, InteractionTestMode::And),
        );
        let ground_colliders: Vec<ColliderHandle> = sw.ground_collider.into_iter().collect();
        sw.set_collision_groups(
            &ground_colliders,
            InteractionGroups::new(GROUND, ROBOT, InteractionTestMode::And),
        );
        let mut obstacle_handles = Vec::new();
        for o in obstacles {
            let (v, _) = o.shape.mesh(16, 32);
            let pts: Vec<Vector> = v.iter().map(|p| vector(p[0], p[1], p[2])).collect();
            let builder = ColliderBuilder::convex_hull(&pts)
                .ok_or_else(|| format!("obstacle `{}`: no convex hull", o.name))?
                .collision_groups(InteractionGroups::new(
                    OBSTACLE,
                    ROBOT,
                    InteractionTestMode::And,
                ))
                .friction(rl::r(sim.friction));
            let ground = sw.ground;
            obstacle_handles.push(sw.world.insert_collider(builder, Some(ground)));
        }
        let mut me = MobileManipulatorPhysics {
            robots: vec![RobotBodies {
                base,
                wheels,
                wheel_joints,
                arm,
                arm_joints,
                colliders: robot_colliders,
                theta: start[2],
                q: std::array::from_fn(|i| start[3 + i]),
                q_ref: std::array::from_fn(|i| start[3 + i]),
            }],
            obstacle_aabbs: obstacle_handles
                .iter()
                .map(|h| sw.world.colliders[*h].compute_aabb())
                .collect(),
            clearance: f64::INFINITY,
            steps: 0,
            sim: sw,
            obstacles: obstacle_handles,
            gain: sim.motor_gain,
            max_torque: sim.motor_max_torque,
            dt: sim.dt,
            last_u: Input::zeros(INPUTS),
        };
        me.apply(&Input::zeros(INPUTS));
        me.clearance = me.min_clearance();
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

    /// Least distance between any robot collider and any obstacle (m), with an
    /// AABB pre-filter; 0 when touching or overlapping.
    pub fn min_clearance(&self) -> f64 {
        let cs = &self.sim.world.colliders;
        let gap = |a: &Aabb, b: &Aabb| {
            let d = (a.mins - b.maxs).max(b.mins - a.maxs).max(Vector::ZERO);
            f(d.length())
        };
        // Robot AABBs once; pairs whose boxes are farther apart than the best
        // distance so far cannot improve it.
        let robot: Vec<(ColliderHandle, Aabb)> = self
            .robots
            .iter()
            .flat_map(|r| r.colliders.iter())
            .map(|c| (*c, cs[*c].compute_aabb()))
            .collect();
        let mut best = f64::INFINITY;
        for (o, ob) in self.obstacles.iter().zip(&self.obstacle_aabbs) {
            let oc = &cs[*o];
            for (c, rb) in &robot {
                if gap(rb, ob) >= best {
                    continue;
                }
                let rc = &cs[*c];
                if let Ok(d) = super::rapier::parry::query::distance(
                    rc.position(),
                    rc.shape(),
                    oc.position(),
                    oc.shape(),
                ) {
                    best = best.min(f(d.distance));
                }
            }
        }
        best
    }

    /// Robot–obstacle collider pairs with an active contact.
    pub fn obstacle_contacts(&self) -> usize {
        self.obstacles
            .iter()
            .map(|o| {
                self.sim
                    .world
                    .narrow_phase
                    .contact_pairs_with(*o)
                    .filter(|p| p.has_any_active_contact())
                    .count()
            })
            .sum()
    }
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
                // A joint servo: the commanded rate plus a stiff pull towards the
                // integral of the commanded rates (the reference at the end of this
                // step), as a real arm's position servos execute velocity commands.
                // A bare velocity motor lets the arm sag under gravity (joint 3
                // drifts 0.05 rad/s at 8 solver iterations), which the feedback law,
                // whose gains vanish at the goal, cannot undo.
                let rate = u[j + 2 + a];
                let target = angles::wrap(r.q_ref[a] + rate * self.dt);
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
                            rl::r(gain / SERVO_TIME),
                            rl::r(gain),
                        )
                        .set_motor_max_force(JointAxis::AngX, rl::r(tmax));
                }
            }
        }
        self.last_u = u.clone();
    }

    fn step(&mut self) {
        self.sim.world.step();
        self.steps += 1;
        if self.steps.is_multiple_of(CLEARANCE_EVERY) {
            self.clearance = self.min_clearance();
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

    fn link_poses(&self) -> Vec<Pose> {
        self.sim.link_poses()
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
        ]
        .map(String::from)
        .to_vec()
    }

    fn channels(&self) -> Vec<f64> {
        let b = &self.sim.world.bodies;
        let r = &self.robots[0];
        let base = &b[r.base];
        let heading = *base.rotation() * Vector::X;
        let side = *base.rotation() * Vector::Y;
        let axle = base.translation();
        let v_axle = base.velocity_at_point(axle);
        let slip = |w: RigidBodyHandle| {
            let wb = &b[w];
            let contact = wb.translation() - vector(0.0, 0.0, WHEEL_RADIUS);
            f(wb.velocity_at_point(contact).dot(heading))
        };
        let joint_err = (0..6)
            .map(|i| (self.joint_rate(r, i) - self.last_u[2 + i]).abs())
            .fold(0.0, f64::max);
        vec![
            self.clearance,
            self.obstacle_contacts() as f64,
            slip(r.wheels[0]),
            slip(r.wheels[1]),
            f(v_axle.dot(side)),
            f(v_axle.dot(heading)) - self.last_u[0],
            f(base.angvel().z) - self.last_u[1],
            joint_err,
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn urdf_matches_the_model() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/mobile_manipulator.urdf");
        let text = urdf();
        if std::env::var_os("UPDATE_URDF").is_some() {
            std::fs::write(&path, &text).unwrap();
        }
        let committed = std::fs::read_to_string(&path).unwrap_or_default();
        assert!(
            committed == text,
            "models/mobile_manipulator.urdf differs from the model: UPDATE_URDF=1 cargo test --release --lib urdf_matches"
        );
        let robot = urdf_rs::read_from_string(&text).unwrap();
        check_urdf(&robot).unwrap();
    }
}
