//! The arm's passive mechanics in the engine: the compliant wrist between
//! flange and gripper (a spring–damper per axis, settled at rest before the
//! replay) and each joint's armature, the motor rotor's reflected inertia.

use crate::engine::rapier::prelude::*;
use crate::engine::real::{self as rl, f, vector};
use crate::error::SetupError;
use crate::robots::mobile_manipulator::kinematics::CompliantWrist;
use crate::robots::mobile_manipulator::physics::{CarriedBeam, RobotBodies, GRASP_OFFSET};

/// The grasp frame on the flange and on the gripper: the tool frame
/// moved to the grasp point (the URDF's `tool_joint` has the identity origin).
pub(super) fn grasp_frame() -> crate::engine::rapier::math::Pose {
    crate::engine::rapier::math::Pose::from_translation(vector(0.0, 0.0, GRASP_OFFSET))
}

/// Channels of compliant wrists (after the pair's): each wrist's deflection,
/// translation (m) and rotation (rad) of the gripper's grasp frame against
/// the flange's, and their largest share of the travel on any axis.
pub const WRIST_CHANNELS: [&str; 6] = [
    "wrist1_deflection",
    "wrist1_rotation",
    "wrist1_travel_used",
    "wrist2_deflection",
    "wrist2_rotation",
    "wrist2_travel_used",
];

/// The compliant wrist as an impulse joint between link 6 (the flange) and
/// the gripper: all six axes free, each with a force-based spring–damper
/// (Rapier integrates its motors implicitly) towards zero and a hard stop at
/// ± travel, about the grasp point in the tool's axes (the model's
/// [`CompliantWrist`]).
pub(super) fn compliant_wrist_joint(w: &CompliantWrist) -> GenericJoint {
    let mut j = GenericJoint::new(JointAxesMask::empty());
    j.set_local_frame1(grasp_frame())
        .set_local_frame2(grasp_frame())
        .set_contacts_enabled(false);
    let axes = [
        JointAxis::LinX,
        JointAxis::LinY,
        JointAxis::LinZ,
        JointAxis::AngX,
        JointAxis::AngY,
        JointAxis::AngZ,
    ];
    for (i, axis) in axes.into_iter().enumerate() {
        j.set_motor_model(axis, MotorModel::ForceBased)
            .set_motor(axis, 0.0, 0.0, rl::r(w.stiffness[i]), rl::r(w.damping[i]))
            .set_limits(axis, [rl::r(-w.travel[i]), rl::r(w.travel[i])]);
    }
    j
}

/// Put each gripper where its compliant wrist holds it at rest under the
/// gripper's weight (`m`, centre of mass `com` in the tool frame) and its share of the beam's (the carried chain's statics
/// at the start, see `model::beam::statics`), so the replay does not start
/// with the grippers dropping into their springs.
pub(super) fn settle_wrists(
    world: &mut PhysicsWorld,
    robots: &[RobotBodies],
    w: &CompliantWrist,
    spec: &CarriedBeam,
    (m, com): (f64, [f64; 3]),
) -> Result<(), SetupError> {
    use crate::model::spatial::{self, Pose as SPose};
    use crate::robots::mobile_manipulator::beam::{FeBeam, GraspStatics};
    let fe = FeBeam::new(&spec.beam)?;
    let k = spec.grasp.map(|g| w.stiffness_in(&g.r));
    let statics = GraspStatics::new(&fe, [Some(k[0]), Some(k[1])])?;
    let flange =
        |world: &PhysicsWorld, r: &RobotBodies| rl::to_spatial(world.bodies[r.arm[5]].position());
    let gw = world.gravity;
    let g = [f(gw.x), f(gw.y), f(gw.z)];
    let end0 = flange(world, &robots[0]).then(&spec.grasp[0]);
    let on_beam = statics.wrenches(&[0.0; 6], &spatial::mul_mtv(&end0.r, g));
    for (r, rb) in robots.iter().enumerate() {
        let tool = flange(world, rb);
        // On the gripper, tool axes, about the grasp point: the beam's
        // reaction (end axes → tool axes by the grasp offset) and its weight.
        let rot = &spec.grasp[r].r;
        let wr = &on_beam[r];
        let fb = spatial::mul_mv(rot, [-wr[0], -wr[1], -wr[2]]);
        let mb = spatial::mul_mv(rot, [-wr[3], -wr[4], -wr[5]]);
        let fg = spatial::scale(spatial::mul_mtv(&tool.r, g), m);
        let mg = spatial::cross(spatial::sub(com, [0.0, 0.0, GRASP_OFFSET]), fg);
        let load = [
            fb[0] + fg[0],
            fb[1] + fg[1],
            fb[2] + fg[2],
            mb[0] + mg[0],
            mb[1] + mg[1],
            mb[2] + mg[2],
        ];
        let d: [f64; 6] =
            std::array::from_fn(|i| (load[i] / w.stiffness[i]).clamp(-w.travel[i], w.travel[i]));
        let grasp = SPose::translation([0.0, 0.0, GRASP_OFFSET]);
        let rvec = [d[3], d[4], d[5]];
        let deflect = SPose {
            r: crate::robots::mobile_manipulator::beam::se3_exp(&[
                0.0, 0.0, 0.0, rvec[0], rvec[1], rvec[2],
            ])
            .r,
            p: [d[0], d[1], d[2]],
        };
        let pose = tool.then(&grasp).then(&deflect).then(&grasp.inverse());
        world.bodies[rb.tool].set_position(rl::from_spatial(&pose), true);
    }
    Ok(())
}

/// Add each joint's armature (kg m²) to its child link's inertia about the
/// joint axis (the link frame's z: the URDF's joint origin is the child's
/// frame). A rotor's reflected inertia Jm·G² loads only its own joint's
/// acceleration; as link inertia it also loads other joints' motions by
/// Ja·(z_i·z_j)² and adds a gyroscopic moment Ja·ω × (ω·z)z — at the arm's
/// rates (≤ 0.6 rad/s, platform ≤ 0.8 rad/s) a fraction of a newton metre.
pub(super) fn add_armature(
    world: &mut PhysicsWorld,
    r: &RobotBodies,
    armature: &[f64; 6],
) -> Result<(), SetupError> {
    for (body, a) in r.arm.iter().zip(armature) {
        add_rotor_inertia(&mut world.bodies[*body], *a)?;
    }
    Ok(())
}

/// Add `a` kg m² about the body frame's z axis to a body whose inertial is
/// its additional mass properties (as every URDF link's here).
pub(super) fn add_rotor_inertia(b: &mut RigidBody, a: f64) -> Result<(), SetupError> {
    if a == 0.0 {
        return Ok(());
    }
    let link = match b.mass_properties().additional_local_mprops.as_deref() {
        Some(RigidBodyAdditionalMassProps::MassProps(p)) => *p,
        _ => {
            return Err(SetupError::other(
                "mobile manipulator physics: an arm link has no URDF inertial".to_string(),
            ))
        }
    };
    // Massless, about an axis through the link origin along z: the sum's
    // centre of mass stays the link's.
    let rotor = MassProperties::new(Vector::ZERO, 0.0, vector(0.0, 0.0, rl::r(a)));
    b.set_additional_mass_properties(link + rotor, true);
    Ok(())
}
