//! Rigid-body overconstrained rover: `models/rover.urdf` on a ground plane.
//!
//! Five wheels touch the ground: the steered, driven front wheel and the two
//! passive rear axles (middle and back). Nothing enforces the kinematic
//! constraints: every wheel moves the body only through contact friction, so
//! which rear axle holds and which one slips (σ of the seed's multiple-model
//! system) is decided by the contact solver.
//!
//! Actuation: servo drives on `front_wheel_joint` at u1 / ρ (u1 is the
//! front wheel's ground speed) and on `steer_joint` at u2 (the URDF joint
//! limit bounds ψ and the drive's commanded angle). Read-back: (x, y, θ) of the chassis
//! frame, whose origin is the middle-axle centre (the model's reference
//! point), and ψ the steering joint angle.
//!
//! Channels: per wheel the contact-point velocity along and across the wheel
//! (`slip_<wheel>_lon`, `slip_<wheel>_lat`, m/s), and the envelope check of
//! the measured (x', y', θ') against the multiple-model set for the last
//! applied input (`envelope_distance`, `sigma_estimate`: 0 = model a, 1 =
//! model b, NaN when the models coincide, i.e. ψ = 0 or u1 = 0).

use crate::engine::rapier::prelude::*;
use crate::engine::real::{f, r as real, vector};
use crate::engine::required::Required;
use crate::engine::urdf::{Drive, SimWorld};
use crate::engine::{angles, PhysicsSettings, PhysicsSystem};
use crate::error::SetupError;
use crate::model::{Input, State};
use crate::record::Pose;
use crate::robots::rover::kinematics::{envelope, RoverGeometry};

use std::path::Path;

/// Chassis link name (frame origin = middle-axle centre).
pub const CHASSIS: &str = "chassis";
/// Steering joint name (revolute about chassis z).
pub const STEER_JOINT: &str = "steer_joint";
/// Driven front wheel joint name.
pub const FRONT_JOINT: &str = "front_wheel_joint";
/// Wheel links, in channel order; the first is the steered front wheel.
pub const WHEELS: [&str; 5] = [
    "front_wheel",
    "middle_left_wheel",
    "middle_right_wheel",
    "back_left_wheel",
    "back_right_wheel",
];
/// Steering link name (between `steer_joint` and the front wheel).
pub const STEERING: &str = "steering";
/// The back axle's left wheel joint (its x offset is the back axle's).
pub const BACK_JOINT: &str = "back_left_wheel_joint";

/// The links and joints the rover looks up in its URDF.
pub const REQUIRED: [Required; 10] = [
    Required::link(
        CHASSIS,
        "the body (root link); its origin is the middle-axle centre, +x forward",
    ),
    Required::link(STEERING, "turns about `steer_joint`, carries the front wheel"),
    Required::link(
        WHEELS[0],
        "steered, driven front wheel, with a sphere or cylinder collision of `geometry.wheel_radius`",
    ),
    Required::link(WHEELS[1], "passive middle-axle wheel, left"),
    Required::link(WHEELS[2], "passive middle-axle wheel, right"),
    Required::link(WHEELS[3], "passive back-axle wheel, left"),
    Required::link(WHEELS[4], "passive back-axle wheel, right"),
    Required::joint(
        STEER_JOINT,
        "chassis to steering, revolute about z at x = `geometry.l`; its limit bounds ψ",
    ),
    Required::joint(FRONT_JOINT, "steering to front wheel: driven at u1 / radius"),
    Required::joint(BACK_JOINT, "its x offset is the back axle's, −`geometry.r`"),
];

/// x offset of a joint's origin in its parent frame.
fn joint_x(robot: &urdf_rs::Robot, joint: &str) -> Option<f64> {
    robot
        .joints
        .iter()
        .find(|j| j.name == joint)
        .map(|j| j.origin.xyz[0])
}

/// The rover in Rapier.
pub struct RoverPhysics {
    sim: SimWorld,
    geom: RoverGeometry,
    chassis: RigidBodyHandle,
    steering: RigidBodyHandle,
    wheels: Vec<RigidBodyHandle>,
    /// Drives of the steering joint (u2) and the front wheel (u1 / ρ).
    steer: Drive,
    front: Drive,
    /// Radius of the simulated wheels (the model's unless worn), m.
    rim: f64,
    /// Unwrapped heading.
    theta: f64,
    /// Last applied input (the envelope check compares against it).
    last_u: Input,
    /// Model coordinates (x, y, θ, ψ) read back after the last step (the replay
    /// and the channels both read them every step).
    q: State,
}

impl RoverPhysics {
    /// Build the rover at `start` = (x, y, θ, ψ). The URDF must match `geom`.
    pub fn new(
        robot: &urdf_rs::Robot,
        urdf_dir: &Path,
        geom: RoverGeometry,
        start: &[f64],
        sim: &PhysicsSettings,
    ) -> Result<Self, SetupError> {
        let rho = crate::engine::urdf::round_collision(robot, WHEELS[0], "the front wheel")?;
        if (rho - geom.wheel_radius).abs() > 1e-6 {
            return Err(SetupError::key(
                "model.geometry",
                format!(
                    "URDF front wheel radius {rho} m differs from model.geometry.wheel_radius {} m",
                    geom.wheel_radius
                ),
            ));
        }
        let l = joint_x(robot, STEER_JOINT)
            .ok_or_else(|| SetupError::urdf(format!("URDF has no joint `{STEER_JOINT}`")))?;
        let r = joint_x(robot, BACK_JOINT)
            .ok_or_else(|| SetupError::urdf(format!("URDF has no joint `{BACK_JOINT}`")))?;
        if (l - geom.l).abs() > 1e-6 || (-r - geom.r).abs() > 1e-6 {
            return Err(SetupError::key("model.geometry", format!(
                "URDF axle positions (l = {l} m, r = {} m) differ from model.geometry (l = {}, r = {})",
                -r, geom.l, geom.r
            )));
        }
        // Worn wheels (`wheel_radius_scale`): all five, the chassis lower by
        // as much; the drive still converts u1 with the model's radius.
        let s = sim.wheel_radius_scale;
        let worn = crate::engine::perturb::world::worn_wheels(robot, &WHEELS, s);
        let robot: &urdf_rs::Robot = &worn;
        let rim = rho * s;
        let root = crate::engine::rapier::math::Pose::from_parts(
            vector(start[0], start[1], rim),
            Rotation::from_rotation_z(real(start[2])),
        );
        let mut sw = SimWorld::on_ground(robot, urdf_dir, sim, root)?;
        let chassis = sw.require_link(CHASSIS)?;
        let steering = sw.require_link(STEERING)?;
        let wheels = WHEELS
            .iter()
            .map(|w| sw.require_link(w))
            .collect::<Result<Vec<_>, _>>()?;
        let steer_joint = sw.require_joint(STEER_JOINT)?;
        let front_joint = sw.require_joint(FRONT_JOINT)?;
        // Initial steering angle: rotate the steering link and the front wheel about the
        // steering axis (the joint starts at ψ = 0 in the URDF pose).
        if start[3] != 0.0 {
            let axis_pt = sw.world.bodies[chassis]
                .position()
                .transform_point(vector(l, 0.0, 0.0));
            let rot = Rotation::from_rotation_z(real(start[3]));
            for h in [steering, wheels[0]] {
                let b = &mut sw.world.bodies[h];
                let p = *b.position();
                let t = axis_pt + rot * (p.translation - axis_pt);
                b.set_position(
                    crate::engine::rapier::math::Pose::from_parts(t, rot * p.rotation),
                    true,
                );
            }
        }
        // No CCD: the rover is slow (wheel rims < 1 m/s, 2 ms steps) and meets only the
        // ground half-space, so Rapier's CCD never acts on it, yet with CCD on every step
        // still sweeps each body's solved motion (pose errors, fast-body test): ~5 % of the
        // step's instructions. Off, every rover scenario's metrics are the same to the last bit.
        sw.world.integration_parameters.max_ccd_substeps = 0;
        let steer = sw.drive_for(steer_joint, JointAxis::AngX, start[3]);
        let front = sw.drive_for(front_joint, JointAxis::AngX, 0.0);
        let mut me = RoverPhysics {
            sim: sw,
            geom,
            chassis,
            steering,
            wheels,
            steer,
            front,
            rim,
            theta: start[2],
            last_u: Input::zeros(2),
            q: State::zeros(4),
        };
        me.read_back();
        me.apply(&Input::zeros(2));
        Ok(me)
    }

    /// Update the model coordinates from the bodies.
    fn read_back(&mut self) {
        let c = self.sim.world.bodies[self.chassis].translation();
        let (x, y, psi) = (f(c.x), f(c.y), self.steer_angle());
        self.q.copy_from_slice(&[x, y, self.theta, psi]);
    }

    fn steer_angle(&self) -> f64 {
        let b = &self.sim.world.bodies;
        let rel = b[self.chassis].rotation().inverse() * *b[self.steering].rotation();
        angles::yaw(&rel)
    }

    /// Contact-point velocity of wheel `i` along and across its rolling direction, m/s.
    pub fn wheel_slip(&self, i: usize) -> (f64, f64) {
        let b = &self.sim.world.bodies[self.wheels[i]];
        let contact = b.translation() - vector(0.0, 0.0, self.rim);
        let v = b.velocity_at_point(contact);
        // The wheel's axle is its local y axis; rolling direction = axle × z.
        let axle = *b.rotation() * Vector::Y;
        let fwd = Vector::new(axle.y, -axle.x, 0.0).normalize_or_zero();
        let side = Vector::new(-fwd.y, fwd.x, 0.0);
        (f(v.dot(fwd)), f(v.dot(side)))
    }

    /// Measured (x', y', θ') of the middle-axle point.
    pub fn body_velocity(&self) -> nalgebra::Vector3<f64> {
        let b = &self.sim.world.bodies[self.chassis];
        let v = b.velocity_at_point(b.translation());
        nalgebra::Vector3::new(f(v.x), f(v.y), f(b.angvel().z))
    }
}

impl PhysicsSystem for RoverPhysics {
    fn state(&self) -> State {
        self.q.clone()
    }

    fn apply(&mut self, u: &Input) {
        self.sim
            .drive(&mut self.front, u[0] / self.geom.wheel_radius);
        self.sim.drive(&mut self.steer, u[1]);
        if self.last_u.len() == u.len() {
            self.last_u.copy_from(u);
        } else {
            self.last_u = u.clone();
        }
    }

    fn step(&mut self) {
        self.sim.step();
        let yaw = angles::yaw(self.sim.world.bodies[self.chassis].rotation());
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
        let mut out = Vec::new();
        for w in WHEELS {
            let w = w.trim_end_matches("_wheel");
            out.push(format!("slip_{w}_lon"));
            out.push(format!("slip_{w}_lat"));
        }
        out.push("envelope_distance".into());
        out.push("sigma_estimate".into());
        out
    }

    fn channels(&self) -> Vec<f64> {
        let mut out = Vec::with_capacity(12);
        for i in 0..WHEELS.len() {
            let (lon, lat) = self.wheel_slip(i);
            out.push(lon);
            out.push(lat);
        }
        let fit = envelope(&self.geom, &self.q, &self.last_u, &self.body_velocity());
        out.push(fit.distance);
        out.push(fit.sigma.unwrap_or(f64::NAN));
        out
    }
}
