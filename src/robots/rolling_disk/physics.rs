//! Rigid-body rolling disk: `models/rolling_disk.urdf` on a ground plane.
//!
//! The wheel joint's servo drive realises θ'. A joint between the world and
//! the yoke locks roll and pitch (the balance controller the paper takes for
//! granted) and drives the yaw with −α' (α is measured from +y towards +x,
//! yaw from +x towards +y: yaw = π/2 − α). Translation is free:
//! the disk moves only through wheel–ground friction.

use crate::engine::rapier::prelude::*;
use crate::engine::real::{f, r, vector};
use crate::engine::required::Required;
use crate::engine::urdf::{Drive, SimWorld};
use crate::engine::{angles, PhysicsSettings, PhysicsSystem};
use crate::error::SetupError;
use crate::model::{Input, State};
use crate::record::Pose;
use std::f64::consts::FRAC_PI_2;
use std::path::Path;

/// Names the URDF must use.
pub const YOKE: &str = "yoke";
/// Wheel link name.
pub const WHEEL: &str = "wheel";
/// Wheel joint name.
pub const WHEEL_JOINT: &str = "wheel_joint";

/// The links and joints the disk looks up in its URDF.
pub const REQUIRED: [Required; 3] = [
    Required::link(
        YOKE,
        "the body carrying the axle (the root link): held upright, yaw driven",
    ),
    Required::link(
        WHEEL,
        "the disk, with a sphere or cylinder collision of radius `radius`",
    ),
    Required::joint(WHEEL_JOINT, "yoke to wheel, about the axle: driven at θ'"),
];

/// The disk in Rapier.
pub struct DiskPhysics {
    sim: SimWorld,
    yoke: RigidBodyHandle,
    wheel: RigidBodyHandle,
    /// Wheel joint drive (θ') and the balance joint's yaw drive (−α').
    wheel_drive: Drive,
    yaw_drive: Drive,
    r: f64,
    /// θ at the start (the URDF wheel joint starts at 0).
    theta0: f64,
    /// Unwrapped wheel joint angle and yoke yaw.
    joint: f64,
    yaw: f64,
}

/// Wheel angle about the axle (yoke +y) relative to the yoke, in (−π, π].
fn wheel_angle(
    yoke: &crate::engine::rapier::math::Rotation,
    wheel: &crate::engine::rapier::math::Rotation,
) -> f64 {
    angles::about_axis(&(yoke.inverse() * *wheel), 1)
}

impl DiskPhysics {
    /// Build the disk at `start` = (x, y, θ, α). Errors name what the URDF lacks.
    pub fn new(
        robot: &urdf_rs::Robot,
        urdf_dir: &Path,
        radius: f64,
        start: &[f64],
        sim: &PhysicsSettings,
    ) -> Result<Self, SetupError> {
        crate::engine::urdf::require_radius(robot, WHEEL, "the wheel", radius)?;
        // A worn wheel (`wheel_radius_scale`): the model keeps `radius`.
        let s = sim.wheel_radius_scale;
        let worn = crate::engine::perturb::world::worn_wheels(robot, &[WHEEL], s);
        let robot: &urdf_rs::Robot = &worn;
        let radius = radius * s;
        let yaw0 = FRAC_PI_2 - start[3];
        let root = crate::engine::rapier::math::Pose::from_parts(
            vector(start[0], start[1], radius),
            Rotation::from_rotation_z(r(yaw0)),
        );
        let mut sw = SimWorld::on_ground(robot, urdf_dir, sim, root)?;
        let yoke = sw.require_link(YOKE)?;
        let wheel = sw.require_link(WHEEL)?;
        let wheel_joint = sw.require_joint(WHEEL_JOINT)?;
        // Balance controller: roll and pitch locked, yaw servoed, translation free.
        let balance = GenericJointBuilder::new(JointAxesMask::ANG_X | JointAxesMask::ANG_Y)
            .local_frame1(crate::engine::rapier::math::Pose::IDENTITY)
            .local_frame2(crate::engine::rapier::math::Pose::IDENTITY)
            .build();
        let balance = sw
            .world
            .impulse_joints
            .insert(sw.ground, yoke, balance, true);
        let wheel_drive = sw.drive_for(wheel_joint, JointAxis::AngX, 0.0);
        let yaw_drive = sw.drive_for(balance, JointAxis::AngZ, yaw0);
        let mut me = DiskPhysics {
            sim: sw,
            yoke,
            wheel,
            wheel_drive,
            yaw_drive,
            r: radius,
            theta0: start[2],
            joint: 0.0,
            yaw: yaw0,
        };
        me.apply(&Input::zeros(2));
        Ok(me)
    }

    /// Velocity of the wheel's lowest point, split along the heading and the axle, m/s.
    fn contact_slip(&self) -> (f64, f64) {
        let b = &self.sim.world.bodies[self.wheel];
        let v = b.linvel();
        let w = b.angvel();
        let contact = v + w.cross(vector(0.0, 0.0, -self.r));
        let heading = vector(self.yaw.cos(), self.yaw.sin(), 0.0);
        let axle = vector(-self.yaw.sin(), self.yaw.cos(), 0.0);
        (f(contact.dot(heading)), f(contact.dot(axle)))
    }
}

impl PhysicsSystem for DiskPhysics {
    fn state(&self) -> State {
        let c = self.sim.world.bodies[self.wheel].translation();
        State::from_vec(vec![
            f(c.x),
            f(c.y),
            self.theta0 + self.joint,
            FRAC_PI_2 - self.yaw,
        ])
    }

    fn apply(&mut self, u: &Input) {
        self.sim.drive(&mut self.wheel_drive, u[0]);
        self.sim.drive(&mut self.yaw_drive, -u[1]);
    }

    fn step(&mut self) {
        self.sim.step();
        let bodies = &self.sim.world.bodies;
        let (yq, wq) = (bodies[self.yoke].rotation(), bodies[self.wheel].rotation());
        self.yaw = angles::unwrap(self.yaw, angles::yaw(yq));
        self.joint = angles::unwrap(self.joint, wheel_angle(yq, wq));
    }

    fn link_poses(&self) -> Vec<Pose> {
        self.sim.link_poses()
    }

    fn sim_world(&mut self) -> Option<&mut SimWorld> {
        Some(&mut self.sim)
    }

    fn channel_names(&self) -> Vec<String> {
        ["slip_longitudinal", "slip_lateral", "wheel_height"]
            .map(String::from)
            .to_vec()
    }

    fn channels(&self) -> Vec<f64> {
        let (lon, lat) = self.contact_slip();
        let z = f(self.sim.world.bodies[self.wheel].translation().z) - self.r;
        vec![lon, lat, z]
    }
}
