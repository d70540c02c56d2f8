//! Rigid-body rolling disk: `models/rolling_disk.urdf` on a ground plane.
//!
//! The wheel joint's velocity motor realises θ'. A joint between the world
//! and the yoke locks roll and pitch (the balance controller the paper takes
//! for granted) and servoes the yaw rate to −α' (α is measured from +y
//! towards +x, yaw from +x towards +y: yaw = π/2 − α). Translation is free:
//! the disk moves only through wheel–ground friction.

use super::urdf::SimWorld;
use super::{angles, PhysicsSystem};
use crate::model::{Input, State};
use crate::record::Pose;
use crate::scenario::SimConfig;
use rapier3d::prelude::*;
use std::f64::consts::FRAC_PI_2;
use std::path::Path;

/// Names the URDF must use.
pub const YOKE: &str = "yoke";
/// Wheel link name.
pub const WHEEL: &str = "wheel";
/// Wheel joint name.
pub const WHEEL_JOINT: &str = "wheel_joint";

/// The disk in Rapier.
pub struct DiskPhysics {
    sim: SimWorld,
    yoke: RigidBodyHandle,
    wheel: RigidBodyHandle,
    wheel_joint: ImpulseJointHandle,
    balance: ImpulseJointHandle,
    r: f64,
    gain: f64,
    max_torque: f64,
    /// θ at the start (the URDF wheel joint starts at 0).
    theta0: f64,
    /// Unwrapped wheel joint angle and yoke yaw.
    joint: f64,
    yaw: f64,
}

/// Wheel angle about the axle (yoke +y) relative to the yoke, in (−π, π].
fn wheel_angle(yoke: &rapier3d::math::Rotation, wheel: &rapier3d::math::Rotation) -> f64 {
    angles::about_axis(&(yoke.inverse() * *wheel), 1)
}

impl DiskPhysics {
    /// Build the disk at `start` = (x, y, θ, α). Errors name what the URDF lacks.
    pub fn new(
        robot: &urdf_rs::Robot,
        urdf_dir: &Path,
        radius: f64,
        start: &[f64],
        sim: &SimConfig,
    ) -> Result<Self, String> {
        super::urdf::require_radius(robot, WHEEL, "the wheel", radius)?;
        let yaw0 = FRAC_PI_2 - start[3];
        let root = rapier3d::math::Pose::from_parts(
            Vector::new(start[0] as Real, start[1] as Real, radius as Real),
            Rotation::from_rotation_z(yaw0 as Real),
        );
        let mut sw = SimWorld::on_ground(robot, urdf_dir, sim, root);
        let yoke = sw.require_link(YOKE)?;
        let wheel = sw.require_link(WHEEL)?;
        let wheel_joint = sw.require_joint(WHEEL_JOINT)?;
        // Balance controller: roll and pitch locked, yaw servoed, translation free.
        let balance = GenericJointBuilder::new(JointAxesMask::ANG_X | JointAxesMask::ANG_Y)
            .local_frame1(rapier3d::math::Pose::IDENTITY)
            .local_frame2(rapier3d::math::Pose::IDENTITY)
            .motor_velocity(JointAxis::AngZ, 0.0, sim.motor_gain as Real)
            .motor_max_force(JointAxis::AngZ, sim.motor_max_torque as Real)
            .build();
        let balance = sw
            .world
            .impulse_joints
            .insert(sw.ground, yoke, balance, true);
        let mut me = DiskPhysics {
            sim: sw,
            yoke,
            wheel,
            wheel_joint,
            balance,
            r: radius,
            gain: sim.motor_gain,
            max_torque: sim.motor_max_torque,
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
        let contact = v + w.cross(Vector::new(0.0, 0.0, -self.r as Real));
        let heading = Vector::new(self.yaw.cos() as Real, self.yaw.sin() as Real, 0.0);
        let axle = Vector::new(-self.yaw.sin() as Real, self.yaw.cos() as Real, 0.0);
        (contact.dot(heading) as f64, contact.dot(axle) as f64)
    }
}

impl PhysicsSystem for DiskPhysics {
    fn state(&self) -> State {
        let c = self.sim.world.bodies[self.wheel].translation();
        State::from_vec(vec![
            c.x as f64,
            c.y as f64,
            self.theta0 + self.joint,
            FRAC_PI_2 - self.yaw,
        ])
    }

    fn apply(&mut self, u: &Input) {
        let (gain, tmax) = (self.gain, self.max_torque);
        self.sim.drive_joint(self.wheel_joint, u[0], gain, tmax);
        if let Some(j) = self.sim.world.impulse_joints.get_mut(self.balance, false) {
            j.data
                .set_motor_velocity(JointAxis::AngZ, -u[1] as Real, gain as Real);
        }
    }

    fn step(&mut self) {
        self.sim.world.step();
        let bodies = &self.sim.world.bodies;
        let (yq, wq) = (bodies[self.yoke].rotation(), bodies[self.wheel].rotation());
        self.yaw = angles::unwrap(self.yaw, angles::yaw(yq));
        self.joint = angles::unwrap(self.joint, wheel_angle(yq, wq));
    }

    fn link_poses(&self) -> Vec<Pose> {
        self.sim.link_poses()
    }

    fn channel_names(&self) -> Vec<String> {
        ["slip_longitudinal", "slip_lateral", "wheel_height"]
            .map(String::from)
            .to_vec()
    }

    fn channels(&self) -> Vec<f64> {
        let (lon, lat) = self.contact_slip();
        let z = self.sim.world.bodies[self.wheel].translation().z as f64 - self.r;
        vec![lon, lat, z]
    }
}
