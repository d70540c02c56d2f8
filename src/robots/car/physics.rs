//! Rigid-body car-like robot: four wheels, Ackermann-steered front wheels
//! and driven rear wheels (`models/car.urdf`, or a user's URDF with the
//! declared names) on a ground plane.
//!
//! The kinematic bicycle has one steered wheel on the centre line. The car
//! steers each front wheel to its own Ackermann angle
//! ([`crate::robots::car::kinematics::ackermann`]: the inner wheel more), so that all
//! four axles point at one turning centre, and drives each rear wheel at its
//! own speed ([`crate::robots::car::kinematics::rear_speeds`]: the inner wheel
//! slower, an electronic differential). With both exact and no slip, the
//! rear-axle midpoint follows the bicycle. What the physical car adds:
//! wheels that slip (along and across, measured per wheel); steering
//! servos with inertia and a torque limit, which lag a fast steering
//! command; drive torque limits; steering that stops at the joints' limits.
//! The front wheels roll freely (no drive, no bearing friction).
//!
//! Geometry from the URDF (see [`crate::robots::wheeled`]): wheel radii, the
//! wheelbase (front steering pivots to rear axle, checked against
//! `model.wheelbase`), both tracks, the reference point (rear-axle
//! midpoint). Each front wheel's centre must sit on its steering axis (no
//! scrub radius: a wheel steered in place turns about its contact point).
//!
//! Actuation: the bicycle angle φ commanded by integrating φ' (stopped at
//! ±`max_steer` like the model), or, steered by angle
//! ([`SteeringInput::Angle`]), the commanded angle itself within ±`max_steer`;
//! each steering joint servoed to its Ackermann angle of that φ (by angle:
//! the servo's commanded φ slews to the commanded angle as fast as the
//! joints' `<limit velocity>` allow, the faster wheel at its limit, then
//! holds it; without a velocity limit it jumps, and the knuckle gets there
//! as fast as the gains, its inertia and the joint's effort allow), each
//! rear wheel to its speed for the measured φ. Drive torques are capped at the joints' `<limit
//! effort>` (`[sim] motor_max_torque` when the URDF gives none).
//!
//! Read-back: (x, y) of the rear-axle midpoint, θ the body's yaw
//! (unwrapped), φ the bicycle angle of the measured wheel angles (the mean
//! of what each front wheel's angle implies); steered by angle the state is
//! (x, y, θ) and φ is read only for the differential and the channels.
//!
//! Channels: per wheel the contact-point velocity along and across it
//! (`slip_<wheel>_lon`, `slip_<wheel>_lat`, m/s, wheels `rear_left`,
//! `rear_right`, `front_left`, `front_right`), the measured front wheel
//! angles (`steer_left_deg`, `steer_right_deg`) and the rear wheels' rim
//! speeds relative to the body (`rim_speed_rear_left`,
//! `rim_speed_rear_right`, m/s).

use crate::engine::rapier::prelude::*;
use crate::engine::reading::UrdfReading;
use crate::engine::real::{f, vector};
use crate::engine::required::Required;
use crate::engine::urdf::effort;
use crate::engine::urdf::{Drive, SimWorld};
use crate::engine::{angles, PhysicsSettings, PhysicsSystem};
use crate::error::SetupError;
use crate::model::{Input, State};
use crate::record::Pose;
use crate::robots::car::kinematics::{
    ackermann, ackermann_slope, bicycle_angle, rear_speeds, Bicycle, Steering as SteeringInput,
};
use crate::robots::wheeled::{self, Wheel};
use std::path::Path;

/// Default body link name.
pub const BASE: &str = "base_link";
/// Default joint names: rear wheels (left, right).
pub const REAR: [&str; 2] = ["rear_left_wheel_joint", "rear_right_wheel_joint"];
/// Default joint names: steering (left, right).
pub const STEER: [&str; 2] = ["front_left_steer_joint", "front_right_steer_joint"];
/// Default joint names: front wheels (left, right).
pub const FRONT: [&str; 2] = ["front_left_wheel_joint", "front_right_wheel_joint"];

/// Wheel names in channel order.
const WHEELS: [&str; 4] = ["rear_left", "rear_right", "front_left", "front_right"];

/// The links and joints a car looks up in its URDF.
pub const REQUIRED: [Required; 7] = [
    Required::link(
        BASE,
        "the body; its +x axis is the heading θ; the rear wheels and steering joints hang from it",
    )
    .renamed_by("base_link"),
    Required::joint(
        REAR[0],
        "continuous, to the rear left wheel (a link with a sphere or cylinder collision); axis horizontal, across the body's x axis; driven",
    )
    .renamed_by("rear_left_wheel_joint"),
    Required::joint(REAR[1], "the same for the rear right wheel, on the same axle")
        .renamed_by("rear_right_wheel_joint"),
    Required::joint(
        STEER[0],
        "revolute about the vertical, body to the front left knuckle; its limits must admit the Ackermann angles at ±max_steer_deg",
    )
    .renamed_by("front_left_steer_joint"),
    Required::joint(STEER[1], "the same for the front right knuckle")
        .renamed_by("front_right_steer_joint"),
    Required::joint(
        FRONT[0],
        "continuous, knuckle to the front left wheel (centre on the steering axis); passive",
    )
    .renamed_by("front_left_wheel_joint"),
    Required::joint(FRONT[1], "the same for the front right wheel")
        .renamed_by("front_right_wheel_joint"),
];

/// The URDF names a scenario gives the car's parts.
#[derive(Debug, Clone)]
pub struct CarNames {
    /// Body link.
    pub base: String,
    /// Rear wheel joints (left, right).
    pub rear: [String; 2],
    /// Steering joints (left, right).
    pub steer: [String; 2],
    /// Front wheel joints (left, right).
    pub front: [String; 2],
}

/// A steering joint as the physics uses it.
#[derive(Debug, Clone)]
pub struct Steering {
    /// The joint.
    pub joint: String,
    /// Its child (the knuckle carrying the wheel).
    pub knuckle: String,
    /// +1 when a positive joint angle turns the wheel left (axis up), −1 down.
    pub sign: f64,
    /// Joint limits, rad.
    pub limits: [f64; 2],
    /// Torque limit from `<limit effort>`, N·m.
    pub effort: Option<f64>,
    /// Speed limit from `<limit velocity>`, rad/s (`None` when not positive).
    pub velocity: Option<f64>,
    /// The knuckle's rest orientation in the body frame.
    rest: Rotation,
}

/// What the car's physics reads from the URDF, in the body frame.
#[derive(Debug, Clone)]
pub struct CarGeometry {
    /// Rear wheels (left, right).
    pub rear: [Wheel; 2],
    /// Front wheels (left, right), at zero steering.
    pub front: [Wheel; 2],
    /// Steering joints (left, right).
    pub steer: [Steering; 2],
    /// Rear-axle to front-pivot distance, m.
    pub wheelbase: f64,
    /// Half the distance between the steering pivots, m.
    pub front_half_track: f64,
    /// Half the rear track, m.
    pub rear_half_track: f64,
    /// The rear-axle midpoint (the model's reference point) in the body frame, m.
    pub point: [f64; 2],
    /// Height of the wheels' contact plane in the body frame, m.
    pub ground: f64,
    /// Rear drives' torque limits, N·m.
    pub rear_effort: [Option<f64>; 2],
}

/// Left and right on one axle: same x, left at larger y.
fn axle(l: &Wheel, r: &Wheel, base: &str) -> Result<(), SetupError> {
    if !wheeled::same_position(l.center[0], r.center[0]) {
        return Err(SetupError::urdf_at("joint", l.joint.to_string(), format!(
            "URDF joints `{}` and `{}` must put both wheels on one axle: their centres sit at x = {:.4} and {:.4} m in `{base}`",
            l.joint, r.joint, l.center[0], r.center[0]
        )));
    }
    if l.center[1] <= r.center[1] {
        return Err(SetupError::urdf_at("joint", l.joint.to_string(), format!(
            "URDF joint `{}` puts its wheel at y = {:.4} m in `{base}`, not left of `{}`'s ({:.4} m): left and right swapped?",
            l.joint, l.center[1], r.joint, r.center[1]
        )));
    }
    Ok(())
}

impl CarGeometry {
    /// Read and check the URDF against the bicycle `model`: errors name the
    /// joint or link at fault, or the `[model]` key that disagrees.
    pub fn read(
        robot: &urdf_rs::Robot,
        names: &CarNames,
        model: &Bicycle,
    ) -> Result<Self, SetupError> {
        let frames = wheeled::link_frames(robot);
        let base = names.base.as_str();
        let body = frames[base];
        let mut rear = Vec::new();
        for j in &names.rear {
            rear.push(wheeled::wheel(robot, &frames, base, j)?);
            let parent = &wheeled::joint(robot, j)?.parent.link;
            wheeled::rigidly_on(robot, parent, base, &format!("joint `{j}`"))?;
        }
        let mut steer = Vec::new();
        let mut front = Vec::new();
        let mut pivots = Vec::new();
        for (sj, fj) in names.steer.iter().zip(&names.front) {
            let s = wheeled::joint(robot, sj)?;
            if s.joint_type != urdf_rs::JointType::Revolute {
                return Err(SetupError::urdf_at(
                    "joint",
                    sj.to_string(),
                    format!("URDF joint `{sj}` must be revolute (steering stops at its limits)"),
                ));
            }
            wheeled::rigidly_on(robot, &s.parent.link, base, &format!("joint `{sj}`"))?;
            let knuckle = s.child.link.clone();
            let in_body = body.inverse() * frames[&knuckle];
            let a = s.axis.xyz.0;
            let up = in_body.rotation * vector(a[0], a[1], a[2]).normalize_or_zero();
            if f(up.x).abs() > 1e-3 || f(up.y).abs() > 1e-3 {
                return Err(SetupError::urdf_at(
                    "joint",
                    sj.to_string(),
                    format!(
                    "URDF joint `{sj}` axis must be vertical in `{base}`, is ({:.4}, {:.4}, {:.4})",
                    f(up.x),
                    f(up.y),
                    f(up.z)
                ),
                ));
            }
            let w = wheeled::wheel(robot, &frames, base, fj)?;
            let parent = &wheeled::joint(robot, fj)?.parent.link;
            wheeled::rigidly_on(robot, parent, &knuckle, &format!("joint `{fj}`"))?;
            let pivot = [f(in_body.translation.x), f(in_body.translation.y)];
            let off = (w.center[0] - pivot[0]).hypot(w.center[1] - pivot[1]);
            if off > 1e-4 {
                return Err(SetupError::urdf_at("joint", fj.to_string(), format!(
                    "URDF joint `{fj}` must put the wheel's centre on the steering axis of `{sj}` (it is {off:.4} m off)"
                )));
            }
            steer.push(Steering {
                joint: sj.clone(),
                knuckle,
                sign: f(up.z).signum(),
                limits: [s.limit.lower, s.limit.upper],
                effort: effort(robot, sj),
                velocity: (s.limit.velocity.is_finite() && s.limit.velocity > 0.0)
                    .then_some(s.limit.velocity),
                rest: in_body.rotation,
            });
            pivots.push(pivot);
            front.push(w);
        }
        let [rl, rr]: [Wheel; 2] = rear.try_into().expect("two rear wheels");
        let [fl, fr]: [Wheel; 2] = front.try_into().expect("two front wheels");
        axle(&rl, &rr, base)?;
        axle(&fl, &fr, base)?;
        let ground = wheeled::contact_plane(&[&rl, &rr, &fl, &fr])?;
        let wheelbase = 0.5 * (pivots[0][0] + pivots[1][0]) - rl.center[0];
        if (wheelbase - model.wheelbase).abs() > 1e-4 {
            return Err(SetupError::key("model.wheelbase", format!(
                "URDF wheelbase {wheelbase:.4} m (rear axle to the steering pivots) differs from model.wheelbase {} m",
                model.wheelbase
            )));
        }
        let front_half_track = 0.5 * (pivots[0][1] - pivots[1][1]);
        // Each joint must reach its wheel's Ackermann angles at ±max_steer.
        let steer: [Steering; 2] = steer.try_into().expect("two steering joints");
        for (i, s) in steer.iter().enumerate() {
            let lo = ackermann(-model.max_steer, wheelbase, front_half_track)[i];
            let hi = ackermann(model.max_steer, wheelbase, front_half_track)[i];
            let (a, b) = (
                (s.sign * lo).min(s.sign * hi),
                (s.sign * lo).max(s.sign * hi),
            );
            if s.limits[0] > a + 1e-9 || s.limits[1] < b - 1e-9 {
                return Err(SetupError::key("model.max_steer_deg", format!(
                    "URDF joint `{}` limits [{:.4}, {:.4}] rad do not reach its Ackermann angles [{a:.4}, {b:.4}] rad at model.max_steer_deg = {}",
                    s.joint,
                    s.limits[0],
                    s.limits[1],
                    model.max_steer.to_degrees()
                )));
            }
        }
        Ok(CarGeometry {
            rear_effort: [effort(robot, &rl.joint), effort(robot, &rr.joint)],
            rear_half_track: 0.5 * (rl.center[1] - rr.center[1]),
            point: [
                0.5 * (rl.center[0] + rr.center[0]),
                0.5 * (rl.center[1] + rr.center[1]),
            ],
            rear: [rl, rr],
            front: [fl, fr],
            steer,
            wheelbase,
            front_half_track,
            ground,
        })
    }
}

/// The car in Rapier.
pub struct CarPhysics {
    sim: SimWorld,
    geom: CarGeometry,
    model: Bicycle,
    base: RigidBodyHandle,
    /// Wheel bodies: rear left, rear right, front left, front right.
    wheels: [RigidBodyHandle; 4],
    knuckles: [RigidBodyHandle; 2],
    rear_drives: [Drive; 2],
    steer_drives: [Drive; 2],
    /// The commanded bicycle angle (the integral of φ', held at the limit;
    /// steered by angle, the last commanded angle within the limit).
    phi_cmd: f64,
    dt: f64,
    theta: f64,
    /// Measured front wheel angles, rad.
    delta: [f64; 2],
    /// The bicycle angle of the measured wheel angles, rad.
    phi: f64,
    q: State,
}

impl CarPhysics {
    /// Build the car at `start` = (x, y, θ, φ) on the ground, front wheels
    /// at the Ackermann angles of φ (steered by angle: `start` = (x, y, θ),
    /// front wheels straight).
    pub fn new(
        robot: &urdf_rs::Robot,
        urdf_dir: &Path,
        names: &CarNames,
        model: &Bicycle,
        start: &[f64],
        sim: &PhysicsSettings,
    ) -> Result<Self, SetupError> {
        let geom = CarGeometry::read(robot, names, model)?;
        let phi0 = match model.steering {
            SteeringInput::Rate => start[3],
            SteeringInput::Angle => 0.0,
        };
        if phi0.abs() > model.max_steer + 1e-12 {
            return Err(SetupError::key(
                "start",
                format!(
                    "steering angle {}° is beyond model.max_steer_deg = {}",
                    crate::numfmt::readable(phi0.to_degrees()),
                    crate::numfmt::readable(model.max_steer.to_degrees())
                ),
            ));
        }
        let frames = wheeled::link_frames(robot);
        // Worn or mismatched tyres (`wheel_radius_scale`): every simulated
        // wheel gets the scaled radius, the model and the drives keep the
        // URDF's; the body starts that much lower, on its wheels.
        let all: Vec<&Wheel> = geom.rear.iter().chain(&geom.front).collect();
        let wear = (1.0 - sim.wheel_radius_scale) * all[0].radius;
        let links: Vec<&str> = all.iter().map(|w| w.link.as_str()).collect();
        let worn =
            crate::engine::perturb::world::worn_wheels(robot, &links, sim.wheel_radius_scale);
        let root = wheeled::root_pose(
            &frames,
            &names.base,
            geom.point,
            geom.ground + wear,
            start[0],
            start[1],
            start[2],
        );
        let mut sw = SimWorld::on_ground(&worn, urdf_dir, sim, root)?;
        let balls: Vec<Wheel> = all.iter().map(|w| (*w).clone()).collect();
        wheeled::roll_on_balls(&mut sw, &balls)?;
        let base = sw.require_link(&names.base)?;
        let link = |w: &Wheel| sw.require_link(&w.link);
        let wheels = [
            link(&geom.rear[0])?,
            link(&geom.rear[1])?,
            link(&geom.front[0])?,
            link(&geom.front[1])?,
        ];
        let knuckles = [
            sw.require_link(&geom.steer[0].knuckle)?,
            sw.require_link(&geom.steer[1].knuckle)?,
        ];
        // Initial steering: turn each knuckle and its wheel about the steering axis.
        let delta0 = ackermann(phi0, geom.wheelbase, geom.front_half_track);
        for i in 0..2 {
            if delta0[i] == 0.0 {
                continue;
            }
            let pivot = sw.world.bodies[knuckles[i]].translation();
            let rot = Rotation::from_rotation_z(crate::engine::real::r(delta0[i]));
            for h in [knuckles[i], wheels[2 + i]] {
                let b = &mut sw.world.bodies[h];
                let p = *b.position();
                let t = pivot + rot * (p.translation - pivot);
                b.set_position(
                    crate::engine::rapier::math::Pose::from_parts(t, rot * p.rotation),
                    true,
                );
            }
        }
        let mut rear_drives = Vec::new();
        for (w, e) in geom.rear.iter().zip(geom.rear_effort) {
            let mut d = sw.drive_for(sw.require_joint(&w.joint)?, JointAxis::AngX, 0.0);
            d.max_torque = e;
            rear_drives.push(d);
        }
        let mut steer_drives = Vec::new();
        for (s, d0) in geom.steer.iter().zip(delta0) {
            let h = sw.require_joint(&s.joint)?;
            let mut d = sw.drive_for(h, JointAxis::AngX, s.sign * d0);
            d.max_torque = s.effort;
            steer_drives.push(d);
        }
        // Slow robot on a half-space: CCD never acts (see the rover).
        sw.world.integration_parameters.max_ccd_substeps = 0;
        let mut me = CarPhysics {
            sim: sw,
            model: *model,
            base,
            wheels,
            knuckles,
            rear_drives: rear_drives.try_into().expect("two drives"),
            steer_drives: steer_drives.try_into().expect("two drives"),
            phi_cmd: phi0,
            dt: sim.dt,
            theta: start[2],
            delta: delta0,
            phi: phi0,
            q: State::zeros(match model.steering {
                SteeringInput::Rate => 4,
                SteeringInput::Angle => 3,
            }),
            geom,
        };
        me.read_back();
        me.apply(&Input::zeros(2));
        Ok(me)
    }

    /// The geometry read from the URDF.
    pub fn geometry(&self) -> &CarGeometry {
        &self.geom
    }

    /// Steered by angle: the fastest the commanded bicycle angle may change
    /// now, rad/s, so that neither wheel's Ackermann angle turns faster than
    /// its joint's `<limit velocity>` (infinite without one).
    pub fn max_phi_rate(&self) -> f64 {
        let g = &self.geom;
        let slope = ackermann_slope(self.phi_cmd, g.wheelbase, g.front_half_track);
        (0..2)
            .filter_map(|i| g.steer[i].velocity.map(|v| v / slope[i].abs()))
            .fold(f64::INFINITY, f64::min)
    }

    fn read_back(&mut self) {
        let bodies = &self.sim.world.bodies;
        let b = &bodies[self.base];
        let p = self.geom.point;
        let c = b.position().transform_point(vector(p[0], p[1], 0.0));
        let (l, h) = (self.geom.wheelbase, self.geom.front_half_track);
        let mut phi = 0.0;
        for i in 0..2 {
            let rel = b.rotation().inverse()
                * *bodies[self.knuckles[i]].rotation()
                * self.geom.steer[i].rest.inverse();
            self.delta[i] = angles::yaw(&rel);
            phi += 0.5 * bicycle_angle(self.delta[i], i, l, h);
        }
        self.phi = phi;
        let q = [f(c.x), f(c.y), self.theta, phi];
        let n = self.q.len();
        self.q.copy_from_slice(&q[..n]);
    }
}

impl PhysicsSystem for CarPhysics {
    fn state(&self) -> State {
        self.q.clone()
    }

    fn apply(&mut self, u: &Input) {
        let g = &self.geom;
        let m = self.model.max_steer;
        let next = match self.model.steering {
            SteeringInput::Rate => {
                let rate = if self.model.clipped(self.phi_cmd, u[1]) {
                    0.0
                } else {
                    u[1]
                };
                (self.phi_cmd + self.dt * rate).clamp(-m, m)
            }
            SteeringInput::Angle => {
                let target = u[1].clamp(-m, m);
                let step = target - self.phi_cmd;
                (self.phi_cmd
                    + step.clamp(
                        -self.dt * self.max_phi_rate(),
                        self.dt * self.max_phi_rate(),
                    ))
                .clamp(-m, m)
            }
        };
        let now_d = ackermann(self.phi_cmd, g.wheelbase, g.front_half_track);
        let next_d = ackermann(next, g.wheelbase, g.front_half_track);
        for (i, drive) in self.steer_drives.iter_mut().enumerate() {
            let s = g.steer[i].sign;
            drive.angle = s * now_d[i];
            let r = s * (next_d[i] - now_d[i]) / self.dt;
            self.sim.drive(drive, r);
        }
        self.phi_cmd = next;
        // The electronic differential reads the measured steering angle.
        let v = rear_speeds(u[0], self.phi, g.wheelbase, g.rear_half_track);
        for ((wheel, drive), v) in self.geom.rear.iter().zip(&mut self.rear_drives).zip(v) {
            self.sim.drive(drive, wheel.rate(v));
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

    fn reading(&self) -> UrdfReading {
        let g = &self.geom;
        let default = self.sim.settings.motor_max_torque;
        let mut out = UrdfReading::default();
        for w in g.rear.iter().chain(&g.front) {
            out.wheels.push(w.reading());
        }
        for (w, e) in g.rear.iter().zip(g.rear_effort) {
            out.drive(&w.joint, e, default);
        }
        for s in &g.steer {
            out.drive(&s.joint, s.effort, default);
        }
        out.geometry = vec![
            ("wheelbase_m".into(), vec![g.wheelbase]),
            ("rear_track_m".into(), vec![2.0 * g.rear_half_track]),
            ("front_pivot_track_m".into(), vec![2.0 * g.front_half_track]),
            ("reference_point_m".into(), g.point.to_vec()),
        ];
        out
    }

    fn channel_names(&self) -> Vec<String> {
        let mut out = Vec::new();
        for w in WHEELS {
            out.push(format!("slip_{w}_lon"));
            out.push(format!("slip_{w}_lat"));
        }
        out.extend(
            [
                "steer_left_deg",
                "steer_right_deg",
                "rim_speed_rear_left",
                "rim_speed_rear_right",
            ]
            .map(String::from),
        );
        out
    }

    fn channels(&self) -> Vec<f64> {
        let bodies = &self.sim.world.bodies;
        let g = &self.geom;
        let all = [&g.rear[0], &g.rear[1], &g.front[0], &g.front[1]];
        let mut out = Vec::with_capacity(12);
        for (h, w) in self.wheels.iter().zip(all) {
            let (lon, lat) = wheeled::contact_slip(&bodies[*h], w);
            out.push(lon);
            out.push(lat);
        }
        out.push(self.delta[0].to_degrees());
        out.push(self.delta[1].to_degrees());
        for i in 0..2 {
            out.push(wheeled::rim_speed(
                &bodies[self.base],
                &bodies[self.wheels[i]],
                &g.rear[i],
            ));
        }
        out
    }
}
