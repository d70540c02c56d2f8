//! What wheeled robots read from their own URDFs: where each wheel sits in
//! the body frame, which way its joint turns it, its radius; and the slip
//! of a wheel's contact point in the simulated world.
//!
//! Geometry is read at the URDF's zero joint angles (forward kinematics of
//! the joint origins), relative to the robot's body link, so a user's URDF
//! may put its frames anywhere: the checks only ask what the kinematic model
//! assumes (axles horizontal and across the body's +x axis, the wheels on
//! the ground plane of the body).

pub mod obstacles;
pub mod slip;

use crate::engine::rapier::math::Pose as RPose;
use crate::engine::rapier::prelude::*;
use crate::engine::real::{arr, f, vector};
use crate::engine::world::origin;
use crate::error::SetupError;
use std::collections::HashMap;
use urdf_rs::{JointType, Robot};

/// Tolerance of the geometric checks (axes within ~0.06°, positions 0.1 mm).
const AXIS_TOL: f64 = 1e-3;
const POS_TOL: f64 = 1e-4;

/// Pose of every link relative to the root link, all joints at zero.
pub fn link_frames(robot: &Robot) -> HashMap<String, RPose> {
    let mut out: HashMap<String, RPose> = HashMap::new();
    let children: std::collections::HashSet<&str> =
        robot.joints.iter().map(|j| j.child.link.as_str()).collect();
    for l in robot
        .links
        .iter()
        .filter(|l| !children.contains(l.name.as_str()))
    {
        out.insert(l.name.clone(), RPose::IDENTITY);
    }
    // The validation pass guarantees one tree: each pass places at least one more link.
    for _ in 0..robot.joints.len() {
        let mut placed = false;
        for j in &robot.joints {
            if out.contains_key(&j.child.link) {
                continue;
            }
            if let Some(p) = out.get(&j.parent.link).copied() {
                out.insert(j.child.link.clone(), p * origin(&j.origin));
                placed = true;
            }
        }
        if !placed {
            break;
        }
    }
    out
}

/// Check that `link` is `body` or hangs from it through fixed joints only
/// (so it moves with the body); `what` names the element for the message.
pub(crate) fn rigidly_on(
    robot: &Robot,
    link: &str,
    body: &str,
    what: &str,
) -> Result<(), SetupError> {
    let mut at = link;
    for _ in 0..=robot.joints.len() {
        if at == body {
            return Ok(());
        }
        match robot.joints.iter().find(|j| j.child.link == at) {
            Some(j) if j.joint_type == JointType::Fixed => at = &j.parent.link,
            _ => break,
        }
    }
    Err(SetupError::urdf(format!(
        "URDF {what} must hang from link `{body}` through fixed joints only"
    )))
}

/// A joint by name; the message says what it is for when it is missing.
pub fn joint<'r>(robot: &'r Robot, name: &str) -> Result<&'r urdf_rs::Joint, SetupError> {
    robot
        .joints
        .iter()
        .find(|j| j.name == name)
        .ok_or_else(|| SetupError::urdf(format!("URDF lacks joint `{name}`")))
}

/// A wheel as the kinematics sees it, in the body frame.
#[derive(Debug, Clone)]
pub struct Wheel {
    /// The wheel's joint.
    pub joint: String,
    /// The wheel link (the joint's child).
    pub link: String,
    /// Radius of the wheel's round collision, m.
    pub radius: f64,
    /// Wheel centre (of its round collision) in the body frame, m.
    pub center: [f64; 3],
    /// The same centre in the wheel link's own frame, m.
    pub center_local: [f64; 3],
    /// The axle in the wheel link's own frame, oriented so that a positive
    /// rotation about it rolls the wheel towards the body's +x.
    pub axle_local: [f64; 3],
    /// +1 when a positive joint rate rolls the wheel towards the body's +x,
    /// −1 when it rolls it backwards.
    pub sign: f64,
    /// The round collision's shape (`sphere` or `cylinder`).
    pub shape: &'static str,
}

impl Wheel {
    /// The joint rate that rolls the wheel at ground speed `v` (m/s).
    pub fn rate(&self, v: f64) -> f64 {
        self.sign * v / self.radius
    }

    /// The wheel as read, for the user.
    pub fn reading(&self) -> crate::engine::reading::WheelReading {
        crate::engine::reading::WheelReading {
            joint: self.joint.clone(),
            link: self.link.clone(),
            radius: self.radius,
            center: self.center,
            shape: self.shape,
        }
    }
}

/// Read wheel joint `joint_name` of `robot` relative to `body`: a continuous
/// joint whose child has a sphere or cylinder collision and whose axis is
/// horizontal and across the body's +x axis. `frames` from [`link_frames`].
pub fn wheel(
    robot: &Robot,
    frames: &HashMap<String, RPose>,
    body: &str,
    joint_name: &str,
) -> Result<Wheel, SetupError> {
    let j = joint(robot, joint_name)?;
    if j.joint_type != JointType::Continuous {
        return Err(SetupError::urdf_at(
            "joint",
            joint_name.to_string(),
            format!("URDF joint `{joint_name}` must be continuous (a wheel turns without limits)"),
        ));
    }
    let link = j.child.link.clone();
    let radius = crate::engine::urdf::round_collision(robot, &link, "a wheel's radius")?;
    let (c, shape) = round_collision_center(robot, &link);
    let base = frames[body];
    let wheel_in_body = base.inverse() * frames[&link];
    let a = j.axis.xyz.0;
    let axle_local = vector(a[0], a[1], a[2]).normalize_or_zero();
    let center_local = vector(c[0], c[1], c[2]);
    let off_axis = center_local - axle_local * center_local.dot(axle_local);
    if f(off_axis.length()) > POS_TOL {
        return Err(SetupError::urdf_at("link", link.to_string(), format!(
            "URDF link `{link}`: the centre of its round collision must lie on the axle of joint `{joint_name}` (it is {:.4} m off)",
            f(off_axis.length())
        )));
    }
    // The joint frame is the child link's frame: the axle in body coordinates.
    let axle = arr(wheel_in_body.rotation * axle_local);
    if axle[0].abs() > AXIS_TOL || axle[2].abs() > AXIS_TOL {
        return Err(SetupError::urdf_at("joint", joint_name.to_string(), format!(
            "URDF joint `{joint_name}` axis must be horizontal and across link `{body}`'s x axis, is ({:.4}, {:.4}, {:.4}) in `{body}`",
            axle[0], axle[1], axle[2]
        )));
    }
    // Rolling without slip moves the centre at ω r (axle × z): +x for an axle along +y.
    let sign = axle[1].signum();
    Ok(Wheel {
        joint: joint_name.to_string(),
        link,
        radius,
        center: arr(wheel_in_body.transform_point(center_local)),
        center_local: c,
        axle_local: arr(axle_local * crate::engine::real::r(sign)),
        sign,
        shape,
    })
}

/// Origin of the first sphere or cylinder collision of `link`, in its
/// frame, and its shape.
fn round_collision_center(robot: &Robot, link: &str) -> ([f64; 3], &'static str) {
    robot
        .links
        .iter()
        .find(|l| l.name == link)
        .and_then(|l| {
            l.collision.iter().find(|c| {
                matches!(
                    c.geometry,
                    urdf_rs::Geometry::Sphere { .. } | urdf_rs::Geometry::Cylinder { .. }
                )
            })
        })
        .map_or(([0.0; 3], "sphere"), |c| {
            (c.origin.xyz.0, crate::engine::urdf::shape_tag(&c.geometry))
        })
}

/// Check that the wheels share one contact plane (their lowest points at the
/// same height in the body frame, within 0.1 mm); returns that height.
pub(crate) fn contact_plane(wheels: &[&Wheel]) -> Result<f64, SetupError> {
    let low: Vec<f64> = wheels.iter().map(|w| w.center[2] - w.radius).collect();
    let lo = low.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = low.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if hi - lo > POS_TOL {
        let list: Vec<String> = wheels
            .iter()
            .zip(&low)
            .map(|(w, z)| format!("`{}` {z:.4}", w.link))
            .collect();
        return Err(SetupError::urdf(format!(
            "URDF wheels must touch one ground plane: their lowest points sit at different heights ({} m)",
            list.join(", ")
        )));
    }
    Ok(lo)
}

/// Give every cylinder wheel of `wheels` a ball of its radius, centred on the
/// axle, as its collision: one contact point under the axle, as a thin
/// wheel rolls. Rapier's cylinder–plane manifold puts its points on the
/// rims and switches between them as the wheel rolls: on a published
/// two-wheel robot (0.033 m wheels, 0.018 m wide) arcs at 0.3 m/s slipped
/// sideways at up to 0.18 m/s with cylinders, 7e-6 m/s with balls, 0.016
/// m/s with parry's round cylinder (border 0.9 of the half width). The
/// price: sideways, against an obstacle, the wheel is as wide as it is tall.
pub fn roll_on_balls(
    sw: &mut crate::engine::world::SimWorld,
    wheels: &[Wheel],
) -> Result<(), SetupError> {
    let links: Vec<&str> = wheels.iter().map(|w| w.link.as_str()).collect();
    roll_links_on_balls(sw, &links)
}

/// [`roll_on_balls`] for the wheel links named.
pub(crate) fn roll_links_on_balls(
    sw: &mut crate::engine::world::SimWorld,
    links: &[&str],
) -> Result<(), SetupError> {
    for l in links {
        for c in sw.colliders_of(l)? {
            let Some(col) = sw.world.colliders.get_mut(c) else {
                continue;
            };
            if let Some(radius) = col.shape().as_cylinder().map(|c| c.radius) {
                col.set_shape(SharedShape::ball(radius));
            }
        }
    }
    Ok(())
}

/// Whether two body-frame coordinates agree within the position tolerance.
pub(crate) fn same_position(a: f64, b: f64) -> bool {
    (a - b).abs() <= POS_TOL
}

/// Root-link pose that puts `body` at yaw `theta` with the body-frame point
/// `point` at world (x, y) and the body-frame height `ground` on z = 0.
pub fn root_pose(
    frames: &HashMap<String, RPose>,
    body: &str,
    point: [f64; 2],
    ground: f64,
    x: f64,
    y: f64,
    theta: f64,
) -> RPose {
    let rot = Rotation::from_rotation_z(crate::engine::real::r(theta));
    let offset = rot * vector(point[0], point[1], ground);
    let body_pose = RPose::from_parts(vector(x, y, 0.0) - offset, rot);
    body_pose * frames[body].inverse()
}

/// Velocity of a wheel's lowest point along and across its rolling
/// direction (m/s): zero for rolling without slip.
pub(crate) fn contact_slip(b: &RigidBody, w: &Wheel) -> (f64, f64) {
    let c = w.center_local;
    let center = b.position().transform_point(vector(c[0], c[1], c[2]));
    let contact = center - vector(0.0, 0.0, w.radius);
    let v = b.velocity_at_point(contact);
    let a = w.axle_local;
    let axle = *b.rotation() * vector(a[0], a[1], a[2]);
    let fwd = Vector::new(axle.y, -axle.x, 0.0).normalize_or_zero();
    let side = Vector::new(-fwd.y, fwd.x, 0.0);
    (f(v.dot(fwd)), f(v.dot(side)))
}

/// Ground speed of a wheel's rim relative to its parent (m/s, positive
/// forward): its rate about the axle times its radius.
pub(crate) fn rim_speed(parent: &RigidBody, wheel: &RigidBody, w: &Wheel) -> f64 {
    let a = w.axle_local;
    let axle = *wheel.rotation() * vector(a[0], a[1], a[2]);
    f((wheel.angvel() - parent.angvel()).dot(axle)) * w.radius
}
