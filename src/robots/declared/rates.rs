//! Velocities a declared model reads back (`LINK.vx|vy|vz|wx|wy|wz`,
//! `JOINT.velocity`), from Rapier's body velocities.

use crate::engine::rapier::math::Pose as RPose;
use crate::engine::rapier::prelude::*;
use crate::engine::real::f;
use crate::engine::world::SimWorld;

/// Component `k` (vx, vy, vz, wx, wy, wz) of the velocity of the link frame
/// at `off` on body `b`, in that frame's own axes: the linear velocity of
/// its origin (m/s) or the angular velocity (rad/s), as a ROS odometry
/// twist gives them.
pub fn link_velocity(sim: &SimWorld, b: RigidBodyHandle, off: &RPose, k: usize) -> f64 {
    let Some(body) = sim.world.bodies.get(b) else {
        return f64::NAN;
    };
    let frame = *body.position() * *off;
    let world = if k < 3 {
        body.velocity_at_point(frame.translation)
    } else {
        body.angvel()
    };
    let local = frame.rotation.inverse() * world;
    f(local[k % 3])
}

/// The rate of a one-axis joint (rad/s, or m/s for a prismatic joint):
/// body 2's motion relative to body 1 along the joint's axis (the x axis of
/// its frame on body 1), the convention of [`SimWorld::joint_position`].
pub fn joint_velocity(sim: &SimWorld, h: ImpulseJointHandle) -> Option<f64> {
    let j = sim.world.impulse_joints.get(h)?;
    let (b1, b2) = (
        sim.world.bodies.get(j.body1())?,
        sim.world.bodies.get(j.body2())?,
    );
    let f1 = *b1.position() * j.data.local_frame1;
    let axis = f1.rotation * Vector::new(1.0, 0.0, 0.0);
    Some(f(if j.data.locked_axes.contains(JointAxesMask::LIN_X) {
        (b2.angvel() - b1.angvel()).dot(axis)
    } else {
        let f2 = *b2.position() * j.data.local_frame2;
        let p = f2.translation;
        (b2.velocity_at_point(p) - b1.velocity_at_point(p)).dot(axis)
    }))
}
