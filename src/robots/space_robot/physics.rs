//! Rigid-body free-floating space robot: `models/space_robot.urdf` in Rapier.
//!
//! Design (measured choices, see the scenarios and `tests/it/space_robot.rs`):
//! * **Impulse joints** ([`crate::engine::world`]): every joint impulse acts equally
//!   and oppositely on two bodies, so the solver conserves the system's
//!   linear and angular momentum. Multibody joints drifted ~0.3 % in base
//!   attitude and injected momentum in an earlier prototype (not re-measured
//!   here), so they are not used. What leaks (f32 round-off, Rapier's relax
//!   pass, several substeps with position-targeting drives) is measured in
//!   docs/src/research/space-robot.md; with f64, one substep, 4 sweeps and no
//!   relax pass (no ground) max |L_z| on `space_robot_paper` is 1.5e-6
//!   kg m²/s (the vehicle alone carries up to ~0.7 kg m²/s).
//! * No ground, **gravity must be zero**, bodies never sleep. Nothing holds
//!   the vehicle: θ0 changes only because the joint drives exchange angular
//!   momentum between the bodies.
//! * Joints θ1, θ2 have servo drives ([`crate::engine::world::Drive`]) for the model
//!   inputs θ1', θ2'.
//! * **All robot self-contacts are disabled**: the loader already skips the
//!   jointed pairs (vehicle/link 1, link 1/link 2: its joints have contacts
//!   disabled), and the non-adjacent pair vehicle/link 2 is excluded with
//!   collision groups (the arm may fold over the vehicle; the kinematic model
//!   has no contacts). The `contact_pairs` channel counts active contact
//!   pairs every step so a scenario can assert it stays 0.
//! * The start configuration is set by placing the three bodies at the poses
//!   of [`SpaceRobot::body_poses`] (system CoM at the world origin), which
//!   satisfies both revolute joints exactly.
//!
//! Read-back: θ0 is the vehicle's angle about z, θ1 and θ2 the relative
//! angles about z of link 1 to the vehicle and of link 2 to link 1, all
//! unwrapped continuously. Channels (per step): total angular momentum about
//! the system CoM (z component and the out-of-plane part), linear momentum,
//! the distance of the system CoM from where it started, the largest
//! out-of-plane excursion (|z| of a body CoM, m, plus tilt of a body's z axis,
//! rad) and the number of active contact pairs.

use crate::engine::rapier::prelude::*;
use crate::engine::real::{arr, quat, r, vector};
use crate::engine::required::Required;
use crate::engine::urdf::{Drive, SimWorld, WorldOptions};
use crate::engine::{angles, PhysicsSettings, PhysicsSystem};
use crate::error::SetupError;
use crate::model::{Input, State};
use crate::record::Pose;
use crate::robots::space_robot::kinematics::SpaceRobot;

use std::path::Path;

/// Link names the URDF must use (vehicle, link 1, link 2).
pub const LINKS: [&str; 3] = ["vehicle", "link1", "link2"];
/// Joint names (θ1, θ2).
pub const JOINTS: [&str; 2] = ["joint1", "joint2"];

/// The links and joints the space robot looks up in its URDF (it must have
/// exactly these, with the model's masses, inertias and lengths).
pub const REQUIRED: [Required; 5] = [
    Required::link(
        LINKS[0],
        "the vehicle (root link), mass m0 and izz I0 of the model",
    ),
    Required::link(LINKS[1], "arm link 1, CoM at l1/2 on its x axis"),
    Required::link(LINKS[2], "arm link 2, CoM at l2/2 on its x axis"),
    Required::joint(JOINTS[0], "vehicle to link1 at its origin, about +z: θ1"),
    Required::joint(JOINTS[1], "link1 to link2 at x = l1, about +z: θ2"),
];

/// Names of the per-step channels, in [`SpaceRobotPhysics::channels`] order.
pub const CHANNELS: [&str; 6] = [
    "angular_momentum_z",
    "angular_momentum_out_of_plane",
    "linear_momentum_norm",
    "com_drift",
    "out_of_plane",
    "contact_pairs",
];

/// Angle about z of a rotation (exact for rotations about z).
fn angle_z(q: &crate::engine::rapier::math::Rotation) -> f64 {
    angles::about_axis(q, 2)
}

/// Checks the URDF against the model's geometry and mass table (1e-6 relative).
pub(crate) fn check_urdf(robot: &urdf_rs::Robot, model: &SpaceRobot) -> Result<(), SetupError> {
    let link = |name: &str| {
        robot.links.iter().find(|l| l.name == name).ok_or_else(|| {
            SetupError::urdf(format!(
                "URDF has no link `{name}` (needs {})",
                LINKS.join(", ")
            ))
        })
    };
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-6 * (1.0 + b.abs());
    let expect = [
        (LINKS[0], model.m0, model.i0, 0.0),
        (LINKS[1], model.m1, model.i1, 0.5 * model.l1),
        (LINKS[2], model.m2, model.i2, 0.5 * model.l2),
    ];
    for (name, m, izz, com_x) in expect {
        let l = link(name)?;
        let i = &l.inertial;
        if !close(i.mass.value, m) {
            return Err(SetupError::urdf_at(
                "link",
                name.to_string(),
                format!(
                    "URDF link `{name}` mass {} differs from the model's {m} kg",
                    i.mass.value
                ),
            ));
        }
        if !close(i.inertia.izz, izz) {
            return Err(SetupError::urdf_at(
                "link",
                name.to_string(),
                format!(
                    "URDF link `{name}` izz {} differs from the model's {izz} kg m²",
                    i.inertia.izz
                ),
            ));
        }
        let o = &i.origin;
        if !close(o.xyz[0], com_x) || o.xyz[1].abs() > 1e-9 || o.xyz[2].abs() > 1e-9 {
            return Err(SetupError::urdf_at(
                "link",
                name.to_string(),
                format!(
                    "URDF link `{name}` CoM xyz=\"{}\" must be at ({com_x}, 0, 0) for the planar model",
                    crate::engine::urdf_text::numbers(&o.xyz.0)
                ),
            ));
        }
        if o.rpy.0.iter().any(|a| a.abs() > 1e-9) {
            return Err(SetupError::urdf_at(
                "link",
                name.to_string(),
                format!("URDF link `{name}` inertial must not be rotated"),
            ));
        }
        let t = &i.inertia;
        if t.ixy.abs() > 1e-12 || t.ixz.abs() > 1e-12 || t.iyz.abs() > 1e-12 {
            return Err(SetupError::urdf_at(
                "link",
                name.to_string(),
                format!("URDF link `{name}` inertia must be diagonal"),
            ));
        }
    }
    let expect = [
        (JOINTS[0], LINKS[0], LINKS[1], 0.0),
        (JOINTS[1], LINKS[1], LINKS[2], model.l1),
    ];
    for (name, parent, child, x) in expect {
        let j = robot
            .joints
            .iter()
            .find(|j| j.name == name)
            .ok_or_else(|| {
                SetupError::urdf(format!(
                    "URDF has no joint `{name}` (needs {})",
                    JOINTS.join(", ")
                ))
            })?;
        if j.parent.link != parent || j.child.link != child {
            return Err(SetupError::urdf_at(
                "joint",
                name.to_string(),
                format!("URDF joint `{name}` must connect `{parent}` to `{child}`"),
            ));
        }
        if !matches!(
            j.joint_type,
            urdf_rs::JointType::Continuous | urdf_rs::JointType::Revolute
        ) {
            return Err(SetupError::urdf_at(
                "joint",
                name.to_string(),
                format!("URDF joint `{name}` must be continuous (or revolute)"),
            ));
        }
        let a = j.axis.xyz.0;
        if a[0].abs() > 1e-9 || a[1].abs() > 1e-9 || a[2] <= 0.0 {
            return Err(SetupError::urdf_at(
                "joint",
                name.to_string(),
                format!("URDF joint `{name}` axis must be +z (planar model)"),
            ));
        }
        let o = &j.origin;
        if !close(o.xyz[0], x) || o.xyz[1].abs() > 1e-9 || o.xyz[2].abs() > 1e-9 {
            return Err(SetupError::urdf_at(
                "joint",
                name.to_string(),
                format!("URDF joint `{name}` must sit at ({x}, 0, 0) in `{parent}`"),
            ));
        }
        if o.rpy.0.iter().any(|a| a.abs() > 1e-9) {
            return Err(SetupError::urdf_at(
                "joint",
                name.to_string(),
                format!("URDF joint `{name}` origin must not be rotated"),
            ));
        }
    }
    if robot.links.len() != 3 || robot.joints.len() != 2 {
        return Err(
            "URDF must have exactly the links vehicle, link1, link2 and joints joint1, joint2"
                .into(),
        );
    }
    Ok(())
}

/// The space robot in Rapier.
pub struct SpaceRobotPhysics {
    sim: SimWorld,
    bodies: [RigidBodyHandle; 3],
    /// Drives of joints θ1, θ2.
    drives: [Drive; 2],
    /// Unwrapped (θ0, θ1, θ2).
    q: [f64; 3],
    /// System CoM at the start.
    com0: [f64; 3],
    /// Body masses, kg.
    mass: [f64; 3],
    /// Body CoMs in the link frames, m.
    local_com: [[f64; 3]; 3],
    /// Body inertia tensors about their CoMs in body axes.
    inertia: [[[f64; 3]; 3]; 3],
    channels: [f64; CHANNELS.len()],
}

fn rot(angle: f64) -> crate::engine::rapier::math::Rotation {
    Rotation::from_rotation_z(r(angle))
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Rotate `v` by the quaternion `q` (f64).
fn rotate(q: &crate::engine::rapier::math::Rotation, v: [f64; 3]) -> [f64; 3] {
    let [x, y, z, w] = quat(q);
    let u = [x, y, z];
    let t = cross(u, v).map(|c| 2.0 * c);
    let c = cross(u, t);
    [
        v[0] + w * t[0] + c[0],
        v[1] + w * t[1] + c[1],
        v[2] + w * t[2] + c[2],
    ]
}

fn conj(q: &crate::engine::rapier::math::Rotation) -> crate::engine::rapier::math::Rotation {
    q.inverse()
}

impl SpaceRobotPhysics {
    /// Build the robot at `start` = (θ0, θ1, θ2), system CoM at the world origin.
    pub fn new(
        robot: &urdf_rs::Robot,
        urdf_dir: &Path,
        model: &SpaceRobot,
        start: &[f64],
        sim: &PhysicsSettings,
    ) -> Result<Self, SetupError> {
        check_urdf(robot, model)?;
        if sim.gravity.iter().any(|g| *g != 0.0) {
            return Err(SetupError::key("sim.gravity", "scenario key `sim.gravity` must be [0, 0, 0]: the space robot floats free (no ground, no gravity)".to_string()));
        }
        if start.len() != 3 {
            return Err(SetupError::other("start needs (θ0, θ1, θ2)".to_string()));
        }
        let poses = model.body_poses(&State::from_column_slice(start));
        // Vehicle frame = vehicle CoM (joint 1).
        let p0 = poses[0].position;
        let root =
            crate::engine::rapier::math::Pose::from_parts(vector(p0.x, p0.y, 0.0), rot(start[0]));
        let mut sw = SimWorld::new(
            robot,
            urdf_dir,
            &WorldOptions {
                settings: sim,
                root_pose: root,
                ground: false,
                keep_fixed: &[],
            },
        )?;
        let mut bodies = [RigidBodyHandle::invalid(); 3];
        for (b, name) in bodies.iter_mut().zip(LINKS) {
            *b = sw.require_link(name)?;
        }
        let mut joints = [ImpulseJointHandle::invalid(); 2];
        for (j, name) in joints.iter_mut().zip(JOINTS) {
            *j = sw.require_joint(name)?;
        }
        // Place the links at the start joint angles: link frames sit at the joints.
        let phi1 = start[0] + start[1];
        let joint1 = sw.world.bodies[bodies[0]].position().translation;
        let frame1 = crate::engine::rapier::math::Pose::from_parts(joint1, rot(phi1));
        let l1 = model.l1;
        let joint2 = vector(p0.x + l1 * phi1.cos(), p0.y + l1 * phi1.sin(), 0.0);
        let frame2 = crate::engine::rapier::math::Pose::from_parts(joint2, rot(phi1 + start[2]));
        for (h, pose) in [(bodies[1], frame1), (bodies[2], frame2)] {
            if let Some(b) = sw.world.bodies.get_mut(h) {
                b.set_position(pose, true);
                b.set_linvel(Vector::ZERO, true);
                b.set_angvel(Vector::ZERO, true);
            }
        }
        let drives = [
            sw.drive_for(joints[0], JointAxis::AngX, start[1]),
            sw.drive_for(joints[1], JointAxis::AngX, start[2]),
        ];
        // No self-contacts at all (non-adjacent pairs included).
        let groups = InteractionGroups::new(
            Group::GROUP_1,
            Group::ALL.difference(Group::GROUP_1),
            InteractionTestMode::And,
        );
        let colliders = sw.robot.colliders.clone();
        sw.set_collision_groups(&colliders, groups);
        // Mass properties as written in the URDF (checked against the model
        // above; Rapier computes its own copy only on the first step).
        let mut mass = [0.0; 3];
        let mut local_com = [[0.0; 3]; 3];
        let mut inertia = [[[0.0; 3]; 3]; 3];
        for (i, name) in LINKS.iter().enumerate() {
            let l = robot
                .links
                .iter()
                .find(|l| l.name == *name)
                .ok_or_else(|| SetupError::urdf(format!("URDF has no link `{name}`")))?;
            let t = &l.inertial.inertia;
            mass[i] = l.inertial.mass.value;
            local_com[i] = l.inertial.origin.xyz.0;
            inertia[i] = [
                [t.ixx, t.ixy, t.ixz],
                [t.ixy, t.iyy, t.iyz],
                [t.ixz, t.iyz, t.izz],
            ];
        }
        let mut me = SpaceRobotPhysics {
            sim: sw,
            bodies,
            drives,
            q: [start[0], start[1], start[2]],
            com0: [0.0; 3],
            mass,
            local_com,
            inertia,
            channels: [0.0; CHANNELS.len()],
        };
        // Rapier updates world CoMs on the first step; compute them from the poses now.
        me.com0 = me.system_com();
        me.apply(&Input::zeros(2));
        me.channels = me.measure();
        Ok(me)
    }

    /// World CoM of one body from its pose and local CoM.
    fn body_com(&self, i: usize) -> [f64; 3] {
        let p = self.sim.world.bodies[self.bodies[i]].position();
        let c = rotate(&p.rotation, self.local_com[i]);
        let t = arr(p.translation);
        [t[0] + c[0], t[1] + c[1], t[2] + c[2]]
    }

    /// System centre of mass.
    pub fn system_com(&self) -> [f64; 3] {
        let mut s = [0.0; 3];
        let mut mt = 0.0;
        for i in 0..3 {
            let (m, c) = (self.mass[i], self.body_com(i));
            for k in 0..3 {
                s[k] += m * c[k];
            }
            mt += m;
        }
        s.map(|v| v / mt)
    }

    /// Total linear momentum and angular momentum about the system CoM.
    pub fn momentum(&self) -> ([f64; 3], [f64; 3]) {
        let com = self.system_com();
        let (mut p, mut l) = ([0.0; 3], [0.0; 3]);
        for (i, h) in self.bodies.iter().enumerate() {
            let b = &self.sim.world.bodies[*h];
            let m = self.mass[i];
            let v = arr(b.linvel());
            let w = arr(b.angvel());
            let c = self.body_com(i);
            let r = [c[0] - com[0], c[1] - com[1], c[2] - com[2]];
            let rv = cross(r, v);
            // I_world ω = R I R^T ω.
            let q = b.rotation();
            let wl = rotate(&conj(q), w);
            let iw: [f64; 3] =
                std::array::from_fn(|r| (0..3).map(|c| self.inertia[i][r][c] * wl[c]).sum());
            let iw = rotate(q, iw);
            for k in 0..3 {
                p[k] += m * v[k];
                l[k] += m * rv[k] + iw[k];
            }
        }
        (p, l)
    }

    fn measure(&self) -> [f64; CHANNELS.len()] {
        let (p, l) = self.momentum();
        let com = self.system_com();
        let drift = (0..3)
            .map(|k| (com[k] - self.com0[k]).powi(2))
            .sum::<f64>()
            .sqrt();
        let mut out_of_plane: f64 = 0.0;
        for (i, h) in self.bodies.iter().enumerate() {
            let b = &self.sim.world.bodies[*h];
            let z = self.body_com(i)[2].abs();
            let axis = rotate(b.rotation(), [0.0, 0.0, 1.0]);
            let tilt = axis[0].hypot(axis[1]).atan2(axis[2]);
            out_of_plane = out_of_plane.max(z).max(tilt);
        }
        let contacts = self
            .sim
            .world
            .narrow_phase
            .contact_pairs()
            .filter(|c| c.has_any_active_contact())
            .count();
        [
            l[2],
            l[0].hypot(l[1]),
            (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt(),
            drift,
            out_of_plane,
            contacts as f64,
        ]
    }
}

impl PhysicsSystem for SpaceRobotPhysics {
    fn state(&self) -> State {
        State::from_vec(self.q.to_vec())
    }

    fn apply(&mut self, u: &Input) {
        for (d, rate) in self.drives.iter_mut().zip(u.iter()) {
            self.sim.drive(d, *rate);
        }
    }

    fn step(&mut self) {
        self.sim.world.step();
        let b = &self.sim.world.bodies;
        let r = self.bodies.map(|h| *b[h].rotation());
        let read = [
            angle_z(&r[0]),
            angle_z(&(conj(&r[0]) * r[1])),
            angle_z(&(conj(&r[1]) * r[2])),
        ];
        for (q, v) in self.q.iter_mut().zip(read) {
            *q = angles::unwrap(*q, v);
        }
        self.channels = self.measure();
    }

    fn link_poses(&self) -> Vec<Pose> {
        self.sim.link_poses()
    }

    fn channel_names(&self) -> Vec<String> {
        CHANNELS.map(String::from).to_vec()
    }

    fn channels(&self) -> Vec<f64> {
        self.channels.to_vec()
    }
}
