//! Rigid-body rolling sphere: `models/sphere.urdf` (one link, `ball`) on a ground plane.
//!
//! The ball is a free rigid body: a hollow shell with an internal drive, lumped into one
//! inertia. The drive is idealised as a pure torque on the shell that servoes the ball's
//! world-frame angular velocity to the command (ω_x, ω_y, 0): three angular velocity motors
//! (gain `sim.motor_gain`, each capped at `sim.motor_max_torque`) about the world x, y, z
//! axes, solved by Rapier together with the contact. Nothing constrains the translation: the
//! centre moves only through ball–ground friction, so slip (and spin, if the servo saturates)
//! are real. State read back each step: centre (x, y) and the body orientation as a unit
//! quaternion, kept sign-continuous.
//!
//! Channels: `slip_speed` (horizontal speed of the contact point, m/s), `spin_rate` (ω_z,
//! rad/s), `orientation_error_deg` (geodesic angle between the simulated orientation and
//! the orientation the commanded ω produces when integrated exactly, i.e. the ideal
//! orientation up to O(dt²)), `height` (centre height minus the radius, m).

use crate::engine::rapier::prelude::*;
use crate::engine::real::{f, quat, r, rotation, vector};
use crate::engine::required::Required;
use crate::engine::urdf::SimWorld;
use crate::engine::{PhysicsSettings, PhysicsSystem};
use crate::error::SetupError;
use crate::model::{Input, State};
use crate::record::Pose;
use crate::robots::rolling_sphere::kinematics::geodesic_angle;
use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use std::path::Path;

/// The link the URDF must provide.
pub const BALL: &str = "ball";

/// The links the sphere looks up in its URDF.
pub const REQUIRED: [Required; 1] = [Required::link(
    BALL,
    "the ball, with a sphere collision of radius `radius`",
)];

/// The sphere in Rapier.
pub struct SpherePhysics {
    sim: SimWorld,
    ball: RigidBodyHandle,
    drive: ImpulseJointHandle,
    a: f64,
    gain: f64,
    dt: f64,
    /// Sign-continuous orientation read back after the last step (w, x, y, z).
    q: [f64; 4],
    /// Orientation from integrating the commanded ω exactly.
    q_cmd: UnitQuaternion<f64>,
    /// Last command.
    u: [f64; 2],
}

impl SpherePhysics {
    /// Build the ball at `start` = (x, y, qw, qx, qy, qz), resting on the plane.
    pub fn new(
        robot: &urdf_rs::Robot,
        urdf_dir: &Path,
        radius: f64,
        start: &[f64],
        sim: &PhysicsSettings,
    ) -> Result<Self, SetupError> {
        crate::engine::urdf::require_radius(robot, BALL, "the ball", radius)?;
        // A ball of another radius than the model's (`wheel_radius_scale`).
        let s = sim.wheel_radius_scale;
        let worn = crate::engine::perturb::world::worn_wheels(robot, &[BALL], s);
        let robot: &urdf_rs::Robot = &worn;
        let radius = radius * s;
        if start.len() != 6 {
            return Err(SetupError::other(format!(
                "sphere physics needs a 6-value state, got {}",
                start.len()
            )));
        }
        let q0 = UnitQuaternion::from_quaternion(Quaternion::new(
            start[2], start[3], start[4], start[5],
        ));
        let root = crate::engine::rapier::math::Pose::from_parts(
            vector(start[0], start[1], radius),
            rotation(q0.i, q0.j, q0.k, q0.w),
        );
        let mut sw = SimWorld::on_ground(robot, urdf_dir, sim, root)?;
        let ball = sw.require_link(BALL)?;
        // The drive: no locked axes, angular velocity motors about the world axes.
        let mut b = GenericJointBuilder::new(JointAxesMask::empty())
            .local_frame1(crate::engine::rapier::math::Pose::IDENTITY)
            .local_frame2(crate::engine::rapier::math::Pose::IDENTITY);
        for axis in [JointAxis::AngX, JointAxis::AngY, JointAxis::AngZ] {
            b = b
                .motor_velocity(axis, 0.0, r(sim.motor_gain))
                .motor_max_force(axis, r(sim.motor_max_torque * sim.torque_scale));
        }
        let drive = sw
            .world
            .impulse_joints
            .insert(sw.ground, ball, b.build(), true);
        let mut me = SpherePhysics {
            sim: sw,
            ball,
            drive,
            a: radius,
            gain: sim.motor_gain,
            dt: sim.dt,
            q: [q0.w, q0.i, q0.j, q0.k],
            q_cmd: q0,
            u: [0.0, 0.0],
        };
        me.apply(&Input::zeros(2));
        Ok(me)
    }

    fn quat(&self) -> UnitQuaternion<f64> {
        let [w, x, y, z] = self.q;
        UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z))
    }

    /// Horizontal velocity of the ball's lowest point, m/s.
    fn contact_slip(&self) -> f64 {
        let b = &self.sim.world.bodies[self.ball];
        let v = b.linvel() + b.angvel().cross(vector(0.0, 0.0, -self.a));
        f(v.x).hypot(f(v.y))
    }
}

impl PhysicsSystem for SpherePhysics {
    fn state(&self) -> State {
        let c = self.sim.world.bodies[self.ball].translation();
        let [w, x, y, z] = self.q;
        State::from_vec(vec![f(c.x), f(c.y), w, x, y, z])
    }

    fn apply(&mut self, u: &Input) {
        self.u = [u[0], u[1]];
        let gain = r(self.gain);
        if let Some(j) = self.sim.world.impulse_joints.get_mut(self.drive, false) {
            j.data
                .set_motor_velocity(JointAxis::AngX, r(u[0]), gain)
                .set_motor_velocity(JointAxis::AngY, r(u[1]), gain)
                .set_motor_velocity(JointAxis::AngZ, 0.0, gain);
        }
    }

    fn step(&mut self) {
        self.sim.step();
        let [x, y, z, w] = quat(self.sim.world.bodies[self.ball].rotation());
        let mut q = [w, x, y, z];
        let dot: f64 = q.iter().zip(&self.q).map(|(a, b)| a * b).sum();
        if dot < 0.0 {
            q = q.map(|v| -v);
        }
        let n = q.iter().map(|v| v * v).sum::<f64>().sqrt();
        self.q = q.map(|v| v / n);
        let w = Vector3::new(self.u[0], self.u[1], 0.0) * self.dt;
        self.q_cmd = UnitQuaternion::from_scaled_axis(w) * self.q_cmd;
    }

    fn link_poses(&self) -> Vec<Pose> {
        self.sim.link_poses()
    }

    fn sim_world(&mut self) -> Option<&mut SimWorld> {
        Some(&mut self.sim)
    }

    fn channel_names(&self) -> Vec<String> {
        ["slip_speed", "spin_rate", "orientation_error_deg", "height"]
            .map(String::from)
            .to_vec()
    }

    fn channels(&self) -> Vec<f64> {
        let b = &self.sim.world.bodies[self.ball];
        vec![
            self.contact_slip(),
            f(b.angvel().z),
            geodesic_angle(&self.q_cmd, &self.quat()).to_degrees(),
            f(b.translation().z) - self.a,
        ]
    }
}
